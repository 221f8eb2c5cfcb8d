//! The uniform cell grid: cells, storage order, periodic axes, neighbour runs (see the
//! [module documentation](super)), and the wall pair list.

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
///
/// The cells are those of one fixed lattice, whatever the points: along an open axis, cell
/// `m` holds the coordinates `x` with `floor(x / cell) = m`; along a periodic axis, the
/// period is cut into whole cells from its lower end. The grid covers the lattice cells from
/// `base` on that hold points, so a point lies in the same lattice cell in any set of points
/// it is part of.
#[derive(Clone, Debug, Default)]
pub struct CellGrid<V: Vector> {
    /// Where the lattice starts along each axis: zero along open axes, the lower end of the
    /// period along periodic ones.
    anchor: V,
    /// Lattice index of the grid's first cell along each axis.
    pub(super) base: [i64; 3],
    inv_cell: f64,
    /// Inverse cell side per axis (periodic axes have cells stretched to fit the period).
    inv_cells: [f64; 3],
    cell: f64,
    pub(super) dims: [usize; 3],
    period: Periodicity<V>,
    periodic: bool,
    /// Start slot of each cell, indexed by the cell's rank in the storage order (plus one
    /// end entry).
    cell_start: Vec<u32>,
    /// Point index of each slot.
    pub(super) items: Vec<u32>,
    cell_of: Vec<u32>,
    /// Rank of the first cell of each row (`cy + ny cz`) in the storage order.
    row_rank: Vec<u32>,
    /// The grid dimensions `row_rank` was made for.
    row_dims: [usize; 3],
    /// `true` when `items[k] = k` (the points were reordered into the storage order).
    contiguous: bool,
    /// Per cell (`cx + nx (cy + ny cz)`), `true` when it and its neighbour cells are empty
    /// ([`CellGrid::no_candidates`]); empty on periodic grids.
    empty_around: Vec<bool>,
}

impl<V: Vector> CellGrid<V> {
    /// An empty grid with cells of side `cell_size`.
    pub fn new(cell_size: f64) -> Self {
        CellGrid {
            anchor: V::ZERO,
            base: [0; 3],
            inv_cell: 1.0 / cell_size,
            inv_cells: [1.0 / cell_size; 3],
            cell: cell_size,
            dims: [1; 3],
            period: Periodicity::none(),
            periodic: false,
            cell_start: vec![0, 0],
            items: Vec::new(),
            cell_of: Vec::new(),
            row_rank: vec![0],
            row_dims: [1; 3],
            contiguous: false,
            empty_around: Vec::new(),
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
                grid.anchor.set(k, period.min.get(k));
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

    /// Point indices in the storage order (by row of cells, rows along a Morton curve over
    /// `(y, z)`, cells along `x` within a row, each cell's points in increasing key, see
    /// [`CellGrid::rebuild_keyed`]): the permutation that reorders particles so that runs of
    /// cells are contiguous in memory.
    pub fn sorted_items(&self) -> &[u32] {
        &self.items
    }

    /// Declares that the points were permuted by [`CellGrid::sorted_items`] (new point `k` is
    /// old point `sorted_items()[k]`): the cells keep their slots and each slot now holds the
    /// point of the same index, so no rebuild is needed and queries read contiguous slices.
    pub fn mark_reordered(&mut self) {
        for (k, item) in self.items.iter_mut().enumerate() {
            *item = k as u32;
        }
        self.contiguous = true;
    }

    /// Ranks of the rows in the storage order, for the current dimensions.
    fn rank_rows(&mut self) {
        let [nx, ny, nz] = self.dims;
        if self.row_dims == self.dims && self.row_rank.len() == ny * nz {
            return;
        }
        let mut rows: Vec<(u64, u32)> = (0..ny * nz)
            .map(|row| (morton_key([row % ny, row / ny, 0], 2), row as u32))
            .collect();
        rows.sort_unstable();
        self.row_rank.clear();
        self.row_rank.resize(ny * nz, 0);
        for (k, &(_, row)) in rows.iter().enumerate() {
            self.row_rank[row as usize] = (k * nx) as u32;
        }
        self.row_dims = self.dims;
    }

    /// Rebuilds the grid for `points` (all of which must be finite), each cell's points in
    /// increasing index.
    pub fn rebuild(&mut self, points: &[V]) {
        self.rebuild_cells(points);
    }

    /// Rebuilds the grid for `points` (all of which must be finite), each cell's points in
    /// increasing `keys` (one per point, all different): with a global identity as the key,
    /// every query meets its neighbours in an order that depends neither on where the points
    /// are stored nor on which other points the grid holds, only on the lattice cells and
    /// the keys.
    pub fn rebuild_keyed(&mut self, points: &[V], keys: &[u32]) {
        assert_eq!(points.len(), keys.len(), "one key per point");
        self.rebuild_cells(points);
        let (starts, items) = (&self.cell_start, &mut self.items);
        for cell in starts.windows(2) {
            let slots = &mut items[cell[0] as usize..cell[1] as usize];
            if slots.len() > 1 {
                slots.sort_unstable_by_key(|&i| keys[i as usize]);
            }
        }
    }

    fn rebuild_cells(&mut self, points: &[V]) {
        let n = points.len();
        self.contiguous = false;
        if n == 0 {
            self.dims = [1; 3];
            self.cell_start.clear();
            self.cell_start.extend([0, 0]);
            self.items.clear();
            self.empty_around.clear();
            return;
        }
        let (mut lo, mut hi) = (points[0], points[0]);
        for &p in points {
            lo = lo.min_by_component(p);
            hi = hi.max_by_component(p);
        }
        let mut dims = [1usize; 3];
        let mut base = [0i64; 3];
        for (k, d) in dims.iter_mut().enumerate().take(V::DIM) {
            if self.period.is_periodic(k) {
                *d = (self.period.length.get(k) * self.inv_cells[k]).round() as usize;
            } else {
                base[k] = floor_to_i64(lo.get(k) * self.inv_cell);
                *d = (floor_to_i64(hi.get(k) * self.inv_cell) - base[k]) as usize + 1;
            }
        }
        self.base = base;
        self.dims = dims;
        self.rank_rows();
        let cells = dims[0] * dims[1] * dims[2];
        let mut cell_of = std::mem::take(&mut self.cell_of);
        cell_of.resize(n, 0);
        let this = &*self;
        cell_of
            .par_iter_mut()
            .zip(points.par_iter())
            .with_min_len(4096)
            .for_each(|(c, &p)| *c = this.cell_rank(p) as u32);
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
        // Stable counting sort by rank: fill each cell in increasing point order.
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
        self.map_empty_neighbourhoods();
    }

    /// Estimated heap memory of the grid in bytes.
    pub fn memory_bytes(&self) -> usize {
        4 * (self.cell_start.capacity()
            + self.items.capacity()
            + self.cell_of.capacity()
            + self.row_rank.capacity())
            + self.empty_around.capacity()
    }

    #[inline(always)]
    fn coords(&self, p: V) -> [i64; 3] {
        let mut c = [0i64; 3];
        for (k, ck) in c.iter_mut().enumerate().take(V::DIM) {
            *ck = floor_to_i64((p.get(k) - self.anchor.get(k)) * self.inv_cells[k]) - self.base[k];
        }
        c
    }

    /// Rank in the storage order of the cell of `p` (clamped to the grid).
    #[inline(always)]
    fn cell_rank(&self, p: V) -> usize {
        let c = self.coords(p);
        let clamp = |v: i64, d: usize| v.clamp(0, d as i64 - 1) as usize;
        let row = clamp(c[1], self.dims[1]) + self.dims[1] * clamp(c[2], self.dims[2]);
        self.row_rank[row] as usize + clamp(c[0], self.dims[0])
    }

    /// The points in the order in which the searches meet them: rows of cells in increasing
    /// `z`, then `y`, the cells of a row in increasing `x`, a cell's points in their storage
    /// order. Without periodic axes, a search around any place meets the points near it in
    /// this order; with them, `None` (a search meets the images across the end first).
    pub fn points_in_search_order(&self) -> Option<Vec<u32>> {
        if self.periodic {
            return None;
        }
        let [nx, ny, nz] = self.dims;
        let mut order = Vec::with_capacity(self.items.len());
        for row in 0..ny * nz {
            let (start, end) = self.run_slots(row, 0, nx - 1);
            order.extend_from_slice(&self.items[start..end]);
        }
        Some(order)
    }

    /// Slots `start..end` of the cells `x0..=x1` of row `row` (`cy + ny cz`).
    #[inline(always)]
    fn run_slots(&self, row: usize, x0: usize, x1: usize) -> (usize, usize) {
        let first = self.row_rank[row] as usize;
        (
            self.cell_start[first + x0] as usize,
            self.cell_start[first + x1 + 1] as usize,
        )
    }

    /// Slots `(start, end)` of the cells of the block anchored at cell `a` (grid coordinates):
    /// the cell at offset `d` from it (bit `k` of `d` one step along axis `k`) at index `d`,
    /// wrapped around periodic axes; empty past the grid along open axes and for `d >= 2^dim`.
    #[inline]
    pub(crate) fn block_cells(&self, a: [u32; 3]) -> [(usize, usize); 8] {
        let mut cells = [(0, 0); 8];
        for (d, cell) in cells.iter_mut().enumerate().take(1 << V::DIM) {
            let mut c = [0usize; 3];
            let mut inside = true;
            for k in 0..V::DIM {
                let m = a[k] as usize + (d >> k & 1);
                c[k] = if m < self.dims[k] {
                    m
                } else if self.period.is_periodic(k) {
                    m - self.dims[k]
                } else {
                    inside = false;
                    break;
                };
            }
            if inside {
                let rank = self.row_rank[c[1] + self.dims[1] * c[2]] as usize + c[0];
                *cell = (
                    self.cell_start[rank] as usize,
                    self.cell_start[rank + 1] as usize,
                );
            }
        }
        cells
    }

    /// Calls `visit(j)` for every point `j` in the cells around `x` (a superset of the points
    /// within one cell size of `x`). The caller filters by distance.
    #[inline(always)]
    pub fn for_each_candidate(&self, x: V, visit: impl FnMut(usize)) {
        self.for_each_in_span(x, 1, visit);
    }

    /// Calls `visit(j)` for every point `j` in the cells that can hold points within `radius`
    /// of `x` (a superset of them, for radii larger than one cell as well).
    #[inline(always)]
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
                let (start, end) = self.run_slots(cy + self.dims[1] * cz, lo[0], hi[0]);
                for &j in &self.items[start..end] {
                    visit(j as usize);
                }
            }
        }
    }

    /// `true` when the cells around `x` (those [`CellGrid::for_each_candidate`] visits) hold
    /// no point: a cheap test that spares a walk through empty cells (one look-up in the map
    /// the last rebuild made, for `x` inside the grid). Without periodic axes only (it answers
    /// `false` on a periodic grid, so callers walk as before).
    #[inline(always)]
    pub fn no_candidates(&self, x: V) -> bool {
        if self.periodic {
            return false;
        }
        let c = self.coords(x);
        let [nx, ny, _] = self.dims;
        let inside = (0..3).all(|k| c[k] >= 0 && c[k] < self.dims[k] as i64);
        // The map is empty (before the first rebuild) or covers every cell.
        if inside && !self.empty_around.is_empty() {
            return self.empty_around[c[0] as usize + nx * (c[1] as usize + ny * c[2] as usize)];
        }
        self.cells_empty_around(c)
    }

    /// `true` when the cells at most one away from cell `c` (clipped to the grid) are empty.
    fn cells_empty_around(&self, c: [i64; 3]) -> bool {
        let mut lo = [0usize; 3];
        let mut hi = [0usize; 3];
        for k in 0..3 {
            let d = self.dims[k] as i64;
            let s = i64::from(k < V::DIM);
            let a = (c[k] - s).max(0);
            let b = (c[k] + s).min(d - 1);
            if a > b {
                return true;
            }
            lo[k] = a as usize;
            hi[k] = b as usize;
        }
        for cz in lo[2]..=hi[2] {
            for cy in lo[1]..=hi[1] {
                let (start, end) = self.run_slots(cy + self.dims[1] * cz, lo[0], hi[0]);
                if start != end {
                    return false;
                }
            }
        }
        true
    }

    /// Maps, for [`CellGrid::no_candidates`], every cell to whether the cells around it are
    /// empty (grids without periodic axes).
    fn map_empty_neighbourhoods(&mut self) {
        let mut empty = std::mem::take(&mut self.empty_around);
        empty.clear();
        if !self.periodic {
            let [nx, ny, nz] = self.dims;
            empty.reserve(nx * ny * nz);
            for cz in 0..nz as i64 {
                for cy in 0..ny as i64 {
                    for cx in 0..nx as i64 {
                        empty.push(self.cells_empty_around([cx, cy, cz]));
                    }
                }
            }
        }
        self.empty_around = empty;
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
    #[inline(always)]
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
        self.for_each_run(x, span, |start, end, shift| {
            for &j in &self.items[start..end] {
                visit(j as usize, shift);
            }
        });
    }

    /// Calls `visit(start, end, shift)` for each run of consecutive cells at most `span` cells
    /// from the cell of `x` (the slots `start..end` of [`CellGrid::sorted_items`]), wrapping around periodic axes (each cell
    /// once, at the image nearest to `x`; `shift` moves its points there, zero without
    /// periodic axes). One call site of `visit`, so callers' closures inline into it.
    #[inline(always)]
    fn for_each_run(&self, x: V, span: i64, mut visit: impl FnMut(usize, usize, V)) {
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
                        let row = cy + self.dims[1] * cz;
                        for &(x0, x1, sx) in &runs[0][..counts[0]] {
                            shift.set(0, sx);
                            let (start, end) = self.run_slots(row, x0, x1);
                            visit(start, end, shift);
                        }
                    }
                }
            }
        }
    }

    /// [`CellGrid::for_each_neighbour`] over sparse points (wall elements, vertex particles),
    /// which most queries have none of around them: a query whose cells are empty
    /// ([`CellGrid::no_candidates`]) returns before the walk. The same pairs in the same order.
    #[inline(always)]
    pub fn for_each_sparse_neighbour(
        &self,
        x: V,
        points: &[V],
        radius: f64,
        visit: impl FnMut(usize, V, f64),
    ) {
        if !self.no_candidates(x) {
            self.for_each_neighbour(x, points, radius, visit);
        }
    }

    /// Calls `visit(j, r_ij, |r_ij|)` with `r_ij = points[j] - x` (the minimum image across
    /// periodic axes) for every point with `|r_ij| < radius` (at most one cell), in storage
    /// order
    /// ([`CellGrid::for_each_neighbour_run`], one at a time).
    #[inline(always)]
    pub fn for_each_neighbour(
        &self,
        x: V,
        points: &[V],
        radius: f64,
        visit: impl FnMut(usize, V, f64),
    ) {
        let mut kept = KeptBlock::new();
        self.for_each_neighbour_run(x, points, radius, &mut kept, one_at_a_time(visit));
    }

    /// Calls `visit(index, r_ij, r2)` with runs of the points within `radius` (at most one
    /// cell) of `x`, in storage order: `index[k]` is a point `j`, `r_ij[k] = points[j] - x` (the minimum image
    /// across periodic axes) and `r2[k] = |r_ij[k]|^2`.
    ///
    /// The candidates of each run of cells are filtered in blocks without a branch per
    /// candidate: every candidate's index, offset and `r^2` are written to small buffers whose
    /// fill count grows by one only for points inside the radius, then `visit` gets the kept
    /// ones. With reordered points ([`CellGrid::mark_reordered`]) the candidates are read as a
    /// contiguous slice of `points`. `kept` holds the buffers; one per task, reused from
    /// query to query, saves clearing them for each.
    #[inline(always)]
    pub fn for_each_neighbour_run(
        &self,
        x: V,
        points: &[V],
        radius: f64,
        kept: &mut KeptBlock<V>,
        mut visit: impl FnMut(&[u32], &[V], &[f64]),
    ) {
        let r2max = radius * radius;
        self.for_each_run(x, 1, |start, end, shift| {
            // The image of `x` seen from the run's points (exactly `x` without periodicity).
            let origin = x - shift;
            let mut s = start;
            while s < end {
                let e = end.min(s + KEPT_BLOCK);
                let n = if self.contiguous {
                    kept.filter(
                        (s..e)
                            .zip(&points[s..e])
                            .map(|(j, &p)| (j as u32, p - origin)),
                        r2max,
                    )
                } else {
                    kept.filter(
                        self.items[s..e]
                            .iter()
                            .map(|&j| (j, points[j as usize] - origin)),
                        r2max,
                    )
                };
                visit(&kept.index[..n], &kept.offset[..n], &kept.r2[..n]);
                s = e;
            }
        });
    }
}

/// The run visitor of the `for_each_neighbour_run` searches that calls `visit(j, r_ij,
/// |r_ij|)` for each neighbour of the run in turn.
#[inline(always)]
pub(super) fn one_at_a_time<V: Copy>(
    mut visit: impl FnMut(usize, V, f64),
) -> impl FnMut(&[u32], &[V], &[f64]) {
    move |index, offset, r2| {
        for ((&j, &r_ij), &r2) in index.iter().zip(offset).zip(r2) {
            visit(j as usize, r_ij, r2.sqrt());
        }
    }
}

/// Candidates filtered per block: the longest run of partners a filtered sweep visits at once.
pub const KEPT_BLOCK: usize = 32;

/// The buffers of the branch-free block filter of the neighbour searches (896 bytes in
/// 2-D): a sweep makes one per task and passes it to every query, since clearing them per
/// query cost 4.6% of a step (perf, 20k dam break, 2 threads).
pub struct KeptBlock<V> {
    pub(super) index: [u32; KEPT_BLOCK],
    pub(super) offset: [V; KEPT_BLOCK],
    pub(super) r2: [f64; KEPT_BLOCK],
}

impl<V: Vector> KeptBlock<V> {
    /// Cleared buffers.
    pub fn new() -> Self {
        KeptBlock {
            index: [0; KEPT_BLOCK],
            offset: [V::ZERO; KEPT_BLOCK],
            r2: [0.0; KEPT_BLOCK],
        }
    }

    /// Keeps, in order, the candidates `(j, r_ij)` (at most [`KEPT_BLOCK`]) with
    /// `|r_ij|^2 < r2max`; returns how many.
    #[inline(always)]
    pub(super) fn filter(
        &mut self,
        candidates: impl Iterator<Item = (u32, V)>,
        r2max: f64,
    ) -> usize {
        let mut n = 0usize;
        for (j, d) in candidates {
            let r2 = d.length_squared();
            self.index[n % KEPT_BLOCK] = j;
            self.offset[n % KEPT_BLOCK] = d;
            self.r2[n % KEPT_BLOCK] = r2;
            n += usize::from(r2 < r2max);
        }
        n
    }
}

impl<V: Vector> Default for KeptBlock<V> {
    fn default() -> Self {
        Self::new()
    }
}

/// The neighbours of fixed query points, kept while neither the queries nor the points move
/// (the iterations of a midpoint step): for query `i`, the points `j` that
/// [`CellGrid::for_each_neighbour`] visits, in its order, each with its `r_ij` (minimum image)
/// and a per-pair factor `factor(|r_ij|)` (the kernel gradient factor for the fluid sums).
///
/// Compressed rows in blocks of [`PairList::BLOCK`] queries, each block filled by one task:
/// the pairs of the block's query `k` are `start[k]..start[k + 1]` of its index, displacement
/// and factor arrays (`4 + size_of::<V>() + 8` bytes per pair: 28 in 2-D, 36 in 3-D). The
/// buffers are kept between rebuilds, so a rebuild allocates only when the list grows.
#[derive(Clone, Debug, Default)]
pub struct PairList<V> {
    blocks: Vec<PairBlock<V>>,
    queries: usize,
}

/// One block of queries of a [`PairList`].
#[derive(Clone, Debug, Default)]
struct PairBlock<V> {
    start: Vec<u32>,
    index: Vec<u32>,
    offset: Vec<V>,
    factor: Vec<f64>,
}

impl<V: Vector> PairList<V> {
    /// Queries per block.
    pub const BLOCK: usize = 256;

    /// Bytes stored per pair.
    pub const PAIR_BYTES: usize = 4 + std::mem::size_of::<V>() + 8;

    /// Lists the neighbours within `radius` among `points` (indexed by `grid`) of every point
    /// of `queries`, with `factor(|r_ij|)` per pair; in parallel over blocks of queries (the
    /// content does not depend on the number of threads). A query with no point in the cells
    /// around it gets its empty row without a walk ([`CellGrid::for_each_sparse_neighbour`]):
    /// the particles away from the walls, the elements out of the water.
    pub fn rebuild(
        &mut self,
        grid: &CellGrid<V>,
        queries: &[V],
        points: &[V],
        radius: f64,
        factor: impl Fn(f64) -> f64 + Sync,
    ) {
        self.fill(queries.len(), factor, |i, visit| {
            grid.for_each_sparse_neighbour(queries[i], points, radius, visit)
        });
    }

    /// Lists, for each of the `points` points of `rows`, the queries whose rows in `rows` hold
    /// it, each with its offset negated and its factor, visiting the queries in `order`: the
    /// rows that [`PairList::rebuild`] would list from the points among the queries, with the
    /// same bits, when `order` is the queries' grid's [`CellGrid::points_in_search_order`]
    /// (the same pairs within the same radius; `q - p = -(p - q)` exactly, so `|r_ij|` and the
    /// factor keep their bits) — without a search. In parallel over chunks of blocks, each
    /// task reading every row (the content does not depend on the number of threads).
    pub fn transpose(&mut self, rows: &PairList<V>, points: usize, order: &[u32]) {
        let mut counts = vec![0u32; points];
        for block in &rows.blocks {
            for &j in &block.index {
                counts[j as usize] += 1;
            }
        }
        self.queries = points;
        self.blocks
            .resize_with(points.div_ceil(Self::BLOCK), Default::default);
        let chunk = self
            .blocks
            .len()
            .div_ceil(4 * rayon::current_num_threads())
            .max(1);
        self.blocks
            .par_chunks_mut(chunk)
            .enumerate()
            .for_each(|(c, blocks)| {
                let first = c * chunk * Self::BLOCK;
                let last = (first + blocks.len() * Self::BLOCK).min(points);
                // Each point's next slot in its block.
                let mut next = vec![0u32; last - first];
                for (b, block) in blocks.iter_mut().enumerate() {
                    let p0 = first + b * Self::BLOCK;
                    let p1 = (p0 + Self::BLOCK).min(points);
                    block.start.clear();
                    block.start.push(0);
                    for p in p0..p1 {
                        next[p - first] = *block.start.last().unwrap();
                        block.start.push(next[p - first] + counts[p]);
                    }
                    let pairs = *block.start.last().unwrap() as usize;
                    block.index.resize(pairs, 0);
                    block.offset.resize(pairs, V::ZERO);
                    block.factor.resize(pairs, 0.0);
                }
                for &q in order {
                    let (index, offset, factor) = rows.neighbours(q as usize);
                    for ((&j, &r_ij), &f) in index.iter().zip(offset).zip(factor) {
                        let j = j as usize;
                        if !(first..last).contains(&j) {
                            continue;
                        }
                        let block = &mut blocks[(j - first) / Self::BLOCK];
                        let slot = &mut next[j - first];
                        let k = *slot as usize;
                        block.index[k] = q;
                        block.offset[k] = -r_ij;
                        block.factor[k] = f;
                        *slot += 1;
                    }
                }
            });
    }

    /// Fills the rows of `queries` queries, block by block in parallel: `neighbours(i, visit)`
    /// calls `visit(j, r_ij, |r_ij|)` for each neighbour of query `i`, in the row's order.
    fn fill(
        &mut self,
        queries: usize,
        factor: impl Fn(f64) -> f64 + Sync,
        neighbours: impl Fn(usize, &mut dyn FnMut(usize, V, f64)) + Sync,
    ) {
        self.queries = queries;
        self.blocks
            .resize_with(queries.div_ceil(Self::BLOCK), Default::default);
        self.blocks
            .par_iter_mut()
            .enumerate()
            .for_each(|(b, block)| {
                block.start.clear();
                block.index.clear();
                block.offset.clear();
                block.factor.clear();
                block.start.push(0);
                for i in b * Self::BLOCK..((b + 1) * Self::BLOCK).min(queries) {
                    neighbours(i, &mut |j, r_ij, r| {
                        block.index.push(j as u32);
                        block.offset.push(r_ij);
                        block.factor.push(factor(r));
                    });
                    block.start.push(block.index.len() as u32);
                }
            });
    }

    /// The listed neighbours of query `i`, their offsets `r_ij` and factors, in the order of
    /// [`CellGrid::for_each_neighbour`].
    #[inline(always)]
    pub fn neighbours(&self, i: usize) -> (&[u32], &[V], &[f64]) {
        let block = &self.blocks[i / Self::BLOCK];
        let k = i % Self::BLOCK;
        let (s, e) = (block.start[k] as usize, block.start[k + 1] as usize);
        (&block.index[s..e], &block.offset[s..e], &block.factor[s..e])
    }

    /// Calls `visit(j, r_ij, factor)` for every listed neighbour of query `i`, in the order of
    /// [`CellGrid::for_each_neighbour`].
    #[inline(always)]
    pub fn for_each(&self, i: usize, mut visit: impl FnMut(usize, V, f64)) {
        let (index, offset, factor) = self.neighbours(i);
        for ((&j, &r_ij), &f) in index.iter().zip(offset).zip(factor) {
            visit(j as usize, r_ij, f);
        }
    }

    /// Number of queries listed.
    pub fn len(&self) -> usize {
        self.queries
    }

    /// `true` when no query is listed.
    pub fn is_empty(&self) -> bool {
        self.queries == 0
    }

    /// Number of pairs listed.
    pub fn pairs(&self) -> usize {
        self.blocks.iter().map(|b| b.index.len()).sum()
    }

    /// Bytes held by the buffers (their capacities).
    pub fn memory_bytes(&self) -> usize {
        self.blocks
            .iter()
            .map(|b| {
                4 * (b.start.capacity() + b.index.capacity())
                    + std::mem::size_of::<V>() * b.offset.capacity()
                    + 8 * b.factor.capacity()
            })
            .sum()
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
pub(super) mod tests {
    use super::*;
    use glam::{DVec2, DVec3};

    pub(in crate::neighbours) fn pseudo_random(n: usize, seed: u64) -> impl Iterator<Item = f64> {
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

    /// The neighbours of a point, as keys, in the order a keyed grid visits them.
    fn keyed_order<V: Vector>(
        grid: &CellGrid<V>,
        points: &[V],
        keys: &[u32],
        x: V,
        radius: f64,
    ) -> Vec<u32> {
        let mut order = Vec::new();
        grid.for_each_neighbour(x, points, radius, |j, _, _| order.push(keys[j]));
        order
    }

    /// A keyed grid visits a point's neighbours in the same order, with the same offsets,
    /// whatever the storage order of the points and whichever other points it holds: a grid
    /// over a shuffled band of the points (`0.3 - radius <= x < 0.6 + radius`) agrees with
    /// the grid over all of them for every query in `0.3 <= x < 0.6`, in 2-D, in 3-D, and
    /// across a periodic axis.
    fn check_parts_agree<V: Vector>(points: Vec<V>, radius: f64, period: Periodicity<V>) {
        let keys: Vec<u32> = (0..points.len() as u32).collect();
        let mut whole = CellGrid::with_period(radius, period).unwrap();
        whole.rebuild_keyed(&points, &keys);
        // A part in shuffled order: every third point first, then the others backwards.
        let inside = |p: &V| (0.3 - radius..0.6 + radius).contains(&p.get(0));
        let mut order: Vec<u32> = (0..points.len() as u32).step_by(3).collect();
        order.extend((0..points.len() as u32).rev().filter(|k| k % 3 != 0));
        order.retain(|&k| inside(&points[k as usize]));
        let part_points: Vec<V> = order.iter().map(|&k| points[k as usize]).collect();
        let mut part = CellGrid::with_period(radius, period).unwrap();
        part.rebuild_keyed(&part_points, &order);
        let mut checked = 0;
        for &x in points.iter().filter(|p| (0.3..0.6).contains(&p.get(0))) {
            let a = keyed_order(&whole, &points, &keys, x, radius);
            let b = keyed_order(&part, &part_points, &order, x, radius);
            assert_eq!(a, b, "neighbour order of {:?}", x.to_xyz());
            let mut offsets = (Vec::new(), Vec::new());
            whole.for_each_neighbour(x, &points, radius, |_, d, _| offsets.0.push(d));
            part.for_each_neighbour(x, &part_points, radius, |_, d, _| offsets.1.push(d));
            assert!(offsets.0 == offsets.1);
            checked += a.len();
        }
        assert!(checked > points.len(), "test must see real neighbours");
    }

    #[test]
    fn keyed_grids_order_neighbours_alike_in_any_part() {
        let r: Vec<f64> = pseudo_random(6000, 11).collect();
        let p2: Vec<DVec2> = r.chunks(2).map(|c| DVec2::new(c[0], c[1] - 0.3)).collect();
        check_parts_agree(p2.clone(), 0.07, Periodicity::none());
        let periodic = Periodicity {
            min: DVec2::new(0.0, -0.3),
            length: DVec2::new(0.0, 1.0),
        };
        check_parts_agree(p2, 0.07, periodic);
        let p3: Vec<DVec3> = r
            .chunks(3)
            .map(|c| DVec3::new(c[0], c[1] + 2.0, 0.3 * c[2] - 1.0))
            .collect();
        check_parts_agree(p3, 0.15, Periodicity::none());
    }

    /// Points along the border of the unit square (a wall), queried from inside and
    /// outside: the sparse search gives the same pairs, order and bits as the walk, and most
    /// queries find nothing.
    #[test]
    fn sparse_search_equals_the_walk() {
        let radius = 0.05;
        let wall: Vec<DVec2> = (0..400)
            .map(|k| {
                let s = k as f64 / 100.0;
                match k / 100 {
                    0 => DVec2::new(s, 0.0),
                    1 => DVec2::new(1.0, s - 1.0),
                    2 => DVec2::new(3.0 - s, 1.0),
                    _ => DVec2::new(0.0, 4.0 - s),
                }
            })
            .collect();
        let mut grid = CellGrid::new(radius);
        grid.rebuild(&wall);
        let r: Vec<f64> = pseudo_random(4000, 5).collect();
        let (mut empty, mut found_any) = (0, 0);
        for c in r.chunks(2) {
            let x = DVec2::new(1.2 * c[0] - 0.1, 1.2 * c[1] - 0.1);
            let (mut walk, mut sparse) = (Vec::new(), Vec::new());
            grid.for_each_neighbour(x, &wall, radius, |j, d, l| walk.push((j, d, l)));
            grid.for_each_sparse_neighbour(x, &wall, radius, |j, d, l| sparse.push((j, d, l)));
            assert_eq!(walk, sparse, "query at {x:?}");
            // The map of empty neighbourhoods answers as the cells do, in and out of the grid.
            let mut candidates = 0;
            grid.for_each_candidate(x, |_| candidates += 1);
            assert_eq!(grid.no_candidates(x), candidates == 0, "query at {x:?}");
            if walk.is_empty() {
                empty += 1;
            } else {
                found_any += 1;
            }
        }
        assert!(
            empty > found_any && found_any > 100,
            "{empty} empty, {found_any} not"
        );
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

    fn check_pair_list<V: Vector>(points: Vec<V>, radius: f64, period: Periodicity<V>) {
        let points: Vec<V> = points.into_iter().map(|p| period.wrap(p)).collect();
        let mut grid = CellGrid::with_period(radius, period).unwrap();
        grid.rebuild(&points);
        let factor = |r: f64| (1.0 - r / radius).powi(3);
        let mut list = PairList::default();
        // Rebuilt twice, the second time over fewer queries into the kept buffers.
        for queries in [&points[..], &points[..points.len() / 2 + 3]] {
            list.rebuild(&grid, queries, &points, radius, factor);
            assert_eq!(list.len(), queries.len());
            let mut total = 0;
            for (i, &x) in queries.iter().enumerate() {
                let mut searched = Vec::new();
                grid.for_each_neighbour(x, &points, radius, |j, r_ij, r| {
                    searched.push((j, r_ij, factor(r)));
                });
                let mut listed = Vec::new();
                list.for_each(i, |j, r_ij, f| listed.push((j, r_ij, f)));
                // Same order, same bits (r_ij and the factor), so sums over either agree.
                assert_eq!(listed, searched, "query {i}");
                total += listed.len();
            }
            assert_eq!(list.pairs(), total);
            assert!(list.memory_bytes() >= total * PairList::<V>::PAIR_BYTES);
        }
    }

    /// Pseudo-random 2-D and 3-D point clouds from `seed`, each with a period along x (and z
    /// in 3-D) that the points fill.
    pub(in crate::neighbours) fn point_clouds(
        seed: u64,
    ) -> (
        Vec<DVec2>,
        Periodicity<DVec2>,
        Vec<DVec3>,
        Periodicity<DVec3>,
    ) {
        let r: Vec<f64> = pseudo_random(3000, seed).collect();
        let p2 = r
            .chunks(2)
            .map(|c| DVec2::new(c[0] - 0.1, 0.6 * c[1]))
            .collect();
        let period2 = Periodicity {
            min: DVec2::new(-0.1, 0.0),
            length: DVec2::new(1.0, 0.0),
        };
        let p3 = r
            .chunks(3)
            .map(|c| DVec3::new(c[0], c[1], 0.5 * c[2]))
            .collect();
        let period3 = Periodicity {
            min: DVec3::ZERO,
            length: DVec3::new(1.0, 0.0, 0.5),
        };
        (p2, period2, p3, period3)
    }

    #[test]
    fn pair_list_repeats_the_search_in_order_and_bits() {
        let (p2, period2, p3, period3) = point_clouds(5);
        check_pair_list(p2.clone(), 0.07, Periodicity::none());
        check_pair_list(p2, 0.07, period2);
        check_pair_list(p3, 0.15, period3);
    }

    /// Rows transposed from a search of the queries' grid (in the points' search order)
    /// against the rows a search of the points' grid lists: the same partners in the same
    /// order with the same bits.
    fn check_transpose<V: Vector>(queries: Vec<V>, points: Vec<V>, radius: f64) {
        let factor = |r: f64| (1.0 - r / radius).powi(3);
        let mut query_grid = CellGrid::new(radius * 1.3);
        query_grid.rebuild(&queries);
        let mut point_grid = CellGrid::new(radius);
        point_grid.rebuild(&points);
        let mut searched = PairList::default();
        searched.rebuild(&point_grid, &queries, &points, radius, factor);
        // The queries near each point, the points visited as a search of their grid meets them.
        let mut from_points = PairList::default();
        from_points.rebuild(&query_grid, &points, &queries, radius, factor);
        let order = point_grid.points_in_search_order().unwrap();
        let mut transposed = PairList::default();
        // Twice: the second time into the kept buffers.
        for _ in 0..2 {
            transposed.transpose(&from_points, queries.len(), &order);
            assert_eq!(transposed.len(), queries.len());
            assert_eq!(transposed.pairs(), searched.pairs());
            for i in 0..queries.len() {
                let bits = |list: &PairList<V>| {
                    let mut row = Vec::new();
                    list.for_each(i, |j, r_ij, f| {
                        let mut b = vec![j as u64, f.to_bits()];
                        b.extend((0..V::DIM).map(|k| r_ij.get(k).to_bits()));
                        row.push(b);
                    });
                    row
                };
                assert_eq!(bits(&transposed), bits(&searched), "query {i}");
            }
        }
        assert!(searched.pairs() > queries.len());
    }

    #[test]
    fn transposed_rows_repeat_the_search_in_order_and_bits() {
        let (p2, _, p3, _) = point_clouds(11);
        // Sparse points (a tenth, shifted, some outside the queries' box) against all.
        let sparse2 = p2.iter().step_by(10).map(|&p| p * 1.2 - DVec2::splat(0.05));
        check_transpose(p2.clone(), sparse2.collect(), 0.07);
        let sparse3 = p3.iter().step_by(10).map(|&p| p * 1.2 - DVec3::splat(0.05));
        check_transpose(p3.clone(), sparse3.collect(), 0.15);
        let (_, _, p3b, _) = point_clouds(12);
        check_transpose(p3, p3b, 0.15);
    }

    #[test]
    fn a_periodic_grid_has_no_single_search_order() {
        let (p2, period2, _, _) = point_clouds(5);
        let mut grid = CellGrid::with_period(0.07, period2).unwrap();
        let points: Vec<DVec2> = p2.into_iter().map(|p| period2.wrap(p)).collect();
        grid.rebuild(&points);
        assert!(grid.points_in_search_order().is_none());
        let mut open = CellGrid::new(0.07);
        open.rebuild(&points);
        let mut order = open.points_in_search_order().unwrap();
        order.sort_unstable();
        assert_eq!(order, (0..points.len() as u32).collect::<Vec<_>>());
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
    fn storage_order_is_rows_along_the_z_curve_with_contiguous_runs() {
        assert_eq!(morton_key([1, 0, 0], 2), 1);
        assert_eq!(morton_key([0, 1, 0], 2), 2);
        assert_eq!(morton_key([3, 3, 0], 2), 15);
        assert_eq!(morton_key([0, 0, 1], 3), 4);
        assert_eq!(morton_key([1, 1, 1], 3), 7);
        assert_eq!(morton_key([2, 0, 0], 3), 8);
        // 2-D: plain row order.
        let pts: Vec<DVec2> = (0..16)
            .map(|k| DVec2::new((k % 4) as f64 + 0.5, (k / 4) as f64 + 0.5))
            .rev()
            .collect();
        let mut grid = CellGrid::new(1.0);
        grid.rebuild(&pts);
        let expected: Vec<u32> = (0..16).rev().collect();
        assert_eq!(grid.sorted_items(), &expected[..]);
        // 3-D: 2 cells per row, rows (y, z) along the Z curve.
        let cell = |cx: usize, cy: usize, cz: usize| cx + 2 * (cy + 4 * cz);
        let pts: Vec<DVec3> = (0..32)
            .map(|k| {
                let (cx, cy, cz) = (k % 2, (k / 2) % 4, k / 8);
                DVec3::new(cx as f64, cy as f64, cz as f64) + 0.5
            })
            .collect();
        let mut grid = CellGrid::new(1.0);
        grid.rebuild(&pts);
        let rows = [
            (0, 0),
            (1, 0),
            (0, 1),
            (1, 1),
            (2, 0),
            (3, 0),
            (2, 1),
            (3, 1),
        ];
        let expected: Vec<u32> = rows
            .iter()
            .flat_map(|&(cy, cz)| [cell(0, cy, cz) as u32, cell(1, cy, cz) as u32])
            .collect();
        assert_eq!(&grid.sorted_items()[..16], &expected[..]);
    }

    fn check_reordered<V: Vector>(points: Vec<V>, radius: f64, period: Periodicity<V>) {
        let mut grid = CellGrid::with_period(radius, period).unwrap();
        grid.rebuild(&points);
        let order = grid.sorted_items().to_vec();
        let sorted: Vec<V> = order.iter().map(|&k| points[k as usize]).collect();
        grid.mark_reordered();
        let mut fresh = CellGrid::with_period(radius, period).unwrap();
        fresh.rebuild(&sorted);
        assert_eq!(fresh.sorted_items(), grid.sorted_items(), "already sorted");
        for &x in sorted.iter().step_by(7) {
            let mut found = Vec::new();
            grid.for_each_neighbour(x, &sorted, radius, |j, r, d| found.push((j, r, d)));
            let mut again = Vec::new();
            fresh.for_each_neighbour(x, &sorted, radius, |j, r, d| again.push((j, r, d)));
            assert_eq!(found, again);
            let mut brute: Vec<usize> = (0..sorted.len())
                .filter(|&j| period.minimum_image(sorted[j] - x).length_squared() < radius * radius)
                .collect();
            let mut ids: Vec<usize> = found.iter().map(|f| f.0).collect();
            ids.sort();
            brute.sort();
            assert_eq!(ids, brute);
        }
    }

    #[test]
    fn reordered_points_are_queried_as_contiguous_runs() {
        let r: Vec<f64> = pseudo_random(3000, 5).collect();
        let p2: Vec<DVec2> = r
            .chunks(2)
            .map(|c| DVec2::new(c[0], 2.0 * c[1] - 0.5))
            .collect();
        check_reordered(p2.clone(), 0.07, Periodicity::none());
        let period = Periodicity {
            min: DVec2::new(0.0, -0.5),
            length: DVec2::new(1.0, 2.0),
        };
        check_reordered(p2, 0.07, period);
        let p3: Vec<DVec3> = r
            .chunks(3)
            .map(|c| DVec3::new(c[0], c[1], 0.3 * c[2]))
            .collect();
        check_reordered(p3, 0.15, Periodicity::none());
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
