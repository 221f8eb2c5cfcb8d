//! The particle start that fits usaw walls (`fill = "usaw"`): [`relax_positions`] removes the
//! zero-order residual of the operators, [`balance_positions`] then holds still water at rest.

use super::model::{UsawWalls, Vertices};
use crate::dim::Vector;
use crate::kernel::Wendland;
use crate::neighbours::{CellGrid, Nearby};
use crate::walls::geometric_shepard;
use crate::walls::{BoundaryElements, ParticleView, WallModel};
use rayon::prelude::*;

/// Outcome of [`relax_positions`].
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Relaxation {
    /// Iterations run.
    pub iterations: usize,
    /// Largest `|R_a|` [1/m] over the particles deeper than one support below the surface,
    /// before and after.
    pub deep_residual: [f64; 2],
    /// Largest `|R_a|` over all particles (the mirror lid in place), before and after.
    pub residual: [f64; 2],
}

/// The pressure sum of eq 37 (paper 3, `k = 0`, before the division by `gamma_a`) at `xa`,
/// pressure `pa`, density `rho_a`: the fluid pairs `sum_F (p_a + p_b) V_b grad_a W_ab` over
/// `points` (pressures `p`, volume `volume` each, found through `grid`; the sweep's
/// [`crate::terms::pressure_gradient::pair`]) plus the wall part of [`UsawWalls`] (vertex pairs
/// and segments, with the vertex pressures held in `walls`). With every pressure `1/2` it is
/// the zero-order residual `R_a = sum_P V_b grad_a W_ab - grad gamma_a`.
#[allow(clippy::too_many_arguments)]
fn pressure_sum<V: Vector>(
    kernel: &Wendland,
    (xa, pa, rho_a): (V, f64, f64),
    points: &[V],
    p: &[f64],
    grid: &CellGrid<V>,
    volume: f64,
    walls: &UsawWalls<'_, V>,
    elements: &BoundaryElements<V>,
    element_grid: &CellGrid<V>,
) -> V {
    let mut sum = V::ZERO;
    grid.for_each_neighbour(xa, points, kernel.support, |b, r_ab, d| {
        let grad_w = r_ab * kernel.gradient_factor(d);
        sum += crate::terms::pressure_gradient::pair(pa, p[b], grad_w, volume);
    });
    let view = ParticleView {
        index: 0,
        x: xa,
        u: V::ZERO,
        p: pa,
        rho: rho_a,
    };
    sum + walls
        .particle_terms(kernel, &view, elements, Nearby::grid(element_grid))
        .pressure_gradient
}

/// The usaw walls of the two fit stages: `vertices` with the pressures `pressure` and
/// densities `density` (at rest), `k = 0`, walls in tension allowed (paper 3 as written).
fn walls_with_pressures<V: Vector>(
    vertices: &Vertices<V>,
    pressure: impl Fn(V) -> f64,
    density: impl Fn(f64) -> f64,
) -> Vertices<V> {
    let mut v = vertices.clone();
    v.pressure = v.position.iter().map(|&y| pressure(y)).collect();
    v.density = v.pressure.iter().map(|&p| density(p)).collect();
    v.velocity = vec![V::ZERO; v.position.len()];
    v
}

/// What both stages of a start that fits usaw walls read ([`relax_positions`],
/// [`balance_positions`]): the kernel, the lattice spacing `dx` and the particle volume
/// (`dx^d`), the walls (vertex particles with their volumes `m_v / rho_v`, and segments), the
/// free surface at height `surface` along `up`, and the most iterations of each stage.
#[derive(Clone, Copy)]
pub struct FitSetting<'a, V: Vector> {
    /// The kernel.
    pub kernel: &'a Wendland,
    /// Lattice spacing.
    pub dx: f64,
    /// Volume of each fluid particle.
    pub volume: f64,
    /// The vertex particles.
    pub vertices: &'a Vertices<V>,
    /// The wall segments.
    pub elements: &'a BoundaryElements<V>,
    /// Unit vector against gravity.
    pub up: V,
    /// Height of the free surface along `up`.
    pub surface: f64,
    /// Most iterations of each stage.
    pub max_iterations: usize,
}

impl<V: Vector> FitSetting<'_, V> {
    /// Nearest a shift may bring a particle to a wall (unless it started nearer): half the
    /// spacing, where a lattice along a flat wall has its first row.
    fn clearance(&self) -> f64 {
        0.5 * self.dx
    }
}

/// Particle initialisation that fits usaw walls: shifts the fluid particles `x` (volume
/// `volume` each, the lattice's `dx^d`) down the zero-order residual `R_a` of the usaw
/// operators ([`pressure_sum`] with every pressure `1/2`): `dx_a = -D R_a`, `D = 0.5 h^2`, at most `0.1 dx` per
/// iteration, as BIPI does (paper 4, eq 15) but with the residual that eq 37 sees (vertex
/// particles in the volume sum, segments by their exact `grad gamma_as`), so that a
/// constant pressure exerts no force at rest. The free surface (at height `surface` along
/// `up`) is a mirror during the relaxation: the fluid within one support of it is reflected
/// across it, so the top rows keep their spacing from the surface (the walls must continue
/// above the surface by a support, as an open tank's do). Stops when no particle moves by
/// more than `1e-6 dx` or after `max_iterations`. Vertex volumes are those of `vertices`
/// (`m_v / rho_v`).
pub fn relax_positions<V: Vector>(fit: &FitSetting<'_, V>, x: &mut [V]) -> Relaxation {
    let FitSetting {
        kernel,
        volume,
        vertices,
        elements,
        up,
        surface,
        ..
    } = *fit;
    let support = kernel.support;
    let mut element_grid = CellGrid::new(support + elements.max_reach);
    element_grid.rebuild(&elements.centre);
    let diffusion = 0.5 * kernel.h * kernel.h;
    let half = walls_with_pressures(vertices, |_| 0.5, |_| 1.0);
    let walls = UsawWalls {
        vertices: &half,
        density_power: 0,
        no_tension: false,
    };
    let measure = |x: &[V]| {
        // The fluid and its mirror images across the surface.
        let mut points = x.to_vec();
        points.extend(
            x.iter()
                .filter(|&&p| surface - p.dot(up) < support)
                .map(|&p| p + up * (2.0 * (surface - p.dot(up)))),
        );
        let p = vec![0.5; points.len()];
        let mut grid = CellGrid::new(support);
        grid.rebuild(&points);
        x.par_iter()
            .map(|&xa| {
                let at = (xa, 0.5, 1.0);
                pressure_sum(
                    kernel,
                    at,
                    &points,
                    &p,
                    &grid,
                    volume,
                    &walls,
                    elements,
                    &element_grid,
                )
            })
            .collect::<Vec<V>>()
    };
    let depth = |p: V| surface - p.dot(up);
    let step = |_: V, r: V| r * -diffusion;
    let clearance = fit.clearance();
    let crosses = |from: V, to: V| blocked(elements, &element_grid, clearance, from, to);
    shift_until_still(x, fit, depth, measure, step, crosses)
}

/// Second stage of [`relax_positions`], for still water: shifts the fluid particles `x` along
/// their acceleration at hydrostatic rest, `a_a = -Grad^{gamma,0} p / rho_a + g` (paper 3,
/// eq 37 with `k = 0`: `Grad p = (sum_P (p_a + p_b) V_b grad_a W_ab - sum_s (p_a + p_s) grad
/// gamma_as) / gamma_a`), with every pressure the still water's at its height: `pressure`
/// of the depth below the surface (at height `surface` along `up`, `g` the gravity's size),
/// for the fluid and the vertex particles alike (above the surface continued as `rho0 g d`,
/// negative), segment values the mean of their vertices, `rho_a` from `density`, `gamma_a`
/// geometric. No mirror: the free surface is the real one, so the top rows settle where the
/// operator holds them. Shift `beta_a a_a` with `beta_a = 0.5 h^2 / (2 p_a / rho_a + g h)`
/// (the stiffness of the constant-pressure part), at most `0.1 dx`; stops when no particle
/// moves by more than `1e-6 dx` or after `max_iterations`. Returns the iterations and the
/// largest `|a|` before and after, over all particles and over those deeper than a support.
pub fn balance_positions<V: Vector>(
    fit: &FitSetting<'_, V>,
    x: &mut [V],
    g: f64,
    pressure: &(dyn Fn(f64) -> f64 + Sync),
    density: &(dyn Fn(f64) -> f64 + Sync),
) -> Relaxation {
    let FitSetting {
        kernel,
        volume,
        vertices,
        elements,
        up,
        surface,
        ..
    } = *fit;
    let support = kernel.support;
    let mut grid = CellGrid::new(support + elements.max_reach);
    grid.rebuild(&elements.centre);
    let rho0 = density(0.0);
    let p_at = |y: V| {
        let d = surface - y.dot(up);
        if d >= 0.0 {
            pressure(d)
        } else {
            rho0 * g * d
        }
    };
    let at_rest = walls_with_pressures(vertices, p_at, density);
    let walls = UsawWalls {
        vertices: &at_rest,
        density_power: 0,
        no_tension: false,
    };
    let accelerations = |x: &[V]| -> Vec<V> {
        let p: Vec<f64> = x.iter().map(|&y| p_at(y)).collect();
        let mut fluid_grid = CellGrid::new(support);
        fluid_grid.rebuild(x);
        (0..x.len())
            .into_par_iter()
            .map(|a| {
                let at = (x[a], p[a], density(p[a]));
                let sum = pressure_sum(
                    kernel,
                    at,
                    x,
                    &p,
                    &fluid_grid,
                    volume,
                    &walls,
                    elements,
                    &grid,
                );
                let gamma = geometric_shepard::gamma(kernel, x[a], elements, &grid);
                sum * (-1.0 / (gamma * at.2)) - up * g
            })
            .collect()
    };
    let depth = |p: V| surface - p.dot(up);
    let step = |y: V, a: V| {
        let pa = p_at(y).max(0.0);
        a * (0.5 * kernel.h * kernel.h / (2.0 * pa / density(pa) + g * kernel.h))
    };
    let clearance = fit.clearance();
    let crosses = |from: V, to: V| blocked(elements, &grid, clearance, from, to);
    shift_until_still(x, fit, depth, accelerations, step, crosses)
}

/// `true` when a shift of the fit from `from` to `to` is not allowed: its straight path touches
/// a wall element, or it ends nearer to a wall than `clearance` and nearer than it started
/// (`grid` holds the element centres, with cells at least `max_reach` wide).
fn blocked<V: Vector>(
    elements: &BoundaryElements<V>,
    grid: &CellGrid<V>,
    clearance: f64,
    from: V,
    to: V,
) -> bool {
    let reach = (to - from).length() + elements.max_reach;
    let mut hit = false;
    grid.for_each_sparse_neighbour(from, &elements.centre, reach, |k, _, _| {
        hit = hit || crate::bi::path_crosses_element(from, to, elements.current_corners(k));
    });
    hit || {
        let near = wall_distance(elements, grid, to, clearance);
        near < clearance && near < wall_distance(elements, grid, from, clearance)
    }
}

/// Distance from `x` to the nearest wall element, if one lies within `radius` (else infinite).
fn wall_distance<V: Vector>(
    elements: &BoundaryElements<V>,
    grid: &CellGrid<V>,
    x: V,
    radius: f64,
) -> f64 {
    let mut d2 = f64::INFINITY;
    grid.for_each_sparse_neighbour(
        x,
        &elements.centre,
        radius + elements.max_reach,
        |k, _, _| {
            if let Some((dk2, _, _)) =
                crate::walls::nearest_on_element(elements.current_corners(k), V::ZERO, x)
            {
                d2 = d2.min(dk2);
            }
        },
    );
    d2.sqrt()
}

/// The iteration of [`relax_positions`] and [`balance_positions`]: evaluates the field
/// `field(x)` (a residual or an acceleration), shifts each particle by `step(x_a, f_a)`, at
/// most `0.1 dx` and never out of the water: a shift whose path touches a wall
/// (`crosses(from, to)`) or ends above the free surface (`depth < 0`) is halved until it does
/// not, or dropped after 8 halvings; until no particle moves by more than `1e-6 dx` or
/// `max_iterations`; reports
/// the largest `|f|` before and after, over all particles and over those deeper than `support`
/// (`depth(x_a)` below the surface).
fn shift_until_still<V: Vector>(
    x: &mut [V],
    fit: &FitSetting<'_, V>,
    depth: impl Fn(V) -> f64,
    field: impl Fn(&[V]) -> Vec<V>,
    step: impl Fn(V, V) -> V,
    crosses: impl Fn(V, V) -> bool,
) -> Relaxation {
    let (dx, support, max_iterations) = (fit.dx, fit.kernel.support, fit.max_iterations);
    let largest = |x: &[V], f: &[V]| {
        let (mut all, mut deep) = (0.0f64, 0.0f64);
        for (&p, fa) in x.iter().zip(f) {
            all = all.max(fa.length());
            if depth(p) > support {
                deep = deep.max(fa.length());
            }
        }
        (all, deep)
    };
    let cap = 0.1 * dx;
    let mut f = field(x);
    let (all0, deep0) = largest(x, &f);
    let mut iterations = 0;
    while iterations < max_iterations {
        let mut moved = 0.0f64;
        for (p, &fa) in x.iter_mut().zip(&f) {
            let mut shift = step(*p, fa);
            let l = shift.length();
            if l > cap {
                shift = shift * (cap / l);
            }
            for halvings in 0..=8 {
                if depth(*p + shift) >= 0.0 && !crosses(*p, *p + shift) {
                    break;
                }
                shift = if halvings < 8 { shift * 0.5 } else { V::ZERO };
            }
            *p += shift;
            moved = moved.max(shift.length());
        }
        iterations += 1;
        f = field(x);
        if moved < 1e-6 * dx {
            break;
        }
    }
    let (all1, deep1) = largest(x, &f);
    Relaxation {
        iterations,
        deep_residual: [deep0, deep1],
        residual: [all0, all1],
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::eos::Eos;
    use crate::geometry::box_elements_2d;
    use crate::neighbours::Periodicity;
    use glam::DVec2;

    /// An open tank `[0, 1] x [0, 1.5]` (dx = 0.1, h = 2 dx) holding the lattice of still
    /// water 1.05 deep, as `fill = "usaw"` starts it.
    fn still_tank() -> (
        Wendland,
        BoundaryElements<DVec2>,
        Vertices<DVec2>,
        Vec<DVec2>,
    ) {
        let dx = 0.1;
        let kernel = Wendland::new(2.0 * dx, 2);
        let open = ["+y".to_string()];
        let mut e = BoundaryElements::<DVec2>::default();
        for s in box_elements_2d(DVec2::new(0.0, 0.0), DVec2::new(1.0, 1.5), &open, dx) {
            e.push(s.centre, s.normal, s.area, 0, &s.corners);
        }
        let v =
            Vertices::from_elements(&e, 1000.0, kernel.support, dx, Periodicity::none()).unwrap();
        let x = crate::geometry::lattice_box(DVec2::new(0.05, 0.05), DVec2::new(0.95, 1.05), dx);
        (kernel, e, v, x)
    }

    /// The fit of [`still_tank`]: surface 1.05, at most 5000 iterations per stage.
    fn tank_fit<'a>(
        kernel: &'a Wendland,
        vertices: &'a Vertices<DVec2>,
        elements: &'a BoundaryElements<DVec2>,
    ) -> FitSetting<'a, DVec2> {
        FitSetting {
            kernel,
            dx: 0.1,
            volume: 0.01,
            vertices,
            elements,
            up: DVec2::new(0.0, 1.0),
            surface: 1.05,
            max_iterations: 5000,
        }
    }

    /// [`balance_positions`] for water (Tait, `rho0 = 1000`, sound speed `c0`) under
    /// `g = 9.81`.
    fn balance_in_water(fit: &FitSetting<'_, DVec2>, x: &mut [DVec2], c0: f64) -> Relaxation {
        let eos = Eos::Tait {
            rho0: 1000.0,
            c0,
            p0: 0.0,
            xi: 7.0,
        };
        let pressure = |d: f64| eos.hydrostatic_pressure(9.81, d);
        let density = |p: f64| eos.density(p).unwrap();
        balance_positions(fit, x, 9.81, &pressure, &density)
    }

    /// The zero-order residual (vertex particles included) falls by three orders of magnitude
    /// from the lattice's, where the fluid sum overshoots the exact `grad gamma` near walls.
    #[test]
    fn relaxation_removes_the_zero_order_residual() {
        let (kernel, e, v, mut x) = still_tank();
        let r = relax_positions(&tank_fit(&kernel, &v, &e), &mut x);
        assert!(r.deep_residual[0] > 0.1, "lattice residual {:?}", r);
        assert!(r.residual[1] < 1e-3 * r.residual[0], "{r:?}");
        assert!(
            x.iter().all(|p| p.x > 0.05 && p.x < 0.95 && p.y > 0.05),
            "left the tank"
        );
    }

    /// After the residual, the balance at hydrostatic rest brings the largest acceleration
    /// (free surface included) down by more than tenfold.
    #[test]
    fn balance_holds_still_water_at_rest() {
        let (kernel, e, v, mut x) = still_tank();
        let fit = tank_fit(&kernel, &v, &e);
        relax_positions(&fit, &mut x);
        let r = balance_in_water(&fit, &mut x, 20.0);
        assert!(r.residual[0] > 1.0, "{r:?}");
        assert!(r.residual[1] < 0.05 * r.residual[0], "{r:?}");
    }

    /// Water in a tank with a 30 degree side that meets the free surface at an acute angle
    /// (the lattice of the polygon leaves a particle 0.18 dx from the sloped wall there):
    /// after both stages no particle has left the water, none is nearer a wall than half a
    /// spacing unless its lattice point was, and none moved nearer than its lattice point.
    #[test]
    fn the_fit_keeps_particles_in_the_water_and_off_the_walls() {
        let dx = 0.025;
        let kernel = Wendland::new(2.0 * dx, 2);
        let wall = [
            DVec2::new(0.0, 0.8),
            DVec2::new(0.0, 0.0),
            DVec2::new(0.8, 0.1),
            DVec2::new(2.012_435_57, 0.8),
        ];
        let mut e = BoundaryElements::<DVec2>::default();
        for s in crate::geometry::polyline_elements(&wall, false, dx) {
            e.push(s.centre, s.normal, s.area, 0, &s.corners);
        }
        let block = [
            DVec2::new(0.0, 0.0),
            DVec2::new(0.8, 0.1),
            DVec2::new(1.492_820_32, 0.5),
            DVec2::new(0.0, 0.5),
        ];
        let mut x = crate::geometry::lattice_polygon(&block, dx);
        let start = x.clone();
        let v =
            Vertices::from_elements(&e, 1000.0, kernel.support, dx, Periodicity::none()).unwrap();
        let fit = FitSetting {
            kernel: &kernel,
            dx,
            volume: dx * dx,
            vertices: &v,
            elements: &e,
            up: DVec2::new(0.0, 1.0),
            surface: 0.5,
            max_iterations: 5000,
        };
        relax_positions(&fit, &mut x);
        balance_in_water(&fit, &mut x, 22.15);
        let mut grid = CellGrid::new(kernel.support + e.max_reach);
        grid.rebuild(&e.centre);
        let distance = |p: DVec2| wall_distance(&e, &grid, p, kernel.support);
        let nearest_start = start.iter().map(|&p| distance(p)).fold(f64::MAX, f64::min);
        assert!(nearest_start < 0.2 * dx, "the lattice {nearest_start}");
        for (&p, &p0) in x.iter().zip(&start) {
            assert!(p.y <= 0.5, "above the surface: {p}");
            let (d, d0) = (distance(p), distance(p0));
            assert!(
                d >= (0.5 * dx).min(d0) - 1e-12,
                "{p} is {d} from a wall (from {d0})"
            );
        }
    }
}
