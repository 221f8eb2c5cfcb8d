//! Set-up geometry: walls split into boundary elements, fluid blocks filled on a lattice.
//!
//! Orientation rule for 2-D polylines: the normal of a segment from `a` to `b` points to the
//! **right** of the direction of travel, `(b - a)^perp = (dy, -dx) / L`. A polygon listed
//! counter-clockwise around the fluid therefore has normals out of the fluid.

use crate::dim::Vector;
use glam::{DVec2, DVec3};

/// One boundary element before it is owned by a body.
#[derive(Clone, Debug, PartialEq)]
pub struct ElementShape<V> {
    /// Centre.
    pub centre: V,
    /// Unit normal (out of the fluid).
    pub normal: V,
    /// Area (length in 2-D).
    pub area: f64,
    /// Corner points (2 in 2-D, 4 for 3-D patches).
    pub corners: Vec<V>,
}

/// Splits the segment `a -> b` into `max(1, round(L / dx))` equal elements.
pub fn segment_elements(a: DVec2, b: DVec2, dx: f64) -> Vec<ElementShape<DVec2>> {
    let d = b - a;
    let length = d.length();
    if length == 0.0 {
        return Vec::new();
    }
    let n = ((length / dx).round() as usize).max(1);
    let normal = DVec2::new(d.y, -d.x) / length;
    (0..n)
        .map(|k| {
            let p0 = a + d * (k as f64 / n as f64);
            let p1 = a + d * ((k + 1) as f64 / n as f64);
            ElementShape {
                centre: (p0 + p1) * 0.5,
                normal,
                area: length / n as f64,
                corners: vec![p0, p1],
            }
        })
        .collect()
}

/// Elements along a polyline (closed: the last point joins the first).
pub fn polyline_elements(points: &[DVec2], closed: bool, dx: f64) -> Vec<ElementShape<DVec2>> {
    let mut out = Vec::new();
    for w in points.windows(2) {
        out.extend(segment_elements(w[0], w[1], dx));
    }
    if closed && points.len() > 2 {
        out.extend(segment_elements(points[points.len() - 1], points[0], dx));
    }
    out
}

/// Signed area of a polygon (positive when counter-clockwise).
pub fn signed_area(points: &[DVec2]) -> f64 {
    let n = points.len();
    (0..n)
        .map(|k| points[k].perp_dot(points[(k + 1) % n]))
        .sum::<f64>()
        * 0.5
}

/// The four sides of a 2-D box, in counter-clockwise order: `-y`, `+x`, `+y`, `-x`.
pub const BOX_SIDES_2D: [&str; 4] = ["-y", "+x", "+y", "-x"];

/// Walls of a 2-D box enclosing the fluid, without the sides named in `open`
/// (from [`BOX_SIDES_2D`]); normals point out of the box.
pub fn box_elements_2d(
    min: DVec2,
    max: DVec2,
    open: &[String],
    dx: f64,
) -> Vec<ElementShape<DVec2>> {
    let corners = [min, DVec2::new(max.x, min.y), max, DVec2::new(min.x, max.y)];
    let mut out = Vec::new();
    for (k, side) in BOX_SIDES_2D.iter().enumerate() {
        if !open.iter().any(|o| o == side) {
            out.extend(segment_elements(corners[k], corners[(k + 1) % 4], dx));
        }
    }
    out
}

/// Splits the parallelogram `origin + a e1 + b e2` (`a, b` in `[0, 1]`) into patches of side
/// about `dx`, with the given unit normal.
pub fn rectangle_elements(
    origin: DVec3,
    e1: DVec3,
    e2: DVec3,
    normal: DVec3,
    dx: f64,
) -> Vec<ElementShape<DVec3>> {
    let n1 = ((e1.length() / dx).round() as usize).max(1);
    let n2 = ((e2.length() / dx).round() as usize).max(1);
    let area = e1.cross(e2).length() / (n1 * n2) as f64;
    let mut out = Vec::with_capacity(n1 * n2);
    for b in 0..n2 {
        for a in 0..n1 {
            let p = |i: usize, k: usize| {
                origin + e1 * (i as f64 / n1 as f64) + e2 * (k as f64 / n2 as f64)
            };
            let corners = vec![p(a, b), p(a + 1, b), p(a + 1, b + 1), p(a, b + 1)];
            let centre = (corners[0] + corners[2]) * 0.5;
            out.push(ElementShape {
                centre,
                normal,
                area,
                corners,
            });
        }
    }
    out
}

/// The six faces of a 3-D box: `-x`, `+x`, `-y`, `+y`, `-z`, `+z`.
pub const BOX_FACES_3D: [&str; 6] = ["-x", "+x", "-y", "+y", "-z", "+z"];

/// Walls of a 3-D box enclosing the fluid, without the faces named in `open` (from
/// [`BOX_FACES_3D`]); square-ish patches of about `dx^2`, normals out of the box.
pub fn box_elements_3d(
    min: DVec3,
    max: DVec3,
    open: &[String],
    dx: f64,
) -> Vec<ElementShape<DVec3>> {
    let size = max - min;
    let mut out = Vec::new();
    for (k, face) in BOX_FACES_3D.iter().enumerate() {
        if open.iter().any(|o| o == face) {
            continue;
        }
        let axis = k / 2;
        let upper = k % 2 == 1;
        let (u, v) = ((axis + 1) % 3, (axis + 2) % 3);
        let mut origin = min;
        if upper {
            origin[axis] = max[axis];
        }
        let mut e1 = DVec3::ZERO;
        e1[u] = size[u];
        let mut e2 = DVec3::ZERO;
        e2[v] = size[v];
        let mut normal = DVec3::ZERO;
        normal[axis] = if upper { 1.0 } else { -1.0 };
        out.extend(rectangle_elements(origin, e1, e2, normal, dx));
    }
    out
}

/// Splits every quadrilateral patch into two triangles (alternating diagonals, so a flat wall
/// gets triangles of both orientations); triangles and other shapes pass through.
pub fn triangulate(shapes: Vec<ElementShape<DVec3>>) -> Vec<ElementShape<DVec3>> {
    let mut out = Vec::with_capacity(2 * shapes.len());
    for (k, s) in shapes.into_iter().enumerate() {
        if s.corners.len() != 4 {
            out.push(s);
            continue;
        }
        let c = &s.corners;
        let halves = if k % 2 == 0 {
            [[c[0], c[1], c[2]], [c[0], c[2], c[3]]]
        } else {
            [[c[0], c[1], c[3]], [c[1], c[2], c[3]]]
        };
        for t in halves {
            let area = 0.5 * (t[1] - t[0]).cross(t[2] - t[0]).length();
            out.push(ElementShape {
                centre: (t[0] + t[1] + t[2]) / 3.0,
                normal: s.normal,
                area,
                corners: t.to_vec(),
            });
        }
    }
    out
}

/// Lattice points `min + (k + 1/2) dx` inside the box `[min, max]`.
pub fn lattice_box<V: Vector>(min: V, max: V, dx: f64) -> Vec<V> {
    let mut counts = [1usize; 3];
    for (k, c) in counts.iter_mut().enumerate().take(V::DIM) {
        let n = ((max.get(k) - min.get(k)) / dx + 1e-9).floor();
        *c = if n > 0.0 { n as usize } else { 0 };
    }
    let mut out = Vec::with_capacity(counts.iter().product());
    for c in 0..counts[2] {
        for b in 0..counts[1] {
            for a in 0..counts[0] {
                let idx = [a, b, c];
                let mut p = min;
                for (k, &i) in idx.iter().enumerate().take(V::DIM) {
                    p.set(k, min.get(k) + (i as f64 + 0.5) * dx);
                }
                out.push(p);
            }
        }
    }
    out
}

/// Winding number of the closed polygon `points` around `p` (non-zero means inside).
pub fn winding_number(p: DVec2, points: &[DVec2]) -> i32 {
    let n = points.len();
    let mut wn = 0;
    for k in 0..n {
        let (a, b) = (points[k], points[(k + 1) % n]);
        let side = (b - a).perp_dot(p - a);
        if a.y <= p.y {
            if b.y > p.y && side > 0.0 {
                wn += 1;
            }
        } else if b.y <= p.y && side < 0.0 {
            wn -= 1;
        }
    }
    wn
}

/// Lattice points of spacing `dx` (aligned on the polygon's bounding box) inside the polygon.
pub fn lattice_polygon(points: &[DVec2], dx: f64) -> Vec<DVec2> {
    if points.len() < 3 {
        return Vec::new();
    }
    let (mut lo, mut hi) = (points[0], points[0]);
    for &p in points {
        lo = lo.min(p);
        hi = hi.max(p);
    }
    lattice_box(lo, hi, dx)
        .into_iter()
        .filter(|&p| winding_number(p, points) != 0)
        .collect()
}

/// A fault in the edge structure of a polygon mesh (faces as lists of vertex indices).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum EdgeFault {
    /// Faces `first` and `second` run their shared edge `a -> b` in the same direction: one is
    /// flipped relative to the other.
    Flipped {
        /// The face that ran the edge first.
        first: usize,
        /// The face that ran it again.
        second: usize,
        /// Edge start vertex.
        a: u32,
        /// Edge end vertex.
        b: u32,
    },
    /// The edge `a - b` of `face` is used by `uses` faces: more than two, or (closed meshes)
    /// other than two.
    Open {
        /// The first face using the edge.
        face: usize,
        /// How many faces use it.
        uses: usize,
        /// One end.
        a: u32,
        /// The other end.
        b: u32,
    },
}

/// Checks that neighbouring faces agree on orientation (each shared edge is run once in each
/// direction) and that no edge has more than two faces, and, when `closed`, that every edge
/// has exactly two. The open edge reported is the one of the lowest face (then lowest vertex
/// pair), so the answer does not depend on hashing order.
pub fn check_edges<F: AsRef<[u32]>>(faces: &[F], closed: bool) -> Result<(), EdgeFault> {
    use std::collections::HashMap;
    let mut directed: HashMap<(u32, u32), usize> = HashMap::new();
    let mut uses: HashMap<(u32, u32), (usize, usize)> = HashMap::new();
    for (f, ids) in faces.iter().enumerate() {
        let ids = ids.as_ref();
        for k in 0..ids.len() {
            let (a, b) = (ids[k], ids[(k + 1) % ids.len()]);
            uses.entry((a.min(b), a.max(b))).or_insert((0, f)).0 += 1;
            if let Some(&first) = directed.get(&(a, b)) {
                return Err(EdgeFault::Flipped {
                    first,
                    second: f,
                    a,
                    b,
                });
            }
            directed.insert((a, b), f);
        }
    }
    let worst = uses
        .iter()
        .filter(|(_, &(n, _))| n > 2 || (closed && n != 2))
        .map(|(&(a, b), &(uses, face))| (face, a, b, uses))
        .min();
    match worst {
        Some((face, a, b, uses)) => Err(EdgeFault::Open { face, uses, a, b }),
        None => Ok(()),
    }
}

/// Sides of a circle of `radius` drawn with chords of about `size` (at least 16).
fn circle_sides(radius: f64, size: f64) -> usize {
    ((std::f64::consts::TAU * radius / size).ceil() as usize).max(16)
}

/// A circle as a polygon, counter-clockwise, with chords of about `size` (at least 16 sides);
/// its vertices lie on the circle.
pub fn circle_points(centre: DVec2, radius: f64, size: f64) -> Vec<DVec2> {
    let n = circle_sides(radius, size);
    (0..n)
        .map(|k| {
            let phi = std::f64::consts::TAU * k as f64 / n as f64;
            centre + DVec2::new(phi.cos(), phi.sin()) * radius
        })
        .collect()
}

/// A cylinder of `radius` about the axis from `start` to `end`, as faces of 3 or 4 corners
/// counter-clockwise seen from outside (normals out of the cylinder): the side in quads about
/// `size` wide and long, and the end caps kept in `caps` (`[start, end]`) in rings of quads
/// about `size` apart around a fan of triangles, all on the same angular division so that the
/// faces meet edge to edge. Closed when both caps are kept; a cap left out leaves that end's
/// rim as the open edge. `None` when the axis has no length or the radius or size is not
/// positive.
pub fn cylinder_faces(
    start: DVec3,
    end: DVec3,
    radius: f64,
    size: f64,
    caps: [bool; 2],
) -> Option<Vec<Vec<DVec3>>> {
    let axis = end - start;
    let length = axis.length();
    if !(length > 0.0 && radius > 0.0 && size > 0.0 && length.is_finite() && radius.is_finite()) {
        return None;
    }
    let k = axis / length;
    let e1 = k.any_orthonormal_vector();
    let e2 = k.cross(e1);
    let n = circle_sides(radius, size);
    let rings = ((radius / size).ceil() as usize).max(1);
    let layers = ((length / size).ceil() as usize).max(1);
    // Point at radius fraction `rho`, angle index `a`, height fraction `z` along the axis.
    let at = |rho: f64, a: usize, z: f64| {
        let phi = std::f64::consts::TAU * (a % n) as f64 / n as f64;
        start + axis * z + (e1 * phi.cos() + e2 * phi.sin()) * (radius * rho)
    };
    let mut faces = Vec::new();
    for a in 0..n {
        for l in 0..layers {
            let (z0, z1) = (l as f64 / layers as f64, (l + 1) as f64 / layers as f64);
            faces.push(vec![
                at(1.0, a, z0),
                at(1.0, a + 1, z0),
                at(1.0, a + 1, z1),
                at(1.0, a, z1),
            ]);
        }
        for (z, outward, kept) in [(0.0, false, caps[0]), (1.0, true, caps[1])] {
            if !kept {
                continue;
            }
            let centre = start + axis * z;
            let mut cap = vec![vec![
                centre,
                at(1.0 / rings as f64, a, z),
                at(1.0 / rings as f64, a + 1, z),
            ]];
            for r in 1..rings {
                let (r0, r1) = (r as f64 / rings as f64, (r + 1) as f64 / rings as f64);
                cap.push(vec![
                    at(r0, a, z),
                    at(r1, a, z),
                    at(r1, a + 1, z),
                    at(r0, a + 1, z),
                ]);
            }
            for mut face in cap {
                // Counter-clockwise about +axis as built: outward on the end cap only.
                if !outward {
                    face.reverse();
                }
                faces.push(face);
            }
        }
    }
    Some(faces)
}

/// Icosphere subdivisions whose edges are about `edge` on a sphere of `radius` (the
/// icosahedron's edge is `1.05 radius`, halved by each subdivision), at most 8.
pub fn sphere_subdivisions(radius: f64, edge: f64) -> u32 {
    ((1.05 * radius / edge).log2().ceil().max(0.0) as u32).min(8)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn box_walls_have_outward_normals_and_the_right_perimeter() {
        let els = box_elements_2d(DVec2::ZERO, DVec2::new(2.0, 1.0), &[], 0.1);
        let total: f64 = els.iter().map(|e| e.area).sum();
        assert!((total - 6.0).abs() < 1e-12);
        let centre = DVec2::new(1.0, 0.5);
        assert!(els.iter().all(|e| (e.centre - centre).dot(e.normal) > 0.0));
        let closed_sum: DVec2 = els.iter().map(|e| e.normal * e.area).sum();
        assert!(closed_sum.length() < 1e-12);
        let open = box_elements_2d(DVec2::ZERO, DVec2::new(2.0, 1.0), &["+y".into()], 0.1);
        assert_eq!(open.len(), els.len() - 20);
    }

    #[test]
    fn box_faces_are_closed_and_outward() {
        let els = box_elements_3d(DVec3::ZERO, DVec3::new(1.0, 0.5, 0.3), &[], 0.1);
        let area: f64 = els.iter().map(|e| e.area).sum();
        assert!((area - 2.0 * (0.5 + 0.3 + 0.15)).abs() < 1e-12);
        let flux: DVec3 = els.iter().map(|e| e.normal * e.area).sum();
        assert!(flux.length() < 1e-12);
        let c = DVec3::new(0.5, 0.25, 0.15);
        assert!(els.iter().all(|e| (e.centre - c).dot(e.normal) > 0.0));
    }

    #[test]
    fn polygon_fill_matches_box_fill() {
        let square = [
            DVec2::ZERO,
            DVec2::new(1.0, 0.0),
            DVec2::new(1.0, 1.0),
            DVec2::new(0.0, 1.0),
        ];
        assert!(signed_area(&square) > 0.0);
        let a = lattice_polygon(&square, 0.1);
        let b = lattice_box(DVec2::ZERO, DVec2::ONE, 0.1);
        assert_eq!(a, b);
        assert_eq!(b.len(), 100);
        let tri = [DVec2::ZERO, DVec2::new(1.0, 0.0), DVec2::new(0.0, 0.95)];
        let inside: Vec<DVec2> = b
            .iter()
            .copied()
            .filter(|p| p.x + p.y / 0.95 < 1.0)
            .collect();
        assert_eq!(lattice_polygon(&tri, 0.1), inside);
        let clockwise: Vec<DVec2> = tri.iter().rev().copied().collect();
        assert_eq!(lattice_polygon(&clockwise, 0.1), inside);
    }

    #[test]
    fn a_circle_is_counter_clockwise_on_its_radius() {
        let c = DVec2::new(0.3, -0.2);
        let p = circle_points(c, 0.5, 0.01);
        assert_eq!(p.len(), 315);
        assert!(p.iter().all(|q| ((*q - c).length() - 0.5).abs() < 1e-12));
        let area = signed_area(&p);
        assert!(area > 0.0 && (area - std::f64::consts::PI * 0.25).abs() < 1e-4 * area);
        assert_eq!(circle_points(c, 0.01, 1.0).len(), 16);
    }

    /// The welded surface of `faces`, its edges checked (`closed`: every edge used twice).
    fn welded(faces: &[Vec<DVec3>], closed: bool) -> crate::surface::Surface {
        let surface = crate::surface::Surface::from_polygons(faces, None, 1e-9).unwrap();
        check_edges(&surface.faces, closed).unwrap();
        surface
    }

    #[test]
    fn a_circle_holds_its_area_within_the_chord_error() {
        let c = DVec2::new(-1.0, 2.0);
        for (r, size) in [(0.5, 0.01), (0.3, 0.05), (2.0, 0.1)] {
            let p = circle_points(c, r, size);
            let n = p.len();
            assert!((1..=n).all(|k| (p[k % n] - p[k - 1]).length() <= size * (1.0 + 1e-12)));
            // The inscribed polygon holds the circle of radius r cos(pi / n).
            let inner = r * (std::f64::consts::PI / n as f64).cos();
            let area = signed_area(&p);
            let exact = std::f64::consts::PI * r * r;
            assert!(
                area < exact && area > exact * (inner / r).powi(2),
                "{area} vs {exact}"
            );
            // Normals out of the circle (the fluid inside) as the polygon runs.
            for e in polyline_elements(&p, true, size) {
                assert!((e.centre - c).dot(e.normal) > 0.0);
                assert!(((e.centre - c).length() - inner).abs() < 1e-9);
            }
        }
    }

    #[test]
    fn a_cylinder_is_closed_outward_and_holds_its_volume() {
        let (start, end) = (DVec3::new(0.1, 0.2, 0.3), DVec3::new(0.4, 0.2, 1.1));
        let (r, size) = (0.25, 0.05);
        let faces = cylinder_faces(start, end, r, size, [true, true]).unwrap();
        let surface = welded(&faces, true);
        surface.check_topology(true).unwrap();
        // The inscribed polygonal cylinder: n sides of half-angle pi/n.
        let n = 32.0;
        let length = (end - start).length();
        let exact = 0.5 * n * r * r * (std::f64::consts::TAU / n).sin() * length;
        assert!(
            (surface.volume() - exact).abs() < 1e-12 * exact,
            "{}",
            surface.volume()
        );
        // Within the chord error of pi r^2 L.
        let analytic = std::f64::consts::PI * r * r * length;
        let inner = (std::f64::consts::PI / n).cos().powi(2);
        assert!(surface.volume() < analytic && surface.volume() > inner * analytic);
        // Every face faces out: away from the axis on the side, along -+axis on the caps.
        let k = (end - start) / length;
        for f in 0..surface.faces.len() {
            let p = surface.corners(f);
            let centroid = p.iter().copied().sum::<DVec3>() / p.len() as f64;
            let along = (centroid - start).dot(k);
            let normal = surface.normal(f);
            let out = if along < 1e-9 {
                -k
            } else if along > length - 1e-9 {
                k
            } else {
                (centroid - start - k * along).normalize()
            };
            assert!(normal.dot(out) > 0.99, "face {f}: {normal} vs {out}");
            assert!(p
                .windows(2)
                .all(|w| (w[1] - w[0]).length() <= size * (1.0 + 1e-9)));
        }
        assert!(cylinder_faces(start, start, r, size, [true, true]).is_none());
        assert!(cylinder_faces(start, end, -r, size, [true, true]).is_none());
    }

    #[test]
    fn a_cylinder_open_at_one_end_has_one_rim_open() {
        let (start, end) = (DVec3::ZERO, DVec3::new(0.0, 0.0, 1.0));
        let closed = cylinder_faces(start, end, 0.5, 0.1, [true, true]).unwrap();
        for caps in [[true, false], [false, true], [false, false]] {
            let faces = cylinder_faces(start, end, 0.5, 0.1, caps).unwrap();
            let open_ends = caps.iter().filter(|&&c| !c).count();
            let surface = welded(&faces, false);
            assert!(check_edges(&surface.faces, true).is_err());
            // The open edges are the n chords of each missing cap's rim.
            let n = circle_sides(0.5, 0.1);
            let mut uses = std::collections::HashMap::new();
            for f in &surface.faces {
                for k in 0..f.len() {
                    let (a, b) = (f[k], f[(k + 1) % f.len()]);
                    *uses.entry((a.min(b), a.max(b))).or_insert(0) += 1;
                }
            }
            assert_eq!(uses.values().filter(|&&u| u == 1).count(), open_ends * n);
            // The cap left out (n sectors of 5 rings) is the one named.
            assert_eq!(closed.len() - faces.len(), open_ends * n * 5);
            let floor = faces.iter().any(|f| f.iter().all(|p| p.z.abs() < 1e-12));
            assert_eq!(floor, caps[0]);
        }
    }
}
