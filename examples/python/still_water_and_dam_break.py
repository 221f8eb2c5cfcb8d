"""A still-water tank and a dam break from Python: build, run, plot the energy budget and a
pressure probe, and write one PNG per case.

The resolutions here are coarse (dx = H/10 for the tank, H/15 for the dam break) so that the
script finishes in seconds, as CI runs it; pass --fine for the case files' own resolutions
(minutes). Usage:

    python examples/python/still_water_and_dam_break.py --out out/python-example
"""

from __future__ import annotations

import argparse
from pathlib import Path

import matplotlib

matplotlib.use("Agg")  # files only, no display
import matplotlib.pyplot as plt  # noqa: E402

import bisph  # noqa: E402

CASES = Path(__file__).resolve().parents[2] / "cases"

#: (case file, probe to plot, coarse overrides); the fine runs keep the files' values.
STUDIES = [
    ("hydrostatic-2d.toml", "bottom", {"resolution.dx": 0.05, "time.end": 1.0}),
    ("dam-break-2d.toml", "P1", {"resolution.dx": 0.02, "time.end": 0.6}),
]


def run_case(file: str, fine: bool, out: Path) -> bisph.Run:
    """Builds the case (settling still water first), runs it to its end writing the
    command line's outputs into ``out``, and reads them back."""
    case = bisph.Case.from_toml(CASES / file)
    if not fine:
        for key, value in STUDIES[[s[0] for s in STUDIES].index(file)][2].items():
            case.set(key, value)
    sim = case.build()
    if sim.settling is not None:
        print(f"{case.name}: settled in {sim.settling['steps']} steps before t = 0")
    summary = sim.run(out=out)
    print(
        f"{case.name}: {sim.n_particles} particles, {summary['steps']} steps in "
        f"{summary['wall_seconds']:.1f} s, energy drift {summary['energy_drift_relative']:.2e}"
    )
    return bisph.read_run(out)


def plot(run: bisph.Run, probe: str, png: Path) -> None:
    """The energy budget (changes from the start) and one pressure probe against time."""
    e, probes = run.energy, run.probes
    assert probes is not None, "the case has probes"
    t = e["t"]
    fig, (left, right) = plt.subplots(1, 2, figsize=(11, 4), constrained_layout=True)
    names = ["kinetic", "compressible", "potential", "wall_work", "viscous_dissipation", "total"]
    for name in names:
        left.plot(t, e[name] - e[name][0], label=name)
    left.set(xlabel="t [s]", ylabel="energy change [J/m]", title="Energy budget")
    left.legend()
    right.plot(probes["t"], probes[probe] / 1000.0)
    right.set(xlabel="t [s]", ylabel="pressure [kPa]", title=f"Probe {probe}")
    fig.suptitle(run.summary["case"])
    fig.savefig(png, dpi=100)
    plt.close(fig)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--out", type=Path, default=Path("out/python-example"))
    parser.add_argument("--fine", action="store_true", help="the case files' resolutions")
    args = parser.parse_args()
    for file, probe, _ in STUDIES:
        name = Path(file).stem
        run = run_case(file, args.fine, args.out / name)
        png = args.out / f"{name}.png"
        plot(run, probe, png)
        print(f"wrote {png}")


if __name__ == "__main__":
    main()
