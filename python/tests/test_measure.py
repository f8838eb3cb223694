"""sweepmtf.measure: paths and arrays against the CLI, the array kinds, the outputs."""

import csv
import io
import json
import subprocess

import numpy as np
import pytest

import sweepmtf
from conftest import SHOT, TARGET


@pytest.fixture(scope="module")
def cli_run(cli, tmp_path_factory):
    """The CLI's outputs for the README sample (computed once)."""
    out = tmp_path_factory.mktemp("cli")
    subprocess.run(
        [cli, "measure", str(SHOT), "--target", str(TARGET), "-o", str(out)],
        check=True,
        capture_output=True,
    )
    summary = json.loads((out / "a4_log_shot.summary.json").read_text())
    return out, summary


def close(a, b, tol=1e-12):
    if a is None or b is None:
        return a is None and b is None
    return abs(a - b) <= tol * max(1.0, abs(b))


def assert_summary_matches(py_summary, cli_summary, tol=1e-12, crossing_tol=None, array=False):
    """The summaries agree to `tol`; the crossings (MTF50 …) to `crossing_tol`
    (default `tol`). `array`: the Python one measured a numpy array of the
    pixels, which holds no JPEG quantisation table, so it says nothing of
    the quantiser rounding the sine away."""
    crossing_tol = tol if crossing_tol is None else crossing_tol
    assert len(py_summary["curves"]) == len(cli_summary["curves"]) > 0
    for p, c in zip(py_summary["curves"], cli_summary["curves"]):
        assert (p["channel"], p["sweep"]) == (c["channel"], c["sweep"])
        for k in ("chart_modulation", "aliasing_from_cy_px", "clipped_fraction", "mtf_at_nyquist"):
            assert close(p[k], c[k], tol), (k, p[k], c[k])
        k = "rounded_away_from_cy_px"
        assert p[k] is None if array else close(p[k], c[k], tol), (k, p[k], c[k])
        k = "points_jpeg_limited"
        assert p[k] == 0 if array else p[k] == c[k], (k, p[k], c[k])
        for k in ("mtf50", "mtf30", "mtf20", "mtf10", "mtf50p", "mtf20p", "mtf10p"):
            pv, cv = p[k], c[k]
            assert (pv is None) == (cv is None), k
            if pv is not None:
                assert close(pv["cy_px"], cv["cy_px"], crossing_tol), (k, pv, cv)
        for k in ("phase_c0_cycles", "freq_start_cy_per_unit", "c2", "foreshortening_per_unit"):
            assert close(p["sweep_law"][k], c["sweep_law"][k], tol), k
        assert p["points"] == c["points"]
        assert p["print_ends_inside_px"] == c["print_ends_inside_px"]
    for k, v in enumerate(cli_summary["roi_px"]):
        assert np.allclose(py_summary["roi_px"][k], v, rtol=0, atol=1e-12)


def test_path_gives_the_cli_result(cli_run):
    out, cli_summary = cli_run
    m = sweepmtf.measure(SHOT, target=TARGET)
    assert_summary_matches(m.summary, cli_summary)
    # The same CSV, byte for byte.
    assert m.csv_bytes() == (out / "a4_log_shot.mtf.csv").read_bytes()
    # The curve's figures are the summary's.
    c0 = m.curves[0]
    assert close(c0.mtf50, cli_summary["curves"][0]["mtf50"]["cy_px"])
    assert close(c0.mtf50_err, cli_summary["curves"][0]["mtf50"]["err_cy_px"])
    assert 0 < c0.mtf50_err < 0.05 * c0.mtf50
    assert close(c0.mtf50p, cli_summary["curves"][0]["mtf50p"]["cy_px"])
    assert c0.sharpening_peak == cli_summary["curves"][0]["peak"]["sharpening"]
    assert m.warnings == cli_summary["warnings"]
    assert m.notes == cli_summary["notes"]


def test_array_gives_the_path_result(cli_run):
    """The decoded pixels give the file's values. An array holds no JPEG
    quantisation table, so its points do not carry the quantiser's dead
    zone (the file's claims are the same or wider, never narrower), and the
    crossings whose local fit weighs the points by their claims move near it
    (this JPEG's MTF20 at 0.39 cy/px: array 0.3934, file 0.3973, truth
    0.3953; MTF10 0.4747 / 0.4750 / 0.4781)."""
    _, cli_summary = cli_run
    arr = sweepmtf.read_photo(SHOT)
    assert arr.dtype == np.uint8 and arr.ndim in (2, 3)
    m = sweepmtf.measure(arr, target=TARGET, name=str(SHOT))
    assert_summary_matches(m.summary, cli_summary, crossing_tol=6e-3, array=True)
    p = sweepmtf.measure(SHOT, target=TARGET)
    for a, b in zip(m.curves, p.curves):
        np.testing.assert_allclose(a.freq_cy_px, b.freq_cy_px, rtol=1e-12, atol=0)
        np.testing.assert_allclose(a.mtf, b.mtf, rtol=1e-12, atol=1e-15)
        assert np.all(a.mtf_err <= b.mtf_err * (1 + 1e-12) + 1e-15)
        np.testing.assert_array_equal(a.aliased, b.aliased)
        assert not a.jpeg_limited.any()
        assert b.jpeg_limited.dtype == np.bool_ and len(b.jpeg_limited) == len(b.mtf)
    # A view that is not C-contiguous (every column, reversed twice) is accepted.
    view = arr[:, ::-1][:, ::-1]
    assert not view.flags["C_CONTIGUOUS"] or view.base is not None
    v = sweepmtf.measure(view, target=TARGET)
    np.testing.assert_allclose(v.curves[0].mtf, p.curves[0].mtf, rtol=1e-12, atol=1e-15)


def test_roi_given_and_pitch_units(cli, tmp_path):
    """An explicit roi without a target, and a pixel pitch in µm: the CLI's numbers."""
    found = sweepmtf.locate(SHOT, TARGET)
    corners = found[0]["corners_px"]
    roi_text = ",".join(f"{v!r}" for xy in corners for v in xy)
    subprocess.run(
        [cli, "measure", str(SHOT), "--target", str(TARGET), "--roi", roi_text,
         "--pixel-pitch", "4.3um", "--method", "envelope", "-o", str(tmp_path)],
        check=True, capture_output=True,
    )
    cli_summary = json.loads((tmp_path / "a4_log_shot.summary.json").read_text())
    m = sweepmtf.measure(SHOT, roi=corners, target=TARGET, pixel_pitch_um=4.3, method="envelope")
    assert_summary_matches(m.summary, cli_summary)
    assert abs(m.pixel_pitch_mm - 0.0043) < 1e-15
    np.testing.assert_allclose(m.curves[0].freq_cy_mm, m.curves[0].freq_cy_px / 0.0043)
    assert (tmp_path / "a4_log_shot.mtf.csv").read_bytes() == m.csv_bytes()


def grey_strip(dtype, gamma=1.0):
    """A synthetic linear sweep strip (known modulation 0.6 at low frequency) as code values."""
    h, w = 120, 900
    x = np.arange(w) + 0.5
    f = 0.02 + (0.35 - 0.02) * x / w  # cycles/pixel, linear sweep
    phase = np.cumsum(f)
    row = 0.5 + 0.3 * np.sin(2 * np.pi * phase)
    lin = np.tile(row, (h, 1))
    code = lin ** (1.0 / gamma)
    if dtype == np.uint16:
        return np.round(code * 65535).astype(np.uint16)
    if dtype == np.uint8:
        return np.round(code * 255).astype(np.uint8)
    return code.astype(dtype)


STRIP_ROI = [(0, 10), (900, 10), (900, 110), (0, 110)]


def test_keep_ends_keeps_the_paper_beyond_the_print():
    """Corners 40 px beyond the sweep's printed high end, on paper: by default the
    bins there are left out (found within 2 px); keep_ends=True keeps them, and
    the last points read the paper as lost modulation."""
    code = grey_strip(np.uint16).astype(np.float64) / 65535
    code[:, 860:] = 0.92  # paper, below clipping
    img = np.round(code * 65535).astype(np.uint16)
    found = sweepmtf.measure(img, roi=STRIP_ROI, refine_roi=False)
    low, high = found.summary["curves"][0]["print_ends_inside_px"]
    assert high is not None and abs(high - 40.0) < 2.0, high
    kept = sweepmtf.measure(img, roi=STRIP_ROI, refine_roi=False, keep_ends=True)
    assert kept.summary["curves"][0]["print_ends_inside_px"] == [None, None]
    assert kept.curves[0].mtf[-1] < found.curves[0].mtf[-1] - 0.1


def test_array_kinds_agree():
    """uint16, float32, float64 and RGB arrays of the same picture give the same curve."""
    u16 = grey_strip(np.uint16)
    base = sweepmtf.measure(u16, roi=STRIP_ROI, refine_roi=False)
    assert any("taken as linear" in n for n in base.notes)
    c = base.curves[0]
    # Low frequencies of a perfect (unblurred) sweep: MTF ≈ 1 against the
    # estimated chart modulation; the measured modulation is the drawn 0.6.
    low = c.freq_cy_px < 0.08
    assert np.all(np.abs(c.modulation[low] - 0.6) < 0.01), c.modulation[low]
    f32 = (u16 / 65535.0).astype(np.float32)
    for arr in (f32, f32.astype(np.float64), np.dstack([f32, f32, f32])):
        m = sweepmtf.measure(arr, roi=STRIP_ROI, refine_roi=False)
        np.testing.assert_allclose(m.curves[0].freq_cy_px, c.freq_cy_px, rtol=1e-9)
        np.testing.assert_allclose(m.curves[0].mtf, c.mtf, rtol=0, atol=1e-5)
    # tone: a gamma-encoded float picture, decoded by tone=2.2, is the linear one.
    g = grey_strip(np.float32, gamma=2.2)
    m = sweepmtf.measure(g, roi=STRIP_ROI, refine_roi=False, tone=2.2)
    np.testing.assert_allclose(m.curves[0].mtf, c.mtf, rtol=0, atol=2e-3)
    # Read as linear instead, the same picture is either refused by the quality
    # gate (the coded sine's harmonics count as noise) or measured visibly off;
    # never passed as the linear result.
    # (Its own points: the harmonics such a read leaves, aliased onto the
    # pixel grid, may leave some windows out.)
    try:
        wrong = sweepmtf.measure(g, roi=STRIP_ROI, refine_roi=False, tone="linear")
    except sweepmtf.MeasurementError:
        return
    w = wrong.curves[0]
    assert np.max(np.abs(w.modulation[w.freq_cy_px < 0.08] - 0.6)) > 0.02


def test_a_camera_tone_curve_is_taken_out_unless_tone_file():
    """A uint8 sweep coded sRGB + a picture style's S-curve: the default finds
    the curve from the strip's shape; tone='file' reads it through sRGB alone."""
    h, w = 120, 900
    x = np.arange(w) + 0.5
    f = 0.02 + (0.35 - 0.02) * x / w
    truth = np.exp(-((f / 0.25) ** 2))  # the amplitude's fall: the MTF to find
    lin = 0.35 * (1 + 0.8 * truth * np.sin(2 * np.pi * np.cumsum(f)))
    srgb = np.where(lin <= 0.0031308, 12.92 * lin, 1.055 * lin ** (1 / 2.4) - 0.055)
    k = 2.0
    code = 0.5 + 0.5 * np.tanh(k * (srgb - 0.5)) / np.tanh(k / 2)
    img = np.tile(np.round(code * 255).astype(np.uint8), (h, 1))

    def worst(m):
        c = m.curves[0]
        ok = (c.freq_cy_px > 0.05) & (c.freq_cy_px < 0.3) & ~c.aliased
        expect = np.exp(-((c.freq_cy_px[ok] / 0.25) ** 2))
        return np.max(np.abs(c.mtf[ok] - expect))

    fixed = sweepmtf.measure(img, roi=STRIP_ROI, refine_roi=False)
    found = fixed.summary["curves"][0]["tone_correction"]
    assert found["used"] and found["significance"] > 5, found
    # No paper beside this strip: the curve's black level stays unseen, and
    # the chart modulation's uncertainty carries it (printed 0.8).
    assert found["black_level"] is None or not found["black_level"]["used"], found
    assert found["unseen_black_relative"] > 0, found
    cm = fixed.summary["curves"][0]["chart_modulation"]
    cm_err = fixed.summary["curves"][0]["chart_modulation_err"]
    assert abs(cm - 0.8) <= 2 * cm_err, (cm, cm_err)
    assert any("not sine-shaped" in n for n in fixed.notes), fixed.notes
    kept = sweepmtf.measure(img, roi=STRIP_ROI, refine_roi=False, tone="file")
    assert kept.summary["curves"][0]["tone_correction"] is None
    assert worst(fixed) < 0.01 < worst(kept), (worst(fixed), worst(kept))


def test_outputs(tmp_path):
    m = sweepmtf.measure(SHOT, target=TARGET)
    m.to_csv(tmp_path / "a.csv")
    rows = list(csv.DictReader(io.StringIO((tmp_path / "a.csv").read_text())))
    assert len(rows) == len(m.curves[0].mtf) * len(m.curves)
    m.plot(tmp_path / "a.png")
    assert (tmp_path / "a.png").read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    m.plot(tmp_path / "a.svg")
    assert b"<svg" in (tmp_path / "a.svg").read_bytes()[:200]
    with pytest.raises(ValueError):
        m.plot(tmp_path / "a.gif")
    assert not (tmp_path / "a.gif").exists()
    assert m.summary["image_width_px"] > 0
    assert "MTF50" in repr(m)


def test_to_pandas():
    pd = pytest.importorskip("pandas")
    m = sweepmtf.measure(SHOT, target=TARGET)
    df = m.to_pandas()
    assert isinstance(df, pd.DataFrame)
    assert len(df) == sum(len(c.mtf) for c in m.curves)
    np.testing.assert_array_equal(df["mtf"].to_numpy()[: len(m.curves[0].mtf)], m.curves[0].mtf)


def test_chart_mtf_gives_the_cli_columns(cli, tmp_path):
    """Dividing out a print (Gaussian σ 0.02 mm): the CLI's `--chart-mtf` CSV columns and JSON figures."""
    spec = "gaussian:sigma=0.02mm"
    subprocess.run(
        [cli, "measure", str(SHOT), "--target", str(TARGET), "--chart-mtf", spec, "-o", str(tmp_path)],
        check=True,
        capture_output=True,
    )
    rows = list(csv.DictReader(io.StringIO((tmp_path / "a4_log_shot.mtf.csv").read_text())))
    summary = json.loads((tmp_path / "a4_log_shot.summary.json").read_text())
    m = sweepmtf.measure(SHOT, target=TARGET)
    got = m.chart_mtf(spec)
    assert len(got) == len(m.curves) == len(summary["curves"])
    k = 0
    for c, g, s in zip(m.curves, got, summary["curves"]):
        n = len(c.mtf)
        assert len(g["camera_mtf"]) == len(g["chart_flag"]) == n
        for i in range(n):
            r = rows[k + i]
            assert g["chart_flag"][i] == r["chart_flag"]
            assert abs(g["chart_mtf"][i] - float(r["chart_mtf"])) <= 6e-7  # the CSV keeps 6 decimals
            if r["camera_mtf"] == "":
                assert np.isnan(g["camera_mtf"][i])
            else:
                assert abs(g["camera_mtf"][i] - float(r["camera_mtf"])) <= 6e-7
        k += n
        for key in ("camera_mtf50_cy_px", "camera_mtf10_cy_px"):
            assert close(g[key], s[key]), key
        # The closed form itself: exp(−2π²σ²f²) at each point's chart frequency (cy/mm of print).
        f = c.freq_chart
        assert np.allclose(g["chart_mtf"], np.exp(-2 * np.pi**2 * 0.02**2 * f**2), rtol=0, atol=1e-12)
    with pytest.raises(ValueError):
        m.chart_mtf("gaussian:sigma=-1mm")
    with pytest.raises(OSError):
        m.chart_mtf(str(tmp_path / "no_such_print.mtf.csv"))
