//! The precision and width a formula runs in: one f64 (the reference), one
//! f32 (the study's "f32 everywhere" method) or f64 lanes side by side (the
//! packets the renderer traces: four in SSE2 registers, [`F64x4`]; four in
//! an AVX register or eight in an AVX-512 one, [`super::Avx4`] and
//! [`super::Avx8`], where the processor has them). The intersection and
//! shading formulas are written once, generic over [`Real`] and [`Vector`],
//! and each instance runs exactly the operations they spell out: every
//! method here is the one glam or the standard library already provides
//! (or, for lanes, the same IEEE operation on each lane), nothing is added
//! or reordered, so a lane computes bit for bit what the scalar code would.
//!
//! Comparisons give a [`Mask`] (a `bool` for one value, one flag per lane
//! for lanes); a formula's early outs become "no lane is still alive", and
//! its `if`s become [`Real::select`].

use glam::{DVec3, Vec3};
use std::ops::{Add, BitAnd, BitOr, BitXor, Div, Mul, Neg, Not, Sub};
use wide::f64x4;

/// The outcome of a comparison: one flag per lane.
pub trait Mask:
    Copy + BitAnd<Output = Self> + BitOr<Output = Self> + BitXor<Output = Self> + Not<Output = Self>
{
    /// Every lane set.
    const ALL: Self;
    /// Lanes set where `f(i)`.
    fn from_fn(f: impl FnMut(usize) -> bool) -> Self;
    /// The flags as bits, lane i in bit i (a small copy to keep).
    fn bits(self) -> u32;
    /// Whether any lane is set.
    #[inline(always)]
    fn any(self) -> bool {
        self.bits() != 0
    }
    /// Lanes set.
    #[inline(always)]
    fn count(self) -> u32 {
        self.bits().count_ones()
    }
    /// Lane i's flag.
    #[inline(always)]
    fn lane(self, i: usize) -> bool {
        self.bits() >> i & 1 != 0
    }
    /// The mask of [`Mask::bits`].
    #[inline(always)]
    fn from_bits(bits: u32) -> Self {
        Self::from_fn(|i| bits >> i & 1 != 0)
    }
}

impl Mask for bool {
    const ALL: bool = true;
    #[inline(always)]
    fn from_fn(mut f: impl FnMut(usize) -> bool) -> bool {
        f(0)
    }
    #[inline(always)]
    fn bits(self) -> u32 {
        u32::from(self)
    }
}

/// A floating-point scalar: `f64`, `f32`, or lanes of f64 ([`F64x4`]).
pub trait Real:
    Copy
    + Add<Output = Self>
    + Sub<Output = Self>
    + Mul<Output = Self>
    + Div<Output = Self>
    + Neg<Output = Self>
{
    type Mask: Mask;
    const ZERO: Self;
    const ONE: Self;
    const TWO: Self;
    const FOUR: Self;
    /// The value nearest `x` in this precision (in every lane).
    fn from_f64(x: f64) -> Self;
    fn sqrt(self) -> Self;
    /// `self`'s magnitude with `sign`'s sign.
    fn copysign(self, sign: Self) -> Self;
    fn is_nan(self) -> Self::Mask;
    fn is_finite(self) -> Self::Mask;
    fn lt(self, other: Self) -> Self::Mask;
    fn le(self, other: Self) -> Self::Mask;
    fn gt(self, other: Self) -> Self::Mask;
    fn eq(self, other: Self) -> Self::Mask;
    /// Per lane, `if_true` where `mask` is set, else `if_false`.
    fn select(mask: Self::Mask, if_true: Self, if_false: Self) -> Self;
}

/// A 3-vector of a [`Real`]: `DVec3`, `Vec3` or lanes of them ([`Vec3x4`]).
pub trait Vector: Copy + Add<Output = Self> + Sub<Output = Self> + Neg<Output = Self> {
    type Real: Real;
    fn dot(self, other: Self) -> Self::Real;
    fn length_squared(self) -> Self::Real;
    fn length(self) -> Self::Real;
    /// `self / |self|`, as glam computes it: `self · (1 / |self|)`.
    fn normalize(self) -> Self;
    /// `s · self`.
    fn scaled(self, s: Self::Real) -> Self;
    /// Per lane, `if_true` where `mask` is set, else `if_false`.
    fn select(mask: <Self::Real as Real>::Mask, if_true: Self, if_false: Self) -> Self;
}

macro_rules! real {
    ($t:ty) => {
        impl Real for $t {
            type Mask = bool;
            const ZERO: $t = 0.0;
            const ONE: $t = 1.0;
            const TWO: $t = 2.0;
            const FOUR: $t = 4.0;
            #[inline(always)]
            #[allow(clippy::cast_possible_truncation)]
            fn from_f64(x: f64) -> $t {
                x as $t
            }
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
            #[inline(always)]
            fn lt(self, other: $t) -> bool {
                self < other
            }
            #[inline(always)]
            fn le(self, other: $t) -> bool {
                self <= other
            }
            #[inline(always)]
            fn gt(self, other: $t) -> bool {
                self > other
            }
            #[inline(always)]
            #[allow(clippy::float_cmp)]
            fn eq(self, other: $t) -> bool {
                self == other
            }
            #[inline(always)]
            fn select(mask: bool, if_true: $t, if_false: $t) -> $t {
                if mask { if_true } else { if_false }
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
            fn length(self) -> $t {
                <$v>::length(self)
            }
            #[inline(always)]
            fn normalize(self) -> $v {
                <$v>::normalize(self)
            }
            #[inline(always)]
            fn scaled(self, s: $t) -> $v {
                s * self
            }
            #[inline(always)]
            fn select(mask: bool, if_true: $v, if_false: $v) -> $v {
                if mask { if_true } else { if_false }
            }
        }
    };
}

real!(f64);
real!(f32);
vector!(DVec3, f64);
vector!(Vec3, f32);

/// Four f64 lanes (the `wide` crate's `f64x4`: pairs of SSE2 registers on
/// baseline x86-64, the build this project makes; the AVX lanes are
/// [`super::Avx4`], chosen at run time).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct F64x4(pub f64x4);

/// One flag per lane of an [`F64x4`]: all bits set or all clear.
#[derive(Debug, Clone, Copy)]
pub struct Mask4(f64x4);

/// A 3-vector of lanes (one `DVec3` per lane): x, y and z each in lanes
/// of `L` ([`F64x4`], [`super::Avx4`] or [`super::Avx8`]).
#[derive(Debug, Clone, Copy)]
pub struct Vec3x4<L> {
    pub x: L,
    pub y: L,
    pub z: L,
}

/// Four `DVec3`s in [`F64x4`] lanes.
pub type DVec3x4 = Vec3x4<F64x4>;

const ALL_BITS: f64x4 = f64x4::splat(f64::from_bits(u64::MAX));

macro_rules! binary {
    ($t:ty, $trait:ident, $method:ident, $op:tt) => {
        impl $trait for $t {
            type Output = $t;
            #[inline(always)]
            fn $method(self, other: $t) -> $t {
                Self(self.0 $op other.0)
            }
        }
    };
}
binary!(F64x4, Add, add, +);
binary!(F64x4, Sub, sub, -);
binary!(F64x4, Mul, mul, *);
binary!(F64x4, Div, div, /);
binary!(Mask4, BitAnd, bitand, &);
binary!(Mask4, BitOr, bitor, |);
binary!(Mask4, BitXor, bitxor, ^);

impl Neg for F64x4 {
    type Output = F64x4;
    #[inline(always)]
    fn neg(self) -> F64x4 {
        F64x4(-self.0)
    }
}

impl Not for Mask4 {
    type Output = Mask4;
    #[inline(always)]
    fn not(self) -> Mask4 {
        Mask4(self.0 ^ ALL_BITS)
    }
}

impl Mask for Mask4 {
    const ALL: Mask4 = Mask4(ALL_BITS);
    #[inline(always)]
    fn from_fn(mut f: impl FnMut(usize) -> bool) -> Mask4 {
        let flag = |set: bool| if set { f64::from_bits(u64::MAX) } else { 0.0 };
        Mask4(f64x4::new([flag(f(0)), flag(f(1)), flag(f(2)), flag(f(3))]))
    }
    #[inline(always)]
    fn bits(self) -> u32 {
        self.0.to_bitmask()
    }
}

impl Real for F64x4 {
    type Mask = Mask4;
    const ZERO: F64x4 = F64x4(f64x4::splat(0.0));
    const ONE: F64x4 = F64x4(f64x4::splat(1.0));
    const TWO: F64x4 = F64x4(f64x4::splat(2.0));
    const FOUR: F64x4 = F64x4(f64x4::splat(4.0));
    #[inline(always)]
    fn from_f64(x: f64) -> F64x4 {
        F64x4(f64x4::splat(x))
    }
    #[inline(always)]
    fn sqrt(self) -> F64x4 {
        F64x4(self.0.sqrt())
    }
    #[inline(always)]
    fn copysign(self, sign: F64x4) -> F64x4 {
        // The sign bit of `sign`, the other bits of `self` (f64::copysign).
        const SIGN: f64x4 = f64x4::splat(-0.0);
        F64x4((self.0 & !SIGN) | (sign.0 & SIGN))
    }
    #[inline(always)]
    fn is_nan(self) -> Mask4 {
        Mask4(self.0.is_nan())
    }
    #[inline(always)]
    fn is_finite(self) -> Mask4 {
        Mask4(self.0.is_finite())
    }
    #[inline(always)]
    fn lt(self, other: F64x4) -> Mask4 {
        Mask4(self.0.simd_lt(other.0))
    }
    #[inline(always)]
    fn le(self, other: F64x4) -> Mask4 {
        Mask4(self.0.simd_le(other.0))
    }
    #[inline(always)]
    fn gt(self, other: F64x4) -> Mask4 {
        Mask4(self.0.simd_gt(other.0))
    }
    #[inline(always)]
    fn eq(self, other: F64x4) -> Mask4 {
        Mask4(self.0.simd_eq(other.0))
    }
    #[inline(always)]
    fn select(mask: Mask4, if_true: F64x4, if_false: F64x4) -> F64x4 {
        F64x4(mask.0.select(if_true.0, if_false.0))
    }
}

impl<L: Real> Add for Vec3x4<L> {
    type Output = Vec3x4<L>;
    #[inline(always)]
    fn add(self, o: Vec3x4<L>) -> Vec3x4<L> {
        Vec3x4 {
            x: self.x + o.x,
            y: self.y + o.y,
            z: self.z + o.z,
        }
    }
}

impl<L: Real> Sub for Vec3x4<L> {
    type Output = Vec3x4<L>;
    #[inline(always)]
    fn sub(self, o: Vec3x4<L>) -> Vec3x4<L> {
        Vec3x4 {
            x: self.x - o.x,
            y: self.y - o.y,
            z: self.z - o.z,
        }
    }
}

impl<L: Real> Neg for Vec3x4<L> {
    type Output = Vec3x4<L>;
    #[inline(always)]
    fn neg(self) -> Vec3x4<L> {
        Vec3x4 {
            x: -self.x,
            y: -self.y,
            z: -self.z,
        }
    }
}

impl<L: Real> Vector for Vec3x4<L> {
    type Real = L;
    #[inline(always)]
    fn dot(self, o: Vec3x4<L>) -> L {
        // glam's order: (x x') + (y y') + (z z').
        (self.x * o.x) + (self.y * o.y) + (self.z * o.z)
    }
    #[inline(always)]
    fn length_squared(self) -> L {
        self.dot(self)
    }
    #[inline(always)]
    fn length(self) -> L {
        self.dot(self).sqrt()
    }
    #[inline(always)]
    fn normalize(self) -> Vec3x4<L> {
        self.scaled(L::ONE / self.length())
    }
    #[inline(always)]
    fn scaled(self, s: L) -> Vec3x4<L> {
        Vec3x4 {
            x: s * self.x,
            y: s * self.y,
            z: s * self.z,
        }
    }
    #[inline(always)]
    fn select(mask: L::Mask, if_true: Vec3x4<L>, if_false: Vec3x4<L>) -> Vec3x4<L> {
        Vec3x4 {
            x: L::select(mask, if_true.x, if_false.x),
            y: L::select(mask, if_true.y, if_false.y),
            z: L::select(mask, if_true.z, if_false.z),
        }
    }
}

/// f64 lanes the renderer traces side by side: one `f64` (the picks, the
/// study's f32 method), four ([`F64x4`], [`super::Avx4`]) or eight
/// ([`super::Avx8`]): the tiles. A lane's values come from and go back to
/// plain `f64` and `DVec3`.
pub trait Lanes: Real {
    type Vector: Vector<Real = Self>;
    /// Lanes traced together.
    const WIDTH: usize;
    fn splat(x: f64) -> Self;
    fn lane(self, i: usize) -> f64;
    fn from_fn(f: impl FnMut(usize) -> f64) -> Self;
    fn splat_vector(v: DVec3) -> Self::Vector;
    fn vector_lane(v: Self::Vector, i: usize) -> DVec3;
    fn vector_from_fn(f: impl FnMut(usize) -> DVec3) -> Self::Vector;
    /// A vector's x, y and z lanes.
    fn components(v: Self::Vector) -> [Self; 3];
}

impl Lanes for f64 {
    type Vector = DVec3;
    const WIDTH: usize = 1;
    #[inline(always)]
    fn splat(x: f64) -> f64 {
        x
    }
    #[inline(always)]
    fn lane(self, _: usize) -> f64 {
        self
    }
    #[inline(always)]
    fn from_fn(mut f: impl FnMut(usize) -> f64) -> f64 {
        f(0)
    }
    #[inline(always)]
    fn splat_vector(v: DVec3) -> DVec3 {
        v
    }
    #[inline(always)]
    fn vector_lane(v: DVec3, _: usize) -> DVec3 {
        v
    }
    #[inline(always)]
    fn vector_from_fn(mut f: impl FnMut(usize) -> DVec3) -> DVec3 {
        f(0)
    }
    #[inline(always)]
    fn components(v: DVec3) -> [f64; 3] {
        v.to_array()
    }
}

/// The most lanes a [`Lanes`] type has (AVX-512's eight).
pub const MAX_LANES: usize = 8;

/// [`Lanes`] for a type of `$n` lanes with `from_array` and `to_array`.
macro_rules! four_lanes {
    ($t:ty, $n:literal) => {
        impl $crate::geometry::Lanes for $t {
            type Vector = $crate::geometry::Vec3x4<$t>;
            const WIDTH: usize = $n;
            #[inline(always)]
            fn splat(x: f64) -> $t {
                <$t>::from_array([x; $n])
            }
            #[inline(always)]
            fn lane(self, i: usize) -> f64 {
                self.to_array()[i]
            }
            #[inline(always)]
            fn from_fn(mut f: impl FnMut(usize) -> f64) -> $t {
                // A loop, not std::array::from_fn: the hot path must stay
                // inlined (see geometry::avx).
                let mut a = [0.0; $n];
                for (i, x) in a.iter_mut().enumerate() {
                    *x = f(i);
                }
                <$t>::from_array(a)
            }
            #[inline(always)]
            fn splat_vector(v: glam::DVec3) -> Self::Vector {
                $crate::geometry::Vec3x4 {
                    x: Self::splat(v.x),
                    y: Self::splat(v.y),
                    z: Self::splat(v.z),
                }
            }
            #[inline(always)]
            fn vector_lane(v: Self::Vector, i: usize) -> glam::DVec3 {
                glam::DVec3::new(v.x.lane(i), v.y.lane(i), v.z.lane(i))
            }
            #[inline(always)]
            fn vector_from_fn(mut f: impl FnMut(usize) -> glam::DVec3) -> Self::Vector {
                let (mut x, mut y, mut z) = ([0.0; $n], [0.0; $n], [0.0; $n]);
                for i in 0..$n {
                    let v = f(i);
                    (x[i], y[i], z[i]) = (v.x, v.y, v.z);
                }
                $crate::geometry::Vec3x4 {
                    x: <$t>::from_array(x),
                    y: <$t>::from_array(y),
                    z: <$t>::from_array(z),
                }
            }
            #[inline(always)]
            fn components(v: Self::Vector) -> [$t; 3] {
                [v.x, v.y, v.z]
            }
        }
    };
}
pub(super) use four_lanes;

impl F64x4 {
    #[inline(always)]
    fn from_array(a: [f64; 4]) -> F64x4 {
        F64x4(f64x4::new(a))
    }
    #[inline(always)]
    fn to_array(self) -> [f64; 4] {
        self.0.to_array()
    }
}

four_lanes!(F64x4, 4);

/// Checks that every operation of the lanes `L` gives, in each lane, what
/// the f64 operation gives, bit for bit, NaN, infinities, signed zeros and
/// subnormals included (20 000 random and special pairs). Used by the
/// tests of each lane type.
#[cfg(test)]
pub(super) fn check_lanes<L: Lanes>() {
    let specials = [
        0.0,
        -0.0,
        1.0,
        -1.5,
        f64::NAN,
        f64::INFINITY,
        f64::NEG_INFINITY,
        f64::MIN_POSITIVE / 3.0,
        1e300,
        -2.5e-310,
        std::f64::consts::PI,
    ];
    let mut seed = 0x9E37_79B9_7F4A_7C15_u64;
    let mut next = || {
        seed ^= seed << 13;
        seed ^= seed >> 7;
        seed ^= seed << 17;
        let pick = (seed % 16) as usize;
        if pick < specials.len() {
            specials[pick]
        } else {
            f64::from_bits(seed >> 2) * if seed & 1 == 0 { 1.0 } else { -1.0 }
        }
    };
    for _ in 0..20_000 {
        let a: [f64; MAX_LANES] = std::array::from_fn(|_| next());
        let b: [f64; MAX_LANES] = std::array::from_fn(|_| next());
        let (x, y) = (L::from_fn(|i| a[i]), L::from_fn(|i| b[i]));
        for i in 0..L::WIDTH {
            let (p, q) = (a[i], b[i]);
            let same = |lanes: L, scalar: f64| {
                assert_eq!(lanes.lane(i).to_bits(), scalar.to_bits(), "{p} {q}")
            };
            same(x + y, p + q);
            same(x - y, p - q);
            same(x * y, p * q);
            same(x / y, p / q);
            same(-x, -p);
            same(x.sqrt(), p.sqrt());
            same(Real::copysign(x, y), p.copysign(q));
            same(L::from_f64(p), p);
            same(L::select(x.lt(y), x, y), if p < q { p } else { q });
            assert_eq!(x.le(y).lane(i), p <= q);
            assert_eq!(x.gt(y).lane(i), p > q);
            assert_eq!(Real::eq(x, y).lane(i), p == q);
            assert_eq!(Real::is_nan(x).lane(i), p.is_nan());
            assert_eq!(Real::is_finite(x).lane(i), p.is_finite());
            // NaN: neither less nor, negated, "greater or equal".
            assert_eq!(
                (!x.lt(y)).lane(i),
                p.partial_cmp(&q) != Some(std::cmp::Ordering::Less)
            );
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The SSE2 lanes compute what f64 computes (see [`check_lanes`]).
    #[test]
    fn lanes_compute_what_f64_computes() {
        check_lanes::<F64x4>();
        check_lanes::<f64>();
    }
}
