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
//! tests/lanes.rs renders with all three widths and compares the images.
//!
//! This is the crate's one module with `unsafe`. Its single invariant: an
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

/// Proof that this processor has AVX2: made only by [`Avx2::detect`].
#[derive(Debug, Clone, Copy)]
pub struct Avx2(());

impl Avx2 {
    /// `Some` when the processor has AVX2, and `RAYOFLIGHT_SIMD` is not
    /// `baseline` (which keeps the SSE2 lanes, to compare them).
    pub fn detect() -> Option<Avx2> {
        static FOUND: OnceLock<bool> = OnceLock::new();
        let found = *FOUND.get_or_init(|| {
            let baseline = std::env::var_os("RAYOFLIGHT_SIMD").is_some_and(|v| v == "baseline");
            !baseline && is_x86_feature_detected!("avx2")
        });
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
const SIGN: __m256d = splat_const(-0.0);

impl Avx4 {
    #[inline(always)]
    fn from_array(a: [f64; 4]) -> Avx4 {
        Avx4(avx!(_mm256_loadu_pd(a.as_ptr())))
    }
    #[inline(always)]
    fn to_array(self) -> [f64; 4] {
        let mut a = [0.0; 4];
        avx!(_mm256_storeu_pd(a.as_mut_ptr(), self.0));
        a
    }
}

four_lanes!(Avx4, 4);

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
binary!(Avx4, Add, add, _mm256_add_pd);
binary!(Avx4, Sub, sub, _mm256_sub_pd);
binary!(Avx4, Mul, mul, _mm256_mul_pd);
binary!(Avx4, Div, div, _mm256_div_pd);
binary!(AvxMask, BitAnd, bitand, _mm256_and_pd);
binary!(AvxMask, BitOr, bitor, _mm256_or_pd);
binary!(AvxMask, BitXor, bitxor, _mm256_xor_pd);

impl Neg for Avx4 {
    type Output = Avx4;
    #[inline(always)]
    fn neg(self) -> Avx4 {
        // Flip the sign bit, as f64's negation does.
        Avx4(avx!(_mm256_xor_pd(self.0, SIGN)))
    }
}

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
    fn any(self) -> bool {
        avx!(_mm256_movemask_pd(self.0)) != 0
    }
    #[inline(always)]
    fn count(self) -> u32 {
        avx!(_mm256_movemask_pd(self.0)).count_ones()
    }
    #[inline(always)]
    fn lane(self, i: usize) -> bool {
        avx!(_mm256_movemask_pd(self.0)) & (1 << i) != 0
    }
    #[inline(always)]
    fn from_fn(mut f: impl FnMut(usize) -> bool) -> AvxMask {
        let flag = |set: bool| if set { f64::from_bits(u64::MAX) } else { 0.0 };
        let a = [flag(f(0)), flag(f(1)), flag(f(2)), flag(f(3))];
        AvxMask(avx!(_mm256_loadu_pd(a.as_ptr())))
    }
}

macro_rules! compare {
    ($method:ident, $predicate:ident) => {
        #[inline(always)]
        fn $method(self, other: Avx4) -> AvxMask {
            // Ordered and quiet: false where either is NaN, as in Rust.
            AvxMask(avx!(_mm256_cmp_pd::<$predicate>(self.0, other.0)))
        }
    };
}

impl Real for Avx4 {
    type Mask = AvxMask;
    const ZERO: Avx4 = Avx4(splat_const(0.0));
    const ONE: Avx4 = Avx4(splat_const(1.0));
    const TWO: Avx4 = Avx4(splat_const(2.0));
    const FOUR: Avx4 = Avx4(splat_const(4.0));
    #[inline(always)]
    fn from_f64(x: f64) -> Avx4 {
        Avx4(avx!(_mm256_set1_pd(x)))
    }
    #[inline(always)]
    fn sqrt(self) -> Avx4 {
        Avx4(avx!(_mm256_sqrt_pd(self.0)))
    }
    #[inline(always)]
    fn copysign(self, sign: Avx4) -> Avx4 {
        // The sign bit of `sign`, the other bits of `self` (f64::copysign).
        Avx4(avx!(_mm256_or_pd(
            _mm256_andnot_pd(SIGN, self.0),
            _mm256_and_pd(SIGN, sign.0)
        )))
    }
    #[inline(always)]
    fn is_nan(self) -> AvxMask {
        AvxMask(avx!(_mm256_cmp_pd::<_CMP_UNORD_Q>(self.0, self.0)))
    }
    #[inline(always)]
    fn is_finite(self) -> AvxMask {
        // |x| < ∞: false for the infinities and NaN.
        let magnitude = avx!(_mm256_andnot_pd(SIGN, self.0));
        AvxMask(avx!(_mm256_cmp_pd::<_CMP_LT_OQ>(
            magnitude,
            splat_const(f64::INFINITY)
        )))
    }
    compare!(lt, _CMP_LT_OQ);
    compare!(le, _CMP_LE_OQ);
    compare!(gt, _CMP_GT_OQ);
    compare!(eq, _CMP_EQ_OQ);
    #[inline(always)]
    fn select(mask: AvxMask, if_true: Avx4, if_false: Avx4) -> Avx4 {
        Avx4(avx!(_mm256_blendv_pd(if_false.0, if_true.0, mask.0)))
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
            let narrower =
                std::env::var_os("RAYOFLIGHT_SIMD").is_some_and(|v| v == "baseline" || v == "avx2");
            !narrower && is_x86_feature_detected!("avx512f") && is_x86_feature_detected!("avx512dq")
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

const SIGN8: __m512d = splat8(-0.0);

impl Avx8 {
    #[inline(always)]
    fn from_array(a: [f64; 8]) -> Avx8 {
        Avx8(avx!(_mm512_loadu_pd(a.as_ptr())))
    }
    #[inline(always)]
    fn to_array(self) -> [f64; 8] {
        let mut a = [0.0; 8];
        avx!(_mm512_storeu_pd(a.as_mut_ptr(), self.0));
        a
    }
}

four_lanes!(Avx8, 8);

binary!(Avx8, Add, add, _mm512_add_pd);
binary!(Avx8, Sub, sub, _mm512_sub_pd);
binary!(Avx8, Mul, mul, _mm512_mul_pd);
binary!(Avx8, Div, div, _mm512_div_pd);

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

impl Neg for Avx8 {
    type Output = Avx8;
    #[inline(always)]
    fn neg(self) -> Avx8 {
        // Flip the sign bit, as f64's negation does.
        Avx8(avx!(_mm512_xor_pd(self.0, SIGN8)))
    }
}

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
    fn any(self) -> bool {
        self.0 != 0
    }
    #[inline(always)]
    fn count(self) -> u32 {
        self.0.count_ones()
    }
    #[inline(always)]
    fn lane(self, i: usize) -> bool {
        self.0 & (1 << i) != 0
    }
    #[inline(always)]
    fn from_fn(mut f: impl FnMut(usize) -> bool) -> Avx8Mask {
        let mut bits = 0u8;
        for i in 0..8 {
            bits |= u8::from(f(i)) << i;
        }
        Avx8Mask(bits)
    }
}

macro_rules! compare8 {
    ($method:ident, $predicate:ident) => {
        #[inline(always)]
        fn $method(self, other: Avx8) -> Avx8Mask {
            // Ordered and quiet: false where either is NaN, as in Rust.
            Avx8Mask(avx!(_mm512_cmp_pd_mask::<$predicate>(self.0, other.0)))
        }
    };
}

impl Real for Avx8 {
    type Mask = Avx8Mask;
    const ZERO: Avx8 = Avx8(splat8(0.0));
    const ONE: Avx8 = Avx8(splat8(1.0));
    const TWO: Avx8 = Avx8(splat8(2.0));
    const FOUR: Avx8 = Avx8(splat8(4.0));
    #[inline(always)]
    fn from_f64(x: f64) -> Avx8 {
        Avx8(avx!(_mm512_set1_pd(x)))
    }
    #[inline(always)]
    fn sqrt(self) -> Avx8 {
        Avx8(avx!(_mm512_sqrt_pd(self.0)))
    }
    #[inline(always)]
    fn copysign(self, sign: Avx8) -> Avx8 {
        // The sign bit of `sign`, the other bits of `self` (f64::copysign).
        Avx8(avx!(_mm512_or_pd(
            _mm512_andnot_pd(SIGN8, self.0),
            _mm512_and_pd(SIGN8, sign.0)
        )))
    }
    #[inline(always)]
    fn is_nan(self) -> Avx8Mask {
        Avx8Mask(avx!(_mm512_cmp_pd_mask::<_CMP_UNORD_Q>(self.0, self.0)))
    }
    #[inline(always)]
    fn is_finite(self) -> Avx8Mask {
        // |x| < ∞: false for the infinities and NaN.
        let magnitude = avx!(_mm512_andnot_pd(SIGN8, self.0));
        Avx8Mask(avx!(_mm512_cmp_pd_mask::<_CMP_LT_OQ>(
            magnitude,
            splat8(f64::INFINITY)
        )))
    }
    compare8!(lt, _CMP_LT_OQ);
    compare8!(le, _CMP_LE_OQ);
    compare8!(gt, _CMP_GT_OQ);
    compare8!(eq, _CMP_EQ_OQ);
    #[inline(always)]
    fn select(mask: Avx8Mask, if_true: Avx8, if_false: Avx8) -> Avx8 {
        Avx8(avx!(_mm512_mask_blend_pd(mask.0, if_false.0, if_true.0)))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::geometry::Lanes;

    /// Each lane operation gives what the f64 operation gives, bit for bit,
    /// NaN, infinities, signed zeros and subnormals included (where this
    /// processor has AVX2).
    #[test]
    fn avx_lanes_compute_what_f64_computes() {
        // Out of `Avx2::run` the lanes' instructions are calls, not
        // inlined, but the same instructions: fine once AVX2 is there.
        if Avx2::detect().is_none() {
            eprintln!("no AVX2 here: the AVX lanes are not used on this machine");
            return;
        }
        {
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
                let a: [f64; 4] = std::array::from_fn(|_| next());
                let b: [f64; 4] = std::array::from_fn(|_| next());
                let (x, y) = (Avx4::from_fn(|i| a[i]), Avx4::from_fn(|i| b[i]));
                for i in 0..4 {
                    let (p, q) = (a[i], b[i]);
                    let same = |lanes: Avx4, scalar: f64| {
                        assert_eq!(lanes.lane(i).to_bits(), scalar.to_bits(), "{p} {q}")
                    };
                    same(x + y, p + q);
                    same(x - y, p - q);
                    same(x * y, p * q);
                    same(x / y, p / q);
                    same(-x, -p);
                    same(x.sqrt(), p.sqrt());
                    same(Real::copysign(x, y), p.copysign(q));
                    same(Avx4::select(x.lt(y), x, y), if p < q { p } else { q });
                    assert_eq!(x.le(y).lane(i), p <= q);
                    assert_eq!(x.gt(y).lane(i), p > q);
                    assert_eq!(Real::eq(x, y).lane(i), p == q);
                    assert_eq!(Real::is_nan(x).lane(i), p.is_nan());
                    assert_eq!(Real::is_finite(x).lane(i), p.is_finite());
                    assert_eq!(
                        (!x.lt(y)).lane(i),
                        p.partial_cmp(&q) != Some(std::cmp::Ordering::Less)
                    );
                }
            }
        }
    }

    /// The same for the eight AVX-512 lanes (where this processor has
    /// AVX-512).
    #[test]
    fn avx512_lanes_compute_what_f64_computes() {
        if Avx512::detect().is_none() {
            eprintln!("no AVX-512 here: the eight lanes are not used on this machine");
            return;
        }
        let values = [
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
            7.25,
            -1e-300,
        ];
        let n = values.len();
        for shift in 0..n {
            let a: [f64; 8] = std::array::from_fn(|i| values[i % n]);
            let b: [f64; 8] = std::array::from_fn(|i| values[(i * 5 + shift) % n]);
            let (x, y) = (Avx8::from_fn(|i| a[i]), Avx8::from_fn(|i| b[i]));
            for i in 0..8 {
                let (p, q) = (a[i], b[i]);
                let same = |lanes: Avx8, scalar: f64| {
                    assert_eq!(lanes.lane(i).to_bits(), scalar.to_bits(), "{p} {q}")
                };
                same(x + y, p + q);
                same(x - y, p - q);
                same(x * y, p * q);
                same(x / y, p / q);
                same(-x, -p);
                same(x.sqrt(), p.sqrt());
                same(Real::copysign(x, y), p.copysign(q));
                same(Avx8::select(x.lt(y), x, y), if p < q { p } else { q });
                assert_eq!(x.le(y).lane(i), p <= q);
                assert_eq!(x.gt(y).lane(i), p > q);
                assert_eq!(Real::eq(x, y).lane(i), p == q);
                assert_eq!(Real::is_nan(x).lane(i), p.is_nan());
                assert_eq!(Real::is_finite(x).lane(i), p.is_finite());
                assert_eq!(
                    (!x.lt(y)).lane(i),
                    p.partial_cmp(&q) != Some(std::cmp::Ordering::Less)
                );
            }
        }
    }
}
