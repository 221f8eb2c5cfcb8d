"""The state as NumPy arrays: shapes, dtypes, units, views and copies."""

from __future__ import annotations

import numpy as np
import pytest

import bisph
from conftest import STILL_WATER, small_case

G, RHO0, DEPTH = 9.81, 1000.0, 0.5
#: Sound speed of cases/hydrostatic-2d.toml [m/s].
C0 = 22.15


@pytest.fixture(scope="module")
def tank():
    """The still-water tank (1 m x 0.5 m of water, dx = 0.05) after settling."""
    return small_case(STILL_WATER).build()


def test_particle_arrays_have_their_shapes_dtypes_and_units(tank):
    n = tank.n_particles
    for name in ("positions", "velocities", "accelerations"):
        a = getattr(tank, name)
        assert a.shape == (n, 2) and a.dtype == np.float64, name
    for name in ("density", "pressure", "mass", "gamma"):
        a = getattr(tank, name)
        assert a.shape == (n,) and a.dtype == np.float64, name
    x, y = tank.positions.T
    assert 0 < x.min() and x.max() < 1 and 0 < y.min() and y.max() < DEPTH + 0.05  # m
    assert np.allclose(tank.density, RHO0, rtol=0.02)  # kg/m^3
    # kg per m depth: the lattice's cells times the initial (hydrostatic, linear equation of
    # state) density rho0 (1 + g d / c0^2), whose mean over the depth is exact on the rows.
    mass = RHO0 * 1.0 * DEPTH * (1.0 + G * DEPTH / (2.0 * C0**2))
    assert tank.mass.sum() == pytest.approx(mass, rel=1e-9)
    # Hydrostatic pressure [Pa]: rho g (H - y) up to the particle spacing.
    assert np.allclose(tank.pressure, RHO0 * G * (DEPTH - y), atol=RHO0 * G * 0.05)
    assert np.abs(tank.velocities).max() < 0.01 * np.sqrt(G * DEPTH)  # m/s, settled


def test_element_arrays_have_their_shapes_dtypes_and_units(tank):
    m = tank.n_elements
    for name in ("element_centres", "element_normals", "element_velocities"):
        a = getattr(tank, name)
        assert a.shape == (m, 2) and a.dtype == np.float64, name
    assert tank.element_areas.shape == (m,)
    assert tank.element_bodies.dtype == np.uint32
    assert np.allclose(np.linalg.norm(tank.element_normals, axis=1), 1.0)
    # The box without a lid: a bottom 1 m and two sides 0.8 m high [m].
    assert tank.element_areas.sum() == pytest.approx(2.6, rel=1e-12)
    bottom = tank.element_centres[:, 1] == 0.0
    assert np.all(tank.element_normals[bottom] == [0.0, -1.0])  # out of the fluid
    assert tank.probes["bottom"] == pytest.approx(RHO0 * G * DEPTH, rel=0.1)  # Pa
    assert tank.element_pressures[bottom].mean() == pytest.approx(RHO0 * G * DEPTH, rel=0.1)


def test_element_arrays_are_read_only_live_views_and_particle_arrays_copies():
    sim = small_case().build()
    pressures = sim.element_pressures
    assert not pressures.flags.writeable
    assert isinstance(pressures.base, bisph.Simulation)  # a view of the solver's buffer
    with pytest.raises(ValueError):
        pressures[0] = 1.0
    before = pressures.copy()
    positions = sim.positions
    assert positions.flags.writeable
    assert not np.shares_memory(positions, sim.positions)  # a fresh copy at each read
    positions[:] = 0.0  # a copy: the simulation is not touched
    for _ in range(20):
        sim.step()
    assert not np.array_equal(pressures, before)  # the view shows the new values
    assert np.array_equal(pressures, sim.element_pressures)
    assert sim.positions.any()
    del sim  # the view keeps its simulation alive
    assert np.isfinite(pressures).all()


def test_particle_arrays_keep_the_particle_order_while_the_solver_reorders():
    sim = small_case().build()
    start = sim.positions
    for _ in range(100):
        sim.step()
    moved = np.linalg.norm(sim.positions - start, axis=1)
    # 100 steps of about 2e-4 s at under 2 m/s: each particle moves well under dx = 0.02 m.
    assert moved.max() < 0.02


#: The dam break's water thrown up out of its open tank: about a fifth of it leaves the domain
#: by t = 0.25 s.
SPLASH = (
    "dam-break-2d.toml",
    [
        "resolution.dx=0.02",
        'wall.0.open=["+y"]',
        "fluid_block.0.velocity=[0.0, 4.0]",
        "diagnostics.removed_fraction_max=0.5",
    ],
)


def test_particles_that_leave_the_domain_are_removed_and_their_ids_skipped():
    sim = small_case(SPLASH).build()
    n = sim.n_particles
    assert sim.ids.dtype == np.uint32
    assert np.array_equal(sim.ids, np.arange(n))
    sim.run(until=0.25)
    ids = sim.ids
    assert 0 < len(ids) < n and sim.n_particles == len(ids)
    assert np.all(np.diff(ids.astype(np.int64)) > 0)  # increasing, no repeats
    assert sim.positions.shape == (len(ids), 2) and sim.mass.shape == (len(ids),)
    e = sim.energy
    assert e["removed"] > 0.0


def test_energy_bodies_and_probes():
    sim = small_case().build()
    e = sim.energy
    assert set(e) == {
        "kinetic", "compressible", "potential", "wall_work", "total",
        "viscous_dissipation", "forcing_work", "diffusion_dissipation", "removed",
    }
    parts = e["kinetic"] + e["compressible"] + e["potential"] + e["wall_work"]
    dissipated = e["viscous_dissipation"] + e["diffusion_dissipation"] + e["removed"]
    assert e["total"] == pytest.approx(parts + dissipated - e["forcing_work"])
    assert e["kinetic"] == 0.0
    sim.run(until=0.05)
    assert sim.energy["kinetic"] > 0  # J per m depth: the column has started to fall
    assert list(sim.probes) == ["P1", "P2", "P3", "P4"]
    (walls,) = sim.bodies
    assert walls["motion"] == "fixed" and walls["force"].shape == (2,)
    assert walls["force"][1] < 0  # the water pushes the floor down [N/m]
