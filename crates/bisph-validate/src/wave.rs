//! The scalar wave equation on fixed particles in 1-D with Robin walls at both ends (paper 3,
//! section 6.2): the stand-alone check of the Robin wall condition ([`bisph_core::walls::robin`]).
//!
//! `d2u/dt2 = Lap(u)` (eq 75) on particles at `x_a = (a + 1/2) dx` in `[x_0, x_1]`; the
//! Laplacian is eq 18 with `f = 1`:
//! `Lap_a = (1/gamma_a) [sum_b V_b 2 (u_a - u_b) F_ab - 2 sum_s (du/dn)_s W_as]`,
//! `grad W(r) = F r`, `gamma_a = int W` over the segment (Gauss-Legendre), `grad gamma_as =
//! n_s W_as` in 1-D, `n_s` into the fluid. The wall derivative comes from the Robin condition
//! and the wall value of eq 74: `(du/dn)_s = (mu3 - mu1 beta_1) / mu2`. Time: central second
//! differences, `u^{n+1} = 2 u^n - u^{n-1} + dt^2 Lap(u^n)`, started with the Taylor step
//! `u^1 = u^0 + dt v^0 + dt^2/2 Lap(u^0)`.

use bisph_core::kernel::Wendland;
use bisph_core::quadrature::gauss_legendre;
use bisph_core::walls::robin::{wall_value, RobinCondition, RobinSample};
use glam::DVec2;

/// One end of the segment.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct WaveWall {
    /// Position of the end.
    pub position: f64,
    /// Unit normal into the fluid (`+1` at the left end, `-1` at the right end).
    pub normal: f64,
    /// The condition `mu1 u + mu2 du/dn = mu3`.
    pub condition: RobinCondition,
}

/// The 1-D wave solver on fixed particles.
#[derive(Clone, Debug)]
pub struct Wave1d {
    /// Particle positions.
    pub x: Vec<f64>,
    /// `u^n`.
    pub u: Vec<f64>,
    u_previous: Vec<f64>,
    /// Particle spacing (the volume of each particle).
    pub dx: f64,
    /// The 1-D kernel.
    pub kernel: Wendland,
    /// `gamma_a`.
    pub gamma: Vec<f64>,
    /// The two ends.
    pub walls: [WaveWall; 2],
    /// Order `m` of the Robin fit (eq 66).
    pub order: usize,
    /// Time step.
    pub dt: f64,
    /// Current time.
    pub time: f64,
    /// Fluid neighbours of each particle: `(b, F_ab)`.
    neighbours: Vec<Vec<(usize, f64)>>,
    /// Particles seen by each wall: `(a, W_as, F_as)`.
    wall_neighbours: [Vec<(usize, f64, f64)>; 2],
    /// Volume of the vertex particle at each end (0: no vertex particles).
    pub vertex_volume: f64,
}

/// Where the particles sit.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum WaveLayout {
    /// Fluid particles at `(a + 1/2) dx`; the walls enter through the boundary term only.
    Staggered,
    /// Fluid particles at `a dx`, `0 < a < n`, and a vertex particle of volume `dx/2` on each
    /// wall carrying the wall value `beta_1` in the particle sum of eq 18 (the semi-analytical
    /// layout of paper 3).
    Vertex,
}

impl Wave1d {
    /// Particles of spacing `length / n` in `[x0, x0 + length]`, `h = h_over_dx dx`, at rest
    /// with `u = u0(x)` and `du/dt = v0(x)`.
    #[allow(clippy::too_many_arguments)]
    pub fn new(
        x0: f64,
        length: f64,
        n: usize,
        layout: WaveLayout,
        h_over_dx: f64,
        conditions: [RobinCondition; 2],
        order: usize,
        dt: f64,
        u0: impl Fn(f64) -> f64,
        v0: impl Fn(f64) -> f64,
    ) -> Self {
        let dx = length / n as f64;
        let kernel = Wendland::new(h_over_dx * dx, 1);
        let (x, vertex_volume): (Vec<f64>, f64) = match layout {
            WaveLayout::Staggered => ((0..n).map(|a| x0 + (a as f64 + 0.5) * dx).collect(), 0.0),
            WaveLayout::Vertex => ((1..n).map(|a| x0 + a as f64 * dx).collect(), 0.5 * dx),
        };
        let support = kernel.support;
        let neighbours = x
            .iter()
            .map(|&xa| {
                x.iter()
                    .enumerate()
                    .filter(|&(_, &xb)| (xb - xa).abs() < support)
                    .map(|(b, &xb)| (b, kernel.gradient_factor((xb - xa).abs())))
                    .collect()
            })
            .collect();
        let x1 = x0 + length;
        let gamma = x
            .iter()
            .map(|&xa| {
                let (lo, hi) = ((xa - support).max(x0), (xa + support).min(x1));
                let w = |s: f64| kernel.value((s - xa).abs());
                gauss_legendre(lo, xa, 4, w) + gauss_legendre(xa, hi, 4, w)
            })
            .collect();
        let walls = [
            WaveWall {
                position: x0,
                normal: 1.0,
                condition: conditions[0],
            },
            WaveWall {
                position: x1,
                normal: -1.0,
                condition: conditions[1],
            },
        ];
        let wall_neighbours = walls.map(|w| {
            x.iter()
                .enumerate()
                .filter(|&(_, &xa)| (xa - w.position).abs() < support)
                .map(|(a, &xa)| {
                    let r = (xa - w.position).abs();
                    (a, kernel.value(r), kernel.gradient_factor(r))
                })
                .collect()
        });
        let u: Vec<f64> = x.iter().map(|&xa| u0(xa)).collect();
        let mut solver = Wave1d {
            u_previous: u.clone(),
            u,
            x,
            dx,
            kernel,
            gamma,
            walls,
            order,
            dt,
            time: 0.0,
            neighbours,
            wall_neighbours,
            vertex_volume,
        };
        // u^{-1} such that the central step gives u^1 = u^0 + dt v0 + dt^2/2 Lap(u^0).
        let lap = solver.laplacian(&solver.u);
        for (a, l) in lap.iter().enumerate() {
            let v = v0(solver.x[a]);
            solver.u_previous[a] = solver.u[a] - dt * v + 0.5 * dt * dt * l;
        }
        solver
    }

    /// The wall values `beta_1` of both ends for the field `u` (eq 74), `NaN` where the fit
    /// is singular.
    pub fn wall_values(&self, u: &[f64]) -> [f64; 2] {
        let mut values = [0.0; 2];
        for (s, wall) in self.walls.iter().enumerate() {
            let samples = self.wall_neighbours[s]
                .iter()
                .map(|&(a, w, _)| RobinSample {
                    offset: DVec2::new(self.x[a] - wall.position, 0.0),
                    value: u[a],
                    weight: self.dx * w,
                });
            values[s] = wall_value(
                &wall.condition,
                self.order,
                DVec2::new(wall.normal, 0.0),
                samples,
            )
            .unwrap_or(f64::NAN);
        }
        values
    }

    /// `Lap(u)` at every particle (eq 18 with the Robin wall flux).
    pub fn laplacian(&self, u: &[f64]) -> Vec<f64> {
        let beta = self.wall_values(u);
        let mut lap: Vec<f64> = (0..self.x.len())
            .map(|a| {
                self.neighbours[a]
                    .iter()
                    .map(|&(b, f)| 2.0 * self.dx * (u[a] - u[b]) * f)
                    .sum::<f64>()
            })
            .collect();
        for (s, wall) in self.walls.iter().enumerate() {
            let flux = wall.condition.normal_derivative(beta[s]);
            for &(a, w, f) in &self.wall_neighbours[s] {
                lap[a] += 2.0 * self.vertex_volume * (u[a] - beta[s]) * f - 2.0 * flux * w;
            }
        }
        for (l, g) in lap.iter_mut().zip(&self.gamma) {
            *l /= g;
        }
        lap
    }

    /// One central-difference step.
    #[allow(clippy::needless_range_loop)]
    pub fn step(&mut self) {
        let lap = self.laplacian(&self.u);
        let dt2 = self.dt * self.dt;
        for a in 0..self.u.len() {
            let next = 2.0 * self.u[a] - self.u_previous[a] + dt2 * lap[a];
            self.u_previous[a] = self.u[a];
            self.u[a] = next;
        }
        self.time += self.dt;
    }
}

/// The modal solution of `u_tt = u_xx` on `[0, 1]` with `du/dn = u` (`n` into the domain) at
/// both ends, `u(x, 0) = 0`, `u_t(x, 0) = sin(2 pi x)` (paper 3 eqs 76-79):
/// `u = sum_i alpha_i sin(kappa_i t) X_i(x)`, `X_i = sin(kappa_i x) + kappa_i cos(kappa_i x)`,
/// `tan kappa_i = 2 kappa_i / (kappa_i^2 - 1)` (one root in each `(n pi, (n+1) pi)`),
/// `alpha_i = <sin 2 pi x, X_i> / (kappa_i ||X_i||^2)`, `||X_i||^2 = (kappa_i^2 + 1)/2 + 1`,
/// `<sin 2 pi x, X_i> = a / (a^2 - kappa_i^2) [kappa_i (1 - cos kappa_i) - sin kappa_i]`,
/// `a = 2 pi` (derivation: `shared/data/robin-wave/PROVENANCE.md`).
#[derive(Clone, Debug)]
pub struct RobinWaveSeries {
    /// `kappa_i`.
    pub kappa: Vec<f64>,
    /// `alpha_i`.
    pub alpha: Vec<f64>,
}

impl RobinWaveSeries {
    /// The first `modes` terms.
    pub fn new(modes: usize) -> Self {
        let a = 2.0 * std::f64::consts::PI;
        let g = |k: f64| (k * k - 1.0) * k.sin() - 2.0 * k * k.cos();
        let mut kappa = Vec::with_capacity(modes);
        let mut alpha = Vec::with_capacity(modes);
        for n in 0..modes {
            let (mut lo, mut hi) = (
                n as f64 * std::f64::consts::PI + 1e-12,
                (n + 1) as f64 * std::f64::consts::PI - 1e-12,
            );
            for _ in 0..200 {
                let mid = 0.5 * (lo + hi);
                if (g(lo) > 0.0) == (g(mid) > 0.0) {
                    lo = mid;
                } else {
                    hi = mid;
                }
            }
            let k = 0.5 * (lo + hi);
            let norm2 = 0.5 * (k * k + 1.0) + 1.0;
            let projection = a / (a * a - k * k) * (k * (1.0 - k.cos()) - k.sin());
            kappa.push(k);
            alpha.push(projection / (k * norm2));
        }
        RobinWaveSeries { kappa, alpha }
    }

    /// `u(x, t)`.
    pub fn value(&self, x: f64, t: f64) -> f64 {
        self.kappa
            .iter()
            .zip(&self.alpha)
            .map(|(&k, &a)| a * (k * t).sin() * ((k * x).sin() + k * (k * x).cos()))
            .sum()
    }
}

/// The same problem with Neumann walls (`du/dn = 0`): `u = sum_n alpha_n sin(n pi t)
/// cos(n pi x)`, `alpha_n = 2 <sin 2 pi x, cos n pi x> / (n pi)` (the mean mode is zero).
pub fn neumann_wave_value(x: f64, t: f64, modes: usize) -> f64 {
    let pi = std::f64::consts::PI;
    let integral_sin = |k: f64| {
        if k == 0.0 {
            0.0
        } else {
            (1.0 - k.cos()) / k
        }
    };
    (1..=modes)
        .map(|n| {
            let k = n as f64 * pi;
            let projection = 0.5 * (integral_sin(2.0 * pi + k) + integral_sin(2.0 * pi - k));
            2.0 * projection / k * (k * t).sin() * (k * x).cos()
        })
        .sum()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn series_matches_the_shared_mode_table() {
        // shared/data/robin-wave/modes.csv, modes 1, 2, 4.
        let s = RobinWaveSeries::new(20);
        assert!((s.kappa[0] - 1.306542374188806).abs() < 1e-12);
        assert!((s.kappa[1] - 3.673194406304252).abs() < 1e-12);
        assert!((s.alpha[1] - 5.864306815835388e-2).abs() < 1e-14);
        assert!((s.alpha[3] + 4.924475880739783e-3).abs() < 1e-15);
        assert!(s.alpha[0].abs() < 1e-15 && s.alpha[2].abs() < 1e-15);
        assert!((s.alpha[19] + 1.995814400538093e-6).abs() < 1e-17);
    }

    #[test]
    fn series_meets_the_robin_condition_and_the_initial_velocity() {
        let s = RobinWaveSeries::new(400);
        let (t, e) = (0.37, 1e-6);
        let u0 = s.value(0.0, t);
        let du0 = (s.value(e, t) - s.value(-e, t)) / (2.0 * e);
        assert!((du0 - u0).abs() < 1e-6, "{du0} vs {u0}");
        let v = (s.value(0.3, 1e-6) - s.value(0.3, -1e-6)) / 2e-6;
        assert!((v - (0.6 * std::f64::consts::PI).sin()).abs() < 2e-3, "{v}");
    }

    #[test]
    fn interior_laplacian_of_a_parabola_is_two() {
        let w = Wave1d::new(
            0.0,
            1.0,
            100,
            WaveLayout::Staggered,
            2.0,
            [RobinCondition::neumann(0.0); 2],
            2,
            1e-3,
            |x| x * x,
            |_| 0.0,
        );
        let lap = w.laplacian(&w.u);
        // The discrete second moment of the kernel at h = 2 dx is 0.4 % off its integral.
        assert!((lap[50] - 2.0).abs() < 1e-2, "{}", lap[50]);
    }
}
