//! Settling before `t = 0` (`[settle]`): a resting tank comes closer to rest, a dam-break
//! column is recognised as not at rest and keeps its start bit for bit, and cases settling
//! cannot apply to are refused with a named error.

use bisph_core::Simulation;
use bisph_io::case::build_simulation;
use bisph_io::case::LoadedCase;
use bisph_io::parse_case;
use bisph_io::run::settle::SettlingSummary;
use bisph_io::run::{settle_fresh, RunError};
use glam::DVec2;

/// Settles as `bisph run` does before `t = 0` (no checkpoints, no stop signal).
fn settle(
    loaded: &LoadedCase,
    sim: &mut Simulation<DVec2>,
) -> Result<Option<SettlingSummary>, RunError> {
    settle_fresh(loaded, sim, None, &mut |_| {})
}

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
end = 0.5
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
"#;

fn largest_acceleration(sim: &Simulation<DVec2>) -> f64 {
    sim.fluid
        .acceleration
        .iter()
        .map(|a| a.length())
        .fold(0.0, f64::max)
}

#[test]
fn settling_a_resting_tank_lowers_its_largest_acceleration_and_restarts_the_clock() {
    let loaded = parse_case("<tank>", TANK, &[]).unwrap();
    let mut sim: Simulation<DVec2> = build_simulation(&loaded).unwrap();
    let before = largest_acceleration(&sim);
    let report = settle(&loaded, &mut sim).unwrap().expect("settling is on");
    assert_ne!(report.outcome, "not_at_rest");
    assert!(report.steps > 0 && report.time > 0.0);
    let after = largest_acceleration(&sim);
    assert!(
        after < 0.2 * before,
        "largest |a| {before} before settling, {after} after"
    );
    assert_eq!(sim.time, 0.0);
    assert_eq!(sim.step, 0);
    assert_eq!(sim.wall_work, 0.0);
    assert!(sim.fluid.velocity.iter().all(|u| *u == DVec2::ZERO));
}

#[test]
fn a_dam_break_column_is_not_at_rest_and_keeps_its_start_bit_for_bit() {
    let dam = TANK.replace("max = [1.0, 0.5]", "max = [0.4, 0.5]");
    let loaded = parse_case("<dam>", &dam, &[]).unwrap();
    let mut settled: Simulation<DVec2> = build_simulation(&loaded).unwrap();
    let report = settle(&loaded, &mut settled).unwrap().unwrap();
    assert_eq!(report.outcome, "not_at_rest");
    let fresh: Simulation<DVec2> = build_simulation(&loaded).unwrap();
    assert_eq!(settled.fluid.position, fresh.fluid.position);
    assert_eq!(settled.fluid.density, fresh.fluid.density);
    assert_eq!(settled.fluid.acceleration, fresh.fluid.acceleration);
    assert_eq!(settled.fluid.density_rate, fresh.fluid.density_rate);
    assert_eq!(settled.time, 0.0);
}

#[test]
fn settling_is_off_when_the_case_says_so() {
    let loaded = parse_case("<tank>", TANK, &["settle.enabled=false".into()]).unwrap();
    let mut sim: Simulation<DVec2> = build_simulation(&loaded).unwrap();
    assert!(settle(&loaded, &mut sim).unwrap().is_none());
}

/// The tank without a `[settle]` table: what a case gets by default.
fn by_default(case: &str) -> String {
    case.replace("[settle]\nenabled = true\n", "")
}

#[test]
fn a_resting_tank_settles_by_default() {
    let loaded = parse_case("<tank>", &by_default(TANK), &[]).unwrap();
    let mut sim: Simulation<DVec2> = build_simulation(&loaded).unwrap();
    assert!(sim.rests_against_walls());
    let report = settle(&loaded, &mut sim)
        .unwrap()
        .expect("settles by default");
    assert_ne!(report.outcome, "not_at_rest");
}

#[test]
fn a_dam_break_column_or_a_moving_start_is_not_settled_by_default() {
    let dam = by_default(TANK).replace("max = [1.0, 0.5]", "max = [0.4, 0.5]");
    let loaded = parse_case("<dam>", &dam, &[]).unwrap();
    let mut sim: Simulation<DVec2> = build_simulation(&loaded).unwrap();
    assert!(!sim.rests_against_walls(), "the column's free face");
    assert!(settle(&loaded, &mut sim).unwrap().is_none());
    let moving = parse_case(
        "<tank>",
        &by_default(TANK),
        &["fluid_block.0.velocity=[1.0, 0.0]".into()],
    )
    .unwrap();
    let mut sim: Simulation<DVec2> = build_simulation(&moving).unwrap();
    assert!(settle(&moving, &mut sim).unwrap().is_none());
}

#[test]
fn settling_a_case_that_is_not_at_rest_is_a_named_error() {
    for (set, names) in [
        (
            "fluid_block.0.velocity=[1.0, 0.0]",
            "fluid_block[0].velocity",
        ),
        ("fluid.gravity=[0.0, 0.0]", "no gravity"),
        ("settle.tolerance=-1.0", "positive"),
    ] {
        let err = parse_case("<tank>", TANK, &[set.into()]).unwrap_err();
        let text = err.to_string();
        assert!(text.contains("settle."), "{set}: {text}");
        assert!(text.contains(names), "{set}: {text}");
    }
}
