//! `mpirun -np K bisph run` writes the series of `bisph run` in one process, to the byte
//! (`energy.csv`, `forces.csv`, `probes.csv`, `bodies.csv`, `body_<name>.csv`, `midpoint.csv`),
//! for K = 2 to 4 (oversubscribed where the machine has fewer cores) and four cases, with the
//! fluid of each frame in K pieces; a split run killed after a checkpoint and resumed on
//! another number of ranks ends with the same series; unbound ranks without `--threads` share
//! the cores. Needs the `mpi` feature and Open MPI's `mpirun`.

mod common;

use std::path::Path;
use std::process::{Command, Output};
use std::time::{Duration, Instant};

fn case(name: &str) -> String {
    format!("{}/../../cases/{name}", env!("CARGO_MANIFEST_DIR"))
}

/// A fresh, empty folder for one run, removed when dropped.
fn folder(name: &str) -> common::Scratch {
    common::temp_dir("mpi-run", name)
}

/// `bisph ARGS` under `mpirun -np ranks` (one thread each), or alone for 1 rank.
fn command(ranks: usize, args: &[&str]) -> Command {
    let bisph = env!("CARGO_BIN_EXE_bisph");
    let mut c = match ranks {
        1 => Command::new(bisph),
        _ => {
            let mut c = Command::new("mpirun");
            c.args([
                "-np",
                &ranks.to_string(),
                "--oversubscribe",
                "--bind-to",
                "none",
            ])
            .arg(bisph);
            c
        }
    };
    c.args(args)
        .args(["--threads", "1", "--quiet"])
        // Containers often run tests as root, which Open MPI refuses unless told.
        .env("OMPI_ALLOW_RUN_AS_ROOT", "1")
        .env("OMPI_ALLOW_RUN_AS_ROOT_CONFIRM", "1");
    c
}

/// Kills (SIGKILL) `mpirun` and every rank whose command line names `word`, and waits until
/// none is left.
fn kill_all_naming(word: &str) {
    let started = Instant::now();
    loop {
        let pids: Vec<String> = std::fs::read_dir("/proc")
            .unwrap()
            .filter_map(|e| {
                let name = e.ok()?.file_name().to_string_lossy().into_owned();
                name.parse::<u32>().ok()?;
                let line = std::fs::read(format!("/proc/{name}/cmdline")).ok()?;
                let named = String::from_utf8_lossy(&line).contains(word);
                let own = name == std::process::id().to_string();
                (named && !own).then_some(name)
            })
            .collect();
        if pids.is_empty() {
            return;
        }
        assert!(
            started.elapsed() < Duration::from_secs(60),
            "cannot kill {pids:?}"
        );
        let _ = Command::new("sh")
            .args(["-c", &format!("kill -9 {}", pids.join(" "))])
            .status();
        std::thread::sleep(Duration::from_millis(50));
    }
}

fn run(ranks: usize, args: &[&str]) -> Output {
    command(ranks, args)
        .output()
        .unwrap_or_else(|e| panic!("mpirun could not be started ({e}): install Open MPI"))
}

/// The CSV series of `dir`, by name, with their bytes.
fn series(dir: &Path) -> Vec<(String, Vec<u8>)> {
    let mut all: Vec<(String, Vec<u8>)> = std::fs::read_dir(dir)
        .unwrap()
        .map(|e| e.unwrap().path())
        .filter(|p| p.extension().is_some_and(|e| e == "csv"))
        .map(|p| {
            let name = p.file_name().unwrap().to_string_lossy().into_owned();
            (name, std::fs::read(&p).unwrap())
        })
        .collect();
    all.sort();
    all
}

fn assert_same_series(whole: &Path, split: &Path, run: &str) {
    let (a, b) = (series(whole), series(split));
    assert!(a.len() >= 3, "{run}: {} series", a.len());
    let names = |s: &[(String, Vec<u8>)]| s.iter().map(|f| f.0.clone()).collect::<Vec<_>>();
    assert_eq!(names(&a), names(&b), "{run}");
    for (x, y) in a.iter().zip(&b) {
        assert!(x.1 == y.1, "{run}: {} differs", x.0);
    }
}

/// The dam break of the kill and resume.
const DAM: [&str; 4] = [
    "--set",
    "resolution.dx=0.02",
    "--set",
    "output.vtk_interval=0.1",
];

/// The cases of the comparison: the explicit scheme with energy walls (2-D) and with `bi`
/// walls and the geometric Shepard factor (3-D), a piston and a free body under the midpoint
/// scheme; each with its settings.
const CASES: [(&str, &[&str]); 4] = [
    (
        "dam-break-2d.toml",
        &[
            "--set",
            "resolution.dx=0.02",
            "--set",
            "time.end=0.2",
            "--set",
            "output.vtk_interval=0.1",
        ],
    ),
    (
        "dam-break-3d.toml",
        &[
            "--set",
            "boundary=\"bi\"",
            "--set",
            "shepard=\"geometric\"",
            "--set",
            "resolution.dx=0.04",
            "--set",
            "time.end=0.08",
            "--set",
            "output.vtk_interval=0.04",
        ],
    ),
    (
        "adiabatic-piston.toml",
        &["--set", "time.end=1.0", "--set", "output.vtk_interval=0.5"],
    ),
    (
        "floating-box-2d.toml",
        &[
            "--set",
            "resolution.dx=0.04",
            "--set",
            "time.end=0.1",
            "--set",
            "output.vtk_interval=0.05",
        ],
    ),
];

#[test]
fn a_run_split_over_ranks_writes_the_series_of_one_process() {
    for (name, settings) in CASES {
        let path = case(name);
        let dirs: Vec<common::Scratch> = (0..=4).map(|r| folder(&format!("{name}-{r}"))).collect();
        let out = |ranks: usize| dirs[ranks].to_path_buf();
        let mut lines = 0;
        for ranks in 1..=4 {
            let dir = out(ranks).display().to_string();
            let mut args = vec!["run", path.as_str(), "--out", dir.as_str()];
            args.extend(settings);
            let o = run(ranks, &args);
            let err = String::from_utf8_lossy(&o.stderr);
            assert!(o.status.success(), "{name} on {ranks} ranks: {err}");
            // The report of one process, from the first rank only.
            let stdout = String::from_utf8_lossy(&o.stdout);
            if ranks == 1 {
                lines = stdout.lines().count();
            }
            assert_eq!(stdout.lines().count(), lines, "{name}: {stdout}");
            if ranks > 1 {
                assert_same_series(&out(1), &out(ranks), &format!("{name}, {ranks} ranks"));
                let pieces = std::fs::read_dir(out(ranks).join("vtk"))
                    .unwrap()
                    .filter(|e| {
                        let n = e.as_ref().unwrap().file_name();
                        n.to_string_lossy().starts_with("fluid_000000_")
                    })
                    .count();
                assert_eq!(pieces, ranks, "{name}: pieces of the first frame");
            }
        }
    }
}

/// Unbound ranks share the cores: without `--threads`, each takes its share.
#[test]
fn unbound_ranks_share_the_cores() {
    let path = case("dam-break-2d.toml");
    let dir = folder("unbound");
    let out = dir.display().to_string();
    let o = Command::new("mpirun")
        .args(["-np", "2", "--oversubscribe", "--bind-to", "none"])
        .arg(env!("CARGO_BIN_EXE_bisph"))
        .args(["run", &path, "--out", &out, "--quiet"])
        .args(["--set", "time.end=0.01", "--set", "output.vtk_interval=0"])
        .env("OMPI_ALLOW_RUN_AS_ROOT", "1")
        .env("OMPI_ALLOW_RUN_AS_ROOT_CONFIRM", "1")
        .output()
        .unwrap_or_else(|e| panic!("mpirun could not be started ({e}): install Open MPI"));
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let summary = std::fs::read_to_string(dir.join("summary.json")).unwrap();
    let summary: serde_json::Value = serde_json::from_str(&summary).unwrap();
    let cores = std::thread::available_parallelism().map_or(1, |n| n.get());
    assert_eq!(summary["threads"], (cores / 2).max(1));
    assert_eq!(summary["ranks"], 2);
}

#[test]
fn a_split_run_killed_after_a_checkpoint_resumes_on_other_ranks_to_the_same_end() {
    let path = case("dam-break-2d.toml");
    let settings = ["--set", "time.end=0.3", "--checkpoint-steps", "25"];
    let whole = folder("whole");
    let dir = whole.display().to_string();
    let mut args = vec!["run", path.as_str(), "--out", dir.as_str()];
    args.extend(DAM);
    args.extend(settings);
    assert!(run(1, &args).status.success());
    let split = folder("killed");
    let dir = split.display().to_string();
    let mut args = vec!["run", path.as_str(), "--out", dir.as_str()];
    args.extend(DAM);
    args.extend(settings);
    // Killed as soon as the first checkpoint is there.
    let mut job = command(3, &args).spawn().expect("mpirun starts");
    let checkpoint = split.join("checkpoint.bin");
    let started = Instant::now();
    while !checkpoint.exists() {
        assert!(
            job.try_wait().unwrap().is_none(),
            "the run ended before its first checkpoint"
        );
        assert!(
            started.elapsed() < Duration::from_secs(120),
            "no checkpoint"
        );
        std::thread::sleep(Duration::from_millis(5));
    }
    kill_all_naming(&dir);
    job.wait().unwrap();
    let o = run(2, &["run", "--resume", &dir]);
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(o.status.success(), "resumed on 2 ranks: {err}");
    assert_same_series(&whole, &split, "killed on 3 ranks, resumed on 2");
    let summary = std::fs::read_to_string(split.join("summary.json")).unwrap();
    let summary: serde_json::Value = serde_json::from_str(&summary).unwrap();
    let resumed = summary["resumed_from_step"].as_u64().expect("resumed");
    assert!(resumed > 0 && resumed < summary["steps"].as_u64().unwrap());
    assert_eq!(summary["ranks"], 2);
}
