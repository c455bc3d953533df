//! What every kind of primitive answers ([`Surface`], and [`Surface32`]
//! in f32), and what an intersection formula returns ([`Found`]). Below
//! the shapes' files, which implement it, and the table of kinds that
//! dispatches over them ([`super::Primitive`]), so that neither imports
//! the other.

use super::precision::{Mask, Real};
use super::single::Ray32;
use super::{Aabb, Lanes, Ray};
use glam::{DVec3, Vec3};

/// A root per lane and whether that lane found one: what the formulas
/// return, for one value or for lanes alike.
#[derive(Debug, Clone, Copy)]
pub struct Found<R: Real> {
    pub t: R,
    pub found: R::Mask,
}

impl<R: Real> Found<R> {
    /// No lane found anything.
    #[inline(always)]
    pub fn none() -> Found<R> {
        Found {
            t: R::ZERO,
            found: !R::Mask::ALL,
        }
    }
}

impl<R: Real> Found<R> {
    /// Only what `lanes` found.
    #[inline(always)]
    pub fn of(self, lanes: R::Mask) -> Found<R> {
        Found {
            t: self.t,
            found: self.found & lanes,
        }
    }
}

impl<R: Real<Mask = bool>> Found<R> {
    /// The root of a single ray, if any.
    #[inline(always)]
    pub fn get(self) -> Option<R> {
        self.found.then_some(self.t)
    }
}

/// What every kind of primitive answers, in world space: where a packet of
/// rays meets it, its normal at a point, its bounds, and its form in
/// single precision.
pub trait Surface {
    /// The same primitive rounded to f32 (the study's "f32 everywhere").
    type Single: Surface32 + std::fmt::Debug + Clone + PartialEq;

    /// The nearest t > 0 at which each lane's ray (unit direction) meets
    /// the surface. `TEXTBOOK` picks the textbook quadratic where there is
    /// one (the study's method).
    fn intersect<const TEXTBOOK: bool, L: Lanes>(&self, ray: &Ray<L::Vector>) -> Found<L>;

    /// The unit geometric normal at `ray.at(t)` (not yet turned to face
    /// the ray).
    fn normal_at(&self, ray: &Ray, t: f64) -> DVec3;

    /// How a packet finds the normal at `ray.at(t)`: given here, or from a
    /// centre, computed in the lanes from the lanes' own hit points.
    #[inline(always)]
    fn lane_normal(&self, ray: &Ray, t: f64) -> LaneNormal {
        LaneNormal::Given(self.normal_at(ray, t))
    }

    /// The world bounding box; `None` for an unbounded one (tested apart
    /// from the hierarchy).
    fn bounds(&self) -> Option<Aabb>;

    /// Its form in single precision.
    fn single(&self) -> Self::Single;
}

/// [`Surface`] in single precision.
pub trait Surface32 {
    /// The nearest t > 0, in f32, by the same formulas.
    fn intersect<const TEXTBOOK: bool>(&self, ray: &Ray32) -> Option<f32>;
    /// The unit geometric normal at `ray.at(t)`, in f32.
    fn normal_at(&self, ray: &Ray32, t: f32) -> Vec3;
}

/// A lane's normal, as [`Surface::lane_normal`] gives it.
pub enum LaneNormal {
    Given(DVec3),
    FromCenter(DVec3),
}

/// A boxed primitive is the primitive (the rare big ones are boxed, so
/// that the common ones stay small in a row of a million).
impl<S: Surface> Surface for Box<S> {
    type Single = S::Single;
    #[inline(always)]
    fn intersect<const TEXTBOOK: bool, L: Lanes>(&self, ray: &Ray<L::Vector>) -> Found<L> {
        (**self).intersect::<TEXTBOOK, L>(ray)
    }
    #[inline(always)]
    fn normal_at(&self, ray: &Ray, t: f64) -> DVec3 {
        (**self).normal_at(ray, t)
    }
    #[inline(always)]
    fn lane_normal(&self, ray: &Ray, t: f64) -> LaneNormal {
        (**self).lane_normal(ray, t)
    }
    fn bounds(&self) -> Option<Aabb> {
        (**self).bounds()
    }
    fn single(&self) -> S::Single {
        (**self).single()
    }
}
