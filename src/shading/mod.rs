//! Shading: materials, lights and the illumination formulas of the scene
//! format's Illumination section (docs/scene-format.md), written with its
//! names.
//!
//! At a hit point M with unit shading normal N (facing the incoming ray) and
//! unit V pointing back along the ray, for each light l at S_l of colour I_l:
//!
//! ```text
//! L_l = normalize(S_l − M)      cos θ_l = N · L_l
//! R_l = 2 cos θ_l N − L_l       cos α_l = R_l · V
//! ambient  I = ka C
//! lambert  I = ka C + Σ I_l kd cos θ_l
//! phong    I = ka C + Σ I_l (kd cos θ_l + ks (cos α_l)^m)
//! whitted  I = phong + ks I_r
//! ```
//!
//! A light contributes nothing where cos θ_l ≤ 0, the specular term nothing
//! where cos α_l ≤ 0; there are no shadows, and the diffuse term is not
//! multiplied by C (as in docs/scene-format.md's formulas). The reflected
//! colour I_r of `whitted` is traced by the renderer, which calls
//! [`local_color`] once per bounce and weights it by the product of the ks
//! met so far.

mod light;
mod material;
mod model;

pub use light::Light;
pub use material::{Color, Material};
pub use model::{Illumination, Model};

use crate::geometry::{Lanes, MAX_LANES, Mask, Real, Vector};
use glam::DVec3;

/// What one hit point needs to be shaded (per lane, with lanes).
#[derive(Debug, Clone, Copy)]
pub struct SurfacePoint<V = DVec3> {
    /// The hit point M, world space.
    pub m: V,
    /// Unit shading normal N, facing the incoming ray.
    pub n: V,
    /// Unit vector V from M back toward the ray's origin.
    pub v: V,
}

/// The three terms of a hit's own colour (per lane, with lanes), as
/// [`local_color`] computes them.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Terms<V = DVec3> {
    /// ka C.
    pub ambient: V,
    /// Σ I_l kd cos θ_l over the lights in front of the surface.
    pub diffuse: V,
    /// Σ I_l ks (cos α_l)^m over those whose mirror direction faces V.
    pub specular: V,
}

impl<V: Vector> Terms<V> {
    /// The hit's own colour: (ambient + diffuse) + specular, added in
    /// that order (the renderer's order, which the passes and the
    /// explained pixel repeat bit for bit).
    #[inline(always)]
    pub fn local(&self) -> V {
        (self.ambient + self.diffuse) + self.specular
    }
}

/// Sees each light's share of a hit as [`local_color`] computes it: the
/// explained pixel's numbers. `()` sees nothing (renders).
pub trait LightObserver<L: Lanes> {
    /// Light `index` at the hit: cos θ, cos α (`None` where the model
    /// has no specular term or no lane is lit), and what it added to the
    /// diffuse and specular sums (zero where nothing).
    #[inline(always)]
    fn light(
        &mut self,
        index: usize,
        cos_theta: L,
        cos_alpha: Option<L>,
        diffuse: L::Vector,
        specular: L::Vector,
    ) {
        let _ = (index, cos_theta, cos_alpha, diffuse, specular);
    }
}

impl<L: Lanes> LightObserver<L> for () {}

/// The colour of a hit without the reflected term: the `ambient`,
/// `lambert` or `phong` formula (`whitted` uses `phong` here), as its
/// three [`Terms`]. One hit, or one per lane (each lane with its
/// surface's C and material): a lane computes what the hit alone would,
/// bit for bit.
#[inline(always)]
pub fn local_color<L: Lanes>(
    illumination: Illumination,
    c: L::Vector,
    material: &Material<L>,
    lights: &[Light],
    p: &SurfacePoint<L::Vector>,
    observer: &mut impl LightObserver<L>,
) -> Terms<L::Vector> {
    let Material { ka, kd, ks, m } = *material;
    let zero = L::splat_vector(DVec3::ZERO);
    let mut terms = Terms {
        // Ambient term: ka C.
        ambient: c.scaled(ka),
        diffuse: zero,
        specular: zero,
    };
    let specular = match illumination {
        Illumination::Ambient => return terms,
        Illumination::Lambert => false,
        Illumination::Phong | Illumination::Whitted => true,
    };
    let (n, v) = (p.n, p.v);
    for (index, light) in lights.iter().enumerate() {
        // L: unit vector toward the light; cos θ = N · L.
        let l = (L::splat_vector(light.position) - p.m).normalize();
        let cos_theta = n.dot(l);
        // Lit: the light is in front of the surface.
        let lit = !(cos_theta.is_nan() | cos_theta.le(L::ZERO));
        if !lit.any() {
            observer.light(index, cos_theta, None, zero, zero);
            continue;
        }
        let intensity = L::splat_vector(light.color);
        // Diffuse: I kd cos θ (the factor 0 in unlit lanes, which then
        // add +0: the sum is as if they were left out).
        let diffuse = intensity.scaled(L::select(lit, kd * cos_theta, L::ZERO));
        terms.diffuse = terms.diffuse + diffuse;
        let mut seen_alpha = None;
        let mut shine = zero;
        if specular {
            // R: L mirrored about N; cos α = R · V.
            let r = n.scaled(L::TWO * cos_theta) - l;
            let cos_alpha = r.dot(v);
            // Specular: I ks (cos α)^m, where R faces V.
            let highlight = lit & cos_alpha.gt(L::ZERO);
            if highlight.any() {
                let factor = ks * specular_power(cos_alpha, m);
                shine = intensity.scaled(L::select(highlight, factor, L::ZERO));
                terms.specular = terms.specular + shine;
            }
            seen_alpha = Some(cos_alpha);
        }
        observer.light(index, cos_theta, seen_alpha, diffuse, shine);
    }
    terms
}

/// Largest whole exponent raised by multiplications.
const MAX_WHOLE_POWER: f64 = 1024.0;

/// (cos α)^m per lane. A whole exponent (the usual case) is raised by
/// binary exponentiation, exactly as `f64::powi` does it (the standard
/// library's `__powidf2`: square, multiply where a bit is set, invert for
/// a negative power), several times cheaper than `powf`; both are within
/// an ulp or two of the exact power, far below an 8-bit step. Other
/// exponents go through `powf`, one lane at a time.
#[inline(always)]
fn specular_power<L: Lanes>(cos_alpha: L, m: L) -> L {
    // The lanes as plain values first (closures below stay scalar).
    let (mut ms, mut xs) = ([0.0; MAX_LANES], [0.0; MAX_LANES]);
    for i in 0..L::WIDTH {
        (ms[i], xs[i]) = (m.lane(i), cos_alpha.lane(i));
    }
    let mut whole = [false; MAX_LANES];
    let mut exponent = [0i32; MAX_LANES];
    for i in 0..L::WIDTH {
        let m = ms[i];
        // m.fract() == 0, without a call to trunc where it fits an i32.
        let fraction_free = if m >= -2_147_483_648.0 {
            f64::from(m as i32) == m
        } else {
            m.fract() == 0.0
        };
        whole[i] = fraction_free && m <= MAX_WHOLE_POWER;
        // The exponent as powi takes it (0 for the lanes that are not
        // whole: their result is replaced).
        exponent[i] = if whole[i] { m as i32 } else { 0 };
    }
    // Each lane multiplies where its own exponent has a bit set.
    let (mut power, mut a) = (L::ONE, cos_alpha);
    let mut bits = [0u32; MAX_LANES];
    for i in 0..L::WIDTH {
        bits[i] = exponent[i].unsigned_abs();
    }
    loop {
        let odd = L::Mask::from_fn(|i| bits[i] & 1 != 0);
        if odd.any() {
            power = L::select(odd, power * a, power);
        }
        let mut left = 0;
        for b in &mut bits[..L::WIDTH] {
            *b >>= 1;
            left |= *b;
        }
        if left == 0 {
            break;
        }
        a = a * a;
    }
    let negative = L::Mask::from_fn(|i| exponent[i] < 0);
    if negative.any() {
        power = L::select(negative, L::ONE / power, power);
    }
    if whole[..L::WIDTH].iter().all(|&w| w) {
        return power;
    }
    let mut powers = [0.0; MAX_LANES];
    for (i, p) in powers.iter_mut().enumerate().take(L::WIDTH) {
        *p = if whole[i] {
            power.lane(i)
        } else {
            xs[i].powf(ms[i])
        };
    }
    L::from_fn(|i| powers[i])
}

/// Mirror direction R = 2 (N · V) N − V of the ray arriving along −V (per
/// lane, in any precision).
#[inline(always)]
pub fn reflect<V: Vector>(n: V, v: V) -> V {
    n.scaled(V::Real::TWO * n.dot(v)) - v
}

#[cfg(test)]
mod tests {
    use super::*;

    fn point() -> SurfacePoint {
        SurfacePoint {
            m: DVec3::ZERO,
            n: DVec3::NEG_Z,
            v: DVec3::NEG_Z,
        }
    }

    fn light_at(position: DVec3) -> Light {
        Light {
            position,
            color: DVec3::ONE,
        }
    }

    const MAT: Material = Material {
        ka: 0.2,
        kd: 0.5,
        ks: 0.4,
        m: 3.0,
    };

    #[test]
    fn ambient_is_ka_times_c() {
        let c = DVec3::new(1.0, 0.5, 0.0);
        let i = local_color::<f64>(
            Illumination::Ambient,
            c,
            &MAT,
            &[light_at(DVec3::NEG_Z)],
            &point(),
            &mut (),
        );
        assert_eq!(i.local(), 0.2 * c);
    }

    #[test]
    fn light_at_45_degrees() {
        // L at 45° in the y-z plane: cos θ = √½.
        let s = std::f64::consts::FRAC_1_SQRT_2;
        let lights = [light_at(DVec3::new(0.0, -1.0, -1.0))];
        let lambert = local_color::<f64>(
            Illumination::Lambert,
            DVec3::ONE,
            &MAT,
            &lights,
            &point(),
            &mut (),
        );
        assert!(
            (lambert.local() - DVec3::splat(0.2 + 0.5 * s))
                .abs()
                .max_element()
                < 1e-15
        );
        assert_eq!(lambert.specular, DVec3::ZERO);
        let phong = local_color::<f64>(
            Illumination::Phong,
            DVec3::ONE,
            &MAT,
            &lights,
            &point(),
            &mut (),
        );
        assert_eq!(phong.ambient, DVec3::splat(0.2));
        assert!((phong.diffuse - DVec3::splat(0.5 * s)).abs().max_element() < 1e-15);
        assert!(
            (phong.specular - DVec3::splat(0.4 * s.powf(3.0)))
                .abs()
                .max_element()
                < 1e-15
        );
        let phong = phong.local();
        // N = (0,0,-1), L = (0,-s,-s): R = 2s N − L = (0, s, -s), so cos α = R · V = s.
        let expected = 0.2 + 0.5 * s + 0.4 * s.powf(3.0);
        assert!((phong - DVec3::splat(expected)).abs().max_element() < 1e-15);
    }

    #[test]
    fn lights_behind_the_surface_add_nothing() {
        let lights = [light_at(DVec3::new(0.0, 0.0, 5.0))];
        let i = local_color::<f64>(
            Illumination::Phong,
            DVec3::ONE,
            &MAT,
            &lights,
            &point(),
            &mut (),
        );
        assert_eq!(i.local(), DVec3::splat(0.2));
    }

    #[test]
    fn reflect_mirrors_about_the_normal() {
        let v = DVec3::new(1.0, 0.0, -1.0).normalize();
        let r = reflect(DVec3::NEG_Z, v);
        assert!((r - DVec3::new(-1.0, 0.0, -1.0).normalize()).length() < 1e-15);
    }
}

#[cfg(test)]
mod power {
    use super::*;
    use crate::geometry::F64x4;

    /// The binary exponentiation is `f64::powi`, bit for bit, for every
    /// whole exponent it takes, one value or four lanes (mixed with
    /// exponents that go through `powf`).
    #[test]
    fn whole_powers_are_powi_bit_for_bit() {
        let mut x = 0.123_456_789_f64;
        for m in (-1100..=1024).chain([i32::MIN, -100_000]) {
            for _ in 0..8 {
                x = (x * 3.7 + 0.31).fract();
                let expected = x.powi(m);
                let m = f64::from(m);
                assert_eq!(
                    specular_power(x, m).to_bits(),
                    expected.to_bits(),
                    "{x}^{m}"
                );
                let lanes = specular_power(
                    F64x4::from_fn(|i| x + i as f64 * 0.01),
                    F64x4::from_fn(|i| if i == 1 { m + 0.5 } else { m }),
                );
                for i in [0, 2, 3] {
                    let x = x + i as f64 * 0.01;
                    assert_eq!(lanes.lane(i).to_bits(), x.powi(m as i32).to_bits());
                }
                assert_eq!(lanes.lane(1).to_bits(), (x + 0.01).powf(m + 0.5).to_bits());
            }
        }
    }
}
