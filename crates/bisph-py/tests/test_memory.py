"""Stepping and reading arrays keep memory flat."""

from __future__ import annotations

import os

from conftest import small_case


def resident_bytes() -> int:
    """Resident set size of this process, from /proc/self/statm."""
    with open("/proc/self/statm") as f:
        pages = int(f.read().split()[1])
    return pages * os.sysconf("SC_PAGE_SIZE")


def test_no_memory_growth_over_1000_steps():
    sim = small_case().build()
    per_step = 0
    for _ in range(100):  # warm up: scratch buffers, neighbour lists, allocator pools
        sim.step()
    before = resident_bytes()
    for _ in range(1000):
        sim.step()
        arrays = [sim.positions, sim.velocities, sim.density, sim.pressure, sim.element_pressures]
        per_step = sum(a.nbytes for a in arrays)
        _ = sim.energy, sim.probes, sim.bodies
    grown = resident_bytes() - before
    # A leak of the arrays read at each step alone would add 1000 * per_step (about 15 MB).
    assert per_step * 1000 > 10 * 2**20
    assert grown < 2**20, f"resident memory grew by {grown} bytes over 1000 steps"
