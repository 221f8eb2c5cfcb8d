//! Halos: the copies of points a part needs from outside its region.
//!
//! A part evaluates the neighbour sums of the points in its region; their neighbours within
//! `width` (kernel support plus skin) may be owned by other parts, or be the part's own
//! points seen across a periodic boundary. The halo of a part is every image `x + shift` of a
//! point, `shift` a multiple of the period along each periodic axis, that lies within `width`
//! of the part's region (the region cut back to one period), except the part's own points
//! where they are. A point can appear in one halo under several shifts when a region spans
//! nearly a whole period.

use super::bisection::Decomposition;
use super::GlobalId;
use crate::dim::Vector;
use crate::neighbours::Periodicity;

/// One image in a part's halo: the point `index` of the input (owned by `owner`, global id
/// `id`) placed at `position + shift`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct HaloEntry<V> {
    /// Index of the point in the arrays given to [`select_halos`].
    pub index: usize,
    /// Global id of the point.
    pub id: GlobalId,
    /// Part that owns the point.
    pub owner: usize,
    /// Periods added along each axis (-1, 0 or 1; 0 along non-periodic axes and beyond
    /// the dimension).
    pub periods: [i8; 3],
    /// The displacement to add to the point's stored position: `periods[k] L_k` along axis k.
    pub shift: V,
}

/// For each part of `decomposition`, its halo (see the module documentation) among the points
/// at `positions` (stored in the primary period along the periodic axes of `period`), with
/// global ids `ids`, owned by the parts `owners`: the images within `width` of the part's
/// region, ordered by global id and then by `periods`. On a distributed run each process
/// calls it with its own points: entry `p` is then what it sends to part `p`.
///
/// # Panics
/// When the slices differ in length, an owner is not a part of `decomposition`, or `width`
/// is not less than a period (then a point could be needed under two shifts along one
/// axis).
pub fn select_halos<V: Vector>(
    decomposition: &Decomposition<V>,
    positions: &[V],
    ids: &[GlobalId],
    owners: &[usize],
    width: f64,
    period: &Periodicity<V>,
) -> Vec<Vec<HaloEntry<V>>> {
    assert_eq!(positions.len(), ids.len(), "one id per point");
    assert_eq!(positions.len(), owners.len(), "one owner per point");
    assert!(
        (0..V::DIM).all(|k| !period.is_periodic(k) || width < period.length.get(k)),
        "the halo width must be less than every period"
    );
    let mut halos: Vec<Vec<HaloEntry<V>>> = vec![Vec::new(); decomposition.parts()];
    for (index, (&x, (&id, &owner))) in positions.iter().zip(ids.iter().zip(owners)).enumerate() {
        assert!(owner < decomposition.parts(), "owner {owner} is not a part");
        for_each_image(x, width, period, |periods, shift| {
            let unshifted = periods == [0; 3];
            decomposition.parts_within(x + shift, width, period, &mut |part| {
                if !(unshifted && part == owner) {
                    halos[part].push(HaloEntry {
                        index,
                        id,
                        owner,
                        periods,
                        shift,
                    });
                }
            });
        });
    }
    for halo in halos.iter_mut() {
        halo.sort_unstable_by_key(|entry| (entry.id, entry.periods));
    }
    halos
}

/// Calls `visit(periods, shift)` for every periodic image of `x` (shifts of -1, 0 or 1
/// period along each periodic axis) that lies within `width` of the primary period along
/// every axis; the unshifted image first.
fn for_each_image<V: Vector>(
    x: V,
    width: f64,
    period: &Periodicity<V>,
    mut visit: impl FnMut([i8; 3], V),
) {
    // Per axis, the period counts whose image stays within `width` of the period.
    let mut choices = [[0i8; 3]; 3];
    let mut counts = [1usize; 3];
    for k in 0..V::DIM {
        if !period.is_periodic(k) {
            continue;
        }
        let lo = period.min.get(k);
        let length = period.length.get(k);
        for wrap in [-1i8, 1] {
            let image = x.get(k) + f64::from(wrap) * length;
            if image >= lo - width && image <= lo + length + width {
                choices[k][counts[k]] = wrap;
                counts[k] += 1;
            }
        }
    }
    for &pz in &choices[2][..counts[2]] {
        for &py in &choices[1][..counts[1]] {
            for &px in &choices[0][..counts[0]] {
                let periods = [px, py, pz];
                let mut shift = V::ZERO;
                for (k, &wrap) in periods.iter().enumerate().take(V::DIM) {
                    shift.set(k, f64::from(wrap) * period.length.get(k));
                }
                visit(periods, shift);
            }
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

    struct Cloud<V> {
        positions: Vec<V>,
        ids: Vec<GlobalId>,
        period: Periodicity<V>,
    }

    impl<V: Vector> Cloud<V> {
        /// The points bisected into `parts` with `weights`, and each point's part.
        fn split(&self, weights: &[f64], parts: usize) -> (Decomposition<V>, Vec<usize>) {
            let d = bisect(
                &self.positions,
                weights,
                &self.ids,
                parts,
                Bounds::everywhere(),
            );
            let owners = d.owners(&self.positions);
            (d, owners)
        }

        /// The halos of `d` of the given `width`.
        fn halos(
            &self,
            d: &Decomposition<V>,
            owners: &[usize],
            width: f64,
        ) -> Vec<Vec<HaloEntry<V>>> {
            select_halos(d, &self.positions, &self.ids, owners, width, &self.period)
        }
    }

    /// Random points in the box `[0, 1 + k)` along axis k, periodic along the axes in
    /// `periodic_axes`, with shuffled ids.
    fn cloud<V: Vector>(seed: u64, n: usize, periodic_axes: &[usize]) -> Cloud<V> {
        let mut rng = XorShift::new(seed);
        let mut span = V::ZERO;
        for k in 0..V::DIM {
            span.set(k, 1.0 + k as f64);
        }
        let mut period = Periodicity::<V>::none();
        for &k in periodic_axes {
            period.length.set(k, span.get(k));
        }
        let positions = (0..n).map(|_| rng.point_in(V::ZERO, span)).collect();
        let mut ids: Vec<GlobalId> = (0..n as u32).map(|i| 5 * i + 1).collect();
        rng.shuffle(&mut ids);
        Cloud {
            positions,
            ids,
            period,
        }
    }

    /// Every image `x + s`, `s` in {-L, 0, L} along each periodic axis, tested against every
    /// region directly.
    fn brute_force_halos<V: Vector>(
        d: &Decomposition<V>,
        cloud: &Cloud<V>,
        owners: &[usize],
        width: f64,
    ) -> Vec<Vec<(GlobalId, [i8; 3])>> {
        let periodic: Vec<usize> = (0..V::DIM)
            .filter(|&k| cloud.period.is_periodic(k))
            .collect();
        let mut all_periods = vec![[0i8; 3]];
        for &k in &periodic {
            all_periods = all_periods
                .into_iter()
                .flat_map(|p| {
                    [-1i8, 0, 1].map(|w| {
                        let mut q = p;
                        q[k] = w;
                        q
                    })
                })
                .collect();
        }
        let mut halos = vec![Vec::new(); d.parts()];
        for (part, region) in d.regions().iter().enumerate() {
            let region = region.within_period(&cloud.period);
            for (i, &x) in cloud.positions.iter().enumerate() {
                for &periods in &all_periods {
                    let mut image = x;
                    for (k, &wrap) in periods.iter().enumerate().take(V::DIM) {
                        image.set(k, x.get(k) + f64::from(wrap) * cloud.period.length.get(k));
                    }
                    let own = owners[i] == part && periods == [0; 3];
                    if !own && region.distance_squared(image) <= width * width {
                        halos[part].push((cloud.ids[i], periods));
                    }
                }
            }
            halos[part].sort_unstable();
        }
        halos
    }

    fn check_against_brute_force<V: Vector>(seed: u64, periodic_axes: &[usize]) {
        let cloud = cloud::<V>(seed, 800, periodic_axes);
        let weights = vec![1.0; cloud.positions.len()];
        let mut shifted_entries = 0;
        for parts in [1, 2, 3, 4, 7] {
            let (d, owners) = cloud.split(&weights, parts);
            for width in [0.05, 0.3] {
                let halos = cloud.halos(&d, &owners, width);
                let expected = brute_force_halos(&d, &cloud, &owners, width);
                for (part, (halo, brute)) in halos.iter().zip(&expected).enumerate() {
                    let got: Vec<(GlobalId, [i8; 3])> =
                        halo.iter().map(|e| (e.id, e.periods)).collect();
                    assert_eq!(&got, brute, "K = {parts}, width {width}, part {part}");
                    for e in halo {
                        assert_eq!(e.id, cloud.ids[e.index]);
                        assert_eq!(e.owner, owners[e.index]);
                        for k in 0..V::DIM {
                            let expected_shift =
                                f64::from(e.periods[k]) * cloud.period.length.get(k);
                            assert_eq!(e.shift.get(k), expected_shift);
                        }
                    }
                    if parts > 1 {
                        assert!(!halo.is_empty(), "K = {parts}: part {part} has no halo");
                    }
                    shifted_entries += halo.iter().filter(|e| e.periods != [0; 3]).count();
                }
            }
        }
        assert_eq!(
            shifted_entries > 0,
            !periodic_axes.is_empty(),
            "periodic images are exercised exactly when there are periodic axes"
        );
    }

    #[test]
    fn halos_equal_a_brute_force_selection() {
        check_against_brute_force::<DVec2>(1, &[]);
        check_against_brute_force::<DVec2>(2, &[0]);
        check_against_brute_force::<DVec2>(3, &[0, 1]);
        check_against_brute_force::<DVec3>(4, &[]);
        check_against_brute_force::<DVec3>(5, &[2]);
        check_against_brute_force::<DVec3>(6, &[0, 1, 2]);
    }

    /// What the halo is for: every neighbour (minimum image, within `width`) of a point is in
    /// the point's own part unshifted or in that part's halo with the shift of the minimum
    /// image.
    fn check_neighbours_are_covered<V: Vector>(seed: u64, periodic_axes: &[usize]) {
        let cloud = cloud::<V>(seed, 600, periodic_axes);
        let width = 0.25;
        let weights: Vec<f64> = (0..cloud.positions.len())
            .map(|i| 1.0 + (i % 3) as f64)
            .collect();
        for parts in [2, 3, 5] {
            let (d, owners) = cloud.split(&weights, parts);
            let halos = cloud.halos(&d, &owners, width);
            for (i, &xi) in cloud.positions.iter().enumerate() {
                for (j, &xj) in cloud.positions.iter().enumerate() {
                    let raw = xj - xi;
                    let nearest = cloud.period.minimum_image(raw);
                    if i == j || nearest.length() >= width {
                        continue;
                    }
                    let mut periods = [0i8; 3];
                    for (k, p) in periods.iter_mut().enumerate().take(V::DIM) {
                        let l = cloud.period.length.get(k);
                        if l > 0.0 {
                            *p = ((nearest.get(k) - raw.get(k)) / l).round() as i8;
                        }
                    }
                    let local = owners[j] == owners[i] && periods == [0; 3];
                    let in_halo = halos[owners[i]]
                        .iter()
                        .any(|e| e.index == j && e.periods == periods);
                    assert!(
                        local || in_halo,
                        "K = {parts}: neighbour {j} of {i} missing"
                    );
                }
            }
        }
    }

    #[test]
    fn halos_hold_every_neighbour_of_a_parts_points() {
        check_neighbours_are_covered::<DVec2>(7, &[]);
        check_neighbours_are_covered::<DVec2>(8, &[0, 1]);
        check_neighbours_are_covered::<DVec3>(9, &[0]);
    }
}
