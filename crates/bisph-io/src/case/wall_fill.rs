//! `shape = "walls"`: the fluid inside the case's walls below a level. A lattice over the
//! walls' bounding box keeps the points below `level` that lie above a floor (the first wall
//! met straight down along gravity faces down, out of the fluid: water poured in from above
//! would rest there), below which the walls are open or close with a lid, and at least
//! `clearance` from every wall. Obstacles and bodies are cut out the same way: a point inside
//! one meets its bottom going down, which faces up, or its top going up, which faces down.

use crate::case::dim::oriented_wall_shapes;
use crate::case::dim::CaseDim;
use crate::case::error::CaseError;
use crate::case::schema::LoadedCase;
use bisph_core::geometry::{lattice_box, ElementShape};
use glam::DVec3;
use rayon::prelude::*;

/// Default least distance of a particle from a wall, in units of the spacing.
pub const DEFAULT_CLEARANCE_OVER_DX: f64 = 0.5;

/// One wall element as a planar polygon in 3-D coordinates (2-D: a segment at z = 0).
pub(crate) struct Facet {
    /// Corners.
    pub corners: Vec<DVec3>,
    /// Unit normal, out of the fluid.
    pub normal: DVec3,
    lo: DVec3,
    hi: DVec3,
}

/// What a `shape = "walls"` block fills: the walls as facets, gravity's direction and the
/// level and clearance of block `k` at spacing `dx` (walls split into elements of
/// `element_size` unless a wall gives its own).
pub(crate) struct WallWater {
    pub facets: Vec<Facet>,
    /// Unit vector along gravity.
    pub down: DVec3,
    /// Height along `-down` below which the walls are filled.
    pub level: f64,
    /// Least distance of a lattice point from a wall.
    pub clearance: f64,
}

impl WallWater {
    pub(crate) fn of<V: CaseDim>(
        loaded: &LoadedCase,
        k: usize,
        dx: f64,
        element_size: f64,
    ) -> Result<Self, CaseError> {
        let case = &loaded.case;
        let block = &case.fluid_block[k];
        let key = format!("fluid_block[{k}]");
        let gravity = V::from_slice(&case.fluid.gravity);
        let g = gravity.length();
        if g == 0.0 {
            return Err(loaded.error(
                &format!("{key}.shape"),
                "\"walls\" fills the walls up to a level along gravity: fluid.gravity must not be zero",
            ));
        }
        let mut facets = Vec::new();
        for w in 0..case.wall.len() {
            let size = case.wall[w].element_size.unwrap_or(element_size);
            facets.extend(
                oriented_wall_shapes::<V>(loaded, w, size)?
                    .iter()
                    .map(facet),
            );
        }
        if facets.is_empty() {
            return Err(loaded.error(&key, "\"walls\" needs at least one [[wall]] to fill"));
        }
        Ok(WallWater {
            facets,
            down: DVec3::from_array(gravity.to_xyz()) / g,
            level: block.level.unwrap_or(f64::INFINITY),
            clearance: block.clearance.unwrap_or(DEFAULT_CLEARANCE_OVER_DX) * dx,
        })
    }

    /// `true` when `x` lies in the water: below the level and above a floor.
    pub(crate) fn holds(&self, x: DVec3) -> bool {
        -x.dot(self.down) < self.level && above_a_floor(&self.facets, x, self.down)
    }

    /// The lattice points at spacing `dx` in the water and at least the clearance from
    /// every wall.
    pub(crate) fn lattice<V: CaseDim>(&self, dx: f64) -> Vec<V> {
        let (mut lo, mut hi) = (self.facets[0].lo, self.facets[0].hi);
        for f in &self.facets {
            lo = lo.min(f.lo);
            hi = hi.max(f.hi);
        }
        let (lo, hi) = (V::from_slice(&lo.to_array()), V::from_slice(&hi.to_array()));
        lattice_box(lo, hi, dx)
            .into_par_iter()
            .filter(|&p| {
                let x = DVec3::from_array(p.to_xyz());
                self.holds(x) && clear(&self.facets, x, self.clearance)
            })
            .collect()
    }
}

/// The lattice points of block `k` (`shape = "walls"`) at spacing `dx`.
pub fn fill_inside_walls<V: CaseDim>(
    loaded: &LoadedCase,
    k: usize,
    dx: f64,
) -> Result<Vec<V>, CaseError> {
    let element_size = dx * loaded.case.resolution.element_over_dx;
    Ok(WallWater::of::<V>(loaded, k, dx, element_size)?.lattice(dx))
}

fn facet<V: CaseDim>(s: &ElementShape<V>) -> Facet {
    let corners: Vec<DVec3> = s
        .corners
        .iter()
        .map(|c| DVec3::from_array(c.to_xyz()))
        .collect();
    let (mut lo, mut hi) = (corners[0], corners[0]);
    for c in &corners {
        lo = lo.min(*c);
        hi = hi.max(*c);
    }
    Facet {
        corners,
        normal: DVec3::from_array(s.normal.to_xyz()),
        lo,
        hi,
    }
}

/// `true` when `x` lies in the water the walls hold: the first facet met straight down faces
/// down (out of the fluid: a floor), and straight up the walls are open or the first facet met
/// faces up (a lid). A point inside an obstacle meets its bottom going down, or, where the
/// obstacle is open at the bottom, its top going up, which faces down.
fn above_a_floor(facets: &[Facet], x: DVec3, down: DVec3) -> bool {
    first_facing(facets, x, down).is_some_and(|facing| facing > 0.0)
        && first_facing(facets, x, -down).is_none_or(|facing| facing > 0.0)
}

/// `normal . dir` of the first facet met from `x` along `dir` (`None`: none is met).
fn first_facing(facets: &[Facet], x: DVec3, dir: DVec3) -> Option<f64> {
    let mut first: Option<(f64, f64)> = None;
    for f in facets {
        let facing = f.normal.dot(dir);
        if facing.abs() < 1e-12 {
            continue;
        }
        let s = (f.corners[0] - x).dot(f.normal) / facing;
        if s <= 0.0 || first.is_some_and(|(best, _)| s >= best) {
            continue;
        }
        if contains(f, x + dir * s) {
            first = Some((s, facing));
        }
    }
    first.map(|(_, facing)| facing)
}

/// `true` when `q`, a point of the facet's plane, lies on the facet.
fn contains(f: &Facet, q: DVec3) -> bool {
    let eps = 1e-9 * (f.hi - f.lo).length().max(1e-300);
    if (q - f.lo).min_element() < -eps || (f.hi - q).min_element() < -eps {
        return false;
    }
    if f.corners.len() == 2 {
        return true;
    }
    let c = &f.corners;
    (1..c.len() - 1).any(|m| in_triangle(q, c[0], c[m], c[m + 1], eps))
}

fn in_triangle(q: DVec3, a: DVec3, b: DVec3, c: DVec3, eps: f64) -> bool {
    let n = (b - a).cross(c - a);
    let side = |u: DVec3, v: DVec3| (v - u).cross(q - u).dot(n) >= -eps * n.length();
    side(a, b) && side(b, c) && side(c, a)
}

/// `true` when `x` is at least `clearance` from every facet.
fn clear(facets: &[Facet], x: DVec3, clearance: f64) -> bool {
    facets.iter().all(|f| {
        let outside_box = (f.lo - x).max(x - f.hi).max(DVec3::ZERO);
        outside_box.length() >= clearance || distance(f, x) >= clearance * (1.0 - 1e-9)
    })
}

/// Distance from `x` to a facet (a segment, or a planar polygon split into triangles).
fn distance(f: &Facet, x: DVec3) -> f64 {
    let c = &f.corners;
    if c.len() == 2 {
        return segment_distance(x, c[0], c[1]);
    }
    let plane = (x - c[0]).dot(f.normal);
    let q = x - f.normal * plane;
    if contains(f, q) {
        return plane.abs();
    }
    (0..c.len())
        .map(|m| segment_distance(x, c[m], c[(m + 1) % c.len()]))
        .fold(f64::INFINITY, f64::min)
}

fn segment_distance(x: DVec3, a: DVec3, b: DVec3) -> f64 {
    let ab = b - a;
    let t = ((x - a).dot(ab) / ab.length_squared().max(1e-300)).clamp(0.0, 1.0);
    (x - (a + ab * t)).length()
}
