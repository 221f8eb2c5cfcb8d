//! A run split into parts, each a thread with its end of an in-process transport, gives the
//! bits of the whole run: the energy budget, the bodies' motion, the probes and the time step
//! at every step, and every particle's final state, for 1 to 4 parts.

// Shared with the MPI test, which uses all of it.
#[allow(dead_code)]
#[path = "support/split_runs.rs"]
mod split_runs;

use bisph_core::decomposition::InProcess;
use bisph_core::dim::Vector;
use bisph_core::Simulation;
use bisph_io::case::CaseDim;
use bisph_io::run::checkpoint::SimState;
use split_runs::{advance, SplitCase, Trace, SPLIT_CASES};

/// What one split run did besides its trace: particles handed between parts and halo
/// particles held at the end, summed over the parts, and the times the regions were cut
/// again.
struct Traffic {
    departed: u64,
    halo: usize,
    rebalances: u64,
}

/// `work` on each part of `whole` split into `parts` parts, each on its own thread; the
/// results by part.
fn on_parts<V: Vector, T: Send>(
    whole: &Simulation<V>,
    parts: usize,
    work: impl Fn(&mut Simulation<V>) -> T + Sync,
) -> Vec<T> {
    let ends = InProcess::connect(parts);
    std::thread::scope(|scope| {
        let runs: Vec<_> = ends
            .into_iter()
            .map(|end| {
                let work = &work;
                scope.spawn(move || work(&mut Simulation::part_of(whole, Box::new(end))))
            })
            .collect();
        runs.into_iter().map(|r| r.join().unwrap()).collect()
    })
}

/// The trace of `whole` split into `parts` parts, each on its own thread.
fn split_run<V: Vector>(whole: &Simulation<V>, parts: usize, steps: usize) -> (Trace, Traffic) {
    let runs = on_parts(whole, parts, |part| {
        let trace = advance(part, steps);
        (trace, part.departed(), part.halo_len(), part.rebalances())
    });
    let traffic = Traffic {
        departed: runs.iter().map(|r| r.1).sum(),
        halo: runs.iter().map(|r| r.2).sum(),
        rebalances: runs[0].3,
    };
    assert!(
        runs.iter().all(|r| r.3 == traffic.rebalances),
        "the parts cut alike"
    );
    let mut traces = runs.into_iter().map(|r| r.0);
    let first = traces.next().unwrap();
    for other in traces {
        assert!(other == first, "every part has the same trace");
    }
    (first, traffic)
}

/// Asserts that `trace` has the bits of `expected`, step by step, then at the end.
fn assert_same(trace: &Trace, expected: &Trace, run: &str) {
    for (step, (got, want)) in trace.steps.iter().zip(&expected.steps).enumerate() {
        assert_eq!(got, want, "{run}, step {}", step + 1);
    }
    assert_eq!(trace.particles.len(), expected.particles.len(), "{run}");
    assert!(
        trace.particles == expected.particles,
        "{run}: the final particle states differ"
    );
    assert_eq!(trace.totals, expected.totals, "{run}: totals");
}

/// Checks that the case split into 1 to 4 parts runs with the bits of the whole; returns the
/// particles handed between parts and the times the regions were cut again, for each split
/// run.
fn check<V: CaseDim>(case: &SplitCase) -> Vec<(u64, u64)> {
    check_counting_kept::<V>(case).0
}

/// [`check`], and the steps of the whole run that kept its neighbour lists with particles
/// moved past half the skin.
fn check_counting_kept<V: CaseDim>(case: &SplitCase) -> (Vec<(u64, u64)>, u64) {
    let mut whole = case.build::<V>();
    let expected = advance(&mut whole, case.steps);
    let start = case.build::<V>();
    let mut departed = Vec::new();
    for parts in 1..=4 {
        let (trace, traffic) = split_run(&start, parts, case.steps);
        departed.push((traffic.departed, traffic.rebalances));
        assert_eq!(traffic.halo > 0, parts > 1, "{parts} parts: halos");
        assert_same(&trace, &expected, &format!("{parts} parts"));
    }
    (departed, whole.timings.lists_kept_moved)
}

#[test]
fn a_breaking_dam_with_energy_walls() {
    // The collapsing column hands particles between parts, and drains the work of the
    // parts that held its top: on 3 and 4 parts the regions are cut again (on 2, the two
    // halves of the column keep their work within 10%).
    let (traffic, kept) = check_counting_kept::<glam::DVec2>(&SPLIT_CASES[0]);
    assert!(kept > 0, "no step kept the lists past half a skin");
    assert_eq!(traffic[0], (0, 0));
    let moved = traffic[1..].iter().all(|&(n, _)| n > 0);
    let cut = traffic[2..].iter().all(|&(_, cuts)| cuts > 0);
    assert!(moved && cut, "handed over, cut again: {traffic:?}");
}

#[test]
fn a_breaking_dam_in_3d_with_bi_walls_and_geometric_gamma() {
    let (traffic, kept) = check_counting_kept::<glam::DVec3>(&SPLIT_CASES[1]);
    assert!(kept > 0, "no step kept the lists past half a skin");
    assert!(
        traffic[1..].iter().all(|&(n, _)| n > 0),
        "handed over: {traffic:?}"
    );
}

#[test]
fn a_piston_under_the_midpoint_scheme() {
    check::<glam::DVec2>(&SPLIT_CASES[2]);
}

#[test]
fn a_free_floating_body() {
    check::<glam::DVec2>(&SPLIT_CASES[3]);
}

#[test]
fn periodic_flow_with_flux_forcing() {
    check::<glam::DVec2>(&SplitCase {
        name: "poiseuille-flux.toml",
        text: None,
        overrides: &["resolution.dx=0.025", "time.dt=2.5e-4"],
        steps: 50,
        three_d: false,
    });
}

#[test]
fn semi_analytical_walls() {
    check::<glam::DVec2>(&SplitCase {
        name: "usaw-still-water.toml",
        text: None,
        overrides: &[],
        steps: 20,
        three_d: false,
    });
}

/// A whole run's state, restored and split into 1 to 4 parts, continues with the bits of the
/// uninterrupted run: the checkpoint of a whole run resumes on any number of parts.
fn check_resumed<V: CaseDim>(case: &SplitCase, before: usize) {
    let mut whole = case.build::<V>();
    advance(&mut whole, before);
    let mut state = SimState::default();
    state.capture(&whole);
    let expected = advance(&mut whole, case.steps);
    let mut restored = case.build::<V>();
    state.restore(&mut restored).unwrap();
    assert!(
        restored.neighbour_list_origin().is_some(),
        "the whole is resumed with its Verlet list"
    );
    for parts in 1..=4 {
        let (trace, _) = split_run(&restored, parts, case.steps);
        assert_same(&trace, &expected, &format!("resumed on {parts} parts"));
    }
}

#[test]
fn particles_leaving_the_domain_are_removed_alike_on_any_number_of_parts() {
    let case = &SPLIT_CASES[4];
    let mut whole = case.build::<glam::DVec2>();
    advance(&mut whole, case.steps);
    assert_eq!(whole.removed, 80);
    check::<glam::DVec2>(case);
}

#[test]
fn a_run_that_lost_particles_resumes_on_any_number_of_parts() {
    // Two rows (40 particles) have left by step 300, two more by step 340.
    let case = SplitCase {
        steps: 40,
        ..SPLIT_CASES[4]
    };
    let mut whole = case.build::<glam::DVec2>();
    advance(&mut whole, 300);
    assert_eq!(whole.removed, 40);
    check_resumed::<glam::DVec2>(&case, 300);
}

#[test]
fn a_breaking_dam_resumed_while_its_lists_are_kept_past_half_a_skin() {
    // Resumed right after a step that kept the lists with particles moved past half the
    // skin: the restored list, grid and wall-distance bounds continue as the run did.
    let case = SplitCase {
        steps: 200,
        ..SPLIT_CASES[0]
    };
    let mut whole = case.build::<glam::DVec2>();
    let mut before = 0;
    while whole.timings.lists_kept_moved == 0 {
        advance(&mut whole, 1);
        before += 1;
        assert!(before < 2000, "no step kept the lists past half a skin");
    }
    check_resumed::<glam::DVec2>(&case, before);
}

#[test]
fn a_breaking_dam_resumed_on_any_number_of_parts() {
    let case = SplitCase {
        steps: 400,
        ..SPLIT_CASES[0]
    };
    check_resumed::<glam::DVec2>(&case, 500);
}

#[test]
fn a_floating_body_resumed_on_any_number_of_parts() {
    let case = SplitCase {
        steps: 30,
        ..SPLIT_CASES[3]
    };
    check_resumed::<glam::DVec2>(&case, 30);
}

/// A split run's state gathered from its parts ([`SimState::capture_whole`]) restores into a
/// whole simulation that continues with the bits of the uninterrupted run: a checkpoint of a
/// split run, resumed in one process.
#[test]
fn a_split_run_gathered_continues_whole() {
    let case = &SPLIT_CASES[0];
    let (before, after) = (500, 400);
    let mut whole = case.build::<glam::DVec2>();
    advance(&mut whole, before);
    let expected = advance(&mut whole, after);
    let start = case.build::<glam::DVec2>();
    for parts in [2, 3] {
        let states = on_parts(&start, parts, |part| {
            advance(part, before);
            let mut state = SimState::default();
            state.capture_whole(part);
            state
        });
        for state in &states {
            let mut resumed = case.build::<glam::DVec2>();
            state.restore(&mut resumed).unwrap();
            assert!(resumed.neighbour_list_origin().is_some(), "with its list");
            let trace = advance(&mut resumed, after);
            assert!(trace == expected, "gathered from {parts} parts");
        }
    }
}
