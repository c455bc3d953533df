//! The geometry of each method, for a packet of rays traced side by side
//! in SIMD lanes: how a method's rays are held, what they hit (the nearest
//! hit of each lane, through the BVH or a tile's candidates), the hit
//! points and normals, and the reflected rays ([`Kernel`]: [`Exact`] in
//! f64 lanes, [`Single`] in f32 one ray at a time). And the choice of the
//! kernel at run time, once per piece of work ([`WithKernel`],
//! [`Prepared::with_kernel`]): the sphere test, the precision, then the
//! widest lanes the processor has. Shading stays in the trace loop
//! ([`super::trace`]), the same for every kernel.

use super::{Candidates, Hit, Prepared, PrimitiveRef};
#[cfg(target_arch = "x86_64")]
use crate::geometry::{Avx2, Avx4, Avx8, Avx512, Vectorized};
use crate::geometry::{
    F64x4, Found, Lanes, Mask, Primitive, Primitive32, Ray, Ray32, Real, Search, Vector,
};
use crate::render::{Offset, Precision, SphereTest};
use crate::shading::SurfacePoint;
use std::marker::PhantomData;

/// The nearest hit found so far by each lane of a packet of rays.
#[derive(Debug, Clone, Copy)]
pub(super) struct Hits<L: Lanes> {
    /// World distance (infinity where nothing was found).
    pub(super) t: L,
    /// Index of the object in the scene's object list (exact in f64).
    pub(super) object: L,
    /// Which primitive: bounded k as k, plane k as −1 − k.
    pub(super) primitive: L,
    pub(super) found: L::Mask,
}

impl<L: Lanes> Hits<L> {
    #[inline(always)]
    pub(super) fn none() -> Hits<L> {
        Hits {
            t: L::splat(f64::INFINITY),
            object: L::ZERO,
            primitive: L::ZERO,
            found: !L::Mask::ALL,
        }
    }

    /// Keeps `hit` of `object`'s primitive where it is nearer; ties go to
    /// the object listed first in the scene.
    #[inline(always)]
    pub(super) fn consider(&mut self, hit: Found<L>, object: u32, primitive: f64) {
        if !hit.found.any() {
            return;
        }
        let rank = L::splat(f64::from(object));
        let nearer = hit.t.lt(self.t) | (hit.t.eq(self.t) & rank.lt(self.object));
        let better = hit.found & (!self.found | nearer);
        if better.any() {
            self.t = L::select(better, hit.t, self.t);
            self.object = L::select(better, rank, self.object);
            self.primitive = L::select(better, L::splat(primitive), self.primitive);
            self.found = self.found | better;
        }
    }

    /// Lane i's hit (where one was found).
    #[inline(always)]
    pub(super) fn lane(&self, i: usize) -> Hit {
        let p = self.primitive.lane(i);
        Hit {
            t: self.t.lane(i),
            object: self.object.lane(i) as usize,
            primitive: if p >= 0.0 {
                PrimitiveRef::Bounded(p as usize)
            } else {
                PrimitiveRef::Plane((-1.0 - p) as usize)
            },
        }
    }
}

/// A kernel's intersection test of its rays against one primitive `P`.
/// (A trait rather than a closure: the AVX path needs it inlined, and
/// only functions can be marked `#[inline(always)]`.)
trait Test<P, L: Lanes> {
    fn test(&self, primitive: &P) -> Found<L>;
}

/// The f64 rays of a packet, against f64 primitives.
struct TestExact<'a, const TEXTBOOK: bool, L: Lanes>(&'a Ray<L::Vector>);

impl<const TEXTBOOK: bool, L: Lanes> Test<Primitive, L> for TestExact<'_, TEXTBOOK, L> {
    #[inline(always)]
    fn test(&self, primitive: &Primitive) -> Found<L> {
        primitive.intersect::<TEXTBOOK, L>(self.0)
    }
}

/// An f32 ray against f32 primitives.
struct TestSingle<'a, const TEXTBOOK: bool>(&'a Ray32);

impl<const TEXTBOOK: bool> Test<Primitive32, f64> for TestSingle<'_, TEXTBOOK> {
    #[inline(always)]
    fn test(&self, primitive: &Primitive32) -> Found<f64> {
        match primitive.intersect::<TEXTBOOK>(self.0) {
            Some(t) => Found {
                t: f64::from(t),
                found: true,
            },
            None => Found::none(),
        }
    }
}

/// A packet's search through the BVH: each lane keeps its nearest hit.
struct BvhSearch<'a, L: Lanes, P, I: Test<P, L>> {
    hits: &'a mut Hits<L>,
    bounded: &'a [P],
    objects: &'a [u32],
    intersect: &'a I,
}

impl<L: Lanes, P, I: Test<P, L>> Search<L> for BvhSearch<'_, L, P, I> {
    #[inline(always)]
    fn t_max(&self) -> L {
        self.hits.t
    }

    #[inline(always)]
    fn test(&mut self, k: usize, lanes: L::Mask) {
        let hit = self.intersect.test(&self.bounded[k]);
        self.hits.consider(hit.of(lanes), self.objects[k], k as f64);
    }
}

/// The geometry of a method, for a packet of rays traced side by side in
/// its lanes ([`Lanes`]): how the rays are held, what they hit, the hit
/// points and normals, and the reflected rays. Shading (f64) stays in
/// [`Prepared::trace`].
pub(super) trait Kernel {
    type L: Lanes;
    type Rays: Copy;
    fn primary(&self, rays: Ray<Vectors<Self>>) -> Self::Rays;
    /// The nearest hits of the `alive` lanes.
    fn nearest(
        &self,
        p: &Prepared,
        rays: &Self::Rays,
        alive: Alive<Self>,
        among: Candidates,
    ) -> Hits<Self::L>;
    /// The hit points M, the shading normals N (turned to face the ray)
    /// and V, of the `alive` lanes.
    fn surface(
        &self,
        p: &Prepared,
        rays: &Self::Rays,
        hits: &Hits<Self::L>,
        alive: Alive<Self>,
    ) -> SurfacePoint<Vectors<Self>>;
    /// The reflected rays R leaving `point`, offset off the surface.
    fn reflected(&self, point: &SurfacePoint<Vectors<Self>>) -> Self::Rays;
    /// The rays in f64 (as they are, for the f64 kernels): what the
    /// explained pixel shows.
    fn in_f64(&self, rays: &Self::Rays) -> Ray<Vectors<Self>>;
}

/// A kernel's vectors (one per lane).
pub(super) type Vectors<K> = <<K as Kernel>::L as Lanes>::Vector;
/// A kernel's lanes still tracing.
pub(super) type Alive<K> = <<K as Kernel>::L as Real>::Mask;

/// Work that runs with the kernel of the prepared scene's method
/// ([`Prepared::with_kernel`]): generic over it, so each kernel's trace
/// loop is compiled on its own and the reference path pays nothing for the
/// others.
pub(super) trait WithKernel {
    type Output;
    /// Runs one lane at a time (f64 geometry in plain f64).
    const ONE_LANE: bool = false;
    fn run<K: Kernel>(self, p: &Prepared, kernel: &K) -> Self::Output;
}
/// Work run with a kernel in AVX lanes ([`Avx2::run`]).
#[cfg(target_arch = "x86_64")]
struct OnAvx<'a, W, K> {
    work: W,
    prepared: &'a Prepared,
    kernel: K,
}

#[cfg(target_arch = "x86_64")]
impl<W: WithKernel, K: Kernel> Vectorized for OnAvx<'_, W, K> {
    type Output = W::Output;
    #[inline(always)]
    fn run(self) -> W::Output {
        self.work.run(self.prepared, &self.kernel)
    }
}

/// f64 geometry, a packet of rays at a time in the lanes of `L` ([`F64x4`],
/// [`Avx4`] or [`Avx8`]): the reference
/// (stable test, the reference offset) and its study variants.
struct Exact<const TEXTBOOK: bool, L> {
    offset: Offset,
    lanes: PhantomData<L>,
}

impl<const TEXTBOOK: bool, L> Exact<TEXTBOOK, L> {
    fn new(offset: Offset) -> Self {
        Exact {
            offset,
            lanes: PhantomData,
        }
    }
}

impl<const TEXTBOOK: bool, L: Lanes> Kernel for Exact<TEXTBOOK, L> {
    type L = L;
    type Rays = Ray<L::Vector>;

    #[inline(always)]
    fn primary(&self, rays: Ray<L::Vector>) -> Ray<L::Vector> {
        rays
    }

    #[inline(always)]
    fn nearest(
        &self,
        p: &Prepared,
        rays: &Ray<L::Vector>,
        alive: L::Mask,
        among: Candidates,
    ) -> Hits<L> {
        p.nearest_with(
            rays,
            alive,
            among,
            &p.world.shapes.bounded,
            &p.world.shapes.planes,
            &TestExact::<TEXTBOOK, L>(rays),
        )
    }

    #[inline(always)]
    fn surface(
        &self,
        p: &Prepared,
        rays: &Ray<L::Vector>,
        hits: &Hits<L>,
        alive: L::Mask,
    ) -> SurfacePoint<L::Vector> {
        let m = rays.at(hits.t);
        // The geometric normal, geometry's answer for each lane's hit.
        let n = Primitive::normals::<L>(rays, hits.t, m, |i| {
            alive.lane(i).then(|| match hits.lane(i).primitive {
                PrimitiveRef::Bounded(k) => &p.world.shapes.bounded[k],
                PrimitiveRef::Plane(k) => &p.world.shapes.planes[k],
            })
        });
        // Shading normal N: the geometric normal turned to face the ray.
        let n = L::Vector::select(n.dot(rays.dir).gt(L::ZERO), -n, n);
        SurfacePoint { m, n, v: -rays.dir }
    }

    #[inline(always)]
    fn reflected(&self, point: &SurfacePoint<L::Vector>) -> Ray<L::Vector> {
        self.offset.reflected(point)
    }

    #[inline(always)]
    fn in_f64(&self, rays: &Ray<L::Vector>) -> Ray<L::Vector> {
        *rays
    }
}

/// f32 geometry, one ray at a time: the ray, the intersections, the hit
/// point, the normal and the reflected ray in single precision (the BVH's
/// box tests read the same ray widened to f64, exactly).
struct Single<const TEXTBOOK: bool> {
    offset: Offset,
}

impl<const TEXTBOOK: bool> Kernel for Single<TEXTBOOK> {
    type L = f64;
    type Rays = Ray32;

    #[inline(always)]
    fn primary(&self, ray: Ray) -> Ray32 {
        Ray32::from_f64(&ray)
    }

    #[inline(always)]
    fn nearest(&self, p: &Prepared, ray: &Ray32, alive: bool, among: Candidates) -> Hits<f64> {
        p.nearest_with(
            &ray.to_f64(),
            alive,
            among,
            &p.world.shapes.bounded32,
            &p.world.shapes.planes32,
            &TestSingle::<TEXTBOOK>(ray),
        )
    }

    #[inline(always)]
    fn surface(&self, p: &Prepared, ray: &Ray32, hits: &Hits<f64>, _: bool) -> SurfacePoint {
        let hit = hits.lane(0);
        // t came from f32: the narrowing is exact.
        let t = hit.t as f32;
        let m = ray.at(t);
        let mut n = match hit.primitive {
            PrimitiveRef::Bounded(k) => p.world.shapes.bounded32[k].normal_at(ray, t),
            PrimitiveRef::Plane(k) => p.world.shapes.planes32[k].normal_at(ray, t),
        };
        if n.dot(ray.dir) > 0.0 {
            n = -n;
        }
        SurfacePoint {
            m: m.as_dvec3(),
            n: n.as_dvec3(),
            v: (-ray.dir).as_dvec3(),
        }
    }

    #[inline(always)]
    fn reflected(&self, point: &SurfacePoint) -> Ray32 {
        // The point's vectors hold f32 values: the narrowing is exact.
        let point = SurfacePoint {
            m: point.m.as_vec3(),
            n: point.n.as_vec3(),
            v: point.v.as_vec3(),
        };
        let ray = self.offset.reflected(&point);
        Ray32::new(ray.origin, ray.dir)
    }

    #[inline(always)]
    fn in_f64(&self, ray: &Ray32) -> Ray {
        ray.to_f64()
    }
}
impl Prepared {
    /// The nearest hit with t > 0 in world distance, if any. Ties go to the
    /// object listed first in the scene.
    pub fn nearest_hit(&self, ray: &Ray) -> Option<Hit> {
        let hits = self.nearest_with::<f64, _>(
            ray,
            true,
            Candidates::All,
            &self.world.shapes.bounded,
            &self.world.shapes.planes,
            &TestExact::<false, f64>(ray),
        );
        hits.found.then(|| hits.lane(0))
    }

    /// The nearest hits of the `alive` lanes of `rays` among `bounded` and
    /// `planes` (the f64 primitives or their f32 copies, in the same
    /// order), `intersect` testing one for every lane; `rays` serves the
    /// BVH's box tests.
    #[inline(always)]
    fn nearest_with<L: Lanes, P>(
        &self,
        rays: &Ray<L::Vector>,
        alive: L::Mask,
        candidates: Candidates,
        bounded: &[P],
        planes: &[P],
        intersect: &impl Test<P, L>,
    ) -> Hits<L> {
        let mut hits = Hits::none();
        for (k, plane) in planes.iter().enumerate() {
            hits.consider(
                intersect.test(plane).of(alive),
                self.world.shapes.plane_objects[k],
                -1.0 - k as f64,
            );
        }
        match (&self.world.shapes.bvh, candidates) {
            (_, Candidates::Only(list)) => {
                for &k in list {
                    hits.consider(
                        intersect.test(&bounded[k]).of(alive),
                        self.world.shapes.bounded_objects[k],
                        k as f64,
                    );
                }
            }
            (Some(bvh), Candidates::All) => {
                let mut search = BvhSearch {
                    hits: &mut hits,
                    bounded,
                    objects: &self.world.shapes.bounded_objects,
                    intersect,
                };
                bvh.nearest(rays, alive, &mut search);
            }
            (None, Candidates::All) => {
                for (k, primitive) in bounded.iter().enumerate() {
                    hits.consider(
                        intersect.test(primitive).of(alive),
                        self.world.shapes.bounded_objects[k],
                        k as f64,
                    );
                }
            }
        }
        hits
    }
    /// Runs `work` with the kernel of the method's choices, each dispatched
    /// once, one choice at a time: the sphere test, the precision, then
    /// (f64) the widest lanes.
    #[inline(always)]
    pub(super) fn with_kernel<W: WithKernel>(&self, work: W) -> W::Output {
        match self.world.sphere {
            SphereTest::Stable => self.with_precision::<false, W>(work),
            SphereTest::Textbook => self.with_precision::<true, W>(work),
        }
    }

    #[inline(always)]
    fn with_precision<const TEXTBOOK: bool, W: WithKernel>(&self, work: W) -> W::Output {
        match self.world.shapes.precision {
            Precision::F64 if W::ONE_LANE => {
                work.run(self, &Exact::<TEXTBOOK, f64>::new(self.world.offset))
            }
            Precision::F64 => self.with_lanes::<TEXTBOOK, W>(work),
            Precision::F32 => work.run(
                self,
                &Single::<TEXTBOOK> {
                    offset: self.world.offset,
                },
            ),
        }
    }

    /// The f64 kernel in the widest lanes the processor has: eight in an
    /// AVX-512 register, four in an AVX2 one (the work compiled for that
    /// feature), else four in SSE2 pairs. All give the same image, bit for
    /// bit.
    #[inline(always)]
    fn with_lanes<const TEXTBOOK: bool, W: WithKernel>(&self, work: W) -> W::Output {
        let offset = self.world.offset;
        #[cfg(target_arch = "x86_64")]
        if let Some(avx512) = Avx512::detect() {
            return avx512.run(OnAvx {
                work,
                prepared: self,
                kernel: Exact::<TEXTBOOK, Avx8>::new(offset),
            });
        }
        #[cfg(target_arch = "x86_64")]
        if let Some(avx2) = Avx2::detect() {
            return avx2.run(OnAvx {
                work,
                prepared: self,
                kernel: Exact::<TEXTBOOK, Avx4>::new(offset),
            });
        }
        work.run(self, &Exact::<TEXTBOOK, F64x4>::new(offset))
    }
}
