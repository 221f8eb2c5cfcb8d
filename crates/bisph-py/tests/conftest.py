"""Shared fixtures: the repository's cases, the command-line binary, small cases."""

from __future__ import annotations

import os
import shutil
import subprocess
from pathlib import Path
from typing import List

import pytest

import bisph

ROOT = Path(__file__).resolve().parents[3]
CASES = ROOT / "cases"

#: A dam break small enough for tests: 450 particles, 0.1 s (about 430 steps).
DAM_BREAK = ("dam-break-2d.toml", ["resolution.dx=0.02", "time.end=0.1"])
#: A still-water tank that settles before t = 0: 200 particles, 0.05 s.
STILL_WATER = ("hydrostatic-2d.toml", ["resolution.dx=0.05", "time.end=0.05"])


def small_case(spec=DAM_BREAK) -> bisph.Case:
    """One of the small cases above, with its overrides set as ``--set`` would."""
    name, overrides = spec
    case = bisph.Case.from_toml(str(CASES / name))
    for item in overrides:
        key, value = item.split("=", 1)
        case.set(key, value)
    return case


def cli() -> Path:
    """The ``bisph`` binary: ``$BISPH_BIN``, the repository's release build, or ``bisph`` on
    the PATH."""
    candidates = [os.environ.get("BISPH_BIN"), ROOT / "target" / "release" / "bisph"]
    for c in candidates:
        if c and Path(c).is_file():
            return Path(c)
    found = shutil.which("bisph")
    if found is None:
        pytest.fail("no bisph binary: build it (cargo build --release) or set BISPH_BIN")
    return Path(found)


def run_cli(spec, out: Path, extra: List[str] = ()) -> None:
    """``bisph run`` on a small case into ``out``."""
    name, overrides = spec
    args = [str(cli()), "run", str(CASES / name), "--out", str(out), "--quiet"]
    for item in overrides:
        args += ["--set", item]
    subprocess.run(args + list(extra), check=True, capture_output=True)
