//! Ray against a plane (the object-space plane z = 0 placed in the world:
//! a point and a unit normal).

use super::Ray;

/// t > 0 where the ray meets the plane through `point` with unit `normal`
/// (world space), or `None` when parallel or moving away.
#[inline]
pub fn intersect_plane_world(ray: &Ray, point: glam::DVec3, normal: glam::DVec3) -> Option<f64> {
    let denom = normal.dot(ray.dir);
    let num = normal.dot(point - ray.origin);
    // t = num / denom > 0 needs equal signs: most planes behind the ray are
    // dismissed without the division.
    if denom == 0.0 || (num > 0.0) != (denom > 0.0) {
        return None;
    }
    let t = num / denom;
    (t > 0.0 && t.is_finite()).then_some(t)
}

#[cfg(test)]
mod tests {
    use super::*;
    use glam::DVec3;

    /// The plane z = 0.
    fn intersect_plane(ray: &Ray) -> Option<f64> {
        intersect_plane_world(ray, DVec3::ZERO, DVec3::Z)
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
