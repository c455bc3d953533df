//! Wider lanes for the renderer's packets, chosen at run time: eight f64
//! in one AVX-512 register ([`Avx8`]) where the processor has AVX-512F and
//! DQ, four in one AVX register ([`Avx4`]) where it has AVX2. The binary is
//! built for baseline x86-64, where [`super::F64x4`] holds four lanes in
//! pairs of SSE2 registers.
//!
//! Both do what [`super::F64x4`] does, lane for lane and bit for bit (the
//! same IEEE operations: add, subtract, multiply, divide, square root,
//! ordered comparisons that are false for NaN, selection by mask); the
//! tests below check them against f64 on random and special values, and
//! tests/render/lanes.rs renders with all three widths and compares the images.
//!
//! This is one of the crate's two modules with `unsafe` (the other,
//! [`crate::system::allocator`], calls glibc's malloc). Its single invariant: an
//! AVX or AVX-512 instruction runs only on a processor that has it. Every
//! `unsafe` block here is an `avx!` call, and every value that reaches one
//! is made under [`Avx2::run`] or [`Avx512::run`], whose receivers exist
//! only once [`Avx2::detect`] or [`Avx512::detect`] has seen the feature
//! (the renderer picks the `Avx4` or `Avx8` kernel only there). Making the
//! constants does not run any instruction.
#![allow(unsafe_code)]

use super::precision::{Mask, Real, four_lanes};
use std::arch::x86_64::*;
use std::ops::{Add, BitAnd, BitOr, BitXor, Div, Mul, Neg, Not, Sub};
use std::sync::OnceLock;

/// An AVX or AVX-512 instruction, run only where `detect` found it.
macro_rules! avx {
    ($e:expr) => {
        // SAFETY: this module's values are operated on only under
        // `Avx2::run` or `Avx512::run`, after `detect` found the feature
        // on this processor (see the module documentation).
        unsafe { $e }
    };
}

/// The widest lanes a run may take, narrowest first.
#[derive(Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord)]
enum Width {
    Baseline,
    Avx2,
    Avx512,
}

/// The widest lanes `RAYOFLIGHT_SIMD` allows (`baseline` or `avx2`; unset
/// or anything else: the widest the processor has). Read by each
/// `detect` once.
fn asked_for() -> Width {
    match std::env::var_os("RAYOFLIGHT_SIMD") {
        Some(v) if v == "baseline" => Width::Baseline,
        Some(v) if v == "avx2" => Width::Avx2,
        _ => Width::Avx512,
    }
}

/// Proof that this processor has AVX2: made only by [`Avx2::detect`].
#[derive(Debug, Clone, Copy)]
pub struct Avx2(());

impl Avx2 {
    /// `Some` when the processor has AVX2, and `RAYOFLIGHT_SIMD` is not
    /// `baseline` (which keeps the SSE2 lanes, to compare them).
    pub fn detect() -> Option<Avx2> {
        static FOUND: OnceLock<bool> = OnceLock::new();
        let found =
            *FOUND.get_or_init(|| asked_for() >= Width::Avx2 && is_x86_feature_detected!("avx2"));
        found.then_some(Avx2(()))
    }

    /// Runs `work` compiled with AVX2 enabled: what its `run` inlines
    /// (the trace loop is `#[inline(always)]` down to these lanes) becomes
    /// AVX code, the lanes' instructions included.
    #[inline]
    pub fn run<W: Vectorized>(self, work: W) -> W::Output {
        // SAFETY: `self` exists only where `detect` found AVX2.
        unsafe { with_avx2(work) }
    }
}

/// Work run by [`Avx2::run`]. Its `run` must be `#[inline(always)]`, and
/// so must everything it calls down to the lanes: a call that is not
/// inlined is compiled for baseline x86-64, and an AVX instruction in it
/// becomes a call of its own, many times slower.
pub trait Vectorized {
    type Output;
    fn run(self) -> Self::Output;
}

#[target_feature(enable = "avx2")]
unsafe fn with_avx2<W: Vectorized>(work: W) -> W::Output {
    work.run()
}

/// Four f64 lanes in an AVX register.
#[derive(Debug, Clone, Copy)]
pub struct Avx4(__m256d);

/// One flag per lane of an [`Avx4`]: all bits set or all clear.
#[derive(Debug, Clone, Copy)]
pub struct AvxMask(__m256d);

const fn splat_const(x: f64) -> __m256d {
    // SAFETY: a plain bit copy of four f64 into the register type (no
    // instruction runs).
    unsafe { std::mem::transmute::<[f64; 4], __m256d>([x; 4]) }
}

const ALL_BITS: __m256d = splat_const(f64::from_bits(u64::MAX));

macro_rules! binary {
    ($t:ident, $trait:ident, $method:ident, $intrinsic:ident) => {
        impl $trait for $t {
            type Output = $t;
            #[inline(always)]
            fn $method(self, other: $t) -> $t {
                $t(avx!($intrinsic(self.0, other.0)))
            }
        }
    };
}
/// The lane type `$t` of `$n` f64 in register `$reg`, with mask type
/// `$mask`: its arithmetic, [`Real`] and [`super::Lanes`], from the
/// intrinsics of its width. One definition for the AVX and AVX-512 lanes;
/// only the names of the instructions differ (and how a mask is held:
/// `$cmp` gives it, `select` uses it).
macro_rules! avx_lanes {
    (
        $t:ident($reg:ty), $mask:ident, $n:literal, splat: $splat:ident,
        load: $load:ident, store: $store:ident, set1: $set1:ident,
        add: $add:ident, sub: $sub:ident, mul: $mul:ident, div: $div:ident,
        sqrt: $sqrt:ident, and: $and:ident, andnot: $andnot:ident, or: $or:ident,
        xor: $xor:ident, cmp: $cmp:ident,
        select: |$m:ident, $if_true:ident, $if_false:ident| $select:expr $(,)?
    ) => {
        impl $t {
            /// Every bit but the sign.
            const SIGN: $reg = $splat(-0.0);

            #[inline(always)]
            fn from_array(a: [f64; $n]) -> $t {
                $t(avx!($load(a.as_ptr())))
            }
            #[inline(always)]
            fn to_array(self) -> [f64; $n] {
                let mut a = [0.0; $n];
                avx!($store(a.as_mut_ptr(), self.0));
                a
            }
        }

        four_lanes!($t, $n);

        binary!($t, Add, add, $add);
        binary!($t, Sub, sub, $sub);
        binary!($t, Mul, mul, $mul);
        binary!($t, Div, div, $div);

        impl Neg for $t {
            type Output = $t;
            #[inline(always)]
            fn neg(self) -> $t {
                // Flip the sign bit, as f64's negation does.
                $t(avx!($xor(self.0, Self::SIGN)))
            }
        }

        impl Real for $t {
            type Mask = $mask;
            const ZERO: $t = $t($splat(0.0));
            const ONE: $t = $t($splat(1.0));
            const TWO: $t = $t($splat(2.0));
            const FOUR: $t = $t($splat(4.0));
            #[inline(always)]
            fn from_f64(x: f64) -> $t {
                $t(avx!($set1(x)))
            }
            #[inline(always)]
            fn sqrt(self) -> $t {
                $t(avx!($sqrt(self.0)))
            }
            #[inline(always)]
            fn copysign(self, sign: $t) -> $t {
                // The sign bit of `sign`, the other bits of `self`
                // (f64::copysign).
                $t(avx!($or(
                    $andnot(Self::SIGN, self.0),
                    $and(Self::SIGN, sign.0)
                )))
            }
            #[inline(always)]
            fn is_nan(self) -> $mask {
                $mask(avx!($cmp::<_CMP_UNORD_Q>(self.0, self.0)))
            }
            #[inline(always)]
            fn is_finite(self) -> $mask {
                // |x| < ∞: false for the infinities and NaN.
                let magnitude = avx!($andnot(Self::SIGN, self.0));
                $mask(avx!($cmp::<_CMP_LT_OQ>(magnitude, $splat(f64::INFINITY))))
            }
            // Ordered and quiet comparisons: false where either is NaN, as
            // in Rust.
            #[inline(always)]
            fn lt(self, other: $t) -> $mask {
                $mask(avx!($cmp::<_CMP_LT_OQ>(self.0, other.0)))
            }
            #[inline(always)]
            fn le(self, other: $t) -> $mask {
                $mask(avx!($cmp::<_CMP_LE_OQ>(self.0, other.0)))
            }
            #[inline(always)]
            fn gt(self, other: $t) -> $mask {
                $mask(avx!($cmp::<_CMP_GT_OQ>(self.0, other.0)))
            }
            #[inline(always)]
            fn eq(self, other: $t) -> $mask {
                $mask(avx!($cmp::<_CMP_EQ_OQ>(self.0, other.0)))
            }
            #[inline(always)]
            fn select($m: $mask, $if_true: $t, $if_false: $t) -> $t {
                $t(avx!($select))
            }
        }
    };
}

avx_lanes!(
    Avx4(__m256d), AvxMask, 4, splat: splat_const,
    load: _mm256_loadu_pd, store: _mm256_storeu_pd, set1: _mm256_set1_pd,
    add: _mm256_add_pd, sub: _mm256_sub_pd, mul: _mm256_mul_pd, div: _mm256_div_pd,
    sqrt: _mm256_sqrt_pd, and: _mm256_and_pd, andnot: _mm256_andnot_pd, or: _mm256_or_pd,
    xor: _mm256_xor_pd, cmp: _mm256_cmp_pd,
    select: |mask, if_true, if_false| _mm256_blendv_pd(if_false.0, if_true.0, mask.0),
);

binary!(AvxMask, BitAnd, bitand, _mm256_and_pd);
binary!(AvxMask, BitOr, bitor, _mm256_or_pd);
binary!(AvxMask, BitXor, bitxor, _mm256_xor_pd);

impl Not for AvxMask {
    type Output = AvxMask;
    #[inline(always)]
    fn not(self) -> AvxMask {
        AvxMask(avx!(_mm256_xor_pd(self.0, ALL_BITS)))
    }
}

impl Mask for AvxMask {
    const ALL: AvxMask = AvxMask(ALL_BITS);
    #[inline(always)]
    fn from_fn(mut f: impl FnMut(usize) -> bool) -> AvxMask {
        let flag = |set: bool| if set { f64::from_bits(u64::MAX) } else { 0.0 };
        let a = [flag(f(0)), flag(f(1)), flag(f(2)), flag(f(3))];
        AvxMask(avx!(_mm256_loadu_pd(a.as_ptr())))
    }
    #[inline(always)]
    fn bits(self) -> u32 {
        avx!(_mm256_movemask_pd(self.0)) as u32
    }
}

/// Proof that this processor has AVX-512 (F and DQ): made only by
/// [`Avx512::detect`].
#[derive(Debug, Clone, Copy)]
pub struct Avx512(());

impl Avx512 {
    /// `Some` when the processor has AVX-512F and DQ, and `RAYOFLIGHT_SIMD`
    /// does not ask for narrower lanes (`baseline` or `avx2`).
    pub fn detect() -> Option<Avx512> {
        static FOUND: OnceLock<bool> = OnceLock::new();
        let found = *FOUND.get_or_init(|| {
            asked_for() >= Width::Avx512
                && is_x86_feature_detected!("avx512f")
                && is_x86_feature_detected!("avx512dq")
        });
        found.then_some(Avx512(()))
    }

    /// Runs `work` compiled with AVX-512 enabled (see [`Avx2::run`]).
    #[inline]
    pub fn run<W: Vectorized>(self, work: W) -> W::Output {
        // SAFETY: `self` exists only where `detect` found AVX-512F and DQ.
        unsafe { with_avx512(work) }
    }
}

#[target_feature(enable = "avx512f,avx512dq")]
unsafe fn with_avx512<W: Vectorized>(work: W) -> W::Output {
    work.run()
}

/// Eight f64 lanes in an AVX-512 register.
#[derive(Debug, Clone, Copy)]
pub struct Avx8(__m512d);

/// One flag per lane of an [`Avx8`]: a bit of an AVX-512 mask register.
#[derive(Debug, Clone, Copy)]
pub struct Avx8Mask(__mmask8);

const fn splat8(x: f64) -> __m512d {
    // SAFETY: a plain bit copy of eight f64 into the register type (no
    // instruction runs).
    unsafe { std::mem::transmute::<[f64; 8], __m512d>([x; 8]) }
}

avx_lanes!(
    Avx8(__m512d), Avx8Mask, 8, splat: splat8,
    load: _mm512_loadu_pd, store: _mm512_storeu_pd, set1: _mm512_set1_pd,
    add: _mm512_add_pd, sub: _mm512_sub_pd, mul: _mm512_mul_pd, div: _mm512_div_pd,
    sqrt: _mm512_sqrt_pd, and: _mm512_and_pd, andnot: _mm512_andnot_pd, or: _mm512_or_pd,
    xor: _mm512_xor_pd, cmp: _mm512_cmp_pd_mask,
    select: |mask, if_true, if_false| _mm512_mask_blend_pd(mask.0, if_false.0, if_true.0),
);

macro_rules! mask_binary {
    ($trait:ident, $method:ident, $op:tt) => {
        impl $trait for Avx8Mask {
            type Output = Avx8Mask;
            #[inline(always)]
            fn $method(self, other: Avx8Mask) -> Avx8Mask {
                Avx8Mask(self.0 $op other.0)
            }
        }
    };
}
mask_binary!(BitAnd, bitand, &);
mask_binary!(BitOr, bitor, |);
mask_binary!(BitXor, bitxor, ^);

impl Not for Avx8Mask {
    type Output = Avx8Mask;
    #[inline(always)]
    fn not(self) -> Avx8Mask {
        Avx8Mask(!self.0)
    }
}

impl Mask for Avx8Mask {
    const ALL: Avx8Mask = Avx8Mask(u8::MAX);
    #[inline(always)]
    fn from_fn(mut f: impl FnMut(usize) -> bool) -> Avx8Mask {
        let mut bits = 0u8;
        for i in 0..8 {
            bits |= u8::from(f(i)) << i;
        }
        Avx8Mask(bits)
    }
    #[inline(always)]
    fn bits(self) -> u32 {
        u32::from(self.0)
    }
    #[inline(always)]
    fn from_bits(bits: u32) -> Avx8Mask {
        Avx8Mask(bits as u8)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::geometry::precision::check_lanes;

    // Out of `Avx2::run` and `Avx512::run` the lanes' instructions are
    // calls, not inlined, but the same instructions: fine once `detect`
    // has seen the feature.

    /// The AVX2 lanes compute what f64 computes, where this processor has
    /// AVX2.
    #[test]
    fn avx_lanes_compute_what_f64_computes() {
        match Avx2::detect() {
            Some(_) => check_lanes::<Avx4>(),
            None => eprintln!("no AVX2 here: the AVX lanes are not used on this machine"),
        }
    }

    /// The AVX-512 lanes compute what f64 computes, where this processor
    /// has AVX-512.
    #[test]
    fn avx512_lanes_compute_what_f64_computes() {
        match Avx512::detect() {
            Some(_) => check_lanes::<Avx8>(),
            None => eprintln!("no AVX-512 here: the eight lanes are not used on this machine"),
        }
    }
}
