//! The midpoint scheme's pair lists only save time: a run that may not list its pairs (a
//! zero budget, as a large run on a small machine) filters the Verlet list's pairs at every
//! iteration and gives the same bits.

use bisph_core::Simulation;
use bisph_io::case::{build_simulation, load_case};
use glam::DVec2;
use std::path::PathBuf;

fn run(budget: Option<usize>) -> Simulation<DVec2> {
    let path =
        PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../../cases/lobovsky-dam-break.toml");
    let overrides = ["resolution.dx=0.01".to_string()];
    let mut sim: Simulation<DVec2> =
        build_simulation(&load_case(Some(&path), &overrides).unwrap()).unwrap();
    if let Some(b) = budget {
        sim.config.pair_list_budget = b;
    }
    for _ in 0..40 {
        sim.advance(None).unwrap();
    }
    sim
}

#[test]
fn listed_and_searched_pairs_give_the_same_bits() {
    let listed = run(None);
    let searched = run(Some(0));
    assert!(listed.last_iterations > 1, "the midpoint scheme iterates");
    assert_eq!(
        listed.energy().total.to_bits(),
        searched.energy().total.to_bits()
    );
    let bits = |s: &Simulation<DVec2>| {
        let f = &s.fluid;
        (0..f.len())
            .flat_map(|i| {
                [
                    f.position[i].x,
                    f.position[i].y,
                    f.velocity[i].x,
                    f.velocity[i].y,
                    f.density[i],
                ]
            })
            .map(f64::to_bits)
            .collect::<Vec<u64>>()
    };
    assert!(bits(&listed) == bits(&searched));
}
