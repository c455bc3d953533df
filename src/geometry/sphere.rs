//! Ray against a sphere: the quadratic |f + t d|² = r² in t, f from the
//! centre to the ray's origin, d the ray's direction. Written once, generic
//! over the precision ([`Vector`]): the f64 reference and the study's f32
//! method run the same formulas.
//!
//! Two root formulas:
//!
//! - [`stable_roots`]: the numerically stable form (the reference);
//! - [`textbook_roots`]: (−b ± √(b² − 4ac)) / 2a, kept for the study of
//!   where it fails.
//!
//! Each takes the leading coefficient a as a [`Leading`]: the computed
//! |d|² (object space, where the direction is scaled), or [`UnitDirection`]
//! (world space, where a = 1 and is never applied).
//!
//! The sphere as a primitive is here too: a [`Ball`] (a sphere under a
//! similarity, in world space) or an [`Ellipsoid`] (any other, in its own
//! space), each answering [`Surface`] in f64 and f32; which one an object
//! becomes, [`primitive`].

use super::precision::{Lanes, MAX_LANES, Mask, Real, Vector};
use super::single::Ray32;
use super::surface::{Found, LaneNormal, Surface, Surface32};
use super::{Aabb, Ray};
use crate::math::Transform;
use glam::{Affine3A, DAffine3, DMat3, DVec3, Mat3, Vec3};

/// The leading coefficient a = |d|² of the quadratic, as the formulas
/// apply it.
pub trait Leading<R: Real>: Copy {
    /// a · x.
    fn times(self, x: R) -> R;
    /// k · a, for a constant k (2a, 4a).
    fn multiple(self, k: R) -> R;
    /// x / a.
    fn divide(self, x: R) -> R;
}

/// a = 1: a unit direction. Applying it is no operation at all (not a
/// product or quotient by one), so the unit-direction formulas keep their
/// own arithmetic.
#[derive(Debug, Clone, Copy)]
pub struct UnitDirection;

impl<R: Real> Leading<R> for UnitDirection {
    #[inline(always)]
    fn times(self, x: R) -> R {
        x
    }
    #[inline(always)]
    fn multiple(self, k: R) -> R {
        k
    }
    #[inline(always)]
    fn divide(self, x: R) -> R {
        x
    }
}

/// a = |d|², computed by the caller.
impl<R: Real> Leading<R> for R {
    #[inline(always)]
    fn times(self, x: R) -> R {
        self * x
    }
    #[inline(always)]
    fn multiple(self, k: R) -> R {
        k * self
    }
    #[inline(always)]
    fn divide(self, x: R) -> R {
        x / self
    }
}

/// What the stable formula does with a ray that starts outside the sphere
/// (c > 0) and moves away from it (b > 0): it has no root t > 0.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Receding {
    /// Dismissed before the discriminant (most spheres behind the ray).
    Dismiss,
    /// Solved like any other ray.
    Solve,
}

/// Nearest root t > 0 of |f + t d|² = r²: the numerically stable form.
///
/// The discriminant is computed from the distance of the line to the
/// centre (Hearn & Baker, as in *Ray Tracing Gems* ch. 7), which does not
/// cancel when the sphere is small and far, and the two roots come from
/// `q` and `c / q`, which avoids subtracting nearly equal numbers.
///
/// With lanes, each early out drops the lanes it concerns and returns
/// once none is left; the survivors compute what a single ray would.
#[inline(always)]
pub fn stable_roots<V: Vector>(
    f: V,
    d: V,
    a: impl Leading<V::Real>,
    r2: V::Real,
    receding: Receding,
) -> Found<V::Real> {
    let zero = V::Real::ZERO;
    // Coefficients: half of the usual b, the quadratic is
    // a t² + 2 b t + c = 0.
    let b = f.dot(d);
    let c = f.length_squared() - r2;
    let mut alive = <V::Real as Real>::Mask::ALL;
    // Receding ray: outside the sphere and moving away from it.
    if receding == Receding::Dismiss {
        alive = !(c.gt(zero) & b.gt(zero));
        if !alive.any() {
            return Found::none();
        }
    }
    // Quarter discriminant: Δ/4 = b² − a c = a (r² − |l|²), l = f − (b/a) d
    // the foot of the perpendicular from the centre to the line.
    let l = f - d.scaled(a.divide(b));
    let quarter_disc = a.times(r2 - l.length_squared());
    alive = alive & !(quarter_disc.is_nan() | quarter_disc.lt(zero));
    if !alive.any() {
        return Found::none();
    }
    // Roots: q = −(b + sign(b) √(Δ/4)), then t = q / a and t = c / q.
    let q = -(b + quarter_disc.sqrt().copysign(b));
    // q = 0: a tangent ray through the centre's perpendicular foot
    // (b = Δ = 0).
    alive = alive & !q.eq(zero);
    if !alive.any() {
        return Found::none();
    }
    let nearest = nearest_positive(a.divide(q), c / q);
    Found {
        t: nearest.t,
        found: alive & nearest.found,
    }
}

/// Nearest root t > 0 of |f + t d|² = r²: the textbook root formula
/// (−b ± √(b² − 4ac)) / 2a. It cancels for small, distant spheres.
#[inline(always)]
pub fn textbook_roots<V: Vector>(
    f: V,
    d: V,
    a: impl Leading<V::Real>,
    r2: V::Real,
) -> Found<V::Real> {
    // Coefficients: the usual b, the quadratic is a t² + b t + c = 0.
    let b = V::Real::TWO * f.dot(d);
    let c = f.length_squared() - r2;
    // Discriminant: Δ = b² − 4ac.
    let disc = b * b - a.multiple(V::Real::FOUR) * c;
    let alive = !(disc.is_nan() | disc.lt(V::Real::ZERO));
    if !alive.any() {
        return Found::none();
    }
    // Roots: (−b ∓ √Δ) / 2a.
    let sq = disc.sqrt();
    let nearest = nearest_positive(
        (-b - sq) / a.multiple(V::Real::TWO),
        (-b + sq) / a.multiple(V::Real::TWO),
    );
    Found {
        t: nearest.t,
        found: alive & nearest.found,
    }
}

/// Nearest root t > 0 of |o + t d|² = 1 (the unit sphere in its own
/// space; d is the mapped direction, not unit), stable form.
#[inline(always)]
pub fn intersect_sphere<V: Vector>(ray: &Ray<V>) -> Found<V::Real> {
    let d = ray.dir;
    stable_roots(
        ray.origin,
        d,
        d.length_squared(),
        V::Real::ONE,
        Receding::Solve,
    )
}

/// Nearest root t > 0 of |o + t d − center|² = radius² for a unit
/// direction d: the stable form in world space, for spheres whose
/// transform is a similarity. `r2` is radius².
#[inline(always)]
pub fn intersect_ball<V: Vector>(ray: &Ray<V>, center: V, r2: V::Real) -> Found<V::Real> {
    stable_roots(
        ray.origin - center,
        ray.dir,
        UnitDirection,
        r2,
        Receding::Dismiss,
    )
}

/// The textbook formula for the unit sphere in its own space.
#[inline(always)]
pub fn intersect_sphere_textbook<V: Vector>(ray: &Ray<V>) -> Found<V::Real> {
    let d = ray.dir;
    textbook_roots(ray.origin, d, d.length_squared(), V::Real::ONE)
}

/// The textbook formula for a ball in world space (unit direction d):
/// a = 1, roots (−b ± √(b² − 4c)) / 2. It cancels when the origin is far
/// from a small ball. `r2` is radius².
#[inline(always)]
pub fn intersect_ball_textbook<V: Vector>(ray: &Ray<V>, center: V, r2: V::Real) -> Found<V::Real> {
    textbook_roots(ray.origin - center, ray.dir, UnitDirection, r2)
}

/// The smaller of two roots that is > 0 (per lane). NaN roots are never
/// chosen.
#[inline(always)]
pub(super) fn nearest_positive<R: Real>(t0: R, t1: R) -> Found<R> {
    let zero = R::ZERO;
    let ordered = t0.le(t1);
    let (near, far) = (R::select(ordered, t0, t1), R::select(ordered, t1, t0));
    let near_ahead = near.gt(zero);
    Found {
        t: R::select(near_ahead, near, far),
        found: near_ahead | far.gt(zero),
    }
}

// ----- the sphere as a primitive -----

/// A sphere under a similarity, in world space: no matrix work to
/// intersect it.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Ball {
    pub center: DVec3,
    pub radius: f64,
}

/// Any other sphere: intersected in its own space.
#[derive(Debug, Clone, PartialEq)]
pub struct Ellipsoid {
    /// World to object space.
    pub to_object: DAffine3,
    /// Object-space normals to world space: (M⁻¹)ᵀ.
    pub normal: DMat3,
    /// Object to world, for the bounding box.
    pub to_world: DAffine3,
}

/// A [`Ball`] in f32.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Ball32 {
    pub center: Vec3,
    pub radius: f32,
}

/// An [`Ellipsoid`] in f32.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Ellipsoid32 {
    pub to_object: Affine3A,
    pub normal: Mat3,
}

/// A sphere placed by `transform`: a [`Ball`] under a similarity, else an
/// [`Ellipsoid`] (as the table of kinds, [`super::Primitive`], holds them).
pub(super) fn primitive<P: From<Ball> + From<Box<Ellipsoid>>>(transform: &Transform) -> P {
    let m = transform.to_world();
    match similarity_scale(&m.matrix3) {
        Some(radius) => P::from(Ball {
            center: m.translation,
            radius,
        }),
        None => {
            let matrices = transform.matrices();
            P::from(Box::new(Ellipsoid {
                to_object: matrices.to_object,
                normal: matrices.normal,
                to_world: matrices.to_world,
            }))
        }
    }
}

/// Relative tolerance for "the linear part is a scaled orthogonal matrix".
const SIMILARITY_TOLERANCE: f64 = 1e-12;

/// `Some(s)` when the linear part is s·Q with Q orthogonal (s > 0).
fn similarity_scale(m: &DMat3) -> Option<f64> {
    let gram = m.transpose() * *m;
    let s2 = gram.x_axis.x;
    let expected = DMat3::from_diagonal(DVec3::splat(s2));
    let off = (gram - expected).to_cols_array();
    let ok = s2 > 0.0 && off.iter().all(|v| v.abs() <= SIMILARITY_TOLERANCE * s2);
    ok.then(|| s2.sqrt())
}

impl Surface for Ball {
    type Single = Ball32;

    #[inline(always)]
    fn intersect<const TEXTBOOK: bool, L: Lanes>(&self, ray: &Ray<L::Vector>) -> Found<L> {
        let (center, r2) = (
            L::splat_vector(self.center),
            L::splat(self.radius * self.radius),
        );
        if TEXTBOOK {
            intersect_ball_textbook(ray, center, r2)
        } else {
            intersect_ball(ray, center, r2)
        }
    }

    #[inline(always)]
    fn normal_at(&self, ray: &Ray, t: f64) -> DVec3 {
        (ray.at(t) - self.center).normalize()
    }

    /// From the centre, in the lanes: as exact as the lanes' hit points.
    #[inline(always)]
    fn lane_normal(&self, _: &Ray, _: f64) -> LaneNormal {
        LaneNormal::FromCenter(self.center)
    }

    fn bounds(&self) -> Option<Aabb> {
        Some(Aabb {
            min: self.center - DVec3::splat(self.radius),
            max: self.center + DVec3::splat(self.radius),
        })
    }

    fn single(&self) -> Ball32 {
        Ball32 {
            center: self.center.as_vec3(),
            radius: self.radius as f32,
        }
    }
}

impl Surface for Ellipsoid {
    type Single = Ellipsoid32;

    #[inline(always)]
    fn intersect<const TEXTBOOK: bool, L: Lanes>(&self, ray: &Ray<L::Vector>) -> Found<L> {
        // Each lane's ray mapped to object space on its own.
        let (mut origins, mut dirs) = ([DVec3::ZERO; MAX_LANES], [DVec3::ZERO; MAX_LANES]);
        for i in 0..L::WIDTH {
            origins[i] = self
                .to_object
                .transform_point3(L::vector_lane(ray.origin, i));
            dirs[i] = self.to_object.transform_vector3(L::vector_lane(ray.dir, i));
        }
        let local = Ray::new(
            L::vector_from_fn(|i| origins[i]),
            L::vector_from_fn(|i| dirs[i]),
        );
        if TEXTBOOK {
            intersect_sphere_textbook(&local)
        } else {
            intersect_sphere(&local)
        }
    }

    #[inline(always)]
    fn normal_at(&self, ray: &Ray, t: f64) -> DVec3 {
        let local = self.to_object.transform_point3(ray.origin)
            + t * self.to_object.transform_vector3(ray.dir);
        (self.normal * local).normalize()
    }

    fn bounds(&self) -> Option<Aabb> {
        // Half-extent along world axis i: the norm of row i of the linear
        // part (the support of the unit sphere).
        let to_world = &self.to_world;
        let m = to_world.matrix3.transpose();
        let half = DVec3::new(m.x_axis.length(), m.y_axis.length(), m.z_axis.length());
        Some(Aabb {
            min: to_world.translation - half,
            max: to_world.translation + half,
        })
    }

    fn single(&self) -> Ellipsoid32 {
        Ellipsoid32 {
            to_object: self.to_object.as_affine3a(),
            normal: self.normal.as_mat3(),
        }
    }
}

impl Surface32 for Ball32 {
    #[inline]
    fn intersect<const TEXTBOOK: bool>(&self, ray: &Ray32) -> Option<f32> {
        let f = ray.origin - self.center;
        sphere32::<TEXTBOOK>(f, ray.dir, self.radius * self.radius)
    }

    #[inline]
    fn normal_at(&self, ray: &Ray32, t: f32) -> Vec3 {
        (ray.at(t) - self.center).normalize()
    }
}

impl Surface32 for Ellipsoid32 {
    #[inline]
    fn intersect<const TEXTBOOK: bool>(&self, ray: &Ray32) -> Option<f32> {
        sphere32::<TEXTBOOK>(
            self.to_object.transform_point3(ray.origin),
            self.to_object.transform_vector3(ray.dir),
            1.0,
        )
    }

    #[inline]
    fn normal_at(&self, ray: &Ray32, t: f32) -> Vec3 {
        let local = self.to_object.transform_point3(ray.origin)
            + t * self.to_object.transform_vector3(ray.dir);
        (self.normal * local).normalize()
    }
}

/// Nearest root t > 0 of |f + t d|² = r², in f32, with a = |d|² computed
/// and no early out (the direction's a = |d|² computed for balls too): the
/// stable form or the textbook formula.
#[inline]
fn sphere32<const TEXTBOOK: bool>(f: Vec3, d: Vec3, r2: f32) -> Option<f32> {
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
    fn hits_the_front_from_outside() {
        let r = Ray::new(DVec3::new(0.0, 0.0, -5.0), DVec3::Z);
        assert_eq!(intersect_sphere(&r).get(), Some(4.0));
        assert_eq!(intersect_sphere_textbook(&r).get(), Some(4.0));
        assert_eq!(
            intersect_ball_textbook(&r, DVec3::ZERO, 1.0).get(),
            Some(4.0)
        );
    }

    #[test]
    fn ball_matches_the_unit_sphere_scaled() {
        let c = DVec3::new(1.0, -2.0, 10.0);
        let r = Ray::new(DVec3::ZERO, (c + DVec3::new(0.5, 0.0, 0.0)).normalize());
        let t = intersect_ball(&r, c, 4.0).get().unwrap();
        let local = Ray::new((r.origin - c) / 2.0, r.dir / 2.0);
        let u = intersect_sphere(&local).get().unwrap();
        assert!((t - u).abs() < 1e-12, "{t} {u}");
        assert!(((r.at(t) - c).length() - 2.0).abs() < 1e-12);
    }

    #[test]
    fn hits_the_far_side_from_inside() {
        let r = Ray::new(DVec3::ZERO, DVec3::X);
        assert_eq!(intersect_sphere(&r).get(), Some(1.0));
    }

    #[test]
    fn misses_behind_and_beside() {
        assert_eq!(
            intersect_sphere(&Ray::new(DVec3::new(0.0, 0.0, 5.0), DVec3::Z)).get(),
            None
        );
        assert_eq!(
            intersect_sphere(&Ray::new(DVec3::new(0.0, 1.5, -5.0), DVec3::Z)).get(),
            None
        );
    }

    #[test]
    fn scaled_direction_gives_world_distance() {
        // A sphere of radius 2 seen in its object space: the unit world
        // direction becomes length 1/2, and t stays the world distance.
        let r = Ray::new(DVec3::new(0.0, 0.0, -5.0), DVec3::Z * 0.5);
        assert_eq!(intersect_sphere(&r).get(), Some(8.0));
    }

    #[test]
    fn stable_where_the_textbook_formula_cancels() {
        // A unit sphere seen from 1e9 away: the textbook discriminant loses
        // every digit (b² and 4ac are both ~4e18), the stable one does not.
        let o = DVec3::new(0.0, 0.0, -1e9);
        let hit = Ray::new(o, DVec3::new(0.0, 0.5e-9, 1.0).normalize());
        let exact = 1e9 - 0.75_f64.sqrt();
        let t = intersect_sphere(&hit).get().unwrap();
        assert!((t - exact).abs() < 1e-6, "{t}");
        let t = intersect_sphere_textbook(&hit).get().unwrap();
        assert!((t - exact).abs() > 0.5, "{t}");
        // Passing 1.5 from the centre: a miss, which the textbook formula
        // reports as a tangent hit.
        let miss = Ray::new(o, DVec3::new(0.0, 1.5e-9, 1.0).normalize());
        assert_eq!(intersect_sphere(&miss).get(), None);
        assert!(intersect_sphere_textbook(&miss).get().is_some());
    }
}
