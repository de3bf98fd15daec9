"""The rest of the API: save/load round trip, simulate → calibrate against
the truth, amplitudes in, options as keywords, demodulate."""

import json
import subprocess

import numpy as np
import pytest

import psdcal


def test_save_load_round_trip(example, tmp_path):
    cal = psdcal.calibrate(example / "template.csv", observations=example / "observations.csv")
    path = tmp_path / "calibration.json"
    cal.save(path)
    assert json.loads(path.read_text())["format"] == "psdcal-calibration"
    back = psdcal.Calibration.load(str(path))
    assert back.parameters == cal.parameters
    assert back.std == cal.std
    pts = np.array([[0.0, 0.0], [2.0, -1.0]])
    np.testing.assert_array_equal(back.aoa(pts), cal.aoa(pts))
    assert not list(tmp_path.glob("*.tmp*"))
    assert "psdcal.Calibration" in repr(cal)


def test_simulate_then_calibrate_recovers_the_truth():
    data = psdcal.simulate(lens=2, snr_db=60, images=9, seed=3)
    assert data["template"].shape == (14, 2)
    assert data["observations"].shape[1] == 4 and data["signals"].shape[1] == 6
    assert data["poses"].shape == (9, 6)
    cal = psdcal.calibrate(data["template"], observations=data["observations"])
    truth = data["truth"]
    for name in ("f", "cx", "cy", "k1"):
        sigma = cal.std[name]
        assert abs(cal.parameters[name] - truth[name]) < 5 * sigma, name
    # Same seed, same data; another seed, other data.
    again = psdcal.simulate(lens=2, snr_db=60, images=9, seed=3)
    np.testing.assert_array_equal(again["observations"], data["observations"])
    other = psdcal.simulate(lens=2, snr_db=60, images=9, seed=4)
    assert not np.array_equal(other["observations"], data["observations"])


def test_signals_and_amplitudes(example):
    cal = psdcal.calibrate(example / "template.csv", signals=example / "signals.csv",
                           fit="f,cx,cy,k1,k2,gains")
    assert {"g_x2", "g_y1", "g_y2"} <= cal.std.keys()
    lines = [l for l in (example / "signals.csv").read_text().splitlines()
             if not l.startswith("#")][1:]
    rows = np.loadtxt(lines, delimiter=",", ndmin=2)
    alpha = cal.aoa(rows[:5, 2:6])
    assert alpha.shape == (5, 2) and np.isfinite(alpha).all()


def test_options_as_keywords(example):
    cal = psdcal.calibrate(
        example / "template.csv",
        observations=example / "observations.csv",
        fit=["f", "cx", "cy", "k1"],
        set={"k2": 3e-5},
        cost="image",
        preliminary="off",
    )
    names, _ = cal.covariance
    assert names == ["f", "cx", "cy", "k1"]
    assert cal.parameters["k2"] == 3e-5
    loc, cov = cal.locate([[0.0, 0.0]], distance=1000, return_covariance=True)
    assert loc.shape == (1, 3) and cov.shape == (1, 3, 3)


def test_demodulate_matches_the_cli(cli, tmp_path):
    sim = tmp_path / "sim"
    subprocess.run(cli + ["--quiet", "simulate", "--images", "3", "--snr", "50", "--raw", "csv",
                          "--out", str(sim)], check=True)
    out = tmp_path / "signals.csv"
    subprocess.run(cli + ["--quiet", "demodulate", "--raw", str(sim / "raw.csv"),
                          "--schedule", str(sim / "schedule.csv"), "--out", str(out)], check=True)
    got = psdcal.demodulate(sim / "raw.csv", schedule=sim / "schedule.csv")
    lines = [l for l in out.read_text().splitlines() if not l.startswith("#")]
    header = lines[0].split(",")
    rows = [dict(zip(header, l.split(","))) for l in lines[1:]]
    assert got["image"] == [r["image"] for r in rows]
    want = np.array([[float(r[c]) for c in ("vx1", "vx2", "vy1", "vy2")] for r in rows])
    np.testing.assert_allclose(got["amplitudes"], want, rtol=1e-12, atol=0)
    np.testing.assert_allclose(got["snr_db"], [float(r["snr_db"]) for r in rows], rtol=1e-12)
    with pytest.raises(psdcal.PsdcalError, match="schedule"):
        psdcal.demodulate(sim / "raw.csv")
