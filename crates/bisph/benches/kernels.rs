//! Criterion micro-benchmarks of the hot kernels: the Wendland kernel, the cell grid rebuild
//! and one explicit step of the built-in 2-D and 3-D dam breaks (about 20k particles).
//! Run with `cargo bench -p bisph`; `bisph bench` measures whole-run throughput.

use bisph_core::neighbours::CellGrid;
use bisph_core::{Simulation, Wendland};
use bisph_io::case::parse_case;
use bisph_io::case::{build_simulation, CaseDim};
use criterion::{criterion_group, criterion_main, Criterion};
use glam::{DVec2, DVec3};
use std::hint::black_box;

const DAM_BREAK_3D: &str = include_str!("../../../cases/dam-break-3d.toml");

/// The dam break refined to `dx`, with explicit steps and no output.
fn dam_break<V: CaseDim>(text: &str, dx: f64) -> Simulation<V> {
    let overrides = vec![
        format!("resolution.dx={dx}"),
        "time.integrator=\"verlet\"".into(),
        "output.plots=false".into(),
    ];
    let loaded = parse_case("<bench>", text, &overrides).expect("built-in case parses");
    build_simulation(&loaded).expect("built-in case builds")
}

fn kernel(c: &mut Criterion) {
    let w = Wendland::new(0.01, 2);
    let radii: Vec<f64> = (0..1000).map(|k| 0.02 * k as f64 / 1000.0).collect();
    c.bench_function("wendland value + gradient, 1000 radii", |b| {
        b.iter(|| {
            radii
                .iter()
                .map(|&r| w.value(black_box(r)) + w.gradient_factor(black_box(r)))
                .sum::<f64>()
        })
    });
}

fn grid(c: &mut Criterion) {
    let sim: Simulation<DVec2> = dam_break(bisph_io::case::DEFAULT_CASE, 0.003);
    let points = sim.fluid.position.clone();
    let mut grid = CellGrid::new(sim.config.kernel.support);
    c.bench_function("cell grid rebuild, 2-D 20k", |b| {
        b.iter(|| grid.rebuild(black_box(&points)))
    });
}

fn steps(c: &mut Criterion) {
    let mut group = c.benchmark_group("explicit step");
    group.sample_size(20);
    let mut sim2: Simulation<DVec2> = dam_break(bisph_io::case::DEFAULT_CASE, 0.003);
    group.bench_function("2-D 20k", |b| {
        b.iter(|| sim2.advance(None).expect("stable"))
    });
    let mut sim3: Simulation<DVec3> = dam_break(DAM_BREAK_3D, 0.0139);
    group.bench_function("3-D 20k", |b| {
        b.iter(|| sim3.advance(None).expect("stable"))
    });
    group.finish();
}

criterion_group!(benches, kernel, grid, steps);
criterion_main!(benches);
