//! Geometry answers one question: where does this ray hit, and what is the
//! normal there. No colours, no lights.
//!
//! Intersections run in the object's own space (unit sphere, plane z = 0)
//! on the ray mapped by the inverse matrix. The direction is mapped but *not*
//! renormalised, so the parameter t found in object space is the world
//! distance along the unit world direction: hits on differently scaled
//! objects compare directly (contract section 2).

mod plane;
mod ray;
mod sphere;

pub use plane::intersect_plane;
pub use ray::Ray;
pub use sphere::{intersect_sphere, intersect_sphere_textbook};
