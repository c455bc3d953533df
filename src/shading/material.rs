use crate::math::Vec3;

/// A linear RGB colour; components are ≥ 0 and may exceed 1.
pub type Color = Vec3;

/// Phong material coefficients (contract section 5).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Material {
    /// Ambient coefficient.
    pub ka: f64,
    /// Diffuse coefficient.
    pub kd: f64,
    /// Specular (and, for `whitted`, reflection) coefficient.
    pub ks: f64,
    /// Specular exponent (shininess).
    pub m: f64,
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
