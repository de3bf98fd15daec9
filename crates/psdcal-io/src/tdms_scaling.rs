//! NI's scaling of a TDMS channel's raw values (docs/formats.md, raw.tdms):
//! when `NI_Scaling_Status` is not `scaled`, `NI_Number_Of_Scales` scales
//! (or as many as the highest `NI_Scale[i]_Scale_Type`), each `Linear`,
//! `y = slope x + intercept`, or `Polynomial`, `y = Σⱼ cⱼ xʲ` (Horner), fed
//! by the raw values (input source `0xFFFFFFFF` or none) or by another
//! scale; the last scale gives the value. Chains are checked for cycles.

use std::collections::HashMap;

use crate::limits::excerpt;
use crate::tdms_meta::Value;

/// One NI scale.
#[derive(Debug, Clone, PartialEq)]
enum Scale {
    Linear { slope: f64, intercept: f64 },
    Polynomial(Vec<f64>),
}

/// A channel's NI scaling: its scales and each one's input (`None`: the raw
/// values); the last scale gives the value.
#[derive(Debug, Clone, PartialEq)]
pub(crate) struct Scaling {
    scales: Vec<(Scale, Option<usize>)>,
}

/// The raw-data input source of a scale.
const RAW_SOURCE: f64 = 4_294_967_295.0;

impl Scaling {
    /// The scaling NI's properties describe (`None`: none, or already applied).
    pub(crate) fn from_properties(props: &HashMap<String, Value>) -> Result<Option<Self>, String> {
        let number = |key: &str| match props.get(key) {
            Some(Value::Number(v)) => Some(*v),
            _ => None,
        };
        if let Some(Value::Text(status)) = props.get("NI_Scaling_Status") {
            if status == "scaled" {
                return Ok(None);
            }
        }
        let n = match number("NI_Number_Of_Scales") {
            Some(n) => n,
            None => {
                // As many as the highest NI_Scale[i]_Scale_Type.
                let top = props
                    .keys()
                    .filter_map(|k| {
                        k.strip_prefix("NI_Scale[")?
                            .strip_suffix("]_Scale_Type")?
                            .parse::<u32>()
                            .ok()
                    })
                    .max();
                match top {
                    Some(t) => t as f64 + 1.0,
                    None => return Ok(None),
                }
            }
        };
        if !((0.0..=64.0).contains(&n) && n.fract() == 0.0) {
            return Err(format!("NI_Number_Of_Scales {n}; expected 0 to 64"));
        }
        let n = n as usize;
        if n == 0 {
            return Ok(None);
        }
        let mut scales = Vec::with_capacity(n);
        for i in 0..n {
            let key = |s: &str| format!("NI_Scale[{i}]_{s}");
            let need = |s: &str| {
                number(&key(s))
                    .ok_or_else(|| format!("no number {}; expected NI's scaling", key(s)))
            };
            let kind = match props.get(&key("Scale_Type")) {
                Some(Value::Text(t)) => t.as_str(),
                _ => {
                    return Err(format!(
                        "no {}; expected Linear or Polynomial scaling (DAQmx scalers are not read)",
                        key("Scale_Type")
                    ))
                }
            };
            let (scale, source_key) = match kind {
                "Linear" => (
                    Scale::Linear {
                        slope: need("Linear_Slope")?,
                        intercept: need("Linear_Y_Intercept")?,
                    },
                    "Linear_Input_Source",
                ),
                "Polynomial" => {
                    let size = number(&key("Polynomial_Coefficients_Size")).unwrap_or(4.0);
                    if !((0.0..=64.0).contains(&size) && size.fract() == 0.0) {
                        return Err(format!(
                            "{} {size}; expected 0 to 64",
                            key("Polynomial_Coefficients_Size")
                        ));
                    }
                    let coefficients = (0..size as usize)
                        .map(|j| need(&format!("Polynomial_Coefficients[{j}]")))
                        .collect::<Result<Vec<f64>, String>>()?;
                    (Scale::Polynomial(coefficients), "Polynomial_Input_Source")
                }
                other => {
                    return Err(format!(
                        "scale type '{}' is not supported; expected Linear or Polynomial (or \
                         values saved scaled)",
                        excerpt(other)
                    ))
                }
            };
            let input = match number(&key(source_key)) {
                None => None,
                Some(v) if v == RAW_SOURCE => None,
                Some(v) if v >= 0.0 && v < n as f64 && v.fract() == 0.0 && v as usize != i => {
                    Some(v as usize)
                }
                Some(v) => return Err(format!("{} {v}; expected another scale", key(source_key))),
            };
            scales.push((scale, input));
        }
        // No cycles: every chain reaches the raw values within n steps.
        for start in 0..n {
            let mut at = start;
            for _ in 0..=n {
                match scales[at].1 {
                    Some(next) => at = next,
                    None => break,
                }
            }
            if scales[at].1.is_some() {
                return Err("the scales' input sources form a cycle; expected a chain".to_string());
            }
        }
        Ok(Some(Self { scales }))
    }

    pub(crate) fn apply(&self, raw: f64) -> f64 {
        self.eval(self.scales.len() - 1, raw)
    }

    fn eval(&self, i: usize, raw: f64) -> f64 {
        let (scale, input) = &self.scales[i];
        let x = match input {
            Some(j) => self.eval(*j, raw),
            None => raw,
        };
        match scale {
            Scale::Linear { slope, intercept } => slope * x + intercept,
            Scale::Polynomial(c) => c.iter().rev().fold(0.0, |acc, &cj| acc * x + cj),
        }
    }
}
