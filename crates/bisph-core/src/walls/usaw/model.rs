//! The unified semi-analytical wall model (paper 3): `grad gamma_as`, the vertex particles and
//! [`UsawWalls`], the wall parts of the operators (eqs 37-38). See [`super`].

use crate::bi::segment::segment_kernel_integral;
use crate::dim::{xy, Vector};
use crate::eos::Eos;
use crate::kernel::Wendland;
use crate::neighbours::{CellGrid, Nearby, Periodicity};
use crate::particles::FluidState;
use crate::walls::{BoundaryElements, ParticleView, WallModel, WallTerms};
use rayon::prelude::*;
use std::f64::consts::PI;

/// `grad gamma_as` of element `j` for a particle at `x` (paper 3, eq 9), `-n_s int_s W`, the
/// exact segment integral of [`crate::bi::segment`]; 2-D only (zero in 3-D and for other elements).
#[inline(always)]
fn segment_grad_gamma<V: Vector>(
    kernel: &Wendland,
    x: V,
    elements: &BoundaryElements<V>,
    j: usize,
) -> V {
    if V::DIM != 2 {
        return V::ZERO;
    }
    let c = elements.current_corners(j);
    if c.len() != 2 {
        return V::ZERO;
    }
    let integral = segment_kernel_integral(kernel, xy(x), xy(c[0]), xy(c[1]), kernel.support);
    let g = -xy(elements.normal[j]) * integral;
    V::from_slice(&[g.x, g.y])
}

/// `grad gamma_a = sum_s grad gamma_as` (paper 3, eq 10), over every element that can
/// overlap the support. On periodic axes the grid hands each element's image shift and the
/// point is moved by it instead (the element's corners are stored at its own image).
pub fn grad_gamma<V: Vector>(
    kernel: &Wendland,
    x: V,
    elements: &BoundaryElements<V>,
    grid: &CellGrid<V>,
) -> V {
    let mut sum = V::ZERO;
    let radius = kernel.support + elements.max_reach;
    grid.for_each_candidate_within_shifted(x, radius, |j, image| {
        sum += segment_grad_gamma(kernel, x - image, elements, j);
    });
    sum
}

/// How vertex values are extrapolated from the fluid.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum WallInterpolation {
    /// Paper 3, eqs 16-17: `f_v = sum_F V_b f_b w_vb / sum_F V_b w_vb` (`dp/dn = 0`).
    #[default]
    Shepard,
    /// Neumann with gravity, the constraint of eq 82: `y_b = p_b - rho_b (g . n_v)(r_bv . n_v)`
    /// (`dp/dn = rho g . n`; tangential variations kept).
    Neumann,
    /// Hydrostatic-corrected, eq 83 with the Neumann part: `y_b = p_b - rho_b g . r_bv`
    /// (tangential hydrostatic variations removed as well).
    Hydrostatic,
}

/// The vertex particles: the end points of the wall segments (paper 3, table 1).
#[derive(Clone, Debug, Default)]
pub struct Vertices<V: Vector> {
    /// Positions.
    pub position: Vec<V>,
    /// Unit normals into the fluid (mean of the adjacent segments' inward normals).
    pub normal: Vec<V>,
    /// Masses `m_v = rho0 V_v`, `V_v = l^2 theta / (2 pi)` with `l` the mean length of the
    /// adjacent segments and `theta` the fluid-side angle at the vertex.
    pub mass: Vec<f64>,
    /// Velocities (walls are fixed: zero).
    pub velocity: Vec<V>,
    /// Extrapolated pressures (eq 16).
    pub pressure: Vec<f64>,
    /// Densities from the pressures by the inverse equation of state.
    pub density: Vec<f64>,
    /// Volumes `m_v / rho_v`.
    pub volume: Vec<f64>,
    /// The two vertices of every element (index = element).
    pub segment: Vec<[u32; 2]>,
    /// Cell grid over the vertex positions.
    pub grid: CellGrid<V>,
}

impl<V: Vector> Vertices<V> {
    /// Vertices of 2-D segment elements: coincident corners (closer than `1e-9 dx`, in the
    /// minimum image along periodic axes) merge, so a wall that runs through a periodic
    /// boundary has one vertex there, kept in the primary period. `None` when an element is
    /// not a segment (3-D) or the period is too short for the grid.
    pub fn from_elements(
        elements: &BoundaryElements<V>,
        rho0: f64,
        cell_size: f64,
        dx: f64,
        period: Periodicity<V>,
    ) -> Option<Self> {
        if V::DIM != 2 {
            return None;
        }
        let tol = 1e-9 * dx;
        let mut v = Vertices::<V> {
            grid: CellGrid::with_period(cell_size, period).ok()?,
            ..Default::default()
        };
        let mut sum_len: Vec<f64> = Vec::new();
        let mut count: Vec<u32> = Vec::new();
        // Per vertex: (inward normal, other end) of each adjacent segment.
        let mut adjacent: Vec<Vec<(V, usize)>> = Vec::new();
        for j in 0..elements.len() {
            let c = elements.current_corners(j);
            if c.len() != 2 {
                return None;
            }
            let mut ids = [0usize; 2];
            for (k, &p) in c.iter().enumerate() {
                let p = period.wrap(p);
                let found = v
                    .position
                    .iter()
                    .position(|&q| period.minimum_image(q - p).length() <= tol);
                ids[k] = match found {
                    Some(id) => id,
                    None => {
                        v.position.push(p);
                        sum_len.push(0.0);
                        count.push(0);
                        adjacent.push(Vec::new());
                        v.position.len() - 1
                    }
                };
                sum_len[ids[k]] += elements.area[j];
                count[ids[k]] += 1;
            }
            adjacent[ids[0]].push((-elements.normal[j], ids[1]));
            adjacent[ids[1]].push((-elements.normal[j], ids[0]));
            v.segment.push([ids[0] as u32, ids[1] as u32]);
        }
        for id in 0..v.position.len() {
            let adj = &adjacent[id];
            let mut n = adj.iter().fold(V::ZERO, |a, &(b, _)| a + b);
            let len = n.length();
            if len > 1e-12 {
                n = n / len;
            }
            // Fluid-side angle: pi for a flat wall or an open end; at a corner, pi minus the
            // turn between the inward normals when the corner is concave (the far end of one
            // segment lies on the fluid side of the other), pi plus it when convex.
            let theta = if adj.len() == 2 {
                let (a, b) = (xy(adj[0].0), xy(adj[1].0));
                let turn = a.perp_dot(b).atan2(a.dot(b)).abs();
                let far = period
                    .minimum_image(v.position[adj[0].1] - v.position[id])
                    .dot(adj[1].0);
                if far > 0.0 {
                    PI - turn
                } else {
                    PI + turn
                }
            } else {
                PI
            };
            let l = sum_len[id] / count[id].max(1) as f64;
            v.normal.push(n);
            v.mass.push(rho0 * l * l * theta / (2.0 * PI));
        }
        let n = v.position.len();
        v.velocity = vec![V::ZERO; n];
        v.pressure = vec![0.0; n];
        v.density = vec![rho0; n];
        v.volume = v.mass.iter().map(|m| m / rho0).collect();
        v.grid.rebuild(&v.position);
        Some(v)
    }

    /// Number of vertices.
    pub fn len(&self) -> usize {
        self.position.len()
    }

    /// `true` when there are none.
    pub fn is_empty(&self) -> bool {
        self.position.is_empty()
    }

    /// Vertex pressures by extrapolation from the fluid (paper 3, eqs 16-17, with the
    /// constraint chosen by `interpolation`), densities by the inverse equation of state
    /// (clamped to `[0.5, 2] rho0`), volumes `m_v / rho_v`.
    pub fn update(
        &mut self,
        kernel: &Wendland,
        eos: &Eos,
        gravity: V,
        interpolation: WallInterpolation,
        fluid: &FluidState<V>,
        fluid_grid: &CellGrid<V>,
    ) {
        let (pos, normal) = (&self.position, &self.normal);
        let rho0 = eos.rho0();
        self.pressure
            .par_iter_mut()
            .zip(self.density.par_iter_mut())
            .zip(self.volume.par_iter_mut().zip(self.mass.par_iter()))
            .enumerate()
            .for_each(|(v, ((p, rho), (vol, &m)))| {
                let (mut weighted, mut alpha) = (0.0, 0.0);
                let n = normal[v];
                fluid_grid.for_each_neighbour(
                    pos[v],
                    fluid.position,
                    kernel.support,
                    |b, r_vb, r| {
                        let wv = kernel.value(r) * fluid.volume[b];
                        // r_vb = r_b - r_v.
                        let y = match interpolation {
                            WallInterpolation::Shepard => fluid.pressure[b],
                            WallInterpolation::Neumann => {
                                fluid.pressure[b] - fluid.density[b] * gravity.dot(n) * r_vb.dot(n)
                            }
                            WallInterpolation::Hydrostatic => {
                                fluid.pressure[b] - fluid.density[b] * gravity.dot(r_vb)
                            }
                        };
                        weighted += y * wv;
                        alpha += wv;
                    },
                );
                *p = if alpha > 0.0 { weighted / alpha } else { 0.0 };
                *rho = eos
                    .density(*p)
                    .unwrap_or(rho0)
                    .clamp(0.5 * rho0, 2.0 * rho0);
                *vol = m / *rho;
            });
    }
}

/// The unified semi-analytical wall model (paper 3).
#[derive(Clone, Copy, Debug)]
pub struct UsawWalls<'a, V: Vector> {
    /// The vertex particles, values refreshed before the sweep.
    pub vertices: &'a Vertices<V>,
    /// The power `k` of eqs 37-38 (0 or 1).
    pub density_power: u8,
    /// Walls push but never pull: the vertex pairs and the segments take `max(p, 0)` of the
    /// particle's, the vertices' and the segments' pressures. In tension (`p < 0`, behind a
    /// convex corner where the flow separates) the discrete vertex and segment sums no longer
    /// balance the fluid sum exactly, and the imbalance times a negative pressure draws
    /// particles into the wall; without the wall's part the fluid's tension pulls them back
    /// into the fluid instead. Not in paper 3 (which has no separating flow over a corner at
    /// low resolution); off by default.
    pub no_tension: bool,
}

impl<V: Vector> UsawWalls<'_, V> {
    /// `(rho_a / rho_b)^k`.
    #[inline(always)]
    fn ratio(&self, rho_a: f64, rho_b: f64) -> f64 {
        if self.density_power == 0 {
            1.0
        } else {
            rho_a / rho_b
        }
    }

    /// Mean pressure and density of the two vertices of element `j`.
    #[inline(always)]
    fn segment_values(&self, j: usize) -> (f64, f64) {
        let [a, b] = self.vertices.segment[j];
        let v = self.vertices;
        (
            0.5 * (v.pressure[a as usize] + v.pressure[b as usize]),
            0.5 * (v.density[a as usize] + v.density[b as usize]),
        )
    }
}

impl<V: Vector> WallModel<V> for UsawWalls<'_, V> {
    const RENORMALISE: bool = true;
    const RENORMALISE_DIFFUSION: bool = true;

    /// Segment pressure: mean of its vertices (paper 3, section 2).
    fn update_wall_pressure(
        &self,
        _kernel: &Wendland,
        elements: &mut BoundaryElements<V>,
        _fluid: &FluidState<V>,
        _fluid_near: Nearby<'_, V>,
    ) {
        for j in 0..elements.len() {
            elements.pressure[j] = self.segment_values(j).0;
        }
    }

    fn renormalisation(&self, _discrete: f64, state_gamma: f64) -> f64 {
        state_gamma
    }

    #[inline(always)]
    fn particle_terms(
        &self,
        kernel: &Wendland,
        a: &ParticleView<V>,
        elements: &BoundaryElements<V>,
        near: Nearby<'_, V>,
    ) -> WallTerms<V> {
        let mut pressure_gradient = V::ZERO;
        let mut velocity_divergence = 0.0;
        // Vertex particles in the volume sums (eqs 37-38 over P = V u F).
        let v = self.vertices;
        let wall_p = |p: f64| if self.no_tension { p.max(0.0) } else { p };
        let p_a = wall_p(a.p);
        v.grid
            .for_each_sparse_neighbour(a.x, &v.position, kernel.support, |b, r_ab, r| {
                let grad_w = r_ab * kernel.gradient_factor(r);
                let ratio = self.ratio(a.rho, v.density[b]);
                pressure_gradient += crate::terms::pressure_gradient::pair_k(
                    p_a,
                    wall_p(v.pressure[b]),
                    grad_w,
                    v.volume[b],
                    ratio,
                );
                velocity_divergence += crate::terms::velocity_divergence::pair_k(
                    a.u,
                    v.velocity[b],
                    grad_w,
                    v.volume[b],
                    ratio,
                );
            });
        // Segments (at the image next to the particle on periodic axes).
        let radius = kernel.support + elements.max_reach;
        near.grid
            .for_each_candidate_within_shifted(a.x, radius, |j, image| {
                let gg = segment_grad_gamma(kernel, a.x - image, elements, j);
                if gg == V::ZERO {
                    return;
                }
                let (p_s, rho_s) = self.segment_values(j);
                let ratio = self.ratio(a.rho, rho_s);
                pressure_gradient -= gg * (ratio * wall_p(p_s) + p_a / ratio);
                velocity_divergence -= (elements.velocity[j] - a.u).dot(gg) / ratio;
            });
        WallTerms {
            pressure_gradient,
            velocity_divergence,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::geometry::box_elements_2d;
    use crate::walls::geometric_shepard;
    use glam::DVec2;

    #[test]
    fn polygon_sum_is_the_gradient_of_the_area_gamma() {
        let kernel = Wendland::new(0.05, 2);
        let dx = 0.025;
        let shapes = box_elements_2d(DVec2::new(0.0, 0.0), DVec2::new(1.0, 0.6), &[], dx);
        let mut e = BoundaryElements::default();
        for s in shapes {
            e.push(s.centre, s.normal, s.area, 0, &s.corners);
        }
        let mut grid = CellGrid::new(kernel.support);
        grid.rebuild(&e.centre);
        let mut worst: f64 = 0.0;
        for &(x, y) in &[
            (0.5, 0.03),
            (0.021, 0.5),
            (0.04, 0.045),
            (0.013, 0.007),
            (0.97, 0.58),
            (0.5, 0.3),
            (0.3, 0.0012),
        ] {
            let x = DVec2::new(x, y);
            let g = grad_gamma(&kernel, x, &e, &grid);
            let step = 1e-6;
            let mut fd = DVec2::ZERO;
            for k in 0..2 {
                let mut d = DVec2::ZERO;
                d[k] = step;
                let plus = geometric_shepard::gamma(&kernel, x + d, &e, &grid);
                let minus = geometric_shepard::gamma(&kernel, x - d, &e, &grid);
                fd[k] = (plus - minus) / (2.0 * step);
            }
            // Relative to the scale of grad gamma, ~ 1/h.
            worst = worst.max((g - fd).length() * kernel.h);
        }
        eprintln!("sum grad gamma_as vs FD of geometric gamma: max |diff| h = {worst:e}");
        assert!(worst < 1e-6, "worst {worst:e}");
    }

    #[test]
    fn integrated_gamma_follows_the_geometric_gamma() {
        // A particle moving along and towards a wall (the floor of a box) over 1000 steps.
        let kernel = Wendland::new(0.02, 2);
        let dx = 0.01;
        let shapes = box_elements_2d(DVec2::new(0.0, 0.0), DVec2::new(1.0, 1.0), &[], dx);
        let mut e = BoundaryElements::default();
        for s in shapes {
            e.push(s.centre, s.normal, s.area, 0, &s.corners);
        }
        let mut grid = CellGrid::new(kernel.support);
        grid.rebuild(&e.centre);
        let (start, end) = (DVec2::new(0.3, 0.05), DVec2::new(0.55, 0.004));
        let steps = 1000;
        let mut x = start;
        let mut gamma = geometric_shepard::gamma(&kernel, x, &e, &grid);
        let mut g_old = grad_gamma(&kernel, x, &e, &grid);
        let mut worst: f64 = 0.0;
        for k in 1..=steps {
            let next = start + (end - start) * (k as f64 / steps as f64);
            let g_new = grad_gamma(&kernel, next, &e, &grid);
            gamma += 0.5 * (g_old + g_new).dot(next - x);
            x = next;
            g_old = g_new;
            let exact = geometric_shepard::gamma(&kernel, x, &e, &grid);
            worst = worst.max((gamma - exact).abs());
        }
        assert!(worst < 1e-3, "worst {worst:e}");
        eprintln!("integrated vs geometric gamma over 1000 steps: max |diff| = {worst:e}");
    }

    #[test]
    fn flat_wall_vertices_carry_half_a_particle() {
        let dx = 0.1;
        let shapes = box_elements_2d(DVec2::new(0.0, 0.0), DVec2::new(1.0, 1.0), &[], dx);
        let mut e = BoundaryElements::<DVec2>::default();
        for s in shapes {
            e.push(s.centre, s.normal, s.area, 0, &s.corners);
        }
        let v = Vertices::from_elements(&e, 1000.0, 0.2, dx, Periodicity::none()).unwrap();
        assert_eq!(v.len(), 40);
        let mut corner = 0;
        for i in 0..v.len() {
            let m = v.mass[i] / (1000.0 * dx * dx);
            if (m - 0.5).abs() < 1e-9 {
                continue;
            }
            assert!((m - 0.25).abs() < 1e-9, "mass {m}");
            corner += 1;
        }
        assert_eq!(corner, 4);
    }
}
