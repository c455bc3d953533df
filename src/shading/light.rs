use super::Color;
use crate::math::Vec3;

/// A point light (no shadows: lights are never occluded).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Light {
    /// World position S.
    pub position: Vec3,
    /// Intensity I per channel; 2 is twice as bright as 1.
    pub color: Color,
}
