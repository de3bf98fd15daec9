//! The raw path end to end (docs/model.md §8 "Demodulation"): a simulated
//! raw recording (raw.csv, raw.npy or raw.tdms with schedule.csv, tones.csv)
//! through `demodulate` gives the amplitudes the internal signal chain gives
//! — exactly without noise and impairments, the same file from csv, npy and
//! tdms —
//! and, with noise and every impairment of a card, a calibration of the same
//! angle-of-arrival quality as the internal chain's at the same SNR
//! (seeded Monte Carlo).

use std::path::Path;

use nalgebra::Vector2;
use psdcal::{
    calibrate, demodulate, simulate_raw_files, CalibrationOptions, DataSet, DataSetFiles,
    DemodConfig, DemodulateRequest, Impairments, Lens, LoadOptions, PointSource, RawFormat,
    RawRequest, RecordStatus, SimulateRequest, TemplateKind,
};
use psdcal_io::{read_truth, Calibration, Signals};
use psdcal_model::{Intrinsics, Model, SensorModel};

fn request(dir: &Path, snr_db: Option<f64>, seed: u64) -> SimulateRequest {
    SimulateRequest {
        lens: Lens::Two,
        snr_db,
        imbalance: false,
        psd_distortion: false,
        psd_nonlinearity: false,
        images: 9,
        template: TemplateKind::Scatter14,
        record_cycles: 65,
        seed,
        out: dir.to_path_buf(),
        force: false,
    }
}

fn demodulated(dir: &Path, format: RawFormat, fdma: bool, out: &str) -> psdcal::Demodulated {
    let raw = dir.join(match format {
        RawFormat::Npy => "raw.npy",
        RawFormat::Tdms => "raw.tdms",
        _ => "raw.csv",
    });
    demodulate(&DemodulateRequest {
        raw,
        rate_hz: Some(psdcal::RAW_SAMPLE_RATE_HZ),
        schedule: dir.join("schedule.csv"),
        tones: fdma.then(|| dir.join("tones.csv")),
        frequency_hz: psdcal::RAW_F0_HZ,
        out: dir.join(out),
        config: DemodConfig::default(),
        channels: Vec::new(),
        limits: Default::default(),
    })
    .unwrap()
}

#[test]
fn noise_free_raw_recordings_give_the_exact_amplitudes() {
    let dir = tempfile::tempdir().unwrap();
    for fdma in [false, true] {
        for format in [RawFormat::Csv, RawFormat::Npy, RawFormat::Tdms] {
            let raw = RawRequest {
                format,
                fdma,
                impairments: Impairments::none(),
            };
            simulate_raw_files(&request(dir.path(), None, 3), &raw).unwrap();
            let name = format!("signals_{fdma}_{format:?}.csv");
            let done = demodulated(dir.path(), format, fdma, &name);
            assert_eq!(done.written(), 126, "{:?}", done.counts());
            let want = Signals::read(dir.path().join("signals.csv")).unwrap();
            let got = Signals::read(dir.path().join(&name)).unwrap();
            for (w, g) in want.rows.iter().zip(&got.rows) {
                assert_eq!((&w.image, &w.led), (&g.image, &g.led));
                let (w, g) = (w.amplitudes(), g.amplitudes());
                for (a, b) in [
                    (w.vx1, g.vx1),
                    (w.vx2, g.vx2),
                    (w.vy1, g.vy1),
                    (w.vy2, g.vy2),
                ] {
                    assert!((a - b).abs() <= 1e-12 * a, "fdma {fdma}: {a} vs {b}");
                }
            }
        }
        // The same signals.csv from raw.csv, raw.npy and raw.tdms (after the
        // comment line naming the source).
        let body = |f: RawFormat| {
            let text =
                std::fs::read_to_string(dir.path().join(format!("signals_{fdma}_{f:?}.csv")))
                    .unwrap();
            text.lines().skip(1).collect::<Vec<_>>().join("\n")
        };
        assert_eq!(body(RawFormat::Csv), body(RawFormat::Npy));
        assert_eq!(body(RawFormat::Csv), body(RawFormat::Tdms));
    }
}

/// RMS angle-of-arrival error, rad, of a calibration against the truth over
/// a 9 × 9 grid of directions (80 % of the sensor).
fn aoa_rms(truth: &SensorModel, record: &Calibration) -> f64 {
    let i = &record.intrinsics;
    let model = SensorModel {
        intrinsics: Intrinsics {
            f: i.f_mm,
            cx: i.cx_mm,
            cy: i.cy_mm,
            skew: i.skew,
        },
        distortion: record.distortion,
    };
    let (model, truth) = (Model::standard(&model), Model::standard(truth));
    let (mut sum, mut n) = (0.0, 0.0);
    for a in 0..9 {
        for b in 0..9 {
            let ideal = Vector2::new(
                0.4 * 9.0 * (a as f64 / 4.0 - 1.0),
                0.4 * 9.0 * (b as f64 / 4.0 - 1.0),
            );
            let measured = truth.measured_from_ideal_to_tolerance(&ideal).unwrap();
            let est = model.direction(&measured);
            let want = truth.direction_of_ideal(&ideal);
            let angle = est.cross(&want).norm().atan2(est.dot(&want));
            sum += angle * angle;
            n += 1.0;
        }
    }
    (sum / n).sqrt()
}

fn calibrated_error(dir: &Path, signals: &str, truth: &SensorModel) -> f64 {
    let set = DataSet::from_files(
        &DataSetFiles {
            template: dir.join("template.csv"),
            points: PointSource::Signals(dir.join(signals)),
            gains: None,
        },
        &LoadOptions::default(),
    )
    .unwrap();
    let calibrated = calibrate(&set, &CalibrationOptions::default()).unwrap();
    aoa_rms(truth, &calibrated.record)
}

#[test]
fn raw_path_calibrates_as_well_as_the_internal_chain() {
    let trials = 80;
    let (mut raw_sq, mut internal_sq) = (Vec::new(), Vec::new());
    for seed in 0..trials {
        let dir = tempfile::tempdir().unwrap();
        let raw = RawRequest {
            format: RawFormat::Npy,
            fdma: false,
            impairments: Impairments::default(),
        };
        simulate_raw_files(&request(dir.path(), Some(40.0), 100 + seed), &raw).unwrap();
        let done = demodulated(dir.path(), RawFormat::Npy, false, "demodulated.csv");
        assert!(done.records.iter().all(|r| r.status == RecordStatus::Ok));
        // The per-record SNR (lowest channel) sits near the simulated 40 dB;
        // the weakest channels also carry the ADC's quantisation noise
        // (88 µV) and lose a few dB.
        let (lo, med, hi) = done.snr_range().unwrap();
        assert!((med - 40.0).abs() < 1.5 && hi < 42.0, "{lo} {med} {hi}");
        let t = read_truth(dir.path().join("truth.json")).unwrap();
        let truth = SensorModel {
            intrinsics: Intrinsics {
                f: t.intrinsics.f_mm,
                cx: t.intrinsics.cx_mm,
                cy: t.intrinsics.cy_mm,
                skew: t.intrinsics.skew,
            },
            distortion: t.distortion,
        };
        raw_sq.push(calibrated_error(dir.path(), "demodulated.csv", &truth).powi(2));
        internal_sq.push(calibrated_error(dir.path(), "signals.csv", &truth).powi(2));
    }
    let mean = |v: &[f64]| v.iter().sum::<f64>() / v.len() as f64;
    let ratio = (mean(&raw_sq) / mean(&internal_sq)).sqrt();
    // Standard error of the ratio of the two RMS errors from the trials'
    // spread (delta method on the mean squares, independent noise).
    let rel_var = |v: &[f64]| {
        let m = mean(v);
        v.iter().map(|x| (x - m).powi(2)).sum::<f64>()
            / ((v.len() - 1) as f64 * v.len() as f64)
            / (m * m)
    };
    let se = 0.5 * (rel_var(&raw_sq) + rel_var(&internal_sq)).sqrt() * ratio;
    println!("raw / internal AoA RMS error = {ratio:.3} ± {se:.3}");
    assert!(
        (ratio - 1.0).abs() < 0.10 + 2.0 * se,
        "ratio {ratio} ± {se}"
    );
}

/// `track` on the samples of a recording, one window per record, gives the
/// angles of the amplitudes `demodulate` finds in the same records (each
/// window demodulated on its own, as a record is); a malformed line gets a
/// status and the stream goes on.
#[test]
fn track_gives_the_angles_of_demodulate() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let raw = RawRequest {
        format: RawFormat::Csv,
        fdma: true,
        impairments: Impairments::default(),
    };
    simulate_raw_files(&request(d, Some(40.0), 8), &raw).unwrap();
    demodulated(d, RawFormat::Csv, true, "demodulated.csv");
    let set = DataSet::from_files(
        &DataSetFiles {
            template: d.join("template.csv"),
            points: PointSource::Signals(d.join("signals.csv")),
            gains: None,
        },
        &LoadOptions::default(),
    )
    .unwrap();
    calibrate(&set, &CalibrationOptions::default())
        .unwrap()
        .write(&set, &d.join("cal.json"), None)
        .unwrap();
    // The stream: vx1..vy2 only, a malformed line after the first window.
    let text = std::fs::read_to_string(d.join("raw.csv")).unwrap();
    let mut stream = String::from("vx1,vx2,vy1,vy2\n");
    for (n, line) in text
        .lines()
        .filter(|l| !l.starts_with('#'))
        .skip(1)
        .enumerate()
    {
        if n == 1300 {
            stream += "1,2,oops,4\n";
        }
        stream += line.split_once(',').unwrap().1;
        stream.push('\n');
    }
    let mut out = Vec::new();
    let summary = psdcal::track(
        &psdcal::TrackRequest {
            target: psdcal::TrackTarget::Sensor(d.join("cal.json")),
            rate_hz: Some(psdcal::RAW_SAMPLE_RATE_HZ),
            tones: d.join("tones.csv"),
            window_s: 0.065,
            config: DemodConfig::default(),
            raw: None,
            channels: Vec::new(),
            limits: Default::default(),
            filter: Default::default(),
        },
        stream.as_bytes(),
        &mut out,
    )
    .unwrap();
    assert_eq!((summary.windows, summary.malformed), (9, 1));
    let out = String::from_utf8(out).unwrap();
    let rows: Vec<&str> = out.lines().collect();
    // The same recording as raw.tdms, read with --raw (its rate from
    // wf_increment): the same rows but the malformed line's.
    let raw_tdms = RawRequest {
        format: RawFormat::Tdms,
        ..raw
    };
    simulate_raw_files(&request(d, Some(40.0), 8), &raw_tdms).unwrap();
    let mut from_file = Vec::new();
    psdcal::track(
        &psdcal::TrackRequest {
            target: psdcal::TrackTarget::Sensor(d.join("cal.json")),
            rate_hz: None,
            tones: d.join("tones.csv"),
            window_s: 0.065,
            config: DemodConfig::default(),
            raw: Some(d.join("raw.tdms")),
            channels: Vec::new(),
            limits: Default::default(),
            filter: Default::default(),
        },
        &b""[..],
        &mut from_file,
    )
    .unwrap();
    let from_file = String::from_utf8(from_file).unwrap();
    let without_malformed: Vec<&str> = rows
        .iter()
        .copied()
        .filter(|r| !r.ends_with("malformed_line"))
        .collect();
    assert_eq!(from_file.lines().collect::<Vec<_>>(), without_malformed);
    assert_eq!(rows[0], "t_s,led,alpha_x_deg,alpha_y_deg,snr_db,status");
    assert_eq!(rows[15], "0.065,,,,,malformed_line");
    let sensor = psdcal::LoadedSensor::read(&d.join("cal.json")).unwrap();
    let signals = Signals::read(d.join("demodulated.csv")).unwrap();
    let data_rows: Vec<&str> = rows[1..]
        .iter()
        .copied()
        .filter(|r| !r.ends_with("malformed_line"))
        .collect();
    assert_eq!(data_rows.len(), signals.rows.len());
    for (row, s) in data_rows.iter().zip(&signals.rows) {
        let f: Vec<&str> = row.split(',').collect();
        assert_eq!(f[1], s.led);
        assert_eq!(f[5], "ok");
        let answer = sensor
            .sensor
            .aoa(
                &psdcal::Measurement::Amplitudes(s.amplitudes()),
                &psdcal::LocateOptions::default(),
            )
            .unwrap();
        let ax: f64 = f[2].parse().unwrap();
        let ay: f64 = f[3].parse().unwrap();
        // signals.csv holds the amplitudes to the last digit: the same angles.
        assert!((ax - answer.aoa.alpha.x.to_degrees()).abs() < 1e-9, "{row}");
        assert!((ay - answer.aoa.alpha.y.to_degrees()).abs() < 1e-9, "{row}");
        assert_eq!(f[4].parse::<f64>().unwrap(), s.snr_db.unwrap());
    }
}
