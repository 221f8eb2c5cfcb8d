//! Geometry files: 2-D polygon vertex lists (CSV or whitespace text), 3-D STL meshes (binary
//! and ASCII) and OBJ meshes, particle position files; and the transform (units, scale, rotation,
//! translation) a case applies to them. Errors name the file and, where it applies, the line.

use glam::{DVec2, DVec3};
use std::path::Path;

/// Splits a data line on commas, semicolons, tabs or spaces.
fn fields(line: &str) -> impl Iterator<Item = &str> {
    line.split(|c: char| c == ',' || c == ';' || c.is_whitespace())
        .filter(|s| !s.is_empty())
}

/// Reads rows of numbers: `#` starts a comment, a first line that is not numeric is a
/// header, a blank line ends a group (a polygon loop). Each row must have at least `min_cols`
/// numbers; the first `min_cols` are kept.
fn read_rows(path: &Path, min_cols: usize) -> Result<Vec<Vec<Vec<f64>>>, String> {
    let text = std::fs::read_to_string(path)
        .map_err(|e| format!("cannot read {}: {e}", path.display()))?;
    parse_rows(&text, path, min_cols)
}

/// [`read_rows`] on text already read; `path` names the source in messages.
pub fn parse_rows(text: &str, path: &Path, min_cols: usize) -> Result<Vec<Vec<Vec<f64>>>, String> {
    let mut groups: Vec<Vec<Vec<f64>>> = vec![Vec::new()];
    let mut seen_data = false;
    for (n, raw) in text.lines().enumerate() {
        let line = raw.split('#').next().unwrap_or("").trim();
        if line.is_empty() {
            if raw.trim().is_empty() && !groups.last().is_some_and(|g| g.is_empty()) {
                groups.push(Vec::new());
            }
            continue;
        }
        let parsed: Result<Vec<f64>, _> = fields(line).map(str::parse::<f64>).collect();
        match parsed {
            Ok(v) if v.len() >= min_cols => {
                if v.iter().take(min_cols).any(|x| !x.is_finite()) {
                    return Err(format!(
                        "{}:{}: expected finite numbers, found \"{line}\"",
                        path.display(),
                        n + 1
                    ));
                }
                seen_data = true;
                groups.last_mut().unwrap().push(v[..min_cols].to_vec());
            }
            Err(_) if !seen_data => continue, // a header line
            _ => {
                return Err(format!(
                    "{}:{}: expected {min_cols} numbers (separated by commas or spaces), found \"{line}\"",
                    path.display(),
                    n + 1
                ))
            }
        }
    }
    groups.retain(|g| !g.is_empty());
    if groups.is_empty() {
        return Err(format!("{}: no data rows", path.display()));
    }
    Ok(groups)
}

/// Reads a 2-D polygon file: one vertex `x y` or `x,y` per line; loops separated by blank
/// lines (holes allowed); the closing vertex may be repeated or not.
pub fn read_polygon_file(path: &Path) -> Result<Vec<Vec<DVec2>>, String> {
    Ok(read_rows(path, 2)?
        .into_iter()
        .map(|g| g.into_iter().map(|r| DVec2::new(r[0], r[1])).collect())
        .collect())
}

/// Reads particle positions (`x,y[,z]` per line, further columns ignored).
pub fn read_particles(path: &Path, dim: usize) -> Result<Vec<Vec<f64>>, String> {
    Ok(read_rows(path, dim)?.into_iter().flatten().collect())
}

/// Reads an STL file, binary or ASCII, as a triangle soup.
pub fn read_stl(path: &Path) -> Result<Vec<[DVec3; 3]>, String> {
    Ok(read_stl_facets(path)?.into_iter().map(|(t, _)| t).collect())
}

/// Reads an STL file, binary or ASCII: each facet's corners and its stored normal (zero
/// when the file leaves it blank).
pub fn read_stl_facets(path: &Path) -> Result<Vec<([DVec3; 3], DVec3)>, String> {
    let bytes = std::fs::read(path).map_err(|e| format!("cannot read {}: {e}", path.display()))?;
    let triangles = parse_stl(&bytes, path)?;
    if let Some(k) = triangles
        .iter()
        .position(|(t, n)| !n.is_finite() || t.iter().any(|v| !v.is_finite()))
    {
        return Err(format!(
            "{}: triangle {} has a non-finite coordinate",
            path.display(),
            k + 1
        ));
    }
    Ok(triangles)
}

/// Parses STL bytes (binary or ASCII) into facets (corners, stored normal); `path` names the
/// source in messages. The triangle count
/// of a binary file is trusted only when the file's size matches it.
pub fn parse_stl(bytes: &[u8], path: &Path) -> Result<Vec<([DVec3; 3], DVec3)>, String> {
    let binary_size = |n: usize| 84 + 50 * n;
    if bytes.len() >= 84 {
        let n = u32::from_le_bytes([bytes[80], bytes[81], bytes[82], bytes[83]]) as usize;
        if bytes.len() == binary_size(n) {
            let mut out = Vec::with_capacity(n);
            for t in 0..n {
                let base = 84 + 50 * t;
                let f = |k: usize| {
                    let o = base + 4 * k;
                    f32::from_le_bytes([bytes[o], bytes[o + 1], bytes[o + 2], bytes[o + 3]]) as f64
                };
                out.push((
                    [
                        DVec3::new(f(3), f(4), f(5)),
                        DVec3::new(f(6), f(7), f(8)),
                        DVec3::new(f(9), f(10), f(11)),
                    ],
                    DVec3::new(f(0), f(1), f(2)),
                ));
            }
            return Ok(out);
        }
    }
    let text = std::str::from_utf8(bytes).map_err(|_| {
        format!(
            "{}: neither a binary STL (the size does not match the triangle count) nor ASCII text",
            path.display()
        )
    })?;
    if !text.trim_start().starts_with("solid") {
        return Err(format!(
            "{}: not an STL file (ASCII STL starts with \"solid\"; a binary one has 84 + 50 n bytes)",
            path.display()
        ));
    }
    let mut out = Vec::new();
    let mut current: Vec<DVec3> = Vec::new();
    let mut normal = DVec3::ZERO;
    for (n, raw) in text.lines().enumerate() {
        let mut words = raw.split_whitespace();
        match words.next() {
            Some("facet") => {
                let v: Vec<f64> = words.skip(1).filter_map(|w| w.parse().ok()).collect();
                normal = if v.len() == 3 {
                    DVec3::new(v[0], v[1], v[2])
                } else {
                    DVec3::ZERO
                };
            }
            Some("vertex") => {
                let v: Result<Vec<f64>, _> = words.map(str::parse::<f64>).collect();
                match v {
                    Ok(v) if v.len() == 3 => current.push(DVec3::new(v[0], v[1], v[2])),
                    _ => {
                        return Err(format!(
                            "{}:{}: expected \"vertex x y z\", found \"{}\"",
                            path.display(),
                            n + 1,
                            raw.trim()
                        ))
                    }
                }
            }
            Some("endloop") => {
                if current.len() != 3 {
                    return Err(format!(
                        "{}:{}: a facet has {} vertices; only triangles are supported",
                        path.display(),
                        n + 1,
                        current.len()
                    ));
                }
                out.push(([current[0], current[1], current[2]], normal));
                current.clear();
            }
            _ => {}
        }
    }
    if out.is_empty() {
        return Err(format!("{}: no facet found", path.display()));
    }
    Ok(out)
}

/// Reads a Wavefront OBJ file's faces (`v x y z` vertices, `f a b c [d]` faces with 1-based
/// or negative indices, `a/t/n` forms accepted; other records ignored) as corner polygons.
pub fn read_obj(path: &Path) -> Result<Vec<Vec<DVec3>>, String> {
    let text = std::fs::read_to_string(path)
        .map_err(|e| format!("cannot read {}: {e}", path.display()))?;
    parse_obj(&text, path)
}

/// [`read_obj`] on text already read; `path` names the source in messages. Vertices must be
/// finite.
pub fn parse_obj(text: &str, path: &Path) -> Result<Vec<Vec<DVec3>>, String> {
    let mut vertices: Vec<DVec3> = Vec::new();
    let mut faces = Vec::new();
    for (n, raw) in text.lines().enumerate() {
        let line = raw.split('#').next().unwrap_or("");
        let mut words = line.split_whitespace();
        let here = || format!("{}:{}", path.display(), n + 1);
        match words.next() {
            Some("v") => {
                let v: Result<Vec<f64>, _> = words.take(3).map(str::parse::<f64>).collect();
                match v {
                    Ok(v) if v.len() == 3 && v.iter().all(|x| x.is_finite()) => {
                        vertices.push(DVec3::new(v[0], v[1], v[2]))
                    }
                    _ => {
                        return Err(format!(
                            "{}: expected \"v x y z\" with finite numbers, found \"{}\"",
                            here(),
                            raw.trim()
                        ))
                    }
                }
            }
            Some("f") => {
                let mut face = Vec::new();
                for w in words {
                    let first = w.split('/').next().unwrap_or("");
                    let index: i64 = first.parse().map_err(|_| {
                        format!("{}: expected vertex indices, found \"{w}\"", here())
                    })?;
                    let k = if index > 0 {
                        index - 1
                    } else {
                        vertices.len() as i64 + index
                    };
                    if index == 0 || k < 0 || k >= vertices.len() as i64 {
                        return Err(format!(
                            "{}: vertex index {index} out of range (1 to {} defined so far)",
                            here(),
                            vertices.len()
                        ));
                    }
                    face.push(vertices[k as usize]);
                }
                faces.push(face);
            }
            _ => {}
        }
    }
    if faces.is_empty() {
        return Err(format!("{}: no face (\"f\" record) found", path.display()));
    }
    Ok(faces)
}

/// Writes a binary STL (normals from the corner order).
pub fn write_stl_binary(path: &Path, triangles: &[[DVec3; 3]]) -> std::io::Result<()> {
    let mut bytes = Vec::with_capacity(84 + 50 * triangles.len());
    let mut header = [0u8; 80];
    let title = b"bisph binary STL";
    header[..title.len()].copy_from_slice(title);
    bytes.extend_from_slice(&header);
    bytes.extend_from_slice(&(triangles.len() as u32).to_le_bytes());
    for t in triangles {
        let n = (t[1] - t[0]).cross(t[2] - t[0]).normalize_or_zero();
        for v in std::iter::once(n).chain(t.iter().copied()) {
            for c in [v.x, v.y, v.z] {
                bytes.extend_from_slice(&(c as f32).to_le_bytes());
            }
        }
        bytes.extend_from_slice(&[0, 0]);
    }
    std::fs::write(path, bytes)
}

/// Writes an ASCII STL.
pub fn write_stl_ascii(path: &Path, triangles: &[[DVec3; 3]]) -> std::io::Result<()> {
    use std::fmt::Write as _;
    let mut s = String::from("solid bisph\n");
    for t in triangles {
        let n = (t[1] - t[0]).cross(t[2] - t[0]).normalize_or_zero();
        let _ = writeln!(
            s,
            "  facet normal {:e} {:e} {:e}\n    outer loop",
            n.x, n.y, n.z
        );
        for v in t {
            let _ = writeln!(s, "      vertex {:.17e} {:.17e} {:.17e}", v.x, v.y, v.z);
        }
        s.push_str("    endloop\n  endfacet\n");
    }
    s.push_str("endsolid bisph\n");
    std::fs::write(path, s)
}

/// A similarity transform: `x -> R (s x) + t` (units and scale in `s`).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Transform {
    /// Scale (units times the case's `scale`).
    pub scale: f64,
    /// Rotation angles in radians (2-D: `[theta, 0, 0]`; 3-D: about x, then y, then z).
    pub angles: [f64; 3],
    /// Translation.
    pub translate: [f64; 3],
}

impl Default for Transform {
    fn default() -> Self {
        Transform {
            scale: 1.0,
            angles: [0.0; 3],
            translate: [0.0; 3],
        }
    }
}

impl Transform {
    /// `true` when it changes nothing.
    pub fn is_identity(&self) -> bool {
        *self == Transform::default()
    }

    /// Applies to a 2-D point.
    pub fn apply2(&self, p: DVec2) -> DVec2 {
        let q = p * self.scale;
        let (s, c) = self.angles[0].sin_cos();
        DVec2::new(c * q.x - s * q.y, s * q.x + c * q.y)
            + DVec2::new(self.translate[0], self.translate[1])
    }

    /// Applies to a 3-D point.
    pub fn apply3(&self, p: DVec3) -> DVec3 {
        let q = p * self.scale;
        let r = glam::DQuat::from_rotation_z(self.angles[2])
            * glam::DQuat::from_rotation_y(self.angles[1])
            * glam::DQuat::from_rotation_x(self.angles[0]);
        r * q + DVec3::from_array(self.translate)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A fresh folder for one test's files, removed when dropped.
    fn scratch() -> tempfile::TempDir {
        tempfile::Builder::new()
            .prefix("bisph-shapes-")
            .tempdir()
            .unwrap()
    }

    #[test]
    fn polygon_files_with_header_comments_and_loops() {
        let dir = scratch();
        let p = dir.path().join("poly.csv");
        std::fs::write(
            &p,
            "# comment\nx,y\n0,0\n1,0\n1 1\n\n0.2,0.2\n0.3,0.2\n0.3,0.3 # hole\n",
        )
        .unwrap();
        let loops = read_polygon_file(&p).unwrap();
        assert_eq!(loops.len(), 2);
        assert_eq!(loops[0].len(), 3);
        assert_eq!(loops[1][2], DVec2::new(0.3, 0.3));
        std::fs::write(&p, "0,0\n1,zero\n").unwrap();
        let e = read_polygon_file(&p).unwrap_err();
        assert!(e.contains("poly.csv:2"), "{e}");
    }

    #[test]
    fn stl_round_trips_binary_and_ascii() {
        let tris = vec![
            [DVec3::ZERO, DVec3::X, DVec3::Y],
            [DVec3::ZERO, DVec3::Z, DVec3::X],
        ];
        let dir = scratch();
        let b = dir.path().join("t.stl");
        write_stl_binary(&b, &tris).unwrap();
        assert_eq!(read_stl(&b).unwrap(), tris);
        let a = dir.path().join("ta.stl");
        write_stl_ascii(&a, &tris).unwrap();
        assert_eq!(read_stl(&a).unwrap(), tris);
        std::fs::write(&a, "not an stl").unwrap();
        assert!(read_stl(&a).unwrap_err().contains("not an STL"));
    }

    #[test]
    fn transforms_scale_rotate_translate() {
        let t = Transform {
            scale: 2.0,
            angles: [std::f64::consts::FRAC_PI_2, 0.0, 0.0],
            translate: [1.0, 0.0, 0.0],
        };
        assert!((t.apply2(DVec2::X) - DVec2::new(1.0, 2.0)).length() < 1e-15);
        let t3 = Transform {
            angles: [0.0, 0.0, std::f64::consts::FRAC_PI_2],
            ..t
        };
        assert!((t3.apply3(DVec3::X) - DVec3::new(1.0, 2.0, 0.0)).length() < 1e-15);
    }
}

/// A closed torus about the z axis (major radius `big_r`, minor `small_r`), `nu x nv` quads
/// split into triangles, outward normals.
pub fn torus_triangles(big_r: f64, small_r: f64, nu: usize, nv: usize) -> Vec<[DVec3; 3]> {
    use std::f64::consts::TAU;
    let p = |i: usize, j: usize| {
        let (u, v) = (
            TAU * (i % nu) as f64 / nu as f64,
            TAU * (j % nv) as f64 / nv as f64,
        );
        DVec3::new(
            (big_r + small_r * v.cos()) * u.cos(),
            (big_r + small_r * v.cos()) * u.sin(),
            small_r * v.sin(),
        )
    };
    let mut out = Vec::with_capacity(2 * nu * nv);
    for i in 0..nu {
        for j in 0..nv {
            let (a, b, c, d) = (p(i, j), p(i + 1, j), p(i + 1, j + 1), p(i, j + 1));
            out.push([a, b, c]);
            out.push([a, c, d]);
        }
    }
    out
}

#[cfg(test)]
mod torus_tests {
    use super::*;

    /// Rewrites `cases/shapes/torus.stl` (run with `--ignored`).
    #[test]
    #[ignore]
    fn write_torus_stl() {
        let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../cases/shapes/torus.stl");
        write_stl_binary(&path, &torus_triangles(0.3, 0.12, 48, 24)).unwrap();
    }

    #[test]
    fn torus_is_a_closed_mesh_with_a_hole() {
        let tris = torus_triangles(0.3, 0.12, 48, 24);
        let m = bisph_core::region::TriMesh::from_soup(&tris, 1e-9).unwrap();
        let exact = 2.0 * std::f64::consts::PI.powi(2) * 0.3 * 0.12 * 0.12;
        assert!((m.volume() - exact).abs() < 0.02 * exact);
        assert!(m.contains(DVec3::new(0.3, 0.0, 0.0)));
        assert!(!m.contains(DVec3::ZERO), "the hole of the torus is outside");
        let dx = 0.02;
        let filled = m.lattice(dx).len() as f64 * dx.powi(3);
        assert!((filled - m.volume()).abs() < 0.05 * m.volume());
    }
}
