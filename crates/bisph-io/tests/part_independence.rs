//! A particle's rates depend only on the particles around it, never on how the particles are
//! stored or which other particles the simulation holds: the rates of a part of the fluid,
//! given the particles within a few kernel supports of it (its halo), equal the rates of the
//! whole to the bit. This is what lets a run split over processes give the answers of one.
//!
//! Each case is built whole; then a second simulation is built from its own particles
//! (those on one side of a plane) and their halo, in shuffled storage order, with the same
//! walls; every own particle's acceleration, density rate and Shepard factor must match.

use bisph_core::dim::Vector;
use bisph_core::particles::PermuteScratch;
use bisph_core::Simulation;
use bisph_io::case::{build_simulation, load_case, CaseDim};
use glam::{DVec2, DVec3};
use std::collections::HashMap;
use std::path::PathBuf;

fn case(name: &str, overrides: &[&str]) -> bisph_io::case::LoadedCase {
    let path = PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .join("../../cases")
        .join(name);
    let overrides: Vec<String> = overrides.iter().map(|s| s.to_string()).collect();
    load_case(Some(&path), &overrides).unwrap()
}

/// A permutation of `0..n` from a fixed linear congruential sequence.
fn shuffled(n: usize) -> Vec<u32> {
    let mut order: Vec<u32> = (0..n as u32).collect();
    let mut state = 0x2545_f491_4f6c_dd1du64;
    for k in (1..n).rev() {
        state = state
            .wrapping_mul(6_364_136_223_846_793_005)
            .wrapping_add(1_442_695_040_888_963_407);
        order.swap(k, (state >> 33) as usize % (k + 1));
    }
    order
}

/// Builds, from the state of `whole`, the simulation of the whole fluid and that of the part
/// `x . axis < cut` (the median) with its halo of `halo` kernel supports, and checks that the
/// part's own particles have the rates of the whole. Returns how many particles were checked.
fn check_part<V: Vector>(whole: &Simulation<V>, axis: usize, halo: f64) -> usize {
    let fluid = &whole.fluid;
    let mut along: Vec<f64> = fluid.position.iter().map(|p| p.get(axis)).collect();
    along.sort_by(f64::total_cmp);
    let cut = along[along.len() / 2];
    let reach = cut + halo * whole.config.kernel.support;
    let kept: Vec<u32> = shuffled(fluid.len())
        .into_iter()
        .filter(|&i| fluid.position[i as usize].get(axis) < reach)
        .collect();
    assert!(kept.len() < fluid.len(), "the halo holds every particle");
    let mut part_fluid = fluid.clone();
    part_fluid.permute(&kept, &mut PermuteScratch::default());
    let rebuilt = |f| Simulation::new(whole.config.clone(), f, whole.walls.clone(), Vec::new());
    let all = rebuilt(fluid.clone());
    let part = rebuilt(part_fluid);
    let slot: HashMap<u32, usize> = all
        .fluid
        .id
        .iter()
        .enumerate()
        .map(|(k, &id)| (id, k))
        .collect();
    let mut checked = 0;
    for (k, &id) in part.fluid.id.iter().enumerate() {
        if part.fluid.position[k].get(axis) >= cut {
            continue;
        }
        let j = slot[&id];
        let (a, b) = (&all.fluid, &part.fluid);
        assert_eq!(
            a.acceleration[j].to_xyz().map(f64::to_bits),
            b.acceleration[k].to_xyz().map(f64::to_bits),
            "acceleration of particle {id}"
        );
        assert_eq!(
            a.density_rate[j].to_bits(),
            b.density_rate[k].to_bits(),
            "density rate of particle {id}"
        );
        assert_eq!(
            a.gamma[j].to_bits(),
            b.gamma[k].to_bits(),
            "gamma of particle {id}"
        );
        checked += 1;
    }
    assert!(
        checked > fluid.len() / 3,
        "only {checked} particles checked"
    );
    checked
}

/// Halo widths in kernel supports. A particle's sums reach one support; the wall pressures of
/// the energy-conserving walls and the vertex values of the semi-analytical walls are fluid
/// sums around wall points within a support of it, so those halos reach two supports, plus
/// an element's extent for the energy walls' quadrature.
const BI_HALO: f64 = 2.1;
const USAW_HALO: f64 = 2.1;
const ENERGY_HALO: f64 = 2.5;

fn built<V: CaseDim>(name: &str, overrides: &[&str]) -> Simulation<V> {
    build_simulation(&case(name, overrides)).unwrap()
}

fn advanced<V: CaseDim>(mut sim: Simulation<V>, steps: usize) -> Simulation<V> {
    for _ in 0..steps {
        sim.advance(None).unwrap();
    }
    sim
}

#[test]
fn energy_walls_in_a_breaking_dam() {
    let sim = built::<DVec2>("dam-break-2d.toml", &["resolution.dx=0.02"]);
    check_part(&advanced(sim, 300), 0, ENERGY_HALO);
}

#[test]
fn bi_walls_with_geometric_gamma_in_a_breaking_dam_3d() {
    let overrides = [
        "boundary=\"bi\"",
        "shepard=\"geometric\"",
        "resolution.dx=0.02",
    ];
    let sim = built::<DVec3>("dam-break-3d.toml", &overrides);
    check_part(&advanced(sim, 60), 0, BI_HALO);
}

#[test]
fn semi_analytical_walls() {
    // Periodic along x: cut along y.
    let sim = built::<DVec2>("usaw-still-water.toml", &[]);
    check_part(&sim, 1, USAW_HALO);
}

#[test]
fn periodic_flow_with_flux_forcing() {
    // Energy walls, periodic along x: cut along y.
    let sim = built::<DVec2>(
        "poiseuille-flux.toml",
        &["resolution.dx=0.025", "time.dt=2.5e-4"],
    );
    check_part(&advanced(sim, 50), 1, ENERGY_HALO);
}

#[test]
fn a_piston_under_the_midpoint_scheme() {
    let sim = built::<DVec2>("adiabatic-piston.toml", &[]);
    check_part(&sim, 0, ENERGY_HALO);
}

#[test]
fn a_free_floating_body() {
    let sim = built::<DVec2>("floating-box-2d.toml", &[]);
    check_part(&sim, 0, BI_HALO);
}
