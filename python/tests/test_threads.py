"""The per-point answers (`aoa`, `correct`, `locate`) release the GIL while
they compute and stop at Ctrl-C; threads give the same answers as one call;
integer and number arguments out of range raise PsdcalError.

Nothing here is timed against a bound in seconds: the GIL test compares the
longest pause of a Python thread with the length of one chunk of work (a
held GIL pauses it for a whole chunk; a released one for scheduling
latencies only), the Ctrl-C test compares when the call stops with how long
it would have taken."""

import _thread
import threading
import time

import numpy as np
import pytest

import psdcal

# Rows per chunk of the binding (python/src/calibration.rs, CHUNK_ROWS).
CHUNK = 16_384


@pytest.fixture(scope="module")
def cal(example):
    return psdcal.calibrate(
        str(example / "template.csv"), observations=str(example / "observations.csv")
    )


def points(n, seed=1):
    return np.random.default_rng(seed).uniform(-3.0, 3.0, size=(n, 2))


@pytest.mark.parametrize("call", ["aoa", "correct", "locate"])
def test_another_thread_runs_during_a_call(cal, call):
    pts = points(4 * CHUNK)
    run = {
        "aoa": lambda: cal.aoa(pts, return_sigma=True),
        "correct": lambda: cal.correct(pts),
        "locate": lambda: cal.locate(pts, distance=2000, return_covariance=True),
    }[call]
    done = threading.Event()
    gaps = []

    def watch():
        last = time.perf_counter()
        while not done.is_set():
            now = time.perf_counter()
            gaps.append(now - last)
            last = now

    watcher = threading.Thread(target=watch)
    watcher.start()
    start = time.perf_counter()
    run()
    duration = time.perf_counter() - start
    done.set()
    watcher.join()
    chunk_time = duration / 4
    # With the GIL held the watcher would stand still for whole chunks.
    assert len(gaps) > 100
    assert max(gaps) < 0.5 * chunk_time, (max(gaps), chunk_time)


def test_threads_answer_as_one_call(cal):
    pts = points(2 * CHUNK + 5)
    expected = cal.aoa(pts, return_sigma=True)
    results = [None] * 3

    def work(i):
        results[i] = cal.aoa(pts, return_sigma=True)

    threads = [threading.Thread(target=work, args=(i,)) for i in range(3)]
    for t in threads:
        t.start()
    for t in threads:
        t.join()
    for alpha, sigma in results:
        assert np.array_equal(alpha, expected[0])
        assert np.array_equal(sigma, expected[1])
    # The chunks join into the rows of one call: row k is point k's answer.
    assert np.array_equal(cal.aoa(pts[CHUNK : CHUNK + 3]), expected[0][CHUNK : CHUNK + 3])


def test_ctrl_c_stops_a_long_call(cal):
    pts = points(2 * CHUNK)
    start = time.perf_counter()
    cal.aoa(pts)
    per_row = (time.perf_counter() - start) / len(pts)
    many = points(100 * CHUNK)  # 50 × the call just timed
    full = per_row * len(many)
    timer = threading.Timer(2 * per_row * CHUNK, _thread.interrupt_main)
    start = time.perf_counter()
    timer.start()
    with pytest.raises(KeyboardInterrupt):
        cal.aoa(many)
        time.sleep(full)  # not reached when the call stopped
    stopped = time.perf_counter() - start
    timer.cancel()
    assert stopped < 0.3 * full, (stopped, full)


@pytest.mark.parametrize("seed", [-1, 2**64, 2**70, 1.5, True, "x"])
def test_a_seed_out_of_range_raises_psdcal_error(seed):
    with pytest.raises(psdcal.PsdcalError, match="seed: expected a whole number"):
        psdcal.simulate(seed=seed)


def test_the_largest_seed_is_accepted():
    data = psdcal.simulate(seed=2**64 - 1, images=3)
    assert data["template"].shape[1] == 2


@pytest.mark.parametrize("value", [10**400, "abc", [1.0]])
def test_a_number_argument_out_of_range_raises_psdcal_error(cal, value):
    with pytest.raises(psdcal.PsdcalError, match="point_sigma_mm"):
        cal.aoa(points(2), point_sigma_mm=value)
