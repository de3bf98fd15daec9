"""Bad input raises PsdcalError (a ValueError) with a clear message — the
command line's own for the same mistake — and never crashes the
interpreter."""

import math
import subprocess

import numpy as np
import pytest

import psdcal


def cli_error(cli, args):
    run = subprocess.run(cli + args, capture_output=True, text=True)
    assert run.returncode == 1, run.stderr
    line = run.stderr.strip().splitlines()[-1]
    assert line.startswith("error: ")
    return line[len("error: "):]


@pytest.fixture(scope="module")
def cal(example):
    return psdcal.calibrate(example / "template.csv", observations=example / "observations.csv")


def test_is_a_value_error():
    assert issubclass(psdcal.PsdcalError, ValueError)


def test_missing_file_has_the_cli_message(cli, example, tmp_path):
    missing = tmp_path / "nope.csv"
    with pytest.raises(psdcal.PsdcalError) as e:
        psdcal.calibrate(example / "template.csv", observations=missing)
    want = cli_error(
        cli,
        ["calibrate", "-t", str(example / "template.csv"), "-o", str(missing),
         "--out", str(tmp_path / "c.json")],
    )
    assert str(e.value) == want
    assert "nope.csv" in want


def test_bad_data_file_has_the_cli_message(cli, example, tmp_path):
    bad = tmp_path / "observations.csv"
    text = (example / "observations.csv").read_text().splitlines()
    text[5] = "1,2,abc,0.5"
    bad.write_text("\n".join(text) + "\n")
    with pytest.raises(psdcal.PsdcalError) as e:
        psdcal.calibrate(example / "template.csv", observations=bad)
    want = cli_error(
        cli,
        ["calibrate", "-t", str(example / "template.csv"), "-o", str(bad),
         "--out", str(tmp_path / "c.json")],
    )
    assert str(e.value) == want
    assert ":6" in want


def test_failed_calibration_has_the_cli_message(cli, example, tmp_path):
    # Two images: too few for a calibration.
    few = tmp_path / "observations.csv"
    lines = (example / "observations.csv").read_text().splitlines()
    few.write_text("\n".join(l for l in lines if l.split(",")[0] in ("image", "1", "2")) + "\n")
    with pytest.raises(psdcal.PsdcalError) as e:
        psdcal.calibrate(example / "template.csv", observations=few)
    want = cli_error(
        cli,
        ["calibrate", "-t", str(example / "template.csv"), "-o", str(few),
         "--out", str(tmp_path / "c.json")],
    )
    assert str(e.value) == want
    assert want.startswith("calibration failed: ")


def test_missing_calibration_has_the_cli_message(cli, tmp_path):
    missing = tmp_path / "calibration.json"
    points = tmp_path / "points.csv"
    points.write_text("x_mm,y_mm\n0,0\n")
    with pytest.raises(psdcal.PsdcalError) as e:
        psdcal.Calibration.load(missing)
    assert str(e.value) == cli_error(cli, ["aoa", "-c", str(missing), "-p", str(points)])


def test_option_values_are_refused_with_the_shared_words(example):
    for kwargs, words in [
        ({"focal_guess": -3}, "option focal_guess: expected a positive length in mm"),
        ({"fit": "f,zz"}, "option fit: "),
        ({"fit": ["f", "cx", "gains"]}, "needs the electrode amplitudes"),
        ({"robust": "tukey:1"}, "option robust: unknown loss 'tukey'"),
        ({"uncertainty": "bootstrap:3"}, "at least 10 resamples"),
        ({"cost": "pixels"}, "option cost: expected template or image"),
        ({"colour": "red"}, "unknown option 'colour'"),
        ({"lx": math.nan}, "option lx: expected the side of the active area"),
    ]:
        with pytest.raises(psdcal.PsdcalError) as e:
            psdcal.calibrate(example / "template.csv", observations=example / "observations.csv",
                             **kwargs)
        assert words in str(e.value), (kwargs, str(e.value))
        assert "; " in str(e.value)  # the advice follows


def test_bad_arrays(example, cal):
    template = np.array([[0, 0], [100, 0], [0, 100], [100, 100]], dtype=float)
    obs = np.array([[1, 1, 0.0, 0.0], [1, 2, math.nan, 0.0]])
    with pytest.raises(psdcal.PsdcalError, match=r"observations array:2: x_mm \(column 3\) is NaN"):
        psdcal.calibrate(template, observations=obs)
    with pytest.raises(psdcal.PsdcalError, match=r"has 3 columns; expected \(M, 4\)"):
        psdcal.calibrate(template, observations=np.zeros((5, 3)))
    with pytest.raises(psdcal.PsdcalError, match=r"shape \[2, 2, 2\]"):
        psdcal.calibrate(template, observations=np.zeros((2, 2, 2)))
    with pytest.raises(psdcal.PsdcalError, match="expected a path or a 2-D array of numbers"):
        psdcal.calibrate(template, observations={"x": 1})
    with pytest.raises(psdcal.PsdcalError, match="exactly one of observations"):
        psdcal.calibrate(template)
    with pytest.raises(psdcal.PsdcalError, match=r"points array:2: y_mm \(column 2\) is inf"):
        cal.aoa([[0.0, 0.0], [0.0, math.inf]])
    with pytest.raises(psdcal.PsdcalError, match=r"has 3 columns"):
        cal.correct(np.zeros((4, 3)))
    with pytest.raises(psdcal.PsdcalError, match="has no rows"):
        cal.aoa(np.zeros((0, 2)))
    with pytest.raises(psdcal.PsdcalError, match="exactly one of distance"):
        cal.locate([[0.0, 0.0]])
    with pytest.raises(psdcal.PsdcalError, match="expected a positive length"):
        cal.locate([[0.0, 0.0]], distance=-5)
    with pytest.raises(psdcal.PsdcalError, match="expected a path"):
        psdcal.Calibration.load(3)


def test_a_row_that_cannot_be_answered_is_named(cal):
    # Zero light on every electrode: no impact point.
    with pytest.raises(psdcal.PsdcalError, match=r"points array:2: no_light"):
        cal.aoa([[1.0, 1.0, 1.0, 1.0], [0.0, 0.0, 0.0, 0.0]])
    # A point far outside the valid region.
    with pytest.raises(psdcal.PsdcalError, match=r"points array:1: outside_valid_region"):
        cal.correct([[400.0, 400.0]])


def test_too_few_images_fail_with_advice(example):
    obs = np.array([[1, led, 0.1 * led, 0.05 * led] for led in range(1, 8)], dtype=float)
    template = np.loadtxt(
        [l for l in (example / "template.csv").read_text().splitlines() if not l.startswith("#")][1:],
        delimiter=",",
    )
    with pytest.raises(psdcal.PsdcalError) as e:
        psdcal.calibrate(template, observations=obs)
    assert "; " in str(e.value)


def test_save_refuses_to_overwrite_an_input(example, tmp_path):
    template = tmp_path / "template.csv"
    template.write_bytes((example / "template.csv").read_bytes())
    cal = psdcal.calibrate(template, observations=example / "observations.csv")
    with pytest.raises(psdcal.PsdcalError, match="would overwrite the input"):
        cal.save(template)
    assert template.read_bytes() == (example / "template.csv").read_bytes()
