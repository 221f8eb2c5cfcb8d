//! `bisph run` split into parts, each a thread with its end of an in-process transport, writes
//! the files of the run in one process: the same bytes in every CSV series, the same walls in
//! every frame and the fluid of every frame in pieces, the same `summary.json` figures, the
//! same `diagnostics.json` when a watch trips; and a split run stopped at a checkpoint
//! resumes on another number of parts, or in one process, to the same end.

use bisph_core::decomposition::{InProcess, Transport};
use bisph_core::particles::PermuteScratch;
use bisph_io::case::{load_case, LoadedCase};
use bisph_io::run::checkpoint;
use bisph_io::run::{run_case_split, run_case_with, RunOptions, Summary};
use bisph_io::RunError;
use glam::DVec2;
use serde_json::Value;
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicBool, Ordering};

/// The case `name` of the project's `cases` folder with `overrides`.
fn case(name: &str, overrides: &[&str]) -> LoadedCase {
    let path = PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .join("../../cases")
        .join(name);
    let overrides: Vec<String> = overrides.iter().map(|s| s.to_string()).collect();
    load_case(Some(&path), &overrides).unwrap()
}

/// A fresh, empty folder for one run, removed when dropped.
fn folder(name: &str) -> tempfile::TempDir {
    let prefix = format!("bisph-split-outputs-{name}-");
    tempfile::Builder::new().prefix(&prefix).tempdir().unwrap()
}

/// The run of `loaded` into `out` split into `parts` parts, each on its own thread; the result
/// of every part. `stop_at`: the step at which the first part raises the stop signal.
fn split_run(
    loaded: &LoadedCase,
    out: &Path,
    parts: usize,
    resume: bool,
    stop_at: Option<u64>,
) -> Vec<Result<Summary, RunError>> {
    let stop = AtomicBool::new(false);
    let options = RunOptions {
        stop: Some(&stop),
        resume,
        ..RunOptions::default()
    };
    std::thread::scope(|scope| {
        let runs: Vec<_> = InProcess::connect(parts)
            .into_iter()
            .map(|end| {
                let (stop, options) = (&stop, &options);
                let first = end.rank() == 0;
                scope.spawn(move || {
                    let mut progress = |p: bisph_io::Progress| {
                        if first && !p.settling && stop_at.is_some_and(|s| p.step >= s) {
                            stop.store(true, Ordering::SeqCst);
                        }
                    };
                    run_case_split(loaded, out, options, Some(Box::new(end)), &mut progress)
                })
            })
            .collect();
        runs.into_iter().map(|r| r.join().unwrap()).collect()
    })
}

/// The run of `loaded` into `out` in one process.
fn whole_run(loaded: &LoadedCase, out: &Path) -> Result<Summary, RunError> {
    run_case_with(loaded, out, &RunOptions::default(), &mut |_| {})
}

/// The files of `dir` whose names end with `suffix`, sorted.
fn files(dir: &Path, suffix: &str) -> Vec<String> {
    let mut names: Vec<String> = std::fs::read_dir(dir)
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .filter(|n| n.ends_with(suffix))
        .collect();
    names.sort();
    names
}

/// `summary.json` without what depends on the machine and the split: clocks, threads, ranks.
fn summary_figures(dir: &Path) -> Value {
    let text = std::fs::read_to_string(dir.join("summary.json")).unwrap();
    let mut summary: Value = serde_json::from_str(&text).unwrap();
    let fields = summary.as_object_mut().unwrap();
    for clock in [
        "wall_seconds",
        "particle_steps_per_second",
        "phase_seconds",
        "threads",
        "ranks",
    ] {
        fields.remove(clock);
    }
    if let Some(settling) = fields.get_mut("settling").and_then(Value::as_object_mut) {
        settling.remove("wall_seconds");
    }
    summary
}

/// Number of points in the `.vtu` file `path` (from its piece header).
fn points_in(path: &Path) -> usize {
    let bytes = std::fs::read(path).unwrap();
    let head = String::from_utf8_lossy(&bytes[..bytes.len().min(2000)]).into_owned();
    let at = head.find("NumberOfPoints=\"").unwrap() + "NumberOfPoints=\"".len();
    head[at..].split('"').next().unwrap().parse().unwrap()
}

/// Asserts that the split run in `split` wrote the files of the whole run in `whole`: every
/// CSV series and every walls frame to the byte, the summary's figures, and each fluid frame
/// as `parts` pieces holding the whole fluid between them.
fn assert_same_outputs(whole: &Path, split: &Path, parts: usize, run: &str) {
    let series = files(whole, ".csv");
    assert!(series.len() >= 3, "{run}: series {series:?}");
    assert_eq!(series, files(split, ".csv"), "{run}: the series written");
    for name in &series {
        let (a, b) = (whole.join(name), split.join(name));
        let same = std::fs::read(a).unwrap() == std::fs::read(b).unwrap();
        assert!(same, "{run}: {name} differs");
    }
    assert_eq!(
        summary_figures(whole),
        summary_figures(split),
        "{run}: summary"
    );
    let frames = files(&whole.join("vtk"), ".vtu");
    let walls: Vec<&String> = frames.iter().filter(|n| n.starts_with("walls")).collect();
    assert!(!walls.is_empty(), "{run}: no frames");
    for name in walls {
        let (a, b) = (whole.join("vtk").join(name), split.join("vtk").join(name));
        let same = std::fs::read(a).unwrap() == std::fs::read(b).unwrap();
        assert!(same, "{run}: {name} differs");
        let fluid = name.replace("walls", "fluid");
        let index = split.join("vtk").join(fluid.replace(".vtu", ".pvtu"));
        let index = std::fs::read_to_string(index).unwrap();
        let pieces: Vec<PathBuf> = (0..parts)
            .map(|r| {
                let piece = fluid.replace(".vtu", &format!("_{r}.vtu"));
                assert!(
                    index.contains(&format!("Source=\"{piece}\"")),
                    "{run}: {piece}"
                );
                split.join("vtk").join(piece)
            })
            .collect();
        let held: usize = pieces.iter().map(|p| points_in(p)).sum();
        assert_eq!(
            held,
            points_in(&whole.join("vtk").join(&fluid)),
            "{run}: {fluid}"
        );
    }
    let pvd = std::fs::read_to_string(split.join("fluid.pvd")).unwrap();
    assert!(
        pvd.contains(".pvtu") && !pvd.contains("_0.vtu"),
        "{run}: {pvd}"
    );
}

/// Runs `loaded` whole and split into 2 and 3 parts, and compares their outputs.
fn check(name: &str, loaded: &LoadedCase) {
    let whole_folder = folder(&format!("{name}-whole"));
    let whole = whole_folder.path();
    let summary = whole_run(loaded, whole).unwrap();
    assert!(summary.steps >= 20, "{name}: {} steps", summary.steps);
    for parts in [2, 3] {
        let split_folder = folder(&format!("{name}-{parts}"));
        let split = split_folder.path();
        let runs = split_run(loaded, split, parts, false, None);
        for run in runs {
            let s = run.unwrap();
            assert_eq!((s.steps, s.ranks), (summary.steps, parts), "{name}");
        }
        assert_same_outputs(whole, split, parts, &format!("{name}, {parts} parts"));
    }
}

#[test]
fn a_breaking_dam_with_energy_walls_writes_the_files_of_the_whole_run() {
    let loaded = case(
        "dam-break-2d.toml",
        &[
            "resolution.dx=0.02",
            "time.end=0.25",
            "output.series_interval=0.002",
            "output.vtk_interval=0.1",
        ],
    );
    check("dam-2d", &loaded);
}

#[test]
fn a_breaking_dam_in_3d_with_bi_walls_writes_the_files_of_the_whole_run() {
    let loaded = case(
        "dam-break-3d.toml",
        &[
            "boundary=\"bi\"",
            "shepard=\"geometric\"",
            "resolution.dx=0.04",
            "time.end=0.1",
            "output.series_interval=0.002",
            "output.vtk_interval=0.05",
        ],
    );
    check("dam-3d", &loaded);
}

#[test]
fn a_piston_and_a_floating_box_under_the_midpoint_scheme_write_the_files_of_the_whole_run() {
    let piston = case(
        "adiabatic-piston.toml",
        &["time.end=1.5", "output.vtk_interval=0.5"],
    );
    check("piston", &piston);
    let floating = case(
        "floating-box-2d.toml",
        &[
            "resolution.dx=0.04",
            "time.end=0.1",
            "output.series_interval=0.002",
            "output.vtk_interval=0.05",
        ],
    );
    check("floating", &floating);
}

#[test]
fn a_split_run_stopped_at_a_checkpoint_resumes_on_other_parts_to_the_end_of_the_whole_run() {
    let loaded = case(
        "dam-break-2d.toml",
        &[
            "resolution.dx=0.02",
            "time.end=0.2",
            "output.series_interval=0.002",
            "output.vtk_interval=0.05",
        ],
    );
    let whole_folder = folder("resume-whole");
    let whole = whole_folder.path();
    let summary = whole_run(&loaded, whole).unwrap();
    // Stopped on 2 parts, resumed on 3; stopped on 3 parts, resumed in one process.
    for (first, then) in [(2, 3), (3, 1)] {
        let split_folder = folder(&format!("resume-{first}-{then}"));
        let split = split_folder.path();
        for run in split_run(&loaded, split, first, false, Some(summary.steps / 2)) {
            assert!(
                matches!(run, Err(RunError::Interrupted { .. })),
                "{first} parts: {:?}",
                run.map(|s| s.steps)
            );
        }
        assert!(split.join("checkpoint.bin").exists());
        let ends = match then {
            1 => {
                let options = RunOptions {
                    resume: true,
                    ..RunOptions::default()
                };
                vec![run_case_with(&loaded, split, &options, &mut |_| {})]
            }
            _ => split_run(&loaded, split, then, true, None),
        };
        for end in ends {
            let s = end.unwrap();
            assert_eq!(s.resumed_from_step, Some(summary.steps / 2));
        }
        let series = files(whole, ".csv");
        for name in &series {
            let same = std::fs::read(whole.join(name)).unwrap()
                == std::fs::read(split.join(name)).unwrap();
            assert!(
                same,
                "stopped on {first}, resumed on {then}: {name} differs"
            );
        }
        assert_eq!(summary_figures(whole)["energy_total_final"], {
            summary_figures(split)["energy_total_final"].clone()
        });
    }
}

#[test]
fn a_tripped_watch_in_a_split_run_reports_what_the_whole_run_reports() {
    // Density bounds the collapse soon exceeds.
    let loaded = case(
        "dam-break-2d.toml",
        &[
            "resolution.dx=0.02",
            "time.end=0.3",
            "diagnostics.density_ratio_max=1.02",
            "output.series_interval=0.002",
            "output.vtk_interval=0.1",
        ],
    );
    let whole_folder = folder("trip-whole");
    let whole = whole_folder.path();
    let Err(RunError::Stopped(expected)) = whole_run(&loaded, whole) else {
        panic!("the watch did not trip in the whole run");
    };
    assert!(expected.step > 50, "tripped at step {}", expected.step);
    let split_folder = folder("trip-3");
    let split = split_folder.path();
    for run in split_run(&loaded, split, 3, false, None) {
        let Err(RunError::Stopped(d)) = run else {
            panic!("the watch did not trip in the split run");
        };
        let frame = d.vtk_frame.clone().map(|f| f.replace(".pvtu", ".vtu"));
        assert_eq!(frame, expected.vtk_frame);
        assert_eq!(
            d.particles, expected.particles,
            "the particles named by the watch"
        );
        assert_eq!((d.kind, d.step), (expected.kind, expected.step));
        assert_eq!(d.particles_tripped, expected.particles_tripped);
    }
    let text = |dir: &Path| {
        let mut d: Value =
            serde_json::from_str(&std::fs::read_to_string(dir.join("diagnostics.json")).unwrap())
                .unwrap();
        d.as_object_mut().unwrap().remove("vtk_frame");
        d
    };
    assert_eq!(text(whole), text(split));
    for name in files(whole, ".csv") {
        let same =
            std::fs::read(whole.join(&name)).unwrap() == std::fs::read(split.join(&name)).unwrap();
        assert!(same, "{name} differs");
    }
    // The checkpoint holds the last good state of the whole run, and its histories. A whole
    // run keeps its particles in its own order, a split run gathers them by id: the run
    // continues with the same bits from either (the split-run tests check that).
    let saved = |dir: &Path| {
        let c = checkpoint::read::<DVec2>(&dir.join(checkpoint::FILE_NAME)).unwrap();
        let mut state = c.sim;
        let mut by_id: Vec<u32> = (0..state.fluid.len() as u32).collect();
        by_id.sort_unstable_by_key(|&i| state.fluid.id[i as usize]);
        state.fluid.hold_earlier_rates();
        state.fluid.permute(&by_id, &mut PermuteScratch::default());
        let origin = &state.neighbour_origin;
        if !origin.is_empty() {
            state.neighbour_origin = by_id.iter().map(|&i| origin[i as usize]).collect();
        }
        let state = format!("{state:?}");
        (state, format!("{:?} {:?}", c.history, c.probe_history))
    };
    let (a, b) = (saved(whole), saved(split));
    assert!(a == b, "the checkpoints differ");
}
