"""psdcal: calibrate position-sensitive-device (PSD) angle-of-arrival sensors.

The library behind the ``psdcal`` command, from Python: the same data, the
same options, the same answers (to the last bit), numpy arrays in and out.

>>> import psdcal
>>> cal = psdcal.calibrate("data/example/template.csv",
...                        observations="data/example/observations.csv")
>>> cal.parameters["f"]                     # mm
>>> cal.aoa([[1.0, -0.5]])                  # (N, 2) degrees
>>> cal.save("calibration.json")            # what `psdcal calibrate --out` writes

Arrays (instead of files; row-major ``float64``, identifiers as whole numbers):

- template: ``(N, 2)`` rows ``X_mm, Y_mm`` (LEDs named 1 … N) or ``(N, 3)``
  rows ``led, X_mm, Y_mm``;
- observations: ``(M, 4)`` rows ``image, led, x_mm, y_mm``;
- signals: ``(M, 6)`` rows ``image, led, vx1, vx2, vy1, vy2`` (``(M, 7)`` with
  ``snr_db``);
- points: ``(N, 2)`` measured points ``x_mm, y_mm`` or ``(N, 4)`` amplitudes
  ``vx1, vx2, vy1, vy2``.

Every failure raises :class:`PsdcalError` (a ``ValueError``) with the command
line's message: what happened, then what to do. Messages name an array's row
as ``<name> array:<n>``, ``n`` counting rows from 1. Warnings (data dropped,
diagnostics of the fit) are issued as ``UserWarning``.

Lengths are millimetres, angles degrees (at this boundary), parameters by
their names (``f``, ``cx``, ``cy``, ``k1``, …; see docs/model.md).
"""

from ._psdcal import (
    Calibration,
    PsdcalError,
    __version__,
    calibrate,
    demodulate,
    simulate,
)

__all__ = [
    "Calibration",
    "PsdcalError",
    "__version__",
    "calibrate",
    "demodulate",
    "simulate",
]
