//! Particles that leave the domain are removed, their energy booked, up to
//! `diagnostics.removed_fraction_max` of the fluid; one more stops the run (exit 21).

#[allow(dead_code)]
#[path = "support/split_runs.rs"]
mod split_runs;

use bisph_core::energy::energy_scale;
use bisph_core::{SimError, Simulation};
use glam::DVec2;
use split_runs::{SplitCase, SPLIT_CASES};

const PARTICLES: u64 = 200;

/// The falling block of the split runs, with `overrides`.
fn falling_block(overrides: &'static [&'static str]) -> Simulation<DVec2> {
    SplitCase {
        overrides,
        ..SPLIT_CASES[4]
    }
    .build()
}

/// Advances until the run stops or reaches `t_end`; the error that stopped it, if any.
fn run_until(sim: &mut Simulation<DVec2>, t_end: f64) -> Option<SimError> {
    while sim.time < t_end {
        if let Err(e) = sim.advance(None) {
            return Some(e);
        }
    }
    None
}

#[test]
fn removing_a_particle_keeps_the_energy_total_to_round_off() {
    let mut sim = falling_block(&[]);
    for _ in 0..50 {
        sim.advance(None).unwrap();
    }
    // Three particles thrown out of the domain by hand, one through each open side.
    for (k, r) in [
        (7, DVec2::new(0.0, -0.2)),
        (90, DVec2::new(0.8, 0.1)),
        (150, DVec2::new(0.2, 0.5)),
    ] {
        sim.fluid.position[k] = r;
        sim.fluid.velocity[k] = DVec2::new(0.5, -2.0);
    }
    let before = sim.energy();
    assert!(sim.remove_leaving());
    let after = sim.energy();
    assert_eq!(sim.removed, 3);
    assert_eq!(sim.fluid.len() as u64, PARTICLES - 3);
    assert!(sim.fluid.position.iter().all(|&r| !sim.outside_domain(r)));
    // The removed energy is what the three particles carried, and the total is unchanged up
    // to the rounding of its terms.
    let carried = (before.kinetic + before.compressible + before.potential)
        - (after.kinetic + after.compressible + after.potential);
    let magnitude = before.kinetic.abs() + before.compressible.abs() + before.potential.abs();
    let ulps = 8.0 * f64::EPSILON * magnitude;
    assert!(
        (after.removed - carried).abs() <= ulps,
        "{} vs {carried}",
        after.removed
    );
    assert!(after.removed.abs() > 1e3 * ulps, "{}", after.removed);
    assert!(
        (after.total - before.total).abs() <= ulps,
        "total {} -> {}",
        before.total,
        after.total
    );
    // The run goes on from there.
    sim.advance(None).unwrap();
}

#[test]
fn the_midpoint_books_close_while_particles_leave() {
    let mut sim = falling_block(&["time.integrator=\"midpoint\""]);
    assert_eq!(sim.fluid.len() as u64, PARTICLES);
    let scale = energy_scale(&sim.fluid, &sim.config.eos, sim.config.gravity);
    let e0 = sim.energy().total;
    let mut last = e0;
    // The largest change of the total over a step, without and with a removal in it.
    let (mut plain, mut removing): (f64, f64) = (0.0, 0.0);
    while sim.removed < PARTICLES / 4 {
        let before = sim.removed;
        sim.advance(None).unwrap();
        let total = sim.energy().total;
        let jump = (total - last).abs() / scale;
        if sim.removed > before {
            removing = removing.max(jump);
        } else {
            plain = plain.max(jump);
        }
        last = total;
        assert_eq!(sim.fluid.len() as u64 + sim.removed, PARTICLES);
    }
    let e = sim.energy();
    assert!(
        sim.fluid.position.iter().all(|r| r.y >= -0.1),
        "every particle left inside the domain"
    );
    let mut ids = sim.fluid.id.clone();
    ids.sort_unstable();
    ids.dedup();
    assert_eq!(ids.len(), sim.fluid.len(), "distinct ids");
    // The removed particles carried energy that the books must hold.
    let unbooked = (e.total - e.removed - e0).abs() / scale;
    assert!(unbooked > 1e-2, "unbooked drift {unbooked:e}");
    // With it, a step that removes particles changes the total no more than the scheme's
    // residue changes it in the other steps (about 1e-8 of the scale here).
    assert!(plain < 1e-7, "largest change in a step {plain:e}");
    assert!(
        removing <= plain,
        "a removal step changed the total by {removing:e}, the others by up to {plain:e}"
    );
    let drift = (e.total - e0).abs() / scale;
    assert!(drift < 1e-6, "energy drift {drift:e}");
}

#[test]
fn one_particle_more_than_allowed_stops_the_run() {
    let mut sim = falling_block(&[]);
    assert_eq!(sim.config.max_removed, PARTICLES / 2);
    let e = run_until(&mut sim, 1.0).expect("the run stops");
    let SimError::LeftDomain { position, .. } = e else {
        panic!("stopped by {e}");
    };
    assert!(position[1] < -0.1, "{position:?}");
    // The step that stopped removed nothing: those outside now would exceed the allowance.
    let outside = sim.fluid.position.iter().filter(|r| r.y < -0.1).count() as u64;
    assert!(outside > 0 && sim.removed <= PARTICLES / 2);
    assert!(
        sim.removed + outside > PARTICLES / 2,
        "{} + {outside}",
        sim.removed
    );
    assert_eq!(sim.fluid.len() as u64 + sim.removed, PARTICLES);
}

#[test]
fn with_no_allowance_the_first_particle_to_leave_stops_the_run() {
    let mut sim = falling_block(&["diagnostics.removed_fraction_max=0"]);
    assert_eq!(sim.config.max_removed, 0);
    let e = run_until(&mut sim, 1.0).expect("the run stops");
    assert!(matches!(e, SimError::LeftDomain { .. }), "{e}");
    assert_eq!((sim.removed, sim.energy().removed), (0, 0.0));
    assert_eq!(sim.fluid.len() as u64, PARTICLES);
}

#[test]
fn the_last_particle_is_never_removed() {
    let sim = falling_block(&["diagnostics.removed_fraction_max=1"]);
    assert_eq!(sim.config.max_removed, PARTICLES - 1);
}
