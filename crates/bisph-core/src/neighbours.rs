//! Uniform cell grid for fixed-radius neighbour search.
//!
//! Cells have the side of the kernel support, so every neighbour of a point lies in the
//! `3^d` cells around it. The grid is rebuilt every step by a counting sort (no per-step
//! allocation once the buffers have grown; cell indices are computed in parallel); for the fluid the sort order is also used to
//! reorder the particles themselves, so a cell's particles are contiguous in memory.

use crate::dim::Vector;
use rayon::prelude::*;

/// Cell lists over a set of points: `items[cell_start[c]..cell_start[c + 1]]` are the points
/// in cell `c`.
#[derive(Clone, Debug, Default)]
pub struct CellGrid<V: Vector> {
    origin: V,
    inv_cell: f64,
    cell: f64,
    dims: [usize; 3],
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
            cell: cell_size,
            dims: [1; 3],
            cell_start: vec![0, 0],
            items: Vec::new(),
            cell_of: Vec::new(),
        }
    }

    /// Side of a cell.
    pub fn cell_size(&self) -> f64 {
        self.cell
    }

    /// Point indices sorted by cell (the permutation used to reorder particles).
    pub fn sorted_items(&self) -> &[u32] {
        &self.items
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
        self.origin = lo;
        let mut dims = [1usize; 3];
        for (k, d) in dims.iter_mut().enumerate().take(V::DIM) {
            *d = ((hi.get(k) - lo.get(k)) * self.inv_cell).floor() as usize + 1;
        }
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
            *ck = ((p.get(k) - self.origin.get(k)) * self.inv_cell).floor() as i64;
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

    /// Calls `visit(j, r_ij, |r_ij|)` with `r_ij = points[j] - x` for every point with
    /// `|r_ij| < radius`.
    #[inline(always)]
    pub fn for_each_neighbour(
        &self,
        x: V,
        points: &[V],
        radius: f64,
        mut visit: impl FnMut(usize, V, f64),
    ) {
        let r2max = radius * radius;
        self.for_each_candidate(x, |j| {
            let r = points[j] - x;
            let r2 = r.length_squared();
            if r2 < r2max {
                visit(j, r, r2.sqrt());
            }
        });
    }
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
