//! Four f64 lanes in one 256-bit AVX register, for the renderer's packets
//! on processors that have AVX2, chosen at run time: the binary is built
//! for baseline x86-64, where [`super::F64x4`] holds its lanes in pairs of
//! SSE2 registers.
//!
//! [`Avx4`] does what [`super::F64x4`] does, lane for lane and bit for bit
//! (the same IEEE operations: add, subtract, multiply, divide, square root,
//! ordered comparisons that are false for NaN, selection by mask); the
//! tests below check it against f64 on random and special values.
//!
//! This is the crate's one module with `unsafe`. Its single invariant: an
//! AVX instruction runs only on a processor that has AVX2. Every `unsafe`
//! block here is an `avx!` call, and every value of [`Avx4`] or
//! [`AvxMask`] that reaches one is made under [`Avx2::run`], which exists
//! only once [`Avx2::detect`] has seen the processor's AVX2 (the renderer
//! picks the `Avx4` kernel only there). Making the constants does not run
//! any instruction.
#![allow(unsafe_code)]

use super::precision::{Mask, Real, four_lanes};
use std::arch::x86_64::*;
use std::ops::{Add, BitAnd, BitOr, BitXor, Div, Mul, Neg, Not, Sub};
use std::sync::OnceLock;

/// An AVX instruction, run only where [`Avx2::detect`] found AVX2.
macro_rules! avx {
    ($e:expr) => {
        // SAFETY: this module's values are operated on only under
        // `Avx2::run`, after `Avx2::detect` found AVX2 on this processor
        // (see the module documentation).
        unsafe { $e }
    };
}

/// Proof that this processor has AVX2: made only by [`Avx2::detect`].
#[derive(Debug, Clone, Copy)]
pub struct Avx2(());

impl Avx2 {
    /// `Some` when the processor has AVX2, and `RAYOFLIGHT_SIMD` is not
    /// `baseline` (which keeps the SSE2 lanes, to compare the two).
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

four_lanes!(Avx4);

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
}
