"""Wall time of `Simulation.run` from Python against `bisph run` on the same case.

Runs the two alternately (CLI, Python, CLI, Python, ...) so that a slow spell of the machine
affects both, each into a fresh output folder, and prints every pair and the medians of

- the whole run: the `bisph run` process against `Case.build()` + `Simulation.run(out=...)`
  in this process (both build, run and write the same files);
- the time loop alone: `wall_seconds` of the two `summary.json` files.

Usage (the built-in dam break, `cases/dam-break-2d.toml`, by default):

    python crates/bisph-py/bench/run_vs_cli.py --repeat 3 [--case FILE] [--threads N]
"""

from __future__ import annotations

import argparse
import json
import os
import statistics
import subprocess
import tempfile
import time
from pathlib import Path
from typing import Dict, List

import bisph

ROOT = Path(__file__).resolve().parents[3]


def cli_run(binary: str, case: str, out: Path, threads: int) -> float:
    """Seconds of wall time of one `bisph run` process."""
    args = [binary, "run", case, "--out", str(out), "--quiet", "--threads", str(threads)]
    start = time.perf_counter()
    subprocess.run(args, check=True, capture_output=True)
    return time.perf_counter() - start


def python_run(case: str, out: Path, threads: int) -> float:
    """Seconds of wall time of building and running the case from Python."""
    start = time.perf_counter()
    bisph.Case.from_toml(case).build(threads=threads).run(out=out)
    return time.perf_counter() - start


def loop_seconds(out: Path) -> float:
    """The time loop's wall seconds, from the run's `summary.json`."""
    return float(json.loads((out / "summary.json").read_text())["wall_seconds"])


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--case", default=str(ROOT / "cases" / "dam-break-2d.toml"))
    parser.add_argument("--repeat", type=int, default=3)
    parser.add_argument("--threads", type=int, default=os.cpu_count())
    parser.add_argument("--bin", default=str(ROOT / "target" / "release" / "bisph"))
    args = parser.parse_args()
    whole: Dict[str, List[float]] = {"cli": [], "python": []}
    loop: Dict[str, List[float]] = {"cli": [], "python": []}
    with tempfile.TemporaryDirectory() as tmp:
        for k in range(args.repeat):
            for who in ("cli", "python"):
                out = Path(tmp) / f"{who}-{k}"
                if who == "cli":
                    seconds = cli_run(args.bin, args.case, out, args.threads)
                else:
                    seconds = python_run(args.case, out, args.threads)
                whole[who].append(seconds)
                loop[who].append(loop_seconds(out))
            print(
                f"pair {k + 1}: whole run cli {whole['cli'][-1]:.2f} s, python "
                f"{whole['python'][-1]:.2f} s; time loop cli {loop['cli'][-1]:.2f} s, "
                f"python {loop['python'][-1]:.2f} s",
                flush=True,
            )
    for name, values in (("whole run", whole), ("time loop", loop)):
        cli, py = statistics.median(values["cli"]), statistics.median(values["python"])
        print(f"median {name}: cli {cli:.2f} s, python {py:.2f} s, python/cli {py / cli:.4f}")


if __name__ == "__main__":
    main()
