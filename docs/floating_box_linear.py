#!/usr/bin/env python3
"""Linear heave period of the `floating-box-2d` box in its closed tank (numpy only).

Reference for `bisph validate floating-box-2d` (FLOAT_LINEAR_PERIOD in
crates/bisph-validate/src/rigid.rs). Linear potential flow, Lagrangian form:
generalised coordinates are the free-surface elevations eta_k of the surface cells
(the box heave Z follows from the water's volume, sum eta_k delta + B Z = 0);
- kinetic energy: rho/2 int |grad phi|^2 from the Neumann problem for phi with the
  normal velocities eta_k' on the free surface and Z' on the box bottom (finite volumes,
  cells of side delta), plus m Z'^2 / 2 for the box;
- potential energy: rho g / 2 (sum eta_k^2 delta + B Z^2) (the linear terms cancel by
  Archimedes).
The generalised eigenproblem K q = omega^2 M q gives the modes; the heave mode is the
one in which the box moves (the antisymmetric sloshing modes leave it still).

    python3 docs/floating_box_linear.py 1 2 4   # cells 0.04 x 0.05 m, halved, quartered
    # 1.3170, 1.3286, 1.3351 s; the differences shrink by 0.56 (the box corners):
    # extrapolated 1.3351 + 0.0065 * 0.56 / 0.44 = 1.343 s
"""
import sys

import numpy as np

# Settled geometry: tank width, water depth, box width, box left side, draft, box mass.
W, DEPTH, B, X0, DRAFT, MASS, RHO, G = 2.04, 0.65, 0.6, 0.72, 0.2, 120.0, 1000.0, 9.81


def modes(k):
    """Cells of 0.04 / k by 0.05 / k m (the box's sides and bottom on cell faces)."""
    dx, dy = 0.04 / k, 0.05 / k
    nx, ny = round(W / dx), round(DEPTH / dy)
    jb = round((DEPTH - DRAFT) / dy)
    i0, i1 = round(X0 / dx), round((X0 + B) / dx)
    fluid = np.ones((nx, ny), bool)
    fluid[i0:i1, jb:] = False
    index = -np.ones((nx, ny), int)
    cells = np.argwhere(fluid)
    index[fluid] = np.arange(len(cells))
    n = len(cells)
    a = np.zeros((n, n))  # minus the finite-volume Laplacian, zero flux on walls
    for c, (i, j) in enumerate(cells):
        for di, dj, t in ((1, 0, dy / dx), (-1, 0, dy / dx), (0, 1, dx / dy), (0, -1, dx / dy)):
            p, q = i + di, j + dj
            if 0 <= p < nx and 0 <= q < ny and fluid[p, q]:
                a[c, c] += t
                a[c, index[p, q]] -= t
    surface = [index[i, ny - 1] for i in range(nx) if fluid[i, ny - 1]]
    under = [index[i, jb - 1] for i in range(i0, i1)]
    # Outflow of each cell per unit eta_k': dx through the surface cell's top, and
    # Z' dx = -(dx / B) dx sum eta' through each face of the box bottom.
    flux = np.zeros((n, len(surface)))
    for m, c in enumerate(surface):
        flux[c, m] += dx
    for c in under:
        flux[c, :] -= dx * dx / B
    phi = np.linalg.solve(a + np.ones((n, n)) / n, flux)  # zero-mean potentials
    ones = np.ones((len(surface), 1))
    mass = RHO * flux.T @ phi + MASS * (dx / B) ** 2 * (ones @ ones.T)
    stiff = RHO * G * (dx * np.eye(len(surface)) + dx * dx / B * (ones @ ones.T))
    li = np.linalg.inv(np.linalg.cholesky(mass))
    w2, v = np.linalg.eigh(li @ stiff @ li.T)
    q = li.T @ v
    heave = -dx * q.sum(axis=0) / B
    return 2.0 * np.pi / np.sqrt(w2), heave / np.abs(q).max(axis=0)


if __name__ == "__main__":
    for k in [int(s) for s in sys.argv[1:]] or [1, 2]:
        periods, heave = modes(k)
        j = int(np.argmax(np.abs(heave)))
        print(f"cells {0.04 / k:.4f} x {0.05 / k:.4f} m: heave mode T = {periods[j]:.4f} s "
              f"(Z / max|eta| = {abs(heave[j]):.3f}); first modes {np.round(periods[:4], 4)}")
