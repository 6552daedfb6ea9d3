"""Shared fixtures: the repository's scenes and the `lpc` binary the CLI comparisons run.

`LPC_BIN` names the binary (`test.sh` passes the Rust tests' own); without it, the release
build, built here if missing.
"""

from __future__ import annotations

import os
import subprocess
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[2]
SCENES = ROOT / "scenes"


@pytest.fixture(scope="session")
def lpc_bin() -> Path:
    path = Path(os.environ.get("LPC_BIN", ROOT / "target" / "release" / "lpc"))
    if not path.exists():
        subprocess.run(["cargo", "build", "--release", "--locked", "--bin", "lpc"], cwd=ROOT, check=True)
    return path


@pytest.fixture(scope="session")
def scenes() -> Path:
    return SCENES
