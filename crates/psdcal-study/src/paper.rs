//! The paper's own numbers (Rodríguez-Navarro et al., Sensors 2016,
//! Tables 1–10), transcribed as printed so that psdcal's study can show them
//! next to its own. Where the print is evidently a typo (an exponent or a
//! sign that contradicts the same number elsewhere in the paper), the value is
//! kept as printed and [`PaperTable::notes`] says so; EXPERIMENTS.md
//! discusses the differences.
//!
//! Rows of Tables 3–10: `Cx, Cy, f, k1, k2, residual, iterations` (a mean and,
//! where the paper gives one, a standard deviation over its 200 trials).
//! Tables 1–2: `Cx, Cy, f` of the closed-form (first-stage) solution on one
//! noise-free set of nine images.

/// A printed value: mean and, when given, standard deviation.
pub type Cell = Option<(f64, Option<f64>)>;

/// One column of a paper table.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PaperColumn {
    /// The column's heading, shortened.
    pub label: &'static str,
    /// Values in row order.
    pub cells: &'static [Cell],
}

/// A table of the paper.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PaperTable {
    /// Its columns.
    pub columns: &'static [PaperColumn],
    /// Remarks on the print.
    pub notes: &'static [&'static str],
}

const fn v(mean: f64, std: f64) -> Cell {
    Some((mean, Some(std)))
}
const fn m(mean: f64) -> Cell {
    Some((mean, None))
}

/// Table 1 (lens 1) and Table 2 (lens 2): closed-form Cx, Cy, f; columns
/// (no preliminary correction, plain DLT), (no correction, normalised),
/// (correction, plain DLT), (correction, normalised).
pub const TABLE1: PaperTable = PaperTable {
    columns: &[
        PaperColumn {
            label: "no correction, DLT",
            cells: &[m(0.33172), m(-1.5623), m(26.2146)],
        },
        PaperColumn {
            label: "no correction, normalised",
            cells: &[m(0.31600), m(-1.5030), m(25.7406)],
        },
        PaperColumn {
            label: "correction, DLT",
            cells: &[m(0.3589), m(-1.3373), m(25.1194)],
        },
        PaperColumn {
            label: "correction, normalised",
            cells: &[m(0.2871), m(-1.3077), m(25.1559)],
        },
    ],
    notes: &["Table 1's first two headings are ambiguous in the print; read as in Table 2."],
};

/// Table 2 (lens 2).
pub const TABLE2: PaperTable = PaperTable {
    columns: &[
        PaperColumn {
            label: "no correction, DLT",
            cells: &[m(0.5017), m(-0.7370), m(10.4352)],
        },
        PaperColumn {
            label: "no correction, normalised",
            cells: &[m(0.6585), m(-0.6160), m(11.0650)],
        },
        PaperColumn {
            label: "correction, DLT",
            cells: &[m(0.5103), m(-0.7520), m(9.2115)],
        },
        PaperColumn {
            label: "correction, normalised",
            cells: &[m(0.5113), m(-0.7095), m(9.1549)],
        },
    ],
    notes: &[],
};

/// Table 3: lens 1, noise, with and without corrections.
pub const TABLE3: PaperTable = PaperTable {
    columns: &[
        PaperColumn {
            label: "corrections, 30 dB",
            cells: &[
                v(0.6581, 0.7162),
                v(-0.7749, 0.5186),
                v(24.9084, 0.4832),
                v(2.0140e-3, 2.0461e-4),
                v(1.3808e-6, 7.9395e-6),
                v(1.1286, 0.1116),
                v(32.66, 16.08),
            ],
        },
        PaperColumn {
            label: "corrections, 40 dB",
            cells: &[
                v(0.5062, 0.1551),
                v(-0.6806, 0.2219),
                v(24.9868, 0.1724),
                v(1.9962e-3, 4.8222e-5),
                v(5.2682e-8, 1.5151e-6),
                v(0.1127, 1.0592e-2),
                v(35.62, 12.04),
            ],
        },
        PaperColumn {
            label: "corrections, 50 dB",
            cells: &[
                v(0.5060, 4.3929e-2),
                v(-0.6920, 7.2875e-2),
                v(24.9954, 5.4405e-3),
                v(2.0014e-3, 1.5197e-5),
                v(4.4839e-8, 4.4062e-7),
                v(1.1434e-2, 1.2037e-3),
                v(19.06, 3.8778),
            ],
        },
        PaperColumn {
            label: "no corrections, 30 dB",
            cells: &[
                v(0.7700, 0.6315),
                v(-0.2968, 0.6589),
                v(24.8869, 0.5935),
                v(1.9207e-3, 2.4786e-4),
                v(2.5099e-6, 9.5927e-6),
                v(1.1246, 0.10750),
                v(52.97, 19.37),
            ],
        },
        PaperColumn {
            label: "no corrections, 40 dB",
            cells: &[
                v(0.5097, 0.1665),
                v(-0.6844, 0.2574),
                v(24.9951, 0.1683),
                v(1.9957e-3, 5.1903e-5),
                v(5.4053e-8, 1.2615e-6),
                v(0.1140, 1.1194e-2),
                v(47.62, 6.93),
            ],
        },
        PaperColumn {
            label: "no corrections, 50 dB",
            cells: &[
                v(0.4981, 4.1426e-2),
                v(-0.7002, 7.8348e-2),
                v(25.0009, 4.7079e-2),
                v(1.9961e-3, 1.5991e-5),
                v(2.9584e-8, 4.2352e-7),
                v(1.1523e-2, 1.1441e-3),
                v(28.38, 9.04),
            ],
        },
    ],
    notes: &["The std of f at 50 dB with corrections (5.4405e-3) is ten times below its neighbours'; probably 5.4405e-2."],
};

/// Table 4: lens 2, noise, with and without corrections.
pub const TABLE4: PaperTable = PaperTable {
    columns: &[
        PaperColumn {
            label: "corrections, 30 dB",
            cells: &[
                v(0.5248, 9.9308e-2),
                v(-0.6579, 0.1297),
                v(8.1090, 0.3833),
                v(9.9109e-3, 3.4371e-4),
                v(2.4701e-5, 1.4913e-5),
                v(1.3890, 0.1491),
                v(23.44, 16.08),
            ],
        },
        PaperColumn {
            label: "corrections, 40 dB",
            cells: &[
                v(0.5015, 2.7468e-2),
                v(-0.6975, 3.6233e-2),
                v(8.0213, 0.1061),
                v(9.9923e-3, 1.0460e-4),
                v(2.4541e-4, 4.2144e-6),
                v(0.1398, 1.3390e-2),
                v(15.72, 12.04),
            ],
        },
        PaperColumn {
            label: "corrections, 50 dB",
            cells: &[
                v(0.5001, 9.7033e-3),
                v(-0.6977, 1.0635e-2),
                v(7.9961, 3.9105e-2),
                v(9.9992e-3, 3.5837e-5),
                v(2.9964e-5, 1.4822e-6),
                v(1.3961e-2, 1.3622e-3),
                v(11.64, 3.8778),
            ],
        },
        PaperColumn {
            label: "no corrections, 30 dB",
            cells: &[
                v(0.5173, 0.1247),
                v(-0.6431, 0.1238),
                v(8.0267, 0.4084),
                v(0.9873e-3, 3.6840e-4),
                v(2.3909e-5, 1.4521e-5),
                v(1.4080, 0.1361),
                v(41.72, 19.37),
            ],
        },
        PaperColumn {
            label: "no corrections, 40 dB",
            cells: &[
                v(0.4984, 3.6729e-2),
                v(-0.6896, 3.9594e-2),
                v(7.9991, 0.1297),
                v(0.9987e-3, 1.0071e-4),
                v(2.9938e-5, 4.8994e-6),
                v(0.1404, 1.4854e-2),
                v(40.98, 6.93),
            ],
        },
        PaperColumn {
            label: "no corrections, 50 dB",
            cells: &[
                v(0.4995, 1.1802e-2),
                v(-0.6984, 1.1298e-2),
                v(7.9968, 4.0700e-2),
                v(9.9982e-3, 3.1988e-5),
                v(3.0155e-5, 1.4209e-6),
                v(1.4182e-2, 1.3964e-5),
                v(42.40, 9.04),
            ],
        },
    ],
    notes: &[
        "k2 at 40 dB with corrections is printed 2.4541e-4; Table 10 prints 2.4541e-5.",
        "k1 without corrections at 30 and 40 dB is printed ×1e-3; the values are ×1e-2.",
        "The residual std without corrections at 50 dB (1.3964e-5) is a hundred times below its neighbours'.",
        "The iteration stds repeat Table 3's.",
    ],
};

/// Table 5: lens 1, gain imbalance (with noise at 40 and 50 dB, and without).
pub const TABLE5: PaperTable = PaperTable {
    columns: &[
        PaperColumn {
            label: "imbalance, 40 dB",
            cells: &[
                v(0.5463, 1.1246),
                v(-0.7627, 1.2792),
                v(24.5821, 0.4489),
                v(2.008e-3, 5.5946e-5),
                v(6.3620e-7, 1.7950e-6),
                v(6.1689e-2, 1.2298e-2),
                v(35.72, 9.85),
            ],
        },
        PaperColumn {
            label: "imbalance, 50 dB",
            cells: &[
                v(0.4859, 1.1184),
                v(-0.7442, 1.1955),
                v(24.7798, 0.3366),
                v(1.9911e-3, 4.9795e-5),
                v(8.9598e-8, 1.2040e-6),
                v(5.1177e-2, 5.1542e-3),
                v(24.19, 10.86),
            ],
        },
        PaperColumn {
            label: "imbalance, no noise",
            cells: &[
                v(0.5284, 1.0543),
                v(-0.6862, 1.0025),
                v(24.7831, 0.2916),
                v(1.9964e-3, 3.0805e-5),
                v(3.3083e-8, 1.1553e-6),
                v(4.8745e-2, 3.9578e-3),
                v(24.72, 10.40),
            ],
        },
    ],
    notes: &[
        "The ideal f is printed 8 (it is 25 for lens 1).",
        "The residuals with imbalance are below those of Table 3 at the same SNR, which a larger error cannot give: the paper's imbalance runs likely differ in how the residual is summed.",
    ],
};

/// Table 6: lens 2, gain imbalance.
pub const TABLE6: PaperTable = PaperTable {
    columns: &[
        PaperColumn {
            label: "imbalance, 40 dB",
            cells: &[
                v(0.5383, 0.3093),
                v(-0.7078, 0.3339),
                v(7.9301, 0.1746),
                v(0.9950e-2, 1.4376e-4),
                v(2.9671e-5, 5.7399e-6),
                v(4.6661e-2, 3.2799e-3),
                v(17.08, 0.1710),
            ],
        },
        PaperColumn {
            label: "imbalance, 50 dB",
            cells: &[
                v(0.4881, 0.3005),
                v(-0.6543, 0.2862),
                v(7.9546, 0.1036),
                v(1.012e-3, 1.3249e-4),
                v(2.9786e-5, 5.0512e-6),
                v(3.9131e-2, 2.5302e-3),
                v(12.87, 7.5334),
            ],
        },
        PaperColumn {
            label: "imbalance, no noise",
            cells: &[
                v(0.4972, 0.2963),
                v(-0.6723, 0.2774),
                v(7.9816, 0.1066),
                v(0.9997e-2, 1.2099e-4),
                v(2.8683e-5, 4.7542e-6),
                v(2.3292e-2, 2.7743e-3),
                v(10.97, 3.20),
            ],
        },
    ],
    notes: &["k1 at 50 dB is printed 1.012e-3; the value is ×1e-2."],
};

/// Table 7: lens 1 with the PSD's distortion (k1 then estimates k1 + l1 = 6.9416e-4).
pub const TABLE7: PaperTable = PaperTable {
    columns: &[
        PaperColumn {
            label: "PSD",
            cells: &[
                m(0.5016),
                m(-0.7034),
                m(25.0412),
                m(6.9525e-4),
                m(6.6503e-9),
                m(2.4690e-6),
                m(15.0),
            ],
        },
        PaperColumn {
            label: "PSD, 40 dB",
            cells: &[
                v(0.4812, 0.1564),
                v(-0.6817, 0.1216),
                v(25.0543, 0.1403),
                v(6.8486e-4, 2.9148e-5),
                v(2.7347e-7, 8.0904e-7),
                v(1.0088e-2, 9.9455e-3),
                v(31.80, 10.29),
            ],
        },
        PaperColumn {
            label: "PSD, imbalance",
            cells: &[
                v(0.4105, 1.4487),
                v(-0.7933, 1.4161),
                v(24.8257, 0.1965),
                v(6.9778e-4, 1.5191e-5),
                v(9.0506e-8, 2.4403e-7),
                v(2.5190e-3, 3.0651e-3),
                v(34.52, 13.60),
            ],
        },
        PaperColumn {
            label: "PSD, imbalance, 40 dB",
            cells: &[
                v(0.3840, 1.5763),
                v(-0.8345, 1.5071),
                v(24.8345, 0.2575),
                v(6.9800e-4, 3.2099e-5),
                v(9.9325e-8, 5.9951e-7),
                v(0.1026, 1.1644e-2),
                v(35.14, 15.4214),
            ],
        },
    ],
    notes: &["The noise-free PSD column is one set of images (no std)."],
};

/// Table 8: lens 2 with the PSD's distortion (k1 + l1 = 8.6941e-3).
pub const TABLE8: PaperTable = PaperTable {
    columns: &[
        PaperColumn {
            label: "PSD",
            cells: &[m(0.5039), m(-0.6993), m(8.0146), m(8.7203e-3), m(2.9893e-5), m(5.8242e-5), m(10.0)],
        },
        PaperColumn {
            label: "PSD, 40 dB",
            cells: &[
                v(0.5013, 3.1690e-2),
                v(-0.6926, 4.3307e-2),
                v(8.0175, 0.1441),
                v(8.7065e-3, 1.0378e-4),
                v(2.9708e-5, 4.0140e-6),
                v(1.2502e-2, 1.2933e-2),
                v(13.81, 4.85),
            ],
        },
        PaperColumn {
            label: "PSD, imbalance",
            cells: &[
                v(0.4842, 0.3306),
                v(-0.7254, 0.3232),
                v(7.9482, 0.2061),
                v(8.7226e-3, 1.2086e-4),
                v(2.8592e-5, 4.5308e-6),
                v(1.6771e-2, 1.8478e-2),
                v(11.44, 1.53),
            ],
        },
        PaperColumn {
            label: "PSD, imbalance, 40 dB",
            cells: &[
                v(0.5048, 0.3733),
                v(-0.6807, 0.3158),
                v(8.1176, 0.3547),
                v(8.5761e-3, 8.6034e-4),
                v(2.8139e-5, 6.5081e-6),
                v(3.5957e-4, 1.8663e-3),
                v(16.19, 8.62),
            ],
        },
    ],
    notes: &[
        "The ideal f is printed 25 and the ideal k2 −3e-5 (lens 2 has f = 8, k2 = +3e-5).",
        "The residual with imbalance and 40 dB (3.5957e-4) is far below the 40 dB one without imbalance: probably a misprint.",
    ],
};

/// Table 9: lens 1, the conditions compared.
pub const TABLE9: PaperTable = PaperTable {
    columns: &[
        PaperColumn { label: "40 dB", cells: TABLE3.columns[1].cells },
        PaperColumn { label: "40 dB, imbalance", cells: TABLE5.columns[0].cells },
        PaperColumn { label: "40 dB, PSD", cells: TABLE7.columns[1].cells },
        PaperColumn { label: "40 dB, imbalance, PSD", cells: TABLE7.columns[3].cells },
        PaperColumn {
            label: "50 dB, PSD",
            cells: &[
                v(0.5060, 4.3929e-2),
                v(-0.6920, 7.2875e-2),
                v(24.9954, 5.4405e-3),
                v(6.93531e-4, 9.0483e-6),
                v(3.8829e-8, 2.5433e-7),
                v(1.0000e-2, 1.2037e-3),
                v(15.05, 0.9252),
            ],
        },
    ],
    notes: &[
        "Columns 1–4 repeat Tables 3, 5 and 7 (Table 9 prints k1 with imbalance as −2.008e-3 and the 40 dB PSD residual as 1.0088e-4).",
        "The 50 dB PSD column repeats Table 3's 50 dB Cx, Cy, f and stds.",
    ],
};

/// Table 10: lens 2, the conditions compared.
pub const TABLE10: PaperTable = PaperTable {
    columns: &[
        PaperColumn {
            label: "40 dB",
            cells: TABLE4.columns[1].cells,
        },
        PaperColumn {
            label: "40 dB, imbalance",
            cells: TABLE6.columns[0].cells,
        },
        PaperColumn {
            label: "40 dB, PSD",
            cells: TABLE8.columns[1].cells,
        },
        PaperColumn {
            label: "40 dB, imbalance, PSD",
            cells: TABLE8.columns[3].cells,
        },
        PaperColumn {
            label: "50 dB, PSD",
            cells: &[
                v(0.5001, 9.7033e-3),
                v(-0.6977, 1.0635e-2),
                v(7.9961, 3.9105e-2),
                v(8.7192e-2, 3.1025e-5),
                v(3.0093e-2, 1.1896e-6),
                v(1.3961e-2, 1.3622e-3),
                v(10.60, 0.695),
            ],
        },
    ],
    notes: &[
        "Columns 1–4 repeat Tables 4, 6 and 8 (Table 10 prints the 40 dB k2 as 2.4541e-5).",
        "The 50 dB PSD k1 and k2 are printed ×1e-2; the values are ×1e-3 and ×1e-5.",
    ],
};

/// The paper's table `n` (1–10).
pub fn table(n: u8) -> Option<&'static PaperTable> {
    Some(match n {
        1 => &TABLE1,
        2 => &TABLE2,
        3 => &TABLE3,
        4 => &TABLE4,
        5 => &TABLE5,
        6 => &TABLE6,
        7 => &TABLE7,
        8 => &TABLE8,
        9 => &TABLE9,
        10 => &TABLE10,
        _ => return None,
    })
}
