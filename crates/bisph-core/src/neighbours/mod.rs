//! Fixed-radius neighbour search: a uniform cell grid ([`CellGrid`]) and the fluid's Verlet
//! list ([`PairBlocks`]), and the Verlet list between two point sets ([`CandidateRows`]).
//!
//! Cells have the side of the kernel support, so every neighbour of a point lies in the
//! `3^d` cells around it. The grid is rebuilt every step by a counting sort (no per-step
//! allocation once the buffers have grown; cell indices are computed in parallel); for the fluid the sort order is also used to
//! reorder the particles themselves, so a cell's particles are contiguous in memory.
//!
//! **Each pair once.** The fluid's Verlet list ([`PairBlocks`]) holds each pair once, in
//! blocks of cells that a sweep takes class by class, so that a pair is evaluated once for
//! both of its particles without two threads writing one particle.
//!
//! **Storage order.** Points are sorted by *row* of cells (the cells sharing `y` and `z`),
//! rows in the order of a Morton (Z-order) curve over `(y, z)` (plain row order in 2-D), and
//! by cell along `x` within a row. A run of consecutive cells along `x` is then one contiguous
//! range of sorted slots, so the `3^d` cells around a point are `3^(d-1)` ranges. Once the
//! particles have been reordered into this order ([`CellGrid::mark_reordered`]), slot and
//! point index coincide and a neighbour query streams through contiguous slices of the
//! position array.
//!
//! **Periodic axes.** Along an axis of a [`Periodicity`] the grid spans exactly one period
//! `[min, min + L)` with `floor(L / cell)` cells (so cells are at least `cell` wide), and the
//! cells around a point wrap around. Every visited point comes with the shift (a multiple of
//! `L` per periodic axis) that brings its image next to the query point; the neighbour
//! queries hand out the minimum-image displacement `r_ij = points[j] + shift - x`, so pair
//! terms never see a raw position difference across the period. Stored points must lie in
//! the primary period (see [`Periodicity::wrap`]); periods must hold at least three cells.

mod candidate_rows;
mod grid;
mod pair_blocks;

pub use candidate_rows::{CandidateRows, Nearby};

pub use grid::{CellGrid, KeptBlock, PairList, Periodicity, KEPT_BLOCK};
pub use pair_blocks::{
    renumbering, single_precision, ListedPairs, Listing, PairBlocks, RunValues, GONE,
};
