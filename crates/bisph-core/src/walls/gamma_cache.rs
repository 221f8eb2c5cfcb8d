//! Wall pieces for the geometric Shepard factor (paper 2, eq 8): runs of elements merged
//! into the largest straight segments (2-D) and planar regions (3-D), with per-cell candidate
//! lists; see [`GammaCache`].

use crate::bi;
use crate::bi::segment::point_segment_distance;
use crate::dim::{Concrete, Vector};
use crate::kernel::Wendland;
use crate::neighbours::Periodicity;
use glam::DVec3;
use std::collections::HashMap;

/// The geometry of the wall elements a [`GammaCache`] is built from (the walls' elements,
/// borrowed).
#[derive(Clone, Copy, Debug)]
pub struct ElementGeometry<'a, V: Vector> {
    /// Current corner points, flattened: element `j` owns
    /// `corners[corner_start[j]..corner_start[j + 1]]`.
    pub corners: &'a [V],
    /// Offsets into `corners` (length = elements + 1).
    pub corner_start: &'a [u32],
    /// Unit normals, out of the fluid.
    pub normal: &'a [V],
    /// Areas (lengths in 2-D).
    pub area: &'a [f64],
    /// Centres.
    pub centre: &'a [V],
    /// Largest distance from each centre to a corner.
    pub reach: &'a [f64],
    /// Largest reach of all elements.
    pub max_reach: f64,
}

impl<V: Vector> ElementGeometry<'_, V> {
    /// Number of elements.
    pub fn len(&self) -> usize {
        self.centre.len()
    }

    /// `true` when there are no elements.
    pub fn is_empty(&self) -> bool {
        self.centre.is_empty()
    }

    /// Current corner points of element `j`.
    pub fn current_corners(&self, j: usize) -> &[V] {
        &self.corners[self.corner_start[j] as usize..self.corner_start[j + 1] as usize]
    }
}

/// Wall pieces prepared for the geometric Shepard factor, with per-cell candidate lists.
///
/// `gamma` depends on the wall geometry only, not on how it is cut into elements: the
/// integral over a segment is the sum of the integrals over its parts. So in 2-D every run of
/// consecutive elements that continue one straight wall (each starts exactly where the
/// previous one ends, the same normal, perpendicular to both) becomes one piece, and a
/// particle near a flat wall evaluates one exact segment integral instead of one per element
/// within its support. Other elements (3-D polygons, isolated segments) are pieces of their
/// own. A uniform grid over the pieces (cells of `support / 2` in 2-D, `support` in 3-D)
/// lists, per cell, every piece (with its periodic image) that comes within the support of
/// some point of the cell; a point in a cell with an empty list, or outside the grid, has
/// `gamma = 1` without a walk. Built from the current element corners, so moving and
/// stretching walls rebuild it when they are placed ([`super::Walls::move_to`]); the sum is
/// over the cell's list in piece order, independent of threads.
#[derive(Clone, Debug, Default)]
pub struct GammaCache<V: Vector> {
    /// Kernel support the lists hold for; 0 when not built.
    support: f64,
    period: Periodicity<V>,
    /// Corners of every piece, flattened: piece `p` owns `corners[start[p]..start[p + 1]]`.
    corners: Vec<V>,
    start: Vec<u32>,
    normal: Vec<V>,
    area: Vec<f64>,
    centre: Vec<V>,
    reach: Vec<f64>,
    origin: V,
    inv_cell: f64,
    dims: [usize; 3],
    /// Candidates of cell `c`: `candidates[cell_start[c]..cell_start[c + 1]]`, each a piece
    /// and the index of its image shift in `shifts`.
    cell_start: Vec<u32>,
    candidates: Vec<(u32, u32)>,
    shifts: Vec<V>,
}

impl<V: Vector> GammaCache<V> {
    /// `true` when the lists were built for a kernel of this support.
    pub fn is_built_for(&self, support: f64) -> bool {
        self.support > 0.0 && self.support == support
    }

    /// The support the lists were built for (0 when not built).
    pub fn support(&self) -> f64 {
        self.support
    }

    /// Number of pieces (merged wall segments and other elements).
    pub fn pieces(&self) -> usize {
        self.normal.len()
    }

    /// Corners of piece `p` (2-D: the segment's two ends; 3-D: its outline edges as pairs of
    /// ends).
    pub fn piece_corners(&self, p: usize) -> &[V] {
        &self.corners[self.start[p] as usize..self.start[p + 1] as usize]
    }

    /// Rebuilds the pieces and lists from the current `elements` for kernel support
    /// `support`, with `period` the periodic axes (elements in the primary period).
    pub fn rebuild(
        &mut self,
        elements: ElementGeometry<'_, V>,
        support: f64,
        period: Periodicity<V>,
    ) {
        self.support = support;
        self.period = period;
        self.merge_pieces(elements);
        self.build_lists();
    }

    /// Pieces from the current elements (see [`merge_segments`], [`merge_faces`]).
    fn merge_pieces(&mut self, e: ElementGeometry<'_, V>) {
        self.corners.clear();
        self.start.clear();
        self.start.push(0);
        self.normal.clear();
        self.area.clear();
        self.centre.clear();
        self.reach.clear();
        if V::DIM == 2 {
            merge_segments(e, self);
        } else {
            merge_faces(e, self);
        }
    }

    /// Appends a piece: its corners (2-D: the segment's two ends; 3-D: its outline edges as
    /// pairs of ends), outward normal, area, and a centre and reach bounding it.
    fn push_piece(&mut self, corners: &[V], normal: V, area: f64, centre: V, reach: f64) {
        self.corners.extend_from_slice(corners);
        self.start.push(self.corners.len() as u32);
        self.normal.push(normal);
        self.area.push(area);
        self.centre.push(centre);
        self.reach.push(reach);
    }

    /// The uniform grid over the pieces and each cell's candidates.
    fn build_lists(&mut self) {
        let support = self.support;
        self.shifts.clear();
        self.candidates.clear();
        self.cell_start.clear();
        if self.normal.is_empty() {
            self.dims = [0; 3];
            return;
        }
        let (mut lo, mut hi) = (self.corners[0], self.corners[0]);
        for &c in &self.corners {
            lo = lo.min_by_component(c);
            hi = hi.max_by_component(c);
        }
        for k in 0..V::DIM {
            if self.period.is_periodic(k) {
                let m = self.period.min.get(k);
                lo.set(k, m);
                hi.set(k, m + self.period.length.get(k));
            } else {
                lo.set(k, lo.get(k) - support);
                hi.set(k, hi.get(k) + support);
            }
        }
        let mut cell = if V::DIM == 2 { 0.5 * support } else { support };
        let dims = loop {
            let mut dims = [1usize; 3];
            for (k, d) in dims.iter_mut().enumerate().take(V::DIM) {
                *d = (((hi.get(k) - lo.get(k)) / cell).ceil() as usize).max(1);
            }
            // Bounded memory for walls spread over a large region.
            if dims[0] * dims[1] * dims[2] <= 1 << 22 {
                break dims;
            }
            cell *= 2.0;
        };
        self.origin = lo;
        self.inv_cell = 1.0 / cell;
        self.dims = dims;
        // Image shifts: every combination of -2..=2 periods along the periodic axes.
        let mut ranges = [(0i64, 0i64); 3];
        for (k, r) in ranges.iter_mut().enumerate().take(V::DIM) {
            if self.period.is_periodic(k) {
                *r = (-2, 2);
            }
        }
        for a in ranges[0].0..=ranges[0].1 {
            for b in ranges[1].0..=ranges[1].1 {
                for c in ranges[2].0..=ranges[2].1 {
                    let mut s = V::ZERO;
                    for (k, m) in [a, b, c].into_iter().enumerate().take(V::DIM) {
                        s.set(k, m as f64 * self.period.length.get(k));
                    }
                    self.shifts.push(s);
                }
            }
        }
        let half_diagonal = 0.5 * cell * (V::DIM as f64).sqrt();
        let mut pairs: Vec<(u32, u32, u32)> = Vec::new();
        for p in 0..self.normal.len() {
            let corners = self.piece_corners(p);
            let (mut plo, mut phi) = (corners[0], corners[0]);
            for &c in corners {
                plo = plo.min_by_component(c);
                phi = phi.max_by_component(c);
            }
            for (si, &s) in self.shifts.iter().enumerate() {
                // Cells that the piece's box, widened by the support, overlaps.
                let mut range = [(0usize, 0usize); 3];
                let mut empty = false;
                for (k, r) in range.iter_mut().enumerate() {
                    if k >= V::DIM {
                        continue;
                    }
                    let a = ((plo.get(k) + s.get(k) - support - lo.get(k)) * self.inv_cell).floor();
                    let b = ((phi.get(k) + s.get(k) + support - lo.get(k)) * self.inv_cell).floor();
                    let (a, b) = (a.max(0.0), b.min(dims[k] as f64 - 1.0));
                    if a > b {
                        empty = true;
                        break;
                    }
                    *r = (a as usize, b as usize);
                }
                if empty {
                    continue;
                }
                for cz in range[2].0..=range[2].1 {
                    for cy in range[1].0..=range[1].1 {
                        for cx in range[0].0..=range[0].1 {
                            let mut mid = lo;
                            for (k, ck) in [cx, cy, cz].into_iter().enumerate().take(V::DIM) {
                                mid.set(k, lo.get(k) + (ck as f64 + 0.5) * cell);
                            }
                            // A lower bound of the distance from the cell's centre.
                            let distance = if V::DIM == 2 {
                                point_segment_distance(mid - s, corners[0], corners[1])
                            } else {
                                let sphere = (self.centre[p] + s - mid).length() - self.reach[p];
                                let plane = self.normal[p].dot(mid - s - corners[0]).abs();
                                sphere.max(plane)
                            };
                            if distance < support + half_diagonal {
                                let c = cx + dims[0] * (cy + dims[1] * cz);
                                pairs.push((c as u32, p as u32, si as u32));
                            }
                        }
                    }
                }
            }
        }
        // Counting sort by cell, stable: each cell's pieces in piece order.
        let cells = dims[0] * dims[1] * dims[2];
        self.cell_start.resize(cells + 1, 0);
        for &(c, _, _) in &pairs {
            self.cell_start[c as usize + 1] += 1;
        }
        for c in 0..cells {
            self.cell_start[c + 1] += self.cell_start[c];
        }
        self.candidates.resize(pairs.len(), (0, 0));
        let mut fill = self.cell_start.clone();
        for &(c, p, s) in &pairs {
            let slot = &mut fill[c as usize];
            self.candidates[*slot as usize] = (p, s);
            *slot += 1;
        }
    }

    /// The candidates of the cell holding `x` (empty outside the grid).
    #[inline(always)]
    fn cell_candidates(&self, x: V) -> &[(u32, u32)] {
        let mut c = 0usize;
        let mut stride = 1usize;
        for k in 0..V::DIM {
            let v = (x.get(k) - self.origin.get(k)) * self.inv_cell;
            // Also rejects NaN.
            if !(v >= 0.0 && v < self.dims[k] as f64) {
                return &[];
            }
            c += v as usize * stride;
            stride *= self.dims[k];
        }
        &self.candidates[self.cell_start[c] as usize..self.cell_start[c + 1] as usize]
    }

    /// Geometric Shepard factor at `x` (paper 2, eq 8), as the element walk
    /// [`crate::walls::geometric_shepard::gamma`] but over the cell's
    /// candidate pieces. The kernel must have the support the lists were built for.
    pub fn gamma(&self, kernel: &Wendland, x: V) -> f64 {
        debug_assert!(self.is_built_for(kernel.support));
        let eps = 1e-12 * kernel.h;
        let mut shift = V::ZERO;
        let gamma = self.sum_at(kernel, x, eps, &mut shift);
        if shift == V::ZERO {
            return gamma;
        }
        let mut unused = V::ZERO;
        self.sum_at(kernel, x + shift, eps, &mut unused)
    }

    /// `1 + sum` of the candidates' contributions at `x`; subtracts `eps n` from `shift` for
    /// each piece `x` lies on.
    #[inline(always)]
    fn sum_at(&self, kernel: &Wendland, x: V, eps: f64, shift: &mut V) -> f64 {
        let x = self.period.wrap(x);
        let mut gamma = 1.0;
        for &(p, s) in self.cell_candidates(x) {
            let p = p as usize;
            let xs = x - self.shifts[s as usize];
            let r = self.centre[p] - xs;
            let (n, reach) = (self.normal[p], self.reach[p]);
            if r.length_squared() > (self.support + reach) * (self.support + reach) {
                continue;
            }
            let rn = r.dot(n);
            if rn.abs() < eps && (r - n * rn).length() <= reach * (1.0 + 1e-12) {
                *shift -= n * eps;
            }
            gamma += bi::outline_shepard(kernel, xs, self.piece_corners(p), n);
        }
        gamma
    }
}

/// 2-D pieces of a [`GammaCache`]: every maximal run of consecutive elements that continue
/// one straight wall (each starts exactly where the previous one ends, with the same normal,
/// perpendicular to both) becomes one segment; other elements stay as they are.
fn merge_segments<V: Vector>(e: ElementGeometry<'_, V>, cache: &mut GammaCache<V>) {
    let straight = |c: &[V], n: V| {
        let d = c[1] - c[0];
        c.len() == 2 && n.dot(d).abs() <= 1e-12 * d.length()
    };
    let mut j = 0;
    while j < e.len() {
        let c = e.current_corners(j);
        let n = e.normal[j];
        let mut area = e.area[j];
        if c.len() == 2 && straight(c, n) {
            let (p0, mut p1) = (c[0], c[1]);
            let d0 = p1 - p0;
            while j + 1 < e.len() {
                let next = e.current_corners(j + 1);
                if next.len() != 2
                    || next[0] != p1
                    || e.normal[j + 1] != n
                    || (next[1] - next[0]).dot(d0) <= 0.0
                    || !straight(next, n)
                {
                    break;
                }
                p1 = next[1];
                area += e.area[j + 1];
                j += 1;
            }
            cache.push_piece(
                &[p0, p1],
                n,
                area,
                (p0 + p1) * 0.5,
                (p1 - p0).length() * 0.5,
            );
        } else {
            cache.push_piece(&c[..2], n, area, e.centre[j], e.reach[j]);
        }
        j += 1;
    }
}

/// 3-D pieces of a [`GammaCache`]: the elements of one plane (same normal, bit for bit, and
/// the same offset along it) become one region, the outline left when every edge shared by
/// two of them (the same two corners, opposite directions) is dropped, with runs of
/// collinear outline edges joined; each element is first oriented counter-clockwise about
/// its normal. A box face is then one rectangle of four edges, whatever its mesh.
fn merge_faces<V: Vector>(e: ElementGeometry<'_, V>, cache: &mut GammaCache<V>) {
    let (Concrete::Three(all_corners), Concrete::Three(normal), Concrete::Three(centre)) = (
        V::as_concrete(e.corners),
        V::as_concrete(e.normal),
        V::as_concrete(e.centre),
    ) else {
        return; // 2-D walls are merged by `merge_segments`
    };
    let corners_of =
        |j: usize| &all_corners[e.corner_start[j] as usize..e.corner_start[j + 1] as usize];
    let to_v = |p: DVec3| V::from_slice(&p.to_array());
    let mut push = |corners: &[DVec3], n: DVec3, area: f64, centre: DVec3, reach: f64| {
        let corners: Vec<V> = corners.iter().map(|&c| to_v(c)).collect();
        cache.push_piece(&corners, to_v(n), area, to_v(centre), reach);
    };
    let bits = |p: DVec3| [p.x.to_bits(), p.y.to_bits(), p.z.to_bits()];
    // Corners of element j, counter-clockwise about its normal.
    let oriented = |j: usize| {
        let c = corners_of(j);
        let mut newell = DVec3::ZERO;
        for k in 0..c.len() {
            newell += c[k].cross(c[(k + 1) % c.len()]);
        }
        let mut v = c.to_vec();
        if newell.dot(normal[j]) < 0.0 {
            v.reverse();
        }
        v
    };
    let scale = e.max_reach.max(f64::MIN_POSITIVE);
    let mut planar = Vec::new();
    for j in 0..e.len() {
        let (c, n) = (corners_of(j), normal[j]);
        if c.len() >= 3 && c.iter().all(|&p| n.dot(p - c[0]).abs() <= 1e-12 * scale) {
            planar.push((bits(n), n.dot(c[0]), j));
        } else if c.len() >= 3 {
            // Not flat: a piece of its own, as the element-by-element sum sees it.
            let v = oriented(j);
            let mut edges = Vec::with_capacity(2 * v.len());
            for k in 0..v.len() {
                edges.extend([v[k], v[(k + 1) % v.len()]]);
            }
            push(&edges, n, e.area[j], centre[j], e.reach[j]);
        }
    }
    planar.sort_by(|a, b| a.0.cmp(&b.0).then(a.1.total_cmp(&b.1)).then(a.2.cmp(&b.2)));
    let mut g = 0;
    while g < planar.len() {
        let mut end = g + 1;
        while end < planar.len()
            && planar[end].0 == planar[g].0
            && (planar[end].1 - planar[g].1).abs() <= 1e-10 * scale
        {
            end += 1;
        }
        let mut members: Vec<usize> = planar[g..end].iter().map(|m| m.2).collect();
        members.sort_unstable();
        g = end;
        // Outline: every element's edges, shared ones dropped in pairs.
        let mut edges: Vec<(DVec3, DVec3)> = Vec::new();
        let mut area = 0.0;
        for &j in &members {
            let v = oriented(j);
            area += e.area[j];
            for k in 0..v.len() {
                edges.push((v[k], v[(k + 1) % v.len()]));
            }
        }
        let mut alive = vec![true; edges.len()];
        let mut open: HashMap<([u64; 3], [u64; 3]), Vec<usize>> = HashMap::new();
        for (i, &(p, q)) in edges.iter().enumerate() {
            if let Some(k) = open.get_mut(&(bits(q), bits(p))).and_then(|v| v.pop()) {
                alive[k] = false;
                alive[i] = false;
            } else {
                open.entry((bits(p), bits(q))).or_default().push(i);
            }
        }
        let outline: Vec<(DVec3, DVec3)> = edges
            .iter()
            .zip(&alive)
            .filter(|(_, &a)| a)
            .map(|(&e, _)| e)
            .collect();
        if outline.is_empty() {
            continue;
        }
        let corners = join_collinear(&outline);
        let (mut lo, mut hi) = (corners[0], corners[0]);
        for &c in &corners {
            lo = lo.min(c);
            hi = hi.max(c);
        }
        let centre = (lo + hi) * 0.5;
        let reach = corners
            .iter()
            .map(|&c| (c - centre).length())
            .fold(0.0, f64::max);
        let n = normal[members[0]];
        push(&corners, n, area, centre, reach);
    }
}

/// The outline edges `outline` (pairs of ends) with runs of collinear edges joined: an edge
/// continues the one ending where it starts when that corner has exactly one edge in and one
/// out and the two are parallel. Returns the joined edges as pairs of ends.
fn join_collinear(outline: &[(DVec3, DVec3)]) -> Vec<DVec3> {
    let bits = |p: DVec3| [p.x.to_bits(), p.y.to_bits(), p.z.to_bits()];
    // Join collinear runs: an edge continues the one ending where it starts when that
    // corner has exactly one edge in and one out and the two are parallel.
    let mut starting: HashMap<[u64; 3], Vec<usize>> = HashMap::new();
    let mut ending: HashMap<[u64; 3], usize> = HashMap::new();
    for (i, &(p, q)) in outline.iter().enumerate() {
        starting.entry(bits(p)).or_default().push(i);
        *ending.entry(bits(q)).or_default() += 1;
    }
    let parallel = |i: usize, k: usize| {
        let (u, v) = (outline[i].1 - outline[i].0, outline[k].1 - outline[k].0);
        u.dot(v) > 0.0 && u.cross(v).length() <= 1e-12 * u.length() * v.length()
    };
    let next = |i: usize| {
        let q = bits(outline[i].1);
        match (starting.get(&q).map(Vec::as_slice), ending.get(&q)) {
            (Some(&[k]), Some(&1)) if k != i && parallel(i, k) => Some(k),
            _ => None,
        }
    };
    let mut continues = vec![false; outline.len()];
    for i in 0..outline.len() {
        if let Some(k) = next(i) {
            continues[k] = true;
        }
    }
    let mut used = vec![false; outline.len()];
    let mut corners = Vec::new();
    let chain = |i: usize, used: &mut Vec<bool>, corners: &mut Vec<DVec3>| {
        let start = outline[i].0;
        let mut last = i;
        used[i] = true;
        while let Some(k) = next(last) {
            if used[k] {
                break;
            }
            used[k] = true;
            last = k;
        }
        corners.extend([start, outline[last].1]);
    };
    for i in 0..outline.len() {
        if !continues[i] && !used[i] {
            chain(i, &mut used, &mut corners);
        }
    }
    for i in 0..outline.len() {
        if !used[i] {
            chain(i, &mut used, &mut corners);
        }
    }
    corners
}
