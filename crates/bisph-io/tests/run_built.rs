//! A simulation built and settled by its caller, then run by `run_built`, writes the same
//! series as `run_case`, which builds and settles it itself.

use bisph_core::Simulation;
use bisph_io::case::build_simulation;
use bisph_io::parse_case;
use bisph_io::run::{run_built, run_case, settle_fresh, RunOptions};
use glam::DVec2;

const TANK: &str = r#"
name = "tank"
dim = 2
[fluid]
density = 1000.0
sound_speed = 20.0
gravity = [0.0, -9.81]
[resolution]
dx = 0.05
[time]
end = 0.05
[output]
vtk_interval = 0.0
series_interval = 0.005
plots = false
[settle]
enabled = true
[[fluid_block]]
shape = "box"
min = [0.0, 0.0]
max = [1.0, 0.5]
pressure = "hydrostatic"
[[wall]]
shape = "box"
min = [0.0, 0.0]
max = [1.0, 0.8]
open = ["+y"]
[[probe]]
name = "bottom"
kind = "wall_pressure"
position = [0.5, 0.0]
"#;

#[test]
fn a_caller_built_run_writes_the_series_of_a_whole_run() {
    let scratch = tempfile::Builder::new()
        .prefix("bisph-run-built-")
        .tempdir()
        .unwrap();
    let dir = scratch.path();
    let (whole, built) = (dir.join("whole"), dir.join("built"));
    let loaded = parse_case("<tank>", TANK, &[]).unwrap();
    let a = run_case(&loaded, &whole, &mut |_| {}).unwrap();
    let mut sim: Simulation<DVec2> = build_simulation(&loaded).unwrap();
    let settling = settle_fresh(&loaded, &mut sim, None, &mut |_| {}).unwrap();
    assert!(settling.is_some());
    let b = run_built(
        &loaded,
        &mut sim,
        settling,
        &built,
        &RunOptions::default(),
        &mut |_| {},
    )
    .unwrap();
    assert_eq!(a.steps, b.steps);
    assert!(a.steps > 0);
    assert_eq!(
        a.energy_total_final.to_bits(),
        b.energy_total_final.to_bits()
    );
    for file in [
        "energy.csv",
        "probes.csv",
        "forces.csv",
        "settling.json",
        "case.toml",
    ] {
        let read = |d: &std::path::Path| std::fs::read_to_string(d.join(file)).unwrap();
        let (a, b) = (read(&whole), read(&built));
        if file == "settling.json" {
            // Equal but for the wall-clock seconds the settling took.
            let steps = |t: &str| {
                t.lines()
                    .find(|l| l.contains("\"steps\""))
                    .map(String::from)
            };
            assert_eq!(steps(&a), steps(&b));
        } else {
            assert_eq!(a, b, "{file}");
        }
    }
}
