//! A scene object reduced to what intersection needs, in world space where
//! its transform allows.
//!
//! - A sphere whose matrix is a similarity (rotation or mirror, uniform
//!   scale, translation) is a [`Primitive::Ball`]: a world centre and
//!   radius, intersected without any matrix work.
//! - Any other sphere is an [`Primitive::Ellipsoid`], intersected in its own
//!   space through the cached inverse matrix.
//! - A plane stays a plane under every affine map: a world point and unit
//!   normal.

use super::Shape;
use super::{
    Aabb, Found, Lanes, MAX_LANES, Ray, intersect_ball, intersect_ball_textbook,
    intersect_plane_world, intersect_sphere, intersect_sphere_textbook,
};
use crate::math::Transform;
use glam::{DAffine3, DMat3, DVec3};

#[derive(Debug, Clone, PartialEq)]
pub enum Primitive {
    Ball {
        center: DVec3,
        radius: f64,
    },
    /// Boxed: it is rare and eight times the size of a ball, and the
    /// primitives are scanned in a row.
    Ellipsoid(Box<Ellipsoid>),
    /// Boxed too: planes are few and tested apart, and one in place would
    /// make every primitive 56 bytes instead of 40 (a million spheres: 16
    /// MB).
    Plane(Box<WorldPlane>),
}

/// A plane in world space.
#[derive(Debug, Clone, PartialEq)]
pub struct WorldPlane {
    pub point: DVec3,
    /// Unit normal.
    pub normal: DVec3,
}

#[derive(Debug, Clone, PartialEq)]
pub struct Ellipsoid {
    /// World to object space.
    pub to_object: DAffine3,
    /// Object-space normals to world space: (M⁻¹)ᵀ.
    pub normal: DMat3,
    /// Object to world, for the bounding box.
    pub to_world: DAffine3,
}

/// Relative tolerance for "the linear part is a scaled orthogonal matrix".
const SIMILARITY_TOLERANCE: f64 = 1e-12;

impl Primitive {
    pub fn new(shape: Shape, transform: &Transform) -> Primitive {
        let m = transform.to_world();
        match shape {
            Shape::Plane => Primitive::Plane(Box::new(WorldPlane {
                point: m.translation,
                normal: (transform.normal_matrix() * DVec3::Z).normalize(),
            })),
            Shape::Sphere => match similarity_scale(&m.matrix3) {
                Some(radius) => Primitive::Ball {
                    center: m.translation,
                    radius,
                },
                None => {
                    let matrices = transform.matrices();
                    Primitive::Ellipsoid(Box::new(Ellipsoid {
                        to_object: matrices.to_object,
                        normal: matrices.normal,
                        to_world: matrices.to_world,
                    }))
                }
            },
        }
    }

    /// The nearest t > 0 at which `ray` (unit direction) meets the
    /// surface, per lane. `TEXTBOOK` picks the textbook quadratic for
    /// spheres (the study's method; planes are unchanged).
    #[inline(always)]
    pub fn intersect<const TEXTBOOK: bool, L: Lanes>(&self, ray: &Ray<L::Vector>) -> Found<L> {
        match self {
            Primitive::Ball { center, radius } => {
                let (center, r2) = (L::splat_vector(*center), L::splat(radius * radius));
                if TEXTBOOK {
                    intersect_ball_textbook(ray, center, r2)
                } else {
                    intersect_ball(ray, center, r2)
                }
            }
            Primitive::Ellipsoid(e) => {
                // Each lane's ray mapped to object space on its own.
                let (mut origins, mut dirs) = ([DVec3::ZERO; MAX_LANES], [DVec3::ZERO; MAX_LANES]);
                for i in 0..L::WIDTH {
                    origins[i] = e.to_object.transform_point3(L::vector_lane(ray.origin, i));
                    dirs[i] = e.to_object.transform_vector3(L::vector_lane(ray.dir, i));
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
            Primitive::Plane(plane) => intersect_plane_world(
                ray,
                L::splat_vector(plane.point),
                L::splat_vector(plane.normal),
            ),
        }
    }

    /// The unit geometric normal at the point `ray.at(t)` (not yet turned
    /// to face the ray).
    #[inline(always)]
    pub fn normal_at(&self, ray: &Ray, t: f64) -> DVec3 {
        match self {
            Primitive::Ball { center, .. } => (ray.at(t) - *center).normalize(),
            Primitive::Ellipsoid(e) => {
                let local = e.to_object.transform_point3(ray.origin)
                    + t * e.to_object.transform_vector3(ray.dir);
                (e.normal * local).normalize()
            }
            Primitive::Plane(plane) => plane.normal,
        }
    }

    /// The unit geometric normals (not yet turned to face the rays) at the
    /// hits `m = rays.at(t)` of a packet of rays: lane i's on the
    /// primitive `hit(i)`, zero where it is `None`. A ball's from its
    /// centre, computed in the lanes; a plane's given; an ellipsoid's
    /// through its matrix, one lane at a time. The packet's form of
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
        let mut ball = [false; MAX_LANES];
        for i in 0..L::WIDTH {
            let Some(primitive) = hit(i) else {
                continue;
            };
            match primitive {
                Primitive::Ball { center, .. } => (centers[i], ball[i]) = (*center, true),
                Primitive::Plane(plane) => given[i] = plane.normal,
                Primitive::Ellipsoid(_) => {
                    let ray = Ray::new(L::vector_lane(rays.origin, i), L::vector_lane(rays.dir, i));
                    given[i] = primitive.normal_at(&ray, t.lane(i));
                }
            }
        }
        let from_center = (m - L::vector_from_fn(|i| centers[i])).normalize();
        L::Vector::select(
            L::Mask::from_fn(|i| ball[i]),
            from_center,
            L::vector_from_fn(|i| given[i]),
        )
    }

    /// World bounding box; `None` for the unbounded plane.
    pub fn bounds(&self) -> Option<Aabb> {
        match self {
            Primitive::Ball { center, radius } => Some(Aabb {
                min: *center - DVec3::splat(*radius),
                max: *center + DVec3::splat(*radius),
            }),
            Primitive::Ellipsoid(e) => {
                // Half-extent along world axis i: the norm of row i of the
                // linear part (the support of the unit sphere).
                let to_world = &e.to_world;
                let m = to_world.matrix3.transpose();
                let half = DVec3::new(m.x_axis.length(), m.y_axis.length(), m.z_axis.length());
                Some(Aabb {
                    min: to_world.translation - half,
                    max: to_world.translation + half,
                })
            }
            Primitive::Plane(_) => None,
        }
    }
}

/// `Some(s)` when the linear part is s·Q with Q orthogonal (s > 0).
fn similarity_scale(m: &DMat3) -> Option<f64> {
    let gram = m.transpose() * *m;
    let s2 = gram.x_axis.x;
    let expected = DMat3::from_diagonal(DVec3::splat(s2));
    let off = (gram - expected).to_cols_array();
    let ok = s2 > 0.0 && off.iter().all(|v| v.abs() <= SIMILARITY_TOLERANCE * s2);
    ok.then(|| s2.sqrt())
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
            Primitive::Ball { center, radius } => {
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
