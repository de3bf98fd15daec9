//! Before any work: the files a job reads and writes, so that no output
//! replaces an input (psdcal-io's `refuse_overwrite`; exit 2).

use std::path::Path;

use psdcal::{LocateTarget, MapModel, PointSource};

use crate::cli::Job;

/// A path and the option that names it.
type Named<'a> = (&'static str, &'a Path);

/// The input and output files of `job` (folders of `simulate`, `study` and
/// `demo` are not checked: they read no file; `report`'s page is).
fn files(job: &Job) -> (Vec<Named<'_>>, Vec<Named<'_>>) {
    fn points(p: &PointSource) -> Named<'_> {
        match p {
            PointSource::Observations(path) => ("--observations", path.as_path()),
            PointSource::Signals(path) => ("--signals", path.as_path()),
        }
    }
    fn out(o: &Option<std::path::PathBuf>) -> Vec<Named<'_>> {
        o.iter().map(|p| ("--out", p.as_path())).collect()
    }
    match job {
        Job::Calibrate(c) => {
            let mut inputs = vec![("--template", c.template.as_path()), points(&c.points)];
            inputs.extend(c.gains_file.iter().map(|p| ("--gains", p.as_path())));
            let mut outputs = vec![("--out", c.out.as_path())];
            outputs.extend(c.residuals.iter().map(|p| ("--residuals", p.as_path())));
            (inputs, outputs)
        }
        Job::Gains(g) => (vec![("--signals", g.signals.as_path())], out(&g.out)),
        Job::Correct(c) => (
            vec![
                ("--calibration", c.calibration.as_path()),
                ("--points", c.points.as_path()),
            ],
            out(&c.out),
        ),
        Job::Aoa(c) => (
            vec![
                ("--calibration", c.calibration.as_path()),
                ("--points", c.points.as_path()),
            ],
            out(&c.out),
        ),
        Job::Locate(c) => {
            let target = match &c.target {
                LocateTarget::Plane { calibration, .. } => ("--calibration", calibration.as_path()),
                LocateTarget::Rig(rig) => ("--rig", rig.as_path()),
            };
            (vec![target, ("--points", c.points.as_path())], out(&c.out))
        }
        Job::Map(c) => {
            let inputs = match &c.model {
                MapModel::Calibration(path) => vec![("--calibration", path.as_path())],
                _ => Vec::new(),
            };
            (inputs, out(&c.out))
        }
        Job::Report(c) => {
            let mut inputs = vec![("--calibration", c.calibration.as_path())];
            if let Some((t, o)) = &c.data {
                inputs.extend([("--template", t.as_path()), ("--observations", o.as_path())]);
            }
            (inputs, Vec::new())
        }
        Job::Demodulate(d) => {
            let mut inputs = vec![
                ("--raw", d.raw.as_path()),
                ("--schedule", d.schedule.as_path()),
            ];
            inputs.extend(d.tones.iter().map(|p| ("--tones", p.as_path())));
            (inputs, vec![("--out", d.out.as_path())])
        }
        _ => (Vec::new(), Vec::new()),
    }
}

/// Refuses a job whose output is one of its inputs (or two outputs that are
/// one file).
pub fn check(job: &Job) -> Result<(), psdcal::IoError> {
    let (inputs, outputs) = files(job);
    psdcal_io::refuse_overwrite(&inputs, &outputs)
}
