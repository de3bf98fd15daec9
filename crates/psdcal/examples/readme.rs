//! Calibrate the example data and answer a point (from the repository's
//! root: `cargo run --release -p psdcal --example readme`).
use nalgebra::Vector2;
use psdcal::{
    calibrate, sensor_of, CalibrationOptions, DataSet, DataSetFiles, LoadOptions, LocateOptions,
    Measurement, PointSource,
};

fn main() -> Result<(), psdcal::Error> {
    let set = DataSet::from_files(
        &DataSetFiles {
            template: "data/example/template.csv".into(),
            points: PointSource::Observations("data/example/observations.csv".into()),
            gains: None,
        },
        &LoadOptions::default(),
    )?;
    let calibrated = calibrate(&set, &CalibrationOptions::default())?;
    let sensor = sensor_of(&calibrated.record)?;
    let point = Measurement::Point(Vector2::new(1.0, -0.5));
    let answer = sensor.aoa(&point, &LocateOptions::default())?;
    let alpha = answer.aoa.alpha.map(f64::to_degrees);
    println!("alpha_x = {:.4} deg, alpha_y = {:.4} deg", alpha.x, alpha.y);
    Ok(())
}
