//! Geometry mistakes are found before the first step: each gives exit code 7, a message
//! naming the block or wall, and leaves no output folder behind.

mod common;
use common::bisph;

use std::path::PathBuf;

const TANK_2D: &str = r#"
name = "t"
dim = 2
[fluid]
density = 1000.0
sound_speed = 20.0
gravity = [0.0, -9.81]
[resolution]
dx = 0.05
[time]
end = 0.01
"#;

const TANK_3D: &str = r#"
name = "t"
dim = 3
[fluid]
density = 1000.0
sound_speed = 20.0
gravity = [0.0, 0.0, -9.81]
[resolution]
dx = 0.1
[time]
end = 0.01
"#;

const BOX_WALL_2D: &str = "[[wall]]\nshape = \"box\"\nmin = [0.0, 0.0]\nmax = [1.0, 1.0]\n";

/// Runs `case` (written into a fresh folder) and checks the exit code, that every expected
/// fragment is in the error line, and that the output folder was not created.
fn refused(name: &str, case: &str, expected: &[&str]) {
    let dir = common::temp_dir("geometry", name);
    std::fs::write(dir.join("cube.stl"), cube_stl()).unwrap();
    let file = dir.join("case.toml");
    std::fs::write(&file, case).unwrap();
    let out: PathBuf = dir.join("out");
    let o = bisph(&[
        "run",
        file.to_str().unwrap(),
        "--out",
        out.to_str().unwrap(),
        "--quiet",
    ]);
    let err = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(7), "{name}: {err}");
    assert!(err.starts_with("error: "), "{name}: {err}");
    assert!(err.contains(file.to_str().unwrap()), "{name}: {err}");
    for fragment in expected {
        assert!(err.contains(fragment), "{name}: `{fragment}` not in {err}");
    }
    assert!(!err.contains("panicked"), "{name}: {err}");
    assert!(!out.exists(), "{name}: the output folder was created");
}

/// An ASCII STL of the cube [0, 1]^3, triangles facing out.
fn cube_stl() -> String {
    let v = |i: usize| [(i & 1) as f64, (i >> 1 & 1) as f64, (i >> 2 & 1) as f64];
    let faces = [
        [0, 4, 6, 2],
        [1, 3, 7, 5],
        [0, 1, 5, 4],
        [2, 6, 7, 3],
        [0, 2, 3, 1],
        [4, 5, 7, 6],
    ];
    let mut s = String::from("solid cube\n");
    for f in faces {
        for t in [[f[0], f[1], f[2]], [f[0], f[2], f[3]]] {
            s += "facet normal 0 0 0\nouter loop\n";
            for i in t {
                let p = v(i);
                s += &format!("vertex {} {} {}\n", p[0], p[1], p[2]);
            }
            s += "endloop\nendfacet\n";
        }
    }
    s + "endsolid cube\n"
}

#[test]
fn a_block_outside_the_walls_is_refused() {
    let case = format!(
        "{TANK_2D}{BOX_WALL_2D}[[fluid_block]]\nshape = \"box\"\nmin = [1.5, 0.0]\nmax = [2.0, 0.5]\n"
    );
    refused(
        "outside-2d",
        &case,
        &[
            "key `fluid_block[0]`",
            "outside the walls",
            "behind wall[0]",
        ],
    );
}

#[test]
fn a_block_overlapping_a_wall_is_refused() {
    let case = format!(
        "{TANK_2D}{BOX_WALL_2D}[[fluid_block]]\nshape = \"box\"\nmin = [-0.2, 0.0]\nmax = [0.5, 0.5]\n"
    );
    refused(
        "overlap-2d",
        &case,
        &[
            "key `fluid_block[0]`",
            "overlaps wall[0]",
            "0.175 m behind it",
        ],
    );
}

#[test]
fn a_tank_drawn_the_wrong_way_round_is_refused() {
    let case = format!(
        "{TANK_2D}[[wall]]\nshape = \"polygon\"\npoints = [[0.0, 0.0], [0.0, 1.0], [1.0, 1.0], [1.0, 0.0]]\n\
         [[fluid_block]]\nshape = \"box\"\nmin = [0.0, 0.0]\nmax = [0.5, 0.5]\n"
    );
    refused(
        "reversed-2d",
        &case,
        &["key `wall[0]`", "wrong way round", "counter-clockwise"],
    );
}

#[test]
fn a_wall_crossing_itself_is_refused() {
    let case = format!(
        "{TANK_2D}[[wall]]\nshape = \"polygon\"\npoints = [[0.0, 0.0], [1.0, 0.0], [0.0, 1.0], [1.0, 1.0]]\n\
         [[fluid_block]]\nshape = \"box\"\nmin = [0.3, 0.0]\nmax = [0.7, 0.2]\n"
    );
    refused(
        "crossing-2d",
        &case,
        &["key `wall[0].points`", "crosses itself", "(0.5, 0.5)"],
    );
}

#[test]
fn a_3d_block_outside_a_closed_mesh_is_refused() {
    let case = format!(
        "{TANK_3D}[[wall]]\nshape = \"mesh\"\nfile = \"cube.stl\"\n\
         [[fluid_block]]\nshape = \"box\"\nmin = [2.0, 0.0, 0.0]\nmax = [2.5, 0.5, 0.5]\n"
    );
    refused(
        "outside-3d",
        &case,
        &["key `fluid_block[0]`", "outside the walls", "wall[0]"],
    );
}

#[test]
fn a_3d_block_overlapping_a_box_wall_is_refused() {
    let case = format!(
        "{TANK_3D}[[wall]]\nshape = \"box\"\nmin = [0.0, 0.0, 0.0]\nmax = [1.0, 1.0, 1.0]\n\
         [[fluid_block]]\nshape = \"box\"\nmin = [0.5, 0.0, 0.0]\nmax = [1.5, 0.5, 0.5]\n"
    );
    refused(
        "overlap-3d",
        &case,
        &["key `fluid_block[0]`", "overlaps wall[0]"],
    );
}

#[test]
fn a_3d_open_mesh_flipped_into_the_fluid_is_refused() {
    let case = format!(
        "{TANK_3D}[[wall]]\nshape = \"mesh\"\nfile = \"cube.stl\"\nclosed = false\nflip = true\n\
         [[fluid_block]]\nshape = \"box\"\nmin = [0.0, 0.0, 0.0]\nmax = [0.5, 0.5, 0.5]\n"
    );
    refused(
        "reversed-3d",
        &case,
        &["key `wall[0]`", "wrong way round", "facing out"],
    );
}

/// Runs `case` for its few steps and returns `summary.json`'s particle count.
fn fluid_particles(name: &str, case: &str) -> u64 {
    let dir = common::temp_dir("geometry", name);
    std::fs::write(dir.join("cube.stl"), cube_stl()).unwrap();
    let file = dir.join("case.toml");
    std::fs::write(&file, case).unwrap();
    let out = dir.join("out");
    let o = bisph(&[
        "run",
        file.to_str().unwrap(),
        "--out",
        out.to_str().unwrap(),
        "--quiet",
        "--set",
        "time.end=0.002",
        "--set",
        "settle.enabled=false",
    ]);
    assert!(
        o.status.success(),
        "{name}: {}",
        String::from_utf8_lossy(&o.stderr)
    );
    let summary: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("summary.json")).unwrap()).unwrap();
    summary["fluid_particles"].as_u64().unwrap()
}

#[test]
fn a_walls_block_fills_an_open_tank_around_an_obstacle_2d() {
    // 20 x 10 cells below the level, minus the 6 x 4 inside the clockwise obstacle.
    let case = format!(
        "{TANK_2D}[[wall]]\nshape = \"box\"\nmin = [0.0, 0.0]\nmax = [1.0, 1.0]\nopen = [\"+y\"]\n\
         [[wall]]\nshape = \"polygon\"\npoints = [[0.3, 0.1], [0.3, 0.3], [0.6, 0.3], [0.6, 0.1]]\n\
         [[fluid_block]]\nshape = \"walls\"\nlevel = 0.5\n"
    );
    assert_eq!(fluid_particles("fill-2d", &case), 200 - 24);
}

#[test]
fn a_walls_block_keeps_its_clearance_from_a_slanted_wall_2d() {
    // An open tank with a chamfered corner, filled one spacing clear of its walls: the
    // 18 x 9 cells clear of the box, less those near the chamfer.
    let case = format!(
        "{TANK_2D}[[wall]]\nshape = \"polyline\"\n\
         points = [[0.0, 1.0], [0.0, 0.2], [0.2, 0.0], [1.0, 0.0], [1.0, 1.0]]\n\
         [[fluid_block]]\nshape = \"walls\"\nlevel = 0.5\nclearance = 1.0\n"
    );
    let n = fluid_particles("fill-slope-2d", &case);
    assert!(n > 140 && n < 18 * 9, "{n}");
}

#[test]
fn a_walls_block_fills_a_3d_tank_around_an_stl_obstacle() {
    // 20 x 20 x 10 cells below the level, minus the 10 x 10 x 7 inside the cube.
    let case = format!(
        "{TANK_3D}[[wall]]\nshape = \"box\"\nmin = [0.0, 0.0, 0.0]\nmax = [2.0, 2.0, 2.0]\nopen = [\"+z\"]\n\
         [[wall]]\nshape = \"mesh\"\nfile = \"cube.stl\"\nfluid = \"outside\"\ntranslate = [0.5, 0.5, 0.3]\n\
         [[fluid_block]]\nshape = \"walls\"\nlevel = 1.0\n"
    );
    assert_eq!(fluid_particles("fill-3d", &case), 4000 - 700);
}

#[test]
fn a_walls_block_leaves_out_an_obstacle_standing_on_the_floor_3d() {
    // A box obstacle without a bottom of its own (open towards the floor): the points inside
    // meet the tank's floor going down, but the obstacle's top going up. 20 x 20 x 10 cells
    // below the level, minus the 10 x 10 x 7 inside the obstacle.
    let case = format!(
        "{TANK_3D}[[wall]]\nshape = \"box\"\nmin = [0.0, 0.0, 0.0]\nmax = [2.0, 2.0, 2.0]\nopen = [\"+z\"]\n\
         [[wall]]\nshape = \"box\"\nmin = [0.5, 0.5, 0.0]\nmax = [1.5, 1.5, 0.7]\nopen = [\"-z\"]\nfluid = \"outside\"\n\
         [[fluid_block]]\nshape = \"walls\"\nlevel = 1.0\n"
    );
    assert_eq!(fluid_particles("fill-3d-floor-obstacle", &case), 4000 - 700);
}

#[test]
fn walls_block_keys_are_checked() {
    let dir = common::temp_dir("geometry", "walls-keys");
    let base = format!("{TANK_2D}{BOX_WALL_2D}[[fluid_block]]\nshape = \"walls\"\n");
    for (case, key) in [
        (base.clone(), "fluid_block[0].level"),
        (format!("{base}level = 0.5\nclearance = -1.0\n"), "fluid_block[0].clearance"),
        (
            format!("{TANK_2D}{BOX_WALL_2D}[[fluid_block]]\nshape = \"box\"\nmin = [0.0, 0.0]\nmax = [0.5, 0.5]\nlevel = 0.5\n"),
            "fluid_block[0]",
        ),
    ] {
        let file = dir.join("case.toml");
        std::fs::write(&file, case).unwrap();
        let o = bisph(&["run", file.to_str().unwrap(), "--out", dir.join("out").to_str().unwrap()]);
        let err = String::from_utf8_lossy(&o.stderr);
        assert_eq!(o.status.code(), Some(1), "{err}");
        assert!(err.contains(&format!("key `{key}`")), "{key}: {err}");
    }
}
