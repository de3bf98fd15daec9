//! The files of a positioning evaluation (docs/formats.md, "Positioning
//! evaluation"): truth.csv, the surveyed truth, and the estimates to judge
//! (the CSV `psdcal locate` writes), matched row by row by emitter.
//!
//! truth.csv: `emitter` and the true position `x_mm`, `y_mm`, `z_mm` (mm),
//! and/or the true angles of arrival `alpha_x_deg`, `alpha_y_deg` (degrees).
//!
//! Estimates: `emitter`, the position in the first of these column sets
//! the header has: `x_world_mm, y_world_mm, z_world_mm` (`locate --rig`),
//! `x_sensor_mm, …` (`locate` on a plane), `x_mm, y_mm, z_mm` (any other
//! system); with the same frame's covariance columns (`sigma_x_<frame>_mm`,
//! `sigma_y_…`, `sigma_z_…`, `cov_xy_<frame>_mm2`, `cov_xz_…`, `cov_yz_…`)
//! when they are all present. Angles: `alpha_x_deg`, `alpha_y_deg` with,
//! optionally, `sigma_alpha_x_deg`, `sigma_alpha_y_deg`, `rho_alpha_xy`
//! (`psdcal aoa`). A `status` column is optional: a row whose status is not
//! `ok` (nor a caution) and whose values are empty is a fix that was not
//! made (counted, not compared). Every covariance must be positive definite
//! (a Cholesky factor exists); angles are stored in radians.
//!
//! Errors name the file and line: a missing column, a value that is not a
//! finite number, an emitter twice in one file, an emitter of one file
//! missing from the other, a singular covariance.

use std::collections::HashMap;
use std::path::Path;

use nalgebra::{Matrix2, Matrix3, Vector2, Vector3};

use crate::csv_table::{Col, CsvRow, CsvTable};
use crate::error::IoError;
use crate::limits::ReadLimits;
use crate::location::Location;

const TRUTH_COLUMNS: &str = "emitter, x_mm, y_mm, z_mm (and/or alpha_x_deg, alpha_y_deg)";
const ESTIMATE_COLUMNS: &str = "emitter, x_world_mm, y_world_mm, z_world_mm (as psdcal locate \
                                writes them), or alpha_x_deg, alpha_y_deg";

/// Statuses of a row that was answered (with or without cautions).
const ANSWERED: [&str; 3] = ["ok", "nearly_parallel_rays", "off_active_area"];

/// One emitter's true position and/or angles.
#[derive(Debug, Clone, PartialEq)]
pub struct TruthRow {
    /// Physical line, 1-based.
    pub line_no: usize,
    /// Emitter identifier.
    pub emitter: String,
    /// True position, mm.
    pub position: Option<Vector3<f64>>,
    /// True angles of arrival `(αx, αy)`, rad.
    pub alpha: Option<Vector2<f64>>,
}

/// truth.csv.
#[derive(Debug, Clone, PartialEq)]
pub struct PositionTruth {
    /// File name, for messages.
    pub source: String,
    /// The rows, in file order.
    pub rows: Vec<TruthRow>,
}

/// One estimate: a position and/or angles, with their covariances when the
/// file gives them.
#[derive(Debug, Clone, PartialEq)]
pub struct EstimateRow {
    /// Physical line, 1-based.
    pub line_no: usize,
    /// Emitter identifier.
    pub emitter: String,
    /// The `status` column (`ok` when the file has none).
    pub status: String,
    /// Estimated position, mm (`None`: not answered).
    pub position: Option<Vector3<f64>>,
    /// Its covariance, mm² (positive definite).
    pub position_covariance: Option<Matrix3<f64>>,
    /// Estimated angles `(αx, αy)`, rad.
    pub alpha: Option<Vector2<f64>>,
    /// Their covariance, rad² (positive definite).
    pub alpha_covariance: Option<Matrix2<f64>>,
}

/// The estimates file.
#[derive(Debug, Clone, PartialEq)]
pub struct PositionEstimates {
    /// File name, for messages.
    pub source: String,
    /// The frame of the position columns (`world`, `sensor`, or empty for
    /// `x_mm, y_mm, z_mm`); `None` when the file has no positions.
    pub frame: Option<String>,
    /// The rows, in file order.
    pub rows: Vec<EstimateRow>,
}

/// A truth row and its estimate.
#[derive(Debug, Clone, PartialEq)]
pub struct MatchedEstimate<'a> {
    /// The truth.
    pub truth: &'a TruthRow,
    /// The estimate.
    pub estimate: &'a EstimateRow,
}

/// A table's numbers at a row, read through optional columns.
fn vector<const N: usize>(
    table: &CsvTable,
    row: &CsvRow,
    cols: &Option<[Col; N]>,
) -> Result<Option<[f64; N]>, IoError> {
    let Some(cols) = cols else { return Ok(None) };
    let mut out = [0.0; N];
    for (v, c) in out.iter_mut().zip(cols) {
        *v = table.number(row, c)?;
    }
    Ok(Some(out))
}

/// All of `names`, or none (a partial set is an error naming the missing one).
fn columns<const N: usize>(
    table: &CsvTable,
    names: [&str; N],
) -> Result<Option<[Col; N]>, IoError> {
    let found: Vec<Option<Col>> = names
        .iter()
        .map(|n| table.find_column(n))
        .collect::<Result<_, _>>()?;
    if found.iter().all(Option::is_none) {
        return Ok(None);
    }
    if let Some(k) = found.iter().position(Option::is_none) {
        return Err(table.missing_column(names[k]));
    }
    let cols: Vec<Col> = found.into_iter().flatten().collect();
    Ok(cols.try_into().ok())
}

/// Refuses an emitter seen twice in one file.
fn unique<'a>(
    source: &str,
    rows: impl Iterator<Item = (&'a str, usize)>,
) -> Result<HashMap<&'a str, usize>, IoError> {
    let mut first: HashMap<&str, usize> = HashMap::new();
    for (emitter, line) in rows {
        if let Some(&at) = first.get(emitter) {
            return Err(IoError::Duplicate {
                at: Location::line(source, line),
                first_line: at,
                what: format!("emitter '{emitter}'"),
            });
        }
        first.insert(emitter, line);
    }
    Ok(first)
}

impl PositionTruth {
    /// Reads truth.csv.
    pub fn read(path: impl AsRef<Path>) -> Result<Self, IoError> {
        Self::read_with(path, ReadLimits::default())
    }

    /// [`Self::read`] within `limits` (docs/formats.md, "Limits").
    pub fn read_with(path: impl AsRef<Path>, limits: ReadLimits) -> Result<Self, IoError> {
        Self::from_table(CsvTable::read_path(path.as_ref(), TRUTH_COLUMNS, limits)?)
    }

    /// Parses text; `source` names it in messages.
    pub fn from_str(source: &str, text: &str) -> Result<Self, IoError> {
        Self::from_table(CsvTable::parse(source, text.as_bytes(), TRUTH_COLUMNS)?)
    }

    fn from_table(table: CsvTable) -> Result<Self, IoError> {
        let emitter = table.column("emitter")?;
        let position = columns(&table, ["x_mm", "y_mm", "z_mm"])?;
        let alpha = columns(&table, ["alpha_x_deg", "alpha_y_deg"])?;
        if position.is_none() && alpha.is_none() {
            return Err(table.missing_column("x_mm"));
        }
        table.require_rows()?;
        let mut rows = Vec::with_capacity(table.rows.len());
        for row in &table.rows {
            rows.push(TruthRow {
                line_no: row.line,
                emitter: table.identifier(row, &emitter, "an emitter identifier")?,
                position: vector(&table, row, &position)?.map(Vector3::from),
                alpha: vector(&table, row, &alpha)?
                    .map(|a| Vector2::new(a[0].to_radians(), a[1].to_radians())),
            });
        }
        unique(
            &table.source,
            rows.iter().map(|r| (r.emitter.as_str(), r.line_no)),
        )?;
        Ok(Self {
            source: table.source,
            rows,
        })
    }
}

/// The estimates' position columns: the frame and its columns.
struct PositionColumns {
    frame: String,
    position: [Col; 3],
    covariance: Option<[Col; 6]>,
}

fn position_columns(table: &CsvTable) -> Result<Option<PositionColumns>, IoError> {
    for frame in ["world", "sensor", ""] {
        let name = |axis: &str, unit: &str| {
            if frame.is_empty() {
                format!("{axis}_{unit}")
            } else {
                format!("{axis}_{frame}_{unit}")
            }
        };
        // Plain x_mm, y_mm without z_mm are measured points (aoa's answer).
        if frame.is_empty() && table.find_column("z_mm")?.is_none() {
            continue;
        }
        let position = [name("x", "mm"), name("y", "mm"), name("z", "mm")];
        let Some(position) = columns(table, position.each_ref().map(String::as_str))? else {
            continue;
        };
        let cov = [
            name("sigma_x", "mm"),
            name("sigma_y", "mm"),
            name("sigma_z", "mm"),
            name("cov_xy", "mm2"),
            name("cov_xz", "mm2"),
            name("cov_yz", "mm2"),
        ];
        let covariance = columns(table, cov.each_ref().map(String::as_str))?;
        return Ok(Some(PositionColumns {
            frame: frame.to_string(),
            position,
            covariance,
        }));
    }
    Ok(None)
}

/// Whether every field of `cols` is empty on `row`.
fn all_empty(table: &CsvTable, row: &CsvRow, cols: &[Col]) -> bool {
    cols.iter().all(|c| table.text(row, c).is_empty())
}

fn positive_definite<const N: usize>(
    table: &CsvTable,
    row: &CsvRow,
    m: nalgebra::SMatrix<f64, N, N>,
    what: &str,
) -> Result<nalgebra::SMatrix<f64, N, N>, IoError>
where
    nalgebra::Const<N>: nalgebra::DimMin<nalgebra::Const<N>>,
{
    if m.iter().all(|v| v.is_finite()) && m.cholesky().is_some() {
        return Ok(m);
    }
    Err(IoError::Invalid {
        at: table.at(row.line),
        message: format!(
            "the {what} covariance is singular or not positive definite (its σ and \
             covariances do not form a valid covariance matrix); expected σ > 0 and |ρ| < 1"
        ),
    })
}

impl PositionEstimates {
    /// Reads the estimates.
    pub fn read(path: impl AsRef<Path>) -> Result<Self, IoError> {
        Self::read_with(path, ReadLimits::default())
    }

    /// [`Self::read`] within `limits` (docs/formats.md, "Limits").
    pub fn read_with(path: impl AsRef<Path>, limits: ReadLimits) -> Result<Self, IoError> {
        Self::from_table(CsvTable::read_path(
            path.as_ref(),
            ESTIMATE_COLUMNS,
            limits,
        )?)
    }

    /// Parses text; `source` names it in messages.
    pub fn from_str(source: &str, text: &str) -> Result<Self, IoError> {
        Self::from_table(CsvTable::parse(source, text.as_bytes(), ESTIMATE_COLUMNS)?)
    }

    fn from_table(table: CsvTable) -> Result<Self, IoError> {
        let emitter = table.column("emitter")?;
        let status = table.find_column("status")?;
        let position = position_columns(&table)?;
        let alpha = columns(&table, ["alpha_x_deg", "alpha_y_deg"])?;
        let alpha_cov = columns(
            &table,
            ["sigma_alpha_x_deg", "sigma_alpha_y_deg", "rho_alpha_xy"],
        )?;
        if position.is_none() && alpha.is_none() {
            return Err(table.missing_column("x_world_mm"));
        }
        table.require_rows()?;
        let mut rows = Vec::with_capacity(table.rows.len());
        for row in &table.rows {
            let status = status
                .as_ref()
                .map_or("ok", |c| table.text(row, c))
                .to_string();
            let answered = status.split(';').all(|s| ANSWERED.contains(&s.trim()));
            let mut value_cols: Vec<Col> = Vec::new();
            if let Some(p) = &position {
                value_cols.extend(p.position.iter().cloned());
            }
            if let Some(a) = &alpha {
                value_cols.extend(a.iter().cloned());
            }
            let emitter = table.identifier(row, &emitter, "an emitter identifier")?;
            if !answered && all_empty(&table, row, &value_cols) {
                rows.push(EstimateRow {
                    line_no: row.line,
                    emitter,
                    status,
                    position: None,
                    position_covariance: None,
                    alpha: None,
                    alpha_covariance: None,
                });
                continue;
            }
            let (p, pc) = match &position {
                None => (None, None),
                Some(cols) => {
                    let p = vector(&table, row, &Some(cols.position.clone()))?.map(Vector3::from);
                    let c = vector(&table, row, &cols.covariance)?
                        .map(|[sx, sy, sz, xy, xz, yz]| {
                            let m = Matrix3::new(sx * sx, xy, xz, xy, sy * sy, yz, xz, yz, sz * sz);
                            positive_definite(&table, row, m, "position")
                        })
                        .transpose()?;
                    (p, c)
                }
            };
            let a = vector(&table, row, &alpha)?
                .map(|a| Vector2::new(a[0].to_radians(), a[1].to_radians()));
            let ac = vector(&table, row, &alpha_cov)?
                .map(|[sx, sy, rho]| {
                    let (sx, sy) = (sx.to_radians(), sy.to_radians());
                    let m = Matrix2::new(sx * sx, rho * sx * sy, rho * sx * sy, sy * sy);
                    positive_definite(&table, row, m, "angle")
                })
                .transpose()?;
            rows.push(EstimateRow {
                line_no: row.line,
                emitter,
                status,
                position: p,
                position_covariance: pc,
                alpha: a,
                alpha_covariance: ac,
            });
        }
        unique(
            &table.source,
            rows.iter().map(|r| (r.emitter.as_str(), r.line_no)),
        )?;
        Ok(Self {
            source: table.source,
            frame: position.map(|p| p.frame),
            rows,
        })
    }

    /// Each truth row with its estimate, in truth order. An estimate of an
    /// emitter the truth does not have, and a truth emitter without an
    /// estimate row, are errors naming the file and line.
    pub fn matched<'a>(
        &'a self,
        truth: &'a PositionTruth,
    ) -> Result<Vec<MatchedEstimate<'a>>, IoError> {
        let by_id: HashMap<&str, &EstimateRow> =
            self.rows.iter().map(|r| (r.emitter.as_str(), r)).collect();
        let known: HashMap<&str, ()> = truth
            .rows
            .iter()
            .map(|r| (r.emitter.as_str(), ()))
            .collect();
        if let Some(row) = self
            .rows
            .iter()
            .find(|r| !known.contains_key(r.emitter.as_str()))
        {
            return Err(IoError::Invalid {
                at: Location::line(&self.source, row.line_no),
                message: format!(
                    "emitter '{}' is not in the truth {}; expected every estimated emitter to \
                     have a true position",
                    row.emitter, truth.source
                ),
            });
        }
        truth
            .rows
            .iter()
            .map(|t| match by_id.get(t.emitter.as_str()) {
                Some(e) => Ok(MatchedEstimate {
                    truth: t,
                    estimate: e,
                }),
                None => Err(IoError::Invalid {
                    at: Location::line(&truth.source, t.line_no),
                    message: format!(
                        "emitter '{}' has no row in the estimates {}; expected one row per \
                         emitter of the truth (remove emitters that were not measured)",
                        t.emitter, self.source
                    ),
                }),
            })
            .collect()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    const TRUTH: &str = "emitter,x_mm,y_mm,z_mm\na,0,0,0\nb,100,200,-5\n";

    #[test]
    fn reads_locate_output_and_matches() {
        let truth = PositionTruth::from_str("truth.csv", TRUTH).unwrap();
        let est = PositionEstimates::from_str(
            "est.csv",
            "emitter,sensors,x_world_mm,y_world_mm,z_world_mm,sigma_x_world_mm,sigma_y_world_mm,\
             sigma_z_world_mm,cov_xy_world_mm2,cov_xz_world_mm2,cov_yz_world_mm2,status\n\
             b,l;r,101,199,-4,2,3,4,1,0,0,ok\na,l,,,,,,,,,,too_few_sensors\n",
        )
        .unwrap();
        assert_eq!(est.frame.as_deref(), Some("world"));
        let c = est.rows[0].position_covariance.unwrap();
        assert_eq!(
            c,
            Matrix3::new(4.0, 1.0, 0.0, 1.0, 9.0, 0.0, 0.0, 0.0, 16.0)
        );
        assert_eq!(est.rows[1].position, None);
        let m = est.matched(&truth).unwrap();
        assert_eq!(m[0].estimate.emitter, "a");
        assert_eq!(
            m[1].estimate.position,
            Some(Vector3::new(101.0, 199.0, -4.0))
        );
    }

    #[test]
    fn errors_name_file_and_line() {
        let err = |t: &str, e: &str| {
            let truth = PositionTruth::from_str("truth.csv", t)?;
            let est = PositionEstimates::from_str("est.csv", e)?;
            est.matched(&truth).map(|_| ())
        };
        let e = err(TRUTH, "emitter,x_mm,y_mm,z_mm\na,0,0,0\nc,0,0,0\n").unwrap_err();
        assert!(
            e.to_string()
                .starts_with("est.csv:3: emitter 'c' is not in the truth"),
            "{e}"
        );
        let e = err(TRUTH, "emitter,x_mm,y_mm,z_mm\na,0,0,0\n").unwrap_err();
        assert!(
            e.to_string()
                .starts_with("truth.csv:3: emitter 'b' has no row"),
            "{e}"
        );
        let e = err(TRUTH, "emitter,x_mm,y_mm,z_mm\na,0,0,0\na,1,0,0\n").unwrap_err();
        assert_eq!(
            e.to_string(),
            "est.csv:3: emitter 'a' appears twice (first on line 2)"
        );
        let e = err(TRUTH, "emitter,x_mm,y_mm,z_mm\na,0,NaN,0\n").unwrap_err();
        assert!(
            e.to_string().starts_with("est.csv:2: column 'y_mm' (3)"),
            "{e}"
        );
        let e = err(
            "emitter,x_mm,y_mm,z_mm\na,0,inf,0\n",
            "emitter,x_mm,y_mm,z_mm\na,0,0,0\n",
        )
        .unwrap_err();
        assert!(
            e.to_string().starts_with("truth.csv:2: column 'y_mm'"),
            "{e}"
        );
        let e = err(
            TRUTH,
            "emitter,x_mm,y_mm,z_mm,sigma_x_mm,sigma_y_mm,sigma_z_mm,cov_xy_mm2,cov_xz_mm2,\
             cov_yz_mm2\na,0,0,0,1,1,1,1,0,0\n",
        )
        .unwrap_err();
        assert!(
            e.to_string()
                .starts_with("est.csv:2: the position covariance is singular"),
            "{e}"
        );
        // An answered row with empty values is an error, not a skipped fix.
        let e = err(TRUTH, "emitter,x_mm,y_mm,z_mm,status\na,,,,ok\n").unwrap_err();
        assert!(e.to_string().contains("found an empty field"), "{e}");
        let e = err(TRUTH, "emitter,x_mm,y_mm\na,0,0\n").unwrap_err();
        assert!(e.to_string().contains("missing column 'x_world_mm'"), "{e}");
    }

    #[test]
    fn reads_angles() {
        let truth =
            PositionTruth::from_str("t.csv", "emitter,alpha_x_deg,alpha_y_deg\n1,10,-5\n").unwrap();
        assert!((truth.rows[0].alpha.unwrap().x - 10f64.to_radians()).abs() < 1e-15);
        let est = PositionEstimates::from_str(
            "e.csv",
            "emitter,x_mm,y_mm,alpha_x_deg,alpha_y_deg,sigma_alpha_x_deg,sigma_alpha_y_deg,\
             rho_alpha_xy,status\n1,0.1,0.2,10.01,-5,0.02,0.03,0.5,ok\n",
        )
        .unwrap();
        assert_eq!(est.frame, None);
        let c = est.rows[0].alpha_covariance.unwrap();
        let (sx, sy) = (0.02f64.to_radians(), 0.03f64.to_radians());
        assert!((c[(0, 1)] - 0.5 * sx * sy).abs() < 1e-18);
        est.matched(&truth).unwrap();
    }
}
