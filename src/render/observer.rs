//! What a trace tells whoever watches it: the [`Observer`] the render's
//! own loop ([`Prepared`](super::Prepared)) calls at every ray, hit and
//! end of a chain, and why a chain [`Ended`]. Renders watch with `()`,
//! which sees nothing and compiles to nothing; [`explain`](super::explain)
//! records a pixel's tree with it. In a module of its own so that the loop
//! and the recorder both use it and neither depends on the other's
//! insides.

use crate::geometry::{Lanes, Ray};
use crate::shading::{LightObserver, SurfacePoint, Terms};
use glam::DVec3;

/// Why a chain of reflections ended.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Ended {
    /// The last ray hit nothing (black).
    Missed,
    /// The model's reflection depth is reached (0 for every model but
    /// whitted).
    Depth,
    /// The surface hit has ks = 0: it reflects nothing.
    NoMirror,
    /// The exact early stop: the rest of the chain could add at most
    /// `bound` per channel, too little to change the 8-bit value.
    EarlyStop { bound: DVec3 },
}

/// Sees a trace step by step: how the explained pixel's tree is recorded
/// from the render's own loop ([`super::Prepared::explain`]). `()` sees nothing
/// and compiles to nothing (renders).
pub(super) trait Observer<L: Lanes>: LightObserver<L> {
    /// Bounce `bounce`'s rays (f64) leave.
    #[inline(always)]
    fn ray(&mut self, bounce: u32, rays: &Ray<L::Vector>) {
        let _ = (bounce, rays);
    }
    /// The lanes of `missed` hit nothing: their chains end.
    #[inline(always)]
    fn missed(&mut self, missed: L::Mask) {
        let _ = missed;
    }
    /// The `alive` lanes hit `object` (of reflectance `ks`) at distance
    /// `t` and `point`; their own colour's terms, and the weight it enters
    /// the pixel with.
    #[allow(clippy::too_many_arguments)]
    #[inline(always)]
    fn hit(
        &mut self,
        alive: L::Mask,
        object: L,
        t: L,
        point: &SurfacePoint<L::Vector>,
        terms: &Terms<L::Vector>,
        ks: L,
        weight: L,
    ) {
        let _ = (alive, object, t, point, terms, ks, weight);
    }
    /// The chains of `lanes` end after their hit, for this reason.
    #[inline(always)]
    fn ended(&mut self, lanes: L::Mask, why: Ended) {
        let _ = (lanes, why);
    }
}

impl<L: Lanes> Observer<L> for () {}
