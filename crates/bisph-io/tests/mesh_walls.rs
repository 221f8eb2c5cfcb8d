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

/// A fresh folder for one test's files, removed when dropped.
fn scratch() -> tempfile::TempDir {
    tempfile::Builder::new()
        .prefix("bisph-mesh-walls-")
        .tempdir()
        .unwrap()
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
    let dir = scratch();
    let path = dir.path().join("box.obj");
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
    let dir = scratch();
    let ascii = dir.path().join("box-ascii.stl");
    write_stl_ascii(&ascii, &soup).unwrap();
    // Binary STL stores f32: the box corners here are exact in f32 only up to rounding.
    let binary = dir.path().join("box-binary.stl");
    write_stl_binary(&binary, &soup).unwrap();
    // A coarse STL: 12 triangles, refined by the reader to elements of about dx.
    let coarse = dir.path().join("box-coarse.stl");
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
    let dir = scratch();
    let path = dir.path().join("unit.stl");
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
    let open = dir.path().join("open.stl");
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
    let bad = dir.path().join("flipped.stl");
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
    let obj = dir.path().join("degenerate.obj");
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

/// The SPHERIC test 2 obstacle standing on the floor of a 2 m x 1 m tank at `dx = 0.11`
/// (`h = 0.22 m`), closed or open towards the floor.
fn obstacle_on_floor(open_bottom: bool) -> Simulation<DVec3> {
    let open = if open_bottom { "open = [\"-z\"]\n" } else { "" };
    let text = format!(
        r#"
name = "t"
dim = 3
boundary = "bi"
[fluid]
density = 1000.0
sound_speed = 20.0
gravity = [0.0, 0.0, -9.81]
[resolution]
dx = 0.11
[time]
end = 0.01
[[fluid_block]]
shape = "walls"
level = 0.55
[[wall]]
shape = "box"
min = [0.0, 0.0, 0.0]
max = [2.0, 1.0, 1.0]
open = ["+z"]
[[wall]]
shape = "box"
min = [{}, {}, {}]
max = [{}, {}, {}]
fluid = "outside"
{open}"#,
        OBSTACLE.0[0], OBSTACLE.0[1], OBSTACLE.0[2], OBSTACLE.1[0], OBSTACLE.1[1], OBSTACLE.1[2]
    );
    let loaded = parse_case("<test>", &text, &[]).unwrap();
    build_simulation::<DVec3>(&loaded).unwrap()
}

const OBSTACLE: ([f64; 3], [f64; 3]) = ([0.6635, 0.2955, 0.0], [0.8245, 0.6985, 0.161]);

/// `int W dV` over the water within the support of `x`: above the floor `z = 0` and outside
/// the obstacle (the tank's side walls lie beyond the support of the points used). Spherical
/// coordinates about `x`: each ray's water intervals in closed form, the radial integral by
/// 4-point Gauss-Legendre (exact: `W r^2` is a polynomial of degree 7 in `r`), the directions
/// by the midpoint rule in `cos(theta)` and `phi`.
fn water_integral(sim: &Simulation<DVec3>, x: DVec3) -> f64 {
    let kernel = &sim.config.kernel;
    let radius = kernel.support;
    let (lo, hi) = (DVec3::from(OBSTACLE.0), DVec3::from(OBSTACLE.1));
    let nodes = [
        (-0.861_136_311_594_053, 0.347_854_845_137_454),
        (-0.339_981_043_584_856, 0.652_145_154_862_546),
        (0.339_981_043_584_856, 0.652_145_154_862_546),
        (0.861_136_311_594_053, 0.347_854_845_137_454),
    ];
    let radial = |a: f64, b: f64| -> f64 {
        let (mid, half) = ((a + b) / 2.0, (b - a) / 2.0);
        nodes
            .iter()
            .map(|&(t, w)| {
                let r = mid + half * t;
                w * kernel.value(r) * r * r
            })
            .sum::<f64>()
            * half
    };
    let (n_mu, n_phi) = (400, 800);
    let mut total = 0.0;
    for a in 0..n_mu {
        let mu = -1.0 + (a as f64 + 0.5) * 2.0 / n_mu as f64;
        let s = (1.0 - mu * mu).sqrt();
        for b in 0..n_phi {
            let phi = (b as f64 + 0.5) * std::f64::consts::TAU / n_phi as f64;
            let d = DVec3::new(s * phi.cos(), s * phi.sin(), mu);
            let end = if d.z < 0.0 {
                radius.min(x.z / -d.z)
            } else {
                radius
            };
            // The ray's stretch inside the obstacle (slab method).
            let (mut t_in, mut t_out) = (0.0_f64, end);
            for k in 0..3 {
                if d[k].abs() < 1e-15 {
                    if x[k] <= lo[k] || x[k] >= hi[k] {
                        t_out = -1.0;
                    }
                    continue;
                }
                let (t0, t1) = ((lo[k] - x[k]) / d[k], (hi[k] - x[k]) / d[k]);
                t_in = t_in.max(t0.min(t1));
                t_out = t_out.min(t0.max(t1));
            }
            total += if t_in < t_out {
                radial(0.0, t_in) + radial(t_out, end)
            } else {
                radial(0.0, end)
            };
        }
    }
    total * (2.0 / n_mu as f64) * (std::f64::consts::TAU / n_phi as f64)
}

#[test]
fn a_closed_obstacle_on_the_floor_gives_gamma_the_water_around_it() {
    // Points by the obstacle's foot, above its top and away from it (the tank's side walls
    // beyond their support); gamma of the walls (paper 2,
    // eq 8) against the kernel integrated over the water. Closed, the obstacle's bottom lies
    // on the floor with the opposite normal and cancels it; open, the floor runs on under it.
    let points = [
        DVec3::new(0.6, 0.5, 0.05),
        DVec3::new(0.62, 0.5, 0.12),
        DVec3::new(0.74, 0.5, 0.2),
        DVec3::new(0.85, 0.45, 0.05),
        DVec3::new(0.9, 0.5, 0.03),
        DVec3::new(1.4, 0.5, 0.05),
    ];
    let closed = obstacle_on_floor(false);
    let open = obstacle_on_floor(true);
    let mut open_error: f64 = 0.0;
    for x in points {
        let reference = water_integral(&closed, x);
        let g = gamma(
            &closed.config.kernel,
            x,
            &closed.walls.elements,
            &closed.walls.grid,
        );
        assert!(
            (g - reference).abs() < 2e-5,
            "closed obstacle at {x}: gamma {g}, water integral {reference}"
        );
        let g_open = gamma(
            &open.config.kernel,
            x,
            &open.walls.elements,
            &open.walls.grid,
        );
        open_error = open_error.max((g_open - reference).abs());
    }
    assert!(
        open_error > 0.05,
        "open towards the floor, gamma is off by {open_error}"
    );
}
