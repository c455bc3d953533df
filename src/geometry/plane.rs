//! Ray against the plane z = 0.

use super::Ray;

/// t > 0 where o.z + t d.z = 0, or `None` when the ray is parallel to the
/// plane or moving away from it.
pub fn intersect_plane(ray: &Ray) -> Option<f64> {
    if ray.dir.z == 0.0 {
        return None;
    }
    let t = -ray.origin.z / ray.dir.z;
    (t > 0.0 && t.is_finite()).then_some(t)
}

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
