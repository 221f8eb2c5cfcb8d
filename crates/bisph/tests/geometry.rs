//! Geometry mistakes are found before the first step: each gives exit code 7, a message
//! naming the block or wall, and leaves no output folder behind.

mod common;
use common::bisph;

use std::path::{Path, PathBuf};

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
    particles_in(&run_briefly(name, case))
}

/// The fluid particle count of `summary.json` in `dir/out`.
fn particles_in(dir: &Path) -> u64 {
    let text = std::fs::read_to_string(dir.join("out/summary.json")).unwrap();
    let summary: serde_json::Value = serde_json::from_str(&text).unwrap();
    summary["fluid_particles"].as_u64().unwrap()
}

/// Runs `case` for its few steps into `out` of the folder returned.
fn run_briefly(name: &str, case: &str) -> common::Scratch {
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
    dir
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
    // A closed box obstacle on the floor: the points inside meet its bottom going down, which
    // faces up. 20 x 20 x 10 cells below the level, minus the 10 x 10 x 7 inside the obstacle.
    let case = format!(
        "{TANK_3D}[[wall]]\nshape = \"box\"\nmin = [0.0, 0.0, 0.0]\nmax = [2.0, 2.0, 2.0]\nopen = [\"+z\"]\n\
         [[wall]]\nshape = \"box\"\nmin = [0.5, 0.5, 0.0]\nmax = [1.5, 1.5, 0.7]\nfluid = \"outside\"\n\
         [[fluid_block]]\nshape = \"walls\"\nlevel = 1.0\n"
    );
    assert_eq!(fluid_particles("fill-3d-floor-obstacle", &case), 4000 - 700);
}

#[test]
fn an_obstacle_open_towards_the_floor_it_stands_on_is_refused() {
    // The floor would run on under the obstacle: the walls would not bound the water.
    let obstacle = |open: &str, min_z: f64| {
        format!(
            "{TANK_3D}[[wall]]\nshape = \"box\"\nmin = [0.0, 0.0, 0.0]\nmax = [2.0, 2.0, 2.0]\nopen = [\"+z\"]\n\
             [[wall]]\nshape = \"box\"\nmin = [0.5, 0.5, {min_z}]\nmax = [1.5, 1.5, 0.7]\nopen = [{open}]\nfluid = \"outside\"\n\
             [[fluid_block]]\nshape = \"walls\"\nlevel = 1.0\n"
        )
    };
    refused(
        "open-on-floor-3d",
        &obstacle("\"-z\"", 0.0),
        &[
            "key `wall[1].open`",
            "the open face \"-z\" lies on wall[0]",
            "remove \"-z\" from open",
        ],
    );
    // The same face open above the floor is not on a wall (the water flows under the box).
    assert!(fluid_particles("open-above-floor-3d", &obstacle("\"-z\"", 0.05)) > 0);
    // A 2-D box obstacle open towards the floor, and a cylinder whose open end stands on it.
    let case = format!(
        "{TANK_2D}{BOX_WALL_2D}open = [\"+y\"]\n\
         [[wall]]\nshape = \"box\"\nmin = [0.4, 0.0]\nmax = [0.6, 0.2]\nopen = [\"-y\"]\nfluid = \"outside\"\n\
         [[fluid_block]]\nshape = \"walls\"\nlevel = 0.5\n"
    );
    refused(
        "open-on-floor-2d",
        &case,
        &["key `wall[1].open`", "the open face \"-y\" lies on wall[0]"],
    );
    let case = format!(
        "{TANK_3D}[[wall]]\nshape = \"box\"\nmin = [0.0, 0.0, 0.0]\nmax = [2.0, 2.0, 2.0]\nopen = [\"+z\"]\n\
         [[wall]]\nshape = \"cylinder\"\nstart = [1.0, 1.0, 0.0]\nend = [1.0, 1.0, 0.5]\nradius = 0.3\nopen = [\"start\"]\n\
         [[fluid_block]]\nshape = \"walls\"\nlevel = 1.0\n"
    );
    refused(
        "open-cylinder-on-floor-3d",
        &case,
        &[
            "key `wall[1].open`",
            "the open end \"start\" lies on wall[0]",
        ],
    );
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

/// Runs `case` with a VTK frame at `t = 0` and returns `summary.json`'s particle count and
/// the fluid particles of that first frame.
fn first_frame(name: &str, case: &str) -> (u64, Vec<[f64; 3]>) {
    let case = format!("{case}[output]\nvtk_interval = 0.001\nplots = false\n");
    let dir = run_briefly(name, &case);
    (
        particles_in(&dir),
        vtu_points(&dir.join("out/vtk/fluid_000000.vtu")),
    )
}

/// The points of a `.vtu` file written by `bisph` (appended raw data, `UInt64` headers).
fn vtu_points(path: &Path) -> Vec<[f64; 3]> {
    let bytes = std::fs::read(path).unwrap();
    let find = |from: usize, pattern: &str| {
        from + bytes[from..]
            .windows(pattern.len())
            .position(|w| w == pattern.as_bytes())
            .unwrap_or_else(|| panic!("`{pattern}` not in {}", path.display()))
    };
    let tag = find(0, "Name=\"Points\"");
    let at = find(tag, "offset=\"") + "offset=\"".len();
    let digits = bytes[at..]
        .iter()
        .take_while(|b| b.is_ascii_digit())
        .count();
    let offset: usize = std::str::from_utf8(&bytes[at..at + digits])
        .unwrap()
        .parse()
        .unwrap();
    let data = find(find(0, "<AppendedData"), "_") + 1 + offset;
    let count = u64::from_le_bytes(bytes[data..data + 8].try_into().unwrap()) as usize;
    let f64_at = |k: usize| {
        let i = data + 8 + 8 * k;
        f64::from_le_bytes(bytes[i..i + 8].try_into().unwrap())
    };
    (0..count / 24)
        .map(|p| [f64_at(3 * p), f64_at(3 * p + 1), f64_at(3 * p + 2)])
        .collect()
}

/// Lattice cell centres of spacing `dx` inside a disc of radius `rho`, at least and at most:
/// every cell whose centre is inside lies in the disc of radius `rho + dx/sqrt(2)`, and every
/// cell of the disc of radius `rho - dx/sqrt(2)` has its centre inside.
fn disc_cells(rho: f64, dx: f64) -> (f64, f64) {
    let half = dx / std::f64::consts::SQRT_2;
    let cells = |r: f64| std::f64::consts::PI * r.max(0.0).powi(2) / (dx * dx);
    (cells(rho - half), cells(rho + half))
}

#[test]
fn a_walls_block_fills_a_2d_tank_around_a_circle() {
    // An open tank with a circular obstacle (the default side of a circle): 20 x 12 cells
    // below the level, less those within the radius and the clearance of the circle.
    let (c, r) = ([0.5, 0.3], 0.15);
    let case = format!(
        "{TANK_2D}[[wall]]\nshape = \"box\"\nmin = [0.0, 0.0]\nmax = [1.0, 1.0]\nopen = [\"+y\"]\n\
         [[wall]]\nshape = \"circle\"\ncentre = [{}, {}]\nradius = {r}\n\
         [[fluid_block]]\nshape = \"walls\"\nlevel = 0.6\n",
        c[0], c[1]
    );
    let (n, points) = first_frame("circle-obstacle-2d", &case);
    assert_eq!(n as usize, points.len());
    let clearance = 0.025;
    for p in &points {
        let d = ((p[0] - c[0]).powi(2) + (p[1] - c[1]).powi(2)).sqrt();
        assert!(
            d > r + clearance * 0.99,
            "particle at {p:?} is {d} m from the centre"
        );
    }
    // 19 chords: the polygon lies between r cos(pi / 19) and r from the centre.
    let inner = r * (std::f64::consts::PI / 19.0).cos();
    let (_, most) = disc_cells(r + clearance, 0.05);
    let (least, _) = disc_cells(inner + clearance, 0.05);
    let (lo, hi) = (240.0 - most, 240.0 - least);
    assert!(n as f64 >= lo && n as f64 <= hi, "{n} not in [{lo}, {hi}]");
}

#[test]
fn a_circle_holds_a_circle_of_fluid_2d() {
    // A circular tank (`fluid = "inside"`) with a circular block of fluid, and a box block
    // with a circular hole around a circular obstacle of the same centre and radius.
    let case = format!(
        "{TANK_2D}[[wall]]\nshape = \"circle\"\ncentre = [0.5, 0.5]\nradius = 0.45\nfluid = \"inside\"\n\
         [[fluid_block]]\nshape = \"circle\"\ncentre = [0.5, 0.5]\nradius = 0.3\n"
    );
    // 38 chords: the polygon lies between r cos(pi / 38) and r from the centre.
    let n = fluid_particles("circle-tank-2d", &case) as f64;
    let (least, _) = disc_cells(0.3 * (std::f64::consts::PI / 38.0).cos(), 0.05);
    let (_, most) = disc_cells(0.3, 0.05);
    assert!(n >= least && n <= most, "{n} not in [{least}, {most}]");
    let case = format!(
        "{TANK_2D}{BOX_WALL_2D}[[wall]]\nshape = \"circle\"\ncentre = [0.5, 0.5]\nradius = 0.2\n\
         [[fluid_block]]\nshape = \"box\"\nmin = [0.0, 0.0]\nmax = [1.0, 1.0]\n\
         [[fluid_block.hole]]\nshape = \"circle\"\ncentre = [0.5, 0.5]\nradius = 0.2\n"
    );
    // 26 chords.
    let n = fluid_particles("circle-hole-2d", &case) as f64;
    let (least, _) = disc_cells(0.2 * (std::f64::consts::PI / 26.0).cos(), 0.05);
    let (_, most) = disc_cells(0.2, 0.05);
    assert!(n >= 400.0 - most && n <= 400.0 - least, "{n}");
}

#[test]
fn a_circle_tank_without_fluid_inside_is_refused() {
    // Circles are obstacles unless `fluid = "inside"`: fluid inside one is behind its walls.
    let case = format!(
        "{TANK_2D}[[wall]]\nshape = \"circle\"\ncentre = [0.5, 0.5]\nradius = 0.45\n\
         [[fluid_block]]\nshape = \"box\"\nmin = [0.3, 0.3]\nmax = [0.7, 0.5]\n"
    );
    refused(
        "circle-reversed-2d",
        &case,
        &["key `wall[0]`", "wrong way round", "`fluid = \"inside\"`"],
    );
}

#[test]
fn a_walls_block_fills_a_3d_cylinder_tank() {
    // A vertical cylinder of radius 0.5, open at its top end or closed by a lid, filled to
    // 0.5: 10 layers of the lattice cells within the radius less the clearance.
    let tank = TANK_3D.replace("dx = 0.1", "dx = 0.05");
    let (r, dx, clearance) = (0.5, 0.05, 0.025);
    let mut counts = Vec::new();
    for open in ["open = [\"end\"]\n", ""] {
        let case = format!(
            "{tank}[[wall]]\nshape = \"cylinder\"\nstart = [0.0, 0.0, 0.0]\nend = [0.0, 0.0, 1.0]\n\
             radius = {r}\nfluid = \"inside\"\n{open}\
             [[fluid_block]]\nshape = \"walls\"\nlevel = 0.5\n"
        );
        counts.push(fluid_particles("cylinder-tank-3d", &case));
    }
    assert_eq!(
        counts[0], counts[1],
        "open and closed tanks hold the same water"
    );
    // 63 sides: the polygon of the cross-section lies between r cos(pi / 63) and r.
    let inner = r * (std::f64::consts::PI / 63.0).cos();
    let (least, _) = disc_cells(inner - clearance, dx);
    let (_, most) = disc_cells(r - clearance, dx);
    let n = counts[0] as f64;
    assert!(n >= 10.0 * least && n <= 10.0 * most, "{n}");
    // Within 4% of the analytic pi (r - clearance)^2 level / dx^3.
    let analytic = std::f64::consts::PI * (r - clearance).powi(2) * 0.5 / dx.powi(3);
    assert!((n - analytic).abs() < 0.04 * analytic, "{n} vs {analytic}");
}

#[test]
fn a_walls_block_fills_a_3d_tank_around_a_sphere() {
    let (c, r) = ([0.5, 0.5, 0.3], 0.2);
    let case = format!(
        "{TANK_3D}[[wall]]\nshape = \"box\"\nmin = [0.0, 0.0, 0.0]\nmax = [1.0, 1.0, 1.0]\nopen = [\"+z\"]\n\
         [[wall]]\nshape = \"sphere\"\ncentre = [{}, {}, {}]\nradius = {r}\n\
         [[fluid_block]]\nshape = \"walls\"\nlevel = 0.6\n",
        c[0], c[1], c[2]
    );
    let (n, points) = first_frame("sphere-obstacle-3d", &case);
    assert_eq!(n as usize, points.len());
    for p in &points {
        let d = (0..3).map(|k| (p[k] - c[k]).powi(2)).sum::<f64>().sqrt();
        assert!(d > r, "particle at {p:?} is {d} m from the centre");
    }
    // 10 x 10 x 6 cells, less about the ball of radius r plus the clearance (65 cells).
    assert!(n > 600 - 100 && n < 600 - 40, "{n}");
}

#[test]
fn spheres_and_cylinders_are_fluid_regions_3d() {
    let tank = format!(
        "{}[[wall]]\nshape = \"box\"\nmin = [0.0, 0.0, 0.0]\nmax = [1.0, 1.0, 1.0]\n",
        TANK_3D.replace("dx = 0.1", "dx = 0.05")
    );
    let volume = |n: u64| n as f64 * 0.05f64.powi(3);
    let pi = std::f64::consts::PI;
    let case = format!(
        "{tank}[[fluid_block]]\nshape = \"cylinder\"\nstart = [0.5, 0.5, 0.1]\nend = [0.5, 0.5, 0.5]\nradius = 0.3\n"
    );
    let v = volume(fluid_particles("cylinder-block-3d", &case));
    let exact = pi * 0.09 * 0.4;
    assert!((v - exact).abs() < 0.06 * exact, "{v} vs {exact}");
    let case = format!(
        "{tank}[[fluid_block]]\nshape = \"sphere\"\ncentre = [0.5, 0.5, 0.5]\nradius = 0.3\n"
    );
    let v = volume(fluid_particles("sphere-block-3d", &case));
    let exact = 4.0 / 3.0 * pi * 0.027;
    assert!((v - exact).abs() < 0.06 * exact, "{v} vs {exact}");
    // Holes of the same shape as an obstacle wall match it: no particle behind the wall.
    for (hole, name) in [
        (
            "shape = \"cylinder\"\nstart = [0.5, 0.5, 0.2]\nend = [0.6, 0.5, 0.4]\nradius = 0.1\n",
            "cylinder-hole-3d",
        ),
        (
            "shape = \"sphere\"\ncentre = [0.5, 0.5, 0.3]\nradius = 0.15\n",
            "sphere-hole-3d",
        ),
    ] {
        let case = format!(
            "{tank}[[wall]]\n{hole}[[fluid_block]]\nshape = \"box\"\nmin = [0.05, 0.05, 0.05]\n\
             max = [0.95, 0.95, 0.6]\n[[fluid_block.hole]]\n{hole}"
        );
        assert!(fluid_particles(name, &case) > 3000, "{name}");
    }
}

#[test]
fn round_shape_keys_are_checked() {
    let tank_3d = format!("{TANK_3D}[[fluid_block]]\nshape = \"walls\"\nlevel = 0.5\n");
    let block_2d = "[[fluid_block]]\nshape = \"box\"\nmin = [0.1, 0.1]\nmax = [0.4, 0.4]\n";
    let cylinder = |rest: &str| format!("{tank_3d}[[wall]]\nshape = \"cylinder\"\n{rest}");
    let cases = [
        (
            format!("{TANK_2D}{BOX_WALL_2D}[[wall]]\nshape = \"circle\"\ncentre = [0.5, 0.5]\n{block_2d}"),
            "wall[1].radius",
            "missing",
        ),
        (
            format!("{TANK_2D}{BOX_WALL_2D}[[wall]]\nshape = \"circle\"\ncentre = [0.5, 0.5]\nradius = -0.2\n{block_2d}"),
            "wall[1].radius",
            "found -0.2",
        ),
        (
            format!("{TANK_2D}[[wall]]\nshape = \"circle\"\ncentre = [0.5, 0.5, 0.5]\nradius = 0.2\n{block_2d}"),
            "wall[0].centre",
            "expected 2 finite numbers (m), found [0.5, 0.5, 0.5]",
        ),
        (
            format!("{TANK_2D}[[wall]]\nshape = \"sphere\"\ncentre = [0.5, 0.5]\nradius = 0.2\n{block_2d}"),
            "wall[0].shape",
            "\"sphere\" is a 3-D shape, but the case is 2-D",
        ),
        (
            format!("{tank_3d}[[wall]]\nshape = \"circle\"\ncentre = [0.5, 0.5]\nradius = 0.2\n"),
            "wall[0].shape",
            "\"circle\" is a 2-D shape, but the case is 3-D",
        ),
        (
            cylinder("start = [0.0, 0.0, 0.0]\nend = [0.0, 0.0, 0.0]\nradius = 0.5\n"),
            "wall[0].end",
            "expected an axis of positive length: end = [0, 0, 0] is start = [0, 0, 0]",
        ),
        (
            cylinder("start = [0.0, 0.0, 0.0]\nradius = 0.5\n"),
            "wall[0].end",
            "missing",
        ),
        (
            cylinder("start = [0.0, 0.0, 0.0]\nend = [0.0, 0.0, 1.0]\nradius = 0.5\nopen = [\"top\"]\n"),
            "wall[0].open",
            "found \"top\"",
        ),
        (
            cylinder("start = [0.0, 0.0, 0.0]\nend = [0.0, 0.0, 1.0]\nradius = 0.5\nfluid = \"in\"\n"),
            "wall[0].fluid",
            "found \"in\"",
        ),
        (
            cylinder("centre = [0.0, 0.0, 0.0]\nradius = 0.5\n"),
            "wall[0].centre",
            "a cylinder has no `centre`",
        ),
        (
            cylinder("start = [0.0, 0.0, 0.0]\nend = [0.0, 0.0, 1.0]\nradius = 0.5\nscale = 2.0\n"),
            "wall[0].scale",
            "takes no `scale`",
        ),
        (
            format!("{TANK_2D}{BOX_WALL_2D}radius = 0.5\n{block_2d}"),
            "wall[0].radius",
            "a \"box\" wall takes no `radius`",
        ),
        (
            format!("{TANK_2D}{BOX_WALL_2D}[[fluid_block]]\nshape = \"circle\"\nradius = 0.2\n"),
            "fluid_block[0].centre",
            "missing",
        ),
        (
            format!("{TANK_3D}[[wall]]\nshape = \"box\"\nmin = [0.0, 0.0, 0.0]\nmax = [1.0, 1.0, 1.0]\n\
                     [[fluid_block]]\nshape = \"cylinder\"\nstart = [0.5, 0.5, 0.1]\nend = [0.5, 0.5, 0.5]\nradius = 0.0\n"),
            "fluid_block[0].radius",
            "found 0",
        ),
        (
            format!("{TANK_3D}[[wall]]\nshape = \"box\"\nmin = [0.0, 0.0, 0.0]\nmax = [1.0, 1.0, 1.0]\n\
                     [[fluid_block]]\nshape = \"box\"\nmin = [0.1, 0.1, 0.1]\nmax = [0.9, 0.9, 0.5]\n\
                     [[fluid_block.hole]]\nshape = \"cylinder\"\nstart = [0.5, 0.5, 0.2]\nend = [0.5, 0.5, 0.2]\nradius = 0.1\n"),
            "fluid_block[0].hole[0].end",
            "positive length",
        ),
    ];
    let dir = common::temp_dir("geometry", "round-keys");
    for (case, key, fragment) in cases {
        let file = dir.join("case.toml");
        std::fs::write(&file, &case).unwrap();
        let out = dir.join("out");
        let o = bisph(&[
            "run",
            file.to_str().unwrap(),
            "--out",
            out.to_str().unwrap(),
        ]);
        let err = String::from_utf8_lossy(&o.stderr);
        assert_eq!(o.status.code(), Some(1), "{key}: {err}");
        assert!(err.starts_with("error: "), "{key}: {err}");
        assert!(err.contains(file.to_str().unwrap()), "{key}: {err}");
        assert!(err.contains(&format!("key `{key}`")), "{key}: {err}");
        assert!(err.contains(fragment), "{key}: `{fragment}` not in {err}");
        assert!(!out.exists(), "{key}: the output folder was created");
    }
}
