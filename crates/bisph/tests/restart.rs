//! Checkpoint and restart: runs killed with SIGKILL at seeded random points (and one stopped
//! with SIGTERM), resumed with `bisph run --resume`, must leave outputs byte-identical to an
//! uninterrupted run: every CSV series, the `.pvd` indices and every VTK frame. Damaged and
//! foreign checkpoints are refused.

mod common;
use common::cases_dir;

use std::path::Path;
use std::process::{Child, Command, Output, Stdio};
use std::time::{Duration, Instant};

fn exe() -> Command {
    Command::new(env!("CARGO_BIN_EXE_bisph"))
}

fn temp_dir(name: &str) -> common::Scratch {
    common::temp_dir("restart", name)
}

/// A small seeded generator (64-bit LCG, top bits).
struct Lcg(u64);

impl Lcg {
    fn below(&mut self, n: u64) -> u64 {
        self.0 = self
            .0
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        (self.0 >> 33) % n.max(1)
    }
}

struct Case {
    name: &'static str,
    file: &'static str,
    sets: &'static [&'static str],
    /// A file with one row per step, polled to pick kill points.
    per_step: &'static str,
    checkpoint_steps: &'static str,
}

const PISTON: Case = Case {
    name: "piston",
    file: "adiabatic-piston.toml",
    sets: &[
        "resolution.dx=0.066",
        "resolution.h_over_dx=2.0",
        "time.end=2.0",
        "output.vtk_interval=0.4",
        "output.plots=false",
    ],
    per_step: "midpoint.csv",
    checkpoint_steps: "6",
};

const DAM_BREAK: Case = Case {
    name: "dam",
    file: "dam-break-2d.toml",
    sets: &[
        "resolution.dx=0.04",
        "time.end=0.25",
        "output.vtk_interval=0.05",
        "output.series_interval=0",
        "output.plots=false",
    ],
    per_step: "energy.csv",
    checkpoint_steps: "9",
};

const DAM_BREAK_3D: Case = Case {
    name: "dam3d",
    file: "dam-break-3d.toml",
    sets: &[
        "resolution.dx=0.04",
        "time.end=0.1",
        "output.vtk_interval=0.05",
        "output.series_interval=0",
        "output.plots=false",
    ],
    per_step: "energy.csv",
    checkpoint_steps: "5",
};

/// The dam break's water thrown up out of its open tank: from step 353 of 644, particles are
/// removed as they leave the domain (37 in all).
const SPLASH: Case = Case {
    name: "splash",
    file: "dam-break-2d.toml",
    sets: &[
        "resolution.dx=0.04",
        "time.end=0.3",
        "wall.0.open=[\"+y\"]",
        "fluid_block.0.velocity=[0.0, 5.0]",
        "diagnostics.removed_fraction_max=0.5",
        "output.vtk_interval=0.05",
        "output.series_interval=0",
        "output.plots=false",
    ],
    per_step: "energy.csv",
    checkpoint_steps: "9",
};

const POISEUILLE: Case = Case {
    name: "poiseuille",
    file: "poiseuille-flux.toml",
    sets: &[
        "time.end=0.08",
        "output.vtk_interval=0.04",
        "output.series_interval=0",
        "output.plots=false",
    ],
    per_step: "flux.csv",
    checkpoint_steps: "7",
};

/// A free rigid body (3 degrees of freedom, midpoint iterations): its attitude, velocities and
/// accelerations are part of the checkpoint; `body_box.csv` resumes like the other series.
const FLOATING: Case = Case {
    name: "floating",
    file: "floating-box-2d.toml",
    sets: &[
        "resolution.dx=0.05",
        "time.end=0.3",
        "output.vtk_interval=0.1",
        "output.series_interval=0",
        "output.plots=false",
    ],
    per_step: "body_box.csv",
    checkpoint_steps: "7",
};

/// The same, staggered coupling: the body moves through a step with the load of the previous
/// one, held in its stored accelerations.
const FLOATING_STAGGERED: Case = Case {
    name: "floating-staggered",
    sets: &[
        "resolution.dx=0.05",
        "time.end=0.3",
        "output.vtk_interval=0.1",
        "output.series_interval=0",
        "output.plots=false",
        "body.0.free.coupling=\"staggered\"",
    ],
    ..FLOATING
};

/// The same under explicit Verlet (the stored accelerations give the first half kick).
const FLOATING_VERLET: Case = Case {
    name: "floating-verlet",
    sets: &[
        "resolution.dx=0.05",
        "time.end=0.3",
        "output.vtk_interval=0.1",
        "output.series_interval=0",
        "output.plots=false",
        "time.integrator=\"verlet\"",
    ],
    checkpoint_steps: "5",
    ..FLOATING
};

/// 3-D: a box with 6 degrees of freedom thrown tumbling into a tank (quaternion attitude,
/// body-axes angular velocity and acceleration).
const TUMBLING_3D: Case = Case {
    name: "tumbling3d",
    file: "../crates/bisph/tests/data/tumbling-box-3d.toml",
    sets: &[],
    per_step: "body_box.csv",
    checkpoint_steps: "4",
};

/// Semi-analytical walls (paper 3) with gamma integrated in time (eq 4): gamma and its
/// gradient are particle state that the checkpoint carries.
const USAW: Case = Case {
    name: "usaw",
    file: "usaw-still-water.toml",
    sets: &[
        "resolution.dx=0.1",
        "time.end=0.3",
        "output.vtk_interval=0.1",
        "output.series_interval=0",
        "output.plots=false",
    ],
    per_step: "energy.csv",
    checkpoint_steps: "6",
};

/// The same with densities by summation (paper 3, eq 84): the per-particle offsets `C_i` are
/// integrated state too.
const USAW_SUMMATION: Case = Case {
    name: "usaw-summation",
    sets: &[
        "resolution.dx=0.1",
        "time.end=0.3",
        "output.vtk_interval=0.1",
        "output.series_interval=0",
        "output.plots=false",
        "usaw.continuity=\"summation\"",
        "usaw.density_power=1",
    ],
    ..USAW
};

fn fresh_args(case: &Case, out: &Path) -> Vec<String> {
    let mut a = vec![
        "run".to_string(),
        cases_dir().join(case.file).display().to_string(),
        "--out".into(),
        out.display().to_string(),
        "--quiet".into(),
        "--threads".into(),
        "1".into(),
        "--checkpoint-steps".into(),
        case.checkpoint_steps.into(),
    ];
    for s in case.sets {
        a.push("--set".into());
        a.push(s.to_string());
    }
    a
}

fn resume_args(case: &Case, out: &Path, threads: &str) -> Vec<String> {
    [
        "run",
        "--resume",
        &out.display().to_string(),
        "--quiet",
        "--threads",
        threads,
        "--checkpoint-steps",
        case.checkpoint_steps,
    ]
    .map(String::from)
    .to_vec()
}

fn run_to_end(args: &[String]) -> Output {
    let out = exe().args(args).output().expect("bisph runs");
    assert!(
        out.status.success(),
        "{args:?}: {}",
        String::from_utf8_lossy(&out.stderr)
    );
    out
}

fn lines(path: &Path) -> usize {
    std::fs::read(path)
        .map(|b| b.iter().filter(|&&c| c == b'\n').count())
        .unwrap_or(0)
}

/// Waits until `file` has more than `rows` lines or the child ends; returns whether it was
/// still running (and then kills it with SIGKILL).
fn kill_after(child: &mut Child, file: &Path, rows: usize) -> bool {
    let start = Instant::now();
    loop {
        if child.try_wait().unwrap().is_some() {
            return false;
        }
        if lines(file) > rows || start.elapsed() > Duration::from_secs(30) {
            child.kill().unwrap(); // SIGKILL on Unix
            child.wait().unwrap();
            return true;
        }
        std::thread::sleep(Duration::from_millis(1));
    }
}

/// Every output of a finished run, by relative path (`summary.json` and plots aside: they hold
/// wall-clock times).
fn outputs(dir: &Path) -> Vec<(String, Vec<u8>)> {
    let mut files = Vec::new();
    for sub in ["", "vtk"] {
        let d = dir.join(sub);
        for entry in std::fs::read_dir(&d).unwrap() {
            let path = entry.unwrap().path();
            let name = path.file_name().unwrap().to_string_lossy().to_string();
            let keep = name.ends_with(".csv")
                || name.ends_with(".pvd")
                || name.ends_with(".vtu")
                || name == "case.toml";
            if path.is_file() && keep {
                files.push((format!("{sub}/{name}"), std::fs::read(&path).unwrap()));
            }
        }
    }
    files.sort();
    files
}

fn compare(reference: &Path, resumed: &Path, what: &str) {
    let (a, b) = (outputs(reference), outputs(resumed));
    let names = |v: &[(String, Vec<u8>)]| v.iter().map(|f| f.0.clone()).collect::<Vec<_>>();
    assert_eq!(names(&a), names(&b), "{what}: different output files");
    for ((name, x), (_, y)) in a.iter().zip(&b) {
        assert!(x == y, "{what}: {name} differs from the uninterrupted run");
    }
    assert!(
        !resumed.join("checkpoint.bin").exists(),
        "{what}: a finished run removes its checkpoint"
    );
}

/// Kills `chains` runs of `case` `kills_per_chain` times each at seeded random steps, resumes
/// each to the end and compares with an uninterrupted run. Returns the number of kills that hit
/// a running process.
fn kill_resume_compare(
    case: &Case,
    seed: u64,
    chains: usize,
    kills_per_chain: usize,
) -> (usize, usize) {
    let reference = temp_dir(&format!("{}-reference", case.name));
    run_to_end(&fresh_args(case, &reference));
    let total = lines(&reference.join(case.per_step));
    assert!(total > 30, "{}: {total} rows", case.name);
    let mut rng = Lcg(seed);
    let (mut kills, mut resumes) = (0, 0);
    for chain in 0..chains {
        let dir = temp_dir(&format!("{}-chain{chain}", case.name));
        let mut args = fresh_args(case, &dir);
        for k in 0..kills_per_chain {
            let rows = lines(&dir.join(case.per_step));
            let target =
                rows + 1 + rng.below((total.saturating_sub(rows) as u64).max(2) * 2 / 3) as usize;
            let mut child = exe()
                .args(&args)
                .stdout(Stdio::null())
                .stderr(Stdio::null())
                .spawn()
                .unwrap();
            if kill_after(&mut child, &dir.join(case.per_step), target) {
                kills += 1;
            }
            // Resume from here on; without a checkpoint yet, start afresh.
            args = if dir.join("checkpoint.bin").exists() {
                resumes += 1;
                // Alternate thread counts: a resumed run must not depend on them either.
                resume_args(case, &dir, if (chain + k) % 2 == 0 { "2" } else { "1" })
            } else {
                fresh_args(case, &dir)
            };
        }
        run_to_end(&args);
        compare(&reference, &dir, &format!("{} chain {chain}", case.name));
    }
    (kills, resumes)
}

/// Midpoint integrator with a piston (its state, the stretching walls, the iteration history)
/// and Verlet on the dam break (VTK frames included): 24 seeded SIGKILLs in all.
#[test]
fn killed_runs_resume_bit_identically() {
    let (piston, piston_resumes) = kill_resume_compare(&PISTON, 0x5eed_0001, 4, 3);
    let (dam, dam_resumes) = kill_resume_compare(&DAM_BREAK, 0x5eed_0002, 4, 3);
    eprintln!(
        "SIGKILLs that hit a running process: piston {piston}, dam break {dam}; \
         resumed from a checkpoint: {piston_resumes} and {dam_resumes} times"
    );
    assert!(piston_resumes >= 6 && dam_resumes >= 6);
    // A kill can miss only when a run finishes before its kill point.
    assert!(
        piston + dam >= 20,
        "only {} kills hit a running process",
        piston + dam
    );
}

/// 3-D: quadrilateral elements, a 3-D cell grid; two SIGKILLs, resumed on two threads.
#[test]
fn killed_3d_run_resumes_bit_identically() {
    let (kills, resumes) = kill_resume_compare(&DAM_BREAK_3D, 0x5eed_0003, 1, 2);
    eprintln!("3-D: {kills} SIGKILLs, {resumes} resumes");
    assert!(resumes >= 1);
}

/// Particles removed as they leave the domain: the count and their energy are part of the
/// checkpoint, and the fluid arrays it saves lack them.
#[test]
fn killed_run_that_loses_particles_resumes_bit_identically() {
    let (kills, resumes) = kill_resume_compare(&SPLASH, 0x5eed_000b, 2, 2);
    eprintln!("splash: {kills} SIGKILLs, {resumes} resumes");
    assert!(resumes >= 2);
}

/// Periodic flux-driven Poiseuille flow with viscosity (paper 3, eq 63): the controller's
/// memory, the driving force and the viscous and forcing energy books are part of the
/// checkpoint; `flux.csv` resumes like the other series.
#[test]
fn killed_flux_run_resumes_bit_identically() {
    let (kills, resumes) = kill_resume_compare(&POISEUILLE, 0x5eed_0004, 2, 2);
    eprintln!("poiseuille-flux: {kills} SIGKILLs, {resumes} resumes");
    assert!(resumes >= 2);
}

/// Free rigid bodies, 2-D (iterated, staggered, Verlet) and 3-D: 15 seeded SIGKILLs; the
/// body state and `body_box.csv` resume bit-identically.
#[test]
fn killed_free_body_runs_resume_bit_identically() {
    let (iterated, a) = kill_resume_compare(&FLOATING, 0x5eed_0005, 3, 3);
    let (staggered, b) = kill_resume_compare(&FLOATING_STAGGERED, 0x5eed_0006, 1, 2);
    let (verlet, c) = kill_resume_compare(&FLOATING_VERLET, 0x5eed_0007, 1, 2);
    let (tumbling, d) = kill_resume_compare(&TUMBLING_3D, 0x5eed_0008, 1, 2);
    eprintln!(
        "free bodies: SIGKILLs that hit a running process: iterated {iterated}, staggered \
         {staggered}, Verlet {verlet}, 3-D {tumbling}; resumed {a}, {b}, {c}, {d} times"
    );
    assert!(a >= 5 && b >= 1 && c >= 1 && d >= 1);
    assert!(iterated + staggered + verlet + tumbling >= 10);
}

/// Semi-analytical walls: integrated gamma (and summation densities), 4 seeded SIGKILLs.
#[test]
fn killed_usaw_runs_resume_bit_identically() {
    let (gamma, a) = kill_resume_compare(&USAW, 0x5eed_0009, 1, 2);
    let (summation, b) = kill_resume_compare(&USAW_SUMMATION, 0x5eed_000a, 1, 2);
    eprintln!("usaw: {gamma} and {summation} SIGKILLs, {a} and {b} resumes");
    assert!(a >= 1 && b >= 1);
}

/// SIGTERM: the run finishes its step, writes a checkpoint, exits with code 10 and its
/// summary says so; the resumed run is identical to an uninterrupted one.
#[test]
fn sigterm_checkpoints_and_resumes() {
    let case = &DAM_BREAK;
    let reference = temp_dir("term-reference");
    run_to_end(&fresh_args(case, &reference));
    let dir = temp_dir("term");
    let mut args = fresh_args(case, &dir);
    let k = args.iter().position(|a| a == "--checkpoint-steps").unwrap();
    args[k + 1] = "0".into();
    let child = exe()
        .args(&args)
        .stdout(Stdio::null())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    let start = Instant::now();
    while lines(&dir.join(case.per_step)) < 40 && start.elapsed() < Duration::from_secs(30) {
        std::thread::sleep(Duration::from_millis(1));
    }
    terminate(&child);
    let out = child.wait_with_output().unwrap();
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(10), "{stderr}");
    assert!(stderr.contains("--resume"), "{stderr}");
    // An interrupt is asked for, not an error.
    assert!(stderr.starts_with("interrupted at step"), "{stderr}");
    assert!(!stderr.contains("error"), "{stderr}");
    let summary = std::fs::read_to_string(dir.join("summary.json")).unwrap();
    assert!(summary.contains("interrupted"), "{summary}");
    run_to_end(&resume_args(case, &dir, "1"));
    compare(&reference, &dir, "sigterm");
}

/// A stop request that arrives twice (as from `timeout`, which signals the process and its
/// group) is one request: the run still finishes its step, writes its checkpoint and exits
/// with code 10, instead of ending at once without a checkpoint.
#[test]
fn a_stop_signal_sent_twice_still_checkpoints() {
    let dir = temp_dir("term-twice");
    let case = cases_dir().join("dam-break-3d.toml");
    let mut command = exe();
    command
        .args([
            "run",
            &case.display().to_string(),
            "--out",
            &dir.display().to_string(),
        ])
        .args(["--quiet", "--threads", "1"]);
    for set in [
        "resolution.dx=0.015",
        "settle.enabled=false",
        "time.end=0.05",
        "output.series_interval=0",
        "output.vtk_interval=0",
        "output.plots=false",
    ] {
        command.args(["--set", set]);
    }
    let child = command
        .stdout(Stdio::null())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    let start = Instant::now();
    while lines(&dir.join("energy.csv")) < 4 && start.elapsed() < Duration::from_secs(60) {
        std::thread::sleep(Duration::from_millis(1));
    }
    // The second signal comes while the first step's end and checkpoint are under way (a
    // step of these 16,000 particles on one thread takes tens of milliseconds).
    terminate(&child);
    std::thread::sleep(Duration::from_millis(5));
    // (Unchecked: the process may have ended already.)
    let _ = Command::new("kill")
        .args(["-TERM", &child.id().to_string()])
        .status();
    let out = child.wait_with_output().unwrap();
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(10), "{stderr}");
    assert!(stderr.starts_with("interrupted at step"), "{stderr}");
    assert!(dir.join("checkpoint.bin").exists());
}

/// Settling writes checkpoints too: a run killed with SIGKILL while settling, resumed, then
/// stopped with SIGTERM while still settling (exit code 10, a checkpoint, no summary) and
/// resumed again on two threads settles and runs to outputs byte-identical to an
/// uninterrupted run, with the same settling steps and time.
#[test]
fn runs_stopped_while_settling_resume_bit_identically() {
    let case = cases_dir().join("hydrostatic-2d.toml");
    let fresh = |out: &Path, every: &str| {
        let mut a: Vec<String> = vec!["run".into(), case.display().to_string()];
        a.extend(["--out".into(), out.display().to_string()]);
        for s in [
            "--quiet",
            "--threads",
            "1",
            "--checkpoint-steps",
            every,
            "--set",
            "resolution.dx=0.025",
            "--set",
            "time.end=0.3",
            "--set",
            "output.vtk_interval=0.1",
        ] {
            a.push(s.into());
        }
        a
    };
    let reference = temp_dir("settling-reference");
    run_to_end(&fresh(&reference, "0"));
    let dir = temp_dir("settling");
    let checkpoint = dir.join("checkpoint.bin");
    let settling = |dir: &Path| !dir.join("energy.csv").exists();
    // SIGKILL after the first settling checkpoint.
    let mut child = exe()
        .args(fresh(&dir, "200"))
        .stdout(Stdio::null())
        .stderr(Stdio::null())
        .spawn()
        .unwrap();
    let start = Instant::now();
    while !checkpoint.exists() && start.elapsed() < Duration::from_secs(30) {
        std::thread::sleep(Duration::from_millis(1));
    }
    child.kill().unwrap();
    child.wait().unwrap();
    assert!(
        checkpoint.exists() && settling(&dir),
        "killed while settling"
    );
    // Resumed, then SIGTERM while still settling.
    let child = exe()
        .args(["run", "--resume", &dir.display().to_string(), "--quiet"])
        .args(["--threads", "2", "--checkpoint-steps", "0"])
        .stdout(Stdio::null())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    std::thread::sleep(Duration::from_millis(300));
    terminate(&child);
    let out = child.wait_with_output().unwrap();
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(10), "{stderr}");
    assert!(stderr.starts_with("interrupted while settling"), "{stderr}");
    assert!(stderr.contains("--resume"), "{stderr}");
    assert!(
        checkpoint.exists() && settling(&dir),
        "stopped while settling"
    );
    assert!(!dir.join("summary.json").exists());
    let resumed = exe()
        .args(["run", "--resume", &dir.display().to_string(), "--quiet"])
        .args(["--threads", "2"])
        .output()
        .unwrap();
    assert!(resumed.status.success(), "{resumed:?}");
    compare(&reference, &dir, "stopped while settling");
    let report = |dir: &Path| {
        let text = std::fs::read_to_string(dir.join("settling.json")).unwrap();
        let v: serde_json::Value = serde_json::from_str(&text).unwrap();
        (v["outcome"].clone(), v["steps"].clone(), v["time"].clone())
    };
    assert_eq!(report(&reference), report(&dir));
}

/// SIGTERM stops `bisph validate` (exit code 10, no report) with a checkpoint of the running
/// case, and the same command continues from it to the figures of an uninterrupted run.
#[test]
fn an_interrupted_validation_continues_from_its_checkpoint() {
    let validate = |out: &Path| {
        let mut command = exe();
        command.args(["validate", "--quick", "spheric-test2", "--out"]);
        command.arg(out);
        command
    };
    let reference = temp_dir("validate-reference");
    let done = validate(&reference).output().unwrap();
    assert!(done.status.success(), "{done:?}");
    let dir = temp_dir("validate-term");
    let child = validate(&dir)
        .stdout(Stdio::null())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    let probes = dir.join("spheric-test2").join("probes.csv");
    let start = Instant::now();
    while lines(&probes) < 20 && start.elapsed() < Duration::from_secs(60) {
        std::thread::sleep(Duration::from_millis(1));
    }
    terminate(&child);
    let out = child.wait_with_output().unwrap();
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(10), "{stderr}");
    assert!(
        stderr.contains("interrupted: no report written; spheric-test2 saved a checkpoint"),
        "{stderr}"
    );
    assert!(!stderr.contains("error"), "{stderr}");
    assert!(!dir.join("report.md").exists());
    let resumed = validate(&dir).output().unwrap();
    assert!(resumed.status.success(), "{resumed:?}");
    let summary = std::fs::read_to_string(dir.join("spheric-test2").join("summary.json")).unwrap();
    let summary: serde_json::Value = serde_json::from_str(&summary).unwrap();
    assert!(summary["resumed_from_step"].as_u64().is_some(), "{summary}");
    // The report's figures (its table rows; the headers hold wall-clock times).
    let rows = |dir: &Path| -> Vec<String> {
        std::fs::read_to_string(dir.join("report.md"))
            .unwrap()
            .lines()
            .filter(|l| l.starts_with('|'))
            .map(String::from)
            .collect()
    };
    let expected = rows(&reference);
    assert!(expected.len() > 2, "{expected:?}");
    assert_eq!(rows(&dir), expected);
}

/// Sends SIGTERM to `child`.
fn terminate(child: &Child) {
    let status = Command::new("kill")
        .args(["-TERM", &child.id().to_string()])
        .status()
        .unwrap();
    assert!(status.success());
}

/// Damaged, truncated, foreign and missing checkpoints are refused with exit code 5 and a
/// message naming the file, before anything is written.
#[test]
fn bad_checkpoints_are_refused() {
    let case = &PISTON;
    let dir = temp_dir("refuse");
    let mut child = exe()
        .args(fresh_args(case, &dir))
        .stdout(Stdio::null())
        .stderr(Stdio::null())
        .spawn()
        .unwrap();
    let ck = dir.join("checkpoint.bin");
    let start = Instant::now();
    while !ck.exists() && start.elapsed() < Duration::from_secs(30) {
        std::thread::sleep(Duration::from_millis(1));
    }
    child.kill().unwrap();
    child.wait().unwrap();
    let good = std::fs::read(&ck).unwrap();
    let energy = std::fs::read(dir.join("energy.csv")).unwrap();
    let attempt = |bytes: &[u8], needle: &str| {
        std::fs::write(&ck, bytes).unwrap();
        let out = exe().args(resume_args(case, &dir, "1")).output().unwrap();
        let stderr = String::from_utf8_lossy(&out.stderr);
        assert_eq!(out.status.code(), Some(5), "{needle}: {stderr}");
        assert!(stderr.contains(needle), "{needle}: {stderr}");
        assert!(stderr.contains("checkpoint.bin"), "{stderr}");
        assert!(!stderr.contains("panicked"), "{stderr}");
        // Nothing touched.
        assert_eq!(std::fs::read(dir.join("energy.csv")).unwrap(), energy);
    };
    let mut flipped = good.clone();
    let mid = flipped.len() / 2;
    flipped[mid] ^= 0x01;
    attempt(&flipped, "damaged");
    attempt(&good[..good.len() - 100], "damaged");
    attempt(b"name = \"not a checkpoint\"\n", "magic");
    let mut other_version = good.clone();
    // The version string follows the magic (8 bytes), the format (4) and its length (8).
    other_version[20] = b'9';
    attempt(&other_version, "written by bisph 9");
    std::fs::remove_file(&ck).unwrap();
    let out = exe().args(resume_args(case, &dir, "1")).output().unwrap();
    assert_eq!(out.status.code(), Some(5));
    assert!(String::from_utf8_lossy(&out.stderr).contains("cannot read checkpoint"));
}
