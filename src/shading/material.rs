use crate::math::Vec3;

/// A linear RGB colour; components are ≥ 0 and may exceed 1.
pub type Color = Vec3;

/// Phong material coefficients (docs/scene-format.md, Illumination); with lanes
/// (`Material<F64x4>`), those of the surface each lane hit.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Material<R = f64> {
    /// Ambient coefficient.
    pub ka: R,
    /// Diffuse coefficient.
    pub kd: R,
    /// Specular (and, for `whitted`, reflection) coefficient.
    pub ks: R,
    /// Specular exponent (shininess).
    pub m: R,
}

impl Default for Material {
    fn default() -> Self {
        Material {
            ka: 0.2,
            kd: 0.6,
            ks: 0.2,
            m: 10.0,
        }
    }
}
