//! A Verlet list that holds each pair once, for sweeps that evaluate a pair for both of its
//! particles, in an order that depends neither on the number of threads nor on how a run is
//! split into parts.
//!
//! **Blocks.** The cells of the grid are at least the listing radius wide, so a pair's two
//! cells are the same or adjacent. A pair belongs to the block of `2^d` cells anchored at its
//! cells' lowest corner (along an axis: the lower cell, or the cell itself when both share
//! it; across the end of a periodic axis, the last cell). Each cell lies in `2^d` blocks.
//!
//! **Classes.** Anchors are classed by the parity of their lattice coordinates, so blocks of
//! one class share no cell. Along a periodic axis with an odd number of cells the last
//! anchor, whose block wraps to the first cell, is a class of its own. A sweep takes the
//! classes in turn and the blocks of a class in parallel: no particle is written by two
//! tasks at once, and each particle receives its pairs class by class, within a block in
//! the block's fixed order.
//!
//! **Order within a block.** Its cells in the order of their offsets from the anchor (`x`
//! first), the particles of a cell in the grid's order (increasing key for a keyed grid).
//! A pair is listed with its first particle: the one in the cell of lower offset, or the
//! earlier one of a shared cell. A part of a split run holds the same particles near its own
//! with the same keys in the same lattice cells, so every own particle meets its pairs in
//! the order of the whole run.

use super::grid::{CellGrid, KeptBlock, Periodicity, KEPT_BLOCK};
use crate::dim::Vector;
use crate::kernel::Wendland;
use rayon::prelude::*;

#[cfg(target_arch = "x86_64")]
mod filter_lanes;
#[cfg(target_arch = "x86_64")]
mod gradient_lanes;

/// A pair list over the blocks of a [`CellGrid`] (see the module documentation): the pairs
/// within a listing radius when built, each once, kept while no particle has moved more than
/// half the skin.
#[derive(Clone, Debug, Default)]
pub struct PairBlocks<V> {
    /// The chunks of blocks of each class, classes in sweep order.
    classes: Vec<Vec<BlockChunk>>,
    /// The points at the build.
    origin: Vec<V>,
    /// Points whose pairs are listed: the pairs with at least one of the first `owned`.
    owned: usize,
    /// The square of the listing radius.
    listing_r2: f64,
    period: Periodicity<V>,
}

/// Consecutive blocks of one class, swept by one task: rows of a first particle and its
/// listed partners.
#[derive(Clone, Debug, Default)]
struct BlockChunk {
    /// Anchors of the chunk's blocks (grid cell coordinates).
    anchors: Vec<[u32; 3]>,
    /// The first particle of each row.
    first: Vec<u32>,
    /// Row `r`'s partners are `second[start[r]..start[r + 1]]`.
    start: Vec<u32>,
    second: Vec<u32>,
}

/// The relative margin on squared distances by which the checks of a kept list err towards
/// rebuilding it.
pub(super) const BORDER: f64 = 1e-9;

/// About this many particles per chunk (a chunk is a task of the sweep).
const CHUNK_PARTICLES: usize = 2048;

impl<V: Vector> PairBlocks<V> {
    /// Lists the pairs within `radius` (at most one cell of `grid`, which must index `points`)
    /// with at least one of the first `owned` points, each once, in parallel over chunks of
    /// blocks (the content does not depend on the number of threads).
    ///
    /// # Panics
    /// When `owned` exceeds the number of points.
    pub fn rebuild(&mut self, grid: &CellGrid<V>, points: &[V], owned: usize, radius: f64) {
        assert!(owned <= points.len(), "more owned points than points");
        self.period = *grid.periodicity();
        self.origin.clear();
        self.origin.extend_from_slice(points);
        self.owned = owned;
        self.partition(grid);
        let period = self.period;
        let r2max = radius * radius;
        self.listing_r2 = r2max;
        self.classes
            .par_iter_mut()
            .flatten()
            .for_each(|chunk| chunk.fill(grid, points, owned, r2max, &period));
    }

    /// Groups the anchors of every class into chunks of about [`CHUNK_PARTICLES`] particles.
    fn partition(&mut self, grid: &CellGrid<V>) {
        let dims = grid.dims;
        let mut classes_per_axis = [1usize; 3];
        for (k, c) in classes_per_axis.iter_mut().enumerate().take(V::DIM) {
            *c = if self.period.is_periodic(k) && dims[k] % 2 == 1 {
                3
            } else {
                2
            };
        }
        let class_of = |a: [usize; 3]| {
            let mut class = 0;
            for k in (0..V::DIM).rev() {
                let c = if self.period.is_periodic(k) {
                    if dims[k] % 2 == 1 && a[k] == dims[k] - 1 {
                        2
                    } else {
                        a[k] % 2
                    }
                } else {
                    (a[k] as i64 + grid.base[k]).rem_euclid(2) as usize
                };
                class = class * classes_per_axis[k] + c;
            }
            class
        };
        let count = classes_per_axis.iter().product::<usize>();
        let mut anchors: Vec<Vec<[u32; 3]>> = vec![Vec::new(); count];
        for z in 0..dims[2] {
            for y in 0..dims[1] {
                for x in 0..dims[0] {
                    let a = [x, y, z];
                    anchors[class_of(a)].push(a.map(|c| c as u32));
                }
            }
        }
        self.classes.resize_with(count, Vec::new);
        for (chunks, anchors) in self.classes.iter_mut().zip(anchors) {
            let mut used = 0;
            let mut particles = CHUNK_PARTICLES;
            for a in anchors {
                let in_block: usize = grid.block_cells(a).iter().map(|&(s, e)| e - s).sum();
                if in_block == 0 {
                    continue;
                }
                if particles >= CHUNK_PARTICLES {
                    if used == chunks.len() {
                        chunks.push(BlockChunk::default());
                    }
                    chunks[used].anchors.clear();
                    used += 1;
                    particles = 0;
                }
                chunks[used - 1].anchors.push(a);
                particles += in_block;
            }
            chunks.truncate(used);
        }
    }

    /// Collects into `moved`, in index order, the points that have moved more than
    /// `half_skin` since the build (minimum image across periodic axes). Returns `false` when
    /// the list was built for another number of points or one of them has moved more than
    /// `limit`.
    pub fn moved_points(
        &self,
        points: &[V],
        half_skin: f64,
        limit: f64,
        moved: &mut Vec<u32>,
    ) -> bool {
        moved.clear();
        if points.len() != self.origin.len() {
            return false;
        }
        let periodic = self.period.any();
        let drift2 = |(&p, &o): (&V, &V)| {
            let d = p - o;
            let d = if periodic {
                self.period.minimum_image(d)
            } else {
                d
            };
            d.length_squared()
        };
        let (half2, limit2) = (half_skin * half_skin, limit * limit);
        let far: Vec<(u32, f64)> = points
            .par_iter()
            .zip(self.origin.par_iter())
            .with_min_len(4096)
            .enumerate()
            .filter_map(|(i, pair)| {
                let d2 = drift2(pair);
                (d2 > half2).then_some((i as u32, d2))
            })
            .collect();
        moved.extend(far.iter().map(|&(i, _)| i));
        far.iter().all(|&(_, d2)| d2 <= limit2)
    }

    /// `true` when one of the `moved` points lies within `radius` of a point that the list
    /// does not pair it with (the two were not within the listing radius at the build), the
    /// pairs of two points at or past `owned` aside. `grid` indexes `points`, the current
    /// positions, in cells at least `radius` wide. Borderline distances (within 1e-9 of the
    /// radii, relative) count as lacking, so rounding never hides a pair.
    pub fn lacks_pair(&self, grid: &CellGrid<V>, points: &[V], moved: &[u32], radius: f64) -> bool {
        let near2 = radius * radius * (1.0 + BORDER);
        let listed2 = self.listing_r2 * (1.0 - BORDER);
        let owned = self.owned;
        let image = |d: V| self.period.minimum_image(d);
        moved.par_iter().any(|&i| {
            let i = i as usize;
            let (x, x0) = (points[i], self.origin[i]);
            let mut lacks = false;
            grid.for_each_candidate_within_shifted(x, radius, |j, _| {
                lacks |= j != i
                    && (i < owned || j < owned)
                    && image(points[j] - x).length_squared() < near2
                    && image(self.origin[j] - x0).length_squared() >= listed2;
            });
            lacks
        })
    }

    /// Keeps the pairs of the points `kept` (old indices, increasing), renumbered `0..` in
    /// that order, of which the first `owned` are own: the list of the remaining points,
    /// each pair where it was, as a build at their positions of the build would list them.
    pub fn retain(&mut self, kept: &[u32], owned: usize) {
        let renumbered = renumbering(kept, self.origin.len());
        self.origin = kept.iter().map(|&i| self.origin[i as usize]).collect();
        self.owned = owned;
        self.classes
            .par_iter_mut()
            .flatten()
            .for_each(|chunk| chunk.retain(&renumbered));
    }

    /// The points as they were at the build.
    pub fn origin(&self) -> &[V] {
        &self.origin
    }

    /// Number of points listed.
    pub fn len(&self) -> usize {
        self.origin.len()
    }

    /// `true` when no point is listed.
    pub fn is_empty(&self) -> bool {
        self.origin.is_empty()
    }

    /// Number of pairs listed of each point (as first or second particle).
    pub fn pair_counts(&self) -> Vec<u32> {
        let mut counts = vec![0u32; self.origin.len()];
        for chunk in self.classes.iter().flatten() {
            for (r, &i) in chunk.first.iter().enumerate() {
                let partners = &chunk.second[chunk.start[r] as usize..chunk.start[r + 1] as usize];
                counts[i as usize] += partners.len() as u32;
                for &j in partners {
                    counts[j as usize] += 1;
                }
            }
        }
        counts
    }

    /// Sweeps the listed pairs within `radius` at the positions `points`: for each first
    /// particle `i`, calls `visit(i, values, index, r_ij, r2)` with runs of its partners
    /// within `radius` (`index[k]` a point `j`, `r_ij[k] = points[j] - points[i]`, the
    /// minimum image across periodic axes, `r2[k] = |r_ij[k]|^2`), where `values` gives
    /// `values[i]` and `values[j]` of the run's partners. Classes in turn, the chunks of a
    /// class in parallel; each point's values are visited in an order that depends only on
    /// the list (see the module documentation).
    ///
    /// # Panics
    /// When `points` or `values` hold fewer entries than the list.
    pub fn sweep<T: Send>(
        &self,
        points: &[V],
        radius: f64,
        values: &mut [T],
        visit: impl Fn(usize, &mut RunValues<'_, T>, &[u32], &[V], &[f64]) + Sync,
    ) {
        assert!(points.len() >= self.len(), "fewer points than listed");
        let r2max = radius * radius;
        let period = self.period;
        sweep_classes(
            &self.classes,
            self.len(),
            values,
            KeptBlock::new,
            |chunk, shared, kept| {
                chunk.sweep(points, r2max, &period, kept, |i, index, r_ij, r2| {
                    let mut run = RunValues { shared, i, index };
                    visit(i, &mut run, index, r_ij, r2);
                });
            },
        );
    }

    /// Lists into `listed` the pairs within `radius` at the positions `points` (none farther
    /// than half the skin from where it was at the build), each with what `listing` asks
    /// for, in the order of [`PairBlocks::sweep`]; in parallel over chunks.
    pub fn list(
        &self,
        points: &[V],
        radius: f64,
        factor: impl Fn(f64) -> f64 + Sync,
        listing: Listing,
        listed: &mut ListedPairs<V>,
    ) {
        listed.len = self.len();
        listed.listing = listing;
        listed.classes.resize_with(self.classes.len(), Vec::new);
        let r2max = radius * radius;
        for (to, from) in listed.classes.iter_mut().zip(&self.classes) {
            to.resize_with(from.len(), Default::default);
            to.par_iter_mut().zip(from.par_iter()).for_each_init(
                KeptBlock::new,
                |kept, (to, from)| {
                    to.fill(from, points, r2max, &self.period, kept, (&factor, listing))
                },
            );
        }
    }

    /// [`PairBlocks::list`] under [`Listing::Product`] with the kernel gradients of `kernel`
    /// (the radius its support, the factor its [`Wendland::gradient_factor`]): in 3-D without
    /// periodic axes, on processors with AVX2, four candidates at a time in vector lanes
    /// (the same list, to the bit).
    pub fn list_kernel_gradients(
        &self,
        points: &[V],
        kernel: &Wendland,
        listed: &mut ListedPairs<V>,
    ) {
        #[cfg(target_arch = "x86_64")]
        if std::any::TypeId::of::<V>() == std::any::TypeId::of::<glam::DVec3>()
            && !self.period.any()
            && crate::avx2::available()
        {
            // SAFETY: `V` is `DVec3` (checked above), so each cast names the type it has.
            let (blocks, points, listed) = unsafe {
                (
                    &*(self as *const PairBlocks<V> as *const PairBlocks<glam::DVec3>),
                    &*(points as *const [V] as *const [glam::DVec3]),
                    &mut *(listed as *mut ListedPairs<V> as *mut ListedPairs<glam::DVec3>),
                )
            };
            // SAFETY: AVX2 is present and no axis is periodic (checked above).
            unsafe { blocks.list_gradients_in_lanes(points, kernel, listed) };
            return;
        }
        let factor = |r| kernel.gradient_factor(r);
        self.list(points, kernel.support, factor, Listing::Product, listed);
    }
}

/// What [`PairBlocks::list`] stores with each pair besides the partner's index.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum Listing {
    /// `r_ij` and the per-pair factor `F(|r_ij|)`.
    #[default]
    OffsetAndFactor,
    /// The product `r_ij F(|r_ij|)` alone (the kernel gradient, with `F` the kernel
    /// gradient factor), rounded once to single precision, for sums that read nothing else
    /// of a pair: 16 bytes per pair in 3-D instead of 36. Both particles of a pair read the
    /// same rounded gradient, so the pair terms stay antisymmetric (momentum) and the
    /// gradient and divergence stay adjoint (the energy balance of the midpoint scheme).
    Product,
}

impl Listing {
    /// Bytes stored per pair.
    pub fn pair_bytes<V: Vector>(self) -> usize {
        match self {
            Listing::OffsetAndFactor => 4 + std::mem::size_of::<V>() + 8,
            Listing::Product => 4 + 4 * V::DIM,
        }
    }
}

/// The pairs of a [`PairBlocks`] within a radius at fixed positions (the iterations of a
/// midpoint step), each with its `r_ij` and a per-pair factor (the kernel gradient factor
/// for the fluid sums) or with their product ([`Listing`]): the blocks' rows and order
/// without the filter. [`Listing::pair_bytes`] per pair (36 or 16 in 3-D); the buffers are
/// kept between listings.
#[derive(Clone, Debug, Default)]
pub struct ListedPairs<V> {
    classes: Vec<Vec<ListedChunk<V>>>,
    len: usize,
    listing: Listing,
}

/// The listed pairs of one [`BlockChunk`].
#[derive(Clone, Debug, Default)]
struct ListedChunk<V> {
    first: Vec<u32>,
    start: Vec<u32>,
    second: Vec<u32>,
    /// `r_ij`; empty under [`Listing::Product`].
    offset: Vec<V>,
    /// `F(|r_ij|)`; empty under [`Listing::Product`].
    factor: Vec<f64>,
    /// Under [`Listing::Product`], the components of `r_ij F(|r_ij|)` in single precision,
    /// `DIM` per pair, then [`GRADIENT_PADDING`] zeros (so that a 16-byte load of the last
    /// pair's components stays within the buffer); else empty.
    gradient: Vec<f32>,
}

/// `v` with each component rounded once to single precision, as [`Listing::Product`] stores
/// the kernel gradients (widened back exactly).
#[inline(always)]
pub fn single_precision<V: Vector>(mut v: V) -> V {
    for k in 0..V::DIM {
        v.set(k, f64::from(v.get(k) as f32));
    }
    v
}

/// Zeros after the last pair's single-precision gradient in a [`ListedChunk`].
const GRADIENT_PADDING: usize = 4;

impl<V: Vector> ListedPairs<V> {
    /// What is listed with each pair.
    pub fn listing(&self) -> Listing {
        self.listing
    }

    /// Number of pairs listed.
    pub fn pairs(&self) -> usize {
        self.classes.iter().flatten().map(|c| c.second.len()).sum()
    }

    /// [`PairBlocks::sweep`] over the listed pairs: `visit(i, values, index, r_ij, factor)`
    /// for each row, with the same pairs in the same order as the blocks' sweep at the
    /// positions of the listing; under [`Listing::Product`], `r_ij` holds the products (the
    /// single-precision gradients widened) and `factor` is empty.
    ///
    /// # Panics
    /// When `values` holds fewer entries than the list's points.
    pub fn sweep<T: Send>(
        &self,
        values: &mut [T],
        visit: impl Fn(usize, &mut RunValues<'_, T>, &[u32], &[V], &[f64]) + Sync,
    ) {
        sweep_classes(
            &self.classes,
            self.len,
            values,
            Vec::new,
            |chunk, shared, widened: &mut Vec<V>| {
                for (r, &i) in chunk.first.iter().enumerate() {
                    let (s, e) = (chunk.start[r] as usize, chunk.start[r + 1] as usize);
                    let index = &chunk.second[s..e];
                    let i = i as usize;
                    let mut run = RunValues { shared, i, index };
                    if self.listing == Listing::Product {
                        let d = V::DIM;
                        let single = &chunk.gradient[d * s..d * e];
                        widened.clear();
                        widened.extend(single.chunks_exact(d).map(|g| {
                            let mut v = V::ZERO;
                            for (k, &c) in g.iter().enumerate() {
                                v.set(k, f64::from(c));
                            }
                            v
                        }));
                        visit(i, &mut run, index, &widened[..], &[]);
                    } else {
                        visit(i, &mut run, index, &chunk.offset[s..e], &chunk.factor[s..e]);
                    }
                }
            },
        );
    }

    /// The sweep of [`ListedPairs::sweep`] over a list of [`Listing::Product`], with the
    /// single-precision gradients as they are stored: `visit(i, values, index, gradient)`,
    /// `gradient` pointing to the `DIM` components of the run's first pair, those of the
    /// others following, and [`GRADIENT_PADDING`] readable values after the run's last.
    ///
    /// # Panics
    /// When the list is not of [`Listing::Product`], or `values` holds fewer entries than
    /// the list's points.
    pub fn sweep_single<T: Send>(
        &self,
        values: &mut [T],
        visit: impl Fn(usize, &mut RunValues<'_, T>, &[u32], *const f32) + Sync,
    ) {
        assert_eq!(
            self.listing,
            Listing::Product,
            "no single-precision gradients"
        );
        sweep_classes(
            &self.classes,
            self.len,
            values,
            || (),
            |chunk, shared, _: &mut ()| {
                for (r, &i) in chunk.first.iter().enumerate() {
                    let (s, e) = (chunk.start[r] as usize, chunk.start[r + 1] as usize);
                    let index = &chunk.second[s..e];
                    let i = i as usize;
                    let mut run = RunValues { shared, i, index };
                    // In range: the padding follows the last pair.
                    let gradient = chunk.gradient[V::DIM * s..].as_ptr();
                    visit(i, &mut run, index, gradient);
                }
            },
        );
    }
}

impl<V: Vector> ListedChunk<V> {
    /// No rows, the buffers kept.
    fn empty(&mut self) {
        self.first.clear();
        self.start.clear();
        self.second.clear();
        self.offset.clear();
        self.factor.clear();
        self.gradient.clear();
        self.start.push(0);
    }

    /// Lists the pairs of `from` within `sqrt(r2max)` at `points`, each with what `listing`
    /// asks for (`factor` gives the per-pair factor from `|r_ij|`).
    fn fill(
        &mut self,
        from: &BlockChunk,
        points: &[V],
        r2max: f64,
        period: &Periodicity<V>,
        kept: &mut KeptBlock<V>,
        (factor, listing): (&(impl Fn(f64) -> f64 + Sync), Listing),
    ) {
        self.empty();
        from.sweep(points, r2max, period, kept, |i, index, r_ij, r2| {
            // A row's runs come one after the other; rows have distinct first particles.
            if self.first.last() != Some(&(i as u32)) {
                self.first.push(i as u32);
                self.start.push(self.second.len() as u32);
            }
            self.second.extend_from_slice(index);
            match listing {
                Listing::OffsetAndFactor => {
                    self.offset.extend_from_slice(r_ij);
                    self.factor.extend(r2.iter().map(|&r2| factor(r2.sqrt())));
                }
                Listing::Product => {
                    let start = self.gradient.len();
                    self.gradient.resize(start + V::DIM * r_ij.len(), 0.0);
                    let to = self.gradient[start..].chunks_exact_mut(V::DIM);
                    for (to, (&r_ij, &r2)) in to.zip(r_ij.iter().zip(r2)) {
                        let g = r_ij * factor(r2.sqrt());
                        for (k, c) in to.iter_mut().enumerate() {
                            *c = g.get(k) as f32;
                        }
                    }
                }
            }
            *self.start.last_mut().unwrap() = self.second.len() as u32;
        });
        if listing == Listing::Product {
            self.gradient.extend([0.0; GRADIENT_PADDING]);
        }
    }
}

/// Sweeps `classes` one after the other, the chunks of a class in parallel, each with
/// `sweep(chunk, values, scratch)`, `scratch` made by `init` once per task; `values` must
/// hold at least `len` entries.
fn sweep_classes<C: Sync, T: Send, S>(
    classes: &[Vec<C>],
    len: usize,
    values: &mut [T],
    init: impl Fn() -> S + Sync + Send,
    sweep: impl Fn(&C, &SharedValues<T>, &mut S) + Sync,
) {
    assert!(values.len() >= len, "fewer values than listed points");
    let shared = SharedValues {
        data: values.as_mut_ptr(),
    };
    for class in classes {
        class
            .par_iter()
            .for_each_init(&init, |scratch, chunk| sweep(chunk, &shared, scratch));
    }
}

/// The values of one point and its partners in a run of [`PairBlocks::sweep`].
pub struct RunValues<'a, T> {
    shared: &'a SharedValues<T>,
    i: usize,
    index: &'a [u32],
}

impl<T> RunValues<'_, T> {
    /// The first particle's value.
    #[inline(always)]
    pub fn first(&mut self) -> &mut T {
        // SAFETY: `i` indexes the values (checked against the list in `sweep`), and no other
        // task of this class reaches it (blocks of a class share no particle); the borrow of
        // `self` keeps it the only reference made here.
        unsafe { &mut *self.shared.data.add(self.i) }
    }

    /// The values of every point, for a sweep that reaches the run's particle and partners
    /// through a pointer: only those are this task's to read and write while the run lasts.
    #[inline(always)]
    pub fn all(&mut self) -> *mut T {
        self.shared.data
    }

    /// The value of the run's partner `k`.
    #[inline(always)]
    pub fn partner(&mut self, k: usize) -> &mut T {
        let j = self.index[k] as usize;
        // SAFETY: as for `first`: `j` is a listed point of this chunk's blocks, and not `i`.
        unsafe { &mut *self.shared.data.add(j) }
    }
}

/// The values of a sweep, shared by its tasks, which write disjoint points.
struct SharedValues<T> {
    data: *mut T,
}

// SAFETY: the tasks of a class write the values of disjoint sets of points (module
// documentation), and classes are swept one after the other.
unsafe impl<T: Send> Sync for SharedValues<T> {}

/// `renumbered[old] = new` for the points `kept` (old indices, increasing) of `len`, and
/// [`GONE`] for the others.
pub fn renumbering(kept: &[u32], len: usize) -> Vec<u32> {
    let mut renumbered = vec![GONE; len];
    for (new, &old) in kept.iter().enumerate() {
        renumbered[old as usize] = new as u32;
    }
    renumbered
}

/// The new index of a point that is not kept.
pub const GONE: u32 = u32::MAX;

impl BlockChunk {
    /// Drops the rows and partners that `renumbered` maps to [`GONE`] and renumbers the
    /// rest, in place and in order.
    fn retain(&mut self, renumbered: &[u32]) {
        let (mut rows, mut pairs) = (0, 0);
        for r in 0..self.first.len() {
            let first = renumbered[self.first[r] as usize];
            let (s, e) = (self.start[r] as usize, self.start[r + 1] as usize);
            if first == GONE {
                continue;
            }
            let row_start = pairs;
            for k in s..e {
                let j = renumbered[self.second[k] as usize];
                self.second[pairs] = j;
                pairs += usize::from(j != GONE);
            }
            if pairs > row_start {
                self.first[rows] = first;
                self.start[rows] = row_start as u32;
                rows += 1;
            }
        }
        self.first.truncate(rows);
        self.start.truncate(rows);
        self.start.push(pairs as u32);
        self.second.truncate(pairs);
    }

    /// Lists the rows of the chunk's blocks: for each particle of a block, its partners within
    /// `sqrt(r2max)` of the block, in the block's order, the pairs of two points at or past
    /// `owned` left out.
    fn fill<V: Vector>(
        &mut self,
        grid: &CellGrid<V>,
        points: &[V],
        owned: usize,
        r2max: f64,
        period: &Periodicity<V>,
    ) {
        #[cfg(target_arch = "x86_64")]
        if std::any::TypeId::of::<V>() == std::any::TypeId::of::<glam::DVec3>()
            && !period.any()
            && crate::avx2::available()
        {
            // SAFETY: `V` is `DVec3` (checked), so each cast names the type it has; AVX2 is
            // present (checked) and `grid` indexes `points`.
            unsafe {
                let grid = &*(grid as *const CellGrid<V> as *const CellGrid<glam::DVec3>);
                let points = &*(points as *const [V] as *const [glam::DVec3]);
                self.fill_in_lanes(grid, points, owned, r2max);
            }
            return;
        }
        if period.any() {
            self.fill_with(grid, points, owned, r2max, |d| period.minimum_image(d));
        } else {
            self.fill_with(grid, points, owned, r2max, |d| d);
        }
    }

    /// [`BlockChunk::fill`] with `image` mapping a displacement to the one that counts (the
    /// minimum image across periodic axes). The candidates of a cell are kept without a
    /// branch per candidate, in blocks of [`KEPT_BLOCK`].
    #[inline(always)]
    fn fill_with<V: Vector>(
        &mut self,
        grid: &CellGrid<V>,
        points: &[V],
        owned: usize,
        r2max: f64,
        image: impl Fn(V) -> V,
    ) {
        self.first.clear();
        self.start.clear();
        self.second.clear();
        self.start.push(0);
        let corners = 1usize << V::DIM;
        let mut kept = [0u32; KEPT_BLOCK];
        for a in &self.anchors {
            let cells = grid.block_cells(*a);
            for d in 0..corners {
                let (s0, s1) = cells[d];
                for s in s0..s1 {
                    let p = grid.items[s] as usize;
                    let x = points[p];
                    // A halo particle keeps only partners below `owned`.
                    let last = if p >= owned { owned as u32 } else { u32::MAX };
                    for (d2, &(t0, t1)) in cells.iter().enumerate().take(corners).skip(d) {
                        if d2 & d != 0 {
                            continue;
                        }
                        let from = if d2 == d { s + 1 } else { t0 };
                        for candidates in grid.items[from..t1].chunks(KEPT_BLOCK) {
                            let mut n = 0usize;
                            for &q in candidates {
                                let r2 = image(points[q as usize] - x).length_squared();
                                kept[n % KEPT_BLOCK] = q;
                                n += usize::from((r2 < r2max) & (q < last));
                            }
                            self.second.extend_from_slice(&kept[..n]);
                        }
                    }
                    if self.second.len() > *self.start.last().unwrap() as usize {
                        self.first.push(p as u32);
                        self.start.push(self.second.len() as u32);
                    }
                }
            }
        }
    }

    /// Calls `visit(i, index, r_ij, r2)` with the runs of partners within `sqrt(r2max)` of
    /// each row's first particle `i` at `points`.
    #[inline(always)]
    fn sweep<V: Vector>(
        &self,
        points: &[V],
        r2max: f64,
        period: &Periodicity<V>,
        kept: &mut KeptBlock<V>,
        mut visit: impl FnMut(usize, &[u32], &[V], &[f64]),
    ) {
        let periodic = period.any();
        for (r, &i) in self.first.iter().enumerate() {
            let i = i as usize;
            let x = points[i];
            let partners = &self.second[self.start[r] as usize..self.start[r + 1] as usize];
            for chunk in partners.chunks(KEPT_BLOCK) {
                let n = if periodic {
                    kept.filter(
                        chunk
                            .iter()
                            .map(|&j| (j, period.minimum_image(points[j as usize] - x))),
                        r2max,
                    )
                } else {
                    kept.filter(chunk.iter().map(|&j| (j, points[j as usize] - x)), r2max)
                };
                if n > 0 {
                    visit(i, &kept.index[..n], &kept.offset[..n], &kept.r2[..n]);
                }
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::neighbours::grid::tests::{point_clouds, pseudo_random};
    use std::collections::BTreeSet;

    /// The keys of each point's partners within `radius` at the positions `at`, in the order
    /// a sweep meets them, from a list of the first `owned` points built at the positions
    /// `built` with a skin of `0.2 radius`; the listed pairs are met alike.
    fn partner_order<V: Vector>(
        (built, at): (&[V], &[V]),
        keys: &[u32],
        owned: usize,
        radius: f64,
        period: Periodicity<V>,
    ) -> Vec<Vec<u32>> {
        let reach = 1.2 * radius;
        let mut grid = CellGrid::with_period(reach, period).unwrap();
        grid.rebuild_keyed(built, keys);
        let mut list = PairBlocks::default();
        list.rebuild(&grid, built, owned, reach);
        let mut moved = vec![0];
        assert!(list.moved_points(at, 0.1 * radius, 0.1 * radius, &mut moved));
        assert!(moved.is_empty());
        let mut order = vec![Vec::new(); at.len()];
        list.sweep(at, radius, &mut order, |i, run, index, r_ij, r2| {
            for (k, &j) in index.iter().enumerate() {
                let expected = period.minimum_image(at[j as usize] - at[i]);
                assert_eq!((r_ij[k], r2[k]), (expected, expected.length_squared()));
                run.first().push(keys[j as usize]);
                run.partner(k).push(keys[i]);
            }
        });
        // The listed pairs: the same pairs in the same order, with their factors.
        let mut listed = ListedPairs::default();
        let factor = |r: f64| 1.0 + r;
        list.list(at, radius, factor, Listing::OffsetAndFactor, &mut listed);
        let mut again = vec![Vec::new(); at.len()];
        listed.sweep(&mut again, |i, run, index, r_ij, f| {
            for (k, &j) in index.iter().enumerate() {
                let expected = period.minimum_image(at[j as usize] - at[i]);
                assert_eq!((r_ij[k], f[k]), (expected, factor(expected.length())));
                run.first().push(keys[j as usize]);
                run.partner(k).push(keys[i]);
            }
        });
        assert_eq!(again, order);
        // Their products alone: the same pairs again, `r_ij F` rounded once to single
        // precision, to the bit.
        list.list(at, radius, factor, Listing::Product, &mut listed);
        let mut products = vec![Vec::new(); at.len()];
        listed.sweep(&mut products, |i, run, index, product, f| {
            assert!(f.is_empty());
            for (k, &j) in index.iter().enumerate() {
                let expected = period.minimum_image(at[j as usize] - at[i]);
                let exact = expected * factor(expected.length());
                let single: Vec<f64> = (0..V::DIM)
                    .map(|c| f64::from(exact.get(c) as f32))
                    .collect();
                assert_eq!(product[k], V::from_slice(&single));
                run.first().push(keys[j as usize]);
                run.partner(k).push(keys[i]);
            }
        });
        assert_eq!(products, order);
        assert_eq!(
            listed.pairs() * 2,
            order.iter().map(Vec::len).sum::<usize>()
        );
        // The kernel gradients of a Wendland kernel of that support, in vector lanes where
        // they apply (3-D, no periodic axis, AVX2): the scalar listing's rows, to the bit.
        let kernel = Wendland::for_dim::<V>(0.5 * radius);
        let rows = |listed: &ListedPairs<V>| {
            let mut rows = vec![Vec::new(); at.len()];
            listed.sweep(&mut rows, |_, run, index, product, _| {
                for (k, &j) in index.iter().enumerate() {
                    run.first().push((j, product[k].to_xyz().map(f64::to_bits)));
                }
            });
            rows
        };
        let gradient = |r| kernel.gradient_factor(r);
        list.list(at, kernel.support, gradient, Listing::Product, &mut listed);
        let scalar = rows(&listed);
        list.list_kernel_gradients(at, &kernel, &mut listed);
        assert_eq!(rows(&listed), scalar);
        assert_eq!(listed.listing(), Listing::Product);
        order
    }

    /// `points` each moved by just under half the skin in a pseudo-random direction.
    fn moved<V: Vector>(points: &[V], skin: f64, period: &Periodicity<V>) -> Vec<V> {
        let noise: Vec<f64> = pseudo_random(3 * points.len(), 11).collect();
        points
            .iter()
            .enumerate()
            .map(|(i, &p)| {
                let mut d = V::ZERO;
                for k in 0..V::DIM {
                    d.set(k, noise[3 * i + k] - 0.5);
                }
                period.wrap(p + d * (0.499 * skin / d.length().max(1e-300)))
            })
            .collect()
    }

    /// Every pair within the radius, at the build and after moves within half the skin, is
    /// met once from each side; a part (its own points and those within the listing radius
    /// of them) meets its own points' pairs in the order of the whole set.
    fn check<V: Vector>(points: Vec<V>, radius: f64, period: Periodicity<V>) {
        let n = points.len();
        let points: Vec<V> = points.into_iter().map(|p| period.wrap(p)).collect();
        let keys: Vec<u32> = (0..n as u32)
            .map(|k| k.wrapping_mul(2654435761) >> 4)
            .collect();
        let later = moved(&points, 0.2 * radius, &period);
        for at in [&points, &later] {
            let whole = partner_order((&points, at), &keys, n, radius, period);
            for i in 0..n {
                let brute: BTreeSet<u32> = (0..n)
                    .filter(|&j| {
                        j != i
                            && period.minimum_image(at[j] - at[i]).length_squared()
                                < radius * radius
                    })
                    .map(|j| keys[j])
                    .collect();
                let met: BTreeSet<u32> = whole[i].iter().copied().collect();
                assert_eq!(met.len(), whole[i].len(), "a pair of point {i} met twice");
                assert_eq!(met, brute, "partners of point {i}");
            }
            let own: Vec<usize> = (0..n).filter(|&i| points[i].get(1) < 0.25).collect();
            let reach = 1.2 * radius;
            let halo: Vec<usize> = (0..n)
                .filter(|&j| points[j].get(1) >= 0.25)
                .filter(|&j| {
                    own.iter().any(|&i| {
                        period.minimum_image(points[j] - points[i]).length_squared() < reach * reach
                    })
                })
                .collect();
            let members: Vec<usize> = own.iter().rev().chain(halo.iter().rev()).copied().collect();
            let pick = |v: &[V]| members.iter().map(|&i| v[i]).collect::<Vec<V>>();
            let part_keys: Vec<u32> = members.iter().map(|&i| keys[i]).collect();
            let (part_built, part_at) = (pick(&points), pick(at));
            let part = partner_order(
                (&part_built, &part_at),
                &part_keys,
                own.len(),
                radius,
                period,
            );
            for (k, &i) in members.iter().enumerate().take(own.len()) {
                assert_eq!(part[k], whole[i], "order of point {i} in the part");
            }
        }
        let mut grid = CellGrid::with_period(1.2 * radius, period).unwrap();
        grid.rebuild(&points);
        let mut list = PairBlocks::default();
        list.rebuild(&grid, &points, n, 1.2 * radius);
        let mut far = points.clone();
        let mut d = V::ZERO;
        d.set(0, 0.101 * radius);
        far[n / 2] = period.wrap(far[n / 2] + d);
        let mut moved = Vec::new();
        assert!(!list.moved_points(&far, 0.1 * radius, 0.1 * radius, &mut moved));
        assert!(list.moved_points(&far, 0.1 * radius, 0.2 * radius, &mut moved));
        assert_eq!(moved, [n as u32 / 2]);
        assert!(!list.moved_points(&points[1..], 0.1 * radius, radius, &mut moved));
    }

    /// After some points have moved past half the skin, the list lacks a pair exactly when a
    /// moved point has come within the radius of a point it was not listed with; when it
    /// lacks none, a sweep meets every pair within the radius.
    fn check_lacking<V: Vector>(points: Vec<V>, radius: f64, period: Periodicity<V>) {
        let n = points.len();
        let points: Vec<V> = points.into_iter().map(|p| period.wrap(p)).collect();
        let listing = 1.2 * radius;
        let mut grid = CellGrid::with_period(listing, period).unwrap();
        grid.rebuild(&points);
        let mut list = PairBlocks::default();
        list.rebuild(&grid, &points, n, listing);
        let noise: Vec<f64> = pseudo_random(3 * n, 5).collect();
        let (mut lacking, mut complete) = (0, 0);
        for step in 1..=12 {
            // Every 7th point moves step * 0.05 radii; the others a quarter of the skin.
            let at: Vec<V> = (0..n)
                .map(|i| {
                    let mut d = V::ZERO;
                    for k in 0..V::DIM {
                        d.set(k, noise[3 * i + k] - 0.5);
                    }
                    let far = if i % 7 == 0 { step as f64 * 0.05 } else { 0.05 };
                    period.wrap(points[i] + d * (far * radius / d.length().max(1e-300)))
                })
                .collect();
            let mut moved = Vec::new();
            assert!(list.moved_points(&at, 0.1 * radius, radius, &mut moved));
            assert!(moved.iter().all(|&i| i % 7 == 0));
            let mut now = CellGrid::with_period(listing, period).unwrap();
            now.rebuild(&at);
            let distance2 =
                |v: &[V], i: usize, j: usize| period.minimum_image(v[j] - v[i]).length_squared();
            let truth = moved.iter().any(|&i| {
                let i = i as usize;
                (0..n).any(|j| {
                    j != i
                        && distance2(&at, i, j) < radius * radius
                        && distance2(&points, i, j) >= listing * listing
                })
            });
            let lacks = list.lacks_pair(&now, &at, &moved, radius);
            assert_eq!(lacks, truth, "moves of {step} x 0.05 radii");
            if lacks {
                lacking += 1;
                continue;
            }
            complete += 1;
            let mut met = vec![0usize; n];
            list.sweep(&at, radius, &mut met, |_, run, index, _, _| {
                *run.first() += index.len();
                for k in 0..index.len() {
                    *run.partner(k) += 1;
                }
            });
            for (i, &count) in met.iter().enumerate() {
                let brute = (0..n)
                    .filter(|&j| j != i && distance2(&at, i, j) < radius * radius)
                    .count();
                assert_eq!(count, brute, "partners of point {i}");
            }
        }
        assert!(
            lacking > 0 && complete > 0,
            "{lacking} lacking, {complete} complete"
        );
    }

    #[test]
    fn every_pair_once_after_moves_within_half_the_skin_in_the_order_of_the_whole_set() {
        let (p2, period2, p3, period3) = point_clouds(7);
        check(p2.clone(), 0.07, Periodicity::none());
        check(p2, 0.07, period2);
        check(p3.clone(), 0.13, Periodicity::none());
        check(p3, 0.13, period3);
    }

    /// A list that drops some points meets the others' pairs in the order of a list built
    /// over those alone, own and halo points alike.
    fn check_retained<V: Vector>(points: Vec<V>, radius: f64, period: Periodicity<V>) {
        let n = points.len();
        let points: Vec<V> = points.into_iter().map(|p| period.wrap(p)).collect();
        let keys: Vec<u32> = (0..n as u32)
            .map(|k| k.wrapping_mul(2654435761) >> 4)
            .collect();
        let owned = n - n / 4;
        let build = |points: &[V], keys: &[u32], owned: usize| {
            let mut grid = CellGrid::with_period(radius, period).unwrap();
            grid.rebuild_keyed(points, keys);
            let mut list = PairBlocks::default();
            list.rebuild(&grid, points, owned, radius);
            list
        };
        let order = |points: &[V], keys: &[u32], owned: usize, list: Option<PairBlocks<V>>| {
            let list = list.unwrap_or_else(|| build(points, keys, owned));
            let mut met = vec![Vec::new(); points.len()];
            list.sweep(points, radius, &mut met, |i, run, index, _, _| {
                for (k, &j) in index.iter().enumerate() {
                    run.first().push(keys[j as usize]);
                    run.partner(k).push(keys[i]);
                }
            });
            met
        };
        let mut list = build(&points, &keys, owned);
        let kept: Vec<u32> = (0..n as u32).filter(|i| i % 5 != 2).collect();
        let kept_owned = kept.iter().filter(|&&i| (i as usize) < owned).count();
        list.retain(&kept, kept_owned);
        let pick = |v: &[u32]| kept.iter().map(|&i| v[i as usize]).collect::<Vec<u32>>();
        let remaining: Vec<V> = kept.iter().map(|&i| points[i as usize]).collect();
        assert_eq!(list.origin(), &remaining[..]);
        let kept_keys = pick(&keys);
        assert_eq!(
            order(&remaining, &kept_keys, kept_owned, Some(list)),
            order(&remaining, &kept_keys, kept_owned, None)
        );
    }

    #[test]
    fn a_list_without_removed_points_meets_the_pairs_of_one_built_without_them() {
        let (p2, period2, p3, period3) = point_clouds(13);
        check_retained(p2.clone(), 0.07, Periodicity::none());
        check_retained(p2, 0.07, period2);
        check_retained(p3.clone(), 0.13, Periodicity::none());
        check_retained(p3, 0.13, period3);
    }

    /// The build lists the rows of the scalar build, partner for partner, own and halo points
    /// alike (in 3-D without periodic axes the build takes the vector lanes where the
    /// processor has them).
    #[test]
    fn the_build_lists_the_rows_of_the_scalar_build() {
        let (_, _, points, _) = point_clouds(11);
        let (n, radius) = (points.len(), 0.13);
        let owned = n - n / 4;
        let mut grid = CellGrid::new(radius);
        grid.rebuild(&points);
        let mut list = PairBlocks::default();
        list.rebuild(&grid, &points, owned, radius);
        let mut pairs = 0;
        for chunk in list.classes.iter().flatten() {
            let mut scalar = chunk.clone();
            scalar.fill_with(&grid, &points, owned, radius * radius, |d| d);
            assert_eq!(chunk.first, scalar.first);
            assert_eq!(chunk.start, scalar.start);
            assert_eq!(chunk.second, scalar.second);
            pairs += chunk.second.len();
        }
        assert!(pairs > 2 * n, "{pairs} pairs of {n} points");
    }

    #[test]
    fn a_kept_list_lacks_a_pair_exactly_when_a_moved_point_met_an_unlisted_one() {
        let (p2, period2, p3, period3) = point_clouds(7);
        check_lacking(p2.clone(), 0.07, Periodicity::none());
        check_lacking(p2, 0.07, period2);
        check_lacking(p3.clone(), 0.13, Periodicity::none());
        check_lacking(p3, 0.13, period3);
    }
}
