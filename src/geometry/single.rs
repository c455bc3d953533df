//! The same primitives in single precision (f32), for the study's "f32
//! everywhere" method: the ray, the intersection, the hit point and the
//! normal are all evaluated in f32, so the method fails where f32 fails
//! (far from the origin, thin offsets).

use super::Primitive;
use super::plane::plane_hit;
use super::sphere::{Receding, stable_roots, textbook_roots};
use glam::{Affine3A, Mat3, Vec3};

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

/// A [`Primitive`] rounded to f32.
#[derive(Debug, Clone, PartialEq)]
pub enum Primitive32 {
    Ball { center: Vec3, radius: f32 },
    Ellipsoid { to_object: Affine3A, normal: Mat3 },
    Plane { point: Vec3, normal: Vec3 },
}

impl Primitive32 {
    pub fn new(p: &Primitive) -> Primitive32 {
        match p {
            Primitive::Ball { center, radius } => Primitive32::Ball {
                center: center.as_vec3(),
                radius: *radius as f32,
            },
            Primitive::Ellipsoid(e) => Primitive32::Ellipsoid {
                to_object: e.to_object.as_affine3a(),
                normal: e.normal.as_mat3(),
            },
            Primitive::Plane(plane) => Primitive32::Plane {
                point: plane.point.as_vec3(),
                normal: plane.normal.as_vec3(),
            },
        }
    }

    /// The nearest t > 0, in f32: the same formulas as [`Primitive::intersect`]
    /// (the direction's a = |d|² computed for balls too); `TEXTBOOK` picks
    /// the root formula.
    #[inline]
    pub fn intersect<const TEXTBOOK: bool>(&self, ray: &Ray32) -> Option<f32> {
        match self {
            Primitive32::Ball { center, radius } => {
                let f = ray.origin - *center;
                sphere::<TEXTBOOK>(f, ray.dir, *radius * *radius)
            }
            Primitive32::Ellipsoid { to_object, .. } => sphere::<TEXTBOOK>(
                to_object.transform_point3(ray.origin),
                to_object.transform_vector3(ray.dir),
                1.0,
            ),
            Primitive32::Plane { point, normal } => {
                plane_hit(ray.origin, ray.dir, *point, *normal).get()
            }
        }
    }

    /// The unit geometric normal at `ray.at(t)`, in f32.
    #[inline]
    pub fn normal_at(&self, ray: &Ray32, t: f32) -> Vec3 {
        match self {
            Primitive32::Ball { center, .. } => (ray.at(t) - *center).normalize(),
            Primitive32::Ellipsoid { to_object, normal } => {
                let local = to_object.transform_point3(ray.origin)
                    + t * to_object.transform_vector3(ray.dir);
                (*normal * local).normalize()
            }
            Primitive32::Plane { normal, .. } => *normal,
        }
    }
}

/// Nearest root t > 0 of |f + t d|² = r², in f32, with a = |d|² computed
/// and no early out: the stable form or the textbook formula.
#[inline]
fn sphere<const TEXTBOOK: bool>(f: Vec3, d: Vec3, r2: f32) -> Option<f32> {
    let a = d.length_squared();
    if TEXTBOOK {
        textbook_roots(f, d, a, r2).get()
    } else {
        stable_roots(f, d, a, r2, Receding::Solve).get()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use glam::DVec3;

    #[test]
    fn agrees_with_f64_near_the_origin() {
        let ball = Primitive::Ball {
            center: DVec3::new(0.5, 0.0, 5.0),
            radius: 1.5,
        };
        let ray = super::super::Ray::new(DVec3::ZERO, DVec3::new(0.1, 0.05, 1.0).normalize());
        let t64 = ball.intersect::<false, f64>(&ray).get().unwrap();
        let p = Primitive32::new(&ball);
        let r = Ray32::from_f64(&ray);
        for t in [p.intersect::<false>(&r), p.intersect::<true>(&r)] {
            assert!((f64::from(t.unwrap()) - t64).abs() < 1e-5);
        }
    }
}
