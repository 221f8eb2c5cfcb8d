//! Fuzzing of every input bisph reads: case TOML (parsing, `--set` overrides, checks, building),
//! polygon/particle row files, STL and OBJ meshes (read, then through the mesh-wall steps:
//! welded faces, topology, mass properties, elements) and checkpoints. Each must answer with a value or a
//! named error: no panic, no hang, no allocation beyond what the input's own size justifies.
//!
//! Structured generators (mutations of valid inputs) and byte-level ones run under proptest.
//! In `cargo test` each kind runs `BISPH_FUZZ_CASES` inputs (default 48); long runs set
//! `BISPH_FUZZ_SECONDS` to keep drawing fresh seeded batches for that long, e.g.
//! `BISPH_FUZZ_SECONDS=600 RAYON_NUM_THREADS=1 nice -n 19 cargo test --release -p bisph-io
//! --test fuzz -- --test-threads 1 --nocapture fuzz_checkpoint`.
//! Inputs that once failed are kept under `tests/fuzz-corpus/<kind>/` and replayed every run.

use bisph_core::surface::Surface;
use bisph_io::case::build_simulation;
use bisph_io::case::mesh_walls::checked_elements;
use bisph_io::case::resources;
use bisph_io::case::schema::MAX_MESH_ELEMENTS;
use bisph_io::formats::mesh_files::{parse_obj, parse_rows, parse_stl};
use bisph_io::parse_case;
use bisph_io::run::checkpoint::{self, Checkpoint, SimState};
use bisph_io::run::shepard::parse_points;
use glam::DVec2;
use glam::DVec3;
use proptest::prelude::*;
use proptest::test_runner::{Config, RngAlgorithm, TestRng, TestRunner};
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicU64, Ordering};
use std::time::Instant;

/// Inputs accepted (parsed, decoded, restored) by the bodies, to show the fuzzing goes deep.
static ACCEPTED: AtomicU64 = AtomicU64::new(0);
static CALLS: AtomicU64 = AtomicU64::new(0);

const VALID: &str = r#"
name = "fuzz"
dim = 2
[fluid]
density = 1000.0
sound_speed = 20.0
gravity = [0.0, -9.81]
[resolution]
dx = 0.1
[time]
end = 0.01
[[fluid_block]]
shape = "box"
min = [0.0, 0.0]
max = [0.5, 0.5]
[[wall]]
shape = "box"
min = [0.0, 0.0]
max = [1.0, 1.0]
[[probe]]
name = "p"
kind = "pressure"
position = [0.5, 0.2]
"#;

fn env_number(name: &str, default: u64) -> u64 {
    std::env::var(name)
        .ok()
        .and_then(|v| v.parse().ok())
        .unwrap_or(default)
}

/// Runs `body` on inputs from `strategy`: `BISPH_FUZZ_CASES` per batch, batches with fresh seeds
/// until `BISPH_FUZZ_SECONDS` have passed (one batch when unset). Prints the executions.
fn fuzz<S: Strategy>(name: &str, strategy: S, body: impl Fn(S::Value))
where
    S::Value: std::fmt::Debug,
{
    let cases = env_number("BISPH_FUZZ_CASES", 48) as u32;
    let seconds = env_number("BISPH_FUZZ_SECONDS", 0) as f64;
    let start = Instant::now();
    let mut executions = 0u64;
    let mut batch = 0u64;
    loop {
        let mut seed = [0u8; 32];
        seed[..8].copy_from_slice(&batch.to_le_bytes());
        seed[8..16].copy_from_slice(&(name.len() as u64 * 0x9e37_79b9).to_le_bytes());
        let config = Config {
            cases,
            failure_persistence: None,
            ..Config::default()
        };
        let mut runner =
            TestRunner::new_with_rng(config, TestRng::from_seed(RngAlgorithm::ChaCha, &seed));
        let result = runner.run(&strategy, |input| {
            CALLS.fetch_add(1, Ordering::Relaxed);
            body(input);
            Ok(())
        });
        if let Err(e) = result {
            panic!("{name}: batch {batch}: {e}");
        }
        executions += cases as u64;
        batch += 1;
        if start.elapsed().as_secs_f64() >= seconds {
            break;
        }
    }
    eprintln!(
        "fuzz {name}: {executions} executions in {:.1} s (body calls {} and inputs accepted {}, all tests in this process)",
        start.elapsed().as_secs_f64(),
        CALLS.load(Ordering::Relaxed),
        ACCEPTED.load(Ordering::Relaxed)
    );
}

fn corpus(kind: &str) -> Vec<(PathBuf, Vec<u8>)> {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("tests/fuzz-corpus")
        .join(kind);
    let mut out: Vec<(PathBuf, Vec<u8>)> = std::fs::read_dir(&dir)
        .map(|r| {
            r.filter_map(|e| e.ok())
                .map(|e| e.path())
                .filter(|p| p.is_file())
                .map(|p| {
                    let b = std::fs::read(&p).unwrap();
                    (p, b)
                })
                .collect()
        })
        .unwrap_or_default();
    out.sort();
    out
}

/// Byte-level mutations of `base`: flips, overwrites, cuts, insertions, duplications.
fn mutated(base: Vec<u8>) -> impl Strategy<Value = Vec<u8>> {
    let len = base.len().max(1);
    prop::collection::vec((0..6u8, 0..len, any::<u8>(), 1..64usize), 1..8).prop_map(move |ops| {
        let mut b = base.clone();
        for (op, at, byte, n) in ops {
            let at = at.min(b.len());
            match op {
                0 if at < b.len() => b[at] ^= 1 << (byte % 8),
                1 if at < b.len() => b[at] = byte,
                2 => b.truncate(at),
                3 => b
                    .splice(at..at, std::iter::repeat_n(byte, n))
                    .for_each(drop),
                4 => {
                    let end = (at + n).min(b.len());
                    let piece = b[at..end].to_vec();
                    b.splice(at..at, piece).for_each(drop);
                }
                _ => {
                    let end = (at + n).min(b.len());
                    b.drain(at..end);
                }
            }
        }
        b
    })
}

/// A case text: parse, check, and (when small) build the simulation; must not panic.
fn case_body(text: &str, overrides: &[String]) {
    if let Ok(loaded) = parse_case("<fuzz>", text, overrides) {
        ACCEPTED.fetch_add(1, Ordering::Relaxed);
        let small = resources::estimated_particles(&loaded) < 4000.0
            && resources::estimated_elements(&loaded) < 4000.0;
        let files = loaded.text.contains("file");
        if small && !files {
            if loaded.case.dim == 2 {
                let _ = build_simulation::<DVec2>(&loaded);
            } else {
                let _ = build_simulation::<glam::DVec3>(&loaded);
            }
        }
    }
}

const KEYS: &[&str] = &[
    "dim",
    "fluid.density",
    "fluid.sound_speed",
    "fluid.eos",
    "fluid.tait_exponent",
    "fluid.gravity",
    "fluid.delta",
    "fluid.background_pressure",
    "resolution.dx",
    "resolution.h_over_dx",
    "resolution.element_over_dx",
    "time.end",
    "time.courant",
    "time.dt",
    "time.min_dt",
    "time.integrator",
    "midpoint.max_iterations",
    "midpoint.tolerance",
    "output.vtk_interval",
    "output.series_interval",
    "checkpoint.every_steps",
    "checkpoint.every_minutes",
    "diagnostics.density_ratio_min",
    "diagnostics.speed_over_c0",
    "diagnostics.energy_growth",
    "domain.min",
    "domain.max",
    "fluid_block.0.shape",
    "fluid_block.0.min",
    "fluid_block.0.max",
    "fluid_block.0.velocity",
    "fluid_block.0.pressure",
    "fluid_block.0.points",
    "fluid_block.0.dx",
    "fluid_block.1",
    "wall.0.shape",
    "wall.0.min",
    "wall.0.max",
    "wall.0.points",
    "wall.0.open",
    "wall.0.body",
    "probe.0.position",
    "probe.0.kind",
    "body",
    "boundary",
    "unknown.key",
    "wall.7.min",
    "fluid_block..x",
];

fn value() -> impl Strategy<Value = String> {
    let number = prop_oneof![
        any::<f64>().prop_map(|x| format!("{x:?}")),
        (-3.0..3.0f64).prop_map(|x| format!("{x}")),
        (0u32..5).prop_map(|k| ["0", "-1", "1e308", "nan", "inf"][k as usize].to_string()),
        any::<i64>().prop_map(|x| x.to_string()),
    ];
    prop_oneof![
        number.clone(),
        prop::collection::vec(number.clone(), 0..4).prop_map(|v| format!("[{}]", v.join(", "))),
        prop::collection::vec(prop::collection::vec(number, 0..3), 0..5).prop_map(|v| {
            let rows: Vec<String> = v.iter().map(|r| format!("[{}]", r.join(","))).collect();
            format!("[{}]", rows.join(","))
        }),
        "[a-z_ \"{}=\\[\\],.]{0,12}",
        Just("box".to_string()),
        Just("polygon".to_string()),
        Just("midpoint".to_string()),
        Just("true".to_string()),
    ]
}

#[test]
fn fuzz_case_structured() {
    let strategy = prop::collection::vec(
        (0..KEYS.len()).prop_flat_map(|k| value().prop_map(move |v| format!("{}={v}", KEYS[k]))),
        0..6,
    );
    fuzz("case-structured", strategy, |overrides| {
        case_body(VALID, &overrides)
    });
}

#[test]
fn fuzz_case_bytes() {
    let strategy = prop_oneof![
        mutated(VALID.as_bytes().to_vec()),
        prop::collection::vec(any::<u8>(), 0..400),
    ];
    fuzz("case-bytes", strategy, |bytes| {
        case_body(&String::from_utf8_lossy(&bytes), &[])
    });
}

#[test]
fn fuzz_rows_and_stl() {
    let polygon = b"x,y\n0,0\n1,0\n1,1 # corner\n\n0.2,0.2\n0.4 0.2\n0.3;0.4\n".to_vec();
    let ascii = b"solid t\nfacet normal 0 0 1\nouter loop\nvertex 0 0 0\nvertex 1 0 0\nvertex 0 1 0\nendloop\nendfacet\nendsolid t\n".to_vec();
    let mut binary = vec![0u8; 80];
    binary.extend_from_slice(&2u32.to_le_bytes());
    for t in 0..2u8 {
        binary.extend(std::iter::repeat_n(0u8, 12));
        for k in 0..9u8 {
            binary.extend_from_slice(&((t + k) as f32).to_le_bytes());
        }
        binary.extend_from_slice(&[0, 0]);
    }
    let strategy = prop_oneof![
        mutated(polygon),
        mutated(ascii),
        mutated(binary),
        prop::collection::vec(any::<u8>(), 0..300),
    ];
    fuzz("rows-stl", strategy, |bytes| {
        let text = String::from_utf8_lossy(&bytes);
        for cols in 1..4 {
            let _ = parse_rows(&text, Path::new("<fuzz>"), cols);
        }
        if let Ok(facets) = parse_stl(&bytes, Path::new("<fuzz>")) {
            ACCEPTED.fetch_add(1, Ordering::Relaxed);
            let polygons: Vec<Vec<DVec3>> = facets.iter().map(|f| f.0.to_vec()).collect();
            let normals: Vec<DVec3> = facets.iter().map(|f| f.1).collect();
            mesh_body(&polygons, Some(&normals));
        }
    });
}

/// A mesh (OBJ polygons, or STL facets with their stored normals) through the steps of a mesh
/// wall (`mesh_walls`): welded, checked faces; topology, open and closed; volume and mass
/// properties when closed; elements at an eighth of its extent, and the element count guard at
/// sizes that would make far too many.
fn mesh_body(polygons: &[Vec<DVec3>], normals: Option<&[DVec3]>) {
    let mut size = 0.0f64;
    for p in polygons.iter().flatten() {
        size = size.max(p.abs().max_element());
    }
    let Ok(surface) = Surface::from_polygons(polygons, normals, 1e-9 * size.max(1e-300)) else {
        return;
    };
    ACCEPTED.fetch_add(1, Ordering::Relaxed);
    let _ = surface.check_topology(false);
    if surface.check_topology(true).is_ok() {
        let _ = surface.volume();
        let _ = surface.mass_properties(1000.0);
    }
    let (mut lo, mut hi) = (DVec3::splat(f64::MAX), DVec3::splat(f64::MIN));
    for &v in &surface.vertices {
        lo = lo.min(v);
        hi = hi.max(v);
    }
    let extent = (hi - lo).max_element();
    for element_size in [extent / 8.0, 1e-3, f64::MIN_POSITIVE] {
        let count = surface.element_count(element_size);
        if count <= 1e5 {
            let _ = checked_elements(&surface, element_size);
        } else if count > MAX_MESH_ELEMENTS || count.is_nan() {
            assert!(checked_elements(&surface, element_size).is_err());
        }
    }
}

/// A valid OBJ mesh: a unit cube of quads, one side as two triangles (`a/t/n` forms and
/// negative indices), with comments and ignored records.
const CUBE_OBJ: &str = "# cube\no cube\nv 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nv 0 0 1\nv 1 0 1\nv 1 1 1\nv 0 1 1\nvt 0 0\nvn 0 0 1\ng sides\ns off\nf 1 4 3 2\nf 1 2 6 5\nf 4 8 7 3\nf 1 5 8 4\nf 2 3 7 6\nf 5/1/1 6/1/1 7/1/1\nf -4//1 -2//1 -1//1 # top\n";

fn obj_body(bytes: &[u8]) {
    let text = String::from_utf8_lossy(bytes);
    if let Ok(polygons) = parse_obj(&text, Path::new("<fuzz>")) {
        mesh_body(&polygons, None);
    }
}

/// OBJ meshes: byte-level mutations of a valid cube, structured random meshes (vertex values
/// from a pool with non-finite and huge numbers, face indices in and out of range, faces of 0 to
/// 6 corners) and raw bytes; STL facets go through the same mesh steps.
/// The `bisph shepard --points` file: a named error or finite points, one per data line.
#[test]
fn fuzz_shepard_points() {
    let points2 = b"x,y\n0.5,0.25\n# probe\n\n1e-3, 2.5e1\n-0.0,3\n".to_vec();
    let points3 = b"X,Y,Z\n0,0,0\n0.1,0.2,0.3\n".to_vec();
    let strategy = prop_oneof![
        mutated(points2),
        mutated(points3),
        prop::collection::vec(any::<u8>(), 0..200),
    ];
    fuzz("shepard-points", strategy, |bytes| {
        let text = String::from_utf8_lossy(&bytes);
        for dim in [2, 3] {
            if let Ok(points) = parse_points("<fuzz>", &text, dim) {
                ACCEPTED.fetch_add(1, Ordering::Relaxed);
                assert!(points.len() <= text.lines().count());
                assert!(points.iter().flatten().all(|v| v.is_finite()));
                assert!(points.iter().all(|p| p[dim..].iter().all(|&v| v == 0.0)));
            }
        }
    });
}

#[test]
fn fuzz_obj_meshes() {
    assert!(parse_obj(CUBE_OBJ, Path::new("cube.obj"))
        .map(|p| {
            let s = Surface::from_polygons(&p, None, 1e-9).unwrap();
            s.check_topology(true).is_ok() && (s.volume() - 1.0).abs() < 1e-12
        })
        .unwrap());
    let number = prop_oneof![
        (0u32..4).prop_map(|k| k as f64),
        -2.0..2.0f64,
        (0u32..6).prop_map(|k| [f64::NAN, f64::INFINITY, 1e300, -1e-300, 1e9, 0.5][k as usize]),
        any::<f64>(),
    ];
    let line = prop_oneof![
        3 => (number.clone(), number.clone(), number).prop_map(|(a, b, c)| format!("v {a:?} {b:?} {c:?}")),
        3 => prop::collection::vec((-10i64..12, 0u8..3), 0..7).prop_map(|v| {
            let words: Vec<String> = v
                .iter()
                .map(|&(i, form)| match form {
                    0 => i.to_string(),
                    1 => format!("{i}/1/1"),
                    _ => format!("{i}//2"),
                })
                .collect();
            format!("f {}", words.join(" "))
        }),
        1 => "[a-z #/0-9.\\-]{0,16}",
    ];
    let structured = prop::collection::vec(line, 0..40).prop_map(|l| l.join("\n").into_bytes());
    let strategy = prop_oneof![
        mutated(CUBE_OBJ.as_bytes().to_vec()),
        structured,
        prop::collection::vec(any::<u8>(), 0..300),
    ];
    fuzz("obj", strategy, |bytes| obj_body(&bytes));
}

/// A valid checkpoint of the small case, its simulation, and the case.
fn checkpoint_bytes() -> (Vec<u8>, bisph_io::LoadedCase) {
    checkpoint_bytes_of(VALID, &[])
}

/// A valid checkpoint of the 2-D case `text` (with `overrides`) after one step.
fn checkpoint_bytes_of(text: &str, overrides: &[String]) -> (Vec<u8>, bisph_io::LoadedCase) {
    let loaded = parse_case("<fuzz>", text, overrides).unwrap();
    let mut sim = build_simulation::<DVec2>(&loaded).unwrap();
    sim.advance(None).unwrap();
    let mut state = SimState::default();
    state.capture(&sim);
    let c = Checkpoint {
        case_source: "<fuzz>".into(),
        case_text: loaded.text.clone(),
        sim: state,
        run: checkpoint::RunCounters {
            next_series: sim.time,
            frame_times: vec![0.0],
            ..Default::default()
        },
        history: vec![[0.0; checkpoint::ENERGY_COLUMNS]; 3],
        probe_history: vec![vec![0.0, 1.0]; 3],
        settling: None,
    };
    (checkpoint::encode(&c), loaded)
}

/// Re-seals mutated bytes with a valid checksum so the payload reader itself is exercised.
fn reseal(mut b: Vec<u8>) -> Vec<u8> {
    if b.len() >= 8 {
        let n = b.len() - 8;
        let sum = checkpoint::fnv1a64(&b[..n]);
        b[n..].copy_from_slice(&sum.to_le_bytes());
    }
    b
}

fn checkpoint_body(bytes: &[u8], loaded: &bisph_io::LoadedCase) {
    let path = Path::new("<fuzz>");
    if let Ok(c) = checkpoint::decode::<DVec2>(path, bytes) {
        let mut sim = build_simulation::<DVec2>(loaded).unwrap();
        if c.sim.restore(&mut sim).is_ok() && c.run.check(sim.time, 0.0, 0.0).is_ok() {
            ACCEPTED.fetch_add(1, Ordering::Relaxed);
            for _ in 0..2 {
                if sim.advance(None).is_err() {
                    break;
                }
            }
        }
    }
    let _ = checkpoint::decode::<glam::DVec3>(path, bytes);
}

#[test]
fn fuzz_checkpoint() {
    let (good, loaded) = checkpoint_bytes();
    let strategy = prop_oneof![
        mutated(good.clone()).prop_map(reseal),
        mutated(good.clone()),
        prop::collection::vec(any::<u8>(), 0..200).prop_map(|mut b| {
            let mut head = checkpoint::MAGIC.to_vec();
            head.append(&mut b);
            reseal(head)
        }),
    ];
    fuzz("checkpoint", strategy, |bytes| {
        checkpoint_body(&bytes, &loaded)
    });
}

/// Checkpoints holding a free rigid body (format 4's body section), mutated and re-sealed.
#[test]
fn fuzz_checkpoint_free_body() {
    let text = include_str!("../../../cases/floating-box-2d.toml");
    let (good, loaded) = checkpoint_bytes_of(text, &["resolution.dx=0.08".into()]);
    let strategy = prop_oneof![mutated(good.clone()).prop_map(reseal), mutated(good)];
    fuzz("checkpoint-free-body", strategy, |bytes| {
        checkpoint_body(&bytes, &loaded)
    });
}

/// The corpus of inputs that once failed, replayed on every run.
#[test]
fn fuzz_corpus_regressions() {
    for (path, bytes) in corpus("case") {
        eprintln!("replaying {}", path.display());
        case_body(&String::from_utf8_lossy(&bytes), &[]);
    }
    for (path, bytes) in corpus("overrides") {
        eprintln!("replaying {}", path.display());
        let text = String::from_utf8_lossy(&bytes);
        let overrides: Vec<String> = text.lines().map(String::from).collect();
        case_body(VALID, &overrides);
    }
    for (path, bytes) in corpus("rows-stl") {
        eprintln!("replaying {}", path.display());
        let _ = parse_rows(&String::from_utf8_lossy(&bytes), &path, 2);
        let _ = parse_stl(&bytes, &path);
    }
    for (path, bytes) in corpus("obj") {
        eprintln!("replaying {}", path.display());
        obj_body(&bytes);
    }
    let (_, loaded) = checkpoint_bytes();
    for (path, bytes) in corpus("checkpoint") {
        eprintln!("replaying {}", path.display());
        checkpoint_body(&bytes, &loaded);
    }
}

/// Hostile inputs that must be refused by name: accepted, each would exhaust memory (a
/// coordinate of 1e300 sizing the cell grid), loop for ever (a next output time far in the past)
/// or feed NaN into the geometry (an STL vertex `nan`).
#[test]
fn hostile_inputs_are_refused() {
    let (good, loaded) = checkpoint_bytes();
    let path = Path::new("<hostile>");
    let c = checkpoint::decode::<DVec2>(path, &good).unwrap();
    let mut sim = build_simulation::<DVec2>(&loaded).unwrap();
    let mut far = c.clone();
    far.sim.fluid.position[0] = DVec2::new(1e300, 0.0);
    let back = checkpoint::decode::<DVec2>(path, &checkpoint::encode(&far)).unwrap();
    let e = back.sim.restore(&mut sim).unwrap_err();
    assert!(e.contains("outside the domain"), "{e}");
    let mut walls = c.clone();
    walls.sim.centre[0] = DVec2::new(1e300, 1e300);
    let e = walls.sim.restore(&mut sim).unwrap_err();
    assert!(e.contains("far beyond"), "{e}");
    let mut past = c.clone();
    past.run.next_series = -1e300;
    assert!(past.run.check(0.01, 1e-3, 0.0).is_err());
    past.run.next_series = f64::NAN;
    assert!(past.run.check(0.01, 1e-3, 0.0).is_err());
    let stl =
        b"solid t\nouter loop\nvertex nan 0 0\nvertex 1 0 0\nvertex 0 1 0\nendloop\nendsolid\n";
    let file = std::env::temp_dir().join(format!("bisph-hostile-{}.stl", std::process::id()));
    std::fs::write(&file, stl).unwrap();
    let e = bisph_io::formats::mesh_files::read_stl(&file).unwrap_err();
    assert!(e.contains("non-finite"), "{e}");
    let _ = std::fs::remove_file(&file);
    // OBJ: a non-finite vertex is refused by name; a vertex far off (or a mesh in the wrong
    // units) would once have made elements without bound at the case's element size.
    let nan = CUBE_OBJ.replace("v 1 1 1", "v 1 nan 1");
    let e = parse_obj(&nan, Path::new("nan.obj")).unwrap_err();
    assert!(e.contains("nan.obj:9") && e.contains("finite"), "{e}");
    let far = "v 0 0 0\nv 1e12 0 0\nv 0 1e12 0\nf 1 2 3\n";
    let p = parse_obj(far, Path::new("far.obj")).unwrap();
    let s = Surface::from_polygons(&p, None, 1e-9).unwrap();
    let e = checked_elements(&s, 0.01).unwrap_err();
    assert!(
        e.contains("boundary elements") && e.contains("units"),
        "{e}"
    );
}
