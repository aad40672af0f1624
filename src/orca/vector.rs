//! Scalar 2-D vector helpers with RVO2's exact operation order.
//!
//! Every helper is plain `f32` arithmetic (`+ - * /`, `sqrt`), written in the order RVO2's
//! `Vector2.h` and `Definitions.h` use, so results are bit-identical with the reference library
//! (and, later, with the WGSL mirror). No fused multiply-add, no SIMD, no reassociation.

use std::ops::{Add, Mul, Neg, Sub};

/// A 2-D vector of `f32` (metres, or metres per second in velocity space).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Vec2 {
    /// x component.
    pub x: f32,
    /// y component.
    pub y: f32,
}

impl Vec2 {
    /// The zero vector.
    pub const ZERO: Self = Self { x: 0.0, y: 0.0 };

    /// Builds a vector from its components.
    #[inline]
    #[must_use]
    pub const fn new(x: f32, y: f32) -> Self {
        Self { x, y }
    }

    /// Builds a vector from an `[x, y]` array.
    #[inline]
    #[must_use]
    pub const fn from_array(a: [f32; 2]) -> Self {
        Self { x: a[0], y: a[1] }
    }

    /// Returns the `[x, y]` array.
    #[inline]
    #[must_use]
    pub const fn to_array(self) -> [f32; 2] {
        [self.x, self.y]
    }

    /// Dot product `a.x*b.x + a.y*b.y`.
    #[inline]
    #[must_use]
    pub fn dot(self, b: Self) -> f32 {
        self.x * b.x + self.y * b.y
    }

    /// Squared length `a·a`.
    #[inline]
    #[must_use]
    pub fn abs_sq(self) -> f32 {
        self.dot(self)
    }

    /// Length `sqrt(a·a)`.
    #[inline]
    #[must_use]
    pub fn abs(self) -> f32 {
        self.abs_sq().sqrt()
    }

    /// Division by a scalar as RVO2 does it: `inv = 1/s`, then two multiplies.
    #[inline]
    #[must_use]
    pub fn div_scalar(self, s: f32) -> Self {
        let inv = 1.0 / s;
        Self::new(self.x * inv, self.y * inv)
    }

    /// Unit vector `self / |self|` (via [`Vec2::div_scalar`]). NaN for the zero vector, as in RVO2.
    #[inline]
    #[must_use]
    pub fn normalize(self) -> Self {
        self.div_scalar(self.abs())
    }

    /// Left normal `(-y, x)`.
    #[inline]
    #[must_use]
    pub const fn perp_l(self) -> Self {
        Self::new(-self.y, self.x)
    }
}

/// Determinant `a.x*b.y - a.y*b.x` (z of the cross product).
#[inline]
#[must_use]
pub fn det(a: Vec2, b: Vec2) -> f32 {
    a.x * b.y - a.y * b.x
}

/// `det(a - c, b - a)`: positive when `c` lies to the left of the directed line `a -> b`.
#[inline]
#[must_use]
pub fn left_of(a: Vec2, b: Vec2, c: Vec2) -> f32 {
    det(a - c, b - a)
}

/// Squared distance from point `c` to the segment `a -> b` (RVO2's `distSqPointLineSegment`).
#[inline]
#[must_use]
pub fn dist_sq_point_segment(a: Vec2, b: Vec2, c: Vec2) -> f32 {
    let r = (c - a).dot(b - a) / (b - a).abs_sq();
    if r < 0.0 {
        (c - a).abs_sq()
    } else if r > 1.0 {
        (c - b).abs_sq()
    } else {
        (c - (a + r * (b - a))).abs_sq()
    }
}

impl Add for Vec2 {
    type Output = Self;
    #[inline]
    fn add(self, b: Self) -> Self {
        Self::new(self.x + b.x, self.y + b.y)
    }
}

impl Sub for Vec2 {
    type Output = Self;
    #[inline]
    fn sub(self, b: Self) -> Self {
        Self::new(self.x - b.x, self.y - b.y)
    }
}

impl Neg for Vec2 {
    type Output = Self;
    #[inline]
    fn neg(self) -> Self {
        Self::new(-self.x, -self.y)
    }
}

/// `s * v`, component-wise (`s*x, s*y`).
impl Mul<Vec2> for f32 {
    type Output = Vec2;
    #[inline]
    fn mul(self, v: Vec2) -> Vec2 {
        Vec2::new(self * v.x, self * v.y)
    }
}

/// `v * s`, component-wise (`x*s, y*s`).
impl Mul<f32> for Vec2 {
    type Output = Self;
    #[inline]
    fn mul(self, s: f32) -> Self {
        Self::new(self.x * s, self.y * s)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn left_of_sign() {
        let a = Vec2::new(0.0, 0.0);
        let b = Vec2::new(1.0, 0.0);
        assert!(left_of(a, b, Vec2::new(0.5, 1.0)) > 0.0);
        assert!(left_of(a, b, Vec2::new(0.5, -1.0)) < 0.0);
    }

    #[test]
    fn div_is_reciprocal_then_multiply() {
        // 7 * fl(1/3), which for some inputs differs from the correctly rounded 7/3.
        let v = Vec2::new(7.0, 1.0).div_scalar(3.0);
        let inv = 1.0_f32 / 3.0;
        assert_eq!(v.x.to_bits(), (7.0_f32 * inv).to_bits());
    }

    #[test]
    fn segment_distance_regions() {
        let a = Vec2::new(0.0, 0.0);
        let b = Vec2::new(2.0, 0.0);
        assert_eq!(dist_sq_point_segment(a, b, Vec2::new(-1.0, 0.0)), 1.0);
        assert_eq!(dist_sq_point_segment(a, b, Vec2::new(3.0, 1.0)), 2.0);
        assert_eq!(dist_sq_point_segment(a, b, Vec2::new(1.0, 2.0)), 4.0);
    }
}
