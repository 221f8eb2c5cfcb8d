//! Anderson's mixing of the midpoint iterations (`midpoint.anderson_depth`) reaches the same
//! converged steps as the plain iteration in fewer rate evaluations, with the energy books
//! as closed.

use bisph_core::energy::energy_scale;
use bisph_core::Simulation;
use bisph_io::case::build_simulation;
use bisph_io::parse_case;
use glam::DVec2;

/// A 2-D dam break (column 0.3 m x 0.2 m in a 0.8 m tank), energy walls, midpoint with a
/// residue tolerance, no dissipation: the energy is conserved to the residue.
const DAM_BREAK: &str = r#"
name = "anderson"
dim = 2
boundary = "energy"
[fluid]
density = 1000.0
sound_speed = 14.0
gravity = [0.0, -9.81]
delta = 0.0
artificial_viscosity = 0.0
[resolution]
dx = 0.02
[time]
end = 1.0
integrator = "midpoint"
[midpoint]
max_iterations = 30
tolerance = 1e-9
tolerance_reference = "potential"
relax_increment = 0.0
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

/// Runs the dam break to `t = 0.15 s` with the given window; returns the simulation, the
/// rate evaluations it took and the largest energy drift over the scale.
fn run(depth: u32) -> (Simulation<DVec2>, u64, f64) {
    let text = DAM_BREAK.replace(
        "relax_increment = 0.0",
        &format!("relax_increment = 0.0\nanderson_depth = {depth}"),
    );
    let loaded = parse_case("<anderson>", &text, &[]).unwrap();
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
    let (plain, plain_evaluations, plain_drift) = run(0);
    let (mixed, mixed_evaluations, mixed_drift) = run(3);
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
