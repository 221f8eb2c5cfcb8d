"""KeyboardInterrupt stops a run between steps and leaves the simulation usable; it stops
settling and packing too."""

from __future__ import annotations

import _thread
import signal
import threading
import time

import pytest

import bisph
from conftest import CASES, STILL_WATER, small_case


#: Steps after which a run that was not interrupted fails the test instead of running on.
TOO_MANY = 5000


@pytest.fixture(autouse=True)
def sigint_raises():
    """Python's own SIGINT handler, which raises KeyboardInterrupt (a process started in the
    background may inherit SIGINT ignored, and then ``interrupt_main`` does nothing)."""
    previous = signal.signal(signal.SIGINT, signal.default_int_handler)
    yield
    signal.signal(signal.SIGINT, previous)


def interrupt_at(step: int):
    """A progress callable that interrupts the main thread once at ``step``."""

    def progress(p: bisph.Progress) -> None:
        if p.step == step:
            _thread.interrupt_main()
        if p.step > TOO_MANY:
            raise AssertionError("the interrupt did not stop the run")

    return progress


def test_keyboard_interrupt_stops_a_long_run_and_the_simulation_goes_on():
    sim = small_case().build()
    with pytest.raises(KeyboardInterrupt):
        sim.run(until=1e6, progress=interrupt_at(20))
    stopped_at = sim.steps
    assert 20 <= stopped_at < TOO_MANY
    assert 0 < sim.time < 1e6
    sim.step()
    assert sim.steps == stopped_at + 1
    sim.run(until=sim.time + 10 * sim.dt)
    assert sim.steps > stopped_at + 1
    assert all(abs(v) < 1e9 for v in sim.energy.values())


def test_keyboard_interrupt_with_outputs_leaves_a_checkpoint(tmp_path):
    sim = small_case().build()
    with pytest.raises(KeyboardInterrupt):
        sim.run(until=1e6, out=tmp_path, progress=interrupt_at(20))
    assert (tmp_path / "checkpoint.bin").is_file()
    assert "interrupted" in bisph.read_run(tmp_path).summary["stopped"]
    steps = sim.steps
    sim.run(until=sim.time + 5 * sim.dt, out=tmp_path / "after")
    assert sim.steps > steps


def test_keyboard_interrupt_stops_settling_and_build_raises():
    seen = []

    def progress(p: bisph.Progress) -> None:
        seen.append(p)
        if p.step == 5:
            _thread.interrupt_main()

    with pytest.raises(KeyboardInterrupt):
        small_case(STILL_WATER).build(progress=progress)
    assert all(p.settling for p in seen)
    assert 5 <= seen[-1].step < 20  # settling alone takes hundreds of steps


def test_keyboard_interrupt_stops_packing():
    case = bisph.Case.from_toml(str(CASES / "pack-trapezoid-2d.toml"))
    case.set("resolution.dx", 0.025)
    start = time.perf_counter()
    bisph.pack(case)
    whole = time.perf_counter() - start
    timer = threading.Timer(0.05 * whole, _thread.interrupt_main)
    start = time.perf_counter()
    timer.start()
    with pytest.raises(KeyboardInterrupt):
        bisph.pack(case)
    # Stopped after the iteration in progress, not at the end of the block.
    assert time.perf_counter() - start < 0.5 * whole
