//! `bisph bench`: throughput suites: the explicit scheme on the built-in dam breaks, and the seed
//! papers' wall-bounded and implicit runs.
//!
//! Each configuration (dimension, particle count, `h/dx`, threads) runs in a child process of
//! its own, so that its peak memory is its own: the dam break is refined to about the asked
//! number of fluid particles, warmed up for three steps, then advanced a fixed number of
//! Verlet steps (one force evaluation per step, no output).
//!
//! Reported per configuration: particle-steps per second (over all timed steps, and from the
//! median step time, which other processes on a shared machine disturb less), pair interactions per second (fluid
//! pairs within the support, each counted from both sides, self included), ns per interaction,
//! the share of each phase (neighbour search, reordering, forces with their fused wall terms,
//! wall pressures, the rest of the integration) and the peak memory per particle (peak resident
//! set minus the resident set before the case was built, over the particle count).
//!
//! Suites: `quick` (2-D 20k), `standard` (2-D 20k and 200k, 3-D 100k), `full` (adds 2-D 1M and
//! 3-D 1M); each at `2h = 2.83 dx` (the neighbour count of DualSPHysics) and `h/dx = 2`, with
//! 1 and 2 threads. `--particles` and `--dim` replace the suite's sizes.
//!
//! Suite `shepard` (paper 2, table 1): the cost of the Shepard factor on the paper-2 still-water
//! tank (`bi` walls) with discrete and geometric gamma, against the energy-conserving walls
//! (no renormalisation, gamma = 1), at 10k and 50k particles.
//!
//! Suite `walls`: the seed papers' wall-bounded and implicit runs with their own settings:
//! SPHERIC test 2 (3-D, `bi` walls with geometric gamma, delta-SPH, Verlet) at 50k and 100k
//! particles, the Lobovsky dam break (2-D, energy walls, the semi-implicit midpoint scheme,
//! which evaluates the rates several times per step) at 50k and 200k, and the Apollo water
//! landing (3-D, energy walls, midpoint scheme with the capsule as a free body) at 62.5k.
//! Each is refined to the particle count from its shipped case file, early in the flow (the
//! first steps after release; the capsule starts with its lowest point on the water).

use bisph_core::decomposition::Transport;
use bisph_core::Simulation;
use bisph_io::case::{build_simulation, CaseDim};
use bisph_io::case::{parse_case, LoadedCase};
use glam::{DVec2, DVec3};
use serde_json::{json, Value};
use std::path::PathBuf;
use std::process::Command;
use std::time::Instant;

/// The built-in 3-D dam break (the 2-D one is `bisph_io::case::DEFAULT_CASE`).
const DAM_BREAK_3D: &str = include_str!("../../../cases/dam-break-3d.toml");
/// The seed papers' wall-bounded cases of the `walls` suite.
const SPHERIC_TEST2: &str = include_str!("../../../cases/spheric-test2.toml");
const LOBOVSKY: &str = include_str!("../../../cases/lobovsky-dam-break.toml");
const APOLLO: &str = include_str!("../../../cases/apollo.toml");

/// Water volumes of the two dam breaks: 0.6 x 0.3 m and 0.6 x 0.3 x 0.3 m.
const WATER_AREA_2D: f64 = 0.18;
const WATER_VOLUME_3D: f64 = 0.054;
/// Water area of paper 2's still-water tank, 0.9 x 0.092 m.
const TANK_AREA: f64 = 0.0828;
/// Water of SPHERIC test 2 (1.228 x 1 x 0.55 m) and of the Lobovsky dam break (0.6 x 0.3 m).
const SPHERIC_WATER: f64 = 1.228 * 0.55;
const LOBOVSKY_WATER: f64 = 0.18;
/// Water of the Apollo pool (16 x 16 x 8 m).
const APOLLO_WATER: f64 = 2048.0;
/// Height of the Apollo capsule's centre (its `translate`) that puts its lowest point on the
/// water surface (z = 8): `8 + R (1 - cos 12 deg)` with the heat shield's radius R = 4.491 m.
const APOLLO_TOUCHING: f64 = 8.098_139;

#[derive(Clone, Copy, Debug, clap::ValueEnum)]
pub enum Suite {
    /// 2-D, 20k particles.
    Quick,
    /// 2-D 20k and 200k, 3-D 100k.
    Standard,
    /// 2-D 20k, 200k and 1M, 3-D 100k and 1M.
    Full,
    /// Shepard factor cost on the still-water tank: discrete, geometric, none; 10k and 50k.
    Shepard,
    /// SPHERIC test 2 (3-D, bi + geometric) at 50k and 100k; Lobovsky (2-D, midpoint) at 50k
    /// and 200k; Apollo (3-D, midpoint, free body) at 62.5k.
    Walls,
}

/// The benchmarked case.
#[derive(Clone, Copy, Debug, PartialEq)]
enum BenchCase {
    /// The built-in dam break of the configuration's dimension.
    DamBreak,
    /// Paper 2's still-water tank with `bi` walls and discrete gamma.
    TankDiscrete,
    /// The same with geometric gamma.
    TankGeometric,
    /// The same tank with the energy-conserving walls (gamma = 1).
    TankEnergy,
    /// SPHERIC test 2 as shipped (3-D).
    SphericTest2,
    /// The Lobovsky dam break as shipped (2-D, midpoint).
    Lobovsky,
    /// The Apollo water landing as shipped (3-D, midpoint, free body).
    Apollo,
}

impl BenchCase {
    const ALL: [(BenchCase, &'static str); 7] = [
        (BenchCase::DamBreak, "dam-break"),
        (BenchCase::TankDiscrete, "tank-discrete"),
        (BenchCase::TankGeometric, "tank-geometric"),
        (BenchCase::TankEnergy, "tank-energy"),
        (BenchCase::SphericTest2, "spheric-test2"),
        (BenchCase::Lobovsky, "lobovsky"),
        (BenchCase::Apollo, "apollo"),
    ];

    /// The dimension of a case that has one of its own.
    fn own_dim(self) -> Option<u8> {
        match self {
            BenchCase::SphericTest2 | BenchCase::Apollo => Some(3),
            BenchCase::Lobovsky => Some(2),
            _ => None,
        }
    }

    fn name(self) -> &'static str {
        Self::ALL
            .iter()
            .find(|(c, _)| *c == self)
            .map_or("", |(_, n)| n)
    }

    fn parse(text: &str) -> Option<BenchCase> {
        Self::ALL.iter().find(|(_, n)| *n == text).map(|(c, _)| *c)
    }
}

#[derive(clap::Args)]
pub struct BenchArgs {
    /// Which set of configurations to run.
    #[arg(long, value_enum, default_value = "standard")]
    suite: Suite,
    /// Particle counts to run instead of the suite's (with `--dim`).
    #[arg(long, value_delimiter = ',')]
    particles: Vec<usize>,
    /// Dimension of the `--particles` runs.
    #[arg(long, default_value_t = 2, value_parser = clap::value_parser!(u8).range(2..=3))]
    dim: u8,
    /// Smoothing lengths over spacing (default: 1.415, i.e. 2h = 2.83 dx, and 2).
    #[arg(long, value_delimiter = ',', default_values_t = vec![1.415, 2.0])]
    h_over_dx: Vec<f64>,
    /// Thread counts to measure.
    #[arg(long, value_delimiter = ',', default_values_t = vec![1, 2])]
    threads: Vec<usize>,
    /// Timed steps per configuration (default: about 8 M particle-steps in 2-D, 2 M in 3-D,
    /// between 3 and 100).
    #[arg(long)]
    steps: Option<u64>,
    /// Skin of the explicit scheme's neighbour list as a fraction of the support (the case key
    /// `time.neighbour_skin`, the same default; 0 = search the cell grid at every step).
    #[arg(long, default_value_t = bisph_io::case::DEFAULT_NEIGHBOUR_SKIN)]
    neighbour_skin: f64,
    /// Runs of each configuration, interleaved (every configuration once, then again), so
    /// that a slow spell of a shared machine spreads over all of them; above one, a summary
    /// gives each configuration's median, lowest and highest pairs/s and the speed-up over
    /// the fewest threads, paired run by run.
    #[arg(long, default_value_t = 1, value_parser = clap::value_parser!(u32).range(1..))]
    repeat: u32,
    /// Pair interactions per second of another code on this machine (e.g. 55e6 for
    /// DualSPHysics on the 2-D dam break): the summary gives the ratio of the medians to it.
    #[arg(long, value_name = "PAIRS_PER_SECOND")]
    reference: Option<f64>,
    /// Also write the results as JSON to this file.
    #[arg(long)]
    json: Option<PathBuf>,
    /// Internal: run one configuration `case,dim,particles,h_over_dx,threads,steps[,skin]` in
    /// this process and print its result as JSON.
    #[arg(long, hide = true)]
    single: Option<String>,
}

impl BenchArgs {
    /// `true` for one configuration run in this process (`--single`).
    pub fn is_single(&self) -> bool {
        self.single.is_some()
    }
}

/// One configuration of the suite.
#[derive(Clone, Copy, Debug)]
struct Config {
    case: BenchCase,
    dim: u8,
    particles: usize,
    h_over_dx: f64,
    threads: usize,
    steps: u64,
    /// `time.neighbour_skin`.
    skin: f64,
}

impl Config {
    fn parse(text: &str) -> Result<Config, String> {
        let bad = || {
            format!(
                "--single expects case,dim,particles,h_over_dx,threads,steps[,skin], got {text:?}"
            )
        };
        let parts: Vec<&str> = text.split(',').collect();
        let (case, dim, particles, h, threads, steps, skin) = match parts[..] {
            [case, dim, particles, h, threads, steps] => {
                (case, dim, particles, h, threads, steps, "0")
            }
            [case, dim, particles, h, threads, steps, skin] => {
                (case, dim, particles, h, threads, steps, skin)
            }
            _ => return Err(bad()),
        };
        Ok(Config {
            case: BenchCase::parse(case).ok_or_else(bad)?,
            dim: dim.parse().map_err(|_| bad())?,
            particles: particles.parse().map_err(|_| bad())?,
            h_over_dx: h.parse().map_err(|_| bad())?,
            threads: threads.parse().map_err(|_| bad())?,
            steps: steps.parse().map_err(|_| bad())?,
            skin: skin.parse().map_err(|_| bad())?,
        })
    }

    fn encode(&self) -> String {
        format!(
            "{},{},{},{},{},{},{}",
            self.case.name(),
            self.dim,
            self.particles,
            self.h_over_dx,
            self.threads,
            self.steps,
            self.skin
        )
    }
}

pub fn bench(args: BenchArgs) -> Result<(), (u8, String)> {
    if let Some(single) = &args.single {
        let config = Config::parse(single).map_err(|e| (1, e))?;
        let transport = crate::launch::rank_transport()?;
        // Split over the ranks of a parallel launch, the first one reports.
        if let Some(result) = run_single(config, transport)? {
            println!("{result}");
        }
        return Ok(());
    }
    let dam = BenchCase::DamBreak;
    let sizes: Vec<(BenchCase, u8, usize)> = if !args.particles.is_empty() {
        args.particles.iter().map(|&n| (dam, args.dim, n)).collect()
    } else {
        match args.suite {
            Suite::Quick => vec![(dam, 2, 20_000)],
            Suite::Standard => vec![(dam, 2, 20_000), (dam, 2, 200_000), (dam, 3, 100_000)],
            Suite::Full => vec![
                (dam, 2, 20_000),
                (dam, 2, 200_000),
                (dam, 2, 1_000_000),
                (dam, 3, 100_000),
                (dam, 3, 1_000_000),
            ],
            Suite::Shepard => [10_000, 50_000]
                .into_iter()
                .flat_map(|n| {
                    [
                        BenchCase::TankDiscrete,
                        BenchCase::TankGeometric,
                        BenchCase::TankEnergy,
                    ]
                    .map(|c| (c, 2, n))
                })
                .collect(),
            Suite::Walls => vec![
                (BenchCase::SphericTest2, 3, 50_000),
                (BenchCase::SphericTest2, 3, 100_000),
                (BenchCase::Lobovsky, 2, 50_000),
                (BenchCase::Lobovsky, 2, 200_000),
                (BenchCase::Apollo, 3, 62_500),
            ],
        }
    };
    // Paper 2's tank and the walls suite's cases run at their own h/dx = 2.
    let own_h = matches!(args.suite, Suite::Shepard | Suite::Walls);
    let h_list = if own_h && args.particles.is_empty() {
        vec![2.0]
    } else {
        args.h_over_dx.clone()
    };
    let exe = std::env::current_exe().map_err(|e| (1, format!("cannot find bisph itself: {e}")))?;
    println!(
        "{:>14} {:>3} {:>6} {:>7} {:>9} {:>6} {:>12} {:>12} {:>12} {:>7} {:>5} {:>6} {:>6} {:>6} {:>6} {:>7} {:>5}",
        "case",
        "dim",
        "h/dx",
        "threads",
        "particles",
        "neigh",
        "part-steps/s",
        "median p-s/s",
        "pairs/s",
        "ns/pair",
        "nbr%",
        "reord%",
        "force%",
        "wall%",
        "integ%",
        "B/part",
        "evals"
    );
    let mut configs = Vec::new();
    for &(case, dim, particles) in &sizes {
        let budget = if dim == 2 { 8.0e6 } else { 2.0e6 };
        let steps = args
            .steps
            .unwrap_or(((budget / particles.max(1) as f64) as u64).clamp(3, 100));
        for &h_over_dx in h_list.iter() {
            for &threads in &args.threads {
                configs.push(Config {
                    case,
                    dim,
                    particles,
                    h_over_dx,
                    threads,
                    steps,
                    skin: args.neighbour_skin,
                });
            }
        }
    }
    let mut results = Vec::new();
    for _ in 0..args.repeat {
        for config in &configs {
            let row = run_child(&exe, config)?;
            print_row(&row);
            results.push(row);
        }
    }
    let summary = if args.repeat > 1 {
        summarise(&configs, &results, args.reference)
    } else {
        Vec::new()
    };
    if let Some(path) = args.json {
        let document = if summary.is_empty() {
            Value::Array(results)
        } else {
            json!({ "runs": results, "summary": summary })
        };
        let text = serde_json::to_string_pretty(&document).unwrap_or_default();
        std::fs::write(&path, text)
            .map_err(|e| (1, format!("cannot write {}: {e}", path.display())))?;
    }
    Ok(())
}

/// Runs one configuration in a child process and reads its JSON row.
fn run_child(exe: &std::path::Path, config: &Config) -> Result<Value, (u8, String)> {
    let output = Command::new(exe)
        .args(["bench", "--single", &config.encode()])
        .output()
        .map_err(|e| (1, format!("cannot start a benchmark process: {e}")))?;
    if !output.status.success() {
        return Err((
            3,
            format!(
                "benchmark {config:?} failed: {}",
                String::from_utf8_lossy(&output.stderr).trim()
            ),
        ));
    }
    serde_json::from_slice(&output.stdout)
        .map_err(|e| (1, format!("benchmark {config:?}: unreadable result: {e}")))
}

/// Per configuration over the repeated runs (`results` holds the runs in the order of
/// `configs`, repeat after repeat): median, lowest and highest pairs/s, the median's ratio to
/// `reference`, and the speed-up over the same case with the fewest threads, taken run by run
/// (the two configurations of one repeat ran next to each other) and summarised the same way.
/// Printed as a table; returned as JSON rows.
fn summarise(configs: &[Config], results: &[Value], reference: Option<f64>) -> Vec<Value> {
    let pairs = |row: &Value| {
        row["pair_interactions_per_second"]
            .as_f64()
            .unwrap_or(f64::NAN)
    };
    let runs_of = |k: usize| results.iter().skip(k).step_by(configs.len());
    let spread = |mut values: Vec<f64>| {
        let median = median_of(&mut values);
        (median, values[0], values[values.len() - 1])
    };
    println!(
        "\nover {} runs each: {:>14} {:>9} {:>3} {:>6} {:>7} {:>14} {:>12} {:>12} {:>8} {:>22}",
        results.len() / configs.len().max(1),
        "case",
        "particles",
        "dim",
        "h/dx",
        "threads",
        "median pairs/s",
        "lowest",
        "highest",
        "ratio",
        "speed-up (med lo hi)"
    );
    let mut rows = Vec::new();
    for (k, config) in configs.iter().enumerate() {
        let (median, lowest, highest) = spread(runs_of(k).map(pairs).collect());
        let ratio = reference.map(|r| median / r);
        // The same case with the fewest threads.
        let base = configs
            .iter()
            .enumerate()
            .filter(|(_, c)| {
                c.case == config.case
                    && c.dim == config.dim
                    && c.particles == config.particles
                    && c.h_over_dx == config.h_over_dx
            })
            .min_by_key(|(_, c)| c.threads)
            .map(|(b, _)| b)
            .unwrap_or(k);
        let speed_up = (base != k).then(|| {
            spread(
                runs_of(k)
                    .zip(runs_of(base))
                    .map(|(run, one)| pairs(run) / pairs(one))
                    .collect(),
            )
        });
        println!(
            "{:>34} {:>9} {:>3} {:>6.3} {:>7} {:>14.3e} {:>12.3e} {:>12.3e} {:>8} {:>22}",
            config.case.name(),
            config.particles,
            config.dim,
            config.h_over_dx,
            config.threads,
            median,
            lowest,
            highest,
            ratio.map_or("-".into(), |r| format!("{r:.2}")),
            speed_up.map_or("-".into(), |(m, lo, hi)| format!("{m:.2} {lo:.2} {hi:.2}")),
        );
        rows.push(json!({
            "case": config.case.name(),
            "dim": config.dim,
            "particles": config.particles,
            "h_over_dx": config.h_over_dx,
            "threads": config.threads,
            "runs": runs_of(k).count(),
            "pairs_per_second_median": median,
            "pairs_per_second_lowest": lowest,
            "pairs_per_second_highest": highest,
            "ratio_to_reference": ratio,
            "speed_up_median": speed_up.map(|s| s.0),
            "speed_up_lowest": speed_up.map(|s| s.1),
            "speed_up_highest": speed_up.map(|s| s.2),
        }));
    }
    rows
}

fn print_row(row: &Value) {
    let f = |key: &str| row[key].as_f64().unwrap_or(f64::NAN);
    let share = |key: &str| 100.0 * f(key) / f("seconds_steps").max(1e-12);
    println!(
        "{:>14} {:>3} {:>6.3} {:>7} {:>9} {:>6.1} {:>12.3e} {:>12.3e} {:>12.3e} {:>7.2} {:>5.1} {:>6.1} {:>6.1} {:>6.1} {:>6.1} {:>7.0} {:>5.2}",
        row["case"].as_str().unwrap_or("?"),
        f("dim"),
        f("h_over_dx"),
        f("threads"),
        f("particles"),
        f("neighbours_per_particle"),
        f("particle_steps_per_second"),
        f("particle_steps_per_second_median"),
        f("pair_interactions_per_second"),
        f("ns_per_interaction"),
        share("seconds_neighbour_search"),
        share("seconds_reorder"),
        share("seconds_forces"),
        share("seconds_wall_pressure"),
        share("seconds_integration"),
        f("peak_bytes_per_particle"),
        f("evaluations_per_step"),
    );
}

/// Runs one configuration in this process.
/// Runs one configuration in this process, or this rank's part of it when `transport` joins
/// the processes of a parallel launch; the result, on the first rank.
fn run_single(
    config: Config,
    transport: Option<Box<dyn Transport>>,
) -> Result<Option<Value>, (u8, String)> {
    let baseline = memory_kib("VmRSS:").unwrap_or(0);
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(config.threads)
        .build()
        .map_err(|e| (1, e.to_string()))?;
    let n = config.particles.max(100) as f64;
    let (text, dx) = match (config.case, config.dim) {
        (BenchCase::DamBreak, 2) => (bisph_io::case::DEFAULT_CASE, (WATER_AREA_2D / n).sqrt()),
        (BenchCase::DamBreak, _) => (DAM_BREAK_3D, (WATER_VOLUME_3D / n).cbrt()),
        (BenchCase::SphericTest2, _) => (SPHERIC_TEST2, (SPHERIC_WATER / n).cbrt()),
        (BenchCase::Lobovsky, _) => (LOBOVSKY, (LOBOVSKY_WATER / n).sqrt()),
        (BenchCase::Apollo, _) => (APOLLO, (APOLLO_WATER / n).cbrt()),
        _ => (bisph_validate::paper2::TANK, (TANK_AREA / n).sqrt()),
    };
    if let Some(d) = config.case.own_dim().filter(|&d| d != config.dim) {
        return Err((2, format!("{} runs in {d}-D only", config.case.name())));
    }
    let mut overrides = vec![
        format!("resolution.dx={dx}"),
        format!("resolution.h_over_dx={}", config.h_over_dx),
        "output.plots=false".into(),
        format!("time.neighbour_skin={}", config.skin),
    ];
    if !matches!(config.case, BenchCase::Lobovsky | BenchCase::Apollo) {
        overrides.push("time.integrator=\"verlet\"".into());
    }
    match config.case {
        BenchCase::DamBreak => {}
        BenchCase::TankDiscrete => overrides.push("shepard=\"discrete\"".into()),
        BenchCase::TankGeometric => overrides.push("shepard=\"geometric\"".into()),
        BenchCase::TankEnergy => overrides.push("boundary=\"energy\"".into()),
        BenchCase::SphericTest2 | BenchCase::Lobovsky => {}
        BenchCase::Apollo => {
            overrides.push(format!("wall.1.translate=[8.0, 8.0, {APOLLO_TOUCHING}]"))
        }
    }
    let loaded = parse_case("<bench>", text, &overrides).map_err(|e| (1, e.to_string()))?;
    pool.install(|| match config.dim {
        2 => measure::<DVec2>(&loaded, config, baseline, transport),
        _ => measure::<DVec3>(&loaded, config, baseline, transport),
    })
}

fn measure<V: CaseDim>(
    loaded: &LoadedCase,
    config: Config,
    baseline_kib: u64,
    transport: Option<Box<dyn Transport>>,
) -> Result<Option<Value>, (u8, String)> {
    let whole: Simulation<V> = build_simulation(loaded).map_err(|e| (1, e.to_string()))?;
    let mut sim = match transport {
        Some(transport) => {
            let part = Simulation::part_of(&whole, transport);
            drop(whole);
            part
        }
        None => whole,
    };
    for _ in 0..3 {
        sim.advance(None).map_err(|e| (3, e.to_string()))?;
    }
    let pairs_per_step = sim.count_pairs() as f64;
    sim.timings = Default::default();
    let traffic_before = sim.traffic().unwrap_or_default();
    let departed_before = sim.departed();
    let mut step_seconds = Vec::with_capacity(config.steps as usize);
    let mut evaluations = 0u64;
    for _ in 0..config.steps {
        let start = Instant::now();
        sim.advance(None).map_err(|e| (3, e.to_string()))?;
        step_seconds.push(start.elapsed().as_secs_f64());
        evaluations += u64::from(sim.last_iterations);
    }
    let seconds: f64 = step_seconds.iter().sum();
    let median = median_of(&mut step_seconds);
    let n = sim.fluid_count() as f64;
    let steps = config.steps as f64;
    let peak = memory_kib("VmHWM:")
        .unwrap_or(0)
        .saturating_sub(baseline_kib);
    let t = sim.timings;
    let pairs = pairs_per_step * steps / seconds;
    // Over the parts of a split run: the largest halo and traffic, the total handed over.
    let traffic = sim.traffic().unwrap_or_default();
    let exchanges = (traffic.exchanges - traffic_before.exchanges) as f64 / steps;
    let words = sim.max_over_parts((traffic.words_sent - traffic_before.words_sent) as f64);
    let exchange_seconds = sim.max_over_parts(traffic.seconds - traffic_before.seconds);
    let halo = sim.max_over_parts(sim.halo_len() as f64);
    let handed = sim.total_over_parts((sim.departed() - departed_before) as f64);
    let peak = sim.max_over_parts((peak * 1024) as f64);
    if sim.rank() != 0 {
        return Ok(None);
    }
    Ok(Some(json!({
        "case": match (config.case, config.dim) {
            (BenchCase::DamBreak, 2) => "dam-break-2d",
            (BenchCase::DamBreak, _) => "dam-break-3d",
            (other, _) => other.name(),
        },
        "dim": config.dim, "h_over_dx": config.h_over_dx, "threads": config.threads,
        "ranks": sim.parts(),
        "particles": n, "wall_elements": sim.walls.elements.len(), "steps": config.steps,
        "neighbours_per_particle": pairs_per_step / n,
        "particle_steps_per_second": n * steps / seconds,
        "pair_interactions_per_second": pairs, "ns_per_interaction": 1e9 / pairs,
        "seconds_per_step": seconds / steps,
        "seconds_per_step_median": median,
        "particle_steps_per_second_median": n / median,
        "seconds_neighbour_search": t.neighbours - t.reorder - t.handover,
        "seconds_reorder": t.reorder,
        "seconds_forces": t.rates - t.wall_pressure, "seconds_wall_pressure": t.wall_pressure,
        "seconds_integration": t.steps - t.neighbours - t.rates, "seconds_steps": t.steps,
        "seconds_handover": t.handover, "seconds_exchange_max": exchange_seconds,
        "exchanges_per_step": exchanges, "words_sent_per_step_max": words / steps,
        "halo_particles_max": halo, "particles_handed_over": handed,
        "rebalances": sim.rebalances(),
        "peak_bytes_per_particle": peak / n * sim.parts() as f64,
        "evaluations_per_step": evaluations as f64 / steps,
    })))
}

/// Median of the step times: on a shared machine, steps slowed by other processes move the
/// mean but not the median.
fn median_of(values: &mut [f64]) -> f64 {
    values.sort_by(f64::total_cmp);
    let k = values.len();
    match k {
        0 => f64::NAN,
        _ if k % 2 == 1 => values[k / 2],
        _ => 0.5 * (values[k / 2 - 1] + values[k / 2]),
    }
}

/// A `/proc/self/status` memory line (`VmRSS:`, `VmHWM:`), in KiB (Linux).
fn memory_kib(key: &str) -> Option<u64> {
    let status = std::fs::read_to_string("/proc/self/status").ok()?;
    let line = status.lines().find(|l| l.starts_with(key))?;
    line.split_whitespace().nth(1)?.parse().ok()
}
