//! The density diffusion's energy is booked: with the energy-conserving walls and the midpoint
//! scheme, `total` (which carries `diffusion_dissipation`) stays at its initial value to the
//! scheme's residue while delta-SPH removes compressible energy. Anderson's mixing of the
//! midpoint iterations (`midpoint.anderson_depth`) reaches the same converged steps as the
//! plain iteration in fewer rate evaluations, with the books as closed.

use bisph_core::energy::energy_scale;
use bisph_core::Simulation;
use bisph_io::case::build_simulation;
use bisph_io::parse_case;
use glam::DVec2;

/// A 2-D dam break (column 0.3 m x 0.2 m in a 0.8 m tank), energy walls, midpoint, delta-SPH,
/// no viscosity: the diffusion is the only term that is not conservative.
const DAM_BREAK: &str = r#"
name = "books"
dim = 2
boundary = "energy"
[fluid]
density = 1000.0
sound_speed = 14.0
gravity = [0.0, -9.81]
delta = 0.1
artificial_viscosity = 0.0
[resolution]
dx = 0.02
[time]
end = 1.0
integrator = "midpoint"
[settle]
enabled = false
[[fluid_block]]
shape = "box"
min = [0.0, 0.0]
max = [0.3, 0.2]
pressure = "hydrostatic"
[[wall]]
shape = "box"
min = [0.0, 0.0]
max = [0.8, 0.5]
open = ["+y"]
"#;

#[test]
fn the_density_diffusion_closes_the_midpoint_energy_books() {
    let loaded = parse_case("<books>", DAM_BREAK, &[]).unwrap();
    let mut sim: Simulation<DVec2> = build_simulation(&loaded).unwrap();
    let scale = energy_scale(&sim.fluid, &sim.config.eos, sim.config.gravity);
    let e0 = sim.energy().total;
    let mut drift: f64 = 0.0;
    while sim.time < 0.25 {
        sim.advance(None).unwrap();
        drift = drift.max((sim.energy().total - e0).abs() / scale);
    }
    let e = sim.energy();
    // Delta-SPH took a share of the energy that the books must carry.
    let booked = e.diffusion_dissipation / scale;
    assert!(booked > 1e-4, "diffusion booked {booked:e} of the scale");
    // Without the diffusion's column the books would be off by that share.
    let unbooked = (e.total - e.diffusion_dissipation - e0).abs() / scale;
    assert!(unbooked > 1e-4, "unbooked drift {unbooked:e}");
    // With it they close to the midpoint scheme's residue.
    assert!(
        drift < 1e-7,
        "energy drift {drift:e} over {} steps",
        sim.step
    );
}

#[test]
fn without_diffusion_nothing_is_booked() {
    let text = DAM_BREAK.replace("delta = 0.1", "delta = 0.0");
    let loaded = parse_case("<books>", &text, &[]).unwrap();
    let mut sim: Simulation<DVec2> = build_simulation(&loaded).unwrap();
    for _ in 0..20 {
        sim.advance(None).unwrap();
    }
    assert_eq!(sim.energy().diffusion_dissipation, 0.0);
    assert_eq!(sim.diffusion_power, 0.0);
}

/// The dam break without dissipation, midpoint iterations to a tolerance of `1e-9` of the
/// potential energy (at most 30, no relaxation) and Anderson's window `depth`, to
/// `t = 0.15 s`: the simulation, the rate evaluations it took and the largest energy drift
/// over the scale.
fn run_to_tolerance(depth: u32) -> (Simulation<DVec2>, u64, f64) {
    let depth = format!("midpoint.anderson_depth={depth}");
    let overrides = [
        "fluid.delta=0.0",
        "midpoint.max_iterations=30",
        "midpoint.tolerance=1e-9",
        "midpoint.tolerance_reference=\"potential\"",
        "midpoint.relax_increment=0.0",
        depth.as_str(),
    ]
    .map(String::from);
    let loaded = parse_case("<books>", DAM_BREAK, &overrides).unwrap();
    let mut sim: Simulation<DVec2> = build_simulation(&loaded).unwrap();
    let scale = energy_scale(&sim.fluid, &sim.config.eos, sim.config.gravity);
    let e0 = sim.energy().total;
    let (mut evaluations, mut drift) = (0, 0.0f64);
    while sim.time < 0.15 {
        sim.advance(None).unwrap();
        assert!(
            sim.last_iterations < 30,
            "step {} did not converge",
            sim.step
        );
        evaluations += u64::from(sim.last_iterations);
        drift = drift.max((sim.energy().total - e0).abs() / scale);
    }
    (sim, evaluations, drift)
}

#[test]
fn anderson_mixing_converges_to_the_same_steps_in_fewer_evaluations() {
    let (plain, plain_evaluations, plain_drift) = run_to_tolerance(0);
    let (mixed, mixed_evaluations, mixed_drift) = run_to_tolerance(3);
    assert_eq!(plain.step, mixed.step);
    assert!(
        20 * mixed_evaluations < 19 * plain_evaluations,
        "evaluations: plain {plain_evaluations}, Anderson {mixed_evaluations}"
    );
    // Both converge every step to the tolerance: the energy books close alike...
    assert!(
        plain_drift < 1e-7 && mixed_drift < 1e-7,
        "{plain_drift:e} {mixed_drift:e}"
    );
    // ... and the flows agree to the converged iterations' residue.
    let largest = plain
        .fluid
        .position
        .iter()
        .zip(&mixed.fluid.position)
        .map(|(a, b)| (*a - *b).length())
        .fold(0.0, f64::max);
    assert!(largest < 1e-6, "positions differ by {largest:e} m");
}
