"""The whole `psdcal demodulate` process in NumPy/SciPy, to time against the
CLI on the same recording (time-multiplexed schedule, one tone).

The same work per record as psdcal (docs/model.md §8 "Demodulation"):
the schedule's interval mapped to the nearest samples, a saturation check,
the 2nd-order Butterworth band-pass of 600 Hz around the tone from rest
(second-order sections, scipy.signal.sosfilt, the four channels at once),
the transient skipped (the slowest pole's decay to 1e-11), the last whole
number of cycles kept, least-squares I/Q against cos/sin (the 2x2 Gram
matrix, the projections), the amplitude divided by the filter's gain at
the tone, the residual noise and SNR per channel, the dark check, and
signals.csv written. psdcal also re-estimates each record's modulation
frequency (clock mismatch); this script does not: the comparison is
favourable to NumPy.

Run:
    python3 numpy_demodulate.py RAW.npy|RAW.csv RATE_HZ SCHEDULE.csv OUT.csv [REPEATS]

prints the best and median wall and CPU (process) time of the whole work
(reading the recording and the schedule, every record, writing
signals.csv), measured inside the interpreter (the interpreter's start and
NumPy's and SciPy's import not counted). Pin it to one core
(`taskset -c 0`) to compare with psdcal's single-threaded demodulate.
A raw.csv is read with numpy.loadtxt (columns vx1, vx2, vy1, vy2).
"""

import sys
import time

import numpy as np
from scipy.signal import butter, sosfilt, sosfreqz

TOL = 1e-11
BANDWIDTH = 600.0
FULL_SCALE = 10.0


def read_schedule(path):
    rows = []
    header = None
    with open(path) as f:
        for line in f:
            if line.startswith("#") or not line.strip():
                continue
            fields = line.strip().split(",")
            if header is None:
                header = fields
                continue
            row = dict(zip(header, fields))
            rows.append((row["image"], row.get("led", ""), float(row["t_start_s"]),
                         float(row["t_stop_s"])))
    return rows


def read_raw(path):
    if path.endswith(".npy"):
        return np.load(path)
    with open(path) as f:
        while True:
            line = f.readline()
            if not line.startswith("#"):
                break
        names = line.strip().split(",")
        cols = [names.index(c) for c in ("vx1", "vx2", "vy1", "vy2")]
        return np.loadtxt(f, delimiter=",", usecols=cols, ndmin=2)


class Filter:
    """The band-pass of one tone: sections, settling, gain, noise gain."""

    def __init__(self, f0, fs):
        self.sos = butter(2, [f0 - BANDWIDTH / 2, f0 + BANDWIDTH / 2], btype="bandpass",
                          fs=fs, output="sos")
        poles = np.concatenate([np.roots(s[3:]) for s in self.sos])
        decay = -fs * np.log(np.abs(poles).max())
        self.settle = int(np.ceil(np.log(1 / TOL) / decay * fs))
        self.gain = abs(sosfreqz(self.sos, worN=[f0], fs=fs)[1][0])
        impulse = np.zeros(int(np.ceil(np.log(1e10) / decay * fs)))
        impulse[0] = 1.0
        self.nu = float(np.sum(sosfilt(self.sos, impulse) ** 2))


def demodulate(raw, fs, schedule, f0, out):
    filt = Filter(f0, fs)
    rail = FULL_SCALE * (1 - 2.0 ** -15)
    lines = ["# demodulated by numpy_demodulate.py; amplitudes in peak volts",
             "image,led,vx1,vx2,vy1,vy2,snr_db"]
    for image, led, t0, t1 in schedule:
        start, stop = int(round(t0 * fs)), int(round(t1 * fs))
        rec = raw[start:stop]
        if np.any(np.abs(rec) >= rail):
            continue
        length = len(rec)
        cycles = np.floor((length - filt.settle) * f0 / fs)
        m = int(round(cycles * fs / f0))
        y = sosfilt(filt.sos, rec, axis=0)[length - m:]
        arg = 2 * np.pi * f0 / fs * np.arange(length - m, length)
        ref = np.stack([np.cos(arg), np.sin(arg)], axis=1)
        gram = ref.T @ ref
        proj = ref.T @ y
        iq = np.linalg.solve(gram, proj)
        amp = np.hypot(iq[0], iq[1]) / filt.gain
        rss = np.einsum("ij,ij->j", y, y) - np.einsum("ij,ij->j", iq, proj)
        sigma = np.sqrt(np.maximum(rss, 0) / ((m - 2) * filt.nu))
        spread = np.sqrt(0.5 * np.trace(np.linalg.inv(gram)))
        if amp.sum() <= 3.0 * (sigma * spread).sum():
            continue
        with np.errstate(divide="ignore"):
            snr = np.clip(10 * np.log10(amp ** 2 / (2 * sigma ** 2)), -200, 200)
        lines.append("%s,%s,%r,%r,%r,%r,%r" % (image, led, *amp.tolist(), float(snr.min())))
    with open(out, "w") as f:
        f.write("\n".join(lines) + "\n")


def main():
    raw_path, rate, schedule_path, out = sys.argv[1:5]
    repeats = int(sys.argv[5]) if len(sys.argv) > 5 else 5
    fs = float(rate)
    wall, cpu = [], []
    for _ in range(repeats):
        t0, c0 = time.perf_counter(), time.process_time()
        raw = read_raw(raw_path)
        schedule = read_schedule(schedule_path)
        demodulate(raw, fs, schedule, 1000.0, out)
        wall.append(time.perf_counter() - t0)
        cpu.append(time.process_time() - c0)
    wall.sort()
    cpu.sort()
    print("numpy/scipy demodulate %s: %d frames, %d records; wall best %.3f s, median %.3f s; "
          "CPU best %.3f s, median %.3f s"
          % (raw_path, len(raw), len(schedule), wall[0], wall[len(wall) // 2], cpu[0],
             cpu[len(cpu) // 2]))


if __name__ == "__main__":
    main()
