//! Before any work: the files a job reads and writes, so that no output
//! replaces an input (psdcal-io's `refuse_overwrite`; exit 2).

use std::path::Path;

use psdcal::{LocateTarget, MapModel, PointSource};

use crate::cli::Job;

/// A path and the option that names it.
type Named<'a> = (&'static str, &'a Path);

/// The input and output files of `job` (folders of `simulate`, `study` and
/// `demo` are not checked: they read no file; `report`'s page is, and the
/// calibrations a rig lists).
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
            inputs.extend(c.options.psd_map.iter().map(|p| ("--psd-map", p.as_path())));
            let mut outputs = vec![("--out", c.out.as_path())];
            outputs.extend(c.residuals.iter().map(|p| ("--residuals", p.as_path())));
            (inputs, outputs)
        }
        Job::Gains(g) => (vec![("--signals", g.signals.as_path())], out(&g.out)),
        Job::SimulateScan(s) => (Vec::new(), vec![("--out", s.out.as_path())]),
        Job::PsdMap(m) => (
            vec![("--scan", m.scan.as_path())],
            vec![("--out", m.out.as_path())],
        ),
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
            // The page is the one output whose name an input could have
            // (the plots are .svg and .png files).
            (inputs, vec![("--out", c.page.as_path())])
        }
        Job::Evaluate(e) => {
            let mut inputs = vec![
                ("--truth", e.truth.as_path()),
                ("--estimates", e.estimates.as_path()),
            ];
            inputs.extend(e.rig.iter().map(|p| ("--rig", p.as_path())));
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
        Job::CalibrateInSitu(a) => {
            let mut outputs = vec![("--out", a.out.as_path())];
            outputs.extend(a.poses_out.iter().map(|p| ("--poses-out", p.as_path())));
            (
                vec![
                    ("--template", a.template.as_path()),
                    ("--observations", a.observations.as_path()),
                ],
                outputs,
            )
        }
        _ => (Vec::new(), Vec::new()),
    }
}

/// Refuses a job whose output is one of its inputs (or two outputs that are
/// one file).
pub fn check(job: &Job) -> Result<(), psdcal::IoError> {
    let (inputs, outputs) = files(job);
    psdcal_io::refuse_overwrite(&inputs, &outputs)?;
    // The calibrations a rig lists are inputs too (a rig that cannot be read
    // is the job's own error, reported when it runs).
    if let Job::Locate(c) = job {
        if let LocateTarget::Rig(rig) = &c.target {
            if let Ok(file) = psdcal_io::read_rig(rig) {
                let listed: Vec<Named<'_>> = file
                    .sensors
                    .iter()
                    .map(|s| {
                        (
                            "a calibration listed in --rig",
                            s.calibration_path.as_path(),
                        )
                    })
                    .collect();
                psdcal_io::refuse_overwrite(&listed, &outputs)?;
            }
        }
    }
    Ok(())
}
