//! Axis-aligned boxes: the regions of a decomposition.

use crate::dim::Vector;
use crate::neighbours::Periodicity;

/// An axis-aligned box `[lo, hi)` (half-open along every axis); components may be infinite,
/// so the outermost regions of a decomposition can extend without bound.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Bounds<V> {
    /// Lower corner (inclusive).
    pub lo: V,
    /// Upper corner (exclusive).
    pub hi: V,
}

impl<V: Vector> Bounds<V> {
    /// The box that holds every point: `(-inf, inf)` along every axis.
    pub fn everywhere() -> Self {
        let mut lo = V::ZERO;
        let mut hi = V::ZERO;
        for k in 0..V::DIM {
            lo.set(k, f64::NEG_INFINITY);
            hi.set(k, f64::INFINITY);
        }
        Bounds { lo, hi }
    }

    /// `true` when `lo <= x < hi` along every axis.
    pub fn contains(&self, x: V) -> bool {
        (0..V::DIM).all(|k| self.lo.get(k) <= x.get(k) && x.get(k) < self.hi.get(k))
    }

    /// Distance from `x` to the box along axis `k` (zero when `x` lies between its faces).
    #[inline]
    pub fn axis_distance(&self, x: V, k: usize) -> f64 {
        let below = self.lo.get(k) - x.get(k);
        let above = x.get(k) - self.hi.get(k);
        below.max(above).max(0.0)
    }

    /// Squared Euclidean distance from `x` to the closest point of the box (zero inside).
    pub fn distance_squared(&self, x: V) -> f64 {
        (0..V::DIM)
            .map(|k| {
                let d = self.axis_distance(x, k);
                d * d
            })
            .sum()
    }

    /// The box cut back to one period `[min, min + L)` along each periodic axis of `period`
    /// (the points of a periodic domain are stored in that period, so no region needs to
    /// reach beyond it).
    pub fn within_period(&self, period: &Periodicity<V>) -> Self {
        let mut clipped = *self;
        for k in 0..V::DIM {
            if period.is_periodic(k) {
                let start = period.min.get(k);
                let end = start + period.length.get(k);
                clipped.lo.set(k, self.lo.get(k).clamp(start, end));
                clipped.hi.set(k, self.hi.get(k).clamp(start, end));
            }
        }
        clipped
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use glam::DVec2;

    #[test]
    fn distance_is_zero_inside_and_euclidean_outside() {
        let b = Bounds {
            lo: DVec2::new(0.0, 0.0),
            hi: DVec2::new(2.0, 1.0),
        };
        assert_eq!(b.distance_squared(DVec2::new(1.0, 0.5)), 0.0);
        assert_eq!(b.distance_squared(DVec2::new(-3.0, 0.5)), 9.0);
        assert_eq!(b.distance_squared(DVec2::new(5.0, 5.0)), 9.0 + 16.0);
        assert!(b.contains(DVec2::new(0.0, 0.0)));
        assert!(!b.contains(DVec2::new(2.0, 0.5)), "the upper face is open");
    }

    #[test]
    fn unbounded_box_holds_everything_and_clips_to_a_period() {
        let b = Bounds::<DVec2>::everywhere();
        assert!(b.contains(DVec2::new(-1e300, 1e300)));
        let period = Periodicity {
            min: DVec2::new(-1.0, 0.0),
            length: DVec2::new(4.0, 0.0),
        };
        let clipped = b.within_period(&period);
        assert_eq!(clipped.lo.x, -1.0);
        assert_eq!(clipped.hi.x, 3.0);
        assert_eq!(
            clipped.lo.y,
            f64::NEG_INFINITY,
            "a non-periodic axis is kept"
        );
    }
}
