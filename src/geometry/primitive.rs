//! A scene object reduced to what intersection needs, in world space where
//! its transform allows, and the one place the kinds of primitive are
//! dispatched (the `primitives!` table below): each kind is a type of its
//! shape's file that answers [`Surface`] (and [`Surface32`] for its f32
//! form), and a row of that table. Today's kinds:
//!
//! - a sphere whose matrix is a similarity (rotation or mirror, uniform
//!   scale, translation) is a [`Ball`]: a world centre and radius,
//!   intersected without any matrix work;
//! - any other sphere is an [`Ellipsoid`], intersected in its own space
//!   through the cached inverse matrix;
//! - a plane stays a plane under every affine map: a [`WorldPlane`], a
//!   world point and unit normal.
//!
//! Which kind an object becomes is its shape's to say
//! ([`Shape::primitive`]).

use super::single::Ray32;
use super::sphere::{Ball, Ellipsoid};
use super::surface::{LaneNormal, Surface, Surface32};
use super::{Aabb, Found, Lanes, MAX_LANES, Ray, Shape, WorldPlane};
use crate::math::Transform;
use glam::{DVec3, Vec3};

/// Declares the kinds of primitive, each once: the enum in f64 and in
/// f32 and every dispatch over them.
macro_rules! primitives {
    ($($(#[doc = $what:literal])* $kind:ident($ty:ty),)*) => {
        /// An object as intersection sees it: one of the kinds.
        #[derive(Debug, Clone, PartialEq)]
        pub enum Primitive {
            $($(#[doc = $what])* $kind($ty),)*
        }

        /// A [`Primitive`] rounded to f32.
        #[derive(Debug, Clone, PartialEq)]
        pub enum Primitive32 {
            $($kind(<$ty as Surface>::Single),)*
        }

        $(impl From<$ty> for Primitive {
            fn from(p: $ty) -> Primitive {
                Primitive::$kind(p)
            }
        })*

        impl Primitive {
            /// See [`Surface::intersect`].
            #[inline(always)]
            pub fn intersect<const TEXTBOOK: bool, L: Lanes>(&self, ray: &Ray<L::Vector>) -> Found<L> {
                match self {
                    $(Primitive::$kind(p) => p.intersect::<TEXTBOOK, L>(ray),)*
                }
            }

            /// See [`Surface::normal_at`].
            #[inline(always)]
            pub fn normal_at(&self, ray: &Ray, t: f64) -> DVec3 {
                match self {
                    $(Primitive::$kind(p) => p.normal_at(ray, t),)*
                }
            }

            #[inline(always)]
            fn lane_normal(&self, ray: &Ray, t: f64) -> LaneNormal {
                match self {
                    $(Primitive::$kind(p) => p.lane_normal(ray, t),)*
                }
            }

            /// See [`Surface::bounds`].
            pub fn bounds(&self) -> Option<Aabb> {
                match self {
                    $(Primitive::$kind(p) => p.bounds(),)*
                }
            }
        }

        impl Primitive32 {
            pub fn new(p: &Primitive) -> Primitive32 {
                match p {
                    $(Primitive::$kind(p) => Primitive32::$kind(p.single()),)*
                }
            }

            /// The nearest t > 0, in f32: the same formulas as
            /// [`Primitive::intersect`]; `TEXTBOOK` picks the root formula.
            #[inline]
            pub fn intersect<const TEXTBOOK: bool>(&self, ray: &Ray32) -> Option<f32> {
                match self {
                    $(Primitive32::$kind(p) => p.intersect::<TEXTBOOK>(ray),)*
                }
            }

            /// The unit geometric normal at `ray.at(t)`, in f32.
            #[inline]
            pub fn normal_at(&self, ray: &Ray32, t: f32) -> Vec3 {
                match self {
                    $(Primitive32::$kind(p) => p.normal_at(ray, t),)*
                }
            }
        }
    };
}

primitives! {
    /// A sphere under a similarity: a world centre and radius.
    Ball(Ball),
    /// Any other sphere. Boxed: it is rare and eight times the size of a
    /// ball, and the primitives are scanned in a row.
    Ellipsoid(Box<Ellipsoid>),
    /// Boxed too: planes are few and tested apart, and one in place would
    /// make every primitive 56 bytes instead of 40 (a million spheres: 16
    /// MB).
    Plane(Box<WorldPlane>),
}

impl Primitive {
    /// What an object of `shape` placed by `transform` is to intersection:
    /// its shape says ([`Shape::primitive`]).
    pub fn new(shape: Shape, transform: &Transform) -> Primitive {
        shape.primitive(transform)
    }

    /// The unit geometric normals (not yet turned to face the rays) at the
    /// hits `m = rays.at(t)` of a packet of rays: lane i's on the
    /// primitive `hit(i)`, zero where it is `None`. Each kind says how
    /// ([`Surface::lane_normal`]): a ball's from its centre, computed in
    /// the lanes; the others given for the lane. The packet's form of
    /// [`Primitive::normal_at`]: the trace asks, geometry answers.
    #[inline(always)]
    pub fn normals<'p, L: Lanes>(
        rays: &Ray<L::Vector>,
        t: L,
        m: L::Vector,
        hit: impl Fn(usize) -> Option<&'p Primitive>,
    ) -> L::Vector {
        use super::{Mask, Vector};
        let mut centers = [DVec3::ZERO; MAX_LANES];
        let mut given = [DVec3::ZERO; MAX_LANES];
        let mut from_center = [false; MAX_LANES];
        for i in 0..L::WIDTH {
            let Some(primitive) = hit(i) else {
                continue;
            };
            let ray = Ray::new(L::vector_lane(rays.origin, i), L::vector_lane(rays.dir, i));
            match primitive.lane_normal(&ray, t.lane(i)) {
                LaneNormal::FromCenter(center) => (centers[i], from_center[i]) = (center, true),
                LaneNormal::Given(normal) => given[i] = normal,
            }
        }
        let radial = (m - L::vector_from_fn(|i| centers[i])).normalize();
        L::Vector::select(
            L::Mask::from_fn(|i| from_center[i]),
            radial,
            L::vector_from_fn(|i| given[i]),
        )
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::math::TransformStep;

    fn transform(steps: Vec<TransformStep>) -> Transform {
        Transform::from_steps(steps).unwrap()
    }

    /// A million of them are held: a ball in place, anything bigger boxed.
    #[test]
    fn a_primitive_is_a_ball_and_a_tag() {
        assert_eq!(std::mem::size_of::<Primitive>(), 40);
    }

    #[test]
    fn similarities_become_balls() {
        let t = transform(vec![
            TransformStep::UniformScale(-2.0),
            TransformStep::RotateX(0.3),
            TransformStep::RotateZ(1.1),
            TransformStep::Translate(DVec3::new(1.0, 2.0, 3.0)),
        ]);
        match Primitive::new(Shape::Sphere, &t) {
            Primitive::Ball(Ball { center, radius }) => {
                assert!((radius - 2.0).abs() < 1e-14);
                assert!((center - DVec3::new(1.0, 2.0, 3.0)).length() < 1e-14);
            }
            other => panic!("{other:?}"),
        }
        let t = transform(vec![TransformStep::Scale(DVec3::new(1.0, 2.0, 1.0))]);
        assert!(matches!(
            Primitive::new(Shape::Sphere, &t),
            Primitive::Ellipsoid(_)
        ));
    }

    #[test]
    fn ball_and_ellipsoid_paths_agree() {
        // The same similarity intersected both ways.
        let t = transform(vec![
            TransformStep::UniformScale(1.5),
            TransformStep::RotateY(0.4),
            TransformStep::Translate(DVec3::new(0.5, -0.2, 6.0)),
        ]);
        let ball = Primitive::new(Shape::Sphere, &t);
        let ellipsoid = Primitive::Ellipsoid(Box::new(Ellipsoid {
            to_object: t.to_object(),
            normal: t.normal_matrix(),
            to_world: t.to_world(),
        }));
        for k in 0..50 {
            let y = -1.5 + 0.06 * f64::from(k);
            let ray = Ray::new(DVec3::ZERO, DVec3::new(0.1, y, 1.0).normalize() * 1.0);
            let (a, b) = (
                ball.intersect::<false, f64>(&ray).get(),
                ellipsoid.intersect::<false, f64>(&ray).get(),
            );
            match (a, b) {
                (Some(a), Some(b)) => {
                    assert!((a - b).abs() < 1e-12 * a, "{a} {b}");
                    let (na, nb) = (ball.normal_at(&ray, a), ellipsoid.normal_at(&ray, b));
                    assert!((na - nb).length() < 1e-9);
                }
                (None, None) => {}
                other => panic!("ray {k}: {other:?}"),
            }
        }
        // Both boxes enclose the sphere.
        let (bb, eb) = (ball.bounds().unwrap(), ellipsoid.bounds().unwrap());
        assert!((bb.min - eb.min).length() < 1e-12 && (bb.max - eb.max).length() < 1e-12);
    }
}
