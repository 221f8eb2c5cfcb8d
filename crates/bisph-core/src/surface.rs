//! Wall surfaces from polygon meshes (triangles and quadrilaterals, e.g. read from STL or OBJ):
//! checks with named errors, orientation, refinement into boundary elements (element centre
//! at the face centroid, the face's area and unit normal out of the fluid: paper 1, 5.4), mass
//! properties of the enclosed solid, and the parametric Apollo-like capsule of paper 1, 5.4.

use crate::geometry::{check_edges, EdgeFault, ElementShape};
use glam::{DMat3, DVec3};
use std::collections::HashMap;
use std::f64::consts::TAU;

/// Why a mesh cannot be a wall surface. Faces are counted from 0 in file order.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum SurfaceError {
    /// No face at all.
    #[error("the mesh has no face")]
    Empty,
    /// A face with fewer than 3 or more than 4 corners.
    #[error("face {face} has {corners} corners; expected a triangle or a quadrilateral")]
    BadFace {
        /// Face index.
        face: usize,
        /// Number of corners.
        corners: usize,
    },
    /// A coordinate is NaN or infinite.
    #[error("face {face} has a non-finite coordinate")]
    NonFinite {
        /// Face index.
        face: usize,
    },
    /// A face of (nearly) zero area or with repeated corners.
    #[error("face {face} is degenerate (area {area:e}) near ({x:.6}, {y:.6}, {z:.6})")]
    Degenerate {
        /// Face index.
        face: usize,
        /// Its area.
        area: f64,
        /// Centroid.
        x: f64,
        /// Centroid.
        y: f64,
        /// Centroid.
        z: f64,
    },
    /// An edge used by one face only (or by more than two): the mesh is open.
    #[error(
        "open mesh: the edge ({ax:.6}, {ay:.6}, {az:.6}) - ({bx:.6}, {by:.6}, {bz:.6}) of face {face} is used by {uses} face(s), expected 2 (set closed = false for an open surface)"
    )]
    Open {
        /// A face owning the edge.
        face: usize,
        /// Number of faces using the edge.
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
    /// Two neighbouring faces run their shared edge in the same direction: one of them is
    /// flipped relative to the other.
    #[error(
        "inconsistent normals: faces {first} and {second} share the edge near ({x:.6}, {y:.6}, {z:.6}) in the same direction (one of them is flipped)"
    )]
    Inconsistent {
        /// One face.
        first: usize,
        /// The other.
        second: usize,
        /// Edge midpoint.
        x: f64,
        /// Edge midpoint.
        y: f64,
        /// Edge midpoint.
        z: f64,
    },
    /// A face's stored normal (STL facet normal) points against its corner order.
    #[error(
        "inverted normal: face {face}'s stored normal points against its corner order (dot = {dot:.3})"
    )]
    Inverted {
        /// Face index.
        face: usize,
        /// Cosine between the stored normal and the corner-order normal.
        dot: f64,
    },
    /// A non-planar quadrilateral.
    #[error("face {face} is a non-planar quadrilateral (corner {distance:e} off its plane)")]
    NonPlanar {
        /// Face index.
        face: usize,
        /// Distance of a corner from the mean plane.
        distance: f64,
    },
}

/// A polygon surface: vertices and faces (3 or 4 vertex indices, counter-clockwise seen from
/// the side the normal points to).
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Surface {
    /// Vertices.
    pub vertices: Vec<DVec3>,
    /// Faces as vertex indices.
    pub faces: Vec<Vec<u32>>,
}

/// Twice the vector area of a polygon (`sum p_k x p_{k+1}`), normal by the corner order.
fn vector_area(p: &[DVec3]) -> DVec3 {
    let mut s = DVec3::ZERO;
    for k in 0..p.len() {
        s += p[k].cross(p[(k + 1) % p.len()]);
    }
    0.5 * s
}

impl Surface {
    /// A surface from face polygons given by their corner points; corners closer than `weld`
    /// are merged. `stored_normals` (STL facet normals, zero when absent) must agree with the
    /// corner order. Checks every face (3 or 4 finite corners, non-zero area, planar).
    pub fn from_polygons(
        polygons: &[Vec<DVec3>],
        stored_normals: Option<&[DVec3]>,
        weld: f64,
    ) -> Result<Self, SurfaceError> {
        if polygons.is_empty() {
            return Err(SurfaceError::Empty);
        }
        let mut index: HashMap<[i64; 3], u32> = HashMap::new();
        let mut s = Surface::default();
        let key = |p: DVec3| {
            let q = p / weld.max(f64::MIN_POSITIVE);
            [q.x.round() as i64, q.y.round() as i64, q.z.round() as i64]
        };
        for (f, poly) in polygons.iter().enumerate() {
            if poly.len() < 3 || poly.len() > 4 {
                return Err(SurfaceError::BadFace {
                    face: f,
                    corners: poly.len(),
                });
            }
            if poly.iter().any(|p| !p.is_finite()) {
                return Err(SurfaceError::NonFinite { face: f });
            }
            let ids: Vec<u32> = poly
                .iter()
                .map(|&p| {
                    *index.entry(key(p)).or_insert_with(|| {
                        s.vertices.push(p);
                        (s.vertices.len() - 1) as u32
                    })
                })
                .collect();
            s.faces.push(ids);
        }
        for f in 0..s.faces.len() {
            s.check_face(f)?;
            if let Some(normals) = stored_normals {
                let stored = normals.get(f).copied().unwrap_or(DVec3::ZERO);
                if stored.length() > 0.0 {
                    let n = s.normal(f);
                    let dot = n.dot(stored.normalize());
                    if dot < 0.0 {
                        return Err(SurfaceError::Inverted { face: f, dot });
                    }
                }
            }
        }
        Ok(s)
    }

    /// Corner points of face `f`.
    pub fn corners(&self, f: usize) -> Vec<DVec3> {
        self.faces[f]
            .iter()
            .map(|&i| self.vertices[i as usize])
            .collect()
    }

    /// Unit normal of face `f` by its corner order.
    pub fn normal(&self, f: usize) -> DVec3 {
        vector_area(&self.corners(f)).normalize_or_zero()
    }

    /// Area of face `f`.
    pub fn area(&self, f: usize) -> f64 {
        vector_area(&self.corners(f)).length()
    }

    fn check_face(&self, f: usize) -> Result<(), SurfaceError> {
        let ids = &self.faces[f];
        let p = self.corners(f);
        let centroid = p.iter().copied().sum::<DVec3>() / p.len() as f64;
        let size = p
            .iter()
            .map(|&q| (q - centroid).length())
            .fold(0.0, f64::max);
        let area = vector_area(&p).length();
        let repeated = (0..ids.len()).any(|a| (a + 1..ids.len()).any(|b| ids[a] == ids[b]));
        if repeated || area.is_nan() || area <= 1e-12 * size * size {
            return Err(SurfaceError::Degenerate {
                face: f,
                area,
                x: centroid.x,
                y: centroid.y,
                z: centroid.z,
            });
        }
        if p.len() == 4 {
            let n = vector_area(&p).normalize();
            let distance = p
                .iter()
                .map(|&q| (q - centroid).dot(n).abs())
                .fold(0.0, f64::max);
            if distance > 1e-9 * size {
                return Err(SurfaceError::NonPlanar { face: f, distance });
            }
        }
        Ok(())
    }

    /// Checks that neighbouring faces agree on orientation (each shared edge is run once in
    /// each direction) and, when `closed`, that every edge is shared by exactly two faces.
    pub fn check_topology(&self, closed: bool) -> Result<(), SurfaceError> {
        let vertex = |i: u32| self.vertices[i as usize];
        match check_edges(&self.faces, closed) {
            Ok(()) => Ok(()),
            Err(EdgeFault::Flipped {
                first,
                second,
                a,
                b,
                ..
            }) => {
                let m = (vertex(a) + vertex(b)) * 0.5;
                Err(SurfaceError::Inconsistent {
                    first,
                    second,
                    x: m.x,
                    y: m.y,
                    z: m.z,
                })
            }
            Err(EdgeFault::Open { face, uses, a, b }) => {
                let (pa, pb) = (vertex(a), vertex(b));
                Err(SurfaceError::Open {
                    face,
                    uses,
                    ax: pa.x,
                    ay: pa.y,
                    az: pa.z,
                    bx: pb.x,
                    by: pb.y,
                    bz: pb.z,
                })
            }
        }
    }

    /// Signed enclosed volume (positive when the normals point outward; closed meshes).
    pub fn volume(&self) -> f64 {
        self.triangles()
            .iter()
            .map(|[a, b, c]| a.dot(b.cross(*c)) / 6.0)
            .sum()
    }

    /// Reverses every face (normals flip).
    pub fn flip(&mut self) {
        for f in &mut self.faces {
            f.reverse();
        }
    }

    /// Applies `p -> transform(p)` to every vertex (a proper rigid or similarity map keeps
    /// the orientation).
    pub fn map(&mut self, transform: impl Fn(DVec3) -> DVec3) {
        for v in &mut self.vertices {
            *v = transform(*v);
        }
    }

    /// Faces split into triangles (quads along their first diagonal).
    pub fn triangles(&self) -> Vec<[DVec3; 3]> {
        let mut out = Vec::with_capacity(self.faces.len() * 2);
        for f in 0..self.faces.len() {
            let p = self.corners(f);
            out.push([p[0], p[1], p[2]]);
            if p.len() == 4 {
                out.push([p[0], p[2], p[3]]);
            }
        }
        out
    }

    /// Mass, centre of mass and inertia tensor about it (world axes) of the solid enclosed by
    /// a closed, outward-oriented surface of uniform `density`: sums over the signed
    /// tetrahedra `(0, a, b, c)` of the volume `det/6`, the first moment and the second
    /// moment `C = det [[2,1,1],[1,2,1],[1,1,2]]/120` in the tetrahedron's edge basis;
    /// `I = tr(C') 1 - C'` with `C' = C - m c c^T`.
    pub fn mass_properties(&self, density: f64) -> (f64, DVec3, DMat3) {
        let canon = DMat3::from_cols_array(&[2.0, 1.0, 1.0, 1.0, 2.0, 1.0, 1.0, 1.0, 2.0]) / 120.0;
        let (mut volume, mut first, mut second) = (0.0, DVec3::ZERO, DMat3::ZERO);
        for [a, b, c] in self.triangles() {
            let basis = DMat3::from_cols(a, b, c);
            let det = basis.determinant();
            volume += det / 6.0;
            first += (a + b + c) * (det / 24.0);
            second += basis * canon * basis.transpose() * det;
        }
        let mass = density * volume;
        let centre = first / volume;
        let outer = |v: DVec3| DMat3::from_cols(v * v.x, v * v.y, v * v.z);
        let c = second * density - outer(centre) * mass;
        let trace = c.x_axis.x + c.y_axis.y + c.z_axis.z;
        (mass, centre, DMat3::IDENTITY * trace - c)
    }

    /// Number of elements [`Surface::elements`] makes at `size` (as a float, so that a huge
    /// mesh or a tiny size cannot overflow): lets a caller refuse a mesh before allocating.
    pub fn element_count(&self, size: f64) -> f64 {
        let count = |l: f64| (l / size * (1.0 - 1e-9)).ceil().max(1.0);
        let mut total = 0.0;
        for f in 0..self.faces.len() {
            let p = self.corners(f);
            total += if p.len() == 3 {
                let m = count(
                    (p[1] - p[0])
                        .length()
                        .max((p[2] - p[1]).length())
                        .max((p[0] - p[2]).length()),
                );
                m * m
            } else {
                count((p[1] - p[0]).length().max((p[2] - p[3]).length()))
                    * count((p[3] - p[0]).length().max((p[2] - p[1]).length()))
            };
        }
        total
    }

    /// Boundary elements of about `size`: every triangle split into `m^2` similar triangles
    /// and every (planar) quadrilateral into `m x n` bilinear sub-quads, `m`, `n` from the
    /// longest edges; each element at its centroid with its area and the face's normal.
    pub fn elements(&self, size: f64) -> Vec<ElementShape<DVec3>> {
        let mut out = Vec::new();
        let mut push = |q: &[DVec3], normal: DVec3| {
            let area = vector_area(q).length();
            // Area-weighted centroid (the face centroid; corner mean for triangles).
            let centre = if q.len() == 3 {
                (q[0] + q[1] + q[2]) / 3.0
            } else {
                let (a1, a2) = (
                    vector_area(&[q[0], q[1], q[2]]).length(),
                    vector_area(&[q[0], q[2], q[3]]).length(),
                );
                ((q[0] + q[1] + q[2]) * a1 + (q[0] + q[2] + q[3]) * a2) / (3.0 * (a1 + a2))
            };
            out.push(ElementShape {
                centre,
                normal,
                area,
                corners: q.to_vec(),
            });
        };
        for f in 0..self.faces.len() {
            let p = self.corners(f);
            let normal = vector_area(&p).normalize();
            let count = |l: f64| ((l / size * (1.0 - 1e-9)).ceil() as usize).max(1);
            if p.len() == 3 {
                let [a, b, c] = [p[0], p[1], p[2]];
                let m = count((b - a).length().max((c - b).length()).max((a - c).length()));
                let at = |i: usize, j: usize| {
                    a + (b - a) * (i as f64 / m as f64) + (c - a) * (j as f64 / m as f64)
                };
                for j in 0..m {
                    for i in 0..m - j {
                        push(&[at(i, j), at(i + 1, j), at(i, j + 1)], normal);
                        if i + j + 1 < m {
                            push(&[at(i + 1, j), at(i + 1, j + 1), at(i, j + 1)], normal);
                        }
                    }
                }
            } else {
                let m = count((p[1] - p[0]).length().max((p[2] - p[3]).length()));
                let n = count((p[3] - p[0]).length().max((p[2] - p[1]).length()));
                let at = |i: usize, j: usize| {
                    let (u, v) = (i as f64 / m as f64, j as f64 / n as f64);
                    p[0] * ((1.0 - u) * (1.0 - v))
                        + p[1] * (u * (1.0 - v))
                        + p[2] * (u * v)
                        + p[3] * ((1.0 - u) * v)
                };
                for j in 0..n {
                    for i in 0..m {
                        push(
                            &[at(i, j), at(i + 1, j), at(i + 1, j + 1), at(i, j + 1)],
                            normal,
                        );
                    }
                }
            }
        }
        out
    }
}

/// Dimensions of an Apollo-like capsule (paper 1, 5.4), axis `+z`, heat-shield apex at the
/// origin: a spherical heat shield, a toroidal shoulder tangent to it and to a conical
/// afterbody, closed by a flat top.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Capsule {
    /// Radius of the spherical heat shield.
    pub heat_shield_radius: f64,
    /// Largest diameter (at the shoulder).
    pub diameter: f64,
    /// Radius of the toroidal shoulder.
    pub shoulder_radius: f64,
    /// Half-angle of the afterbody cone (radians).
    pub cone_half_angle: f64,
    /// Total height from the heat-shield apex to the flat top.
    pub height: f64,
}

impl Capsule {
    /// The profile `(r, z)` from the apex (r = 0, z = 0) to the top centre, points about
    /// `size` apart; `None` when the dimensions do not fit together.
    pub fn profile(&self, size: f64) -> Option<Vec<(f64, f64)>> {
        let (big_r, rs, alpha) = (
            self.heat_shield_radius,
            self.shoulder_radius,
            self.cone_half_angle,
        );
        let r_max = 0.5 * self.diameter;
        let sin1 = (r_max - rs) / (big_r - rs);
        if !(rs > 0.0 && big_r > rs && sin1 > 0.0 && sin1 < 1.0 && alpha > 0.0 && alpha < 1.5) {
            return None;
        }
        let phi1 = sin1.asin();
        // Shoulder centre: on the ray from the sphere centre (0, R) at angle phi1.
        let (rc, zc) = ((big_r - rs) * sin1, big_r - (big_r - rs) * phi1.cos());
        let beta1 = phi1 - 0.5 * std::f64::consts::PI;
        let (r2, z2) = (rc + rs * alpha.cos(), zc + rs * alpha.sin());
        if self.height <= z2 {
            return None;
        }
        let r_top = r2 - (self.height - z2) * alpha.tan();
        if r_top <= 0.0 {
            return None;
        }
        let steps = |length: f64| ((length / size).ceil() as usize).max(1);
        let mut out = vec![(0.0, 0.0)];
        let n = steps(big_r * phi1);
        for k in 1..=n {
            let phi = phi1 * k as f64 / n as f64;
            out.push((big_r * phi.sin(), big_r * (1.0 - phi.cos())));
        }
        let n = steps(rs * (alpha - beta1));
        for k in 1..=n {
            let beta = beta1 + (alpha - beta1) * k as f64 / n as f64;
            out.push((rc + rs * beta.cos(), zc + rs * beta.sin()));
        }
        let cone = (self.height - z2) / alpha.cos();
        let n = steps(cone);
        for k in 1..=n {
            let s = k as f64 / n as f64;
            out.push((r2 + (r_top - r2) * s, z2 + (self.height - z2) * s));
        }
        let n = steps(r_top);
        for k in 1..=n {
            out.push((r_top * (1.0 - k as f64 / n as f64), self.height));
        }
        Some(out)
    }

    /// The closed surface of revolution, normals outward, faces of about `size`
    /// (triangle fans at the two poles, planar quads elsewhere: each band is a frustum
    /// cut into `ceil(2 pi r_max / size)` sectors).
    pub fn surface(&self, size: f64) -> Option<Surface> {
        let profile = self.profile(size)?;
        let sectors = ((TAU * 0.5 * self.diameter / size).ceil() as usize).max(8);
        let mut s = Surface::default();
        let ring = |r: f64, z: f64, k: usize| {
            let t = TAU * k as f64 / sectors as f64;
            DVec3::new(r * t.cos(), r * t.sin(), z)
        };
        // Vertex 0: bottom pole; each inner profile point: a ring; last: top pole.
        s.vertices.push(DVec3::ZERO);
        let inner = &profile[1..profile.len() - 1];
        for &(r, z) in inner {
            for k in 0..sectors {
                s.vertices.push(ring(r, z, k));
            }
        }
        let top = s.vertices.len() as u32;
        s.vertices.push(DVec3::new(0.0, 0.0, self.height));
        let id = |band: usize, k: usize| (1 + band * sectors + k % sectors) as u32;
        for k in 0..sectors {
            // Outward normal of the bottom fan points down: order pole, k+1, k.
            s.faces.push(vec![0, id(0, k + 1), id(0, k)]);
        }
        for band in 0..inner.len() - 1 {
            for k in 0..sectors {
                s.faces.push(vec![
                    id(band, k),
                    id(band, k + 1),
                    id(band + 1, k + 1),
                    id(band + 1, k),
                ]);
            }
        }
        let last = inner.len() - 1;
        for k in 0..sectors {
            s.faces.push(vec![top, id(last, k), id(last, k + 1)]);
        }
        Some(s)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn cube(lo: DVec3, hi: DVec3) -> Vec<Vec<DVec3>> {
        let v = |i: usize| {
            DVec3::new(
                if i & 1 == 1 { hi.x } else { lo.x },
                if i & 2 == 2 { hi.y } else { lo.y },
                if i & 4 == 4 { hi.z } else { lo.z },
            )
        };
        [
            [0, 4, 6, 2],
            [1, 3, 7, 5],
            [0, 1, 5, 4],
            [2, 6, 7, 3],
            [0, 2, 3, 1],
            [4, 5, 7, 6],
        ]
        .iter()
        .map(|f| f.iter().map(|&i| v(i)).collect())
        .collect()
    }

    #[test]
    fn cube_checks_volume_and_inertia() {
        let (lo, hi) = (DVec3::new(1.0, 2.0, 3.0), DVec3::new(3.0, 3.0, 3.5));
        let s = Surface::from_polygons(&cube(lo, hi), None, 1e-9).unwrap();
        s.check_topology(true).unwrap();
        assert!((s.volume() - 1.0).abs() < 1e-12);
        let (m, c, i) = s.mass_properties(2.0);
        assert!((m - 2.0).abs() < 1e-12);
        assert!((c - DVec3::new(2.0, 2.5, 3.25)).length() < 1e-12);
        // Box a x b x c: I_x = m (b^2 + c^2) / 12.
        let (a, b, cz) = (2.0, 1.0, 0.5);
        let expect = DVec3::new(b * b + cz * cz, a * a + cz * cz, a * a + b * b) * (m / 12.0);
        assert!((DVec3::new(i.x_axis.x, i.y_axis.y, i.z_axis.z) - expect).length() < 1e-12);
        assert!(i.x_axis.y.abs() < 1e-12 && i.x_axis.z.abs() < 1e-12);
        let e = s.elements(0.25);
        let area: f64 = e.iter().map(|e| e.area).sum();
        assert!((area - 2.0 * (2.0 + 1.0 + 0.5)).abs() < 1e-12);
        assert_eq!(e.len(), 2 * (8 * 4 + 8 * 2 + 4 * 2));
    }

    #[test]
    fn named_errors_say_which_face() {
        let (lo, hi) = (DVec3::ZERO, DVec3::ONE);
        let mut faces = cube(lo, hi);
        faces.pop();
        let s = Surface::from_polygons(&faces, None, 1e-9).unwrap();
        assert!(matches!(
            s.check_topology(true),
            Err(SurfaceError::Open { uses: 1, .. })
        ));
        assert!(s.check_topology(false).is_ok());
        let mut faces = cube(lo, hi);
        faces[3].reverse();
        let s = Surface::from_polygons(&faces, None, 1e-9).unwrap();
        match s.check_topology(true) {
            Err(SurfaceError::Inconsistent { first, second, .. }) => {
                assert!(first == 3 || second == 3)
            }
            other => panic!("{other:?}"),
        }
        let mut faces = cube(lo, hi);
        faces[2] = vec![faces[2][0], faces[2][1], faces[2][1]];
        assert!(matches!(
            Surface::from_polygons(&faces, None, 1e-9),
            Err(SurfaceError::Degenerate { face: 2, .. })
        ));
        let faces = cube(lo, hi);
        let mut normals = vec![DVec3::ZERO; 6];
        normals[4] = DVec3::Z; // face 4 is the bottom (-z)
        assert!(matches!(
            Surface::from_polygons(&faces, Some(&normals), 1e-9),
            Err(SurfaceError::Inverted { face: 4, .. })
        ));
    }

    #[test]
    fn capsule_is_closed_outward_and_has_its_dimensions() {
        let c = Capsule {
            heat_shield_radius: 4.491,
            diameter: 3.849,
            shoulder_radius: 0.196,
            cone_half_angle: 32.5f64.to_radians(),
            height: 2.184,
        };
        let s = c.surface(0.1).unwrap();
        s.check_topology(true).unwrap();
        let v = s.volume();
        assert!(v > 0.0);
        let (lo, hi) = s
            .vertices
            .iter()
            .fold((DVec3::splat(1e9), DVec3::splat(-1e9)), |(a, b), &p| {
                (a.min(p), b.max(p))
            });
        assert!((hi.z - 2.184).abs() < 1e-12 && lo.z.abs() < 1e-12);
        assert!((hi.x - 3.849 / 2.0).abs() < 2e-3);
        // Volume of the revolved profile (Pappus, trapezoids in r^2) vs the polyhedron.
        let p = c.profile(0.01).unwrap();
        let exact: f64 = p
            .windows(2)
            .map(|w| {
                let ((r0, z0), (r1, z1)) = (w[0], w[1]);
                std::f64::consts::PI * (z1 - z0) * (r0 * r0 + r0 * r1 + r1 * r1) / 3.0
            })
            .sum();
        assert!((v - exact).abs() / exact < 0.01, "{v} vs {exact}");
    }
}
