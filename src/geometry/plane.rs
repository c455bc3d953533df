//! Ray against a plane (the object-space plane z = 0 placed in the world:
//! a point and a unit normal), and the plane as a primitive
//! ([`WorldPlane`], answering [`Surface`] in f64 and f32).

use super::precision::{Lanes, Mask, Real, Vector};
use super::single::Ray32;
use super::surface::{Found, Surface, Surface32};
use super::{Aabb, Ray};
use crate::math::Transform;
use glam::{DVec3, Vec3};

/// t > 0 where the ray `origin + t · dir` meets the plane through `point`
/// with unit `normal` (per lane, not found when parallel or moving away);
/// in f64, f32 or lanes.
#[inline(always)]
pub fn plane_hit<V: Vector>(origin: V, dir: V, point: V, normal: V) -> Found<V::Real> {
    let zero = V::Real::ZERO;
    // t = num / denom, num = N·(P − O), denom = N·D.
    let denom = normal.dot(dir);
    let num = normal.dot(point - origin);
    // Receding or parallel: t > 0 needs equal signs, so most planes behind
    // the ray are dismissed without the division.
    let alive = !(denom.eq(zero) | (num.gt(zero) ^ denom.gt(zero)));
    if !alive.any() {
        return Found::none();
    }
    let t = num / denom;
    Found {
        t,
        found: alive & t.gt(zero) & t.is_finite(),
    }
}

/// [`plane_hit`] for a world-space ray.
#[inline(always)]
pub fn intersect_plane_world<V: Vector>(ray: &Ray<V>, point: V, normal: V) -> Found<V::Real> {
    plane_hit(ray.origin, ray.dir, point, normal)
}

// ----- the plane as a primitive -----

/// A plane in world space.
#[derive(Debug, Clone, PartialEq)]
pub struct WorldPlane {
    pub point: DVec3,
    /// Unit normal.
    pub normal: DVec3,
}

/// A [`WorldPlane`] in f32.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Plane32 {
    pub point: Vec3,
    pub normal: Vec3,
}

/// The plane z = 0 placed by `transform`: a plane stays a plane under
/// every affine map.
pub(super) fn primitive<P: From<Box<WorldPlane>>>(transform: &Transform) -> P {
    P::from(Box::new(WorldPlane {
        point: transform.to_world().translation,
        normal: (transform.normal_matrix() * DVec3::Z).normalize(),
    }))
}

impl Surface for WorldPlane {
    type Single = Plane32;

    #[inline(always)]
    fn intersect<const TEXTBOOK: bool, L: Lanes>(&self, ray: &Ray<L::Vector>) -> Found<L> {
        intersect_plane_world(
            ray,
            L::splat_vector(self.point),
            L::splat_vector(self.normal),
        )
    }

    #[inline(always)]
    fn normal_at(&self, _: &Ray, _: f64) -> DVec3 {
        self.normal
    }

    fn bounds(&self) -> Option<Aabb> {
        None
    }

    fn single(&self) -> Plane32 {
        Plane32 {
            point: self.point.as_vec3(),
            normal: self.normal.as_vec3(),
        }
    }
}

impl Surface32 for Plane32 {
    #[inline]
    fn intersect<const TEXTBOOK: bool>(&self, ray: &Ray32) -> Option<f32> {
        plane_hit(ray.origin, ray.dir, self.point, self.normal).get()
    }

    #[inline]
    fn normal_at(&self, _: &Ray32, _: f32) -> Vec3 {
        self.normal
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use glam::DVec3;

    /// The plane z = 0.
    fn intersect_plane(ray: &Ray) -> Option<f64> {
        intersect_plane_world(ray, DVec3::ZERO, DVec3::Z).get()
    }

    #[test]
    fn hits_from_either_side() {
        let down = Ray::new(DVec3::new(1.0, 2.0, 3.0), -DVec3::Z);
        assert_eq!(intersect_plane(&down), Some(3.0));
        let up = Ray::new(DVec3::new(1.0, 2.0, -3.0), DVec3::Z);
        assert_eq!(intersect_plane(&up), Some(3.0));
    }

    #[test]
    fn parallel_and_receding_rays_miss() {
        assert_eq!(
            intersect_plane(&Ray::new(DVec3::new(0.0, 0.0, 1.0), DVec3::X)),
            None
        );
        assert_eq!(
            intersect_plane(&Ray::new(DVec3::new(0.0, 0.0, 1.0), DVec3::Z)),
            None
        );
    }
}
