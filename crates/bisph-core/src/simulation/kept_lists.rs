//! When the Verlet lists of a step may be kept.
//!
//! The lists hold the pairs within the support plus a skin at their build. While no particle
//! has moved more than half the skin, no pair can have come within the support unlisted. A
//! few fast particles (the spray of a breaking wave) would force a rebuild every step or two,
//! so the lists are also kept while at most [`MOVED_SHARE`] of the particles have moved more
//! than half the skin, none more than [`DRIFT_LIMIT`] skins, and a search around each of
//! them finds no fluid partner and no wall element within reach that the lists lack.
//!
//! The cell grid then indexes the current positions (its cells, one listing radius wide, hold
//! every neighbour of a point only while points lie within half a skin of where the grid put
//! them), and the wall-distance bounds of the moved particles are dropped. Which grid is in
//! use is a function of the positions and those of the build alone, so a resumed run takes
//! the same decisions as one never stopped; every part of a split run takes them from the
//! same totals.

use super::Simulation;
use crate::decomposition::ExactSum;
use crate::dim::Vector;

/// Largest share of the particles that may have moved past half the skin with the lists
/// kept: the search around each costs about as much as listing its pairs.
pub(crate) const MOVED_SHARE: f64 = 1.0 / 16.0;

/// Farthest a particle may have moved since the build with the lists kept, in skins: the
/// halo of a split run is two such drifts wider than the listing radius needs.
pub(crate) const DRIFT_LIMIT: f64 = 2.0;

impl<V: Vector> Simulation<V> {
    /// Farthest a particle may move from where the lists were built while they are kept.
    pub(crate) fn drift_limit(&self) -> f64 {
        DRIFT_LIMIT * self.scratch.skin
    }

    /// Whether the Verlet lists hold the pairs within reach at the current positions (see the
    /// module documentation); places the cell grid for the step. Every part of a split run
    /// must call it.
    pub(crate) fn lists_hold(&mut self) -> bool {
        let half = 0.5 * self.scratch.skin;
        let limit = self.drift_limit();
        let mut moved = std::mem::take(&mut self.scratch.moved);
        moved.clear();
        let s = &self.scratch;
        let within = s.candidates_valid
            && s.candidates
                .moved_points(&self.fluid.position, half, limit, &mut moved);
        let owned = self.owned_len();
        let own_moved = moved.partition_point(|&i| (i as usize) < owned);
        // The moved particles and all particles of the run, in one exchange.
        let mut totals = [own_moved as f64, owned as f64].map(|n| {
            let mut sum = ExactSum::new();
            sum.add(n);
            sum
        });
        self.sum_over_parts(&mut totals);
        let (moved_total, total) = (totals[0].value(), totals[1].value());
        let few = moved_total <= MOVED_SHARE * total;
        self.scratch.moved_anywhere = moved_total > 0.0;
        // Otherwise the step rebuilds the grid with the lists.
        if within && few {
            self.place_fluid_grid(moved_total > 0.0);
        }
        let lacks = within && few && moved_total > 0.0 && self.lists_lack_pairs(&moved, own_moved);
        let holds = within && few && !lacks;
        if holds {
            self.wall_clearance.forget_points(&moved);
        }
        self.scratch.moved = moved;
        holds
    }

    /// Rebuilds the cell grid over the current positions where some particle has moved past
    /// half the skin, or along periodic axes (where particles wrap); else puts it back over
    /// the positions of the build.
    fn place_fluid_grid(&mut self, moved: bool) {
        let s = &mut self.scratch;
        if moved || self.config.periodicity.any() {
            self.fluid_grid
                .rebuild_keyed(&self.fluid.position, &self.fluid.id);
            s.grid_at_build = false;
        } else if !s.grid_at_build {
            self.fluid_grid
                .rebuild_keyed(s.candidates.origin(), &self.fluid.id);
            s.grid_at_build = true;
        }
    }

    /// Whether a search around the `moved` particles (the first `own_moved` of them own)
    /// finds a fluid pair or a particle-element pair within reach that the lists lack.
    fn lists_lack_pairs(&self, moved: &[u32], own_moved: usize) -> bool {
        let s = &self.scratch;
        let position = &self.fluid.position;
        let support = self.config.kernel.support;
        if s.candidates
            .lacks_pair(&self.fluid_grid, position, moved, support)
        {
            return true;
        }
        if !s.wall_rows_valid {
            return false;
        }
        let (grid, centres) = (&self.walls.grid, &self.walls.elements.centre);
        let origin = s.candidates.origin();
        s.particle_element_rows.lacks_fixed_partner(
            grid,
            centres,
            &moved[..own_moved],
            position,
            origin,
        ) || s
            .element_particle_rows
            .lacks_fixed_partner(grid, centres, moved, position, origin)
    }

    /// Keeps the neighbour lists, and the wall-distance bounds, of the particles `kept` (old
    /// indices of `len` particles, increasing; the first `owned` are own) after the others
    /// were removed, renumbered in that order: the pairs of the remaining particles, where
    /// they were, as a build at the list's build positions would list them. The cell grid
    /// is rebuilt over the current positions (the next step places it, [`Self::lists_hold`]).
    /// Without a valid list, the next step builds one.
    pub(crate) fn keep_lists_of(&mut self, kept: &[u32], len: usize, owned: usize) {
        let s = &mut self.scratch;
        s.moved.clear();
        if !(s.skin > 0.0 && s.candidates_valid) {
            s.candidates_valid = false;
            self.wall_clearance.forget();
            return;
        }
        s.candidates.retain(kept, owned);
        if s.wall_rows_valid {
            s.particle_element_rows.retain_queries(&kept[..owned]);
            s.element_particle_rows.retain_points(kept, len);
        }
        self.wall_clearance.retain(kept);
        self.fluid_grid
            .rebuild_keyed(&self.fluid.position, &self.fluid.id);
        s.grid_at_build = false;
    }
}
