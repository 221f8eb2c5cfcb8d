//! The classic boundary integrals' part of the continuity equation under the explicit scheme:
//! integrated over each drift as `rho *= gamma^n / gamma^{n+1}`, it makes a particle's
//! compression by the walls a function of where it is, so a particle that meets the walls
//! alone leaves them with the speed it came with, and at its rest density.

#[allow(dead_code)]
#[path = "support/split_runs.rs"]
mod split_runs;

use bisph_core::Simulation;
use glam::DVec2;
use split_runs::built_from_text;

/// One particle, alone in a closed box without gravity, sent from 0.05 m towards the box's
/// corner at `velocity`; classic walls with the geometric gamma, no bounce.
fn lone_particle(velocity: &str) -> Simulation<DVec2> {
    let text = r#"
name = "lone-particle"
dim = 2
boundary = "bi"
shepard = "geometric"
elastic_bounce = false
[fluid]
density = 1000.0
sound_speed = 10.0
gravity = [0.0, 0.0]
delta = 0.0
artificial_viscosity = 0.0
[resolution]
dx = 0.02
[time]
end = 10.0
[settle]
enabled = false
[[fluid_block]]
shape = "box"
min = [0.04, 0.04]
max = [0.06, 0.06]
[[wall]]
shape = "box"
min = [0.0, 0.0]
max = [1.0, 1.0]
"#;
    let velocity = format!("fluid_block.0.velocity={velocity}");
    built_from_text(text, &[velocity.as_str()])
}

#[test]
fn a_lone_particle_leaves_a_concave_corner_with_its_speed_and_rest_density() {
    // Into the corner, along the floor, and slowly: the last spends the longest in the
    // walls' reach.
    for velocity in ["[-0.2, -0.15]", "[-0.5, -0.02]", "[-0.05, -0.05]"] {
        let mut sim = lone_particle(velocity);
        let speed = sim.fluid.velocity[0].length();
        let rho0 = sim.config.eos.rho0();
        let reach = sim.config.kernel.support;
        let mut densest: f64 = 0.0;
        // Until it is out of the walls' reach again, moving away from them.
        let out_of_reach = |sim: &Simulation<DVec2>| {
            let (x, u) = (sim.fluid.position[0], sim.fluid.velocity[0]);
            x.min_element() > reach && u.x >= 0.0 && u.y >= 0.0
        };
        while !out_of_reach(&sim) {
            sim.advance(None).unwrap();
            densest = densest.max(sim.fluid.density[0]);
            assert!(
                sim.time < 10.0,
                "{velocity}: still at {}",
                sim.fluid.position[0]
            );
        }
        // The walls compressed it on the way in.
        assert!(densest > 1.001 * rho0, "{velocity}: densest {densest}");
        let out = sim.fluid.velocity[0].length();
        assert!(
            (out / speed - 1.0).abs() < 1e-3,
            "{velocity}: speed {speed} in, {out} out"
        );
        assert_eq!(sim.fluid.density[0], rho0, "{velocity}");
    }
}
