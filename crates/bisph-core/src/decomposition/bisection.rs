//! Recursive coordinate bisection of weighted points.
//!
//! A set of points to be split into `K` parts is cut by a plane normal to the longest extent
//! of its bounding box into `floor(K/2)` parts below the plane and `ceil(K/2)` above, with the
//! weight divided in the same ratio; each side is cut again until every part is one region.
//!
//! **The cut rule.** Along the chosen axis the points are ordered by coordinate (then by
//! global id, so the order is total). A plane can only pass between two distinct coordinates;
//! among those places it takes the one whose weight below is nearest to the target
//! `W floor(K/2) / K` (the lower one on a tie), at a coordinate strictly above the last point
//! below and at most the first point above. The weights below are exact sums
//! ([`ExactSum`]), so the cut depends only on the positions and weights, neither on the order
//! in which the points are given nor on how the sum is grouped: a distributed search
//! that counts weights below a trial plane on each process and reduces them exactly finds the
//! same plane. Points with equal coordinates always fall on the same side.

use super::bounds::Bounds;
use super::exact_sum::ExactSum;
use super::GlobalId;
use crate::dim::Vector;
use crate::neighbours::Periodicity;

/// One cutting plane of a [`Decomposition`]: points with `x[axis] < position` belong to the
/// parts `first_part..first_part + below`, the others to the next `above` parts.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Cut {
    /// Axis normal to the plane.
    pub axis: usize,
    /// Coordinate of the plane along `axis`.
    pub position: f64,
    /// First part of the points this cut divides.
    pub first_part: usize,
    /// Number of parts below the plane (`floor(K/2)` of the `K` parts divided).
    pub below: usize,
    /// Number of parts above the plane (`ceil(K/2)`).
    pub above: usize,
}

/// A node of the cut tree (children follow in pre-order).
#[derive(Clone, Debug, PartialEq)]
enum Node {
    /// A final part.
    Part(usize),
    /// A plane; `above` is the index of the node of the upper side (the lower side's node
    /// follows this one).
    Split { cut: Cut, above: usize },
}

/// The result of [`bisect`]: a tree of cutting planes whose leaves are the parts `0..K`
/// (numbered from the lower side of each plane to the upper), and each part's region.
#[derive(Clone, Debug, PartialEq)]
pub struct Decomposition<V> {
    nodes: Vec<Node>,
    regions: Vec<Bounds<V>>,
    domain: Bounds<V>,
}

/// A point being sorted into parts.
#[derive(Clone, Copy, Debug)]
struct Item<V> {
    x: V,
    weight: f64,
    id: GlobalId,
}

/// Splits the points `points` (with work `weights` and unique global `ids`) into `parts`
/// regions by recursive coordinate bisection (see the module documentation for the cut
/// rule). Regions are cut out of `domain` (use [`Bounds::everywhere`] for unbounded outer
/// regions). Weights must be finite and non-negative; when none is positive every point
/// weighs one. With fewer distinct points than parts some parts are empty.
///
/// # Panics
/// When `parts` is zero, the slices differ in length, a weight is negative or not finite,
/// or `domain` has `lo > hi` along an axis.
pub fn bisect<V: Vector>(
    points: &[V],
    weights: &[f64],
    ids: &[GlobalId],
    parts: usize,
    domain: Bounds<V>,
) -> Decomposition<V> {
    assert!(parts >= 1, "a decomposition needs at least one part");
    assert_eq!(points.len(), weights.len(), "one weight per point");
    assert_eq!(points.len(), ids.len(), "one id per point");
    assert!(
        weights.iter().all(|&w| w.is_finite() && w >= 0.0),
        "weights must be finite and non-negative"
    );
    assert!(
        (0..V::DIM).all(|k| domain.lo.get(k) <= domain.hi.get(k)),
        "the domain must have lo <= hi"
    );
    let unit = !weights.iter().any(|&w| w > 0.0);
    let mut items: Vec<Item<V>> = (0..points.len())
        .map(|i| Item {
            x: points[i],
            weight: if unit { 1.0 } else { weights[i] },
            id: ids[i],
        })
        .collect();
    let mut decomposition = Decomposition {
        nodes: Vec::with_capacity(2 * parts - 1),
        regions: vec![domain; parts],
        domain,
    };
    decomposition.split(&mut items, 0, parts, domain);
    decomposition
}

impl<V: Vector> Decomposition<V> {
    /// Number of parts.
    pub fn parts(&self) -> usize {
        self.regions.len()
    }

    /// The region of each part, indexed by part: boxes that tile the domain without overlap.
    pub fn regions(&self) -> &[Bounds<V>] {
        &self.regions
    }

    /// The domain the regions were cut from.
    pub fn domain(&self) -> &Bounds<V> {
        &self.domain
    }

    /// The cutting planes in pre-order (a plane before the planes of its lower side, those
    /// before the planes of its upper side).
    pub fn cuts(&self) -> impl Iterator<Item = &Cut> + '_ {
        self.nodes.iter().filter_map(|node| match node {
            Node::Split { cut, .. } => Some(cut),
            Node::Part(_) => None,
        })
    }

    /// The part that owns the point `x`: the leaf reached by going below or above each plane.
    /// Inside the domain it is the part whose region holds `x`; outside it, the part whose
    /// region is reached by the same planes. Points of a periodic domain must be wrapped into
    /// the primary period first ([`Periodicity::wrap`]).
    pub fn owner(&self, x: V) -> usize {
        let mut node = 0;
        loop {
            match self.nodes[node] {
                Node::Part(part) => return part,
                Node::Split { cut, above } => {
                    node = if x.get(cut.axis) < cut.position {
                        node + 1
                    } else {
                        above
                    };
                }
            }
        }
    }

    /// [`Decomposition::owner`] of every point.
    pub fn owners(&self, points: &[V]) -> Vec<usize> {
        points.iter().map(|&x| self.owner(x)).collect()
    }

    /// Calls `visit(part)` for every part whose region, cut back to one period along the
    /// periodic axes of `period` ([`Bounds::within_period`]), lies within `width` of the
    /// point `x` (squared distance to the box at most `width^2`), in increasing part order.
    /// `x` is taken as it is: the caller places the periodic images it wants tested. Only
    /// the branches of the cut tree near `x` are walked.
    pub fn parts_within(
        &self,
        x: V,
        width: f64,
        period: &Periodicity<V>,
        visit: &mut impl FnMut(usize),
    ) {
        let root = self.domain.within_period(period);
        self.visit_within(0, root, x, width * width, visit);
    }

    fn visit_within(
        &self,
        node: usize,
        region: Bounds<V>,
        x: V,
        width_squared: f64,
        visit: &mut impl FnMut(usize),
    ) {
        if region.distance_squared(x) > width_squared {
            return;
        }
        match self.nodes[node] {
            Node::Part(part) => visit(part),
            Node::Split { cut, above } => {
                let (lower, upper) = split_region(region, cut.axis, cut.position);
                self.visit_within(node + 1, lower, x, width_squared, visit);
                self.visit_within(above, upper, x, width_squared, visit);
            }
        }
    }

    /// Builds the subtree that divides `items` into the parts `first_part..first_part +
    /// parts` within `region`; returns its root node.
    fn split(
        &mut self,
        items: &mut [Item<V>],
        first_part: usize,
        parts: usize,
        region: Bounds<V>,
    ) -> usize {
        let node = self.nodes.len();
        if parts == 1 {
            self.nodes.push(Node::Part(first_part));
            self.regions[first_part] = region;
            return node;
        }
        let below = parts / 2;
        let axis = longest_axis(items);
        items.sort_unstable_by(|a, b| {
            a.x.get(axis)
                .total_cmp(&b.x.get(axis))
                .then(a.id.cmp(&b.id))
        });
        let target_fraction = below as f64 / parts as f64;
        let (count_below, position) = match best_cut(items, axis, target_fraction) {
            Some(k) => (
                k,
                plane_between(items[k - 1].x.get(axis), items[k].x.get(axis)),
            ),
            // No two distinct coordinates: everything goes above a plane at the points (or,
            // with no points, across the middle of the region).
            None => (0, fallback_position(items, axis, &region)),
        };
        let cut = Cut {
            axis,
            position,
            first_part,
            below,
            above: parts - below,
        };
        self.nodes.push(Node::Split { cut, above: 0 });
        let (lower, upper) = split_region(region, axis, position);
        let (items_below, items_above) = items.split_at_mut(count_below);
        self.split(items_below, first_part, below, lower);
        let above_node = self.split(items_above, first_part + below, parts - below, upper);
        self.nodes[node] = Node::Split {
            cut,
            above: above_node,
        };
        node
    }
}

/// The axis of the largest extent of the points' bounding box (the lowest such axis on a
/// tie; axis 0 without points).
fn longest_axis<V: Vector>(items: &[Item<V>]) -> usize {
    let Some(first) = items.first() else {
        return 0;
    };
    let (mut lo, mut hi) = (first.x, first.x);
    for item in items {
        lo = lo.min_by_component(item.x);
        hi = hi.max_by_component(item.x);
    }
    let mut best = 0;
    for k in 1..V::DIM {
        if hi.get(k) - lo.get(k) > hi.get(best) - lo.get(best) {
            best = k;
        }
    }
    best
}

/// Among the places `k` (points `..k` below) where `items` (sorted along `axis`) change
/// coordinate, the one whose weight below is nearest to `target_fraction` of the total
/// (the lowest on a tie); `None` when no coordinate changes.
fn best_cut<V: Vector>(items: &[Item<V>], axis: usize, target_fraction: f64) -> Option<usize> {
    let mut total = ExactSum::new();
    total.add_all(items.iter().map(|item| item.weight));
    let target = total.value() * target_fraction;
    let mut below = ExactSum::new();
    let mut best: Option<(usize, f64)> = None;
    for k in 1..items.len() {
        below.add(items[k - 1].weight);
        if items[k - 1].x.get(axis) < items[k].x.get(axis) {
            let weight_below = below.value();
            let miss = (weight_below - target).abs();
            if best.is_none_or(|(_, best_miss)| miss < best_miss) {
                best = Some((k, miss));
            }
            if weight_below >= target {
                break; // the weights below only grow from here
            }
        }
    }
    best.map(|(k, _)| k)
}

/// A plane position `c` with `a < c <= b` (for `a < b`): the midpoint when it falls strictly
/// above `a`, else `b`.
fn plane_between(a: f64, b: f64) -> f64 {
    let middle = 0.5 * a + 0.5 * b;
    if middle > a && middle <= b {
        middle
    } else {
        b
    }
}

/// The plane of a set that cannot be divided: at the points' common coordinate, or without
/// points at the middle of the region (its finite side if it has one, else 0).
fn fallback_position<V: Vector>(items: &[Item<V>], axis: usize, region: &Bounds<V>) -> f64 {
    if let Some(first) = items.first() {
        return first.x.get(axis);
    }
    let (lo, hi) = (region.lo.get(axis), region.hi.get(axis));
    match (lo.is_finite(), hi.is_finite()) {
        (true, true) => 0.5 * lo + 0.5 * hi,
        (true, false) => lo,
        (false, true) => hi,
        (false, false) => 0.0,
    }
}

/// The parts of `region` below and above the plane `x[axis] = position` (the plane clamped
/// into the region, so both parts stay boxes with `lo <= hi`).
fn split_region<V: Vector>(
    region: Bounds<V>,
    axis: usize,
    position: f64,
) -> (Bounds<V>, Bounds<V>) {
    let plane = position.clamp(region.lo.get(axis), region.hi.get(axis));
    let mut lower = region;
    let mut upper = region;
    lower.hi.set(axis, plane);
    upper.lo.set(axis, plane);
    (lower, upper)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::decomposition::test_support::XorShift;
    use glam::{DVec2, DVec3};

    fn random_cloud<V: Vector>(rng: &mut XorShift, n: usize) -> (Vec<V>, Vec<f64>, Vec<u32>) {
        let points = (0..n).map(|_| rng.point_in(V::ZERO, span())).collect();
        let weights = (0..n).map(|_| 0.5 + rng.uniform()).collect();
        let mut ids: Vec<u32> = (0..n as u32).map(|i| 3 * i + 7).collect();
        rng.shuffle(&mut ids);
        (points, weights, ids)
    }

    /// The extent of [`random_cloud`]'s points: `1 + k` along axis `k`.
    fn span<V: Vector>() -> V {
        let mut hi = V::ZERO;
        for k in 0..V::DIM {
            hi.set(k, 1.0 + k as f64);
        }
        hi
    }

    /// Unbounded, and a box a quarter wider than the points on every side.
    fn domains<V: Vector>() -> [Bounds<V>; 2] {
        let span = span::<V>();
        [
            Bounds::everywhere(),
            Bounds {
                lo: span * -0.25,
                hi: span * 1.25,
            },
        ]
    }

    fn check_regions_tile<V: Vector>(seed: u64) {
        let mut rng = XorShift::new(seed);
        let (points, weights, ids) = random_cloud::<V>(&mut rng, 600);
        let span = span::<V>();
        for domain in domains::<V>() {
            for parts in 1..=9 {
                let d = bisect(&points, &weights, &ids, parts, domain);
                assert_eq!(d.parts(), parts);
                assert_eq!(d.cuts().count(), parts - 1);
                let (lo, hi) = (V::ZERO - span * 0.5, span * 1.5);
                let strays: Vec<V> = (0..300).map(|_| rng.point_in(lo, hi)).collect();
                let queries = points.iter().chain(&strays).copied();
                for x in queries.filter(|&x| domain.contains(x)) {
                    let owner = d.owner(x);
                    assert!(
                        d.regions()[owner].contains(x),
                        "{x:?} outside its owner's region"
                    );
                    let holders = d.regions().iter().filter(|r| r.contains(x)).count();
                    assert_eq!(holders, 1, "regions overlap or leave a gap at {x:?}");
                }
            }
        }
    }

    #[test]
    fn every_point_lies_in_exactly_one_region_its_owners() {
        check_regions_tile::<DVec2>(1);
        check_regions_tile::<DVec3>(2);
    }

    fn check_loads_share_the_weight<V: Vector>(seed: u64) {
        let mut rng = XorShift::new(seed);
        let (points, weights, ids) = random_cloud::<V>(&mut rng, 2000);
        let total: f64 = weights.iter().sum();
        let heaviest = weights.iter().copied().fold(0.0, f64::max);
        for parts in 1..=11 {
            let d = bisect(&points, &weights, &ids, parts, Bounds::everywhere());
            let mut loads = vec![0.0; parts];
            for (&x, &w) in points.iter().zip(&weights) {
                loads[d.owner(x)] += w;
            }
            // Each level misses its target by at most one point's weight.
            let levels = (parts as f64).log2().ceil();
            for (part, load) in loads.iter().enumerate() {
                let ideal = total / parts as f64;
                assert!(
                    (load - ideal).abs() <= levels * heaviest + 1e-9,
                    "K = {parts}, part {part}: load {load}, ideal {ideal}"
                );
            }
        }
    }

    #[test]
    fn parts_carry_equal_shares_of_the_weight_for_any_part_count() {
        check_loads_share_the_weight::<DVec2>(3);
        check_loads_share_the_weight::<DVec3>(4);
    }

    #[test]
    fn cuts_do_not_depend_on_input_order_or_on_ids() {
        let mut rng = XorShift::new(9);
        // A lattice with random weights: many equal coordinates, so the tie rule matters.
        let mut points = Vec::new();
        for i in 0..30 {
            for j in 0..20 {
                points.push(DVec2::new(i as f64 * 0.1, j as f64 * 0.1));
            }
        }
        let weights: Vec<f64> = points.iter().map(|_| rng.uniform() * 1e-3 + 1.0).collect();
        let ids: Vec<u32> = (0..points.len() as u32).collect();
        for parts in [2, 3, 5, 8] {
            let reference = bisect(&points, &weights, &ids, parts, Bounds::everywhere());
            for _ in 0..5 {
                let mut order: Vec<usize> = (0..points.len()).collect();
                rng.shuffle(&mut order);
                let shuffled_points: Vec<DVec2> = order.iter().map(|&i| points[i]).collect();
                let shuffled_weights: Vec<f64> = order.iter().map(|&i| weights[i]).collect();
                let same_ids: Vec<u32> = order.iter().map(|&i| ids[i]).collect();
                let again = bisect(
                    &shuffled_points,
                    &shuffled_weights,
                    &same_ids,
                    parts,
                    Bounds::everywhere(),
                );
                assert_eq!(
                    again, reference,
                    "input order changed the cuts (K = {parts})"
                );
                let mut other_ids = same_ids.clone();
                rng.shuffle(&mut other_ids);
                let relabelled = bisect(
                    &shuffled_points,
                    &shuffled_weights,
                    &other_ids,
                    parts,
                    Bounds::everywhere(),
                );
                assert_eq!(relabelled, reference, "ids changed the cuts (K = {parts})");
            }
        }
    }

    #[test]
    fn the_longest_extent_is_cut_in_the_ratio_of_the_part_counts() {
        // 1000 x 10 points evenly along a strip 10 long and 1 high.
        let points: Vec<DVec2> = (0..10_000)
            .map(|i| DVec2::new((i / 10) as f64 * 0.01 + 0.005, (i % 10) as f64 * 0.1 + 0.05))
            .collect();
        let weights = vec![1.0; points.len()];
        let ids: Vec<u32> = (0..points.len() as u32).collect();
        let halves = bisect(&points, &weights, &ids, 2, Bounds::everywhere());
        let first = *halves.cuts().next().unwrap();
        assert_eq!(first.axis, 0);
        assert!((first.position - 5.0).abs() < 0.01, "{first:?}");
        let thirds = bisect(&points, &weights, &ids, 3, Bounds::everywhere());
        let cuts: Vec<Cut> = thirds.cuts().copied().collect();
        assert_eq!((cuts[0].below, cuts[0].above), (1, 2));
        assert!((cuts[0].position - 10.0 / 3.0).abs() < 0.01, "{cuts:?}");
        assert!((cuts[1].position - 20.0 / 3.0).abs() < 0.01, "{cuts:?}");
        // Weight, not count, sets the cut: the right half twice as heavy moves it left.
        let heavy_right: Vec<f64> = points
            .iter()
            .map(|x| if x.x > 5.0 { 2.0 } else { 1.0 })
            .collect();
        let weighted = bisect(&points, &heavy_right, &ids, 2, Bounds::everywhere());
        let cut = weighted.cuts().next().unwrap().position;
        assert!((cut - 6.25).abs() < 0.01, "{cut}");
    }

    #[test]
    fn more_parts_than_points_leaves_parts_empty() {
        let points = [
            DVec3::new(0.0, 0.0, 0.0),
            DVec3::new(1.0, 0.0, 0.0),
            DVec3::new(1.0, 0.0, 0.0),
        ];
        let d = bisect(&points, &[1.0; 3], &[0, 1, 2], 6, Bounds::everywhere());
        let owners = d.owners(&points);
        assert_ne!(owners[0], owners[1]);
        assert_eq!(
            owners[1], owners[2],
            "coincident points cannot be separated"
        );
        let none = bisect::<DVec2>(&[], &[], &[], 3, Bounds::everywhere());
        assert_eq!(none.parts(), 3);
        assert!(none.owner(DVec2::new(0.3, 0.1)) < 3);
    }
}
