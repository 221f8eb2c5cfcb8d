//! Discrete identities of paper 1 that must hold to round-off for any particle state:
//! skew-adjointness of the fluid operators (eq 13), no power exchanged with fixed walls,
//! and the fluid's power loss equal to `sum_j F_j . U_j` for moving walls (App. C).

use bisph_core::eos::Eos;
use bisph_core::geometry::{box_elements_2d, box_elements_3d, polyline_elements, ElementShape};
use bisph_core::kernel::Wendland;
use bisph_core::neighbours::{CellGrid, Nearby};
use bisph_core::particles::FluidState;
use bisph_core::terms::{particle_operators, DensityDiffusion, DiffusionForm, RateModel};
use bisph_core::walls::energy_bi::{wall_pressure, EnergyConservingWalls};
use bisph_core::walls::BoundaryElements;
use bisph_core::Vector;
use glam::{DVec2, DVec3};

struct Lcg(u64);
impl Lcg {
    fn next(&mut self) -> f64 {
        self.0 = self
            .0
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        (self.0 >> 11) as f64 / (1u64 << 53) as f64
    }
    fn vector<V: Vector>(&mut self, scale: f64) -> V {
        let mut v = V::ZERO;
        for k in 0..V::DIM {
            v.set(k, scale * (2.0 * self.next() - 1.0));
        }
        v
    }
}

struct State<V> {
    position: Vec<V>,
    velocity: Vec<V>,
    density: Vec<f64>,
    mass: Vec<f64>,
    pressure: Vec<f64>,
}

/// Disordered particles on a jittered lattice inside `[lo, hi]`, random velocities and pressures.
fn random_state<V: Vector>(lo: V, hi: V, dx: f64, rng: &mut Lcg) -> State<V> {
    let mut position = bisph_core::geometry::lattice_box(lo, hi, dx);
    for r in &mut position {
        *r += rng.vector::<V>(0.3 * dx);
    }
    let n = position.len();
    let velocity = (0..n).map(|_| rng.vector::<V>(1.0)).collect();
    let density: Vec<f64> = (0..n)
        .map(|_| 1000.0 * (1.0 + 0.02 * (rng.next() - 0.5)))
        .collect();
    let mass = vec![1000.0 * dx.powi(V::DIM as i32); n];
    let pressure = (0..n).map(|_| 1.0e4 * (rng.next() - 0.3)).collect();
    State {
        position,
        velocity,
        density,
        mass,
        pressure,
    }
}

fn elements_from<V: Vector>(
    shapes: Vec<ElementShape<V>>,
    rng: &mut Lcg,
    moving: bool,
) -> BoundaryElements<V> {
    let mut e = BoundaryElements::default();
    for s in shapes {
        e.push(s.centre, s.normal, s.area, 0, &s.corners);
    }
    if moving {
        for u in &mut e.velocity {
            *u = rng.vector::<V>(0.7);
        }
    }
    e
}

/// Returns (fluid-part P_k + P_c, wall-part P_k + P_c, sum_j F_j . U_j, power scale).
fn powers<V: Vector>(
    state: &State<V>,
    elements: &mut BoundaryElements<V>,
    h: f64,
) -> (f64, f64, f64, f64) {
    let kernel = Wendland::for_dim::<V>(h);
    let model = RateModel {
        kernel,
        gravity: V::ZERO,
        diffusion: DensityDiffusion {
            scale: 0.0,
            hydrostatic_gradient: V::ZERO,
            eos: Eos::Linear {
                rho0: 1.0,
                c0: 1.0,
                p0: 0.0,
            },
            form: DiffusionForm::Laplacian,
        },
        viscosity: Default::default(),
        body_force: V::ZERO,
        density_power: 0,
        summation_density: false,
        wall_continuity_in_drift: false,
    };
    let volume: Vec<f64> = state
        .mass
        .iter()
        .zip(&state.density)
        .map(|(m, rho)| m / rho)
        .collect();
    let gamma = vec![1.0; state.position.len()];
    let view = FluidState {
        volume: &volume,
        position: &state.position,
        velocity: &state.velocity,
        density: &state.density,
        mass: &state.mass,
        pressure: &state.pressure,
        gamma: &gamma,
    };
    let mut grid = CellGrid::new(kernel.support);
    grid.rebuild(&state.position);
    let mut wall_grid = CellGrid::new(kernel.support);
    wall_grid.rebuild(&elements.centre);
    let (mut fluid_power, mut wall_power, mut scale) = (0.0, 0.0, 0.0);
    for i in 0..state.position.len() {
        let op = particle_operators(
            &model,
            &EnergyConservingWalls,
            &view,
            &grid,
            elements,
            &wall_grid,
            i,
        );
        let volume = state.mass[i] / state.density[i];
        let (u, p) = (state.velocity[i], state.pressure[i]);
        // P_k = -sum V u . grad p,  P_c = -sum V p div u  (paper 1 eqs 27-28)
        let fluid = -volume * (u.dot(op.pressure_gradient) + p * op.velocity_divergence);
        let wall = -volume * (u.dot(op.wall_pressure_gradient) + p * op.wall_velocity_divergence);
        fluid_power += fluid;
        wall_power += wall;
        scale += volume
            * (u.length() * op.pressure_gradient.length() + (p * op.velocity_divergence).abs());
    }
    wall_pressure(&kernel, elements, &view, Nearby::grid(&grid));
    let f_dot_u: f64 = (0..elements.len())
        .map(|j| {
            elements.pressure[j] * elements.area[j] * elements.normal[j].dot(elements.velocity[j])
        })
        .sum();
    (fluid_power, wall_power, f_dot_u, scale)
}

#[test]
fn fluid_operators_are_skew_adjoint_eq_13() {
    let mut rng = Lcg(11);
    let s2 = random_state(DVec2::ZERO, DVec2::new(0.3, 0.2), 0.01, &mut rng);
    let (fluid, _, _, scale) = powers(&s2, &mut BoundaryElements::default(), 0.02);
    assert!(fluid.abs() < 1e-12 * scale, "2-D: {fluid} vs {scale}");
    let s3 = random_state(DVec3::ZERO, DVec3::new(0.12, 0.1, 0.1), 0.01, &mut rng);
    let (fluid, _, _, scale) = powers(&s3, &mut BoundaryElements::default(), 0.015);
    assert!(fluid.abs() < 1e-12 * scale, "3-D: {fluid} vs {scale}");
}

#[test]
fn fixed_walls_exchange_no_power_2d_polygon_and_3d_box() {
    let mut rng = Lcg(5);
    // A slanted polygonal wall: a notch in a box.
    let poly = [
        DVec2::new(0.0, 0.0),
        DVec2::new(0.15, -0.03),
        DVec2::new(0.3, 0.0),
        DVec2::new(0.3, 0.2),
        DVec2::new(0.0, 0.2),
    ];
    let s2 = random_state(DVec2::new(0.0, 0.0), DVec2::new(0.3, 0.2), 0.01, &mut rng);
    let mut e2 = elements_from(polyline_elements(&poly, true, 0.01), &mut rng, false);
    let (_, wall, f_dot_u, scale) = powers(&s2, &mut e2, 0.02);
    assert!(
        scale > 0.0 && wall.abs() < 1e-12 * scale,
        "2-D: {wall} vs {scale}"
    );
    assert_eq!(f_dot_u, 0.0);
    let s3 = random_state(DVec3::ZERO, DVec3::new(0.1, 0.1, 0.08), 0.01, &mut rng);
    let mut e3 = elements_from(
        box_elements_3d(DVec3::ZERO, DVec3::new(0.1, 0.1, 0.08), &[], 0.01),
        &mut rng,
        false,
    );
    let (_, wall, _, scale) = powers(&s3, &mut e3, 0.015);
    assert!(
        scale > 0.0 && wall.abs() < 1e-12 * scale,
        "3-D: {wall} vs {scale}"
    );
}

#[test]
fn moving_walls_power_equals_sum_of_element_force_times_velocity() {
    let mut rng = Lcg(99);
    let s2 = random_state(DVec2::ZERO, DVec2::new(0.3, 0.2), 0.01, &mut rng);
    let mut e2 = elements_from(
        box_elements_2d(DVec2::ZERO, DVec2::new(0.3, 0.2), &[], 0.01),
        &mut rng,
        true,
    );
    let (_, wall, f_dot_u, scale) = powers(&s2, &mut e2, 0.02);
    assert!(
        f_dot_u.abs() > 1e-3 * scale,
        "the test must see real wall power"
    );
    assert!(
        (wall + f_dot_u).abs() < 1e-12 * scale,
        "2-D: {wall} vs {f_dot_u}"
    );
    let s3 = random_state(DVec3::ZERO, DVec3::new(0.1, 0.1, 0.08), 0.01, &mut rng);
    let mut e3 = elements_from(
        box_elements_3d(DVec3::ZERO, DVec3::new(0.1, 0.1, 0.08), &[], 0.01),
        &mut rng,
        true,
    );
    let (_, wall, f_dot_u, scale) = powers(&s3, &mut e3, 0.015);
    assert!(f_dot_u.abs() > 1e-3 * scale);
    assert!(
        (wall + f_dot_u).abs() < 1e-12 * scale,
        "3-D: {wall} vs {f_dot_u}"
    );
}
