//! A Verlet list between two point sets (the fluid particles and the wall elements): for
//! each query point, the points a cell-grid search found within a listing radius at the
//! build, filtered again at the current positions by each search.
//!
//! The listing radius is the largest search radius (the reach) plus a skin. While no query
//! and no point has moved more than half the skin since the build, every point within the
//! reach of a query is among its candidates, so a search of the rows finds the same points
//! as a search of the grid. The candidates keep the grid search's order; without periodic
//! axes and with the grid unchanged, both searches visit the same points in the same order
//! with the same `r_ij`, so sums over them have the same bits.

use super::grid::{one_at_a_time, CellGrid, KeptBlock, Periodicity, KEPT_BLOCK};
use super::pair_blocks::{renumbering, BORDER, GONE};
use crate::dim::Vector;
use rayon::prelude::*;

/// For each query, the points within `reach + skin` of it at the build, in the order of the
/// cell-grid search (see the module documentation); 4 bytes per candidate. The buffers are
/// kept between rebuilds.
#[derive(Clone, Debug, Default)]
pub struct CandidateRows<V> {
    blocks: Vec<RowBlock>,
    queries: usize,
    /// The largest search radius the rows answer for.
    reach: f64,
    /// The listing radius, `reach + skin`.
    listing: f64,
    period: Periodicity<V>,
}

/// The rows of [`CandidateRows::BLOCK`] consecutive queries, filled by one task.
#[derive(Clone, Debug, Default)]
struct RowBlock {
    /// Query `k`'s candidates are `index[start[k]..start[k + 1]]`.
    start: Vec<u32>,
    index: Vec<u32>,
}

impl<V: Vector> CandidateRows<V> {
    /// Queries per block.
    const BLOCK: usize = 256;

    /// Lists, for every point of `queries`, the points of `grid` (which indexes `points`, in
    /// cells at least `reach + skin` wide) within `reach + skin` of it, in parallel over
    /// blocks of queries (the rows do not depend on the number of threads). Searches may then
    /// ask for any radius up to `reach`.
    pub fn rebuild(
        &mut self,
        grid: &CellGrid<V>,
        queries: &[V],
        points: &[V],
        reach: f64,
        skin: f64,
    ) {
        self.queries = queries.len();
        self.reach = reach;
        self.period = *grid.periodicity();
        let radius = reach + skin;
        self.listing = radius;
        debug_assert!(
            radius <= grid.cell_size(),
            "a listing radius wider than a cell"
        );
        self.blocks
            .resize_with(queries.len().div_ceil(Self::BLOCK), Default::default);
        self.blocks
            .par_iter_mut()
            .enumerate()
            .for_each(|(b, block)| {
                block.start.clear();
                block.index.clear();
                block.start.push(0);
                let end = ((b + 1) * Self::BLOCK).min(queries.len());
                for &x in &queries[b * Self::BLOCK..end] {
                    grid.for_each_sparse_neighbour(x, points, radius, |j, _, _| {
                        block.index.push(j as u32)
                    });
                    block.start.push(block.index.len() as u32);
                }
            });
    }

    /// `true` when one of the `moved` items (queries or points, whichever side moves; at
    /// `now`, and at `then` when the rows were built) lies within the reach of a `fixed`
    /// item (indexed by `grid`, in cells at least the reach wide) that was farther than the
    /// listing radius from it at the build: the rows lack that pair. Borderline distances
    /// count as lacking, as in [`super::PairBlocks::lacks_pair`].
    pub fn lacks_fixed_partner(
        &self,
        grid: &CellGrid<V>,
        fixed: &[V],
        moved: &[u32],
        now: &[V],
        then: &[V],
    ) -> bool {
        let near2 = self.reach * self.reach * (1.0 + BORDER);
        let listed2 = self.listing * self.listing * (1.0 - BORDER);
        let image = |d: V| self.period.minimum_image(d);
        moved.par_iter().any(|&m| {
            let (x, x0) = (now[m as usize], then[m as usize]);
            let mut lacks = false;
            grid.for_each_candidate_within_shifted(x, self.reach, |j, _| {
                lacks |= image(fixed[j] - x).length_squared() < near2
                    && image(fixed[j] - x0).length_squared() >= listed2;
            });
            lacks
        })
    }

    /// Keeps the rows of the queries `kept` (old indices, increasing), renumbered `0..` in
    /// that order.
    pub fn retain_queries(&mut self, kept: &[u32]) {
        let old = std::mem::take(&mut self.blocks);
        let row = |i: usize| Self::row_of(&old, i);
        self.blocks = kept
            .par_chunks(Self::BLOCK)
            .map(|queries| {
                let mut block = RowBlock::default();
                block.start.push(0);
                for &i in queries {
                    block.index.extend_from_slice(row(i as usize));
                    block.start.push(block.index.len() as u32);
                }
                block
            })
            .collect();
        self.queries = kept.len();
    }

    /// Keeps the points `kept` (old indices of `len` points, increasing) in every row,
    /// renumbered `0..` in that order.
    pub fn retain_points(&mut self, kept: &[u32], len: usize) {
        let renumbered = renumbering(kept, len);
        self.blocks.par_iter_mut().for_each(|block| {
            let mut n = 0;
            let mut from = 0;
            for k in 0..block.start.len() - 1 {
                let end = block.start[k + 1] as usize;
                for c in from..end {
                    let j = renumbered[block.index[c] as usize];
                    block.index[n] = j;
                    n += usize::from(j != GONE);
                }
                from = end;
                block.start[k + 1] = n as u32;
            }
            block.index.truncate(n);
        });
    }

    /// Number of queries listed.
    pub fn len(&self) -> usize {
        self.queries
    }

    /// `true` when no query is listed.
    pub fn is_empty(&self) -> bool {
        self.queries == 0
    }

    /// Bytes held by the buffers (their capacities).
    pub fn memory_bytes(&self) -> usize {
        self.blocks
            .iter()
            .map(|b| 4 * (b.start.capacity() + b.index.capacity()))
            .sum()
    }

    /// Calls `visit(j, r_ij)` for every candidate `j` of query `i` (each point within the
    /// listing radius of the query at the build), with `r_ij = points[j] - x` (the minimum
    /// image across periodic axes), in the order of the grid search at the build.
    ///
    /// # Panics
    /// When `i` is not a listed query.
    pub fn for_each_listed(&self, i: usize, x: V, points: &[V], mut visit: impl FnMut(usize, V)) {
        let periodic = self.period.any();
        for &j in self.row(i) {
            visit(j as usize, self.offset(periodic, x, points[j as usize]));
        }
    }

    /// The candidates of query `i`, in the order of the grid search at the build.
    #[inline(always)]
    fn row(&self, i: usize) -> &[u32] {
        Self::row_of(&self.blocks, i)
    }

    /// The candidates of query `i` in the row blocks `blocks`.
    #[inline(always)]
    fn row_of(blocks: &[RowBlock], i: usize) -> &[u32] {
        let block = &blocks[i / Self::BLOCK];
        let k = i % Self::BLOCK;
        &block.index[block.start[k] as usize..block.start[k + 1] as usize]
    }

    /// `r_ij = p - x`, its minimum image where `periodic` (the rows' periodic axes).
    #[inline(always)]
    fn offset(&self, periodic: bool, x: V, p: V) -> V {
        let d = p - x;
        if periodic {
            self.period.minimum_image(d)
        } else {
            d
        }
    }

    /// The listing radius: every point within it of a query at the build is among the
    /// query's candidates.
    pub fn listing_radius(&self) -> f64 {
        self.listing
    }

    /// Calls `visit(j, r_ij, |r_ij|)` for the candidates `j` of query `i` within `radius` of
    /// `x` (the query's current position), with `r_ij = points[j] - x` (the minimum image
    /// across periodic axes), in the order of the grid search at the build.
    ///
    /// # Panics
    /// When `i` is not a listed query, or (in debug builds) when `radius` exceeds the reach
    /// the rows were built for.
    #[inline(always)]
    pub fn for_each_within(
        &self,
        i: usize,
        x: V,
        points: &[V],
        radius: f64,
        visit: impl FnMut(usize, V, f64),
    ) {
        debug_assert!(radius <= self.reach, "a search beyond the listed reach");
        let r2max = radius * radius;
        let periodic = self.period.any();
        let mut kept = KeptBlock::<V>::new();
        let mut visit = one_at_a_time(visit);
        for chunk in self.row(i).chunks(KEPT_BLOCK) {
            let offsets = chunk
                .iter()
                .map(|&j| (j, self.offset(periodic, x, points[j as usize])));
            let n = kept.filter(offsets, r2max);
            visit(&kept.index[..n], &kept.offset[..n], &kept.r2[..n]);
        }
    }
}

/// Where a search finds the points near a query: the cell grid over the points, or the
/// query's candidates in a [`CandidateRows`] that holds for the current positions.
#[derive(Clone, Copy, Debug)]
pub struct Nearby<'a, V: Vector> {
    /// The cell grid over the points.
    pub grid: &'a CellGrid<V>,
    /// The candidates listed per query, when they hold.
    pub listed: Option<&'a CandidateRows<V>>,
}

impl<'a, V: Vector> Nearby<'a, V> {
    /// A search of `grid`.
    pub fn grid(grid: &'a CellGrid<V>) -> Self {
        Nearby { grid, listed: None }
    }

    /// Calls `visit(j, r_ij, |r_ij|)` for the points `j` within `radius` of `x`, the position
    /// of query `query`, with `r_ij = points[j] - x` (the minimum image across periodic axes):
    /// [`CellGrid::for_each_sparse_neighbour`], or [`CandidateRows::for_each_within`].
    #[inline(always)]
    pub fn for_each(
        &self,
        query: usize,
        x: V,
        points: &[V],
        radius: f64,
        visit: impl FnMut(usize, V, f64),
    ) {
        match self.listed {
            Some(rows) => rows.for_each_within(query, x, points, radius, visit),
            None => self
                .grid
                .for_each_sparse_neighbour(x, points, radius, visit),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::neighbours::grid::tests::{point_clouds, pseudo_random};

    /// Moves each point by less than `limit` (pseudo-random directions), kept in the period.
    fn moved<V: Vector>(points: &[V], limit: f64, seed: u64, period: &Periodicity<V>) -> Vec<V> {
        let mut r = pseudo_random(points.len() * V::DIM, seed);
        points
            .iter()
            .map(|&p| {
                let mut d = V::ZERO;
                for k in 0..V::DIM {
                    d.set(k, r.next().unwrap() - 0.5);
                }
                // Components within 1/2, so |d| <= sqrt(3) / 2 < 0.87.
                period.wrap(p + d * (0.999 * limit / 0.87))
            })
            .collect()
    }

    /// Rows built over `queries` and `points` find, after every query and point moved by
    /// less than half the skin, exactly the points within each radius up to the reach
    /// (against brute force, minimum image); unmoved and without periodic axes, they repeat
    /// the grid search's order and bits.
    fn check<V: Vector>(all: Vec<V>, reach: f64, period: Periodicity<V>) {
        let all: Vec<V> = all.into_iter().map(|p| period.wrap(p)).collect();
        let (queries, points) = all.split_at(all.len() / 3);
        let skin = 0.2 * reach;
        let mut grid = CellGrid::with_period(reach + skin, period).unwrap();
        grid.rebuild(points);
        let mut rows = CandidateRows::default();
        rows.rebuild(&grid, queries, points, reach, skin);
        assert_eq!(rows.len(), queries.len());
        if !period.any() {
            for (i, &x) in queries.iter().enumerate() {
                let (mut searched, mut listed) = (Vec::new(), Vec::new());
                grid.for_each_neighbour(x, points, reach, |j, r_ij, r| searched.push((j, r_ij, r)));
                rows.for_each_within(i, x, points, reach, |j, r_ij, r| listed.push((j, r_ij, r)));
                assert_eq!(listed, searched, "query {i}");
            }
        }
        let half = 0.5 * skin;
        let (queries, points) = (
            moved(queries, half, 3, &period),
            moved(points, half, 4, &period),
        );
        for radius in [0.6 * reach, reach] {
            for (i, &x) in queries.iter().enumerate() {
                let mut listed = Vec::new();
                rows.for_each_within(i, x, &points, radius, |j, r_ij, r| {
                    assert_eq!(r_ij, period.minimum_image(points[j] - x));
                    assert_eq!(r, r_ij.length_squared().sqrt());
                    listed.push(j);
                });
                let expected: Vec<usize> = (0..points.len())
                    .filter(|&j| {
                        period.minimum_image(points[j] - x).length_squared() < radius * radius
                    })
                    .collect();
                listed.sort_unstable();
                assert_eq!(listed, expected, "query {i}, radius {radius}");
            }
        }
    }

    /// Rows from moving queries to fixed points lack a pair exactly when a query moved within
    /// the reach of a point it was not listed with; when they lack none, they find every
    /// point within the reach.
    fn check_lacking<V: Vector>(all: Vec<V>, reach: f64, period: Periodicity<V>) {
        let all: Vec<V> = all.into_iter().map(|p| period.wrap(p)).collect();
        let (queries, points) = all.split_at(all.len() / 3);
        let skin = 0.2 * reach;
        let mut grid = CellGrid::with_period(reach + skin, period).unwrap();
        grid.rebuild(points);
        let mut rows = CandidateRows::default();
        rows.rebuild(&grid, queries, points, reach, skin);
        let everyone: Vec<u32> = (0..queries.len() as u32).collect();
        let (mut lacking, mut complete) = (0, 0);
        for step in 1..=10 {
            let now = moved(queries, step as f64 * 0.1 * reach, 9, &period);
            let distance2 = |x: V, j: usize| period.minimum_image(points[j] - x).length_squared();
            for i in 0..queries.len() {
                let one = &everyone[i..i + 1];
                let lacks = rows.lacks_fixed_partner(&grid, points, one, &now, queries);
                let truth = (0..points.len()).any(|j| {
                    distance2(now[i], j) < reach * reach
                        && distance2(queries[i], j) >= (reach + skin) * (reach + skin)
                });
                assert_eq!(lacks, truth, "query {i} after moves of {step} x 0.1 reach");
                if lacks {
                    lacking += 1;
                    continue;
                }
                complete += 1;
                let mut found = 0;
                rows.for_each_within(i, now[i], points, reach, |_, _, _| found += 1);
                let brute = (0..points.len())
                    .filter(|&j| distance2(now[i], j) < reach * reach)
                    .count();
                assert_eq!(found, brute, "query {i}");
            }
        }
        assert!(
            lacking > 0 && complete > 0,
            "{lacking} lacking, {complete} complete"
        );
    }

    /// Rows that drop some queries and some points are the rows built without them.
    fn check_retained<V: Vector>(all: Vec<V>, reach: f64, period: Periodicity<V>) {
        let all: Vec<V> = all.into_iter().map(|p| period.wrap(p)).collect();
        let (queries, points) = all.split_at(all.len() / 3);
        let skin = 0.2 * reach;
        let rows_of = |queries: &[V], points: &[V]| {
            let mut grid = CellGrid::with_period(reach + skin, period).unwrap();
            grid.rebuild(points);
            let mut rows = CandidateRows::default();
            rows.rebuild(&grid, queries, points, reach, skin);
            let listed: Vec<Vec<usize>> = (0..queries.len())
                .map(|i| {
                    let mut row = Vec::new();
                    rows.for_each_within(i, queries[i], points, reach, |j, _, _| row.push(j));
                    row
                })
                .collect();
            (rows, listed)
        };
        let kept_queries: Vec<u32> = (0..queries.len() as u32).filter(|i| i % 3 != 1).collect();
        let kept_points: Vec<u32> = (0..points.len() as u32).filter(|i| i % 4 != 0).collect();
        let pick = |v: &[V], kept: &[u32]| kept.iter().map(|&i| v[i as usize]).collect::<Vec<V>>();
        let (queries2, points2) = (pick(queries, &kept_queries), pick(points, &kept_points));
        let (mut rows, _) = rows_of(queries, points);
        rows.retain_queries(&kept_queries);
        rows.retain_points(&kept_points, points.len());
        let (_, expected) = rows_of(&queries2, &points2);
        assert_eq!(rows.len(), queries2.len());
        for (i, want) in expected.iter().enumerate() {
            let mut row = Vec::new();
            rows.for_each_within(i, queries2[i], &points2, reach, |j, _, _| row.push(j));
            assert_eq!(&row, want, "query {i}");
        }
    }

    #[test]
    fn rows_without_removed_queries_and_points_are_the_rows_built_without_them() {
        let (p2, period2, p3, period3) = point_clouds(5);
        check_retained(p2.clone(), 0.06, Periodicity::none());
        check_retained(p2, 0.06, period2);
        check_retained(p3.clone(), 0.12, Periodicity::none());
        check_retained(p3, 0.12, period3);
    }

    #[test]
    fn rows_lack_a_pair_exactly_when_a_query_moved_near_an_unlisted_point() {
        let (p2, period2, p3, period3) = point_clouds(3);
        check_lacking(p2.clone(), 0.06, Periodicity::none());
        check_lacking(p2, 0.06, period2);
        check_lacking(p3.clone(), 0.12, Periodicity::none());
        check_lacking(p3, 0.12, period3);
    }

    #[test]
    fn rows_find_every_point_within_the_reach_after_moves_within_half_the_skin() {
        let (p2, period2, p3, period3) = point_clouds(7);
        check(p2.clone(), 0.06, Periodicity::none());
        check(p2, 0.06, period2);
        check(p3.clone(), 0.12, Periodicity::none());
        check(p3, 0.12, period3);
    }
}
