"""Runs from Python: the same files as `bisph run`, bit for bit."""

from __future__ import annotations

import threading

import numpy as np
import pytest

import bisph
from conftest import DAM_BREAK, STILL_WATER, run_cli, small_case

SERIES = ["energy.csv", "probes.csv", "forces.csv", "case.toml"]


@pytest.mark.parametrize("spec", [DAM_BREAK, STILL_WATER], ids=["dam-break", "still-water"])
def test_run_writes_the_series_of_the_command_line_bit_for_bit(spec, tmp_path):
    run_cli(spec, tmp_path / "cli")
    sim = small_case(spec).build(threads=1)
    summary = sim.run(out=tmp_path / "py")
    for name in SERIES:
        cli = (tmp_path / "cli" / name).read_bytes()
        assert (tmp_path / "py" / name).read_bytes() == cli, name
    cli_summary = bisph.read_run(tmp_path / "cli").summary
    assert summary["steps"] == cli_summary["steps"] > 0
    assert summary["energy_total_final"] == cli_summary["energy_total_final"]
    assert summary["threads"] == 1
    assert (summary.get("settling") is None) == (spec is DAM_BREAK)
    assert (summary.get("settling") or {}).get("steps") == (
        cli_summary.get("settling") or {}
    ).get("steps")


def test_run_without_outputs_takes_the_same_steps(tmp_path):
    with_files = small_case().build()
    with_files.run(out=tmp_path)
    without = small_case().build()
    assert without.run() is None
    assert without.steps == with_files.steps
    assert without.time == with_files.time
    assert np.array_equal(without.positions, with_files.positions)
    assert without.energy == with_files.energy


def test_run_until_then_on_to_the_end():
    sim = small_case().build()
    sim.run(until=0.03)
    assert sim.time == pytest.approx(0.03, abs=1e-15)
    sim.run()
    assert sim.time == pytest.approx(sim.case.end, abs=1e-15)
    whole = small_case().build()
    whole.run()
    # Stopping at 0.03 shortens one step there, so the paths differ, but both reach the end.
    assert whole.time == sim.time


def test_step_advances_by_dt():
    sim = small_case().build()
    dt = sim.dt
    assert dt > 0
    sim.step()
    assert sim.time == dt and sim.steps == 1


def test_threads_do_not_change_the_results():
    one = small_case().build(threads=1)
    two = small_case().build(threads=2)
    assert (one.threads, two.threads) == (1, 2)
    for sim in (one, two):
        for _ in range(50):
            sim.step()
    assert np.array_equal(one.positions, two.positions)
    assert np.array_equal(one.density, two.density)


def test_progress_sees_every_step_and_settling():
    seen = []
    sim = small_case(STILL_WATER).build(progress=seen.append)
    assert seen and all(p.settling for p in seen)
    assert seen[-1].step == sim.settling["steps"]
    seen.clear()
    sim.run(until=0.01, progress=seen.append)
    assert [p.step for p in seen] == list(range(sim.steps + 1))
    assert not any(p.settling for p in seen)
    assert seen[-1].time == sim.time


def test_a_failing_progress_callable_stops_the_run_with_its_exception():
    sim = small_case().build()

    def fail(p: bisph.Progress) -> None:
        if p.step == 5:
            raise ValueError("enough")

    with pytest.raises(ValueError, match="enough"):
        sim.run(progress=fail)
    assert sim.steps == 5
    with pytest.raises(TypeError, match="progress"):
        sim.run(progress=42)


def test_a_simulation_running_in_a_thread_refuses_other_callers():
    sim = small_case().build()
    started, stop = threading.Event(), threading.Event()
    raised = []

    def progress(p: bisph.Progress) -> None:
        started.set()
        if stop.is_set():
            raise RuntimeError("stopped by the test")

    def run() -> None:
        try:
            sim.run(until=1e6, progress=progress)
        except RuntimeError as e:
            raised.append(str(e))

    worker = threading.Thread(target=run)
    worker.start()
    assert started.wait(30)
    for call in (lambda: sim.time, lambda: sim.element_pressures, sim.step):
        with pytest.raises(RuntimeError, match="lready"):
            call()
    stop.set()
    worker.join(30)
    assert raised == ["stopped by the test"]
    sim.step()  # usable again
