//! Closed regions to fill with particles: 2-D polygons with holes and 3-D closed triangle
//! meshes. Both are checked on construction (named errors that say where), oriented so that
//! their boundary elements have normals **out of the region**, and answer strict
//! point-in-region queries (a point on the boundary is outside) that are exact on vertices
//! and edges.

use crate::bi::segment::{point_segment_distance, segments_intersect};
use crate::geometry::{check_edges, polyline_elements, signed_area, EdgeFault, ElementShape};
use glam::{DVec2, DVec3};
use std::collections::HashMap;

/// Why a polygon or mesh cannot bound a region.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum RegionError {
    /// No geometry at all.
    #[error("the geometry is empty")]
    Empty,
    /// A coordinate is NaN or infinite.
    #[error("vertex {vertex} of {part} is not a finite point")]
    NonFinite {
        /// Which loop or "mesh".
        part: String,
        /// Vertex index.
        vertex: usize,
    },
    /// A loop with fewer than three distinct vertices.
    #[error("loop {loop_index} has {count} distinct vertices; a closed polygon needs at least 3")]
    TooFewVertices {
        /// Loop index.
        loop_index: usize,
        /// Distinct vertices found.
        count: usize,
    },
    /// Two edges cross or touch away from their shared vertex.
    #[error("the polygon intersects itself: edge {edge_a} of loop {loop_a} meets edge {edge_b} of loop {loop_b} near ({x:.6}, {y:.6})")]
    SelfIntersection {
        /// First loop.
        loop_a: usize,
        /// Edge index in the first loop (from vertex `edge_a` to the next).
        edge_a: usize,
        /// Second loop.
        loop_b: usize,
        /// Edge index in the second loop.
        edge_b: usize,
        /// About where.
        x: f64,
        /// About where.
        y: f64,
    },
    /// A triangle of zero area.
    #[error("triangle {triangle} has zero area (near ({x:.6}, {y:.6}, {z:.6}))")]
    DegenerateTriangle {
        /// Triangle index.
        triangle: usize,
        /// Where.
        x: f64,
        /// Where.
        y: f64,
        /// Where.
        z: f64,
    },
    /// The mesh is not closed: an edge is used by a number of triangles other than two.
    #[error("the mesh is not closed: the edge from ({ax:.6}, {ay:.6}, {az:.6}) to ({bx:.6}, {by:.6}, {bz:.6}) belongs to {uses} triangle(s), not 2")]
    OpenMesh {
        /// Uses of the edge.
        uses: usize,
        /// Edge start.
        ax: f64,
        /// Edge start.
        ay: f64,
        /// Edge start.
        az: f64,
        /// Edge end.
        bx: f64,
        /// Edge end.
        by: f64,
        /// Edge end.
        bz: f64,
    },
    /// Neighbouring triangles disagree on orientation (a Moebius-like or flipped face).
    #[error("triangles {first} and {second} are oriented inconsistently across their shared edge near ({x:.6}, {y:.6}, {z:.6})")]
    InconsistentOrientation {
        /// One triangle.
        first: usize,
        /// The other.
        second: usize,
        /// Where.
        x: f64,
        /// Where.
        y: f64,
        /// Where.
        z: f64,
    },
}

/// A 2-D region bounded by one or more closed loops (holes allowed; even-odd rule).
///
/// After construction every loop is oriented with the region on its left (outer loops
/// counter-clockwise, holes clockwise), so [`polyline_elements`] gives normals out of it.
#[derive(Clone, Debug, PartialEq)]
pub struct PolygonRegion {
    /// The oriented loops (not repeating their first vertex).
    pub loops: Vec<Vec<DVec2>>,
    scale: f64,
}

impl PolygonRegion {
    /// Checks and orients the loops: finite vertices, at least three distinct vertices per
    /// loop (a repeated closing vertex and consecutive duplicates are dropped), no edge
    /// crossing or touching another except at shared loop vertices.
    pub fn new(loops: Vec<Vec<DVec2>>) -> Result<Self, RegionError> {
        if loops.is_empty() {
            return Err(RegionError::Empty);
        }
        let mut cleaned = Vec::with_capacity(loops.len());
        for (l, pts) in loops.into_iter().enumerate() {
            if let Some(v) = pts.iter().position(|p| !p.is_finite()) {
                return Err(RegionError::NonFinite {
                    part: format!("loop {l}"),
                    vertex: v,
                });
            }
            let mut out: Vec<DVec2> = Vec::with_capacity(pts.len());
            for p in pts {
                if out.last() != Some(&p) {
                    out.push(p);
                }
            }
            while out.len() > 1 && out.first() == out.last() {
                out.pop();
            }
            if out.len() < 3 {
                return Err(RegionError::TooFewVertices {
                    loop_index: l,
                    count: out.len(),
                });
            }
            cleaned.push(out);
        }
        let (mut lo, mut hi) = (cleaned[0][0], cleaned[0][0]);
        for p in cleaned.iter().flatten() {
            lo = lo.min(*p);
            hi = hi.max(*p);
        }
        let scale = (hi - lo).max_element().max(f64::MIN_POSITIVE);
        check_no_intersections(&cleaned)?;
        // Orient: a loop inside an odd number of other loops bounds a hole.
        let depth: Vec<usize> = (0..cleaned.len())
            .map(|l| {
                let p = cleaned[l][0];
                (0..cleaned.len())
                    .filter(|&m| m != l && crossing_parity(p, &cleaned[m]))
                    .count()
            })
            .collect();
        for (l, pts) in cleaned.iter_mut().enumerate() {
            let want_ccw = depth[l].is_multiple_of(2);
            if (signed_area(pts) > 0.0) != want_ccw {
                pts.reverse();
            }
        }
        Ok(PolygonRegion {
            loops: cleaned,
            scale,
        })
    }

    /// Area of the region (outer loops minus holes).
    pub fn area(&self) -> f64 {
        self.loops.iter().map(|l| signed_area(l)).sum()
    }

    /// Lower and upper corners of the bounding box.
    pub fn bounds(&self) -> (DVec2, DVec2) {
        let (mut lo, mut hi) = (self.loops[0][0], self.loops[0][0]);
        for p in self.loops.iter().flatten() {
            lo = lo.min(*p);
            hi = hi.max(*p);
        }
        (lo, hi)
    }

    /// Distance from `p` to the nearest boundary edge.
    pub fn boundary_distance(&self, p: DVec2) -> f64 {
        self.edges()
            .map(|(a, b)| point_segment_distance(p, a, b))
            .fold(f64::INFINITY, f64::min)
    }

    fn edges(&self) -> impl Iterator<Item = (DVec2, DVec2)> + '_ {
        self.loops
            .iter()
            .flat_map(|l| (0..l.len()).map(move |k| (l[k], l[(k + 1) % l.len()])))
    }

    /// `true` when `p` is strictly inside (even-odd rule; points on the boundary, within
    /// `1e-12` of the region's size, are outside).
    pub fn contains(&self, p: DVec2) -> bool {
        if self.boundary_distance(p) <= 1e-12 * self.scale {
            return false;
        }
        self.loops.iter().filter(|l| crossing_parity(p, l)).count() % 2 == 1
    }

    /// Lattice points `lo + (k + 1/2) dx` (`lo` the bounding box's lower corner) strictly
    /// inside: BIPI step 1 (paper 4, section 3.1).
    pub fn lattice(&self, dx: f64) -> Vec<DVec2> {
        let (lo, hi) = self.bounds();
        crate::geometry::lattice_box(lo, hi, dx)
            .into_iter()
            .filter(|&p| self.contains(p))
            .collect()
    }

    /// Boundary elements of about `size`, normals out of the region.
    pub fn elements(&self, size: f64) -> Vec<ElementShape<DVec2>> {
        self.loops
            .iter()
            .flat_map(|l| polyline_elements(l, true, size))
            .collect()
    }
}

/// Crossing-number parity of `p` against one closed loop (half-open rule on vertices).
fn crossing_parity(p: DVec2, pts: &[DVec2]) -> bool {
    let n = pts.len();
    let mut inside = false;
    for k in 0..n {
        let (a, b) = (pts[k], pts[(k + 1) % n]);
        if (a.y > p.y) != (b.y > p.y) {
            let x = a.x + (p.y - a.y) * (b.x - a.x) / (b.y - a.y);
            if p.x < x {
                inside = !inside;
            }
        }
    }
    inside
}

fn check_no_intersections(loops: &[Vec<DVec2>]) -> Result<(), RegionError> {
    let edges: Vec<(usize, usize, DVec2, DVec2)> = loops
        .iter()
        .enumerate()
        .flat_map(|(l, pts)| (0..pts.len()).map(move |k| (l, k, pts[k], pts[(k + 1) % pts.len()])))
        .collect();
    for i in 0..edges.len() {
        let (la, ka, a0, a1) = edges[i];
        let n_a = loops[la].len();
        for &(lb, kb, b0, b1) in &edges[i + 1..] {
            // Consecutive edges of a loop share exactly one vertex; skip that contact.
            let adjacent = la == lb && (kb == (ka + 1) % n_a || ka == (kb + 1) % n_a);
            if adjacent {
                // Still an error when they overlap along a line (a spike).
                let (shared, other_a, other_b) = if kb == (ka + 1) % n_a {
                    (a1, a0, b1)
                } else {
                    (a0, a1, b0)
                };
                let (u, v) = (other_a - shared, other_b - shared);
                if u.perp_dot(v) == 0.0 && u.dot(v) > 0.0 {
                    return Err(self_intersection(la, ka, lb, kb, shared));
                }
                continue;
            }
            let min_a = a0.min(a1);
            let max_a = a0.max(a1);
            if b0.max(b1).cmplt(min_a).any() || b0.min(b1).cmpgt(max_a).any() {
                continue;
            }
            if segments_intersect(a0, a1, b0, b1) {
                return Err(self_intersection(la, ka, lb, kb, (a0 + a1) * 0.5));
            }
        }
    }
    Ok(())
}

fn self_intersection(la: usize, ka: usize, lb: usize, kb: usize, at: DVec2) -> RegionError {
    RegionError::SelfIntersection {
        loop_a: la,
        edge_a: ka,
        loop_b: lb,
        edge_b: kb,
        x: at.x,
        y: at.y,
    }
}

/// A closed, consistently oriented triangle mesh bounding a 3-D region, normals outward.
#[derive(Clone, Debug)]
pub struct TriMesh {
    /// Vertices.
    pub vertices: Vec<DVec3>,
    /// Triangles (counter-clockwise seen from outside).
    pub triangles: Vec<[u32; 3]>,
    bins: Bins,
}

#[derive(Clone, Debug, Default)]
struct Bins {
    lo: DVec2,
    cell: f64,
    nx: usize,
    ny: usize,
    start: Vec<u32>,
    items: Vec<u32>,
}

impl TriMesh {
    /// A mesh from a triangle soup (as read from STL): vertices closer than `weld` are
    /// merged, then the mesh is checked (no zero-area triangle, every edge shared by exactly
    /// two triangles with opposite directions) and oriented so its normals point outward.
    pub fn from_soup(soup: &[[DVec3; 3]], weld: f64) -> Result<Self, RegionError> {
        if soup.is_empty() {
            return Err(RegionError::Empty);
        }
        let mut index: HashMap<[i64; 3], u32> = HashMap::new();
        let mut vertices = Vec::new();
        let key = |p: DVec3| {
            let q = p / weld.max(f64::MIN_POSITIVE);
            [q.x.round() as i64, q.y.round() as i64, q.z.round() as i64]
        };
        let mut triangles = Vec::with_capacity(soup.len());
        for (t, tri) in soup.iter().enumerate() {
            let mut ids = [0u32; 3];
            for (k, &p) in tri.iter().enumerate() {
                if !p.is_finite() {
                    return Err(RegionError::NonFinite {
                        part: format!("triangle {t}"),
                        vertex: k,
                    });
                }
                ids[k] = *index.entry(key(p)).or_insert_with(|| {
                    vertices.push(p);
                    (vertices.len() - 1) as u32
                });
            }
            triangles.push(ids);
        }
        Self::new(vertices, triangles)
    }

    /// A mesh from indexed triangles; see [`TriMesh::from_soup`] for the checks.
    pub fn new(vertices: Vec<DVec3>, mut triangles: Vec<[u32; 3]>) -> Result<Self, RegionError> {
        if triangles.is_empty() {
            return Err(RegionError::Empty);
        }
        for (t, tri) in triangles.iter().enumerate() {
            let [a, b, c] = tri.map(|i| vertices[i as usize]);
            if tri[0] == tri[1]
                || tri[1] == tri[2]
                || tri[0] == tri[2]
                || (b - a).cross(c - a) == DVec3::ZERO
            {
                let m = (a + b + c) / 3.0;
                return Err(RegionError::DegenerateTriangle {
                    triangle: t,
                    x: m.x,
                    y: m.y,
                    z: m.z,
                });
            }
        }
        // Closedness and orientation: each directed edge once, its reverse once.
        let vertex = |i: u32| vertices[i as usize];
        match check_edges(&triangles, true) {
            Ok(()) => {}
            Err(EdgeFault::Flipped {
                first,
                second,
                a,
                b,
                ..
            }) => {
                let m = (vertex(a) + vertex(b)) * 0.5;
                return Err(RegionError::InconsistentOrientation {
                    first,
                    second,
                    x: m.x,
                    y: m.y,
                    z: m.z,
                });
            }
            Err(EdgeFault::Open { uses, a, b, .. }) => {
                let (pa, pb) = (vertex(a), vertex(b));
                return Err(RegionError::OpenMesh {
                    uses,
                    ax: pa.x,
                    ay: pa.y,
                    az: pa.z,
                    bx: pb.x,
                    by: pb.y,
                    bz: pb.z,
                });
            }
        }
        let volume: f64 = triangles
            .iter()
            .map(|t| {
                let [a, b, c] = t.map(|i| vertices[i as usize]);
                a.dot(b.cross(c)) / 6.0
            })
            .sum();
        if volume < 0.0 {
            for t in &mut triangles {
                t.swap(1, 2);
            }
        }
        let mut mesh = TriMesh {
            vertices,
            triangles,
            bins: Bins::default(),
        };
        mesh.build_bins();
        Ok(mesh)
    }

    /// A closed sphere: the icosahedron subdivided `subdivisions` times, projected on the
    /// sphere (`20 * 4^subdivisions` triangles).
    pub fn icosphere(centre: DVec3, radius: f64, subdivisions: u32) -> Self {
        let t = (1.0 + 5f64.sqrt()) / 2.0;
        let mut v: Vec<DVec3> = [
            (-1.0, t, 0.0),
            (1.0, t, 0.0),
            (-1.0, -t, 0.0),
            (1.0, -t, 0.0),
            (0.0, -1.0, t),
            (0.0, 1.0, t),
            (0.0, -1.0, -t),
            (0.0, 1.0, -t),
            (t, 0.0, -1.0),
            (t, 0.0, 1.0),
            (-t, 0.0, -1.0),
            (-t, 0.0, 1.0),
        ]
        .iter()
        .map(|&(x, y, z)| DVec3::new(x, y, z).normalize())
        .collect();
        let mut f: Vec<[u32; 3]> = vec![
            [0, 11, 5],
            [0, 5, 1],
            [0, 1, 7],
            [0, 7, 10],
            [0, 10, 11],
            [1, 5, 9],
            [5, 11, 4],
            [11, 10, 2],
            [10, 7, 6],
            [7, 1, 8],
            [3, 9, 4],
            [3, 4, 2],
            [3, 2, 6],
            [3, 6, 8],
            [3, 8, 9],
            [4, 9, 5],
            [2, 4, 11],
            [6, 2, 10],
            [8, 6, 7],
            [9, 8, 1],
        ];
        for _ in 0..subdivisions {
            let mut mid: HashMap<(u32, u32), u32> = HashMap::new();
            let mut next = Vec::with_capacity(f.len() * 4);
            let mut midpoint = |a: u32, b: u32, v: &mut Vec<DVec3>| {
                *mid.entry((a.min(b), a.max(b))).or_insert_with(|| {
                    v.push(((v[a as usize] + v[b as usize]) * 0.5).normalize());
                    (v.len() - 1) as u32
                })
            };
            for &[a, b, c] in &f {
                let ab = midpoint(a, b, &mut v);
                let bc = midpoint(b, c, &mut v);
                let ca = midpoint(c, a, &mut v);
                next.extend([[a, ab, ca], [b, bc, ab], [c, ca, bc], [ab, bc, ca]]);
            }
            f = next;
        }
        let vertices = v.into_iter().map(|p| centre + p * radius).collect();
        // The icosphere is closed and consistently oriented by construction.
        Self::new(vertices, f).expect("an icosphere is a closed mesh")
    }

    /// The triangle `t` as three points.
    pub fn triangle(&self, t: usize) -> [DVec3; 3] {
        self.triangles[t].map(|i| self.vertices[i as usize])
    }

    /// Enclosed volume.
    pub fn volume(&self) -> f64 {
        (0..self.triangles.len())
            .map(|t| {
                let [a, b, c] = self.triangle(t);
                a.dot(b.cross(c)) / 6.0
            })
            .sum()
    }

    /// Lower and upper corners of the bounding box.
    pub fn bounds(&self) -> (DVec3, DVec3) {
        let (mut lo, mut hi) = (self.vertices[0], self.vertices[0]);
        for &p in &self.vertices {
            lo = lo.min(p);
            hi = hi.max(p);
        }
        (lo, hi)
    }

    fn build_bins(&mut self) {
        let (lo, hi) = self.bounds();
        let n = self.triangles.len();
        let side = ((n as f64).sqrt().ceil() as usize).clamp(1, 1024);
        let span = (hi - lo).truncate().max(DVec2::splat(f64::MIN_POSITIVE));
        let cell = span.max_element() / side as f64;
        let nx = ((span.x / cell).ceil() as usize).max(1);
        let ny = ((span.y / cell).ceil() as usize).max(1);
        let lo2 = lo.truncate();
        let cell_of = |p: DVec2| -> (usize, usize) {
            let c = (p - lo2) / cell;
            (
                (c.x.floor().max(0.0) as usize).min(nx - 1),
                (c.y.floor().max(0.0) as usize).min(ny - 1),
            )
        };
        let mut lists: Vec<Vec<u32>> = vec![Vec::new(); nx * ny];
        for t in 0..n {
            let tri = self.triangle(t);
            let a = tri[0]
                .truncate()
                .min(tri[1].truncate())
                .min(tri[2].truncate());
            let b = tri[0]
                .truncate()
                .max(tri[1].truncate())
                .max(tri[2].truncate());
            let (i0, j0) = cell_of(a);
            let (i1, j1) = cell_of(b);
            for j in j0..=j1 {
                for i in i0..=i1 {
                    lists[i + nx * j].push(t as u32);
                }
            }
        }
        let mut start = vec![0u32];
        let mut items = Vec::new();
        for l in lists {
            items.extend(l);
            start.push(items.len() as u32);
        }
        self.bins = Bins {
            lo: lo2,
            cell,
            nx,
            ny,
            start,
            items,
        };
    }

    /// Heights `z` where the vertical line through `(x, y)`, perturbed symbolically by
    /// `(eps, eps^2)`, crosses the surface, sorted. Exact on edges and vertices: each
    /// crossing of a closed surface is counted once.
    pub fn column_crossings(&self, x: f64, y: f64) -> Vec<f64> {
        let b = &self.bins;
        let mut out = Vec::new();
        let c = (DVec2::new(x, y) - b.lo) / b.cell;
        if c.x < -1e-9 || c.y < -1e-9 {
            return out;
        }
        let (i, j) = (c.x.floor() as usize, c.y.floor() as usize);
        let (i, j) = (i.min(b.nx - 1), j.min(b.ny - 1));
        if c.x > b.nx as f64 + 1e-9 || c.y > b.ny as f64 + 1e-9 {
            return out;
        }
        let cell = i + b.nx * j;
        for &t in &b.items[b.start[cell] as usize..b.start[cell + 1] as usize] {
            let tri = self.triangle(t as usize);
            if let Some(z) = column_hit(x, y, tri) {
                out.push(z);
            }
        }
        out.sort_by(f64::total_cmp);
        out
    }

    /// `true` when `p` is strictly inside (ray parity along `+z`; on the surface: outside).
    pub fn contains(&self, p: DVec3) -> bool {
        let z = self.column_crossings(p.x, p.y);
        if z.contains(&p.z) {
            return false;
        }
        z.iter().filter(|&&zc| zc > p.z).count() % 2 == 1
    }

    /// Lattice points `lo + (k + 1/2) dx` strictly inside: BIPI step 1 in 3-D, one ray per
    /// lattice column.
    pub fn lattice(&self, dx: f64) -> Vec<DVec3> {
        let (lo, hi) = self.bounds();
        let count = |k: usize| ((hi[k] - lo[k]) / dx + 1e-9).floor() as usize;
        let (nx, ny, nz) = (count(0), count(1), count(2));
        let mut out = Vec::new();
        for j in 0..ny {
            for i in 0..nx {
                let x = lo.x + (i as f64 + 0.5) * dx;
                let y = lo.y + (j as f64 + 0.5) * dx;
                let zs = self.column_crossings(x, y);
                if zs.len() < 2 {
                    continue;
                }
                for k in 0..nz {
                    let z = lo.z + (k as f64 + 0.5) * dx;
                    if zs.contains(&z) {
                        continue;
                    }
                    if zs.iter().filter(|&&zc| zc > z).count() % 2 == 1 {
                        out.push(DVec3::new(x, y, z));
                    }
                }
            }
        }
        out
    }

    /// Boundary elements: every triangle split into `m^2` similar triangles with
    /// `m = ceil(longest edge / size)`, normals outward.
    pub fn elements(&self, size: f64) -> Vec<ElementShape<DVec3>> {
        let mut out = Vec::new();
        for t in 0..self.triangles.len() {
            let [a, b, c] = self.triangle(t);
            let longest = (b - a).length().max((c - b).length()).max((a - c).length());
            let m = ((longest / size).ceil() as usize).max(1);
            let normal = (b - a).cross(c - a).normalize();
            let p = |i: usize, j: usize| {
                a + (b - a) * (i as f64 / m as f64) + (c - a) * (j as f64 / m as f64)
            };
            for j in 0..m {
                for i in 0..m - j {
                    let mut push = |q: [DVec3; 3]| {
                        let area = 0.5 * (q[1] - q[0]).cross(q[2] - q[0]).length();
                        out.push(ElementShape {
                            centre: (q[0] + q[1] + q[2]) / 3.0,
                            normal,
                            area,
                            corners: q.to_vec(),
                        });
                    };
                    push([p(i, j), p(i + 1, j), p(i, j + 1)]);
                    if i + j + 1 < m {
                        push([p(i + 1, j), p(i + 1, j + 1), p(i, j + 1)]);
                    }
                }
            }
        }
        out
    }
}

/// Symbolic-perturbation sign of the edge function of `a -> b` at `p` (2-D).
fn edge_sign(a: DVec2, b: DVec2, p: DVec2) -> f64 {
    let e = (b.x - a.x) * (p.y - a.y) - (b.y - a.y) * (p.x - a.x);
    if e != 0.0 {
        return e.signum();
    }
    // Perturb p by (eps, eps^2): de = -(b.y - a.y) eps + (b.x - a.x) eps^2.
    if b.y != a.y {
        -(b.y - a.y).signum()
    } else {
        (b.x - a.x).signum()
    }
}

/// Height at which the (perturbed) vertical line through `(x, y)` crosses `tri`, if it does.
fn column_hit(x: f64, y: f64, tri: [DVec3; 3]) -> Option<f64> {
    let p = DVec2::new(x, y);
    let [a, b, c] = tri.map(|v| v.truncate());
    let s0 = edge_sign(a, b, p);
    let s1 = edge_sign(b, c, p);
    let s2 = edge_sign(c, a, p);
    if s0 == 0.0 || s0 != s1 || s1 != s2 {
        return None;
    }
    let area = (b - a).perp_dot(c - a);
    if area == 0.0 {
        return None;
    }
    let w1 = (p - a).perp_dot(c - a) / area;
    let w2 = (b - a).perp_dot(p - a) / area;
    let w0 = 1.0 - w1 - w2;
    Some(tri[0].z * w0 + tri[1].z * w1 + tri[2].z * w2)
}

/// A closed sphere of `radius` as triangles counter-clockwise seen from outside: the
/// icosphere of [`TriMesh::icosphere`] with `subdivisions`
/// (vertices on the sphere).
pub fn sphere_faces(centre: DVec3, radius: f64, subdivisions: u32) -> Vec<Vec<DVec3>> {
    let mesh = TriMesh::icosphere(centre, radius, subdivisions);
    (0..mesh.triangles.len())
        .map(|t| mesh.triangle(t).to_vec())
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn polygon_with_hole_orients_and_contains() {
        let outer = vec![
            DVec2::new(0.0, 0.0),
            DVec2::new(0.0, 1.0),
            DVec2::new(1.0, 1.0),
            DVec2::new(1.0, 0.0),
        ]; // clockwise on purpose
        let hole = vec![
            DVec2::new(0.4, 0.4),
            DVec2::new(0.6, 0.4),
            DVec2::new(0.6, 0.6),
            DVec2::new(0.4, 0.6),
        ]; // counter-clockwise on purpose
        let r = PolygonRegion::new(vec![outer, hole]).unwrap();
        assert!(signed_area(&r.loops[0]) > 0.0 && signed_area(&r.loops[1]) < 0.0);
        assert!((r.area() - 0.96).abs() < 1e-12);
        assert!(r.contains(DVec2::new(0.2, 0.2)));
        assert!(!r.contains(DVec2::new(0.5, 0.5)));
        assert!(!r.contains(DVec2::new(0.0, 0.5)), "on an edge");
        assert!(!r.contains(DVec2::new(0.4, 0.4)), "on a vertex");
        assert!(!r.contains(DVec2::new(1.5, 0.5)));
        // Normals point out of the region: away from the hole's centre on the hole.
        for e in r.elements(0.05) {
            let c = e.centre;
            if (c - DVec2::splat(0.5)).length() < 0.2 {
                assert!((c - DVec2::splat(0.5)).dot(e.normal) < 0.0);
            } else {
                assert!((c - DVec2::splat(0.5)).dot(e.normal) > 0.0);
            }
        }
        assert_eq!(r.lattice(0.1).len(), 100 - 4);
    }

    #[test]
    fn bad_polygons_are_named_errors() {
        let bow = vec![
            DVec2::new(0.0, 0.0),
            DVec2::new(1.0, 1.0),
            DVec2::new(1.0, 0.0),
            DVec2::new(0.0, 1.0),
        ];
        assert!(matches!(
            PolygonRegion::new(vec![bow]),
            Err(RegionError::SelfIntersection { .. })
        ));
        let two = vec![DVec2::ZERO, DVec2::X, DVec2::ZERO];
        assert!(matches!(
            PolygonRegion::new(vec![two]),
            Err(RegionError::TooFewVertices { .. })
        ));
        let nan = vec![DVec2::ZERO, DVec2::X, DVec2::new(f64::NAN, 1.0)];
        assert!(matches!(
            PolygonRegion::new(vec![nan]),
            Err(RegionError::NonFinite { .. })
        ));
    }

    #[test]
    fn icosphere_is_closed_outward_and_fills() {
        let m = TriMesh::icosphere(DVec3::new(0.1, 0.2, 0.3), 1.0, 3);
        let v = m.volume();
        assert!(v > 0.0 && (v - 4.0 / 3.0 * std::f64::consts::PI).abs() < 0.05 * v);
        assert!(m.contains(DVec3::new(0.1, 0.2, 0.3)));
        assert!(m.contains(DVec3::new(0.1, 0.2, 1.2)));
        assert!(!m.contains(DVec3::new(0.1, 0.2, 1.4)));
        // The column through a vertex is counted exactly once per crossing.
        let top = m.vertices[0];
        assert_eq!(m.column_crossings(top.x, top.y).len() % 2, 0);
        let dx = 0.1;
        let pts = m.lattice(dx);
        let filled = pts.len() as f64 * dx * dx * dx;
        assert!((filled - v).abs() < 0.05 * v, "{filled} vs {v}");
        assert!(pts.iter().all(|&p| m.contains(p)));
        for e in m.elements(0.2) {
            assert!((e.centre - DVec3::new(0.1, 0.2, 0.3)).dot(e.normal) > 0.0);
        }
        let area: f64 = m.elements(0.05).iter().map(|e| e.area).sum();
        let area0: f64 = m.elements(10.0).iter().map(|e| e.area).sum();
        assert!((area - area0).abs() < 1e-9 * area0);
    }

    #[test]
    fn open_and_flipped_meshes_are_named_errors() {
        let m = TriMesh::icosphere(DVec3::ZERO, 1.0, 1);
        let soup: Vec<[DVec3; 3]> = (0..m.triangles.len()).map(|t| m.triangle(t)).collect();
        assert!(TriMesh::from_soup(&soup, 1e-9).is_ok());
        // Reversed order everywhere: accepted and re-oriented outward.
        let reversed: Vec<[DVec3; 3]> = soup.iter().map(|t| [t[0], t[2], t[1]]).collect();
        let r = TriMesh::from_soup(&reversed, 1e-9).unwrap();
        assert!(r.volume() > 0.0);
        let open = &soup[1..];
        assert!(matches!(
            TriMesh::from_soup(open, 1e-9),
            Err(RegionError::OpenMesh { uses: 1, .. })
        ));
        let mut flipped = soup.clone();
        flipped[3] = [soup[3][0], soup[3][2], soup[3][1]];
        assert!(matches!(
            TriMesh::from_soup(&flipped, 1e-9),
            Err(RegionError::InconsistentOrientation { .. })
        ));
    }

    #[test]
    fn a_sphere_is_closed_outward_and_holds_its_volume() {
        let c = DVec3::new(0.3, -0.1, 0.2);
        let r = 0.4;
        for size in [0.2, 0.05] {
            let n = crate::geometry::sphere_subdivisions(r, size);
            let faces = sphere_faces(c, r, n);
            assert_eq!(faces.len(), 20 * 4usize.pow(n));
            let surface = crate::surface::Surface::from_polygons(&faces, None, 1e-9).unwrap();
            check_edges(&surface.faces, true).unwrap();
            let mut nearest = f64::INFINITY;
            for f in 0..surface.faces.len() {
                let p = surface.corners(f);
                let normal = surface.normal(f);
                // Outward, and the face's plane no nearer the centre than the chord error.
                let plane = (p[0] - c).dot(normal);
                assert!(plane > 0.0);
                nearest = nearest.min(plane);
                let longest = (0..3).map(|k| (p[(k + 1) % 3] - p[k]).length());
                assert!(longest.fold(0.0, f64::max) < 1.3 * size);
            }
            // The inscribed polyhedron holds the ball of radius `nearest`.
            let ball = |rho: f64| 4.0 / 3.0 * std::f64::consts::PI * rho.powi(3);
            let v = surface.volume();
            assert!(v < ball(r) && v > ball(nearest), "{v} vs {}", ball(r));
            assert!(nearest > r * (1.0 - (size / r).powi(2)));
        }
        assert_eq!(crate::geometry::sphere_subdivisions(1.0, 10.0), 0);
        assert_eq!(crate::geometry::sphere_subdivisions(1.0, 1e-9), 8);
    }
}
