"""The Shepard factor and BIPI packing as arrays; reading a run's folder."""

from __future__ import annotations

import numpy as np
import pytest

import bisph
from bisph import _runs
from conftest import CASES, DAM_BREAK, STILL_WATER, run_cli, small_case


def test_shepard_of_the_walls():
    case = small_case(STILL_WATER)
    points = np.array([[0.5, 0.0], [0.0, 0.0], [0.5, 0.3]])
    gamma = bisph.shepard(case, points)
    assert gamma.shape == (3,) and gamma.dtype == np.float64
    # Half the support on a flat wall, a quarter in a right-angled corner, 1 inside.
    assert gamma == pytest.approx([0.5, 0.25, 1.0], abs=1e-12)
    discrete = bisph.shepard(case, points[2:], method="discrete")
    assert discrete[0] == pytest.approx(1.0, abs=0.05)
    with pytest.raises(ValueError, match="method"):
        bisph.shepard(case, points, method="exact")
    with pytest.raises(ValueError, match=r"shape \(k, 2\)"):
        bisph.shepard(case, np.zeros((2, 3)))


def test_pack_returns_the_packed_particles():
    case = bisph.Case.from_toml(CASES / "pack-trapezoid-2d.toml")
    case.set("resolution.dx", 0.1)
    (block,) = bisph.pack(case)
    n = len(block["frozen"])
    assert n > 50 and block["block"] == 0 and block["iterations"] > 0
    assert block["positions"].shape == block["lattice"].shape == (n, 2)
    assert block["frozen"].dtype == np.bool_
    assert not np.array_equal(block["positions"], block["lattice"])  # relaxed
    assert (block["wall_distance"] > 0).all()  # every particle inside the trapezoid [m]


def test_read_run_reads_a_command_line_run(tmp_path):
    pytest.importorskip("pandas")
    run_cli(DAM_BREAK, tmp_path)
    run = bisph.read_run(tmp_path)
    assert list(run.energy.columns)[:6] == [
        "t", "kinetic", "compressible", "potential", "wall_work", "total",
    ]
    assert run.energy["t"].iloc[-1] == pytest.approx(0.1)
    assert list(run.probes.columns) == ["t", "P1", "P2", "P3", "P4"]
    assert set(run.forces["body"]) == {"walls"}
    assert run.summary["steps"] > 0 and run.settling is None
    assert len(run.fluid) == len(run.fluid.times) == 6  # every 0.02 s from 0 to 0.1
    frame = run.fluid.frame(len(run.fluid) - 1)
    n = run.summary["fluid_particles"]
    assert frame["points"].shape == (n, 3) and frame["pressure"].shape == (n,)
    walls = run.walls.frame(0)
    assert walls["cell_normal"].shape == (run.summary["boundary_elements"], 3)


def test_read_run_without_pandas_gives_dicts_of_arrays(tmp_path, monkeypatch):
    run_cli(DAM_BREAK, tmp_path)
    monkeypatch.setattr(_runs, "_pandas", None)
    run = bisph.read_run(tmp_path)
    assert isinstance(run.energy, dict)
    assert run.energy["total"].dtype == np.float64
    assert run.forces["body"][0] == "walls"
    with pytest.raises(FileNotFoundError):
        bisph.read_run(tmp_path / "nothing")
