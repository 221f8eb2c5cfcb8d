//! Runs of a case whole and split into parts, recorded bit for bit for comparison.

use bisph_core::dim::Vector;
use bisph_core::{EnergyBudget, Simulation};
use bisph_io::case::{build_simulation, load_case, CaseDim};
use bisph_io::parse_case;
use std::path::PathBuf;

/// The case `name` of the project's `cases` folder with `overrides`, built.
pub fn built<V: CaseDim>(name: &str, overrides: &[&str]) -> Simulation<V> {
    let path = PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .join("../../cases")
        .join(name);
    let overrides: Vec<String> = overrides.iter().map(|s| s.to_string()).collect();
    build_simulation(&load_case(Some(&path), &overrides).unwrap()).unwrap()
}

/// The case `text` with `overrides`, built.
pub fn built_from_text<V: CaseDim>(text: &str, overrides: &[&str]) -> Simulation<V> {
    let overrides: Vec<String> = overrides.iter().map(|s| s.to_string()).collect();
    build_simulation(&parse_case("<text>", text, &overrides).unwrap()).unwrap()
}

/// A block of water 0.4 m x 0.2 m (200 particles) falling freely, without walls, out of the
/// bottom of its domain 0.1 m below it: its rows leave one after the other from
/// `t = 0.15 s`, each particle removed as it leaves, until half of them have.
const FALLING_BLOCK: &str = r#"
name = "falling-block"
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
[settle]
enabled = false
[diagnostics]
removed_fraction_max = 0.5
[[fluid_block]]
shape = "box"
min = [0.0, 0.0]
max = [0.4, 0.2]
[domain]
min = [-0.3, -0.1]
max = [0.7, 0.4]
"#;

/// What a run is compared by, as bits: per step, the time, the energy budget, the bodies'
/// velocities, the probes and the count of removed particles; at the end, each particle's id, density, position and velocity
/// (in id order, gathered from every part).
#[derive(Debug, PartialEq)]
pub struct Trace {
    pub steps: Vec<(u64, Vec<u64>, Vec<u64>)>,
    pub particles: Vec<Vec<u64>>,
    /// At the end: the energy scale, the fluid mass, the particle and pair counts, the
    /// largest speed, the body loads.
    pub totals: Vec<u64>,
}

impl Trace {
    /// The trace as text, a line per step and per particle.
    pub fn lines(&self) -> Vec<String> {
        let steps = self.steps.iter().map(|s| format!("step {s:?}"));
        let particles = self.particles.iter().map(|p| format!("particle {p:?}"));
        let totals = std::iter::once(format!("totals {:?}", self.totals));
        steps.chain(particles).chain(totals).collect()
    }
}

fn bits(values: impl IntoIterator<Item = f64>) -> Vec<u64> {
    values.into_iter().map(f64::to_bits).collect()
}

fn budget_bits(e: &EnergyBudget) -> Vec<u64> {
    bits([
        e.kinetic,
        e.compressible,
        e.potential,
        e.wall_work,
        e.viscous_dissipation,
        e.forcing_work,
        e.diffusion_dissipation,
        e.removed,
        e.total,
    ])
}

/// Advances `sim` (whole, or a part: then every part must call it) `steps` steps and records
/// its trace.
pub fn advance<V: Vector>(sim: &mut Simulation<V>, steps: usize) -> Trace {
    let mut trace = Trace {
        steps: Vec::new(),
        particles: Vec::new(),
        totals: Vec::new(),
    };
    for _ in 0..steps {
        sim.advance(None).unwrap();
        let mut bodies = bits(sim.walls.dynamic_velocities());
        bodies.extend(bits(sim.sample_probes()));
        bodies.push(sim.removed);
        let budget = budget_bits(&sim.energy());
        trace.steps.push((sim.time.to_bits(), budget, bodies));
    }
    trace.totals = bits([
        sim.energy_scale(),
        sim.fluid_mass(),
        sim.fluid_count() as f64,
        sim.count_pairs() as f64,
        sim.max_speed(),
    ]);
    for (force, moment) in sim.body_loads() {
        trace.totals.extend(bits(force.to_xyz()));
        trace.totals.extend(bits(V::angular_to_vec(moment)));
    }
    let f = sim.gathered_fluid();
    for i in 0..f.len() {
        let mut record = vec![u64::from(f.id[i]), f.density[i].to_bits()];
        record.extend(bits(f.position[i].to_xyz()));
        record.extend(bits(f.velocity[i].to_xyz()));
        trace.particles.push(record);
    }
    trace
}

/// A case the split runs are checked on: file (or text), overrides, steps and dimension.
pub struct SplitCase {
    /// A file of the project's `cases` folder, or the name of `text`.
    pub name: &'static str,
    /// The case itself, when it is not a file of `cases`.
    pub text: Option<&'static str>,
    pub overrides: &'static [&'static str],
    pub steps: usize,
    pub three_d: bool,
}

impl SplitCase {
    /// The case built.
    pub fn build<V: CaseDim>(&self) -> Simulation<V> {
        match self.text {
            Some(text) => built_from_text(text, self.overrides),
            None => built(self.name, self.overrides),
        }
    }
}

/// The cases split runs must reproduce: the explicit scheme with energy walls (2-D) and with
/// classic walls and the geometric Shepard factor (3-D), long enough for particles to change
/// parts; the midpoint scheme with a piston and with a free body; particles removed as they
/// leave the domain (four rows of the falling block, 80 particles; the fifth row leaves at
/// step 346).
pub const SPLIT_CASES: [SplitCase; 5] = [
    SplitCase {
        name: "dam-break-2d.toml",
        text: None,
        overrides: &["resolution.dx=0.02"],
        steps: 1200,
        three_d: false,
    },
    SplitCase {
        name: "dam-break-3d.toml",
        text: None,
        overrides: &[
            "boundary=\"bi\"",
            "shepard=\"geometric\"",
            "resolution.dx=0.04",
        ],
        steps: 250,
        three_d: true,
    },
    SplitCase {
        name: "adiabatic-piston.toml",
        text: None,
        overrides: &[],
        steps: 40,
        three_d: false,
    },
    SplitCase {
        name: "floating-box-2d.toml",
        text: None,
        overrides: &["resolution.dx=0.04"],
        steps: 40,
        three_d: false,
    },
    SplitCase {
        name: "falling-block",
        text: Some(FALLING_BLOCK),
        overrides: &[],
        steps: 340,
        three_d: false,
    },
];
