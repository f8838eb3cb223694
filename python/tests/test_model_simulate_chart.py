"""model, simulate, chart and locate against truth from outside the code."""

import numpy as np
import pytest

import sweepmtf
from conftest import ROOT, SHOT, TARGET


def test_otf_is_the_closed_form_and_broadcasts():
    a_mm = 4.3e-3
    m = sweepmtf.model(aperture="rect:A=4.3um,B=4.3um")
    u = np.linspace(0, 500, 1001)
    got = m.otf(u, 0.0)
    assert got.shape == u.shape and got.dtype == np.complex128
    # 100 % fill square pixel: OTF(u, 0) = sinc(A u) (numpy's normalised sinc).
    np.testing.assert_allclose(got.real, np.sinc(a_mm * u), rtol=0, atol=1e-12)
    np.testing.assert_allclose(got.imag, 0, atol=1e-12)
    uu, vv = np.meshgrid(np.linspace(-300, 300, 31), np.linspace(-200, 200, 21))
    grid = m.mtf(uu, vv)
    assert grid.shape == (21, 31)
    np.testing.assert_allclose(grid, np.abs(np.sinc(a_mm * uu) * np.sinc(a_mm * vv)), atol=1e-12)
    # Gaussian blur: exp(−2π²σ²f²).
    g = sweepmtf.model(gaussian="sigma=2um")
    f = np.array([0.0, 50.0, 100.0, 200.0])
    np.testing.assert_allclose(g.mtf(f, 0 * f), np.exp(-2 * np.pi**2 * (2e-3) ** 2 * f**2), atol=1e-12)
    # Empty arrays and scalars.
    assert m.otf(np.array([]), np.array([])).shape == (0,)
    assert m.mtf(0.0, 0.0).shape == ()


def test_cut_and_map_agree_with_otf():
    m = sweepmtf.model(optics="diffraction:lambda=550nm,fnum=4", aperture="rect:A=4.3um,B=4.3um",
                       sampling="rect:px=4.3um,py=4.3um")
    c = m.cut("deg=30", 300.0, 301)
    np.testing.assert_allclose(c["otf"], m.otf(c["u_cy_mm"], c["v_cy_mm"]), atol=1e-15)
    assert set(c["factors"]) == set(m.factors)
    assert c["nyquist_cy_mm"] is not None
    nyq_u, nyq_v = m.nyquist_cy_mm
    assert abs(nyq_u - 1 / (2 * 4.3e-3)) < 1e-9
    mp = m.map(200.0, 64)
    assert mp["mtf"].shape == (64, 64)
    uu, vv = np.meshgrid(mp["u_cy_mm"], mp["v_cy_mm"])
    np.testing.assert_allclose(mp["mtf"], m.mtf(uu, vv), atol=1e-12)


def test_simulated_shot_measures_to_its_truth(tmp_path):
    optics = sweepmtf.model(gaussian="sigma=3um")
    shot = sweepmtf.simulate(
        TARGET,
        {"width_px": 1200, "height_px": 800, "encoding": "linear", "bits": 16, "exposure": 0.7},
        optics,
    )
    assert shot.linear.shape == (800, 1200) and shot.linear.dtype == np.float32
    t = shot.truth[0]
    assert len(t["freq_cy_px"]) == len(t["mtf"]) > 10
    m = sweepmtf.measure(shot.linear, target=TARGET, name="shot")
    c = m.curves[0]
    ok = ~c.aliased & (c.freq_cy_px < 0.45)
    truth = np.interp(c.freq_cy_px[ok], t["freq_cy_px"], t["mtf"])
    rms = np.sqrt(np.mean((c.mtf[ok] - truth) ** 2))
    assert rms < 0.02, rms
    written = shot.write(tmp_path / "s.png")
    assert any(p.endswith("s.truth.csv") for p in written)
    assert (tmp_path / "s.png").exists()


def test_chart_writes_the_print_and_its_description(tmp_path):
    r = sweepmtf.chart(tmp_path / "c.png", 0.5, 3.0, width_mm=100, height_mm=60, dpi=300)
    assert r["width_px"] == round(100 * 300 / 25.4)
    assert (tmp_path / "c.png").exists() and (tmp_path / "c.toml").exists()
    assert (tmp_path / "c.preview.png").exists()
    assert r["preview"].ndim == 2 and r["preview"].dtype == np.uint8
    assert "sweep" in r["target_toml"]
    arr = sweepmtf.read_photo(tmp_path / "c.png")
    assert arr.shape[:2] == (r["height_px"], r["width_px"])


def test_locate_path_and_array_agree():
    a = sweepmtf.locate(SHOT, TARGET)
    b = sweepmtf.locate(sweepmtf.read_photo(SHOT), TARGET)
    assert len(a) == len(b) == 1
    np.testing.assert_allclose(a[0]["corners_px"], b[0]["corners_px"], atol=1e-12)
    assert np.asarray(a[0]["homography"]).shape == (3, 3)
    # The simulator's placement is the truth of where the chart is.
    import json
    truth = json.loads((ROOT / "testdata" / "a4_log_shot.json").read_text())["target_corners"]
    np.testing.assert_allclose(np.ravel(a[0]["corners_px"]), truth, atol=1.0)
