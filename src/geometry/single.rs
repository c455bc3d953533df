//! Rays in single precision (f32), for the study's "f32 everywhere"
//! method: the ray, the intersection, the hit point and the normal are all
//! evaluated in f32, so the method fails where f32 fails (far from the
//! origin, thin offsets). Each primitive's f32 form is its shape's
//! ([`super::Surface32`]), dispatched by [`super::Primitive32`].

use glam::Vec3;

/// A ray in f32: `origin + t · dir`, unit `dir` in world space.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Ray32 {
    pub origin: Vec3,
    pub dir: Vec3,
}

impl Ray32 {
    pub fn new(origin: Vec3, dir: Vec3) -> Ray32 {
        Ray32 { origin, dir }
    }

    /// The f32 ray nearest to an f64 one.
    pub fn from_f64(ray: &super::Ray) -> Ray32 {
        Ray32::new(ray.origin.as_vec3(), ray.dir.as_vec3())
    }

    /// The same ray in f64 (exact), for the BVH's box tests.
    pub fn to_f64(&self) -> super::Ray {
        super::Ray::new(self.origin.as_dvec3(), self.dir.as_dvec3())
    }

    pub fn at(&self, t: f32) -> Vec3 {
        self.origin + t * self.dir
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use glam::DVec3;

    #[test]
    fn agrees_with_f64_near_the_origin() {
        let ball = super::super::Primitive::Ball(super::super::Ball {
            center: DVec3::new(0.5, 0.0, 5.0),
            radius: 1.5,
        });
        let ray = super::super::Ray::new(DVec3::ZERO, DVec3::new(0.1, 0.05, 1.0).normalize());
        let t64 = ball.intersect::<false, f64>(&ray).get().unwrap();
        let p = super::super::Primitive32::new(&ball);
        let r = Ray32::from_f64(&ray);
        for t in [p.intersect::<false>(&r), p.intersect::<true>(&r)] {
            assert!((f64::from(t.unwrap()) - t64).abs() < 1e-5);
        }
    }
}
