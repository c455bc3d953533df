//! Ray against the unit sphere |P|² = 1 centred on the origin.

use super::Ray;

/// Nearest root t > 0 of |o + t d|² = 1, or `None`.
///
/// Numerically stable form: the discriminant is computed from the distance
/// of the line to the centre (Hearn & Baker, as in *Ray Tracing Gems* ch. 7),
/// which does not cancel when the sphere is small and far, and the two roots
/// come from `q` and `c / q`, which avoids subtracting nearly equal numbers.
pub fn intersect_sphere(ray: &Ray) -> Option<f64> {
    let (o, d) = (ray.origin, ray.dir);
    let a = d.length_squared();
    // Half of the usual b: the quadratic is a t² + 2 b t + c = 0.
    let b = o.dot(d);
    let c = o.length_squared() - 1.0;
    // Δ/4 = b² − a c = a (1 − |l|²), l the closest point of the line to the centre.
    let l = o - (b / a) * d;
    let quarter_disc = a * (1.0 - l.length_squared());
    if quarter_disc.is_nan() || quarter_disc < 0.0 {
        return None;
    }
    let q = -(b + quarter_disc.sqrt().copysign(b));
    if q == 0.0 {
        // Tangent ray through the centre's perpendicular foot: b = Δ = 0.
        return None;
    }
    let (t0, t1) = (q / a, c / q);
    nearest_positive(t0, t1)
}

/// Nearest root t > 0 of |o + t d − center|² = radius² for a unit
/// direction d: the same stable formula in world space, for spheres whose
/// transform is a similarity.
#[inline]
pub fn intersect_ball(ray: &Ray, center: glam::DVec3, radius: f64) -> Option<f64> {
    // f: from the centre to the origin; with |d| = 1 the quadratic is
    // t² + 2 b t + c = 0.
    let f = ray.origin - center;
    let d = ray.dir;
    let b = f.dot(d);
    let r2 = radius * radius;
    let c = f.length_squared() - r2;
    if c > 0.0 && b > 0.0 {
        return None; // outside the sphere and moving away from it
    }
    // Δ/4 = r² − |l|², l the foot of the perpendicular from the centre.
    let l = f - b * d;
    let quarter_disc = r2 - l.length_squared();
    if quarter_disc.is_nan() || quarter_disc < 0.0 {
        return None;
    }
    let q = -(b + quarter_disc.sqrt().copysign(b));
    if q == 0.0 {
        return None;
    }
    nearest_positive(q, c / q)
}

/// The textbook root formula (−b ± √(b² − 4ac)) / 2a, kept for the study of
/// where it fails: it cancels for small, distant spheres.
pub fn intersect_sphere_textbook(ray: &Ray) -> Option<f64> {
    let (o, d) = (ray.origin, ray.dir);
    let a = d.length_squared();
    let b = 2.0 * o.dot(d);
    let c = o.length_squared() - 1.0;
    let disc = b * b - 4.0 * a * c;
    if disc.is_nan() || disc < 0.0 {
        return None;
    }
    let sq = disc.sqrt();
    nearest_positive((-b - sq) / (2.0 * a), (-b + sq) / (2.0 * a))
}

/// The textbook formula for a ball in world space (unit direction d):
/// a = 1, b = 2 f·d, c = |f|² − r², roots (−b ± √(b² − 4c)) / 2. Kept for
/// the study: it cancels when the origin is far from a small ball.
#[inline]
pub fn intersect_ball_textbook(ray: &Ray, center: glam::DVec3, radius: f64) -> Option<f64> {
    let f = ray.origin - center;
    let b = 2.0 * f.dot(ray.dir);
    let c = f.length_squared() - radius * radius;
    let disc = b * b - 4.0 * c;
    if disc.is_nan() || disc < 0.0 {
        return None;
    }
    let sq = disc.sqrt();
    nearest_positive((-b - sq) / 2.0, (-b + sq) / 2.0)
}

/// The smaller of two roots that is > 0, in f64 or f32 (`T::default()` is
/// zero). NaN roots are never chosen.
#[inline]
pub(super) fn nearest_positive<T: PartialOrd + Copy + Default>(t0: T, t1: T) -> Option<T> {
    let zero = T::default();
    let (near, far) = if t0 <= t1 { (t0, t1) } else { (t1, t0) };
    if near > zero {
        Some(near)
    } else if far > zero {
        Some(far)
    } else {
        None
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use glam::DVec3;

    #[test]
    fn hits_the_front_from_outside() {
        let r = Ray::new(DVec3::new(0.0, 0.0, -5.0), DVec3::Z);
        assert_eq!(intersect_sphere(&r), Some(4.0));
        assert_eq!(intersect_sphere_textbook(&r), Some(4.0));
        assert_eq!(intersect_ball_textbook(&r, DVec3::ZERO, 1.0), Some(4.0));
    }

    #[test]
    fn ball_matches_the_unit_sphere_scaled() {
        let c = DVec3::new(1.0, -2.0, 10.0);
        let r = Ray::new(DVec3::ZERO, (c + DVec3::new(0.5, 0.0, 0.0)).normalize());
        let t = intersect_ball(&r, c, 2.0).unwrap();
        let local = Ray::new((r.origin - c) / 2.0, r.dir / 2.0);
        let u = intersect_sphere(&local).unwrap();
        assert!((t - u).abs() < 1e-12, "{t} {u}");
        assert!(((r.at(t) - c).length() - 2.0).abs() < 1e-12);
    }

    #[test]
    fn hits_the_far_side_from_inside() {
        let r = Ray::new(DVec3::ZERO, DVec3::X);
        assert_eq!(intersect_sphere(&r), Some(1.0));
    }

    #[test]
    fn misses_behind_and_beside() {
        assert_eq!(
            intersect_sphere(&Ray::new(DVec3::new(0.0, 0.0, 5.0), DVec3::Z)),
            None
        );
        assert_eq!(
            intersect_sphere(&Ray::new(DVec3::new(0.0, 1.5, -5.0), DVec3::Z)),
            None
        );
    }

    #[test]
    fn scaled_direction_gives_world_distance() {
        // A sphere of radius 2 seen in its object space: the unit world
        // direction becomes length 1/2, and t stays the world distance.
        let r = Ray::new(DVec3::new(0.0, 0.0, -5.0), DVec3::Z * 0.5);
        assert_eq!(intersect_sphere(&r), Some(8.0));
    }

    #[test]
    fn stable_where_the_textbook_formula_cancels() {
        // A unit sphere seen from 1e9 away: the textbook discriminant loses
        // every digit (b² and 4ac are both ~4e18), the stable one does not.
        let o = DVec3::new(0.0, 0.0, -1e9);
        let hit = Ray::new(o, DVec3::new(0.0, 0.5e-9, 1.0).normalize());
        let exact = 1e9 - 0.75_f64.sqrt();
        let t = intersect_sphere(&hit).unwrap();
        assert!((t - exact).abs() < 1e-6, "{t}");
        let t = intersect_sphere_textbook(&hit).unwrap();
        assert!((t - exact).abs() > 0.5, "{t}");
        // Passing 1.5 from the centre: a miss, which the textbook formula
        // reports as a tangent hit.
        let miss = Ray::new(o, DVec3::new(0.0, 1.5e-9, 1.0).normalize());
        assert_eq!(intersect_sphere(&miss), None);
        assert!(intersect_sphere_textbook(&miss).is_some());
    }
}
