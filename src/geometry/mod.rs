//! Geometry answers one question: where does this ray hit, and what is the
//! normal there. No colours, no lights.
//!
//! Intersections run in the object's own space (unit sphere, plane z = 0)
//! on the ray mapped by the inverse matrix. The direction is mapped but *not*
//! renormalised, so the parameter t found in object space is the world
//! distance along the unit world direction: hits on differently scaled
//! objects compare directly, and the visible hit is the nearest in world
//! distance.
//!
//! [`Shape`] is what an object is in its own space; [`Primitive`] flattens
//! what the transform allows (a sphere under a similarity is a world
//! centre and radius; a plane a world point and normal): each kind is a
//! type of its shape's file answering [`Surface`], listed once where the
//! kinds are dispatched. [`Bvh`] finds the nearest of many bounded
//! primitives. A new shape is its file (its kinds and their formulas), a
//! row in the shapes' table and one in the primitives'.
//!
//! Each intersection formula is written once, generic over the precision
//! and width ([`Vector`]: f64, f32 for the study's [`Primitive32`], or four
//! or eight f64 lanes for the renderer's packets of rays), so they cannot
//! drift:
//! [`stable_roots`] and [`textbook_roots`] for spheres, [`plane_hit`] for
//! planes. They answer per lane ([`Found`]); the BVH walks a packet's
//! lanes together ([`Bvh::nearest`]).

#[cfg(target_arch = "x86_64")]
mod avx;
mod bvh;
mod plane;
mod precision;
mod primitive;
mod ray;
mod shape;
mod single;
mod sphere;
mod surface;
#[cfg(test)]
mod unchanged;

#[cfg(target_arch = "x86_64")]
pub use avx::{Avx2, Avx4, Avx8, Avx8Mask, Avx512, AvxMask, Vectorized};
pub use bvh::{Aabb, Bvh, Search};
pub use plane::{Plane32, WorldPlane, intersect_plane_world, plane_hit};
pub use precision::{DVec3x4, F64x4, Lanes, MAX_LANES, Mask, Mask4, Real, Vec3x4, Vector};
pub use primitive::{Primitive, Primitive32};
pub use ray::Ray;
pub use shape::Shape;
pub use single::Ray32;
pub use sphere::{
    Ball, Ball32, Ellipsoid, Ellipsoid32, Leading, Receding, UnitDirection, intersect_ball,
    intersect_ball_textbook, intersect_sphere, intersect_sphere_textbook, stable_roots,
    textbook_roots,
};
pub use surface::{Found, LaneNormal, Surface, Surface32};
