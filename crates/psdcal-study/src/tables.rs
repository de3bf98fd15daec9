//! The paper's tables as psdcal runs them (its Section 4, Tables 1–10):
//! what each row reports ([`Quantity`]), how each column calibrates
//! ([`Method`]), each column's condition (lens, SNR, gain imbalance, PSD
//! distortion, corrections: [`Condition`]) and each table's columns
//! ([`table_spec`]). Running them is [`crate::study`]'s.

use psdcal_model::SensorModel;
use serde::Serialize;

use psdcal_sim::Lens;

/// A reported quantity (a row of the paper's tables).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
#[serde(rename_all = "lowercase")]
pub enum Quantity {
    /// Optical centre x, mm.
    Cx,
    /// Optical centre y, mm.
    Cy,
    /// Focal length, mm.
    F,
    /// Radial distortion k1, mm⁻².
    K1,
    /// Radial distortion k2, mm⁻⁴.
    K2,
    /// Sum of squared template-plane errors, mm².
    Residual,
    /// Levenberg–Marquardt iterations.
    Iterations,
    /// RMS angle-of-arrival error over held-out directions, degrees.
    AoaRms,
}

impl Quantity {
    /// Rows of Tables 3–10, then psdcal's extra row.
    pub const FULL: [Quantity; 8] = [
        Quantity::Cx,
        Quantity::Cy,
        Quantity::F,
        Quantity::K1,
        Quantity::K2,
        Quantity::Residual,
        Quantity::Iterations,
        Quantity::AoaRms,
    ];
    /// Rows of Tables 1–2.
    pub const FIRST_STAGE: [Quantity; 3] = [Quantity::Cx, Quantity::Cy, Quantity::F];

    /// The row heading.
    pub fn label(self) -> &'static str {
        match self {
            Quantity::Cx => "Cx (mm)",
            Quantity::Cy => "Cy (mm)",
            Quantity::F => "f (mm)",
            Quantity::K1 => "k1 (mm^-2)",
            Quantity::K2 => "k2 (mm^-4)",
            Quantity::Residual => "Residual (mm^2)",
            Quantity::Iterations => "Iterations",
            Quantity::AoaRms => "AoA RMS error (deg)",
        }
    }
}

/// What a trial does with its data.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
#[serde(tag = "kind", rename_all = "snake_case")]
pub enum Method {
    /// The whole calibration; `corrections` switches the preliminary
    /// correction and the data normalisation together (the paper's "with
    /// improvements").
    Calibrate {
        /// Preliminary correction and normalisation on.
        corrections: bool,
        /// Start the refinement as the paper does, straight from the closed
        /// form (`true`, Tables 3–4, which compare iterations), or with
        /// psdcal's checked and refined start (`false`).
        paper_start: bool,
        /// Self-calibrate the amplifier gains from the amplitudes (issue 7).
        fit_gains: bool,
    },
    /// Only the closed form (first stage), for Tables 1–2.
    FirstStage {
        /// Preliminary correction on.
        preliminary: bool,
        /// Normalised DLT.
        normalize: bool,
    },
}

/// One column of a study table.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Condition {
    /// The column heading.
    pub label: String,
    /// The lens.
    pub lens: Lens,
    /// SNR per channel, dB (`None`: no noise).
    pub snr_db: Option<f64>,
    /// Gain imbalance.
    pub imbalance: bool,
    /// PSD distortion.
    pub psd_distortion: bool,
    /// What the trial computes.
    pub method: Method,
}

impl Condition {
    fn new(
        label: &str,
        lens: Lens,
        snr_db: Option<f64>,
        imbalance: bool,
        psd: bool,
        method: Method,
    ) -> Self {
        Self {
            label: label.into(),
            lens,
            snr_db,
            imbalance,
            psd_distortion: psd,
            method,
        }
    }

    /// The true value of a quantity under this condition (`None` where the
    /// paper shows none).
    pub fn ideal(&self, q: Quantity) -> Option<f64> {
        let m = self.lens.model();
        let l1 = if self.psd_distortion {
            SensorModel::PAPER_L1
        } else {
            0.0
        };
        match q {
            Quantity::Cx => Some(m.intrinsics.cx),
            Quantity::Cy => Some(m.intrinsics.cy),
            Quantity::F => Some(m.intrinsics.f),
            Quantity::K1 => Some(m.distortion.k1 + l1),
            Quantity::K2 => Some(m.distortion.k2),
            Quantity::Residual | Quantity::AoaRms => Some(0.0),
            Quantity::Iterations => None,
        }
    }
}

/// A study table: the paper's table `number` or a psdcal extension.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct TableSpec {
    /// Identifier (`table1` … `table10`).
    pub id: String,
    /// Title.
    pub title: String,
    /// The paper's table number, for its numbers.
    pub paper: Option<u8>,
    /// The columns.
    pub columns: Vec<Condition>,
}

impl TableSpec {
    /// The rows this table reports.
    pub fn rows(&self) -> &'static [Quantity] {
        if self
            .columns
            .iter()
            .all(|c| matches!(c.method, Method::FirstStage { .. }))
        {
            &Quantity::FIRST_STAGE
        } else {
            &Quantity::FULL
        }
    }
}

/// The identifiers of every table, in order.
pub const TABLE_IDS: [&str; 10] = [
    "table1", "table2", "table3", "table4", "table5", "table6", "table7", "table8", "table9",
    "table10",
];

/// The specification of table `id` (`table1` … `table10`).
pub fn table_spec(id: &str) -> Option<TableSpec> {
    let n: u8 = id.strip_prefix("table")?.parse().ok()?;
    let lens = if n % 2 == 1 { Lens::One } else { Lens::Two };
    let full = Method::Calibrate {
        corrections: true,
        paper_start: false,
        fit_gains: false,
    };
    let self_calibrated = Method::Calibrate {
        corrections: true,
        paper_start: false,
        fit_gains: true,
    };
    let c = |label: &str, snr: Option<f64>, imb: bool, psd: bool| {
        Condition::new(label, lens, snr, imb, psd, full)
    };
    let (title, columns) = match n {
        1 | 2 => (
            "Closed-form (first-stage) intrinsics, noise-free images",
            [(false, false), (false, true), (true, false), (true, true)]
                .iter()
                .map(|&(preliminary, normalize)| {
                    let label = format!(
                        "{}, {}",
                        if preliminary {
                            "correction"
                        } else {
                            "no correction"
                        },
                        if normalize { "normalised" } else { "DLT" }
                    );
                    Condition::new(
                        &label,
                        lens,
                        None,
                        false,
                        false,
                        Method::FirstStage {
                            preliminary,
                            normalize,
                        },
                    )
                })
                .collect(),
        ),
        3 | 4 => (
            "Calibration with signal noise, with and without corrections",
            [true, false]
                .iter()
                .flat_map(|&corrections| {
                    [30.0, 40.0, 50.0].map(|snr| {
                        let label = format!(
                            "{}, {snr} dB",
                            if corrections {
                                "corrections"
                            } else {
                                "no corrections"
                            }
                        );
                        let method = Method::Calibrate {
                            corrections,
                            paper_start: true,
                            fit_gains: false,
                        };
                        Condition::new(&label, lens, Some(snr), false, false, method)
                    })
                })
                .collect(),
        ),
        5 | 6 => (
            "Calibration with amplifier gain imbalance (and psdcal's self-calibration of the gains)",
            vec![
                c("imbalance, 40 dB", Some(40.0), true, false),
                c("imbalance, 50 dB", Some(50.0), true, false),
                c("imbalance, no noise", None, true, false),
                Condition::new("imbalance + self-calibration, 40 dB", lens, Some(40.0), true, false, self_calibrated),
                Condition::new("imbalance + self-calibration, 50 dB", lens, Some(50.0), true, false, self_calibrated),
            ],
        ),
        7 | 8 => (
            "Calibration with the PSD's distortion",
            vec![
                c("PSD", None, false, true),
                c("PSD, 40 dB", Some(40.0), false, true),
                c("PSD, imbalance", None, true, true),
                c("PSD, imbalance, 40 dB", Some(40.0), true, true),
            ],
        ),
        9 | 10 => (
            "The conditions compared",
            vec![
                c("40 dB", Some(40.0), false, false),
                c("40 dB, imbalance", Some(40.0), true, false),
                c("40 dB, PSD", Some(40.0), false, true),
                c("40 dB, imbalance, PSD", Some(40.0), true, true),
                c("50 dB, PSD", Some(50.0), false, true),
            ],
        ),
        _ => return None,
    };
    Some(TableSpec {
        id: format!("table{n}"),
        title: format!("Table {n} (lens {}): {title}", lens.number()),
        paper: Some(n),
        columns,
    })
}
