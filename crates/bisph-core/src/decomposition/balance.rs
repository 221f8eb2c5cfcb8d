//! Load balance: how unevenly the work is spread over the parts, and when to cut again.

use super::exact_sum::ExactSum;

/// The work of each of `parts` parts: the exact sum ([`ExactSum`]) of the `weights` of the
/// points each part owns (`owners[i]` is the part of point `i`).
///
/// # Panics
/// When the slices differ in length or an owner is not below `parts`.
pub fn part_loads(owners: &[usize], weights: &[f64], parts: usize) -> Vec<f64> {
    assert_eq!(owners.len(), weights.len(), "one weight per point");
    let mut sums = vec![ExactSum::new(); parts];
    for (&owner, &weight) in owners.iter().zip(weights) {
        sums[owner].add(weight);
    }
    sums.iter().map(ExactSum::value).collect()
}

/// The imbalance of the loads of the parts: the largest load over the mean load (1 for an
/// even spread, `K` when one of `K` parts has all the work). 1 when there is no work.
pub fn imbalance(loads: &[f64]) -> f64 {
    let total = super::exact_sum(loads.iter().copied());
    if loads.is_empty() || total <= 0.0 {
        return 1.0;
    }
    let largest = loads.iter().copied().fold(f64::NEG_INFINITY, f64::max);
    largest * loads.len() as f64 / total
}

/// When to decompose again: once the [`imbalance`] of the measured loads exceeds
/// `threshold`. Every process that decides from the same loads decides alike.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct RebalancePolicy {
    /// Largest tolerated imbalance (at least 1; 1.1 accepts a slowest part 10% above the
    /// mean).
    pub threshold: f64,
}

impl RebalancePolicy {
    /// `true` when the imbalance of `loads` is above the threshold.
    pub fn should_rebalance(&self, loads: &[f64]) -> bool {
        imbalance(loads) > self.threshold
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::decomposition::bisection::{bisect, Decomposition};
    use crate::decomposition::bounds::Bounds;
    use glam::DVec2;

    #[test]
    fn imbalance_is_the_largest_load_over_the_mean() {
        assert_eq!(imbalance(&[1.0, 1.0, 1.0, 1.0]), 1.0);
        assert_eq!(imbalance(&[2.0, 1.0, 1.0, 0.0]), 2.0);
        assert_eq!(imbalance(&[0.0, 0.0, 6.0]), 3.0);
        assert_eq!(imbalance(&[0.0, 0.0]), 1.0);
        assert_eq!(imbalance(&[]), 1.0);
        let policy = RebalancePolicy { threshold: 1.5 };
        assert!(
            !policy.should_rebalance(&[1.5, 0.5]),
            "at the threshold: no"
        );
        assert!(policy.should_rebalance(&[1.6, 0.4]));
        assert!(!policy.should_rebalance(&[1.4, 0.6]));
    }

    #[test]
    fn part_loads_sum_the_weights_of_each_part() {
        let loads = part_loads(&[0, 2, 2, 0, 1], &[1.0, 2.0, 3.0, 0.5, 0.25], 4);
        assert_eq!(loads, vec![1.5, 0.25, 5.0, 0.0]);
    }

    /// A 2-D water column `[0, 1] x [0, 2]` that collapses into a layer `[0, 4] x [0, 0.5]`
    /// (area kept: `x' = x s`, `y' = y / s`, `s` from 1 to 4).
    fn column_at(stage: f64) -> Vec<DVec2> {
        let s = 1.0 + 3.0 * stage;
        let mut points = Vec::new();
        for i in 0..100 {
            for j in 0..200 {
                let x = (i as f64 + 0.5) * 0.01;
                let y = (j as f64 + 0.5) * 0.01;
                points.push(DVec2::new(x * s, y / s));
            }
        }
        points
    }

    /// Work per particle: more near the bottom, where the pressure is high and the flow
    /// fastest (any positive measure would do).
    fn work(points: &[DVec2]) -> Vec<f64> {
        points
            .iter()
            .map(|p| 1.0 + 1.0 / (1.0 + 4.0 * p.y))
            .collect()
    }

    fn first_cut(d: &Decomposition<DVec2>) -> (usize, f64) {
        let cut = d.cuts().next().expect("K > 1 has a cut");
        (cut.axis, cut.position)
    }

    fn check_collapse(parts: usize) {
        let policy = RebalancePolicy { threshold: 1.1 };
        let ids: Vec<u32> = (0..20_000).collect();
        let start = column_at(0.0);
        let mut d = bisect(&start, &work(&start), &ids, parts, Bounds::everywhere());
        assert_eq!(first_cut(&d).0, 1, "a tall column is cut across its height");
        let mut rebalances = 0;
        for step in 0..=20 {
            let points = column_at(step as f64 / 20.0);
            let weights = work(&points);
            let loads = part_loads(&d.owners(&points), &weights, parts);
            if step == 0 {
                assert!(!policy.should_rebalance(&loads), "the start is balanced");
            }
            if policy.should_rebalance(&loads) {
                d = bisect(&points, &weights, &ids, parts, Bounds::everywhere());
                rebalances += 1;
                let balanced = part_loads(&d.owners(&points), &weights, parts);
                // A lattice row or column moves as a whole: up to 1% of the work, so 3% of a
                // third, is the resolution of a cut.
                assert!(imbalance(&balanced) < 1.03, "K = {parts}: {balanced:?}");
            }
        }
        assert!(
            rebalances >= 1,
            "K = {parts}: the load moved but the cut did not"
        );
        let end = column_at(1.0);
        let loads = part_loads(&d.owners(&end), &work(&end), parts);
        assert!(
            imbalance(&loads) <= policy.threshold,
            "K = {parts}: {loads:?}"
        );
        let (axis, position) = first_cut(&d);
        assert_eq!(
            axis, 0,
            "K = {parts}: the spread layer is cut along its length"
        );
        // Within the threshold's tolerance of the even split of the layer's length.
        let expected = 4.0 * (parts / 2) as f64 / parts as f64;
        assert!(
            (position - expected).abs() < 0.4,
            "K = {parts}: cut at {position}"
        );
    }

    #[test]
    fn a_collapsing_column_moves_the_cut_from_across_its_height_to_along_the_bottom() {
        for parts in 2..=4 {
            check_collapse(parts);
        }
    }
}
