//! Walls from meshes against the same walls built from primitives: a closed box as an OBJ of
//! quads, as an ASCII and a binary STL of triangles, and the named errors of bad meshes; the
//! generated cylinder and sphere walls facing out of the fluid.

use bisph_core::geometry::{box_elements_3d, triangulate, ElementShape};
use bisph_core::walls::geometric_shepard::gamma;
use bisph_core::Simulation;
use bisph_io::case::build_simulation;
use bisph_io::formats::mesh_files::{write_stl_ascii, write_stl_binary};
use bisph_io::parse_case;
use glam::DVec3;
use std::fmt::Write as _;
use std::path::PathBuf;

const LO: [f64; 3] = [0.0, 0.0, 0.0];
const HI: [f64; 3] = [0.4, 0.3, 0.3];
const DX: f64 = 0.05;

/// Corners of a primitive element in the order of its normal (the primitives do not care).
fn wound(e: &ElementShape<DVec3>) -> Vec<DVec3> {
    let c = &e.corners;
    let mut twice = DVec3::ZERO;
    for k in 0..c.len() {
        twice += c[k].cross(c[(k + 1) % c.len()]);
    }
    let mut out = c.clone();
    if twice.dot(e.normal) < 0.0 {
        out.reverse();
    }
    out
}

fn triangles(shapes: &[ElementShape<DVec3>]) -> Vec<[DVec3; 3]> {
    shapes
        .iter()
        .map(|t| {
            let c = wound(t);
            [c[0], c[1], c[2]]
        })
        .collect()
}

fn temp(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("bisph-mesh-walls-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    dir.join(name)
}

fn case(wall: &str, boundary: &str) -> String {
    format!(
        r#"name = "mesh-box"
dim = 3
boundary = "{boundary}"
shepard = "geometric"
[fluid]
density = 1000.0
sound_speed = 20.0
gravity = [0.0, 0.0, -9.81]
[resolution]
dx = {DX}
[time]
end = 0.01
[[fluid_block]]
shape = "box"
min = [0.0, 0.0, 0.0]
max = [0.4, 0.3, 0.2]
[[wall]]
{wall}
"#
    )
}

fn build(wall: &str, boundary: &str) -> Simulation<DVec3> {
    let loaded = parse_case("<test>", &case(wall, boundary), &[]).unwrap();
    build_simulation::<DVec3>(&loaded).unwrap()
}

fn primitive(boundary: &str) -> Simulation<DVec3> {
    build(
        "shape = \"box\"\nmin = [0.0, 0.0, 0.0]\nmax = [0.4, 0.3, 0.3]",
        boundary,
    )
}

/// Total wall force, and the largest differences of the fluid rates, between two builds.
fn compare(a: &Simulation<DVec3>, b: &Simulation<DVec3>) -> (f64, f64, f64) {
    let fa = a.walls.body_loads(0.0)[0].0;
    let fb = b.walls.body_loads(0.0)[0].0;
    // Pressure force on the bottom (the fluid's weight, minus the side-wall share).
    let bottom = |s: &Simulation<DVec3>| -> f64 {
        let e = &s.walls.elements;
        (0..e.len())
            .filter(|&j| e.normal[j].z < -0.5)
            .map(|j| e.pressure[j] * e.area[j])
            .sum()
    };
    let force = (fa - fb).length() / bottom(a);
    let bottom_rel = (bottom(a) - bottom(b)).abs() / bottom(a);
    let scale = 9.81;
    let acc = a
        .fluid
        .acceleration
        .iter()
        .zip(&b.fluid.acceleration)
        .map(|(x, y)| (*x - *y).length() / scale)
        .fold(0.0, f64::max);
    (force, bottom_rel, acc)
}

fn gamma_difference(a: &Simulation<DVec3>, b: &Simulation<DVec3>) -> f64 {
    let k = &a.config.kernel;
    let mut worst: f64 = 0.0;
    for p in [
        DVec3::new(0.01, 0.02, 0.03),
        DVec3::new(0.2, 0.15, 0.02),
        DVec3::new(0.39, 0.29, 0.29),
        DVec3::new(0.2, 0.15, 0.15),
        DVec3::new(0.0, 0.1, 0.1),
    ] {
        let ga = gamma(k, p, &a.walls.elements, &a.walls.grid);
        let gb = gamma(k, p, &b.walls.elements, &b.walls.grid);
        worst = worst.max((ga - gb).abs());
    }
    worst
}

#[test]
fn closed_box_obj_of_quads_matches_the_primitive_box() {
    let patches = box_elements_3d(DVec3::from_array(LO), DVec3::from_array(HI), &[], DX);
    let mut obj = String::from("# closed box, one quad per patch\n");
    for p in &patches {
        for c in &wound(p) {
            let _ = writeln!(obj, "v {:.17e} {:.17e} {:.17e}", c.x, c.y, c.z);
        }
        let _ = writeln!(obj, "f -4 -3 -2 -1");
    }
    let path = temp("box.obj");
    std::fs::write(&path, obj).unwrap();
    for boundary in ["energy", "bi"] {
        let a = primitive(boundary);
        let b = build(
            &format!("shape = \"mesh\"\nfile = \"{}\"", path.display()),
            boundary,
        );
        assert_eq!(a.walls.elements.len(), b.walls.elements.len());
        let g = gamma_difference(&a, &b);
        let (force, bottom, acc) = compare(&a, &b);
        assert!(g < 1e-12, "{boundary}: gamma differs by {g}");
        assert!(
            force < 1e-12 && bottom < 1e-12,
            "{boundary}: {force} {bottom}"
        );
        assert!(acc < 1e-10, "{boundary}: accelerations differ by {acc} g");
    }
}

#[test]
fn closed_box_stl_matches_the_primitive_box() {
    let tris = triangulate(box_elements_3d(
        DVec3::from_array(LO),
        DVec3::from_array(HI),
        &[],
        DX,
    ));
    let soup = triangles(&tris);
    let ascii = temp("box-ascii.stl");
    write_stl_ascii(&ascii, &soup).unwrap();
    // Binary STL stores f32: the box corners here are exact in f32 only up to rounding.
    let binary = temp("box-binary.stl");
    write_stl_binary(&binary, &soup).unwrap();
    // A coarse STL: 12 triangles, refined by the reader to elements of about dx.
    let coarse = temp("box-coarse.stl");
    let coarse_soup = triangles(&triangulate(box_elements_3d(
        DVec3::from_array(LO),
        DVec3::from_array(HI),
        &[],
        1.0,
    )));
    assert_eq!(coarse_soup.len(), 12);
    write_stl_binary(&coarse, &coarse_soup).unwrap();
    let a = primitive("bi");
    for (path, g_tol, f_tol, acc_tol) in [
        // Triangles against quads: gamma is exact for both; the one-point wall terms differ
        // by the element shapes (a few per cent of g near the walls).
        (&ascii, 1e-10, 1e-6, 0.2),
        (&binary, 1e-6, 1e-5, 0.2),
        (&coarse, 1e-5, 0.05, 0.3),
    ] {
        let b = build(
            &format!("shape = \"mesh\"\nfile = \"{}\"", path.display()),
            "bi",
        );
        let g = gamma_difference(&a, &b);
        let (force, bottom, acc) = compare(&a, &b);
        eprintln!(
            "{}: gamma {g:.2e}, net force {force:.2e}, bottom force {bottom:.2e}, acc {acc:.2e} g",
            path.display()
        );
        assert!(g < g_tol, "{}: gamma differs by {g}", path.display());
        assert!(force < f_tol && bottom < f_tol, "{}", path.display());
        assert!(acc < acc_tol, "{}: {acc}", path.display());
    }
}

#[test]
fn transformed_mesh_walls_and_named_errors() {
    // A unit cube scaled, rotated by 90 degrees about z and moved becomes the same box.
    let unit = triangles(&triangulate(box_elements_3d(
        DVec3::ZERO,
        DVec3::ONE,
        &[],
        1.0,
    )));
    let path = temp("unit.stl");
    write_stl_ascii(&path, &unit).unwrap();
    let moved = build(
        &format!(
            "shape = \"mesh\"\nfile = \"{}\"\nscale = 0.5\nrotate = [0.0, 0.0, 90.0]\ntranslate = [0.5, 0.0, 0.0]",
            path.display()
        ),
        "bi",
    );
    let (mut lo, mut hi) = (DVec3::splat(1e9), DVec3::splat(-1e9));
    for c in &moved.walls.elements.corners {
        lo = lo.min(*c);
        hi = hi.max(*c);
    }
    assert!((lo - DVec3::new(0.0, 0.0, 0.0)).length() < 1e-12, "{lo}");
    assert!((hi - DVec3::new(0.5, 0.5, 0.5)).length() < 1e-12, "{hi}");
    let area: f64 = moved.walls.elements.area.iter().sum();
    assert!((area - 1.5).abs() < 1e-12);

    // Open mesh: drop a triangle.
    let open = temp("open.stl");
    write_stl_ascii(&open, &unit[1..]).unwrap();
    let text = case(
        &format!("shape = \"mesh\"\nfile = \"{}\"", open.display()),
        "bi",
    );
    let e = parse_case("<test>", &text, &[]).unwrap_err().to_string();
    assert!(e.contains("open mesh") && e.contains("wall[0]"), "{e}");
    // Inconsistent: one triangle reversed.
    let mut flipped = unit.clone();
    flipped[5].swap(1, 2);
    let bad = temp("flipped.stl");
    write_stl_binary(&bad, &flipped).unwrap();
    let text = case(
        &format!("shape = \"mesh\"\nfile = \"{}\"", bad.display()),
        "bi",
    );
    let e = parse_case("<test>", &text, &[]).unwrap_err().to_string();
    assert!(
        e.contains("inconsistent normals") && e.contains("face"),
        "{e}"
    );
    // Degenerate face in an OBJ.
    let obj = temp("degenerate.obj");
    std::fs::write(
        &obj,
        "v 0 0 0\nv 1 0 0\nv 2 0 0\nv 0 1 0\nf 1 2 3\nf 1 2 4\n",
    )
    .unwrap();
    let text = case(
        &format!("shape = \"mesh\"\nfile = \"{}\"", obj.display()),
        "bi",
    );
    let e = parse_case("<test>", &text, &[]).unwrap_err().to_string();
    assert!(e.contains("face 0 is degenerate"), "{e}");
    // An open mesh is accepted with closed = false.
    let text = case(
        &format!(
            "shape = \"mesh\"\nfile = \"{}\"\nclosed = false",
            open.display()
        ),
        "bi",
    );
    assert!(parse_case("<test>", &text, &[]).is_ok());
}

/// A case of spacing `DX` with `walls` and a `shape = "walls"` block filled to `level`.
fn round_case(walls: &str, level: f64) -> Simulation<DVec3> {
    let text = format!(
        r#"name = "round"
dim = 3
[fluid]
density = 1000.0
sound_speed = 20.0
gravity = [0.0, 0.0, -9.81]
[resolution]
dx = {DX}
[time]
end = 0.01
[[fluid_block]]
shape = "walls"
level = {level}
{walls}"#
    );
    let loaded = parse_case("<test>", &text, &[]).unwrap();
    build_simulation::<DVec3>(&loaded).unwrap()
}

#[test]
fn an_open_cylinder_tank_faces_out_of_its_water() {
    let (r, length) = (0.3, 0.6);
    let sim = round_case(
        &format!(
            "[[wall]]\nshape = \"cylinder\"\nstart = [0.0, 0.0, 0.0]\nend = [0.0, 0.0, {length}]\n\
             radius = {r}\nfluid = \"inside\"\nopen = [\"end\"]\n"
        ),
        0.4,
    );
    let e = &sim.walls.elements;
    let mut area = 0.0;
    for j in 0..e.len() {
        let (c, n) = (e.centre[j], e.normal[j]);
        assert!(c.z < length - 1e-9, "an element on the open end at {c}");
        if c.z < 1e-9 {
            assert!((n - DVec3::NEG_Z).length() < 1e-9, "floor normal {n}");
        } else {
            let radial = DVec3::new(c.x, c.y, 0.0).normalize();
            assert!(
                n.dot(radial) > 0.99 && n.z.abs() < 1e-9,
                "side normal {n} at {c}"
            );
        }
        area += e.area[j];
    }
    // The inscribed polygon of n = 38 sides: side n 2 r sin(pi/n) L, floor n r^2 sin(2 pi/n)/2.
    let n = 38.0;
    let pi = std::f64::consts::PI;
    let exact = n * 2.0 * r * (pi / n).sin() * length + 0.5 * n * r * r * (2.0 * pi / n).sin();
    assert!((area - exact).abs() < 1e-9 * exact, "{area} vs {exact}");
    // Geometric gamma: 1 in the water beyond the kernel support (0.2) from the walls, 1/2 on
    // the middle of the floor.
    let k = &sim.config.kernel;
    let g = |p: DVec3| gamma(k, p, &sim.walls.elements, &sim.walls.grid);
    assert!((g(DVec3::new(0.0, 0.0, 0.25)) - 1.0).abs() < 1e-6);
    assert!((g(DVec3::new(0.0, 0.0, 1e-9)) - 0.5).abs() < 1e-3);
}

#[test]
fn a_sphere_obstacle_faces_into_itself() {
    let (centre, r) = (DVec3::new(0.25, 0.25, 0.2), 0.1);
    let sim = round_case(
        "[[wall]]\nshape = \"box\"\nmin = [0.0, 0.0, 0.0]\nmax = [0.5, 0.5, 0.5]\nopen = [\"+z\"]\n\
         [[wall]]\nshape = \"sphere\"\ncentre = [0.25, 0.25, 0.2]\nradius = 0.1\n",
        0.4,
    );
    let e = &sim.walls.elements;
    let mut area = 0.0;
    for j in 0..e.len() {
        let d = e.centre[j] - centre;
        if d.length() < 1.01 * r {
            assert!(
                e.normal[j].dot(d.normalize()) < -0.9,
                "normal {}",
                e.normal[j]
            );
            area += e.area[j];
        }
    }
    let sphere = 4.0 * std::f64::consts::PI * r * r;
    assert!(area < sphere && area > 0.9 * sphere, "{area} vs {sphere}");
    // No particle inside.
    assert!(sim
        .fluid
        .position
        .iter()
        .all(|p| (*p - centre).length() > r));
}
