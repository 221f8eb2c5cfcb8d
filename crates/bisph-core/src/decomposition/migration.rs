//! Migration: which points change part when the points move or the regions change.
//!
//! Each part computes its own [`Departures`] from its own points alone (on a distributed run,
//! each process from its local arrays); the [`MigrationPlan`] is all of them. Applying a
//! plan keeps each part's staying points in their order and appends the arrivals ordered by
//! global id, so the result does not depend on the order in which parts send.

use super::bisection::Decomposition;
use super::GlobalId;
use crate::dim::Vector;
use crate::neighbours::Periodicity;

/// The points one part sends away: for each destination part, the local indices of the
/// points whose owner under the new decomposition is that part.
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct Departures {
    /// For each destination part with at least one point to receive, in increasing part
    /// order: the destination and the local indices (increasing) of the points sent there.
    pub to: Vec<(usize, Vec<usize>)>,
}

impl Departures {
    /// The departures from part `from`, whose points are at `positions`, under the
    /// decomposition `target`: a point leaves when [`Decomposition::owner`] of its position
    /// (wrapped into the primary period of `period` first) is another part.
    pub fn of_part<V: Vector>(
        from: usize,
        positions: &[V],
        target: &Decomposition<V>,
        period: &Periodicity<V>,
    ) -> Self {
        let mut by_destination: Vec<Vec<usize>> = vec![Vec::new(); target.parts()];
        for (i, &x) in positions.iter().enumerate() {
            let owner = target.owner(period.wrap(x));
            if owner != from {
                by_destination[owner].push(i);
            }
        }
        Departures {
            to: by_destination
                .into_iter()
                .enumerate()
                .filter(|(_, indices)| !indices.is_empty())
                .collect(),
        }
    }

    /// Number of points leaving.
    pub fn count(&self) -> usize {
        self.to.iter().map(|(_, indices)| indices.len()).sum()
    }

    /// Number of points sent to part `to`.
    pub fn count_to(&self, to: usize) -> usize {
        self.to
            .iter()
            .find(|(part, _)| *part == to)
            .map_or(0, |(_, indices)| indices.len())
    }

    /// The destination of each of `len` local points (`None` for the points that stay).
    pub fn destinations(&self, len: usize) -> Vec<Option<usize>> {
        let mut destination = vec![None; len];
        for (part, indices) in &self.to {
            for &i in indices {
                destination[i] = Some(*part);
            }
        }
        destination
    }
}

/// The departures of every part (indexed by the part they leave), from the current
/// parts to the parts of a new decomposition (which may have another number of parts).
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct MigrationPlan {
    /// Departures of each current part.
    pub departures: Vec<Departures>,
    /// Number of parts after the migration.
    pub target_parts: usize,
}

/// The plan that moves each point of `parts` (the positions held by each current part) to
/// its owner under `target` (see [`Departures::of_part`]).
pub fn plan_migration<V: Vector>(
    parts: &[Vec<V>],
    target: &Decomposition<V>,
    period: &Periodicity<V>,
) -> MigrationPlan {
    MigrationPlan {
        departures: parts
            .iter()
            .enumerate()
            .map(|(from, positions)| Departures::of_part(from, positions, target, period))
            .collect(),
        target_parts: target.parts(),
    }
}

impl MigrationPlan {
    /// Number of points that change part.
    pub fn moved(&self) -> usize {
        self.departures.iter().map(Departures::count).sum()
    }

    /// Number of points that go from part `from` to part `to`.
    pub fn count(&self, from: usize, to: usize) -> usize {
        self.departures.get(from).map_or(0, |d| d.count_to(to))
    }

    /// Moves the items of `parts` (one vector per current part, in the order the plan was
    /// made from) to their new parts: each part keeps its staying items in their order and
    /// then receives the arriving ones in increasing global id (`id_of`). Afterwards `parts`
    /// has one vector per part of the target decomposition.
    ///
    /// # Panics
    /// When `parts` does not have one vector per current part, or a part that the target
    /// decomposition drops still holds staying items.
    pub fn apply<T>(&self, parts: &mut Vec<Vec<T>>, id_of: impl Fn(&T) -> GlobalId) {
        assert_eq!(
            parts.len(),
            self.departures.len(),
            "one vector per current part"
        );
        let mut arriving: Vec<Vec<T>> = (0..self.target_parts).map(|_| Vec::new()).collect();
        for (items, departures) in parts.iter_mut().zip(&self.departures) {
            let destinations = departures.destinations(items.len());
            let mut staying = Vec::with_capacity(items.len() - departures.count());
            for (item, destination) in std::mem::take(items).into_iter().zip(destinations) {
                match destination {
                    Some(to) => arriving[to].push(item),
                    None => staying.push(item),
                }
            }
            *items = staying;
        }
        if parts.len() > self.target_parts {
            assert!(
                parts[self.target_parts..].iter().all(Vec::is_empty),
                "a dropped part still holds items"
            );
        }
        parts.resize_with(self.target_parts, Vec::new);
        for (items, mut arrivals) in parts.iter_mut().zip(arriving) {
            arrivals.sort_by_key(&id_of);
            items.extend(arrivals);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::decomposition::bisection::bisect;
    use crate::decomposition::bounds::Bounds;
    use crate::decomposition::test_support::XorShift;
    use glam::{DVec2, DVec3};

    #[derive(Clone, Copy, Debug, PartialEq)]
    struct Particle<V> {
        id: GlobalId,
        x: V,
    }

    fn positions<V: Vector>(parts: &[Vec<Particle<V>>]) -> Vec<Vec<V>> {
        parts
            .iter()
            .map(|p| p.iter().map(|q| q.x).collect())
            .collect()
    }

    /// Random points in a unit box, periodic along x; decomposed into `old_parts`, moved
    /// and reweighted, decomposed into `new_parts`, then migrated.
    fn check_migration<V: Vector>(seed: u64, old_parts: usize, new_parts: usize) {
        let mut rng = XorShift::new(seed);
        let n = 1500;
        let mut one = V::ZERO;
        for k in 0..V::DIM {
            one.set(k, 1.0);
        }
        let mut period = Periodicity::<V>::none();
        period.length.set(0, 1.0);
        let particles: Vec<Particle<V>> = (0..n)
            .map(|i| Particle {
                id: 1000 + 7 * i as u32,
                x: rng.point_in(V::ZERO, one),
            })
            .collect();
        let xs: Vec<V> = particles.iter().map(|p| p.x).collect();
        let ids: Vec<GlobalId> = particles.iter().map(|p| p.id).collect();
        let old = bisect(&xs, &vec![1.0; n], &ids, old_parts, Bounds::everywhere());
        let mut parts: Vec<Vec<Particle<V>>> = vec![Vec::new(); old_parts];
        for p in &particles {
            parts[old.owner(p.x)].push(*p);
        }
        for part in parts.iter_mut() {
            rng.shuffle(part); // local storage order is arbitrary
            for p in part.iter_mut() {
                p.x += rng.point_in(one * -0.2, one * 0.2); // may leave the period along x
            }
        }
        let moved_x: Vec<V> = parts.iter().flatten().map(|p| period.wrap(p.x)).collect();
        let moved_ids: Vec<GlobalId> = parts.iter().flatten().map(|p| p.id).collect();
        let weights: Vec<f64> = moved_x.iter().map(|x| 1.0 + 3.0 * x.get(0)).collect();
        let new = bisect(
            &moved_x,
            &weights,
            &moved_ids,
            new_parts,
            Bounds::everywhere(),
        );

        let plan = plan_migration(&positions(&parts), &new, &period);
        let before = parts.clone();
        let changing = before
            .iter()
            .enumerate()
            .flat_map(|(from, part)| part.iter().map(move |p| (from, p)))
            .filter(|(from, p)| new.owner(period.wrap(p.x)) != *from)
            .count();
        assert_eq!(plan.moved(), changing);
        plan.apply(&mut parts, |p| p.id);

        assert_eq!(parts.len(), new_parts);
        let mut after_ids: Vec<GlobalId> = parts.iter().flatten().map(|p| p.id).collect();
        after_ids.sort_unstable();
        let mut all_ids = ids.clone();
        all_ids.sort_unstable();
        assert_eq!(after_ids, all_ids, "particles lost, duplicated or invented");
        for (part, items) in parts.iter().enumerate() {
            for p in items {
                assert_eq!(
                    new.owner(period.wrap(p.x)),
                    part,
                    "particle {} misplaced",
                    p.id
                );
            }
            // Staying items first, in their old order; then arrivals by increasing id.
            let stayed = before.get(part).map_or(0, |b| {
                b.iter()
                    .filter(|p| new.owner(period.wrap(p.x)) == part)
                    .count()
            });
            let kept: Vec<_> = before.get(part).map_or(Vec::new(), |b| {
                b.iter()
                    .filter(|p| new.owner(period.wrap(p.x)) == part)
                    .copied()
                    .collect()
            });
            assert_eq!(items[..stayed], kept[..]);
            assert!(items[stayed..].windows(2).all(|w| w[0].id < w[1].id));
            for (from, sender) in before.iter().enumerate() {
                let sent = sender
                    .iter()
                    .filter(|p| from != part && new.owner(period.wrap(p.x)) == part)
                    .count();
                assert_eq!(plan.count(from, part), sent);
            }
        }
    }

    #[test]
    fn migration_conserves_particles_and_ids() {
        for (seed, (old_parts, new_parts)) in [
            (1, 1),
            (2, 2),
            (3, 3),
            (4, 4),
            (2, 5),
            (5, 3),
            (7, 7),
            (6, 1),
        ]
        .into_iter()
        .enumerate()
        {
            check_migration::<DVec2>(seed as u64, old_parts, new_parts);
            check_migration::<DVec3>(100 + seed as u64, old_parts, new_parts);
        }
    }

    #[test]
    fn applying_a_plan_twice_moves_nothing_the_second_time() {
        let mut rng = XorShift::new(3);
        let xs: Vec<DVec2> = (0..400)
            .map(|_| rng.point_in(DVec2::ZERO, DVec2::ONE))
            .collect();
        let ids: Vec<u32> = (0..400).collect();
        let d = bisect(&xs, &vec![1.0; 400], &ids, 4, Bounds::everywhere());
        let mut parts = vec![
            xs[..200]
                .iter()
                .zip(0..)
                .map(|(&x, id)| Particle { id, x })
                .collect(),
            xs[200..]
                .iter()
                .zip(200..)
                .map(|(&x, id)| Particle { id, x })
                .collect(),
            Vec::new(),
            Vec::new(),
        ];
        let plan = plan_migration(&positions(&parts), &d, &Periodicity::none());
        assert!(plan.moved() > 0);
        plan.apply(&mut parts, |p| p.id);
        let again = plan_migration(&positions(&parts), &d, &Periodicity::none());
        assert_eq!(again.moved(), 0);
        assert!(parts.iter().all(|p| !p.is_empty()));
    }
}
