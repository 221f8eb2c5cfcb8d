//! Uniform cell grid for fixed-radius neighbour search.
//!
//! Cells have the side of the kernel support, so every neighbour of a point lies in the
//! `3^d` cells around it. The grid is rebuilt every step by a counting sort (no per-step
//! allocation once the buffers have grown; cell indices are computed in parallel); for the fluid the sort order is also used to
//! reorder the particles themselves, so a cell's particles are contiguous in memory.
//!
//! **Periodic axes.** Along an axis of a [`Periodicity`] the grid spans exactly one period
//! `[min, min + L)` with `floor(L / cell)` cells (so cells are at least `cell` wide), and the
//! cells around a point wrap around. Every visited point comes with the shift (a multiple of
//! `L` per periodic axis) that brings its image next to the query point; the neighbour
//! queries hand out the minimum-image displacement `r_ij = points[j] + shift - x`, so pair
//! terms never see a raw position difference across the period. Stored points must lie in
//! the primary period (see [`Periodicity::wrap`]); periods must hold at least three cells.

use crate::dim::Vector;
use rayon::prelude::*;

/// Periodic axes of a domain: along axis `k` with `length[k] > 0` the point `r` and
/// `r + length[k] e_k` are the same point; `length[k] = 0` marks a non-periodic axis.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Periodicity<V> {
    /// Lower end of the period along each axis.
    pub min: V,
    /// Period along each axis (0 = not periodic).
    pub length: V,
}

impl<V: Vector> Periodicity<V> {
    /// No periodic axis.
    pub fn none() -> Self {
        Periodicity {
            min: V::ZERO,
            length: V::ZERO,
        }
    }

    /// `true` when axis `k` is periodic.
    #[inline(always)]
    pub fn is_periodic(&self, k: usize) -> bool {
        self.length.get(k) > 0.0
    }

    /// `true` when some axis is periodic.
    pub fn any(&self) -> bool {
        (0..V::DIM).any(|k| self.is_periodic(k))
    }

    /// The image of `r` in the primary period `[min, min + L)` along every periodic axis.
    #[inline(always)]
    pub fn wrap(&self, r: V) -> V {
        let mut w = r;
        for k in 0..V::DIM {
            let l = self.length.get(k);
            if l > 0.0 {
                let lo = self.min.get(k);
                let mut x = lo + (r.get(k) - lo).rem_euclid(l);
                if x >= lo + l {
                    x = lo; // rem_euclid may round up to the period itself
                }
                w.set(k, x);
            }
        }
        w
    }

    /// The minimum-image form of a displacement `d` (each periodic component in `[-L/2, L/2]`).
    #[inline(always)]
    pub fn minimum_image(&self, d: V) -> V {
        let mut m = d;
        for k in 0..V::DIM {
            let l = self.length.get(k);
            if l > 0.0 {
                m.set(k, d.get(k) - l * (d.get(k) / l).round());
            }
        }
        m
    }
}

/// Cell lists over a set of points: `items[cell_start[c]..cell_start[c + 1]]` are the points
/// in cell `c`.
#[derive(Clone, Debug, Default)]
pub struct CellGrid<V: Vector> {
    origin: V,
    inv_cell: f64,
    /// Inverse cell side per axis (periodic axes have cells stretched to fit the period).
    inv_cells: [f64; 3],
    cell: f64,
    dims: [usize; 3],
    period: Periodicity<V>,
    periodic: bool,
    cell_start: Vec<u32>,
    items: Vec<u32>,
    cell_of: Vec<u32>,
}

impl<V: Vector> CellGrid<V> {
    /// An empty grid with cells of side `cell_size`.
    pub fn new(cell_size: f64) -> Self {
        CellGrid {
            origin: V::ZERO,
            inv_cell: 1.0 / cell_size,
            inv_cells: [1.0 / cell_size; 3],
            cell: cell_size,
            dims: [1; 3],
            period: Periodicity::none(),
            periodic: false,
            cell_start: vec![0, 0],
            items: Vec::new(),
            cell_of: Vec::new(),
        }
    }

    /// An empty grid with cells of at least `cell_size` that wraps around the periodic axes
    /// of `period`. Fails when a period holds fewer than three cells (then one point could
    /// meet two images of another).
    pub fn with_period(cell_size: f64, period: Periodicity<V>) -> Result<Self, String> {
        let mut grid = Self::new(cell_size);
        for k in 0..V::DIM {
            if period.is_periodic(k) {
                let l = period.length.get(k);
                let cells = (l / cell_size).floor();
                if cells < 3.0 {
                    return Err(format!(
                        "the period {l} along axis {k} must hold at least three kernel supports ({})",
                        3.0 * cell_size
                    ));
                }
                grid.inv_cells[k] = cells / l;
            }
        }
        grid.periodic = period.any();
        grid.period = period;
        Ok(grid)
    }

    /// The grid's periodic axes.
    pub fn periodicity(&self) -> &Periodicity<V> {
        &self.period
    }

    /// Side of a cell.
    pub fn cell_size(&self) -> f64 {
        self.cell
    }

    /// Point indices sorted by cell, row by row (cells in index order).
    pub fn sorted_items(&self) -> &[u32] {
        &self.items
    }

    /// Writes into `order` the point indices with their cells along a Morton (Z-order)
    /// curve, each cell's points in increasing index: the permutation used to reorder
    /// particles, so that the cells around any cell lie close in memory along every axis
    /// (rows only are close in [`CellGrid::sorted_items`]). `cells` is a reusable buffer.
    pub fn morton_order(&self, order: &mut Vec<u32>, cells: &mut Vec<(u64, u32)>) {
        let [nx, ny, nz] = self.dims;
        cells.clear();
        for cz in 0..nz {
            for cy in 0..ny {
                for cx in 0..nx {
                    let c = cx + nx * (cy + ny * cz);
                    if self.cell_start[c] != self.cell_start[c + 1] {
                        cells.push((morton_key([cx, cy, cz], V::DIM), c as u32));
                    }
                }
            }
        }
        cells.sort_unstable();
        order.clear();
        for &(_, c) in cells.iter() {
            let c = c as usize;
            order.extend_from_slice(
                &self.items[self.cell_start[c] as usize..self.cell_start[c + 1] as usize],
            );
        }
    }

    /// Rebuilds the grid for `points` (all of which must be finite).
    pub fn rebuild(&mut self, points: &[V]) {
        let n = points.len();
        if n == 0 {
            self.dims = [1; 3];
            self.cell_start.clear();
            self.cell_start.extend([0, 0]);
            self.items.clear();
            return;
        }
        let (mut lo, mut hi) = (points[0], points[0]);
        for &p in points {
            lo = lo.min_by_component(p);
            hi = hi.max_by_component(p);
        }
        let mut dims = [1usize; 3];
        for (k, d) in dims.iter_mut().enumerate().take(V::DIM) {
            if self.period.is_periodic(k) {
                lo.set(k, self.period.min.get(k));
                *d = (self.period.length.get(k) * self.inv_cells[k]).round() as usize;
            } else {
                *d = ((hi.get(k) - lo.get(k)) * self.inv_cell).floor() as usize + 1;
            }
        }
        self.origin = lo;
        self.dims = dims;
        let cells = dims[0] * dims[1] * dims[2];
        let mut cell_of = std::mem::take(&mut self.cell_of);
        cell_of.resize(n, 0);
        let this = &*self;
        cell_of
            .par_iter_mut()
            .zip(points.par_iter())
            .with_min_len(4096)
            .for_each(|(c, &p)| *c = this.cell_index(p) as u32);
        self.cell_of = cell_of;
        self.cell_start.clear();
        self.cell_start.resize(cells + 1, 0);
        for &c in &self.cell_of {
            self.cell_start[c as usize + 1] += 1;
        }
        for c in 0..cells {
            self.cell_start[c + 1] += self.cell_start[c];
        }
        self.items.clear();
        self.items.resize(n, 0);
        // Stable counting sort: fill each cell in increasing point order.
        for (i, &c) in self.cell_of.iter().enumerate() {
            let slot = &mut self.cell_start[c as usize];
            self.items[*slot as usize] = i as u32;
            *slot += 1;
        }
        // Shift the start offsets back (each one was advanced to the end of its cell).
        for c in (1..=cells).rev() {
            self.cell_start[c] = self.cell_start[c - 1];
        }
        self.cell_start[0] = 0;
    }

    /// Estimated heap memory of the grid in bytes.
    pub fn memory_bytes(&self) -> usize {
        4 * (self.cell_start.capacity() + self.items.capacity() + self.cell_of.capacity())
    }

    #[inline(always)]
    fn coords(&self, p: V) -> [i64; 3] {
        let mut c = [0i64; 3];
        for (k, ck) in c.iter_mut().enumerate().take(V::DIM) {
            *ck = floor_to_i64((p.get(k) - self.origin.get(k)) * self.inv_cells[k]);
        }
        c
    }

    #[inline(always)]
    fn cell_index(&self, p: V) -> usize {
        let c = self.coords(p);
        let clamp = |v: i64, d: usize| v.clamp(0, d as i64 - 1) as usize;
        clamp(c[0], self.dims[0])
            + self.dims[0] * (clamp(c[1], self.dims[1]) + self.dims[1] * clamp(c[2], self.dims[2]))
    }

    /// Calls `visit(j)` for every point `j` in the cells around `x` (a superset of the points
    /// within one cell size of `x`). The caller filters by distance.
    #[inline(always)]
    pub fn for_each_candidate(&self, x: V, visit: impl FnMut(usize)) {
        self.for_each_in_span(x, 1, visit);
    }

    /// Calls `visit(j)` for every point `j` in the cells that can hold points within `radius`
    /// of `x` (a superset of them, for radii larger than one cell as well).
    pub fn for_each_candidate_within(&self, x: V, radius: f64, visit: impl FnMut(usize)) {
        let span = ((radius * self.inv_cell).ceil() as i64).max(1);
        self.for_each_in_span(x, span, visit);
    }

    /// Visits the points in the cells at most `span` cells away from the cell of `x` along each
    /// axis (the grid is clipped; nothing is visited when `x` lies more than `span` cells out).
    #[inline(always)]
    fn for_each_in_span(&self, x: V, span: i64, mut visit: impl FnMut(usize)) {
        let c = self.coords(x);
        let mut lo = [0usize; 3];
        let mut hi = [0usize; 3];
        for k in 0..3 {
            let d = self.dims[k] as i64;
            let s = if k < V::DIM { span } else { 0 };
            let a = (c[k] - s).max(0);
            let b = (c[k] + s).min(d - 1);
            if a > b {
                return;
            }
            lo[k] = a as usize;
            hi[k] = b as usize;
        }
        for cz in lo[2]..=hi[2] {
            for cy in lo[1]..=hi[1] {
                let row = self.dims[0] * (cy + self.dims[1] * cz);
                let start = self.cell_start[row + lo[0]] as usize;
                let end = self.cell_start[row + hi[0] + 1] as usize;
                for &j in &self.items[start..end] {
                    visit(j as usize);
                }
            }
        }
    }

    /// Calls `visit(j, shift)` for every point `j` in the cells around `x`, where
    /// `points[j] + shift` is the image of point `j` next to `x` (`shift` is zero without
    /// periodic axes). The caller filters by distance.
    #[inline(always)]
    pub fn for_each_candidate_shifted(&self, x: V, visit: impl FnMut(usize, V)) {
        self.for_each_in_span_shifted(x, 1, visit);
    }

    /// [`CellGrid::for_each_candidate_within`] with the image shift of each point, as in
    /// [`CellGrid::for_each_candidate_shifted`].
    pub fn for_each_candidate_within_shifted(
        &self,
        x: V,
        radius: f64,
        visit: impl FnMut(usize, V),
    ) {
        let span = ((radius * self.inv_cell).ceil() as i64).max(1);
        self.for_each_in_span_shifted(x, span, visit);
    }

    /// Visits the cells at most `span` cells from the cell of `x`, wrapping around periodic
    /// axes (each cell once, at the image nearest to `x`), with the shift of each cell's image.
    #[inline(always)]
    fn for_each_in_span_shifted(&self, x: V, span: i64, mut visit: impl FnMut(usize, V)) {
        self.for_each_run(x, span, |run, shift| {
            for &j in run {
                visit(j as usize, shift);
            }
        });
    }

    /// Calls `visit(run, shift)` for each run of consecutive cells at most `span` cells from
    /// the cell of `x` (a slice of point indices), wrapping around periodic axes (each cell
    /// once, at the image nearest to `x`; `shift` moves its points there, zero without
    /// periodic axes). One call site of `visit`, so callers' closures inline into it.
    #[inline(always)]
    fn for_each_run(&self, x: V, span: i64, mut visit: impl FnMut(&[u32], V)) {
        let c = self.coords(x);
        // Per axis: up to three runs of cell indices (lo, hi, shift along the axis).
        let mut runs = [[(0usize, 0usize, 0.0f64); 3]; 3];
        let mut counts = [0usize; 3];
        for k in 0..3 {
            let d = self.dims[k] as i64;
            let s = if k < V::DIM { span } else { 0 };
            if self.periodic && k < V::DIM && self.period.is_periodic(k) {
                let l = self.period.length.get(k);
                let (mut a, mut b) = (c[k] - s, c[k] + s);
                if b - a + 1 > d {
                    a = c[k] - (d - 1) / 2;
                    b = a + d - 1;
                }
                let mut m = a;
                while m <= b {
                    let wrap = m.div_euclid(d);
                    let end = b.min((wrap + 1) * d - 1);
                    runs[k][counts[k]] = (
                        (m - wrap * d) as usize,
                        (end - wrap * d) as usize,
                        wrap as f64 * l,
                    );
                    counts[k] += 1;
                    m = end + 1;
                }
            } else {
                let a = (c[k] - s).max(0);
                let b = (c[k] + s).min(d - 1);
                if a > b {
                    return;
                }
                runs[k][0] = (a as usize, b as usize, 0.0);
                counts[k] = 1;
            }
        }
        let mut shift = V::ZERO;
        for &(z0, z1, sz) in &runs[2][..counts[2]] {
            if V::DIM == 3 {
                shift.set(2, sz);
            }
            for cz in z0..=z1 {
                for &(y0, y1, sy) in &runs[1][..counts[1]] {
                    shift.set(1, sy);
                    for cy in y0..=y1 {
                        let row = self.dims[0] * (cy + self.dims[1] * cz);
                        for &(x0, x1, sx) in &runs[0][..counts[0]] {
                            shift.set(0, sx);
                            let start = self.cell_start[row + x0] as usize;
                            let end = self.cell_start[row + x1 + 1] as usize;
                            visit(&self.items[start..end], shift);
                        }
                    }
                }
            }
        }
    }

    /// Calls `visit(j, r_ij, |r_ij|)` with `r_ij = points[j] - x` (the minimum image across
    /// periodic axes) for every point with `|r_ij| < radius`.
    #[inline(always)]
    pub fn for_each_neighbour(
        &self,
        x: V,
        points: &[V],
        radius: f64,
        mut visit: impl FnMut(usize, V, f64),
    ) {
        let r2max = radius * radius;
        self.for_each_run(x, 1, |run, shift| {
            // The image of `x` seen from the run's points (exactly `x` without periodicity).
            let origin = x - shift;
            for &j in run {
                let j = j as usize;
                let r = points[j] - origin;
                let r2 = r.length_squared();
                if r2 < r2max {
                    visit(j, r, r2.sqrt());
                }
            }
        });
    }
}

/// Morton key of cell coordinates: their bits interleaved (`dim` = 2 or 3 axes, at most
/// 32 or 21 bits each).
fn morton_key(c: [usize; 3], dim: usize) -> u64 {
    let bits = if dim == 2 { 32 } else { 21 };
    let mut key = 0u64;
    for b in 0..bits {
        for (k, &ck) in c.iter().enumerate().take(dim) {
            key |= (((ck as u64) >> b) & 1) << (b * dim + k);
        }
    }
    key
}

/// `v.floor() as i64` (saturating, NaN to 0) without a call into libm's software `floor`,
/// which the baseline x86-64 target uses (no SSE4.1 `roundsd`): truncate, then step down
/// for negative non-integers.
#[inline(always)]
fn floor_to_i64(v: f64) -> i64 {
    let t = v as i64;
    t.saturating_sub(i64::from(t as f64 > v))
}

#[cfg(test)]
mod tests {
    use super::*;
    use glam::{DVec2, DVec3};

    fn pseudo_random(n: usize, seed: u64) -> impl Iterator<Item = f64> {
        let mut s = seed;
        (0..n).map(move |_| {
            s = s
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            (s >> 11) as f64 / (1u64 << 53) as f64
        })
    }

    #[test]
    fn floor_to_i64_matches_floor() {
        let small = [
            0.0, -0.0, 0.5, -0.5, 1.0, -1.0, 2.999, -2.999, 1e-300, -1e-300,
        ];
        let large = [1e30, -1e30, 4503599627370495.5, -4503599627370495.5];
        let special = [f64::NAN, f64::INFINITY, f64::NEG_INFINITY];
        let values = small.into_iter().chain(large).chain(special);
        let random = pseudo_random(1000, 3).map(|r| (r - 0.5) * 200.0);
        for v in values.chain(random) {
            assert_eq!(floor_to_i64(v), v.floor() as i64, "{v}");
        }
    }

    fn check<V: Vector>(points: Vec<V>, radius: f64) {
        let mut grid = CellGrid::new(radius);
        grid.rebuild(&points);
        let mut total = 0;
        for (i, &x) in points.iter().enumerate() {
            let mut found = Vec::new();
            grid.for_each_neighbour(x, &points, radius, |j, _, _| found.push(j));
            found.sort();
            let brute: Vec<usize> = (0..points.len())
                .filter(|&j| (points[j] - x).length_squared() < radius * radius)
                .collect();
            assert_eq!(found, brute, "point {i}");
            total += found.len();
        }
        assert!(total > points.len(), "test must see real neighbours");
    }

    #[test]
    fn equals_brute_force_in_2d_and_3d() {
        let r: Vec<f64> = pseudo_random(3000, 7).collect();
        let p2: Vec<DVec2> = r
            .chunks(2)
            .map(|c| DVec2::new(c[0], 2.0 * c[1] - 0.5))
            .collect();
        check(p2, 0.07);
        let p3: Vec<DVec3> = r
            .chunks(3)
            .map(|c| DVec3::new(c[0], c[1], 0.3 * c[2]))
            .collect();
        check(p3, 0.15);
    }

    fn check_periodic<V: Vector>(points: Vec<V>, radius: f64, period: Periodicity<V>) {
        let points: Vec<V> = points.into_iter().map(|p| period.wrap(p)).collect();
        let mut grid = CellGrid::with_period(radius, period).unwrap();
        grid.rebuild(&points);
        let mut total = 0;
        let mut across = 0;
        for (i, &x) in points.iter().enumerate() {
            let mut found = Vec::new();
            grid.for_each_neighbour(x, &points, radius, |j, r, d| {
                let m = period.minimum_image(points[j] - x);
                assert!(
                    (r - m).length() < 1e-12,
                    "displacement is the minimum image"
                );
                assert!((r.length() - d).abs() < 1e-12);
                if (points[j] - x - r).length() > 1e-12 {
                    across += 1;
                }
                found.push(j);
            });
            found.sort();
            let brute: Vec<usize> = (0..points.len())
                .filter(|&j| period.minimum_image(points[j] - x).length_squared() < radius * radius)
                .collect();
            assert_eq!(found, brute, "point {i}");
            total += found.len();
        }
        assert!(total > points.len(), "test must see real neighbours");
        assert!(across > 0, "test must see pairs across the period");
    }

    #[test]
    fn periodic_equals_brute_force_minimum_image_in_2d_and_3d() {
        let r: Vec<f64> = pseudo_random(3000, 11).collect();
        // 2-D: periodic in x only, in y only, in both.
        let p2: Vec<DVec2> = r
            .chunks(2)
            .map(|c| DVec2::new(c[0] - 0.1, 0.6 * c[1]))
            .collect();
        for length in [
            DVec2::new(1.0, 0.0),
            DVec2::new(0.0, 0.6),
            DVec2::new(1.0, 0.6),
        ] {
            let period = Periodicity {
                min: DVec2::new(-0.1, 0.0),
                length,
            };
            check_periodic(p2.clone(), 0.07, period);
            // a period of exactly three cells and one just above
            check_periodic(p2.clone(), 0.199, period);
        }
        let p3: Vec<DVec3> = r
            .chunks(3)
            .map(|c| DVec3::new(c[0], c[1], 0.5 * c[2]))
            .collect();
        for length in [DVec3::new(1.0, 0.0, 0.0), DVec3::new(1.0, 0.0, 0.5)] {
            let period = Periodicity {
                min: DVec3::ZERO,
                length,
            };
            check_periodic(p3.clone(), 0.15, period);
        }
    }

    #[test]
    fn a_period_shorter_than_three_cells_is_refused() {
        let period = Periodicity {
            min: DVec2::ZERO,
            length: DVec2::new(0.5, 0.0),
        };
        assert!(CellGrid::with_period(0.2, period).is_err());
        assert!(CellGrid::with_period(0.16, period).is_ok());
    }

    #[test]
    fn wrap_lands_in_the_primary_period() {
        let period = Periodicity {
            min: DVec2::new(-1.0, 0.0),
            length: DVec2::new(2.0, 0.0),
        };
        let w = period.wrap(DVec2::new(1.5, 7.0));
        assert!((w.x + 0.5).abs() < 1e-15 && w.y == 7.0);
        assert_eq!(period.wrap(DVec2::new(-1.0 - 1e-18, 0.0)).x, -1.0);
    }

    #[test]
    fn morton_order_is_a_permutation_along_the_z_curve() {
        assert_eq!(morton_key([1, 0, 0], 2), 1);
        assert_eq!(morton_key([0, 1, 0], 2), 2);
        assert_eq!(morton_key([3, 3, 0], 2), 15);
        assert_eq!(morton_key([0, 0, 1], 3), 4);
        assert_eq!(morton_key([1, 1, 1], 3), 7);
        assert_eq!(morton_key([2, 0, 0], 3), 8);
        // Points at the centres of a 4 x 4 grid of unit cells, listed row by row.
        let pts: Vec<DVec2> = (0..16)
            .map(|k| DVec2::new((k % 4) as f64 + 0.5, (k / 4) as f64 + 0.5))
            .collect();
        let mut grid = CellGrid::new(1.0);
        grid.rebuild(&pts);
        let (mut order, mut cells) = (Vec::new(), Vec::new());
        grid.morton_order(&mut order, &mut cells);
        assert_eq!(
            order,
            [0, 1, 4, 5, 2, 3, 6, 7, 8, 9, 12, 13, 10, 11, 14, 15]
        );
    }

    #[test]
    fn sorted_items_group_points_by_cell_and_stay_stable() {
        let pts = vec![
            DVec2::new(0.0, 0.0),
            DVec2::new(5.0, 0.0),
            DVec2::new(0.1, 0.1),
        ];
        let mut grid = CellGrid::new(1.0);
        grid.rebuild(&pts);
        assert_eq!(grid.sorted_items(), &[0, 2, 1]);
    }
}
