//! One source for 2-D and 3-D: the dimension is the vector type.
//!
//! Every solver type is generic over [`Vector`], implemented for [`glam::DVec2`] and
//! [`glam::DVec3`]. The command line picks the dimension once (`match case.dim`) and the
//! whole solver is monomorphised for it; `V::DIM` branches are constant-folded.

use glam::{DVec2, DVec3};
use std::fmt::Debug;
use std::ops::{Add, AddAssign, Div, Mul, Neg, Sub, SubAssign};

/// A slice of vectors as its concrete type ([`Vector::as_concrete`]).
#[derive(Clone, Copy, Debug)]
pub enum Concrete<'a> {
    /// Two-dimensional vectors.
    Two(&'a [DVec2]),
    /// Three-dimensional vectors.
    Three(&'a [DVec3]),
}

/// The first two components of `v`, for code that runs in 2-D only.
#[inline(always)]
pub fn xy<V: Vector>(v: V) -> DVec2 {
    DVec2::new(v.get(0), v.get(1))
}

/// A small f64 vector of dimension 2 or 3.
pub trait Vector:
    Copy
    + Send
    + Sync
    + Debug
    + Default
    + PartialEq
    + Add<Output = Self>
    + Sub<Output = Self>
    + Mul<f64, Output = Self>
    + Div<f64, Output = Self>
    + Neg<Output = Self>
    + AddAssign
    + SubAssign
    + 'static
{
    /// Number of space dimensions.
    const DIM: usize;
    /// The zero vector.
    const ZERO: Self;
    /// Angular quantities: a scalar about z in 2-D, a vector in 3-D.
    type Angular: Copy
        + Send
        + Sync
        + Debug
        + Default
        + PartialEq
        + Add<Output = Self::Angular>
        + Mul<f64, Output = Self::Angular>;

    /// Dot product.
    fn dot(self, other: Self) -> f64;
    /// Euclidean length.
    fn length(self) -> f64 {
        self.dot(self).sqrt()
    }
    /// Squared length.
    fn length_squared(self) -> f64 {
        self.dot(self)
    }
    /// Component `k` (0-based, `k < DIM`).
    fn get(self, k: usize) -> f64;
    /// Mutable component `k`.
    fn set(&mut self, k: usize, value: f64);
    /// Builds a vector from the first `DIM` entries of a slice (missing entries are zero).
    fn from_slice(values: &[f64]) -> Self {
        let mut v = Self::ZERO;
        for (k, &x) in values.iter().enumerate().take(Self::DIM) {
            v.set(k, x);
        }
        v
    }
    /// The vector padded to three components (for output).
    fn to_xyz(self) -> [f64; 3];
    /// Component-wise minimum.
    fn min_by_component(self, other: Self) -> Self;
    /// Component-wise maximum.
    fn max_by_component(self, other: Self) -> Self;
    /// `true` when every component is finite.
    fn is_finite(self) -> bool;
    /// Moment of `self` (a lever arm) crossed with a force: `r x f` (scalar z-component in 2-D).
    fn cross(self, force: Self) -> Self::Angular;
    /// Velocity of a point at lever arm `self` on a body rotating at `omega`: `omega x r`.
    fn angular_cross(omega: Self::Angular, r: Self) -> Self;
    /// Rotates `self` by the rotation vector `theta` (angle about z in 2-D; axis * angle in 3-D).
    fn rotated_by(self, theta: Self::Angular) -> Self;
    /// Angular quantity from case-file numbers (1 value in 2-D, 3 in 3-D).
    fn angular_from_slice(values: &[f64]) -> Self::Angular;
    /// Angular quantity as a list (for output): 1 entry in 2-D, 3 in 3-D.
    fn angular_to_vec(a: Self::Angular) -> Vec<f64>;
    /// The vectors as their concrete type. Code with one form per dimension (a closed form
    /// in 2-D, a polygon rule in 3-D) is reached from generic code through it; the match on
    /// the result is resolved when the solver is monomorphised.
    fn as_concrete(values: &[Self]) -> Concrete<'_>;
}

impl Vector for DVec2 {
    const DIM: usize = 2;
    const ZERO: Self = DVec2::ZERO;
    type Angular = f64;

    #[inline(always)]
    fn dot(self, other: Self) -> f64 {
        DVec2::dot(self, other)
    }
    #[inline(always)]
    fn get(self, k: usize) -> f64 {
        self[k]
    }
    #[inline(always)]
    fn set(&mut self, k: usize, value: f64) {
        self[k] = value;
    }
    fn to_xyz(self) -> [f64; 3] {
        [self.x, self.y, 0.0]
    }
    fn min_by_component(self, other: Self) -> Self {
        self.min(other)
    }
    fn max_by_component(self, other: Self) -> Self {
        self.max(other)
    }
    fn is_finite(self) -> bool {
        DVec2::is_finite(self)
    }
    fn cross(self, force: Self) -> f64 {
        self.perp_dot(force)
    }
    fn angular_cross(omega: f64, r: Self) -> Self {
        DVec2::new(-omega * r.y, omega * r.x)
    }
    fn rotated_by(self, theta: f64) -> Self {
        let (s, c) = theta.sin_cos();
        DVec2::new(c * self.x - s * self.y, s * self.x + c * self.y)
    }
    fn angular_from_slice(values: &[f64]) -> f64 {
        values.first().copied().unwrap_or(0.0)
    }
    fn angular_to_vec(a: f64) -> Vec<f64> {
        vec![a]
    }
    #[inline(always)]
    fn as_concrete(values: &[Self]) -> Concrete<'_> {
        Concrete::Two(values)
    }
}

impl Vector for DVec3 {
    const DIM: usize = 3;
    const ZERO: Self = DVec3::ZERO;
    type Angular = DVec3;

    #[inline(always)]
    fn dot(self, other: Self) -> f64 {
        DVec3::dot(self, other)
    }
    #[inline(always)]
    fn get(self, k: usize) -> f64 {
        self[k]
    }
    #[inline(always)]
    fn set(&mut self, k: usize, value: f64) {
        self[k] = value;
    }
    fn to_xyz(self) -> [f64; 3] {
        [self.x, self.y, self.z]
    }
    fn min_by_component(self, other: Self) -> Self {
        self.min(other)
    }
    fn max_by_component(self, other: Self) -> Self {
        self.max(other)
    }
    fn is_finite(self) -> bool {
        DVec3::is_finite(self)
    }
    fn cross(self, force: Self) -> DVec3 {
        DVec3::cross(self, force)
    }
    fn angular_cross(omega: DVec3, r: Self) -> Self {
        omega.cross(r)
    }
    fn rotated_by(self, theta: DVec3) -> Self {
        let angle = theta.length();
        if angle == 0.0 {
            return self;
        }
        glam::DQuat::from_axis_angle(theta / angle, angle) * self
    }
    fn angular_from_slice(values: &[f64]) -> DVec3 {
        DVec3::from_slice(values)
    }
    fn angular_to_vec(a: DVec3) -> Vec<f64> {
        vec![a.x, a.y, a.z]
    }
    #[inline(always)]
    fn as_concrete(values: &[Self]) -> Concrete<'_> {
        Concrete::Three(values)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn rotation_velocity_is_consistent_with_rotation() {
        // d/dt rotate(r, omega t) at t = 0 equals omega x r.
        let r3 = DVec3::new(0.3, -0.2, 0.7);
        let w3 = DVec3::new(0.1, 0.5, -0.4);
        let eps = 1e-7;
        let fd3 = (r3.rotated_by(w3 * eps) - r3.rotated_by(w3 * -eps)) / (2.0 * eps);
        assert!((fd3 - DVec3::angular_cross(w3, r3)).length() < 1e-8);
        let r2 = DVec2::new(0.3, -0.2);
        let fd2 = (r2.rotated_by(0.5 * eps) - r2.rotated_by(-0.5 * eps)) / (2.0 * eps);
        assert!((fd2 - DVec2::angular_cross(0.5, r2)).length() < 1e-8);
    }
}
