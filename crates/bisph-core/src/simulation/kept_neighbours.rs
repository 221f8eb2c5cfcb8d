//! The Verlet list a run keeps across steps while no particle has moved more than half the
//! skin: each pair once for the explicit scheme, whose sweep adds a pair's shares to both
//! particles; each particle's candidates for the midpoint scheme, which lists its pairs with
//! their kernel gradients once per step from them.

use crate::dim::Vector;
use crate::neighbours::{CandidateList, CellGrid, PairBlocks};

/// A Verlet list of one of the two kinds (see the module documentation).
#[derive(Clone, Debug)]
pub(crate) enum KeptNeighbours<V> {
    /// Each particle's candidates.
    Candidates(CandidateList<V>),
    /// Each pair once.
    Pairs(PairBlocks<V>),
}

impl<V: Default> Default for KeptNeighbours<V> {
    fn default() -> Self {
        KeptNeighbours::Candidates(CandidateList::default())
    }
}

impl<V: Vector> KeptNeighbours<V> {
    /// Lists the points within `radius` (at most one cell of `grid`, which indexes `points`)
    /// of the first `owned` points, each pair once when `pairs`.
    pub fn rebuild(
        &mut self,
        pairs: bool,
        grid: &CellGrid<V>,
        points: &[V],
        owned: usize,
        radius: f64,
    ) {
        match self {
            KeptNeighbours::Pairs(list) if pairs => list.rebuild(grid, points, owned, radius),
            KeptNeighbours::Candidates(list) if !pairs => {
                list.rebuild_for(grid, points, owned, radius)
            }
            _ => {
                *self = if pairs {
                    KeptNeighbours::Pairs(PairBlocks::default())
                } else {
                    KeptNeighbours::Candidates(CandidateList::default())
                };
                self.rebuild(pairs, grid, points, owned, radius);
            }
        }
    }

    /// `true` when no point has moved more than `drift` since the build.
    pub fn holds(&self, points: &[V], drift: f64) -> bool {
        match self {
            KeptNeighbours::Candidates(list) => list.holds(points, drift),
            KeptNeighbours::Pairs(list) => list.holds(points, drift),
        }
    }

    /// The points as they were at the build.
    pub fn origin(&self) -> &[V] {
        match self {
            KeptNeighbours::Candidates(list) => list.origin(),
            KeptNeighbours::Pairs(list) => list.origin(),
        }
    }

    /// The listed pairs of each of the first `n` points (as candidates, or as either
    /// particle of a pair).
    pub fn counts(&self, n: usize) -> Vec<u32> {
        match self {
            KeptNeighbours::Candidates(list) => (0..n).map(|i| list.count(i) as u32).collect(),
            KeptNeighbours::Pairs(list) => {
                let mut counts = list.pair_counts();
                counts.resize(n, 0);
                counts
            }
        }
    }
}
