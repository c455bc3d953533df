use super::Vector;
use glam::DVec3;

/// A half-line `origin + t · dir`, t > 0; or, with lanes of vectors
/// ([`super::DVec3x4`]), one ray per lane.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Ray<V = DVec3> {
    pub origin: V,
    /// Unit length in world space; in object space it carries the scale.
    pub dir: V,
}

impl<V: Vector> Ray<V> {
    pub fn new(origin: V, dir: V) -> Ray<V> {
        Ray { origin, dir }
    }

    /// The point at parameter t.
    #[inline(always)]
    pub fn at(&self, t: V::Real) -> V {
        self.origin + self.dir.scaled(t)
    }
}
