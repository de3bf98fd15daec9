//! Writing the CSV inputs of docs/formats.md — template.csv, observations.csv and
//! signals.csv — as psdcal's simulator produces them. Numbers are written in
//! Rust's shortest round-trip form (reading them back gives the same `f64`),
//! identifiers as text (quoted when they hold a comma, quote or line break),
//! and every file atomically.

use std::io::Write as _;
use std::path::Path;

use psdcal_model::Amplitudes;

use crate::atomic::write_atomic;
use crate::csv_field::csv_field;
use crate::IoError;

/// One LED of a template to write.
#[derive(Debug, Clone, PartialEq)]
pub struct TemplateLed {
    /// Identifier.
    pub id: String,
    /// Position on the template, mm.
    pub x_mm: f64,
    /// Position on the template, mm.
    pub y_mm: f64,
    /// Labels of the collinear groups it belongs to.
    pub lines: Vec<String>,
}

/// One measured point to write.
#[derive(Debug, Clone, PartialEq)]
pub struct ObservationRow {
    /// Image id.
    pub image: String,
    /// LED id.
    pub led: String,
    /// Measured impact point, mm.
    pub x_mm: f64,
    /// Measured impact point, mm.
    pub y_mm: f64,
}

/// One row of electrode amplitudes to write.
#[derive(Debug, Clone, PartialEq)]
pub struct SignalRowOut {
    /// Image id.
    pub image: String,
    /// LED id.
    pub led: String,
    /// The four amplitudes.
    pub amplitudes: Amplitudes,
}

/// Writes template.csv (`led,X_mm,Y_mm[,lines]`), with a leading comment.
pub fn write_template(
    path: impl AsRef<Path>,
    comment: &str,
    leds: &[TemplateLed],
) -> Result<(), IoError> {
    let with_lines = leds.iter().any(|l| !l.lines.is_empty());
    write_atomic(path, |w| {
        for line in comment.lines() {
            writeln!(w, "# {line}")?;
        }
        writeln!(w, "led,X_mm,Y_mm{}", if with_lines { ",lines" } else { "" })?;
        for l in leds {
            write!(w, "{},{},{}", csv_field(&l.id), l.x_mm, l.y_mm)?;
            if with_lines {
                write!(w, ",{}", csv_field(&l.lines.join(";")))?;
            }
            writeln!(w)?;
        }
        Ok(())
    })
}

/// Writes observations.csv (`image,led,x_mm,y_mm`), with a leading comment.
pub fn write_observations(
    path: impl AsRef<Path>,
    comment: &str,
    rows: &[ObservationRow],
) -> Result<(), IoError> {
    write_atomic(path, |w| {
        for line in comment.lines() {
            writeln!(w, "# {line}")?;
        }
        writeln!(w, "image,led,x_mm,y_mm")?;
        for r in rows {
            writeln!(
                w,
                "{},{},{},{}",
                csv_field(&r.image),
                csv_field(&r.led),
                r.x_mm,
                r.y_mm
            )?;
        }
        Ok(())
    })
}

/// Writes signals.csv (`image,led,vx1,vx2,vy1,vy2`), with a leading comment.
pub fn write_signals(
    path: impl AsRef<Path>,
    comment: &str,
    rows: &[SignalRowOut],
) -> Result<(), IoError> {
    write_atomic(path, |w| {
        for line in comment.lines() {
            writeln!(w, "# {line}")?;
        }
        writeln!(w, "image,led,vx1,vx2,vy1,vy2")?;
        for r in rows {
            let a = &r.amplitudes;
            writeln!(
                w,
                "{},{},{},{},{},{}",
                csv_field(&r.image),
                csv_field(&r.led),
                a.vx1,
                a.vx2,
                a.vy1,
                a.vy2
            )?;
        }
        Ok(())
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::{Observations, Signals, Template};

    #[test]
    fn written_files_read_back_exactly() {
        let dir = tempfile::tempdir().unwrap();
        let leds = vec![
            TemplateLed {
                id: "1".into(),
                x_mm: -140.0,
                y_mm: 0.1 + 0.2,
                lines: vec!["r1".into(), "c1".into()],
            },
            TemplateLed {
                id: "a,b".into(),
                x_mm: 1e-300,
                y_mm: 7.0,
                lines: vec!["r1".into()],
            },
            TemplateLed {
                id: "3".into(),
                x_mm: 3.0,
                y_mm: -2.5,
                lines: vec!["r1".into()],
            },
            TemplateLed {
                id: "4".into(),
                x_mm: 9.0,
                y_mm: 11.0,
                lines: vec![],
            },
        ];
        let path = dir.path().join("template.csv");
        write_template(&path, "test template", &leds).unwrap();
        let t = Template::read(&path).unwrap();
        assert_eq!(t.leds.len(), 4);
        assert_eq!(t.leds[1].id, "a,b");
        assert_eq!(t.leds[0].y_mm, 0.1 + 0.2);
        assert_eq!(t.leds[1].x_mm, 1e-300);
        assert_eq!(t.leds[0].lines, vec!["r1".to_string(), "c1".to_string()]);
        let obs = vec![ObservationRow {
            image: "1".into(),
            led: "a,b".into(),
            x_mm: -3.3110186202550851,
            y_mm: 2.0 / 3.0,
        }];
        let path = dir.path().join("observations.csv");
        write_observations(&path, "noise-free", &obs).unwrap();
        let o = Observations::read(&path).unwrap();
        assert_eq!(o.rows[0].x_mm, -3.3110186202550851);
        assert_eq!(o.rows[0].y_mm, 2.0 / 3.0);
        assert_eq!(o.rows[0].led, "a,b");
        let sig = vec![SignalRowOut {
            image: "1".into(),
            led: "4".into(),
            amplitudes: Amplitudes {
                vx1: 0.1,
                vx2: 0.2,
                vy1: 1.0 / 3.0,
                vy2: 4e-7,
            },
        }];
        let path = dir.path().join("signals.csv");
        write_signals(&path, "", &sig).unwrap();
        let s = Signals::read(&path).unwrap();
        assert_eq!(s.rows[0].vy1, 1.0 / 3.0);
        assert_eq!(s.rows[0].vy2, 4e-7);
    }
}
