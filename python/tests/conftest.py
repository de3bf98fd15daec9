"""Shared fixtures: the repository's example data and the psdcal binary."""

import os
import pathlib
import shutil
import subprocess

import pytest

ROOT = pathlib.Path(__file__).resolve().parents[2]
EXAMPLE = ROOT / "data" / "example"


@pytest.fixture(scope="session")
def example():
    return EXAMPLE


@pytest.fixture(scope="session")
def cli():
    """The psdcal command: $PSDCAL_BIN, else the release build in the
    target folder, else `cargo run --release --bin psdcal`."""
    given = os.environ.get("PSDCAL_BIN")
    if given:
        return [given]
    target = pathlib.Path(os.environ.get("CARGO_TARGET_DIR", ROOT / "target"))
    built = target / "release" / "psdcal"
    if built.exists():
        return [str(built)]
    cargo = shutil.which("cargo")
    if cargo is None:
        pytest.skip("no psdcal binary and no cargo to build one")
    subprocess.run([cargo, "build", "--release", "--bin", "psdcal"], cwd=ROOT, check=True)
    return [str(built)]
