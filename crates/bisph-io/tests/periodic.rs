//! Periodic domains: with no driving force, mass and the total momentum along every periodic
//! axis are conserved to round-off, in 2-D and 3-D, alone and beside walls.

use bisph_core::Simulation;
use bisph_io::case::parse_case;
use bisph_io::case::{build_simulation, CaseDim};
use glam::{DVec2, DVec3};

fn pseudo_random(seed: &mut u64) -> f64 {
    *seed = seed
        .wrapping_mul(6364136223846793005)
        .wrapping_add(1442695040888963407);
    (*seed >> 11) as f64 / (1u64 << 53) as f64 - 0.5
}

/// Runs `steps` steps from a disturbed state; returns the largest change of the momentum
/// along each periodic axis over the run, relative to `sum m |u|`, and checks mass and count.
fn momentum_drift<V: CaseDim>(text: &str, periodic: &[usize], steps: usize, seed: u64) -> f64 {
    let loaded = parse_case("<periodic test>", text, &[]).unwrap();
    let mut sim: Simulation<V> = build_simulation(&loaded).unwrap();
    let mut s = seed;
    let c0 = sim.config.eos.c0();
    for i in 0..sim.fluid.len() {
        let mut u = V::ZERO;
        for k in 0..V::DIM {
            u.set(k, 0.05 * c0 * pseudo_random(&mut s));
        }
        sim.fluid.velocity[i] = u;
        sim.fluid.density[i] *= 1.0 + 0.002 * pseudo_random(&mut s);
    }
    let n = sim.fluid.len();
    let mass0: f64 = sim.fluid.mass.iter().sum();
    let momentum = |sim: &Simulation<V>| -> (Vec<f64>, f64) {
        let mut p = vec![0.0; V::DIM];
        let mut scale = 0.0;
        for i in 0..sim.fluid.len() {
            let m = sim.fluid.mass[i];
            for (k, pk) in p.iter_mut().enumerate() {
                *pk += m * sim.fluid.velocity[i].get(k);
            }
            scale += m * sim.fluid.velocity[i].length();
        }
        (p, scale)
    };
    let (p0, scale) = momentum(&sim);
    let mut worst: f64 = 0.0;
    let mut crossed = false;
    let first: Vec<V> = sim.fluid.position.clone();
    for _ in 0..steps {
        sim.advance(None).unwrap();
        let (p, _) = momentum(&sim);
        for &k in periodic {
            worst = worst.max((p[k] - p0[k]).abs() / scale);
        }
    }
    // Some particle went through the period (its position jumped by about a period).
    for (i, r) in sim.fluid.position.iter().enumerate() {
        let id = sim.fluid.id[i] as usize;
        if (*r - first[id]).length() > 0.5 {
            crossed = true;
        }
    }
    assert!(crossed, "the test must carry particles across the period");
    assert_eq!(sim.fluid.len(), n);
    let mass: f64 = sim.fluid.mass.iter().sum();
    assert_eq!(mass, mass0);
    worst
}

const CHANNEL_2D: &str = r#"
name = "periodic channel"
dim = 2
[fluid]
density = 1000.0
sound_speed = 10.0
artificial_viscosity = 0.0
[resolution]
dx = 0.05
[time]
end = 1.0
courant = 0.2
[domain]
min = [0.0, -0.1]
max = [1.0, 0.6]
periodic = ["x"]
[[fluid_block]]
shape = "box"
min = [0.0, 0.0]
max = [1.0, 0.5]
[[wall]]
shape = "box"
min = [0.0, 0.0]
max = [1.0, 0.5]
open = ["-x", "+x"]
"#;

#[test]
fn periodic_channel_2d_conserves_momentum_along_the_period() {
    let drift = momentum_drift::<DVec2>(CHANNEL_2D, &[0], 300, 1);
    assert!(drift < 1e-13, "x momentum drift {drift:e}");
}

#[test]
fn fully_periodic_2d_conserves_momentum() {
    let text = CHANNEL_2D
        .replace(
            "min = [0.0, -0.1]\nmax = [1.0, 0.6]",
            "min = [0.0, 0.0]\nmax = [1.0, 0.7]",
        )
        .replace("max = [1.0, 0.5]\n[[wall]]", "max = [1.0, 0.7]\n[[wall]]")
        .replace("periodic = [\"x\"]", "periodic = [\"x\", \"y\"]");
    let text = text.split("[[wall]]").next().unwrap().to_string();
    let drift = momentum_drift::<DVec2>(&text, &[0, 1], 300, 2);
    assert!(drift < 1e-13, "momentum drift {drift:e}");
}

#[test]
fn periodic_duct_3d_conserves_momentum_along_the_periods() {
    let text = r#"
name = "periodic duct"
dim = 3
[fluid]
density = 1000.0
sound_speed = 10.0
artificial_viscosity = 0.0
[resolution]
dx = 0.1
[time]
end = 1.0
[domain]
min = [0.0, -0.2, 0.0]
max = [1.3, 0.8, 1.3]
periodic = ["x", "z"]
[[fluid_block]]
shape = "box"
min = [0.0, 0.0, 0.0]
max = [1.3, 0.6, 1.3]
[[wall]]
shape = "box"
min = [0.0, 0.0, 0.0]
max = [1.3, 0.6, 1.3]
open = ["-x", "+x", "-z", "+z"]
"#;
    let drift = momentum_drift::<DVec3>(text, &[0, 2], 150, 3);
    assert!(drift < 1e-13, "momentum drift {drift:e}");
}

#[test]
fn a_period_shorter_than_three_supports_is_a_named_error() {
    let text = CHANNEL_2D.replace("max = [1.0, 0.6]", "max = [0.5, 0.6]");
    let err = parse_case("<periodic test>", &text, &[]).unwrap_err();
    assert_eq!(err.key, "domain.periodic");
    let err = parse_case(
        "<periodic test>",
        CHANNEL_2D,
        &["domain.periodic=[\"w\"]".to_string()],
    )
    .unwrap_err();
    assert_eq!(err.key, "domain.periodic");
}
