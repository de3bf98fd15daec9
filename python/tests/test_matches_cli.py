"""The Python package gives the command line's answers on the same data:
calibration.json's parameters, σ and covariance, and the angles of arrival,
equal to 1e-12 relative (the same code computes both: a difference means a
front end changed the data or the options)."""

import csv
import json
import subprocess

import numpy as np
import pytest

import psdcal

RTOL = 1e-12


def close(a, b):
    a, b = np.asarray(a, dtype=float), np.asarray(b, dtype=float)
    assert a.shape == b.shape
    np.testing.assert_allclose(a, b, rtol=RTOL, atol=0.0)


@pytest.fixture(scope="module")
def cli_calibration(cli, example, tmp_path_factory):
    out = tmp_path_factory.mktemp("cli") / "calibration.json"
    subprocess.run(
        cli
        + [
            "--quiet",
            "calibrate",
            "--template",
            str(example / "template.csv"),
            "--observations",
            str(example / "observations.csv"),
            "--out",
            str(out),
        ],
        check=True,
    )
    return out


@pytest.fixture(scope="module")
def py_calibration(example):
    return psdcal.calibrate(
        example / "template.csv", observations=str(example / "observations.csv")
    )


def test_calibration_json_matches_the_cli(cli_calibration, py_calibration, tmp_path):
    saved = tmp_path / "calibration.json"
    py_calibration.save(saved)
    a = json.loads(cli_calibration.read_text())
    b = json.loads(saved.read_text())
    for section in ("parameters", "std"):
        assert a[section].keys() == b[section].keys()
        for key in a[section]:
            close(a[section][key], b[section][key])
    assert a["covariance"]["parameters"] == b["covariance"]["parameters"]
    assert a["covariance"]["parameters"] == ["f", "cx", "cy", "k1", "k2"]
    close(a["covariance"]["matrix"], b["covariance"]["matrix"])
    assert a["stages"] == b["stages"]
    close(a["fit"]["residual_mm2"], b["fit"]["residual_mm2"])
    # The loaded file is the same calibration.
    loaded = psdcal.Calibration.load(cli_calibration)
    assert loaded.parameters.keys() == py_calibration.parameters.keys()
    for name, value in py_calibration.parameters.items():
        close(loaded.parameters[name], value)


def test_parameters_std_and_covariance(py_calibration):
    p = py_calibration.parameters
    # The example's truth (noise-free data of the paper's lens 2).
    assert abs(p["f"] - 8.0) < 1e-6
    assert abs(p["cx"] - 0.5) < 1e-6 and abs(p["cy"] + 0.7) < 1e-6
    names, cov = py_calibration.covariance
    assert names == ["f", "cx", "cy", "k1", "k2"]
    assert cov.shape == (5, 5)
    np.testing.assert_array_equal(cov, cov.T)
    for i, name in enumerate(names):
        assert py_calibration.std[name] == pytest.approx(np.sqrt(cov[i, i]), rel=1e-12)
    assert isinstance(py_calibration.diagnostics, list)


def test_aoa_matches_the_cli(cli, cli_calibration, py_calibration, tmp_path):
    rng = np.random.default_rng(7)
    points = rng.uniform(-3.5, 3.5, size=(25, 2))
    points_csv = tmp_path / "points.csv"
    with points_csv.open("w", newline="") as f:
        w = csv.writer(f)
        w.writerow(["x_mm", "y_mm"])
        # repr: the shortest text that reads back as the same float.
        w.writerows([[repr(float(x)), repr(float(y))] for x, y in points])
    out = tmp_path / "aoa.csv"
    subprocess.run(
        cli
        + [
            "--quiet",
            "aoa",
            "--calibration",
            str(cli_calibration),
            "--points",
            str(points_csv),
            "--out",
            str(out),
        ],
        check=True,
    )
    with out.open() as f:
        rows = [r for r in csv.DictReader(line for line in f if not line.startswith("#"))]
    assert [r["status"] for r in rows] == ["ok"] * len(points)
    alpha, sigma = py_calibration.aoa(points, return_sigma=True)
    close(alpha, [[float(r["alpha_x_deg"]), float(r["alpha_y_deg"])] for r in rows])
    close(sigma, [[float(r["sigma_alpha_x_deg"]), float(r["sigma_alpha_y_deg"])] for r in rows])
    ideal = py_calibration.correct(points)
    close(ideal, [[float(r["x_ideal_mm"]), float(r["y_ideal_mm"])] for r in rows])
    corrected = tmp_path / "corrected.csv"
    subprocess.run(
        cli
        + ["--quiet", "correct", "--calibration", str(cli_calibration), "--points",
           str(points_csv), "--out", str(corrected)],
        check=True,
    )
    with corrected.open() as f:
        rows = list(csv.DictReader(line for line in f if not line.startswith("#")))
    close(ideal, [[float(r["x_ideal_mm"]), float(r["y_ideal_mm"])] for r in rows])


def test_locate_matches_the_cli(cli, cli_calibration, py_calibration, tmp_path):
    points = np.array([[0.5, -0.7], [1.0, 2.0], [-2.5, 0.25]])
    points_csv = tmp_path / "points.csv"
    points_csv.write_text("x_mm,y_mm\n" + "".join(f"{float(x)!r},{float(y)!r}\n" for x, y in points))
    out = tmp_path / "located.csv"
    subprocess.run(
        cli
        + [
            "--quiet",
            "locate",
            "--calibration",
            str(cli_calibration),
            "--points",
            str(points_csv),
            "--distance",
            "2000",
            "--out",
            str(out),
        ],
        check=True,
    )
    with out.open() as f:
        rows = list(csv.DictReader(line for line in f if not line.startswith("#")))
    located = py_calibration.locate(points, distance=2000)
    want = [[float(r[f"{a}_sensor_mm"]) for a in "xyz"] for r in rows]
    close(located, want)
    np.testing.assert_array_equal(located[:, 2], 2000.0)
    on_plane = py_calibration.locate(points, plane=(0, 0, 1, 2000))
    close(on_plane, located)


def test_arrays_give_the_files_answer(example, py_calibration):
    def table(name):
        lines = [l for l in (example / name).read_text().splitlines() if not l.startswith("#")]
        return np.loadtxt(lines[1:], delimiter=",", ndmin=2)

    template = table("template.csv")
    observations = table("observations.csv")
    from_arrays = psdcal.calibrate(template, observations=observations)
    for name, value in py_calibration.parameters.items():
        close(from_arrays.parameters[name], value)
    # Without the LED column the template's LEDs are numbered 1 … N.
    numbered = psdcal.calibrate(template[:, 1:], observations=observations)
    close(numbered.parameters["f"], py_calibration.parameters["f"])
