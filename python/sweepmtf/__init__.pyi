"""Type stubs of sweepmtf (units in the names: *_cy_px cycles/pixel, *_cy_mm cycles/mm, *_um, *_mm)."""

import os
from typing import Any, Dict, List, Optional, Sequence, Tuple, Union

import numpy as np
import numpy.typing as npt

PathLike = Union[str, os.PathLike[str]]
Photo = Union[PathLike, np.ndarray]

class MeasurementError(Exception):
    """The photo cannot be measured (no region or chart found, too small, clipped, no oscillation)."""

class Curve:
    channel: str
    sweep_id: str
    strip_unit: str
    s: npt.NDArray[np.float64]
    freq_cy_px: npt.NDArray[np.float64]
    freq_cy_mm: Optional[npt.NDArray[np.float64]]
    freq_chart: npt.NDArray[np.float64]
    modulation: npt.NDArray[np.float64]
    mtf: npt.NDArray[np.float64]
    mtf_err: npt.NDArray[np.float64]
    aliased: npt.NDArray[np.bool_]
    jpeg_limited: npt.NDArray[np.bool_]
    mtf50: Optional[float]
    mtf50_err: Optional[float]
    mtf30: Optional[float]
    mtf20: Optional[float]
    mtf10: Optional[float]
    mtf50p: Optional[float]
    mtf20p: Optional[float]
    mtf10p: Optional[float]
    peak_mtf: Optional[float]
    peak_cy_px: Optional[float]
    sharpening_peak: bool
    mtf_nyquist: Optional[float]
    chart_modulation: float
    chart_modulation_source: str
    aliasing_from_cy_px: Optional[float]
    rounded_away_from_cy_px: Optional[float]
    clipped_fraction: float
    region_px: List[Tuple[float, float]]

class Measurement:
    source: str
    warnings: List[str]
    notes: List[str]
    pixel_pitch_mm: Optional[float]
    roi: List[Tuple[float, float]]
    curves: List[Curve]
    @property
    def summary(self) -> Dict[str, Any]: ...
    def csv_bytes(self) -> bytes: ...
    def chart_mtf(self, print_mtf: Union[str, PathLike], chart_length_mm: Optional[float] = ...) -> List[Dict[str, Any]]: ...
    def to_csv(self, path: PathLike) -> None: ...
    def plot(self, path: PathLike) -> None: ...
    def roi_plot(self, path: PathLike) -> None: ...
    def to_pandas(self) -> Any: ...

def measure(
    photo: Photo,
    roi: Any = ...,
    target: Optional[PathLike] = ...,
    *,
    tone: Union[None, str, float] = ...,
    method: str = ...,
    sweep: str = ...,
    channel: str = ...,
    pixel_pitch_um: Optional[float] = ...,
    refine_roi: bool = ...,
    green_balance: bool = ...,
    keep_ends: bool = ...,
    chart_index: Optional[int] = ...,
    bin_px: float = ...,
    margin: float = ...,
    window_cycles: float = ...,
    max_across: int = ...,
    name: str = ...,
    threads: Optional[int] = ...,
) -> Measurement: ...
def read_photo(path: PathLike) -> np.ndarray: ...
def locate(photo: Photo, target: PathLike, *, name: str = ...) -> List[Dict[str, Any]]: ...

class Model:
    @property
    def name(self) -> Optional[str]: ...
    @property
    def factors(self) -> List[str]: ...
    @property
    def nyquist_cy_mm(self) -> Optional[Tuple[float, float]]: ...
    def otf(self, u: npt.ArrayLike, v: npt.ArrayLike) -> npt.NDArray[np.complex128]: ...
    def mtf(self, u: npt.ArrayLike, v: npt.ArrayLike) -> npt.NDArray[np.float64]: ...
    def cut(self, direction: str = ..., f_max_cy_mm: float = ..., points: int = ...) -> Dict[str, Any]: ...
    def map(self, f_max_cy_mm: float, size: int = ...) -> Dict[str, Any]: ...

def model(system: Optional[PathLike] = ..., **factors: Union[str, Sequence[str]]) -> Model: ...

class Shot:
    linear: npt.NDArray[np.float32]
    signal: npt.NDArray[np.float32]
    truth: List[Dict[str, Any]]
    roi: Optional[List[float]]
    settings: Dict[str, Any]
    def write(self, path: PathLike) -> List[str]: ...

def simulate(
    target: PathLike, camera: Optional[Dict[str, Any]] = ..., model: Optional[Model] = ...
) -> Shot: ...
def chart(
    path: PathLike,
    f_min_cy_mm: float,
    f_max_cy_mm: float,
    *,
    law: str = ...,
    width_mm: float = ...,
    height_mm: float = ...,
    dpi: int = ...,
    contrasts: Union[float, Sequence[float]] = ...,
    mean: float = ...,
    patches: int = ...,
    gamma: Optional[float] = ...,
    name: Optional[str] = ...,
) -> Dict[str, Any]: ...
