//! signals.csv: demodulated electrode amplitudes, the alternative to
//! observations.csv (docs/formats.md).
//!
//! | column | meaning |
//! | --- | --- |
//! | `image`, `led` | as in observations.csv |
//! | `vx1`, `vx2`, `vy1`, `vy2` | amplitude of each electrode channel (volts, or any consistent unit) |
//! | `snr_db` (optional) | the record's estimated SNR, dB (lowest channel), as `psdcal demodulate` writes it |
//!
//! [`Signals::to_observations`] turns each row into an impact point with the
//! pin-cushion formulas of docs/model.md §1 (`psdcal_model::psd`), after
//! dividing out the relative channel gains. A row whose amplitudes sum to zero
//! or less gives no point and is an error naming its line.

use nalgebra::Vector2;
use psdcal_model::psd::impact_point_with_gains;
use psdcal_model::{Amplitudes, ChannelGains, PsdGeometry};

use crate::csv_table::CsvStream;
use crate::error::IoError;
use crate::limits::ReadLimits;
use crate::location::Location;
use crate::observations::{Observation, Observations};

const EXPECTED_COLUMNS: &str = "image, led, vx1, vx2, vy1, vy2";

/// One row of electrode amplitudes.
#[derive(Debug, Clone, PartialEq)]
pub struct SignalRow {
    /// Image identifier.
    pub image: String,
    /// LED identifier.
    pub led: String,
    /// Amplitude of channel x1, electrode at (−,−).
    pub vx1: f64,
    /// Amplitude of channel x2, electrode at (+,+).
    pub vx2: f64,
    /// Amplitude of channel y1, electrode at (+,−).
    pub vy1: f64,
    /// Amplitude of channel y2, electrode at (−,+).
    pub vy2: f64,
    /// The record's estimated SNR, dB (its lowest channel), when the file
    /// has an `snr_db` column (`psdcal demodulate` writes it).
    pub snr_db: Option<f64>,
    /// Physical line of the row, 1-based.
    pub line_no: usize,
}

impl SignalRow {
    /// The row's four amplitudes.
    pub fn amplitudes(&self) -> Amplitudes {
        Amplitudes {
            vx1: self.vx1,
            vx2: self.vx2,
            vy1: self.vy1,
            vy2: self.vy2,
        }
    }
}

/// The rows of a signals file.
#[derive(Debug, Clone, PartialEq)]
pub struct Signals {
    /// File name, for messages.
    pub source: String,
    /// The rows, in file order.
    pub rows: Vec<SignalRow>,
}

impl Signals {
    csv_table_readers!(streamed "signals.csv");

    fn from_stream<R: std::io::BufRead>(stream: CsvStream<R>) -> Result<Self, IoError> {
        let head = &stream.head;
        let image_col = head.column("image")?;
        let led_col = head.column("led")?;
        let v_cols = [
            head.column("vx1")?,
            head.column("vx2")?,
            head.column("vy1")?,
            head.column("vy2")?,
        ];
        let snr_col = head.find_column("snr_db")?;
        let (table, rows) = stream.map_rows(|table, row| {
            let image = table.identifier(row, &image_col, "an image identifier")?;
            let led = table.identifier(row, &led_col, "an LED identifier")?;
            let [vx1, vx2, vy1, vy2] = [
                table.number(row, &v_cols[0])?,
                table.number(row, &v_cols[1])?,
                table.number(row, &v_cols[2])?,
                table.number(row, &v_cols[3])?,
            ];
            let snr_db = match &snr_col {
                Some(col) => Some(table.number(row, col)?),
                None => None,
            };
            Ok(SignalRow {
                image,
                led,
                vx1,
                vx2,
                vy1,
                vy2,
                snr_db,
                line_no: row.line,
            })
        })?;
        if rows.is_empty() {
            table.require_rows()?;
        }
        Ok(Self {
            source: table.source,
            rows,
        })
    }

    /// Impact points of every row (docs/model.md §1), with the relative channel
    /// `gains` divided out first ([`ChannelGains::UNIT`] when there was no
    /// electrical calibration).
    pub fn to_observations(
        &self,
        geometry: &PsdGeometry,
        gains: &ChannelGains,
    ) -> Result<Observations, IoError> {
        let rows = self
            .rows
            .iter()
            .map(|row| {
                let at = || Location::line(&self.source, row.line_no);
                let point = impact_point_at(geometry, &row.amplitudes(), gains, at)?;
                Ok(Observation {
                    image: row.image.clone(),
                    led: row.led.clone(),
                    x_mm: point.x,
                    y_mm: point.y,
                    line_no: row.line_no,
                })
            })
            .collect::<Result<_, IoError>>()?;
        Ok(Observations {
            source: self.source.clone(),
            rows,
        })
    }
}

/// The impact point of one row's amplitudes (docs/model.md §1, gains divided
/// out); `at` locates the row for errors. Amplitudes whose total is not
/// positive, or so large that the point overflows, are an error.
pub(crate) fn impact_point_at(
    geometry: &PsdGeometry,
    amplitudes: &Amplitudes,
    gains: &ChannelGains,
    at: impl Fn() -> Location,
) -> Result<Vector2<f64>, IoError> {
    let point = impact_point_with_gains(geometry, amplitudes, gains)
        .map_err(|source| IoError::Amplitudes { at: at(), source })?;
    if point.x.is_finite() && point.y.is_finite() {
        Ok(point)
    } else {
        Err(IoError::Invalid {
            at: at(),
            message: "the amplitudes are too large to give a finite impact point; expected \
                      amplitudes below about 1e300"
                .to_string(),
        })
    }
}

#[cfg(test)]
mod tests {
    use approx::assert_relative_eq;
    use psdcal_model::psd::electrode_currents;

    use super::*;

    #[test]
    fn reads_the_optional_snr_column() {
        let text = "image,led,vx1,vx2,vy1,vy2,snr_db\n1,a,1,2,3,4,38.5\n";
        let s = Signals::from_str("signals.csv", text).unwrap();
        assert_eq!(s.rows[0].snr_db, Some(38.5));
        let bad = "image,led,vx1,vx2,vy1,vy2,snr_db\n1,a,1,2,3,4,nan\n";
        let e = Signals::from_str("signals.csv", bad).unwrap_err();
        assert!(
            e.to_string().starts_with("signals.csv:2: column 'snr_db'"),
            "{e}"
        );
    }

    #[test]
    fn reads_reordered_columns_with_comments_crlf_and_bom() {
        let text = "\u{feff}# rig 2\r\nvy2,vy1,vx2,vx1,led,image,extra\r\n\r\n4,3,2,1,L1,im,x\r\n";
        let s = Signals::from_str("signals.csv", text).unwrap();
        assert_eq!(
            s.rows,
            vec![SignalRow {
                image: "im".into(),
                led: "L1".into(),
                vx1: 1.0,
                vx2: 2.0,
                vy1: 3.0,
                vy2: 4.0,
                snr_db: None,
                line_no: 4,
            }]
        );
        assert_eq!(
            Signals::from_reader("signals.csv", text.as_bytes()).unwrap(),
            s
        );
    }

    #[test]
    fn converts_to_impact_points_with_and_without_gains() {
        let geometry = PsdGeometry::default();
        let point = Vector2::new(1.2, -2.5);
        let gains = ChannelGains {
            x2: 1.1,
            y1: 0.9,
            y2: 1.05,
        };
        let a = electrode_currents(&geometry, &point, 2.0).apply_gains(&gains);
        let text = format!(
            "image,led,vx1,vx2,vy1,vy2\n1,7,{},{},{},{}\n",
            a.vx1, a.vx2, a.vy1, a.vy2
        );
        let s = Signals::from_str("signals.csv", &text).unwrap();
        let o = s.to_observations(&geometry, &gains).unwrap();
        assert_eq!(o.source, "signals.csv");
        assert_eq!(o.rows.len(), 1);
        assert_eq!(
            (o.rows[0].image.as_str(), o.rows[0].led.as_str()),
            ("1", "7")
        );
        assert_eq!(o.rows[0].line_no, 2);
        assert_relative_eq!(o.rows[0].x_mm, 1.2, epsilon = 1e-12);
        assert_relative_eq!(o.rows[0].y_mm, -2.5, epsilon = 1e-12);
        // Ignoring the gains biases the point.
        let biased = s.to_observations(&geometry, &ChannelGains::UNIT).unwrap();
        assert!((biased.rows[0].x_mm - 1.2).abs() > 1e-3);
    }

    #[test]
    fn zero_or_negative_total_is_an_error_on_its_line() {
        let text = "image,led,vx1,vx2,vy1,vy2\n1,1,1,1,1,1\n# c\n1,2,0,0,0,0\n";
        let s = Signals::from_str("signals.csv", text).unwrap();
        let e = s
            .to_observations(&PsdGeometry::default(), &ChannelGains::UNIT)
            .unwrap_err();
        assert_eq!(e.line(), Some(4));
        assert_eq!(
            e.to_string(),
            "signals.csv:4: electrode amplitudes sum to 0 (must be positive): no usable light spot"
        );
        let text = "image,led,vx1,vx2,vy1,vy2\n1,2,-1,-1,0.5,0.5\n";
        let s = Signals::from_str("signals.csv", text).unwrap();
        let e = s
            .to_observations(&PsdGeometry::default(), &ChannelGains::UNIT)
            .unwrap_err();
        assert_eq!(e.line(), Some(2));
    }

    #[test]
    fn overflowing_amplitudes_are_an_error_on_their_line() {
        let text = "image,led,vx1,vx2,vy1,vy2\n1,1,-1e308,1e308,1e308,-1e307\n";
        let s = Signals::from_str("signals.csv", text).unwrap();
        let e = s
            .to_observations(&PsdGeometry::default(), &ChannelGains::UNIT)
            .unwrap_err();
        assert_eq!(
            e.to_string(),
            "signals.csv:2: the amplitudes are too large to give a finite impact point; expected \
             amplitudes below about 1e300"
        );
    }

    #[test]
    fn non_finite_amplitude_is_an_error_at_parse_time() {
        let text = "image,led,vx1,vx2,vy1,vy2\n1,1,1,1,1,1\n1,2,1,inf,1,1\n";
        let e = Signals::from_str("signals.csv", text).unwrap_err();
        assert_eq!(
            e.to_string(),
            "signals.csv:3: column 'vx2' (4): expected a finite number, found an infinite value \
             'inf'"
        );
    }
}
