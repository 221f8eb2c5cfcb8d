//! `bisph bench`: throughput of the explicit scheme on the 2-D dam break.
//!
//! The built-in dam break is refined to about `--particles` fluid particles and advanced a
//! fixed number of steps (after warm-up, no output) at `h/dx = 2` and at support
//! `2h = 2.83 dx` (the neighbour count DualSPHysics uses), with 1 and 2 threads.
//! Reported: particle-steps per second, pair interactions per second (fluid pairs within the
//! support, each counted from both sides, self included), ns per interaction, the share of
//! each phase (neighbour search, reordering, rate evaluation with its wall terms, the rest of
//! the integration) and the resident memory per particle.

use bisph_core::Simulation;
use bisph_io::build::build_simulation;
use bisph_io::case::parse_case;
use glam::DVec2;
use serde_json::json;
use std::path::PathBuf;
use std::time::Instant;

#[derive(clap::Args)]
pub struct BenchArgs {
    /// Approximate number of fluid particles.
    #[arg(long, default_value_t = 100_000)]
    particles: usize,
    /// Timed steps per configuration.
    #[arg(long, default_value_t = 40)]
    steps: u64,
    /// Thread counts to measure.
    #[arg(long, value_delimiter = ',', default_values_t = vec![1, 2])]
    threads: Vec<usize>,
    /// Also write the results as JSON to this file.
    #[arg(long)]
    json: Option<PathBuf>,
}

/// One measured configuration.
struct Row {
    particles: f64,
    neighbours: f64,
    particle_steps: f64,
    pairs: f64,
    timings: bisph_core::simulation::PhaseTimes,
    bytes: f64,
}

pub fn bench(args: BenchArgs) -> Result<(), (u8, String)> {
    // Water column 0.6 x 0.3 m of the default case.
    let dx = (0.18 / args.particles.max(100) as f64).sqrt();
    let mut results = Vec::new();
    println!(
        "{:>6} {:>7} {:>9} {:>6} {:>12} {:>12} {:>7} {:>6} {:>6} {:>6} {:>6} {:>8}",
        "h/dx",
        "threads",
        "particles",
        "neigh",
        "part-steps/s",
        "pairs/s",
        "ns/pair",
        "nbr%",
        "reord%",
        "rates%",
        "integ%",
        "B/part"
    );
    for h_over_dx in [2.0, 2.83 / 2.0] {
        let overrides = vec![
            format!("resolution.dx={dx}"),
            format!("resolution.h_over_dx={h_over_dx}"),
            "output.plots=false".into(),
        ];
        let loaded = parse_case("<bench>", bisph_io::case::DEFAULT_CASE, &overrides)
            .map_err(|e| (1, e.to_string()))?;
        for &threads in &args.threads {
            let pool = rayon::ThreadPoolBuilder::new()
                .num_threads(threads)
                .build()
                .map_err(|e| (1, e.to_string()))?;
            let row = pool.install(|| -> Result<_, (u8, String)> {
                let mut sim: Simulation<DVec2> =
                    build_simulation(&loaded).map_err(|e| (1, e.to_string()))?;
                for _ in 0..3 {
                    sim.advance(None).map_err(|e| (3, e.to_string()))?;
                }
                let pairs_per_step = sim.count_pairs() as f64;
                sim.timings = Default::default();
                let start = Instant::now();
                for _ in 0..args.steps {
                    sim.advance(None).map_err(|e| (3, e.to_string()))?;
                }
                let seconds = start.elapsed().as_secs_f64();
                let n = sim.fluid.len() as f64;
                let steps = args.steps as f64;
                let bytes = resident_bytes().unwrap_or(0) as f64 / n;
                Ok(Row {
                    particles: n,
                    neighbours: pairs_per_step / n,
                    particle_steps: n * steps / seconds,
                    pairs: pairs_per_step * steps / seconds,
                    timings: sim.timings,
                    bytes,
                })
            })?;
            let Row {
                particles: n,
                neighbours,
                particle_steps: psps,
                pairs,
                timings: t,
                bytes,
            } = row;
            let share = |x: f64| 100.0 * x / t.steps.max(1e-12);
            let integration = t.steps - t.neighbours - t.rates;
            println!(
                "{:>6.3} {:>7} {:>9} {:>6.1} {:>12.3e} {:>12.3e} {:>7.2} {:>6.1} {:>6.1} {:>6.1} {:>6.1} {:>8.0}",
                h_over_dx,
                threads,
                n,
                neighbours,
                psps,
                pairs,
                1e9 / pairs,
                share(t.neighbours - t.reorder),
                share(t.reorder),
                share(t.rates),
                share(integration),
                bytes
            );
            results.push(json!({
                "case": "dam-break-2d", "h_over_dx": h_over_dx, "threads": threads, "particles": n,
                "neighbours_per_particle": neighbours, "particle_steps_per_second": psps,
                "pair_interactions_per_second": pairs, "ns_per_interaction": 1e9 / pairs,
                "steps": args.steps,
                "seconds_neighbour_search": t.neighbours - t.reorder, "seconds_reorder": t.reorder,
                "seconds_rates": t.rates, "seconds_integration": integration, "seconds_steps": t.steps,
                "resident_bytes_per_particle": bytes,
            }));
        }
    }
    if let Some(path) = args.json {
        let text = serde_json::to_string_pretty(&results).unwrap_or_default();
        std::fs::write(&path, text)
            .map_err(|e| (1, format!("cannot write {}: {e}", path.display())))?;
    }
    Ok(())
}

/// Resident memory of this process (Linux `/proc/self/status`), in bytes.
fn resident_bytes() -> Option<u64> {
    let status = std::fs::read_to_string("/proc/self/status").ok()?;
    let line = status.lines().find(|l| l.starts_with("VmRSS:"))?;
    let kb: u64 = line.split_whitespace().nth(1)?.parse().ok()?;
    Some(kb * 1024)
}
