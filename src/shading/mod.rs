//! Shading: materials, lights and the illumination formulas of contract
//! section 5, written with its names.
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
//! multiplied by C (the brief's formula). The reflected colour I_r of
//! `whitted` is traced by the renderer, which calls [`local_color`] once per
//! bounce and weights it by the product of the ks met so far.

mod light;
mod material;
mod model;

pub use light::Light;
pub use material::{Color, Material};
pub use model::{Illumination, Model};

use glam::DVec3;

/// What one hit point needs to be shaded.
#[derive(Debug, Clone, Copy)]
pub struct SurfacePoint {
    /// The hit point M, world space.
    pub m: DVec3,
    /// Unit shading normal N, facing the incoming ray.
    pub n: DVec3,
    /// Unit vector V from M back toward the ray's origin.
    pub v: DVec3,
}

/// The colour of a hit without the reflected term: the `ambient`,
/// `lambert` or `phong` formula (`whitted` uses `phong` here).
pub fn local_color(
    illumination: Illumination,
    c: Color,
    material: &Material,
    lights: &[Light],
    p: &SurfacePoint,
) -> Color {
    let Material { ka, kd, ks, m } = *material;
    // Ambient term: ka C.
    let mut i = ka * c;
    let specular = match illumination {
        Illumination::Ambient => return i,
        Illumination::Lambert => false,
        Illumination::Phong | Illumination::Whitted => true,
    };
    let (n, v) = (p.n, p.v);
    for light in lights {
        // L: unit vector toward the light; cos θ = N · L.
        let l = (light.position - p.m).normalize();
        let cos_theta = n.dot(l);
        if cos_theta.is_nan() || cos_theta <= 0.0 {
            continue; // the light is behind the surface
        }
        let mut k = kd * cos_theta;
        if specular {
            // R: L mirrored about N; cos α = R · V.
            let r = 2.0 * cos_theta * n - l;
            let cos_alpha = r.dot(v);
            if cos_alpha > 0.0 {
                k += ks * specular_power(cos_alpha, m);
            }
        }
        i += k * light.color;
    }
    i
}

/// (cos α)^m. Whole exponents (the usual case) go through `powi`, several
/// times cheaper than `powf`; both are within an ulp or two of the exact
/// power, far below an 8-bit step.
#[inline]
fn specular_power(cos_alpha: f64, m: f64) -> f64 {
    if m.fract() == 0.0 && m <= 1024.0 {
        cos_alpha.powi(m as i32)
    } else {
        cos_alpha.powf(m)
    }
}

/// Mirror direction R = 2 (N · V) N − V of the ray arriving along −V.
pub fn reflect(n: DVec3, v: DVec3) -> DVec3 {
    2.0 * n.dot(v) * n - v
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
        let i = local_color(
            Illumination::Ambient,
            c,
            &MAT,
            &[light_at(DVec3::NEG_Z)],
            &point(),
        );
        assert_eq!(i, 0.2 * c);
    }

    #[test]
    fn light_at_45_degrees() {
        // L at 45° in the y-z plane: cos θ = √½.
        let s = std::f64::consts::FRAC_1_SQRT_2;
        let lights = [light_at(DVec3::new(0.0, -1.0, -1.0))];
        let lambert = local_color(Illumination::Lambert, DVec3::ONE, &MAT, &lights, &point());
        assert!((lambert - DVec3::splat(0.2 + 0.5 * s)).abs().max_element() < 1e-15);
        let phong = local_color(Illumination::Phong, DVec3::ONE, &MAT, &lights, &point());
        // N = (0,0,-1), L = (0,-s,-s): R = 2s N − L = (0, s, -s), so cos α = R · V = s.
        let expected = 0.2 + 0.5 * s + 0.4 * s.powf(3.0);
        assert!((phong - DVec3::splat(expected)).abs().max_element() < 1e-15);
    }

    #[test]
    fn lights_behind_the_surface_add_nothing() {
        let lights = [light_at(DVec3::new(0.0, 0.0, 5.0))];
        let i = local_color(Illumination::Phong, DVec3::ONE, &MAT, &lights, &point());
        assert_eq!(i, DVec3::splat(0.2));
    }

    #[test]
    fn reflect_mirrors_about_the_normal() {
        let v = DVec3::new(1.0, 0.0, -1.0).normalize();
        let r = reflect(DVec3::NEG_Z, v);
        assert!((r - DVec3::new(-1.0, 0.0, -1.0).normalize()).length() < 1e-15);
    }
}
