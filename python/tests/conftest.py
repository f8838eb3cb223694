"""Shared paths: the repository root, its test data, and the CLI binary to compare with."""

import os
import pathlib
import shutil

import pytest

ROOT = pathlib.Path(__file__).resolve().parents[2]
SHOT = ROOT / "testdata" / "a4_log_shot.jpg"
TARGET = ROOT / "targets" / "a4_log.toml"


def cli_binary():
    """The `sweepmtf` CLI: $SWEEPMTF_BIN, else target/{release,debug}/sweepmtf, else PATH."""
    env = os.environ.get("SWEEPMTF_BIN")
    if env:
        return env
    for profile in ("debug", "release"):
        p = ROOT / "target" / profile / "sweepmtf"
        if p.exists():
            return str(p)
    return shutil.which("sweepmtf")


@pytest.fixture(scope="session")
def cli():
    b = cli_binary()
    if b is None:
        if os.environ.get("CI"):
            pytest.fail("no sweepmtf CLI binary to compare with (set SWEEPMTF_BIN)")
        pytest.skip("no sweepmtf CLI binary (build it with cargo build or set SWEEPMTF_BIN)")
    return b
