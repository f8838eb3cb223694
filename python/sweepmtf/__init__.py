"""sweepmtf: measure a camera's MTF from a photograph of a sine-sweep chart.

Thin bindings over the Rust library (the same numbers as the ``sweepmtf``
command line). Units follow the CLI: image frequencies in cycles/pixel
(``*_cy_px``), model and sensor frequencies in cycles/mm (``*_cy_mm``),
lengths in the unit their name carries (``pixel_pitch_um``, ``width_mm``).

The GIL is released while the library works, so Python threads measuring
different shots run in parallel.

>>> import sweepmtf
>>> m = sweepmtf.measure("testdata/a4_log_shot.jpg", target="targets/a4_log.toml")
>>> m.curves[0].mtf50          # cycles/pixel
"""

from __future__ import annotations

import json
import os
from dataclasses import dataclass, field
from typing import Any, Dict, List, Optional, Sequence, Tuple, Union

import numpy as np

from . import _native
from ._native import MeasurementError

__all__ = [
    "MeasurementError",
    "Measurement",
    "Curve",
    "Model",
    "Shot",
    "measure",
    "locate",
    "model",
    "chart",
    "simulate",
    "read_photo",
]

PathLike = Union[str, "os.PathLike[str]"]
Photo = Union[PathLike, np.ndarray]

_CURVE_COLUMNS = (
    "s",
    "freq_cy_px",
    "freq_chart",
    "modulation",
    "mtf",
    "mtf_err",
    "aliased",
    "jpeg_limited",
)


@dataclass(frozen=True)
class Curve:
    """One measured MTF curve (one channel, one sweep), points in increasing frequency.

    Arrays (one value per point): ``s`` (position along the strip, strip units),
    ``freq_cy_px`` (image frequency, cycles/pixel), ``freq_cy_mm`` (cycles/mm on
    the sensor, None without a pixel pitch), ``freq_chart`` (cycles per strip unit:
    cycles/mm on the chart with a target), ``modulation`` (image modulation, linear
    light), ``mtf`` (modulation / chart modulation), ``mtf_err`` (one-sigma
    uncertainty of the MTF), ``aliased`` (bool: the value is not an MTF there),
    ``jpeg_limited`` (bool: a JPEG's quantiser, not noise, is the larger part of
    ``mtf_err`` there, or rounded the sine away: the value is more the file's
    than the lens's).

    Figures (cycles/pixel, None when not reached): ``mtf50``, ``mtf30``, ``mtf20``,
    ``mtf10`` (where the MTF falls to nn % of its low-frequency value 1);
    ``mtf50_err`` (MTF50's one-sigma uncertainty, cycles/pixel);
    ``mtf50p``, ``mtf20p``, ``mtf10p`` (nn % of the peak, searched from the peak
    upward; equal to ``mtf50`` etc. without a sharpening peak); ``peak_mtf`` and
    ``peak_cy_px`` (1 at 0 cy/px without sharpening), ``sharpening_peak`` (bool);
    ``mtf_nyquist`` (MTF at 0.5 cy/px).
    """

    channel: str
    sweep_id: str
    strip_unit: str
    s: np.ndarray
    freq_cy_px: np.ndarray
    freq_cy_mm: Optional[np.ndarray]
    freq_chart: np.ndarray
    modulation: np.ndarray
    mtf: np.ndarray
    mtf_err: np.ndarray
    aliased: np.ndarray
    jpeg_limited: np.ndarray
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
    region_px: List[Tuple[float, float]] = field(repr=False)


class Measurement:
    """The result of measuring one photo.

    ``curves`` (list of :class:`Curve`), ``warnings`` (something may be wrong
    with the result) and ``notes`` (what was done or assumed), lists of one-line strings,
    ``summary`` (the JSON summary, as ``STEM.summary.json``, as a dict),
    ``pixel_pitch_mm`` (None when unknown), ``roi`` (region corners, image px).
    """

    def __init__(self, native: Any) -> None:
        self._native = native
        pitch = native.pixel_pitch_mm
        self.source: str = native.source
        self.warnings: List[str] = list(native.warnings)
        self.notes: List[str] = list(native.notes)
        self.pixel_pitch_mm: Optional[float] = pitch
        self.roi: List[Tuple[float, float]] = [tuple(p) for p in native.roi]
        curves = []
        for d in native.curves():
            for k in _CURVE_COLUMNS:
                d[k].setflags(write=False)
            curves.append(
                Curve(
                    channel=d["channel"],
                    sweep_id=d["sweep_id"],
                    strip_unit=d["strip_unit"],
                    s=d["s"],
                    freq_cy_px=d["freq_cy_px"],
                    freq_cy_mm=None if pitch is None else d["freq_cy_px"] / pitch,
                    freq_chart=d["freq_chart"],
                    modulation=d["modulation"],
                    mtf=d["mtf"],
                    mtf_err=d["mtf_err"],
                    aliased=d["aliased"],
                    jpeg_limited=d["jpeg_limited"],
                    mtf50=d["mtf50_cy_px"],
                    mtf50_err=d["mtf50_err_cy_px"],
                    mtf30=d["mtf30_cy_px"],
                    mtf20=d["mtf20_cy_px"],
                    mtf10=d["mtf10_cy_px"],
                    mtf50p=d["mtf50p_cy_px"],
                    mtf20p=d["mtf20p_cy_px"],
                    mtf10p=d["mtf10p_cy_px"],
                    peak_mtf=d["peak_mtf"],
                    peak_cy_px=d["peak_cy_px"],
                    sharpening_peak=d["sharpening_peak"],
                    mtf_nyquist=d["mtf_nyquist"],
                    chart_modulation=d["chart_modulation"],
                    chart_modulation_source=d["chart_modulation_source"],
                    aliasing_from_cy_px=d["aliasing_from_cy_px"],
                    rounded_away_from_cy_px=d["rounded_away_from_cy_px"],
                    clipped_fraction=d["clipped_fraction"],
                    region_px=[tuple(p) for p in d["region_px"]],
                )
            )
        self.curves: List[Curve] = curves
        self._summary: Optional[Dict[str, Any]] = None

    @property
    def summary(self) -> Dict[str, Any]:
        """The JSON summary as a dict (the CLI's STEM.summary.json without timings)."""
        if self._summary is None:
            self._summary = json.loads(self._native.summary_json())
        return self._summary

    def csv_bytes(self) -> bytes:
        """The CSV the CLI writes as STEM.mtf.csv."""
        return bytes(self._native.csv())

    def chart_mtf(self, print_mtf: str, chart_length_mm: Optional[float] = None) -> List[Dict[str, Any]]:
        """The print's own MTF divided out, as ``measure --chart-mtf``: one dict per curve.

        print_mtf: a print MTF file (the ``.mtf.csv`` ``sweepmtf measure`` writes for
          a scan or close capture of the print, or ``chart --dot-model``'s file)
          or a model, ``gaussian:sigma=0.02mm`` or ``dots:dpi=600``.
        chart_length_mm: without a target, the printed length (mm) of the strip
          between the region's short edges (the image scale).
        Each dict: ``chart_mtf`` (the print's MTF at each point's chart
        frequency), ``camera_mtf`` and ``camera_mtf_err`` (NaN where flagged),
        ``chart_flag`` ('ok', 'chart_below_floor' (print MTF < 0.3),
        'outside_chart_file', 'aliased'), ``camera_mtf50_cy_px``,
        ``camera_mtf50p_cy_px``, ``camera_mtf10_cy_px`` (None where not reached).
        Raises ValueError (bad model, no scale) or OSError (unreadable file).
        """
        return list(self._native.chart_mtf(os.fspath(print_mtf),
                                           None if chart_length_mm is None else float(chart_length_mm)))

    def to_csv(self, path: PathLike) -> None:
        """Writes the CSV the CLI writes as STEM.mtf.csv (atomically)."""
        _write(path, self.csv_bytes())

    def plot(self, path: PathLike) -> None:
        """Writes the MTF plot as PNG or SVG (by the extension), as the CLI's STEM.mtf.png."""
        ext = os.fspath(path).rsplit(".", 1)[-1].lower()
        if ext not in ("png", "svg"):
            raise ValueError(f"{os.fspath(path)}: a plot ends in .png or .svg")
        _write(path, bytes(self._native.plot(ext)))

    def roi_plot(self, path: PathLike) -> None:
        """Writes the picture of the measured region (PNG), as the CLI's STEM.roi.png."""
        _write(path, bytes(self._native.roi_plot()))

    def to_pandas(self) -> Any:
        """All curves as one pandas.DataFrame, a row per point (needs pandas)."""
        try:
            import pandas as pd
        except ImportError as e:  # pragma: no cover - depends on the environment
            raise ImportError("to_pandas() needs pandas: pip install pandas") from e
        frames = []
        for c in self.curves:
            cols: Dict[str, Any] = {"channel": c.channel, "sweep_id": c.sweep_id}
            for k in _CURVE_COLUMNS:
                cols[k] = getattr(c, k)
            if c.freq_cy_mm is not None:
                cols["freq_cy_mm"] = c.freq_cy_mm
            frames.append(pd.DataFrame(cols))
        if not frames:
            return pd.DataFrame(columns=["channel", "sweep_id", *_CURVE_COLUMNS])
        return pd.concat(frames, ignore_index=True)

    def __repr__(self) -> str:
        figs = ", ".join(
            f"{c.channel}/{c.sweep_id} MTF50 "
            + ("not reached" if c.mtf50 is None else f"{c.mtf50:.3f} cy/px")
            for c in self.curves
        )
        return f"<Measurement {self.source}: {figs}>"


def _write(path: PathLike, data: bytes) -> None:
    """Writes data to path atomically: a temporary file beside it, then a rename."""
    path = os.fspath(path)
    tmp = os.path.join(os.path.dirname(path) or ".", f".{os.path.basename(path)}.tmp{os.getpid()}")
    try:
        with open(tmp, "wb") as f:
            f.write(data)
        os.replace(tmp, path)
    except BaseException:
        try:
            os.remove(tmp)
        except OSError:
            pass
        raise


def _roi(roi: Any) -> Optional[List[List[float]]]:
    if roi is None:
        return None
    flat = [float(v) for v in np.asarray(roi, dtype=np.float64).ravel()]
    if len(flat) != 8 or not all(np.isfinite(flat)):
        raise ValueError(
            "roi: expected four corners (x, y) or eight numbers x1,y1,…,x4,y4 (image pixels)"
        )
    return [flat[0:2], flat[2:4], flat[4:6], flat[6:8]]


def _array(photo: np.ndarray) -> np.ndarray:
    """The array as the library takes it: C-contiguous uint8, uint16 or float32."""
    if photo.dtype == np.uint8 or photo.dtype == np.uint16 or photo.dtype == np.float32:
        return np.ascontiguousarray(photo)
    if photo.dtype.kind == "f":
        return np.ascontiguousarray(photo, dtype=np.float32)
    raise ValueError(
        f"photo array of dtype {photo.dtype}: use uint8, uint16 or float (0 = black, 1 = white)"
    )


def _options(
    roi: Any,
    target: Optional[PathLike],
    tone: Union[None, str, float],
    is_array: Optional[np.dtype],
    method: str,
    sweep: str,
    channel: str,
    pixel_pitch_um: Optional[float],
    refine_roi: bool,
    green_balance: bool,
    keep_ends: bool,
    chart_index: Optional[int],
    bin_px: float,
    margin: float,
    window_cycles: float,
    max_across: int = 512,
) -> str:
    gamma: Optional[float] = None
    tone_chart = False
    tone_from_strip = True
    if tone is None:
        pass
    elif isinstance(tone, str) and tone == "chart":
        tone_chart = True
    elif isinstance(tone, str) and tone == "file":
        tone_from_strip = False
    elif isinstance(tone, str) and tone == "linear":
        gamma = 1.0
    elif isinstance(tone, str) and tone == "srgb":
        if is_array is None or is_array != np.uint8:
            raise ValueError(
                "tone='srgb' is the default of 8-bit data only; for other data give a gamma"
            )
    elif isinstance(tone, (int, float)) and not isinstance(tone, bool):
        gamma = float(tone)
        if not (np.isfinite(gamma) and gamma > 0):
            raise ValueError(f"tone (gamma) {tone} must be a positive number")
    else:
        raise ValueError(
            f"tone {tone!r}: use None, 'srgb', 'file', 'linear', 'chart' or a gamma (number)"
        )
    if method not in ("extrema", "fit", "envelope"):
        raise ValueError(f"method '{method}': use extrema, fit or envelope")
    if sweep not in ("auto", "linear", "log"):
        raise ValueError(f"sweep '{sweep}': use auto, linear or log")
    if channel not in ("luma", "r", "g", "b", "all"):
        raise ValueError(f"channel '{channel}': use luma, r, g, b or all")
    pitch_mm = None
    if pixel_pitch_um is not None:
        pitch_mm = float(pixel_pitch_um) / 1000.0
        if not (np.isfinite(pitch_mm) and pitch_mm > 0):
            raise ValueError(f"pixel_pitch_um {pixel_pitch_um} must be a positive number")
    if isinstance(max_across, bool) or int(max_across) != max_across or max_across < 0:
        raise ValueError(f"max_across {max_across} must be a whole number ≥ 0")
    if chart_index is not None and (int(chart_index) != chart_index or chart_index < 0):
        raise ValueError(f"chart_index {chart_index} must be a whole number ≥ 0")
    opts = {
        "roi": _roi(roi),
        "target": None if target is None else os.fspath(target),
        "method": method,
        "sweep": sweep,
        "gamma": gamma,
        "tone_chart": tone_chart,
        "tone_from_strip": tone_from_strip,
        "channel": channel,
        "pixel_pitch_mm": pitch_mm,
        "bin_px": float(bin_px),
        "margin": float(margin),
        "window_cycles": float(window_cycles),
        "chart_index": None if chart_index is None else int(chart_index),
        "refine_roi": bool(refine_roi),
        "green_balance": bool(green_balance),
        "find_print_ends": not bool(keep_ends),
        "max_across": int(max_across),
    }
    return json.dumps(opts)


def measure(
    photo: Photo,
    roi: Any = None,
    target: Optional[PathLike] = None,
    *,
    tone: Union[None, str, float] = None,
    method: str = "fit",
    sweep: str = "auto",
    channel: str = "luma",
    pixel_pitch_um: Optional[float] = None,
    refine_roi: bool = True,
    green_balance: bool = True,
    keep_ends: bool = False,
    chart_index: Optional[int] = None,
    bin_px: float = 0.25,
    margin: float = 0.15,
    window_cycles: float = 4.0,
    max_across: int = 512,
    name: str = "<array>",
    threads: Optional[int] = None,
) -> Measurement:
    """Measures the MTF in a photo of a sine chart, as ``sweepmtf measure``.

    photo: a file path (JPEG, PNG, TIFF, camera raw) or a numpy array of code
      values, H×W (grey) or H×W×3 (RGB): uint8, uint16, or float (0 = black,
      1 = white). Arrays are copied once and only the measured region is
      converted to linear light.
    roi: region corners in image pixels (four (x, y) pairs or eight numbers);
      without a target one sweep strip, with a target the target frame.
    target: target description file (chart TOML or sineMTF tgt.txt); with it and
      no roi the chart is found from its fiducials.
    tone: how code values map to linear light: None = the default (sRGB for
      8-bit, linear for 16-bit and float; a camera's own tone curve on top of
      it is found from each strip's low-frequency periods and taken out),
      'srgb' (the same, for uint8 arrays), 'file' (the file's or the default
      tone only), 'linear', a gamma (number), or 'chart' (from the target's
      grey patches).
    pixel_pitch_um: pixel pitch in micrometres, for cycles/mm (files: default from EXIF).
    refine_roi: refine the roi corners to the region's edges (the CLI's default).
    keep_ends: keep every bin of a strip, as ``--keep-ends``; by default the bins
      beyond where the printed sweep stops inside the region (corners clicked
      beyond the print) are left out (``print_ends_inside_px`` in the summary).
    bin_px, margin, window_cycles: bin width (px), strip margin (fraction), estimator window (cycles).
    max_across: most sample lines binned across a strip, as ``--max-across``: a
      strip taller across is binned from evenly spaced rows (or columns); 0 = all.
    name: stands for an array in messages.
    threads: worker threads for this call (None = all cores); threads=1 with one
      Python thread per core measures several shots at once.

    Raises ValueError (bad arguments), OSError (unreadable files) or
    MeasurementError (no chart or region found, too small, clipped, no oscillation).
    """
    if isinstance(photo, np.ndarray):
        arr = _array(photo)
        opts = _options(roi, target, tone, arr.dtype, method, sweep, channel, pixel_pitch_um,
                        refine_roi, green_balance, keep_ends, chart_index, bin_px, margin,
                        window_cycles, max_across)
        return Measurement(_native.measure_array(arr, opts, name, threads))
    if not isinstance(photo, (str, os.PathLike)):
        raise ValueError(f"photo must be a path or a numpy array, not {type(photo).__name__}")
    opts = _options(roi, target, tone, None, method, sweep, channel, pixel_pitch_um,
                    refine_roi, green_balance, keep_ends, chart_index, bin_px, margin,
                    window_cycles, max_across)
    return Measurement(_native.measure_path(os.fspath(photo), opts, threads))


def read_photo(path: PathLike) -> np.ndarray:
    """Decodes a JPEG, PNG or TIFF file to its code values (uint8 or uint16, H×W or H×W×3)."""
    arr, _bits = _native.read_photo(os.fspath(path))
    return arr


def locate(photo: Photo, target: PathLike, *, name: str = "<array>") -> List[Dict[str, Any]]:
    """Finds every copy of a target in a photo (path or array), left to right.

    Returns a list of dicts: ``corners_px`` (target frame corners (0,0), (w,0),
    (w,h), (0,h) in image px), ``homography`` (3×3, chart mm → image px),
    ``fiducials`` ([(id, (x, y))]), ``hidden`` (a fiducial solved, not seen),
    ``score`` (correlation with the target's pattern, −1…1), ``warnings``.
    Raises MeasurementError when no chart is found.
    """
    if isinstance(photo, np.ndarray):
        return _native.locate_array(_array(photo), os.fspath(target), name)
    return _native.locate_path(os.fspath(photo), os.fspath(target))


_KINDS = ("aperture", "sampling", "optics", "diffusion", "cte", "olpf", "gaussian", "defocus")


class Model:
    """A theoretical system: the product of the named factors' OTFs.

    Frequencies in cycles/mm on the sensor (u right, v up).
    """

    def __init__(self, native: Any) -> None:
        self._native = native

    @property
    def name(self) -> Optional[str]:
        """The system file's name, if any."""
        return self._native.name

    @property
    def factors(self) -> List[str]:
        """The factors' names, in order."""
        return list(self._native.factors)

    @property
    def nyquist_cy_mm(self) -> Optional[Tuple[float, float]]:
        """Nyquist frequencies (u, v) of the sampling grid, cycles/mm, if a factor defines one."""
        return self._native.nyquist

    def otf(self, u: Any, v: Any) -> np.ndarray:
        """Complex OTF at (u, v) cycles/mm; numpy broadcasting, the GIL released."""
        uu, vv = np.broadcast_arrays(np.asarray(u, dtype=np.float64), np.asarray(v, dtype=np.float64))
        shape = uu.shape
        out = self._native.otf(np.ascontiguousarray(uu).ravel(), np.ascontiguousarray(vv).ravel())
        return out.reshape(shape)

    def mtf(self, u: Any, v: Any) -> np.ndarray:
        """MTF |OTF| at (u, v) cycles/mm."""
        return np.abs(self.otf(u, v))

    def cut(self, direction: str = "u", f_max_cy_mm: float = 100.0, points: int = 1001) -> Dict[str, Any]:
        """A 1-D cut from 0 to f_max_cy_mm along 'u', 'v' or 'deg=θ' (as ``model --cut``).

        Returns arrays freq_cy_mm, u_cy_mm, v_cy_mm, otf (complex), mtf, the
        per-factor MTFs in ``factors`` and ``nyquist_cy_mm`` along the ray.
        """
        return self._native.cut(direction, float(f_max_cy_mm), int(points))

    def map(self, f_max_cy_mm: float, size: int = 256) -> Dict[str, Any]:
        """The MTF on a size×size grid over ±f_max_cy_mm (as ``model --map``).

        Returns ``mtf`` (size×size, row 0 at v = +f_max), ``u_cy_mm`` (column
        centres) and ``v_cy_mm`` (row centres, top to bottom).
        """
        flat, coords = self._native.map(float(f_max_cy_mm), int(size))
        return {"mtf": flat.reshape(size, size), "u_cy_mm": coords, "v_cy_mm": coords[::-1].copy()}

    def __repr__(self) -> str:
        return f"<Model {' × '.join(self.factors)}>"


def model(system: Optional[PathLike] = None, **factors: Union[str, Sequence[str]]) -> Model:
    """Builds a model system from a TOML system file and/or factor specs (the CLI's flags).

    >>> m = sweepmtf.model(optics="diffraction:lambda=550nm,fnum=4", aperture="rect:A=4.3um,B=4.3um")

    Keywords: aperture, sampling, optics, diffusion, cte, olpf, gaussian, defocus;
    each a spec string or a list of them (lengths with units, e.g. 4.3um).
    """
    specs: List[Tuple[str, str]] = []
    for kind in _KINDS:
        v = factors.pop(kind, None)
        if v is None:
            continue
        for s in [v] if isinstance(v, str) else list(v):
            specs.append((kind, str(s)))
    if factors:
        raise ValueError(f"unknown factor kind(s) {sorted(factors)}; allowed: {', '.join(_KINDS)}")
    return Model(_native.NativeModel(specs, None if system is None else os.fspath(system)))


class Shot:
    """A simulated shot: ``linear`` (recorded linear image, H×W float32, 1 = clipping),
    ``signal`` (noiseless, unclipped), ``truth`` (per sweep: id, roi, chart_contrast and
    arrays freq_cy_px, mtf, s_mm, freq_cy_mm, chart_freq_cy_mm, x_px, y_px), ``roi``
    (first sweep's strip corners, px) and ``settings`` (the STEM.json document)."""

    def __init__(self, native: Any) -> None:
        self._native = native
        w, h = native.size
        self.linear: np.ndarray = native.linear().reshape(h, w)
        self.signal: np.ndarray = native.signal().reshape(h, w)
        self.truth: List[Dict[str, Any]] = native.truth()
        self.roi: Optional[List[float]] = self.truth[0]["roi"] if self.truth else None
        self.settings: Dict[str, Any] = json.loads(native.settings_json(""))

    def write(self, path: PathLike) -> List[str]:
        """Writes the photo (.png, .tif, .jpg, .dng by extension) with STEM.truth.csv and STEM.json."""
        return [os.fspath(p) for p in self._native.write(os.fspath(path))]


def simulate(target: PathLike, camera: Optional[Dict[str, Any]] = None, model: Optional[Model] = None) -> Shot:
    """Photographs a target through a model with a simulated camera, as ``sweepmtf simulate``.

    camera: the settings, by the names of STEM.json's ``camera`` (width_px,
      height_px, pixel_pitch_um, chart_px, rotate_deg, tilt_deg, exposure,
      full_well_e, read_noise_e, seed, encoding, bits, …); the rest default.
    model: a :func:`model` system (optics, blur…); None = the pixel aperture only.
    """
    cam = json.dumps(camera or {})
    return Shot(_native.simulate(os.fspath(target), cam, None if model is None else model._native))


def chart(
    path: PathLike,
    f_min_cy_mm: float,
    f_max_cy_mm: float,
    *,
    law: str = "log",
    width_mm: float = 297.0,
    height_mm: float = 210.0,
    dpi: int = 600,
    contrasts: Union[float, Sequence[float]] = 0.8,
    mean: float = 0.5,
    patches: int = 12,
    gamma: Optional[float] = None,
    name: Optional[str] = None,
) -> Dict[str, Any]:
    """Writes a printable chart (.png, .tif, .pdf) with NAME.toml and NAME.preview.png, as ``sweepmtf chart``.

    Frequencies in cycles/mm on the print, sizes in mm, dpi in dots per inch.
    Returns target_toml (the description: the truth of what is printed),
    width_px, height_px, dots_per_cycle, warnings, preview (uint8 array) and the paths.
    """
    cs = [float(contrasts)] if isinstance(contrasts, (int, float)) else [float(c) for c in contrasts]
    return _native.chart(os.fspath(path), law, float(f_min_cy_mm), float(f_max_cy_mm), float(width_mm),
                         float(height_mm), int(dpi), cs, float(mean), int(patches), gamma, name)
