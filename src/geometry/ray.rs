use glam::DVec3;

/// A half-line `origin + t · dir`, t > 0.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Ray {
    pub origin: DVec3,
    /// Unit length in world space; in object space it carries the scale.
    pub dir: DVec3,
}

impl Ray {
    pub fn new(origin: DVec3, dir: DVec3) -> Ray {
        Ray { origin, dir }
    }

    /// The point at parameter t.
    pub fn at(&self, t: f64) -> DVec3 {
        self.origin + t * self.dir
    }
}
