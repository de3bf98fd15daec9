"""The same demodulation work in NumPy/SciPy, to compare with the Criterion
bench `signal/demodulate record, 4 channels` (benches/throughput.rs).

The same data (200 000 frames of 4 channels at 20 kHz, the bench's formula),
the same work per record: a 2nd-order Butterworth band-pass 700-1300 Hz
(second-order sections, scipy.signal.sosfilt, from rest), the transient
skipped, then least-squares I/Q detection of the 1 kHz tone over the rest
(references cos/sin, their 2x2 Gram matrix, the projections), per channel.
psdcal's record demodulation does more (frequency estimate, noise, checks):
the comparison is favourable to NumPy.

Run:  python3 numpy_reference.py      (prints channel-samples per second)
"""

import time

import numpy as np
from scipy.signal import butter, sosfilt

FS = 20_000.0
N = 200_000
F0 = 1000.0
SKIP = 480  # the filter's transient, samples (24 ms)


def signal(n):
    i = np.arange(n)
    return 0.7 * np.sin(2 * np.pi * F0 * i / FS + 0.3) + 0.01 * ((i * 7919) % 101) / 101.0


def demodulate(frames, sos):
    y = sosfilt(sos, frames, axis=0)[SKIP:]
    t = np.arange(SKIP, len(frames)) / FS
    c = np.cos(2 * np.pi * F0 * t)
    s = np.sin(2 * np.pi * F0 * t)
    ref = np.stack([c, s], axis=1)
    gram = ref.T @ ref
    proj = ref.T @ y
    iq = np.linalg.solve(gram, proj)
    return np.hypot(iq[0], iq[1])


def main():
    x = signal(N)
    frames = np.stack([x, 0.5 * x, 0.3 * x, 0.8 * x], axis=1)
    sos = butter(2, [F0 - 300.0, F0 + 300.0], btype="bandpass", fs=FS, output="sos")
    demodulate(frames, sos)
    best = float("inf")
    for _ in range(30):
        t0 = time.perf_counter()
        demodulate(frames, sos)
        best = min(best, time.perf_counter() - t0)
    print("numpy/scipy demodulate 4 channels: %.1f M channel-samples/s (%.2f ms per record)"
          % (4 * N / best / 1e6, best * 1e3))
    best = float("inf")
    one = frames[:, :1].copy()
    for _ in range(30):
        t0 = time.perf_counter()
        demodulate(one, sos)
        best = min(best, time.perf_counter() - t0)
    print("numpy/scipy demodulate 1 channel: %.1f M samples/s" % (N / best / 1e6))


if __name__ == "__main__":
    main()
