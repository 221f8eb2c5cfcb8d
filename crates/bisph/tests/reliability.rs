//! Divergence diagnostics, input checks, resource limits and write errors of `bisph run`.

mod common;
use common::{bisph, cases_dir};

use std::path::Path;
use std::process::{Command, Output};

fn temp_dir(name: &str) -> common::Scratch {
    common::temp_dir("rel", name)
}

fn json(path: &Path) -> serde_json::Value {
    serde_json::from_str(&std::fs::read_to_string(path).unwrap()).unwrap()
}

fn dam_break(dir: &Path, extra: &[&str]) -> Output {
    let case = cases_dir().join("dam-break-2d.toml");
    let mut args = vec![
        "run",
        case.to_str().unwrap(),
        "--out",
        dir.to_str().unwrap(),
        "--quiet",
        "--threads",
        "1",
        "--set",
        "resolution.dx=0.02",
        "--set",
        "output.plots=false",
    ];
    args.extend_from_slice(extra);
    let a: Vec<String> = args.iter().map(|s| s.to_string()).collect();
    Command::new(env!("CARGO_BIN_EXE_bisph"))
        .args(&a)
        .output()
        .unwrap()
}

/// A time step far beyond the Courant limit (`c0 dt / h = 4.3`): the watches stop the run
/// before its state turns to NaN, within a few steps of the blow-up, with `diagnostics.json`
/// naming the quantity, the particle, its position, the step and the time; the last good
/// state is kept as a checkpoint and a VTK frame.
#[test]
fn unstable_case_stops_with_diagnostics_before_the_blow_up() {
    // Without the watches: the step at which the state stops being finite.
    let raw = temp_dir("unwatched");
    let out = dam_break(
        &raw,
        &[
            "--set",
            "time.dt=0.01",
            "--set",
            "diagnostics.enabled=false",
        ],
    );
    assert_eq!(
        out.status.code(),
        Some(20),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let blow_up = json(&raw.join("diagnostics.json"))["step"]
        .as_u64()
        .unwrap();

    let dir = temp_dir("unstable");
    let out = dam_break(&dir, &["--set", "time.dt=0.01"]);
    let stderr = String::from_utf8_lossy(&out.stderr);
    let code = out.status.code().unwrap();
    assert!((20..=26).contains(&code), "{code}: {stderr}");
    assert!(!stderr.contains("panicked"), "{stderr}");
    let d = json(&dir.join("diagnostics.json"));
    assert_eq!(d["exit_code"].as_u64(), Some(code as u64));
    let step = d["step"].as_u64().unwrap();
    assert!(
        step >= 1 && step <= blow_up,
        "tripped at {step}, NaN at {blow_up}"
    );
    assert!(
        blow_up - step <= 5,
        "tripped at {step}, long before NaN at {blow_up}"
    );
    assert_eq!(d["last_good_step"].as_u64(), Some(step - 1));
    let particle = &d["particles"][0];
    assert!(particle["id"].is_u64(), "{d}");
    assert_eq!(particle["position"].as_array().unwrap().len(), 3);
    assert!(d["time"].as_f64().unwrap() > 0.0);
    assert!(d["quantity"].as_str().unwrap().len() > 3);
    assert!(
        stderr.contains(&format!("particle {}", particle["id"])),
        "{stderr}"
    );
    assert!(dir.join("checkpoint.bin").exists());
    assert!(dir.join(d["vtk_frame"].as_str().unwrap()).exists());
    let summary = json(&dir.join("summary.json"));
    assert_eq!(summary["steps"].as_u64(), Some(step - 1));
}

/// Each watch trips on its own with its exit code when its bound is set tight.
#[test]
fn each_watch_has_its_exit_code() {
    for (set, code, kind) in [
        ("diagnostics.density_ratio_max=1.0001", 23, "density_ratio"),
        ("diagnostics.speed_over_c0=0.01", 24, "speed"),
        ("diagnostics.energy_growth=1e-12", 26, "energy_growth"),
    ] {
        let dir = temp_dir(kind);
        let out = dam_break(&dir, &["--set", set, "--set", "time.end=0.2"]);
        let stderr = String::from_utf8_lossy(&out.stderr);
        assert_eq!(out.status.code(), Some(code), "{set}: {stderr}");
        let d = json(&dir.join("diagnostics.json"));
        assert_eq!(d["kind"].as_str(), Some(kind), "{d}");
    }
    // Particles pushed through a wall (no bounce, a fast start towards the right wall).
    let dir = temp_dir("crossing");
    let out = dam_break(
        &dir,
        &[
            "--set",
            "elastic_bounce=false",
            "--set",
            "fluid_block.0.velocity=[15.0, 0.0]",
            "--set",
            "diagnostics.speed_over_c0=100",
            "--set",
            "diagnostics.density_ratio_max=100",
            "--set",
            "time.end=0.3",
        ],
    );
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(25), "{stderr}");
    let d = json(&dir.join("diagnostics.json"));
    assert_eq!(d["kind"].as_str(), Some("wall_crossing"), "{d}");
    // Behind the tank's walls: x < 0, x > 1.61 or y < 0.
    let p = &d["particles"][0]["position"];
    let (x, y) = (p[0].as_f64().unwrap(), p[1].as_f64().unwrap());
    assert!(!(0.0..=1.61).contains(&x) || y < 0.0, "{d}");
}

/// Physical nonsense is refused before the run with exit code 1, naming the key and the
/// allowed range.
#[test]
fn physical_nonsense_names_key_and_range() {
    let dir = temp_dir("nonsense");
    let piston = cases_dir().join("adiabatic-piston.toml");
    for (set, key, range) in [
        ("fluid.density=-1000", "fluid.density", "positive"),
        ("fluid.sound_speed=0", "fluid.sound_speed", "positive"),
        ("resolution.h_over_dx=7", "resolution.h_over_dx", "[1, 4]"),
        ("time.courant=1.5", "time.courant", "(0, 1]"),
        ("time.neighbour_skin=-0.1", "time.neighbour_skin", "[0, 1]"),
        (
            "probe.0.position=[3.0, 0.1]",
            "probe[0].position",
            "inside the box around the walls",
        ),
        (
            "diagnostics.density_ratio_min=2",
            "diagnostics.density_ratio_min",
            "(0, 1]",
        ),
        (
            "diagnostics.dt_collapse=1",
            "diagnostics.dt_collapse",
            "[0, 1)",
        ),
        (
            "checkpoint.every_minutes=-1",
            "checkpoint.every_minutes",
            "zero",
        ),
        ("time.min_dt=10", "time.min_dt", "below time.end"),
        // With a [domain]:
        ("resolution.dx=1.25", "resolution.dx", "at most the domain"),
        (
            "fluid_block.0.max=[1.5, 1.0]",
            "fluid_block[0]",
            "inside the domain",
        ),
    ] {
        let out = if set.starts_with("resolution.dx") || set.starts_with("fluid_block") {
            bisph(&[
                "run",
                piston.to_str().unwrap(),
                "--out",
                dir.to_str().unwrap(),
                "--quiet",
                "--set",
                set,
            ])
        } else {
            dam_break(&dir, &["--set", set])
        };
        let stderr = String::from_utf8_lossy(&out.stderr);
        assert_eq!(out.status.code(), Some(1), "{set}: {stderr}");
        assert!(stderr.contains(&format!("`{key}`")), "{set}: {stderr}");
        assert!(stderr.contains(range), "{set}: {stderr}");
        assert!(!stderr.contains("panicked"), "{stderr}");
    }
}

/// A case needing more memory than the machine has is refused up front with the estimate.
#[test]
fn too_large_a_case_is_refused_with_the_estimate() {
    let dir = temp_dir("memory");
    let case = cases_dir().join("dam-break-3d.toml");
    let started = std::time::Instant::now();
    let out = bisph(&[
        "run",
        case.to_str().unwrap(),
        "--out",
        dir.to_str().unwrap(),
        "--quiet",
        "--set",
        "resolution.dx=0.0002",
    ]);
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(6), "{stderr}");
    assert!(
        stderr.contains("GiB") && stderr.contains("MemAvailable"),
        "{stderr}"
    );
    assert!(started.elapsed().as_secs_f64() < 5.0);
}

/// A write that fails mid-run (a VTK frame written onto `/dev/full`: "no space left on
/// device") stops the run with exit code 4 naming the file; the checkpoint written before is
/// kept, and resuming from it (once there is space) ends identical to an uninterrupted run.
#[test]
fn disk_full_stops_with_the_file_named_and_the_checkpoint_kept() {
    let args = [
        "--set",
        "time.end=0.2",
        "--set",
        "output.vtk_interval=0.05",
        "--checkpoint-steps",
        "10",
    ];
    let reference = temp_dir("full-reference");
    let out = dam_break(&reference, &args);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let dir = temp_dir("full");
    std::fs::create_dir_all(dir.join("vtk")).unwrap();
    let victim = dir.join("vtk/fluid_000002.vtu.tmp");
    std::os::unix::fs::symlink("/dev/full", &victim).unwrap();
    let out = dam_break(&dir, &args);
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(4), "{stderr}");
    assert!(stderr.contains("fluid_000002.vtu"), "{stderr}");
    assert!(dir.join("checkpoint.bin").exists());
    // The failed write removed its temporary name (here the link) itself.
    let _ = std::fs::remove_file(&victim);
    let out = bisph(&[
        "run",
        "--resume",
        dir.to_str().unwrap(),
        "--quiet",
        "--threads",
        "1",
    ]);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    for f in [
        "energy.csv",
        "probes.csv",
        "forces.csv",
        "fluid.pvd",
        "vtk/fluid_000003.vtu",
    ] {
        assert!(
            std::fs::read(reference.join(f)).unwrap() == std::fs::read(dir.join(f)).unwrap(),
            "{f} differs"
        );
    }
}

/// An output directory that cannot be written is an I/O error (exit code 4) naming the path.
#[test]
fn unwritable_output_names_the_file() {
    let dir = temp_dir("unwritable");
    let blocker = dir.join("not-a-dir");
    std::fs::write(&blocker, b"x").unwrap();
    let out = dam_break(&blocker.join("out"), &[]);
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(4), "{stderr}");
    assert!(stderr.contains("not-a-dir"), "{stderr}");
    // A series file that is a directory.
    let dir = temp_dir("csv-is-dir");
    std::fs::create_dir_all(dir.join("energy.csv")).unwrap();
    let out = dam_break(&dir, &[]);
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(4), "{stderr}");
    assert!(stderr.contains("energy.csv"), "{stderr}");
}

/// The water thrown up out of the open tank leaves the domain, or falls back over the rim of
/// the tank's walls: its particles are removed, with their energy booked in `energy.csv`, up
/// to `diagnostics.removed_fraction_max` of the fluid (default 1%); one more stops the run with
/// exit code 21, naming the count.
#[test]
fn particles_leaving_the_domain_are_removed_up_to_the_allowance() {
    let splash = [
        "--set",
        "wall.0.open=[\"+y\"]",
        "--set",
        "fluid_block.0.velocity=[0.0, 4.0]",
        "--set",
        "time.end=0.25",
    ];
    let dir = temp_dir("leaving");
    let mut args = splash.to_vec();
    args.extend(["--set", "diagnostics.removed_fraction_max=0.5"]);
    // Past 0.4 s water falls back over the rim and down the back of the walls.
    args.extend(["--set", "time.end=1.0"]);
    let out = dam_break(&dir, &args);
    let stdout = String::from_utf8_lossy(&out.stdout);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let summary = json(&dir.join("summary.json"));
    let removed = summary["removed_particles"].as_u64().unwrap();
    assert_eq!(summary["fluid_particles"].as_u64(), Some(450));
    assert!((10..=225).contains(&removed), "{removed} removed");
    assert_eq!(summary["particles_behind_walls"].as_u64(), Some(0));
    assert!(
        stdout.contains(&format!("{removed} fluid particles")) && stdout.contains("were removed"),
        "{stdout}"
    );
    let energy = std::fs::read_to_string(dir.join("energy.csv")).unwrap();
    let mut rows = energy.lines();
    assert!(rows.next().unwrap().ends_with(",removed"));
    let last: Vec<f64> = rows
        .last()
        .unwrap()
        .split(',')
        .map(|v| v.parse().unwrap())
        .collect();
    assert!(last[9] > 0.0, "removed energy {}", last[9]);

    let dir = temp_dir("left");
    let out = dam_break(&dir, &splash);
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(21), "{stderr}");
    assert!(
        stderr.contains("4 particles left it before and were removed, at most 4 may"),
        "{stderr}"
    );
    let d = json(&dir.join("diagnostics.json"));
    assert_eq!(d["exit_code"].as_u64(), Some(21));
    let summary = json(&dir.join("summary.json"));
    assert_eq!(summary["removed_particles"].as_u64(), Some(4));
}
