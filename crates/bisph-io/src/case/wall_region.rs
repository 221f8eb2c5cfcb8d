//! The closed boundary of `shape = "walls"` water, the region BIPI packs (paper 4): the walls
//! cut at the level, the pieces that face water, and a lid over the water at the level
//! (normal up, out of the water) with the walls' cross-section as its outline, obstacles that
//! pierce the surface as its holes.

use crate::case::dim::CaseDim;
use crate::case::error::CaseError;
use crate::case::regions::BlockRegion;
use crate::case::schema::LoadedCase;
use crate::case::wall_fill::WallWater;
use bisph_core::geometry::{signed_area, winding_number, ElementShape};
use glam::{DVec2, DVec3};
use std::collections::HashMap;

/// The region of block `k` (`shape = "walls"`) at spacing `dx`, walls split into elements of
/// `element_size` (unless a wall gives its own).
pub fn region_inside_walls<V: CaseDim>(
    loaded: &LoadedCase,
    k: usize,
    dx: f64,
    element_size: f64,
) -> Result<BlockRegion<V>, CaseError> {
    let water = WallWater::of::<V>(loaded, k, dx, element_size)?;
    let key = format!("fluid_block[{k}]");
    if !water.level.is_finite() {
        return Err(loaded.error(
            &format!("{key}.level"),
            "BIPI packs a closed region: the water inside the walls needs a level",
        ));
    }
    let up = -water.down;
    // How far in front of a wall piece (or below the level) the water is probed.
    let probe = 1e-6 * dx;
    let mut shapes: Vec<ElementShape<DVec3>> = Vec::new();
    let mut edges = Vec::new();
    let cut = Level {
        up,
        level: water.level,
        tolerance: 1e-9 * dx,
    };
    for f in &water.facets {
        let Some(clipped) = cut.clip(&f.corners) else {
            continue;
        };
        let piece: Vec<DVec3> = clipped.iter().map(|c| c.0).collect();
        let (centre, area) = centroid(&piece);
        if area <= 0.0 {
            continue;
        }
        // A piece bounds the water where any part of it faces water (its centre, or a corner
        // drawn slightly in): a floor element partly under an obstacle standing on it stays
        // whole, so the boundary has no gap beside the obstacle.
        let faces_water = std::iter::once(centre)
            .chain(piece.iter().map(|&c| c + (centre - c) * 0.01))
            .any(|q| water.holds(q - f.normal * probe));
        if !faces_water {
            continue;
        }
        if let Some((a, b)) = slice(&clipped) {
            edges.push((a, b, f.normal));
        }
        shapes.push(ElementShape {
            centre,
            normal: f.normal,
            area,
            corners: piece,
        });
    }
    let lid = if V::DIM == 2 {
        lid_2d(&edges, up, element_size)
    } else {
        lid_3d(&edges, up)
    }
    .map_err(|m| loaded.error(&format!("{key}.level"), m))?;
    shapes.extend(lid);
    // Volume (area in 2-D) by the divergence theorem over the closed boundary.
    let measure = shapes
        .iter()
        .map(|s| s.centre.dot(s.normal) * s.area)
        .sum::<f64>()
        / V::DIM as f64;
    let elements = shapes
        .iter()
        .map(|s| ElementShape {
            centre: V::from_slice(&s.centre.to_array()),
            normal: V::from_slice(&s.normal.to_array()),
            area: s.area,
            corners: s
                .corners
                .iter()
                .map(|c| V::from_slice(&c.to_array()))
                .collect(),
        })
        .collect();
    let lattice = water.lattice(dx);
    Ok(BlockRegion::new(
        elements,
        lattice,
        measure,
        Box::new(move |p: V| water.holds(DVec3::from_array(p.to_xyz()))),
    ))
}

/// The level plane: height `level` along `up`; corners within `tolerance` of it lie on it.
#[derive(Clone, Copy)]
struct Level {
    up: DVec3,
    level: f64,
    tolerance: f64,
}

impl Level {
    /// Height of `p` above the level, zero within the tolerance.
    fn above(&self, p: DVec3) -> f64 {
        let s = p.dot(self.up) - self.level;
        if s.abs() <= self.tolerance {
            0.0
        } else {
            s
        }
    }

    /// Where the edge `a`-`b` meets the level, computed from the edge's end points in a fixed
    /// order, so that the two elements sharing the edge get the same point to the last bit.
    fn crossing(&self, a: DVec3, b: DVec3) -> DVec3 {
        let (a, b) = if a.to_array() <= b.to_array() {
            (a, b)
        } else {
            (b, a)
        };
        let (sa, sb) = (self.above(a), self.above(b));
        if sa == 0.0 {
            return a;
        }
        if sb == 0.0 {
            return b;
        }
        a + (b - a) * (sa / (sa - sb))
    }

    /// The part of a convex polygon (a segment in 2-D) at or below the level, its corners in
    /// order, each flagged when it lies on the level; `None` when nothing of it is below.
    fn clip(&self, corners: &[DVec3]) -> Option<Vec<(DVec3, bool)>> {
        let below = |p: DVec3| self.above(p) <= 0.0;
        let corner = |p: DVec3| (p, self.above(p) == 0.0);
        if corners.len() == 2 {
            let (a, b) = (corners[0], corners[1]);
            return match (below(a), below(b)) {
                (true, true) => Some(vec![corner(a), corner(b)]),
                (true, false) => Some(vec![corner(a), (self.crossing(a, b), true)]),
                (false, true) => Some(vec![(self.crossing(a, b), true), corner(b)]),
                (false, false) => None,
            };
        }
        let m = corners.len();
        let mut out = Vec::with_capacity(m + 1);
        for i in 0..m {
            let (a, b) = (corners[i], corners[(i + 1) % m]);
            if below(a) {
                out.push(corner(a));
            }
            if below(a) != below(b) && self.above(a) != 0.0 && self.above(b) != 0.0 {
                out.push((self.crossing(a, b), true));
            }
        }
        (out.len() >= 3).then_some(out)
    }
}

/// The corners of a clipped piece that lie on the level: its outline there (2-D: the one
/// point, given twice; 3-D: an edge), `None` when it does not reach the level.
fn slice(piece: &[(DVec3, bool)]) -> Option<(DVec3, DVec3)> {
    let on: Vec<DVec3> = piece.iter().filter(|c| c.1).map(|c| c.0).collect();
    match on.len() {
        1 if piece.len() == 2 => Some((on[0], on[0])),
        2 if on[0] != on[1] => Some((on[0], on[1])),
        _ => None,
    }
}

/// Centroid and area of a planar convex polygon (a segment's midpoint and length).
fn centroid(corners: &[DVec3]) -> (DVec3, f64) {
    if corners.len() == 2 {
        return (
            (corners[0] + corners[1]) * 0.5,
            corners[0].distance(corners[1]),
        );
    }
    let (mut sum, mut area) = (DVec3::ZERO, 0.0);
    for i in 1..corners.len() - 1 {
        let (a, b, c) = (corners[0], corners[i], corners[i + 1]);
        let da = 0.5 * (b - a).cross(c - a).length();
        sum += (a + b + c) * (da / 3.0);
        area += da;
    }
    if area == 0.0 {
        return (corners[0], 0.0);
    }
    (sum / area, area)
}

/// The 2-D lid: the stretches of the level line over the water, split into elements of about
/// `size`. Each wall that reaches the level crosses it at a point with the water on one side
/// along the line (`-n`); a stretch runs from a point with the water ahead to the next point,
/// which has the water behind.
fn lid_2d(
    crossings: &[(DVec3, DVec3, DVec3)],
    up: DVec3,
    size: f64,
) -> Result<Vec<ElementShape<DVec3>>, String> {
    // Along the line, with `up` to its left.
    let along = DVec3::new(up.y, -up.x, 0.0);
    let mut points: Vec<(f64, DVec3, bool)> = crossings
        .iter()
        .map(|&(p, _, n)| (p.dot(along), p, n.dot(along) < 0.0))
        .collect();
    points.sort_by(|a, b| a.0.total_cmp(&b.0));
    let flat = |p: DVec3| DVec2::new(p.x, p.y);
    let mut out = Vec::new();
    let mut start: Option<DVec3> = None;
    for (_, p, ahead) in points {
        match (start, ahead) {
            (None, true) => start = Some(p),
            (Some(a), false) => {
                // Corners from the far end back: the normal is right of travel (up).
                for e in bisph_core::geometry::segment_elements(flat(p), flat(a), size) {
                    out.push(ElementShape {
                        centre: e.centre.extend(0.0),
                        normal: e.normal.extend(0.0),
                        area: e.area,
                        corners: e.corners.iter().map(|c| c.extend(0.0)).collect(),
                    });
                }
                start = None;
            }
            _ => {
                return Err(format!(
                    "the walls' crossings of the level do not pair into stretches of water at ({:.6}, {:.6}); expected walls that close around the water there",
                    p.x, p.y
                ))
            }
        }
    }
    if let Some(a) = start {
        return Err(format!(
            "the water at the level is not closed beyond ({:.6}, {:.6}); expected a wall on that side",
            a.x, a.y
        ));
    }
    Ok(out)
}

/// The 3-D lid: the outline at the level chained into loops (water on the left, seen from
/// above), outer loops with the holes they hold, each cut into triangles.
fn lid_3d(
    outline: &[(DVec3, DVec3, DVec3)],
    up: DVec3,
) -> Result<Vec<ElementShape<DVec3>>, String> {
    let (e1, e2) = plane_basis(up);
    let to_plane = |p: DVec3| DVec2::new(p.dot(e1), p.dot(e2));
    // Along the outline with the water on the left, seen from above.
    let edges: Vec<(DVec3, DVec3)> = outline
        .iter()
        .map(|&(a, b, n)| {
            if (b - a).dot(up.cross(n)) >= 0.0 {
                (a, b)
            } else {
                (b, a)
            }
        })
        .collect();
    let loops = chain(&edges)?;
    let loops2: Vec<Vec<DVec2>> = loops
        .iter()
        .map(|l| simplify(&l.iter().map(|&p| to_plane(p)).collect::<Vec<_>>()))
        .filter(|l| l.len() >= 3)
        .collect();
    let height = edges.first().map_or(0.0, |&(a, _)| a.dot(up));
    let from_plane = |q: DVec2| e1 * q.x + e2 * q.y + up * height;
    let mut out = Vec::new();
    for (outer, holes) in nest(&loops2)? {
        let polygon = bridge(outer, holes);
        for [a, b, c] in ear_clip(&polygon)? {
            let corners = vec![from_plane(a), from_plane(b), from_plane(c)];
            let (centre, area) = centroid(&corners);
            if area > 0.0 {
                out.push(ElementShape {
                    centre,
                    normal: up,
                    area,
                    corners,
                });
            }
        }
    }
    Ok(out)
}

/// Two unit vectors that make a right-handed frame with `up`.
fn plane_basis(up: DVec3) -> (DVec3, DVec3) {
    let e1 = up.any_orthonormal_vector();
    (e1, up.cross(e1))
}

/// Chains directed edges into closed loops by their shared end points.
fn chain(edges: &[(DVec3, DVec3)]) -> Result<Vec<Vec<DVec3>>, String> {
    let key = |p: DVec3| p.to_array().map(f64::to_bits);
    let mut next: HashMap<[u64; 3], usize> = HashMap::new();
    for (i, &(a, _)) in edges.iter().enumerate() {
        if next.insert(key(a), i).is_some() {
            return Err(format!(
                "the walls' outline at the level is not a set of closed loops: two walls start at ({:.6}, {:.6}, {:.6}); expected walls that meet edge to edge there",
                a.x, a.y, a.z
            ));
        }
    }
    let mut used = vec![false; edges.len()];
    let mut loops = Vec::new();
    for start in 0..edges.len() {
        if used[start] {
            continue;
        }
        let mut l = Vec::new();
        let mut i = start;
        while !used[i] {
            used[i] = true;
            l.push(edges[i].0);
            let end = edges[i].1;
            i = *next.get(&key(end)).ok_or_else(|| {
                format!(
                    "the walls' outline at the level is open at ({:.6}, {:.6}, {:.6}); expected walls that close around the water there",
                    end.x, end.y, end.z
                )
            })?;
        }
        loops.push(l);
    }
    Ok(loops)
}

/// Drops the corners where the outline runs straight on (many wall elements meet the level
/// along one flat wall).
fn simplify(p: &[DVec2]) -> Vec<DVec2> {
    let scale = p.iter().map(|q| q.length()).fold(1e-300, f64::max);
    let mut out: Vec<DVec2> = p.to_vec();
    let mut changed = true;
    while changed && out.len() > 3 {
        changed = false;
        for i in 0..out.len() {
            let n = out.len();
            let (a, b, c) = (out[(i + n - 1) % n], out[i], out[(i + 1) % n]);
            let straight = (b - a).perp_dot(c - b).abs() <= 1e-12 * scale * scale;
            if straight && (b - a).dot(c - b) > 0.0 || a == b {
                out.remove(i);
                changed = true;
                break;
            }
        }
    }
    out
}

/// Outer loops (counter-clockwise), each with the holes (clockwise) it holds directly.
type Nested<'a> = Vec<(&'a [DVec2], Vec<&'a [DVec2]>)>;

fn nest(loops: &[Vec<DVec2>]) -> Result<Nested<'_>, String> {
    let mut out: Nested<'_> = loops
        .iter()
        .filter(|l| signed_area(l) > 0.0)
        .map(|l| (l.as_slice(), Vec::new()))
        .collect();
    for h in loops.iter().filter(|l| signed_area(l) < 0.0) {
        let owner = out
            .iter_mut()
            .filter(|(o, _)| winding_number(h[0], o) != 0)
            .min_by(|a, b| signed_area(a.0).total_cmp(&signed_area(b.0)));
        match owner {
            Some((_, holes)) => holes.push(h.as_slice()),
            None => {
                return Err(format!(
                    "an obstacle's outline at the level, near ({:.6}, {:.6}) in the level's plane, lies in no water",
                    h[0].x, h[0].y
                ))
            }
        }
    }
    Ok(out)
}

/// `true` when the segments `p`-`q` and `a`-`b` cross at a point inside both.
fn crosses(p: DVec2, q: DVec2, a: DVec2, b: DVec2) -> bool {
    let d1 = (q - p).perp_dot(a - p);
    let d2 = (q - p).perp_dot(b - p);
    let d3 = (b - a).perp_dot(p - a);
    let d4 = (b - a).perp_dot(q - a);
    d1 * d2 < 0.0 && d3 * d4 < 0.0
}

/// One polygon from an outer loop and its holes: each hole is joined to the outline by a
/// pair of coincident edges from its rightmost corner to the nearest corner it can see.
fn bridge(outer: &[DVec2], mut holes: Vec<&[DVec2]>) -> Vec<DVec2> {
    let rightmost = |h: &[DVec2]| {
        (0..h.len())
            .max_by(|&i, &j| h[i].x.total_cmp(&h[j].x))
            .unwrap_or(0)
    };
    holes.sort_by(|a, b| b[rightmost(b)].x.total_cmp(&a[rightmost(a)].x));
    let mut polygon = outer.to_vec();
    for (k, h) in holes.iter().enumerate() {
        let m = rightmost(h);
        let from = h[m];
        let blocked = |to: DVec2, edges: &[DVec2]| {
            (0..edges.len()).any(|i| crosses(from, to, edges[i], edges[(i + 1) % edges.len()]))
        };
        let mut order: Vec<usize> = (0..polygon.len()).collect();
        order.sort_by(|&i, &j| {
            from.distance(polygon[i])
                .total_cmp(&from.distance(polygon[j]))
        });
        let visible = order.into_iter().find(|&i| {
            !blocked(polygon[i], &polygon)
                && !blocked(polygon[i], h)
                && holes[k + 1..].iter().all(|o| !blocked(polygon[i], o))
        });
        let v = visible.unwrap_or(0);
        let mut joined = polygon[..=v].to_vec();
        joined.extend((0..=h.len()).map(|s| h[(m + s) % h.len()]));
        joined.extend_from_slice(&polygon[v..]);
        polygon = joined;
    }
    polygon
}

/// Triangles of a simple counter-clockwise polygon (bridged holes allowed) by ear clipping.
fn ear_clip(polygon: &[DVec2]) -> Result<Vec<[DVec2; 3]>, String> {
    let mut p = polygon.to_vec();
    let mut out = Vec::with_capacity(p.len());
    while p.len() > 3 {
        let n = p.len();
        let ear = (0..n).find(|&i| {
            let (a, b, c) = (p[(i + n - 1) % n], p[i], p[(i + 1) % n]);
            (b - a).perp_dot(c - b) > 0.0
                && p.iter().all(|&q| {
                    q == a
                        || q == b
                        || q == c
                        || !((b - a).perp_dot(q - a) >= 0.0
                            && (c - b).perp_dot(q - b) >= 0.0
                            && (a - c).perp_dot(q - c) >= 0.0)
                })
        });
        let Some(i) = ear else {
            return Err(
                "the lid over the water at the level could not be cut into triangles; expected walls whose outline there is a simple polygon".to_string(),
            );
        };
        out.push([p[(i + n - 1) % n], p[i], p[(i + 1) % n]]);
        p.remove(i);
    }
    if p.len() == 3 && signed_area(&p) > 0.0 {
        out.push([p[0], p[1], p[2]]);
    }
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::case::parse_case;
    use glam::DVec3;

    fn loaded(text: &str) -> LoadedCase {
        parse_case("<region test>", text, &[]).unwrap()
    }

    /// `sum_j n_j s_j` over the region's elements (zero for a closed surface) and the largest
    /// `s_j` (the scale of its round-off).
    fn closure<V: CaseDim>(region: &BlockRegion<V>) -> (f64, f64) {
        let mut sum = DVec3::ZERO;
        let mut largest = 0.0f64;
        for e in &region.elements {
            sum += DVec3::from_array(e.normal.to_xyz()) * e.area;
            largest = largest.max(e.area);
        }
        (sum.length(), largest)
    }

    const TANK_2D: &str = r#"
name = "region"
dim = 2
[fluid]
density = 1000.0
sound_speed = 20.0
gravity = [0.0, -9.81]
[resolution]
dx = 0.05
[time]
end = 0.1
[[wall]]
shape = "box"
min = [0.0, 0.0]
max = [1.0, 1.0]
open = ["+y"]
[[wall]]                     # a pier through the surface, clockwise
shape = "polygon"
points = [[0.3, 0.0], [0.3, 0.8], [0.4, 0.8], [0.4, 0.0]]
[[wall]]                     # an obstacle under water, clockwise
shape = "polygon"
points = [[0.6, 0.1], [0.6, 0.2], [0.8, 0.2], [0.8, 0.1]]
[[fluid_block]]
shape = "walls"
level = 0.5
"#;

    /// The 2-D water around a pier and an obstacle: a closed boundary (its normals sum to
    /// zero to round-off), the exact area, two stretches of lid either side of the pier
    /// (normals up, at the level), and every lattice point inside.
    #[test]
    fn the_water_inside_2d_walls_is_a_closed_region() {
        let l = loaded(TANK_2D);
        let r = region_inside_walls::<DVec2>(&l, 0, 0.05, 0.05).unwrap();
        let (sum, largest) = closure(&r);
        assert!(sum < 1e-12 * largest, "sum n s = {sum}");
        let expected = 0.5 - 0.1 * 0.5 - 0.2 * 0.1;
        assert!((r.measure - expected).abs() < 1e-12, "{}", r.measure);
        let lid: f64 = r
            .elements
            .iter()
            .filter(|e| e.normal == DVec2::Y && e.centre.y == 0.5)
            .inspect(|e| assert!(e.corners.iter().all(|c| c.y == 0.5)))
            .map(|e| e.area)
            .sum();
        assert!((lid - 0.9).abs() < 1e-12, "lid {lid}");
        assert!(!r.lattice.is_empty() && r.lattice.iter().all(|&p| r.contains(p)));
        assert!(!r.contains(DVec2::new(0.35, 0.25)) && !r.contains(DVec2::new(0.7, 0.15)));
        assert!(!r.contains(DVec2::new(0.5, 0.55)));
    }

    /// The 3-D water in a box with a square pier through the surface and a cylinder held
    /// under water (neither touches the floor): closed (normals sum to zero), the volume the box less the pier and the
    /// cylinder's prism, the lid the box's section less the pier's, with the pier as a hole.
    #[test]
    fn the_water_inside_3d_walls_is_a_closed_region_with_a_holed_lid() {
        let text = r#"
name = "region"
dim = 3
[fluid]
density = 1000.0
sound_speed = 20.0
gravity = [0.0, 0.0, -9.81]
[resolution]
dx = 0.1
[time]
end = 0.1
[[wall]]
shape = "box"
min = [0.0, 0.0, 0.0]
max = [1.0, 1.0, 1.0]
open = ["+z"]
[[wall]]
shape = "box"
min = [0.3, 0.3, 0.1]
max = [0.5, 0.6, 0.8]
fluid = "outside"
[[wall]]
shape = "cylinder"
start = [0.75, 0.75, 0.1]
end = [0.75, 0.75, 0.3]
radius = 0.1
[[fluid_block]]
shape = "walls"
level = 0.5
"#;
        let l = loaded(text);
        let r = region_inside_walls::<DVec3>(&l, 0, 0.1, 0.1).unwrap();
        let (sum, largest) = closure(&r);
        assert!(sum < 1e-12 * largest, "sum n s = {sum}");
        let lid: f64 = r
            .elements
            .iter()
            .filter(|e| e.normal == DVec3::Z && e.centre.z == 0.5)
            .map(|e| e.area)
            .sum();
        assert!((lid - (1.0 - 0.2 * 0.3)).abs() < 1e-12, "lid {lid}");
        // The cylinder's prism: its base area times its height, from its own floor-facing cap.
        let cylinder = crate::case::dim::oriented_wall_shapes::<DVec3>(&l, 2, 0.1).unwrap();
        let base: f64 = cylinder
            .iter()
            .filter(|e| e.normal.z > 0.5)
            .map(|e| e.area)
            .sum();
        let expected = 0.5 - 0.2 * 0.3 * 0.4 - base * 0.2;
        assert!(
            (r.measure - expected).abs() < 1e-12,
            "{} vs {expected}",
            r.measure
        );
        assert!(r.lattice.iter().all(|&p| r.contains(p)));
        assert!(!r.contains(DVec3::new(0.4, 0.45, 0.3)));
    }

    /// Walls that do not close around the water at the level are a named error on `level`.
    #[test]
    fn an_open_outline_at_the_level_is_a_named_error() {
        let text = TANK_2D.replace("open = [\"+y\"]", "open = [\"+y\", \"+x\"]");
        let l = loaded(&text);
        let e = region_inside_walls::<DVec2>(&l, 0, 0.05, 0.05)
            .err()
            .unwrap();
        assert_eq!(e.key, "fluid_block[0].level");
    }

    /// BIPI packs the 2-D water around the pier and the obstacle: every particle stays in
    /// the water, none is lost, and a run starts from the packed particles.
    #[test]
    fn bipi_packs_the_water_inside_2d_walls() {
        let text = TANK_2D.replace("level = 0.5", "level = 0.5\nfill = \"bipi\"");
        let l = loaded(&text);
        let packed = crate::case::fill::pack_block::<DVec2>(&l, 0, &mut |_| {
            std::ops::ControlFlow::Continue(())
        })
        .unwrap();
        let x = &packed.packer.positions;
        assert_eq!(x.len(), packed.region.lattice.len());
        assert!(x.iter().all(|&p| packed.region.contains(p)));
        // The run starts from the packed particles, not the lattice.
        let sim: bisph_core::Simulation<DVec2> = crate::case::build_simulation(&l).unwrap();
        assert_eq!(sim.fluid.len(), x.len());
        let start: Vec<DVec2> = (0..x.len()).map(|i| sim.fluid.position[i]).collect();
        let mut packed_sorted = x.clone();
        let mut start_sorted = start;
        for v in [&mut packed_sorted, &mut start_sorted] {
            v.sort_by(|a, b| a.x.total_cmp(&b.x).then(a.y.total_cmp(&b.y)));
        }
        assert_eq!(packed_sorted, start_sorted);
    }
}
