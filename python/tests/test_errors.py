"""Bad input raises ValueError, OSError or MeasurementError with the CLI's one-line message."""

import subprocess

import numpy as np
import pytest

import sweepmtf
from conftest import ROOT, SHOT, TARGET


def cli_error(cli, *args):
    r = subprocess.run([cli, *args], capture_output=True, text=True)
    assert r.returncode != 0
    line = r.stderr.strip().splitlines()[-1]
    for prefix in ("sweepmtf: ", "error: "):
        line = line[len(prefix):] if line.startswith(prefix) else line
    return line


def test_missing_photo_is_oserror_with_the_cli_message(cli, tmp_path):
    missing = tmp_path / "nope.jpg"
    with pytest.raises(OSError) as e:
        sweepmtf.measure(missing, target=TARGET)
    msg = str(e.value)
    assert "nope.jpg" in msg and "\n" not in msg
    assert msg == cli_error(cli, "measure", str(missing), "--target", str(TARGET), "-o", str(tmp_path))


def test_missing_target_is_oserror(cli, tmp_path):
    with pytest.raises(OSError) as e:
        sweepmtf.measure(SHOT, target=tmp_path / "none.toml")
    assert "none.toml" in str(e.value)
    assert str(e.value) == cli_error(
        cli, "measure", str(SHOT), "--target", str(tmp_path / "none.toml"), "-o", str(tmp_path)
    )


def test_not_an_image_is_oserror(tmp_path):
    p = tmp_path / "text.png"
    p.write_text("hello")
    with pytest.raises(OSError, match="text.png"):
        sweepmtf.measure(p, roi=[0, 0, 10, 0, 10, 10, 0, 10])
    with pytest.raises(OSError):
        sweepmtf.read_photo(p)


def test_flat_picture_is_a_measurement_error(cli, tmp_path):
    flat = np.full((200, 400), 128, np.uint8)
    roi = [(10, 50), (390, 50), (390, 150), (10, 150)]
    with pytest.raises(sweepmtf.MeasurementError) as e:
        sweepmtf.measure(flat, roi=roi, name="flat.png")
    assert "flat.png" in str(e.value)
    # The CLI says the same of the same picture in a file.
    import zlib, struct

    def png(a):
        raw = b"".join(b"\x00" + r.tobytes() for r in a)
        chunk = lambda t, d: struct.pack(">I", len(d)) + t + d + struct.pack(">I", zlib.crc32(t + d))
        hdr = struct.pack(">IIBBBBB", a.shape[1], a.shape[0], 8, 0, 0, 0, 0)
        return b"\x89PNG\r\n\x1a\n" + chunk(b"IHDR", hdr) + chunk(b"IDAT", zlib.compress(raw)) + chunk(b"IEND", b"")

    f = tmp_path / "flat.png"
    f.write_bytes(png(flat))
    roi_text = ",".join(str(v) for xy in roi for v in xy)
    cli_msg = cli_error(cli, "measure", str(f), "--roi", roi_text, "-o", str(tmp_path / "o"))
    assert cli_msg.endswith(str(e.value).split(": ", 1)[1])
    # A picture with no chart in it: location fails.
    with pytest.raises(sweepmtf.MeasurementError, match="automatic location failed"):
        sweepmtf.measure(flat, target=TARGET)
    with pytest.raises(sweepmtf.MeasurementError):
        sweepmtf.locate(flat, TARGET)


@pytest.mark.parametrize(
    "kwargs",
    [
        {"roi": [1, 2, 3]},
        {"roi": [0, 0, 10, 0, 10, 10, 0, float("nan")]},
        {"method": "magic"},
        {"sweep": "cubic"},
        {"channel": "ir"},
        {"tone": "sepia"},
        {"tone": -1.0},
        {"pixel_pitch_um": 0},
        {"chart_index": -1},
        {"bin_px": -1.0},
        {"max_across": -1},
        {"max_across": 2.5},
        {"tone": "chart", "roi": [0, 0, 10, 0, 10, 10, 0, 10]},
    ],
)
def test_bad_arguments_are_valueerrors(kwargs):
    with pytest.raises(ValueError):
        sweepmtf.measure(SHOT, **kwargs)


def test_bad_arrays_are_valueerrors():
    roi = [(0, 0), (10, 0), (10, 10), (0, 10)]
    for bad in (
        np.zeros((10, 10), np.int32),
        np.zeros((10, 10, 4), np.uint8),
        np.zeros((10,), np.uint8),
        np.zeros((0, 10), np.uint8),
        np.full((10, 10), np.nan, np.float32),
    ):
        with pytest.raises(ValueError):
            sweepmtf.measure(bad, roi=roi)
    with pytest.raises(ValueError):
        sweepmtf.measure(12345)
    with pytest.raises(ValueError, match="srgb"):
        sweepmtf.measure(np.zeros((10, 10), np.uint16), roi=roi, tone="srgb")


def test_region_outside_is_a_measurement_error():
    arr = sweepmtf.read_photo(SHOT)
    with pytest.raises(sweepmtf.MeasurementError, match="region"):
        sweepmtf.measure(arr, roi=[(-500, -500), (-400, -500), (-400, -400), (-500, -400)])


def test_model_and_chart_errors(tmp_path):
    with pytest.raises(ValueError, match="aperture"):
        sweepmtf.model(aperture="rect:A=-1um,B=1um")
    with pytest.raises(ValueError):
        sweepmtf.model()
    with pytest.raises(ValueError, match="unknown factor"):
        sweepmtf.model(lens="x")
    with pytest.raises(OSError):
        sweepmtf.model(system=tmp_path / "none.toml")
    m = sweepmtf.model(gaussian="sigma=2um")
    with pytest.raises(ValueError):
        m.cut("w", 100)
    with pytest.raises(ValueError):
        m.map(-1)
    with pytest.raises(ValueError):
        sweepmtf.chart(tmp_path / "c.gif", 0.5, 5)
    with pytest.raises(ValueError):
        sweepmtf.chart(tmp_path / "c.png", 5, 0.5, dpi=72)
    assert list(tmp_path.iterdir()) == []
    with pytest.raises(OSError):
        sweepmtf.chart(tmp_path / "no" / "dir" / "c.png", 0.5, 2, width_mm=60, height_mm=40, dpi=150)
    with pytest.raises(ValueError):
        sweepmtf.simulate(ROOT / "targets" / "a4_log.toml", {"width_px": -3})
    with pytest.raises(ValueError):
        sweepmtf.simulate(ROOT / "targets" / "a4_log.toml", {"no_such_setting": 1})
