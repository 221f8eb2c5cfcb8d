#!/usr/bin/env python3
"""Sensor S2 (15 mm) of a Lobovsky dam-break run against the experiment's percentile series.

Reads `probes.csv` of one or more `bisph run cases/lobovsky-dam-break.toml` output folders and
the 2.5% / median / 97.5% time series of the ~100 repeated experiments
(`../shared/data/lobovsky-dambreak/aquagpusph/Fig31_Wemmenhove_sensor2_compared_graph.csv`,
see PROVENANCE.md there), and plots p / (rho g H) against t sqrt(g/H) over the first impact,
raw and averaged over t* = 0.05 (the window of `bisph validate`'s peak check). Needs numpy and
matplotlib (not used by the tests or CI).

    python3 docs/lobovsky_s2.py docs/lobovsky_s2_h200.png out/lobovsky-h200:H/200 out/lobovsky-h100:H/100
"""
import csv
import math
import sys
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

H, G, RHO = 0.3, 9.81, 997.0
T_STAR = math.sqrt(G / H)
WINDOW = 0.05  # in t*
EXPERIMENT = (
    Path(__file__).resolve().parents[2]
    / "shared/data/lobovsky-dambreak/aquagpusph/Fig31_Wemmenhove_sensor2_compared_graph.csv"
)


def sensor(folder):
    """t* and p* of S2 in `folder/probes.csv`."""
    with open(Path(folder) / "probes.csv") as f:
        rows = list(csv.DictReader(f))
    t = np.array([float(r["t"]) for r in rows]) * T_STAR
    p = np.array([float(r["S2"]) for r in rows]) / (RHO * G * H)
    return t, p


def centred_average(t, p, window):
    """Mean of p over [t - window/2, t + window/2] at every sample."""
    c = np.concatenate([[0.0], np.cumsum(p)])
    lo = np.searchsorted(t, t - window / 2, side="left")
    hi = np.searchsorted(t, t + window / 2, side="right")
    return (c[hi] - c[lo]) / (hi - lo)


def main(argv):
    if len(argv) < 3:
        sys.exit(__doc__)
    png, runs = argv[1], argv[2:]
    e = np.loadtxt(EXPERIMENT, delimiter=",", skiprows=1)
    fig, ax = plt.subplots(figsize=(10, 5.5))
    ax.fill_between(e[:, 0], e[:, 1], e[:, 3], color="0.85", label="experiment 2.5-97.5%")
    ax.plot(e[:, 0], e[:, 2], color="k", lw=1.2, label="experiment median")
    for run in runs:
        folder, _, label = run.partition(":")
        t, p = sensor(folder)
        avg = centred_average(t, p, WINDOW)
        line = ax.plot(t, p, lw=0.3, alpha=0.25)[0]
        ax.plot(t, avg, lw=1.6, color=line.get_color(), label=f"bisph {label or folder} (t*-average 0.05)")
        first = (t >= 1.8) & (t <= 3.5)
        k = np.argmax(np.where(first, avg, -np.inf))
        print(f"{label or folder}: S2 first peak {avg[k]:.3f} at t* {t[k]:.3f} (averaged), raw max {p[first].max():.3f}")
    ax.set_xlim(1.5, 8.0)
    ax.set_ylim(-0.3, 3.0)
    ax.set_xlabel("t sqrt(g/H)")
    ax.set_ylabel("p / (rho g H)")
    ax.set_title("Lobovsky dam break, sensor S2 (z = 15 mm)")
    ax.legend(loc="upper right", fontsize=8)
    fig.tight_layout()
    fig.savefig(png, dpi=110)


if __name__ == "__main__":
    main(sys.argv)
