#!/usr/bin/env python3
"""Shots of a printed sine-sweep strip made by a renderer that shares no code
with sweepmtf, measured by the `sweepmtf` CLI as a new user would (strip
corners only, default settings) and scored against this renderer's exact
truth. A check from outside the code under test (issue 15's "shots the tests
never see").

The camera, all in numpy:
- the chart: a log sweep 0.1 < reflectance < 0.9 (mean 0.5, contrast 0.8) on
  white paper (1.0), evaluated analytically at 4×4 points per pixel;
- the geometry: a keystone homography (one strip end up to 1.5× the other's
  height), a turn, and radial distortion r_d = r_u (1 + k1 r_u² + k2 r_u⁴)
  (radius 1 = half the frame diagonal), inverted per sample by Newton;
- the light: a linear gradient across the frame and cos⁴-like vignetting,
  tinted (1, 0.8, 0.55), white-balanced by the camera afterwards;
- the lens: a diffraction-limited circular pupil at f/N (λ = 0.55 µm,
  pitch 4 µm) × a Gaussian aberration blur × optionally a defocus disc, its
  exact OTF applied by FFT on the 4×-supersampled radiance;
- the pixel: the 4×4 sample mean (transfer sin(πf)/(4 sin(πf/4)) per axis);
- the sensor: Poisson shot noise (full well 9000 e⁻) and 3 e⁻ read noise;
- optional unsharp-mask sharpening in linear light (discrete Gaussian
  kernel, its exact discrete transfer in the truth);
- sRGB encoding (and optionally a picture style's S-curve on the code),
  optionally an unsharp mask on the code, 8 bits, then Pillow's libjpeg at
  quality Q with 4:2:0 chroma (or PNG).

Truth at a frequency f along the strip (angle θ in the image):
OTF_lens(f) · B(f cos θ) · B(f sin θ) · (1 + a (1 − G_d(f cos θ, f sin θ))).
With the code sharpened (kinds codesharp and jpegcam: an unsharp mask on the
sRGB or picture-style code, as a camera's JPEG engine does, amount 0.3–1,
radius 0.6–1.5 px) the camera is not linear and has no MTF of its own: the
truth is then the one a sine chart of this contrast at this light defines,
as every modulation-based method reads it: a pure sine of that transfer up
to the code, at the light where the strip has local frequency f, encoded,
each harmonic k of the code scaled by the mask's discrete transfer at k·f,
decoded; its fundamental over its mean, over the printed 0.8
(`code_sharpened`). Over the input's mean instead it would read up to 8 %
higher at 0.2 cy/px: sharpening the code raises the linear mean where it
swings wider (by 14 % through a strong S-curve).

Run: python3 docs/studies/independent_shots.py N SEED [KIND] (needs numpy,
scipy, pillow and a release build: `cargo build --release`). KIND: jpeg75,
jpeg85, png, sharpen, keystone, distort, light, all, tone (a camera's
picture style: a tanh S-curve of strength 1–2.5 on the sRGB code), camera
(all and tone), tonelight (tone and light: the black level from the paper,
session 23), codesharp (sRGB, the code sharpened; session 26), jpegcam
(a picture style and the code sharpened after it, as camera JPEGs are),
linear (a linear sweep; session 27), keylin (a keystoned linear sweep,
issue 15's bar), varied (strips 500–1400 px long, 30–150 px tall, turned
up to ±15° or near vertical, either sweep, exposure 0.3–0.95), bayer (an
RGGB sensor: each pixel sees its own colour, noise per site, white balance,
then a bilinear or Malvar–He–Cutler demosaic, with lateral CA of up to
±1 px at the frame's corner in red and in blue; session 28; its truth is
the luma MTF a sine chart defines through mosaic, demosaic, CA, sRGB and
the JPEG's Y′, `bayer_truth`), bayerall (that with uneven light, the code
sharpened and q75–92), bayernl (bayer's shots demosaicked by Menon et
al.'s directional, non-linear method instead; session 29; needs
colour-demosaicing). EXTRA="--tone file" passes options to `measure`;
SHOW_TONE=1 prints the tone correction and its black level found;
P_<name>=value overrides one of a shot's parameters (P_click=N: corners
clicked up to ±N px off; P_beyond=N: the high end's corners N px past the
print along the strip; P_surround=R: the chart around the strip of
reflectance R instead of white paper, e.g. 0.5, the sweep's mean;
P_f1_px=F: the sweep printed up to F cy/px); with
KEEP=dir (and ONLY=i) the shot, its truth and its corners (roi.txt) stay
(KEEP_ALL=dir: each shot in dir/KIND_SEED_I). Prints one line per shot
and a summary row: RMS |MTF − truth| over 0.01–0.45 cy/px, the MTF50 error and
the chart modulation's error (printed 0.800).
"""

import json
import math
import os
import subprocess
import sys
import tempfile

import numpy as np
from PIL import Image
from scipy.special import j1

S = 4  # samples per pixel along each axis
W, H = 1600, 900  # frame (px)
PITCH_MM = 0.004
LAMBDA_MM = 0.55e-3
BIN = os.environ.get("SWEEPMTF", os.path.join(os.path.dirname(__file__), "../../target/release/sweepmtf"))


def otf_lens(f, p):
    """The lens's OTF at radial frequency f (cy/px)."""
    fc = 1.0 / (LAMBDA_MM * p["fnum"]) * PITCH_MM  # diffraction cut-off, cy/px
    nu = np.clip(np.abs(f) / fc, 0, 1)
    diff = (2 / np.pi) * (np.arccos(nu) - nu * np.sqrt(1 - nu * nu))
    g = np.exp(-2 * np.pi**2 * p["sigma"] ** 2 * f * f)
    x = 2 * np.pi * p["defocus"] * np.abs(f)
    disc = np.where(x > 1e-9, 2 * j1(np.maximum(x, 1e-9)) / np.maximum(x, 1e-9), 1.0)
    return diff * g * disc


def box(f):
    """The 4×4 sample mean's transfer along one axis at f cy/px."""
    f = np.asarray(f, dtype=float)
    num = np.sin(np.pi * f)
    den = S * np.sin(np.pi * f / S)
    return np.where(np.abs(den) > 1e-12, num / np.where(np.abs(den) > 1e-12, den, 1), 1.0)


def usm_kernel(radius):
    r = int(math.ceil(4 * radius))
    x = np.arange(-r, r + 1)
    k1 = np.exp(-0.5 * (x / radius) ** 2)
    k1 /= k1.sum()
    return x, k1


def usm_transfer(fx, fy, p):
    if p["amount"] == 0:
        return 1.0
    x, k = usm_kernel(p["radius"])
    gx = np.sum(k * np.cos(2 * np.pi * fx * x))
    gy = np.sum(k * np.cos(2 * np.pi * fy * x))
    return 1 + p["amount"] * (1 - gx * gy)


def truth(f, p):
    th = p["theta"]
    fx, fy = f * math.cos(th), f * math.sin(th)
    t = float(otf_lens(np.array(f), p) * box(fx) * box(fy) * usm_transfer(fx, fy, p))
    if p["bayer"]:
        return bayer_truth(f, p)
    return code_sharpened(f, t, p) if p["code_amount"] > 0 else t


def homography(src, dst):
    a = []
    for (x, y), (u, v) in zip(src, dst):
        a.append([x, y, 1, 0, 0, 0, -u * x, -u * y, -u])
        a.append([0, 0, 0, x, y, 1, -v * x, -v * y, -v])
    _, _, vt = np.linalg.svd(np.array(a))
    return vt[-1].reshape(3, 3) / vt[-1, -1]


def apply_h(h, x, y):
    d = h[2, 0] * x + h[2, 1] * y + h[2, 2]
    return (h[0, 0] * x + h[0, 1] * y + h[0, 2]) / d, (h[1, 0] * x + h[1, 1] * y + h[1, 2]) / d


def distort(x, y, p):
    """Undistorted → distorted image position (px)."""
    cx, cy, rn = W / 2, H / 2, math.hypot(W, H) / 2
    u, v = (x - cx) / rn, (y - cy) / rn
    r2 = u * u + v * v
    s = 1 + p["k1"] * r2 + p["k2"] * r2 * r2
    return cx + u * s * rn, cy + v * s * rn


def undistort(x, y, p):
    cx, cy, rn = W / 2, H / 2, math.hypot(W, H) / 2
    ud, vd = (x - cx) / rn, (y - cy) / rn
    rd = np.sqrt(ud * ud + vd * vd)
    r = rd.copy()
    for _ in range(8):
        fval = r * (1 + p["k1"] * r * r + p["k2"] * r**4) - rd
        dval = 1 + 3 * p["k1"] * r * r + 5 * p["k2"] * r**4
        r = r - fval / dval
    scale = np.where(rd > 1e-12, r / np.maximum(rd, 1e-12), 1.0)
    return cx + ud * scale * rn, cy + vd * scale * rn


def reflectance(u, v, p):
    """The printed chart at (u, v) mm: the sweep strip on white paper (or
    on the surround's reflectance, P_surround)."""
    L, h, f0, f1 = p["L"], p["h"], p["f0"], p["f1"]
    inside = (u >= 0) & (u <= L) & (v >= 0) & (v <= h)
    uc = np.clip(u, 0, L)
    if p["sweep"] == "lin":
        # A linear sweep: the local frequency f0 + (f1 − f0)·u/L cycles/mm.
        ph = 2 * np.pi * (f0 * uc + (f1 - f0) * uc * uc / (2 * L))
    else:
        k = math.log(f1 / f0) / L
        ph = 2 * np.pi * f0 / k * (np.exp(k * uc) - 1)
    sweep = 0.5 * (1 + 0.8 * np.sin(ph))
    return np.where(inside, sweep, p["surround"])


def strip_geometry(p):
    """The strip's corners in the undistorted image (px) and the homography chart mm → image."""
    L, h = p["L"], p["h"]
    cx, cy = p["cx"], p["cy"]
    half_len = p["len_px"] / 2
    h0 = p["h_px"]
    h1 = h0 * p["keystone"]
    c, s = math.cos(p["theta"]), math.sin(p["theta"])
    local = [(-half_len, -h0 / 2), (half_len, -h1 / 2), (half_len, h1 / 2), (-half_len, h0 / 2)]
    dst = [(cx + c * a - s * b, cy + s * a + c * b) for a, b in local]
    src = [(0, 0), (L, 0), (L, h), (0, h)]
    return dst, homography(src, dst)


def light_raw(xx, yy, p):
    rn = math.hypot(W, H) / 2
    r2 = ((xx - W / 2) ** 2 + (yy - H / 2) ** 2) / rn**2
    vig = 1 - p["vignette"] * r2
    grad = 1 + p["gradient"] * ((xx - W / 2) * math.cos(p["grad_dir"]) + (yy - H / 2) * math.sin(p["grad_dir"])) / rn
    return vig * grad


def light_at(xx, yy, p):
    """The light on the chart at image position (px): white paper there reads this (linear)."""
    if "light_max" not in p:
        gy, gx = np.mgrid[0:H, 0:W]
        p["light_max"] = float(light_raw(gx, gy, p).max())
    return light_raw(xx, yy, p) / p["light_max"] * p["exposure"]


def encode(lin, p):
    """Linear light → the file's code (sRGB and the picture style), 0–1."""
    lin = np.clip(lin, 0, 1)
    c = np.where(lin <= 0.0031308, 12.92 * lin, 1.055 * np.power(lin, 1 / 2.4) - 0.055)
    if p["tone"] > 0:
        # A camera's S-shaped picture style on top of sRGB: tanh of strength k about mid-grey code.
        k = p["tone"]
        c = 0.5 + 0.5 * np.tanh(k * (c - 0.5)) / math.tanh(k / 2)
    return c


def decode(c, p):
    """The file's code → linear light: the inverse of `encode`."""
    c = np.clip(c, 0, 1)
    if p["tone"] > 0:
        k = p["tone"]
        c = 0.5 + np.arctanh(np.clip((2 * c - 1) * math.tanh(k / 2), -1 + 1e-15, 1 - 1e-15)) / k
    return np.where(c <= 0.04045, c / 12.92, np.power((c + 0.055) / 1.055, 2.4))


def where_frequency(f, p):
    """Where on the strip's centre line the local frequency is f cy/px (photo
    px, through the lens's distortion) and the light there."""
    px_per_mm = p["len_px"] / p["L"]
    if p["sweep"] == "lin":
        u = (f * px_per_mm - p["f0"]) / (p["f1"] - p["f0"]) * p["L"]
    else:
        k = math.log(p["f1"] / p["f0"]) / p["L"]
        u = math.log(max(f * px_per_mm, 1e-9) / p["f0"]) / k
    u = min(max(u, 0.0), p["L"])
    _, hm = strip_geometry(p)
    x, y = distort(*apply_h(hm, u, p["h"] / 2), p)
    return x, y, float(light_at(np.array(x), np.array(y), p))


def code_sharpened(f, t_lin, p):
    """The MTF read in linear light where the code is sharpened: a pure sine of
    transfer `t_lin` up to the code, at the light where the strip has local
    frequency f, encoded, each harmonic k of the code scaled by the unsharp
    mask's discrete transfer at k·f, clipped and decoded; its modulation (the
    fundamental over the mean, both after: sharpening the code raises the
    linear mean where it swings wider) over the printed 0.8. A system that is
    not linear has no MTF of its own: this is the one a sine chart of this
    contrast at this light defines, as every modulation-based method reads it."""
    th = p["theta"]
    fx, fy = f * math.cos(th), f * math.sin(th)
    x, y, ell = where_frequency(f, p)
    n = 512
    ph = 2 * np.pi * np.arange(n) / n
    amp = ell * 0.4 * t_lin
    code = encode(ell * 0.5 + amp * np.cos(ph), p)
    spec = np.fft.rfft(code)
    xk, kern = usm_kernel(p["code_radius"])
    hk = np.arange(len(spec))[:, None]
    g = (kern * np.cos(2 * np.pi * hk * fx * xk)).sum(axis=1) * (kern * np.cos(2 * np.pi * hk * fy * xk)).sum(axis=1)
    spec *= 1 + p["code_amount"] * (1 - g)
    out = np.fft.rfft(decode(np.fft.irfft(spec, n), p))
    return 2 * abs(out[1]) / abs(out[0]) / 0.8


def cfa_masks(shape):
    """RGGB site masks (R at even row and column, B at odd row and column)."""
    yy, xx = np.mgrid[0 : shape[0], 0 : shape[1]]
    r = (yy % 2 == 0) & (xx % 2 == 0)
    b = (yy % 2 == 1) & (xx % 2 == 1)
    return r, ~(r | b), b, (yy % 2 == 0)


def demosaic(m, how):
    """A white-balanced RGGB mosaic → R, G, B planes: bilinear (a camera's
    fast path), Malvar–He–Cutler's gradient-corrected 5×5 kernels (2004;
    many camera ISPs and OpenCV's default) or Menon–Andriani–Calvagno's
    directional, edge-adaptive one (2007, "DDFAPD": each missing green
    interpolated along the direction its neighbourhood varies least, then
    refined; not linear), the last from the colour-demosaicing package
    (pip install colour-demosaicing). Our bilinear and Malvar–He–Cutler
    agree with that package's to the last bit away from the frame's edge."""
    from scipy.ndimage import convolve

    if how == "menon":
        from colour_demosaicing import demosaicing_CFA_Bayer_Menon2007

        rgb = demosaicing_CFA_Bayer_Menon2007(m, "RGGB")
        return rgb[..., 0], rgb[..., 1], rgb[..., 2]

    r, g, b, even_row = cfa_masks(m.shape)
    conv = lambda k: convolve(m, np.array(k, dtype=float), mode="mirror")
    if how == "bilinear":
        kg = np.array([[0, 1, 0], [1, 4, 1], [0, 1, 0]]) / 4.0
        krb = np.array([[1, 2, 1], [2, 4, 2], [1, 2, 1]]) / 4.0
        G = convolve(m * g, kg, mode="mirror")
        R = convolve(m * r, krb, mode="mirror")
        B = convolve(m * b, krb, mode="mirror")
        return R, G, B
    kg = np.array([[0, 0, -1, 0, 0], [0, 0, 2, 0, 0], [-1, 2, 4, 2, -1], [0, 0, 2, 0, 0], [0, 0, -1, 0, 0]]) / 8.0
    krow = np.array([[0, 0, 0.5, 0, 0], [0, -1, 0, -1, 0], [-1, 4, 5, 4, -1], [0, -1, 0, -1, 0], [0, 0, 0.5, 0, 0]]) / 8.0
    kdiag = np.array([[0, 0, -1.5, 0, 0], [0, 2, 0, 2, 0], [-1.5, 0, 6, 0, -1.5], [0, 2, 0, 2, 0], [0, 0, -1.5, 0, 0]]) / 8.0
    cg, crow, ccol, cdiag = conv(kg), conv(krow), conv(krow.T), conv(kdiag)
    G = np.where(g, m, cg)
    # R: at G sites of R rows its neighbours sit left and right (krow), at G
    # sites of B rows above and below (kcol), at B sites diagonally.
    R = np.where(r, m, np.where(g & even_row, crow, np.where(g, ccol, cdiag)))
    B = np.where(b, m, np.where(g & ~even_row, crow, np.where(g, ccol, cdiag)))
    return R, G, B


def bayer_truth(f, p):
    """The luma MTF a sine chart defines through the mosaic, the demosaic and
    lateral chromatic aberration: a noise-free pure sine of the presampling
    transfer at the light where the strip has local frequency f, each colour
    displaced by its CA there, mosaicked, demosaicked, sRGB-encoded (each
    code sharpened where the camera sharpens it), mixed to the JPEG's Y′
    (0.299, 0.587, 0.114) and decoded; its fundamental (the CFA's aliases at
    +½ cy/px cancelled, below) over its mean, over the printed 0.8."""
    th = p["theta"]
    fx, fy = f * math.cos(th), f * math.sin(th)
    t = float(otf_lens(np.array(f), p) * box(fx) * box(fy))
    x0, y0, ell = where_frequency(f, p)
    # The chain is periodic in 2 px, so its response to the sine is the sine's
    # fundamental plus aliases at +½ cy/px in x, y or both, and harmonics.
    # Stepping the sine's phase in 16 steps and taking the first Fourier
    # coefficient over them keeps the first harmonic and its aliases; times
    # e^{−i2πf·x} and averaged over a 2×2 block, the aliases (±1 patterns)
    # cancel and the fundamental stays, exactly, at any frequency and angle.
    n, steps = 32, 16
    yy, xx = np.mgrid[0:n, 0:n].astype(float)
    r, g, b, _ = cfa_masks((n, n))
    # The 2×2 block read: far enough inside for the demosaic's and the
    # sharpening's kernels (reflected edges do not reach it).
    c0 = (slice(n // 2 - 1, n // 2 + 1),) * 2
    dc = np.zeros((2, 2))
    c1 = np.zeros((2, 2), dtype=complex)
    for j in range(steps):
        ph0 = 2 * np.pi * j / steps
        m = np.empty((n, n))
        for mask, eps in ((r, p["ca_r"]), (g, 0.0), (b, p["ca_b"])):
            # Lateral CA: this colour's image is magnified by (1 + eps) about
            # the frame's centre, so here it is displaced by eps·(x − centre).
            dx, dy = eps * (x0 - W / 2), eps * (y0 - H / 2)
            v = ell * 0.5 * (1 + 0.8 * t * np.cos(2 * np.pi * (fx * (xx - dx) + fy * (yy - dy)) + ph0))
            m[mask] = v[mask]
        codes = [encode(c, p) for c in demosaic(m, p["bayer"])]
        if p["code_amount"] > 0:
            # The camera's sharpening of each channel's code, as `render` does.
            from scipy.ndimage import convolve1d

            _, kern = usm_kernel(p["code_radius"])
            blur = lambda c: convolve1d(convolve1d(c, kern, axis=0, mode="nearest"), kern, axis=1, mode="nearest")
            codes = [c + p["code_amount"] * (c - blur(c)) for c in codes]
        ypr = 0.299 * codes[0] + 0.587 * codes[1] + 0.114 * codes[2]
        lin = decode(ypr, p)[c0]
        dc += lin / steps
        c1 += lin * np.exp(-1j * ph0) * 2 / steps
    fund = np.mean(c1 * np.exp(-2j * np.pi * (fx * xx[c0] + fy * yy[c0])))
    return abs(fund) / np.mean(dc) / 0.8


def render(p, rng):
    """The 8-bit sRGB frame (H×W×3) and the strip's corners in the image."""
    L, h = p["L"], p["h"]
    dst, hm = strip_geometry(p)
    hinv = np.linalg.inv(hm)
    # Supersampled sample positions (image px), only over the strip's surround band.
    # Pixel (i, j) covers [i, i + 1) × [j, j + 1) (sweepmtf's convention: origin at the top-left corner).
    xs = (np.arange(W * S) + 0.5) / S
    ys = (np.arange(H * S) + 0.5) / S
    img = np.ones((H * S, W * S), dtype=np.float64)
    # Rows of the band that can hold the strip (with a margin for the blur).
    ally = [distort(x, y, p)[1] for x, y in dst]
    y0 = max(0, int((min(ally) - 40) * S))
    y1 = min(H * S, int((max(ally) + 40) * S))
    X, Y = np.meshgrid(xs, ys[y0:y1])
    ux, uy = undistort(X, Y, p)
    cu, cv = apply_h(hinv, ux, uy)
    img[y0:y1] = reflectance(cu, cv, p)
    del X, Y, ux, uy, cu, cv
    # Lens blur by FFT on the band (padded), with the exact OTF.
    band = img[max(0, y0 - 64 * S) : min(H * S, y1 + 64 * S)]
    pad = 64 * S
    b = np.pad(band, ((pad, pad), (pad, pad)), mode="edge")
    fy = np.fft.fftfreq(b.shape[0]) * S  # cy/px
    fx = np.fft.rfftfreq(b.shape[1]) * S
    fr = np.sqrt(fy[:, None] ** 2 + fx[None, :] ** 2)
    b = np.fft.irfft2(np.fft.rfft2(b) * otf_lens(fr, p), s=b.shape)[pad:-pad, pad:-pad]
    img[max(0, y0 - 64 * S) : min(H * S, y1 + 64 * S)] = b
    # Light: gradient × vignetting × tint; exposure so white paper peaks at p["exposure"].
    yy, xx = np.mgrid[0:H, 0:W]
    light = light_at(xx, yy, p)
    tint = np.array([1.0, 0.8, 0.55])
    fw = 9000.0
    if p["bayer"]:
        # Lateral CA: red and blue images magnified by (1 + eps) about the
        # centre (resampled by cubic spline at 4× supersampling); each pixel
        # of the RGGB mosaic sees its own colour; noise per site; white
        # balance; demosaic.
        from scipy.ndimage import map_coordinates

        lo, hi = max(0, y0 - 64 * S), min(H * S, y1 + 64 * S)
        by, bx = np.mgrid[lo:hi, 0 : W * S].astype(float)
        r, g, b, _ = cfa_masks((H, W))
        m = np.zeros((H, W))
        for c, (mask, eps) in enumerate(((r, p["ca_r"]), (g, 0.0), (b, p["ca_b"]))):
            plane = img
            if eps != 0:
                plane = img.copy()
                sx = (W / 2 + ((bx + 0.5) / S - W / 2) / (1 + eps)) * S - 0.5
                sy = (H / 2 + ((by + 0.5) / S - H / 2) / (1 + eps)) * S - 0.5
                plane[lo:hi] = map_coordinates(img, [sy, sx], order=3, mode="nearest")
            refl = plane.reshape(H, S, W, S).mean(axis=(1, 3))
            m[mask] = (refl * light * tint[c])[mask]
        del by, bx
        e = rng.poisson(np.clip(m, 0, None) * fw).astype(np.float64) + rng.normal(0, 3.0, m.shape)
        gain = np.where(r, tint[0], np.where(b, tint[2], tint[1]))
        lin = np.stack(demosaic(e / fw / gain, p["bayer"]), axis=-1)
    else:
        # The pixel aperture: the mean of its S×S samples.
        refl = img.reshape(H, S, W, S).mean(axis=(1, 3))
        lin = refl[..., None] * light[..., None] * tint[None, None, :]
        # Sensor: Poisson shot noise and read noise in electrons, full well 9000.
        e = rng.poisson(np.clip(lin, 0, None) * fw).astype(np.float64) + rng.normal(0, 3.0, lin.shape)
        # P_noise=0 probes a shot without sensor noise (the draws are still made).
        lin = e / fw if p["noise"] == 1 else lin + p["noise"] * (e / fw - lin)
        # White balance (the camera neutralises the tint).
        lin = lin / tint[None, None, :]
    # Unsharp mask in linear light (separable discrete Gaussian).
    if p["amount"] > 0:
        x, k = usm_kernel(p["radius"])
        from scipy.ndimage import convolve1d

        blur = convolve1d(convolve1d(lin, k, axis=0, mode="nearest"), k, axis=1, mode="nearest")
        lin = lin + p["amount"] * (lin - blur)
    srgb = encode(lin, p)
    if p["code_amount"] > 0:
        # A camera's own sharpening, as JPEG engines do it: an unsharp mask
        # on the code (after the tone curve), not in linear light.
        x, k = usm_kernel(p["code_radius"])
        from scipy.ndimage import convolve1d

        blur = convolve1d(convolve1d(srgb, k, axis=0, mode="nearest"), k, axis=1, mode="nearest")
        srgb = srgb + p["code_amount"] * (srgb - blur)
    out = np.clip(np.round(srgb * 255), 0, 255).astype(np.uint8)
    corners = [distort(x, y, p) for x, y in dst]
    return out, corners


def draw(kind, rng):
    u = rng.uniform
    p = dict(
        L=240.0,
        h=20.0,
        theta=math.radians(u(-3, 3)),
        cx=W / 2 + u(-80, 80),
        cy=H / 2 + u(-60, 60),
        len_px=u(1100, 1400),
        h_px=u(70, 110),
        keystone=1.0,
        k1=0.0,
        k2=0.0,
        vignette=u(0.0, 0.2),
        gradient=u(0.0, 0.1),
        grad_dir=u(0, 2 * math.pi),
        exposure=u(0.6, 0.9),
        fnum=u(2.8, 8.0),
        sigma=u(0.3, 0.6),
        defocus=0.0 if u() < 0.5 else u(0.2, 0.7),
        amount=0.0,
        radius=1.0,
        fmt="jpeg",
        quality=85,
        click=0.0,
        beyond=0.0,
        surround=1.0,
        tone=0.0,
        code_amount=0.0,
        code_radius=1.0,
        sweep="log",
        bayer="",
        ca_r=0.0,
        ca_b=0.0,
        noise=1.0,
    )
    # Chart frequencies chosen so the strip reaches ≈ 0.008 … 0.6 cy/px.
    px_per_mm = p["len_px"] / p["L"]
    p["f0"] = 0.008 * px_per_mm
    p["f1"] = 0.6 * px_per_mm
    if kind in ("jpeg75", "all", "camera"):
        p["quality"] = 75
    if kind == "png":
        p["fmt"] = "png"
    if kind in ("sharpen", "all", "camera"):
        p["amount"] = u(0.3, 0.8)
        p["radius"] = u(0.8, 1.5)
    if kind in ("keystone", "all", "camera"):
        p["keystone"] = u(1.2, 1.5) if u() < 0.5 else 1 / u(1.2, 1.5)
    if kind in ("distort", "all", "camera"):
        # −4…+4 % at the frame corner, strip near the top or bottom edge.
        d = u(-0.04, 0.04)
        mix = u(0, 1)
        p["k1"], p["k2"] = d * mix, d * (1 - mix)
        p["cy"] = H / 2 + (1 if u() < 0.5 else -1) * u(250, 320)
    if kind in ("tone", "camera", "tonelight"):
        p["tone"] = u(1.0, 2.5)
    if kind in ("light", "all", "camera", "tonelight"):
        p["vignette"] = 0.5
        p["gradient"] = u(0.3, 0.5)
        p["grad_dir"] = math.atan2(math.sin(p["theta"]), math.cos(p["theta"])) + (0 if u() < 0.5 else math.pi)
    if kind in ("codesharp", "jpegcam"):
        # Drawn last: the other kinds' shots stay as they were.
        p["code_amount"] = u(0.3, 1.0)
        p["code_radius"] = u(0.6, 1.5)
    if kind == "jpegcam":
        p["tone"] = u(1.0, 2.5)
    if kind in ("linear", "keylin"):
        # Drawn last too. A linear sweep from 0.004–0.01 to 0.4–0.6 cy/px,
        # as sineMTF-style charts print; keylin keystones it (issue 15's bar).
        p["sweep"] = "lin"
        p["f0"] = u(0.004, 0.01) * px_per_mm
        p["f1"] = u(0.4, 0.6) * px_per_mm
    if kind == "keylin":
        p["keystone"] = u(1.2, 1.5) if u() < 0.5 else 1 / u(1.2, 1.5)
    if kind == "varied":
        # Geometry and exposure beyond the other kinds' narrow spread: short
        # and long, thin and tall strips, turned up to ±15° or near vertical,
        # either sweep, reaching 0.35–0.6 cy/px from 0.004–0.02.
        p["len_px"] = u(500, 1400)
        p["h_px"] = u(30, 150)
        if u() < 0.3:
            # Near vertical: short enough for the 900-px frame.
            p["theta"] = math.radians(90 + u(-15, 15))
            p["len_px"] = u(400, 700)
            p["cy"] = H / 2
        else:
            p["theta"] = math.radians(u(-15, 15))
        p["exposure"] = u(0.3, 0.95)
        p["sweep"] = "lin" if u() < 0.5 else "log"
        px_per_mm = p["len_px"] / p["L"]
        p["f0"] = u(0.004, 0.02) * px_per_mm
        p["f1"] = u(0.35, 0.6) * px_per_mm
    if kind in ("bayer", "bayerall", "bayernl"):
        # Drawn last too. An RGGB sensor demosaicked bilinearly or by
        # Malvar–He–Cutler, with lateral CA of up to ±1 px at the frame's
        # corner in red and in blue, each its own.
        p["bayer"] = "bilinear" if u() < 0.5 else "mhc"
        rn = math.hypot(W, H) / 2
        p["ca_r"] = u(-1, 1) / rn
        p["ca_b"] = u(-1, 1) / rn
    if kind == "bayernl":
        # A non-linear, edge-directed demosaic instead (session 29).
        p["bayer"] = "menon"
    if kind == "bayerall":
        # And the rest of a camera: uneven light, sharpening of the code, q75–92.
        p["vignette"] = 0.5
        p["gradient"] = u(0.3, 0.5)
        p["grad_dir"] = math.atan2(math.sin(p["theta"]), math.cos(p["theta"])) + (0 if u() < 0.5 else math.pi)
        p["code_amount"] = u(0.3, 1.0)
        p["code_radius"] = u(0.6, 1.5)
        p["quality"] = int(u(75, 92))
    # Overrides for probing one shot: P_<name>=value (e.g. P_fmt=png, P_k1=0).
    for k, v in os.environ.items():
        if k.startswith("P_") and k[2:] in p:
            p[k[2:]] = v if k[2:] in ("fmt", "sweep", "bayer") else int(v) if k[2:] == "quality" else float(v)
    # P_f1_px=F: the sweep printed up to F cy/px instead (e.g. below the
    # band limit, so that what lies beyond its high end is scored).
    if "P_f1_px" in os.environ:
        p["f1"] = float(os.environ["P_f1_px"]) * p["len_px"] / p["L"]
    return p


def true_mtf50(p):
    lo = 0.0
    while truth(lo + 0.001, p) >= 0.5:
        lo += 0.001
    hi = lo + 0.001
    for _ in range(40):
        mid = 0.5 * (lo + hi)
        if truth(mid, p) >= 0.5:
            lo = mid
        else:
            hi = mid
    return lo


def measure(img, corners, p, tmp):
    """Writes the shot, measures it with the CLI from its strip corners, scores it."""
    path = os.path.join(tmp, "shot.jpg" if p["fmt"] == "jpeg" else "shot.png")
    im = Image.fromarray(img, "RGB")
    if p["fmt"] == "jpeg":
        im.save(path, quality=p["quality"], subsampling=2)
    else:
        im.save(path)
    # The high end's corners placed `beyond` px past the print along the strip.
    if p["beyond"]:
        (x0, y0), (x1, y1) = corners[0], corners[1]
        d = math.hypot(x1 - x0, y1 - y0)
        ax, ay = (x1 - x0) / d, (y1 - y0) / d
        corners = [corners[0], (corners[1][0] + p["beyond"] * ax, corners[1][1] + p["beyond"] * ay),
                   (corners[2][0] + p["beyond"] * ax, corners[2][1] + p["beyond"] * ay), corners[3]]
    # Corners as a user clicks them: exact, or off by up to ±click px in x and y.
    jitter = np.random.default_rng(len(corners) + int(1e6 * p["theta"]) % 1000).uniform(-1, 1, 8) * p["click"]
    roi = ",".join(f"{v + j:.2f}" for v, j in zip([v for c in corners for v in c], jitter))
    out = os.path.join(tmp, "out")
    with open(os.path.join(tmp, "roi.txt"), "w") as fh:
        fh.write(roi)
    extra = os.environ.get("EXTRA", "").split()
    r = subprocess.run([BIN, "measure", path, "--roi", roi, "--json", "-q", "-o", out, *extra], capture_output=True, text=True)
    if r.returncode != 0:
        return None, r.stderr.strip()
    j = json.loads(r.stdout)
    c = j["curves"][0]
    se, n = 0.0, 0
    with open(os.path.join(out, "shot.mtf.csv")) as fh:
        head = fh.readline().strip().split(",")
        for line in fh:
            q = dict(zip(head, line.strip().split(",")))
            f = float(q["freq_cy_px"])
            if q["aliased"] == "false" and 0.01 <= f <= 0.45:
                se += (float(q["mtf"]) - truth(f, p)) ** 2
                n += 1
    rms = math.sqrt(se / max(n, 1))
    f50 = (c.get("mtf50") or {}).get("cy_px")
    e50 = f50 / true_mtf50(p) - 1 if f50 else float("nan")
    # MTF50's claimed one-sigma uncertainty, relative (since session 25).
    s50 = (c.get("mtf50") or {}).get("err_cy_px")
    s50 = s50 / f50 if f50 and s50 is not None else float("nan")
    t = c.get("tone_correction")
    if t and os.environ.get("SHOW_TONE"):
        print(f"  tone: used {t['used']} {t['significance']:.1f} σ MTF at 0.5 {100 * t['mtf_change_at_half']:+.2f} % shift {t['max_shift_255']:.2f}/255 light {t['light_ratio']:.2f} code sharpening seen {t.get('code_sharpening_seen')}", flush=True)
        b = t.get("black_level")
        if b and b["offset"] is None:
            print(f"  black: not found: {b['why_not']}", flush=True)
        elif b:
            print(f"  black: used {b['used']} {100 * b['relative_to_mean']:+.2f} % ± {100 * b['offset_err'] / max(abs(b['offset']), 1e-12) * abs(b['relative_to_mean']):.2f} spread {b['light_spread']:.2f} resid {100 * b['residual']:.3f} % bands {b['bands']} {b['why_not']}", flush=True)
    cm_err = (c.get("chart_modulation_err") or float("nan")) / 0.8
    return (rms, e50, c["chart_modulation"] / 0.8 - 1, s50, cm_err), None


def main():
    n = int(sys.argv[1]) if len(sys.argv) > 1 else 5
    seed = int(sys.argv[2]) if len(sys.argv) > 2 else 1
    kind = sys.argv[3] if len(sys.argv) > 3 else "jpeg85"
    res = []
    with tempfile.TemporaryDirectory() as tmp:
        only = os.environ.get("ONLY")
        for i in range(n):
            if only is not None and i != int(only):
                continue
            rng = np.random.default_rng(seed * 1000 + i)
            p = draw(kind, rng)
            img, corners = render(p, rng)
            keep = os.environ.get("KEEP")
            if os.environ.get("KEEP_ALL"):
                # Every shot's files in a directory of its own.
                keep = os.path.join(os.environ["KEEP_ALL"], f"{kind}_{seed}_{i}")
                os.makedirs(keep, exist_ok=True)
            s, err = measure(img, corners, p, keep or tmp)
            if keep:
                with open(f"{keep}/truth.csv", "w") as fh:
                    fh.write("freq_cy_px,truth\n")
                    for f in np.arange(0.002, 0.7, 0.002):
                        fh.write(f"{f:.4f},{truth(f, p):.6f}\n")
            tag = f"{kind} seed {seed} #{i}: θ {math.degrees(p['theta']):+.2f}° f/{p['fnum']:.1f} σ {p['sigma']:.2f} defocus {p['defocus']:.2f}"
            if p["bayer"]:
                tag += f" {p['bayer']} CA R {p['ca_r'] * math.hypot(W, H) / 2:+.2f} B {p['ca_b'] * math.hypot(W, H) / 2:+.2f} px"
            if kind in ("linear", "keylin", "varied"):
                px_per_mm = p["len_px"] / p["L"]
                tag += f" {p['sweep']} {p['len_px']:.0f}×{p['h_px']:.0f} px {p['f0'] / px_per_mm:.3f}–{p['f1'] / px_per_mm:.2f} cy/px exp. {p['exposure']:.2f}"
            if s is None:
                print(f"{tag}: FAILED {err}", flush=True)
                continue
            print(f"{tag}: RMS {s[0]:.4f} MTF50 {100 * s[1]:+.2f} % (± {100 * s[3]:.2f} %) chart mod. {100 * s[2]:+.2f} % (± {100 * s[4]:.2f} %)", flush=True)
            res.append(s)
    if res:
        a = np.array(res)
        e50 = a[:, 1][np.isfinite(a[:, 1])]  # shots whose MTF stays above 0.5 have none
        z50 = np.abs(a[:, 1] / a[:, 3])[np.isfinite(a[:, 1] / a[:, 3])]
        zs = f", |z| ≤ {z50.max():.2f}, beyond 2 σ: {int(np.sum(z50 > 2))}" if len(z50) else ""
        r50 = f"{100 * e50.min():+.2f}…{100 * e50.max():+.2f} %" if len(e50) else "none"
        print(
            f"| {kind} | {len(res)} of {n} | worst RMS {a[:, 0].max():.4f} | MTF50 {r50} "
            f"(beyond 1 %: {int(np.sum(np.abs(e50) > 0.01))}, none found: {len(a) - len(e50)}{zs}) | "
            f"chart mod. {100 * a[:, 2].min():+.2f}…{100 * a[:, 2].max():+.2f} % "
            f"(beyond 0.5 %: {int(np.sum(np.abs(a[:, 2]) > 0.005))}) |"
        )


if __name__ == "__main__":
    main()
