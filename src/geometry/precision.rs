//! The precision a formula runs in: f64 (the reference) or f32 (the
//! study's "f32 everywhere" method). The intersection formulas are written
//! once, generic over [`Vector`], and each precision runs exactly the
//! operations it spells out: every method here is the one glam or the
//! standard library already provides, nothing is added or reordered.

use glam::{DVec3, Vec3};
use std::ops::{Add, Div, Mul, Neg, Sub};

/// A floating-point scalar: `f64` or `f32`.
pub trait Real:
    Copy
    + PartialOrd
    + Default
    + Add<Output = Self>
    + Sub<Output = Self>
    + Mul<Output = Self>
    + Div<Output = Self>
    + Neg<Output = Self>
{
    const ZERO: Self;
    const TWO: Self;
    const FOUR: Self;
    fn sqrt(self) -> Self;
    /// `self`'s magnitude with `sign`'s sign.
    fn copysign(self, sign: Self) -> Self;
    fn is_nan(self) -> bool;
    fn is_finite(self) -> bool;
}

/// A 3-vector of a [`Real`]: `DVec3` or `Vec3`.
pub trait Vector: Copy + Sub<Output = Self> {
    type Real: Real;
    fn dot(self, other: Self) -> Self::Real;
    fn length_squared(self) -> Self::Real;
    /// `s · self`.
    fn scaled(self, s: Self::Real) -> Self;
}

macro_rules! real {
    ($t:ty) => {
        impl Real for $t {
            const ZERO: $t = 0.0;
            const TWO: $t = 2.0;
            const FOUR: $t = 4.0;
            #[inline(always)]
            fn sqrt(self) -> $t {
                <$t>::sqrt(self)
            }
            #[inline(always)]
            fn copysign(self, sign: $t) -> $t {
                <$t>::copysign(self, sign)
            }
            #[inline(always)]
            fn is_nan(self) -> bool {
                <$t>::is_nan(self)
            }
            #[inline(always)]
            fn is_finite(self) -> bool {
                <$t>::is_finite(self)
            }
        }
    };
}

macro_rules! vector {
    ($v:ty, $t:ty) => {
        impl Vector for $v {
            type Real = $t;
            #[inline(always)]
            fn dot(self, other: $v) -> $t {
                <$v>::dot(self, other)
            }
            #[inline(always)]
            fn length_squared(self) -> $t {
                <$v>::length_squared(self)
            }
            #[inline(always)]
            fn scaled(self, s: $t) -> $v {
                s * self
            }
        }
    };
}

real!(f64);
real!(f32);
vector!(DVec3, f64);
vector!(Vec3, f32);
