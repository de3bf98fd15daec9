"""Type stubs of the psdcal package (the native module psdcal._psdcal)."""

import os
from typing import Any, Dict, List, Literal, Mapping, Optional, Sequence, Tuple, Union, overload

import numpy as np
import numpy.typing as npt

__version__: str

PathLike = Union[str, "os.PathLike[str]"]
ArrayLike = npt.ArrayLike
Table = Union[PathLike, ArrayLike]
FloatArray = npt.NDArray[np.float64]

class PsdcalError(ValueError):
    """A psdcal failure; the message is the command line's (what happened; what to do)."""

class Calibration:
    """A sensor's calibration and its calibrated sensor."""

    @staticmethod
    def load(path: PathLike, /) -> "Calibration":
        """Reads calibration.json (version 1 or 2)."""
    def save(self, path: PathLike, /) -> None:
        """Writes calibration.json atomically (what `psdcal calibrate --out` writes)."""
    def to_json(self) -> str:
        """calibration.json's text."""
    @property
    def parameters(self) -> Dict[str, float]:
        """Every model parameter by name (mm, mm^-n, rad)."""
    @property
    def std(self) -> Dict[str, float]:
        """Standard deviation of each estimated parameter, by name."""
    @property
    def covariance(self) -> Tuple[List[str], FloatArray]:
        """(names, covariance matrix) of the estimated parameters."""
    @property
    def diagnostics(self) -> List[Dict[str, str]]:
        """What the fit noticed: dicts with code, severity, message."""
    @overload
    def aoa(
        self,
        points: ArrayLike,
        return_sigma: Literal[False] = ...,
        point_sigma_mm: Optional[float] = ...,
    ) -> FloatArray: ...
    @overload
    def aoa(
        self,
        points: ArrayLike,
        return_sigma: Literal[True],
        point_sigma_mm: Optional[float] = ...,
    ) -> Tuple[FloatArray, FloatArray]: ...
    def correct(self, points: ArrayLike, /) -> FloatArray:
        """Ideal points (N, 2), mm."""
    @overload
    def locate(
        self,
        points: ArrayLike,
        distance: Optional[float] = ...,
        plane: Optional[Sequence[float]] = ...,
        return_covariance: Literal[False] = ...,
        point_sigma_mm: Optional[float] = ...,
    ) -> FloatArray: ...
    @overload
    def locate(
        self,
        points: ArrayLike,
        distance: Optional[float] = ...,
        plane: Optional[Sequence[float]] = ...,
        *,
        return_covariance: Literal[True],
        point_sigma_mm: Optional[float] = ...,
    ) -> Tuple[FloatArray, FloatArray]: ...

def calibrate(
    template: Table,
    observations: Optional[Table] = None,
    signals: Optional[Table] = None,
    fit: Union[str, Sequence[str], None] = None,
    *,
    focal_guess: Optional[float] = ...,
    cost: Literal["template", "image"] = ...,
    noise: Literal["uniform", "channel-snr", "channel-floor"] = ...,
    preliminary: Literal["auto", "straightness", "homography", "off"] = ...,
    normalize: bool = ...,
    robust: Optional[str] = ...,
    uncertainty: str = ...,
    psd_map: Optional[PathLike] = ...,
    set: Union[Mapping[str, float], Sequence[str], str, None] = ...,
    gains: Optional[PathLike] = ...,
    lx: float = ...,
    ly: float = ...,
    strict: bool = ...,
) -> Calibration:
    """Calibrates a sensor from images of an LED template (`psdcal calibrate`)."""

def simulate(
    lens: int = 2,
    snr_db: float = 40.0,
    images: int = 9,
    seed: int = 1,
    imbalance: bool = False,
    psd_distortion: bool = False,
    psd_nonlinearity: bool = False,
    template: Literal["scatter14", "grid"] = "scatter14",
    record_cycles: int = 65,
    noise: bool = True,
) -> Dict[str, Any]:
    """A simulated data set: template, observations, signals, truth, poses."""

def demodulate(
    raw: PathLike,
    rate: Optional[float] = None,
    schedule: Optional[PathLike] = None,
    tones: Optional[PathLike] = None,
    frequency: float = 1000.0,
    full_scale: float = 10.0,
    out: Optional[PathLike] = None,
) -> Dict[str, Any]:
    """Demodulates a raw recording with its schedule (`psdcal demodulate`)."""
