//! The prepared scene: what tracing needs and nothing more.
//!
//! - Objects become [`Primitive`]s: spheres under a similarity are a world
//!   centre and radius, planes a world point and normal; only other spheres
//!   keep their matrices.
//! - Bounded primitives go into a [`Bvh`] once there are enough of them to
//!   pay for it; planes are always tested one by one.
//! - Primary rays of a tile only test the spheres that can be inside the
//!   tile's frustum (four planes through the eye); a tile with none of them
//!   and no plane is black without a single ray.
//! - Rays are traced in packets, side by side in SIMD lanes (a tile row a
//!   packet's width of pixels at a time, a pixel's samples likewise), in
//!   the widest lanes the processor has, picked at run time: eight in an
//!   AVX-512 register ([`Avx8`]), four in an AVX2 one ([`Avx4`]), else four
//!   in a pair of SSE2 registers ([`F64x4`]). Every formula is
//!   the scalar one per lane, so the image is the same bit for bit; a lane
//!   leaves the packet when its chain ends. The f32 study method traces
//!   one ray at a time.
//! - Shading data (colour, material) is read once per hit from the
//!   scene's object, shared with the scene, not copied.
//! - Whitted chains stop as soon as nothing the rest of the chain could add
//!   can change the pixel's 8-bit value (exact: the image is unchanged).
//! - The trace keeps the camera ray's terms and the reflected colour apart
//!   ([`Traced`]) and adds them in one order: a tile's texels are the 8-bit
//!   image or the values of a render pass ([`super::pass`]). An observer
//!   type parameter sees each step; `()` in renders, the explained pixel's
//!   recorder in [`Prepared::explain`] (one lane, the same code).
//! - All of it but the camera is one shared [`World`]: another view of the
//!   same scene ([`Prepared::with_view`]: a coarse pass, a moved camera, a
//!   pick) prepares nothing again.
//!   Its geometry (the primitives and their hierarchy, [`Shapes`]) is
//!   shared in turn with the next version of the scene when only colours,
//!   materials, lights or the model changed ([`Prepared::with_surfaces`]).

use super::explain::{Explanation, PixelValue, Recorder, Sample};
use super::observer::{Ended, Observer};
use super::{
    CameraRays, Cancel, Offset, Pass, Precision, RenderOptions, SphereTest, Texel, Tile, in_f32,
    to_8bit,
};
use crate::geometry::{
    Aabb, Bvh, F64x4, Found, Lanes, MAX_LANES, Mask, Primitive, Primitive32, Ray, Ray32, Real,
    Search, Vector,
};
#[cfg(target_arch = "x86_64")]
use crate::geometry::{Avx2, Avx4, Avx8, Avx512, Vectorized};
use crate::scene::{Camera, Object, Scene};
use crate::shading::{Color, Illumination, Light, Material, SurfacePoint, Terms, local_color};
use glam::DVec3;
use rayon::prelude::*;
use std::marker::PhantomData;
use std::ops::ControlFlow;
use std::sync::Arc;

/// With fewer bounded primitives than this, a linear scan beats the BVH.
pub(super) const BVH_THRESHOLD: usize = 8;
/// Up to this many bounded primitives, each tile culls them one by one
/// against its frustum for its primary rays (4 dot products each per tile).
pub(super) const CULL_LIMIT: usize = 64;
/// With a BVH, a tile whose frustum reaches at most this many primitives
/// tests just those for its primary rays; more, and it uses the BVH.
pub(super) const TILE_CANDIDATES: usize = 24;

/// The nearest hit of a ray.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Hit {
    /// World distance along the ray (the ray's direction is unit length).
    pub t: f64,
    /// Index of the object in the scene's object list.
    pub object: usize,
    /// Which primitive: index into the bounded list, or the plane list.
    primitive: PrimitiveRef,
}

#[derive(Debug, Clone, Copy, PartialEq)]
enum PrimitiveRef {
    Bounded(usize),
    Plane(usize),
}

/// What rendering needs, computed once per render: the scene's part
/// ([`World`]), shared by every view of it (the passes of a preview, the
/// app's picks and outline), and the view (camera rays and rays per pixel).
#[derive(Debug, Clone)]
pub struct Prepared {
    world: Arc<World>,
    camera: CameraRays,
    /// Rays per pixel on each side.
    aa: u32,
    /// What each pixel's `f64` texels hold ([`Prepared::for_pass`]).
    pass: Pass,
}

/// The part of a prepared scene that does not depend on the view.
#[derive(Debug)]
struct World {
    /// What the objects' shapes and transformations prepare to, shared
    /// with the world of an earlier version of the scene that had the same
    /// ones (an edit of a colour, a material, a light or the model prepares
    /// no geometry again: [`Prepared::with_surfaces`]).
    shapes: Arc<Shapes>,
    /// The scene's objects, shared with it: shading reads each hit's
    /// colour and material from its object (a copy of them would be 56
    /// bytes an object more, 56 MB for a million spheres).
    objects: crate::scene::Objects,
    lights: Vec<Light>,
    illumination: Illumination,
    /// Reflected rays followed per primary ray (0 unless whitted).
    depth: u32,
    /// Per channel, the most any one hit can add before weighting: the
    /// largest ka C + Σ I (kd + ks) over the objects.
    max_local: Color,
    /// `tail[r]` = Σ_{k<r} max_ks^k, the most that r more reflections can
    /// add per unit of weight and of `max_local` (empty when max_ks ≥ 1:
    /// no bound).
    tail: Vec<f64>,
    early_stop: bool,
    /// The study's method choices (see [`RenderOptions`]); the defaults
    /// are the reference path.
    sphere: SphereTest,
    offset: Offset,
    draft: bool,
}

/// The geometry of a world: the primitives, their hierarchy and what
/// culls them, made from the objects' shapes and transformations alone
/// (and the options `accelerate` and `precision`).
#[derive(Debug)]
struct Shapes {
    /// Spheres, in the BVH's order when there is one.
    bounded: Vec<Primitive>,
    /// Scene object index of each bounded primitive.
    /// (u32: at most `MAX_OBJECTS`, 4 MB less a million.)
    bounded_objects: Vec<u32>,
    bvh: Option<Bvh>,
    planes: Vec<Primitive>,
    plane_objects: Vec<u32>,
    /// Bounding sphere (centre, radius) of each bounded primitive, for the
    /// tile frustum test; empty when there are too many to cull.
    cull_spheres: Vec<(DVec3, f64)>,
    /// Primary rays of a tile test only what its frustum reaches (and the
    /// BVH is built): `options.accelerate`.
    cull: bool,
    precision: Precision,
    /// `bounded` and `planes` in f32, built only for [`Precision::F32`].
    bounded32: Vec<Primitive32>,
    planes32: Vec<Primitive32>,
}

/// Which bounded primitives a primary ray must test.
#[derive(Debug, Clone, Copy)]
enum Candidates<'a> {
    All,
    Only(&'a [usize]),
}

/// The nearest hit found so far by each lane of a packet of rays.
#[derive(Debug, Clone, Copy)]
struct Hits<L: Lanes> {
    /// World distance (infinity where nothing was found).
    t: L,
    /// Index of the object in the scene's object list (exact in f64).
    object: L,
    /// Which primitive: bounded k as k, plane k as −1 − k.
    primitive: L,
    found: L::Mask,
}

impl<L: Lanes> Hits<L> {
    #[inline(always)]
    fn none() -> Hits<L> {
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
    fn consider(&mut self, hit: Found<L>, object: u32, primitive: f64) {
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
    fn lane(&self, i: usize) -> Hit {
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

/// What tracing a packet gives back, per lane: the camera ray's hit (its
/// terms, normal, distance and object) and the reflected colour behind
/// it. Lanes that hit nothing hold zero terms, t = ∞ and object −1.
#[derive(Debug, Clone, Copy)]
pub(super) struct Traced<L: Lanes> {
    /// The camera ray's hit's own terms.
    pub terms: Terms<L::Vector>,
    /// ks I_r: the later bounces' colours, each weighted by the product
    /// of the ks before it.
    pub reflection: L::Vector,
    /// The shading normal N at the camera ray's hit.
    pub normal: L::Vector,
    pub t: L,
    /// Index of the object in the scene's object list, −1 for none.
    pub object: L,
}

impl<L: Lanes> Traced<L> {
    #[inline(always)]
    fn dark() -> Traced<L> {
        let zero = L::splat_vector(Color::ZERO);
        Traced {
            terms: Terms {
                ambient: zero,
                diffuse: zero,
                specular: zero,
            },
            reflection: zero,
            normal: zero,
            t: L::splat(f64::INFINITY),
            object: L::splat(-1.0),
        }
    }

    /// The colour: ((ambient + diffuse) + specular) + reflection.
    #[inline(always)]
    pub fn color(&self) -> L::Vector {
        self.terms.local() + self.reflection
    }

    /// The value of `pass` (unclamped), per lane.
    #[inline(always)]
    fn value(&self, pass: Pass) -> L::Vector {
        match pass {
            Pass::Final => self.color(),
            Pass::Ambient => self.terms.ambient,
            Pass::Diffuse => self.terms.diffuse,
            Pass::Specular => self.terms.specular,
            Pass::Reflection => self.reflection,
            Pass::Normal => self.normal,
            Pass::Depth => L::vector_from_fn(|i| DVec3::splat(self.t.lane(i))),
            Pass::Object => L::vector_from_fn(|i| DVec3::splat(self.object.lane(i) + 1.0)),
        }
    }

    /// Lane `k`'s four terms and colour in f32, as an EXR holds them
    /// ([`in_f32`]): the value of `pass` (a term or final).
    #[inline(always)]
    fn value_in_f32(&self, pass: Pass, k: usize) -> DVec3 {
        let lane = |v| L::vector_lane(v, k);
        let terms = [
            lane(self.terms.ambient),
            lane(self.terms.diffuse),
            lane(self.terms.specular),
            lane(self.reflection),
        ];
        let (terms, color) = in_f32(terms, lane(self.color()));
        match pass {
            Pass::Ambient => terms[0],
            Pass::Diffuse => terms[1],
            Pass::Specular => terms[2],
            Pass::Reflection => terms[3],
            _ => color,
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
trait Kernel {
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
type Vectors<K> = <<K as Kernel>::L as Lanes>::Vector;
/// A kernel's lanes still tracing.
type Alive<K> = <<K as Kernel>::L as Real>::Mask;

/// Work that runs with the kernel of the prepared scene's method
/// ([`Prepared::with_kernel`]): generic over it, so each kernel's trace
/// loop is compiled on its own and the reference path pays nothing for the
/// others.
trait WithKernel {
    type Output;
    /// Runs one lane at a time (f64 geometry in plain f64).
    const ONE_LANE: bool = false;
    fn run<K: Kernel>(self, p: &Prepared, kernel: &K) -> Self::Output;
}

/// [`Prepared::pixel`]'s work.
struct PixelAt {
    i: u32,
    j: u32,
}

impl WithKernel for PixelAt {
    type Output = [u8; 3];
    #[inline(always)]
    fn run<K: Kernel>(self, p: &Prepared, kernel: &K) -> [u8; 3] {
        let mut out = [[0; 3]; MAX_LANES];
        p.pixels::<K, u8>(
            kernel,
            &[(self.i, self.j)],
            Candidates::All,
            &mut 0,
            &mut out,
        );
        out[0]
    }
}

/// [`Prepared::explain_each`]'s work: each ray through the pixel traced
/// alone, in turn; with a visitor, its trace recorded and handed to it
/// (one tree held at a time), without one only its colour kept. Returns
/// the pixel, or `None` once the visitor stops.
struct ExplainAt<'a> {
    i: u32,
    j: u32,
    visit: Option<&'a mut dyn FnMut(Sample) -> ControlFlow<()>>,
}

impl WithKernel for ExplainAt<'_> {
    type Output = Option<PixelValue>;
    const ONE_LANE: bool = true;
    fn run<K: Kernel>(mut self, p: &Prepared, kernel: &K) -> Option<PixelValue> {
        // The early stop of one-ray pixels, as the render does.
        let exact_stop = p.aa == 1 && p.world.early_stop;
        let (mut sum, mut clamped_sum) = (DVec3::ZERO, DVec3::ZERO);
        let mut first = DVec3::ZERO;
        // In a draft, the pixel whose rays this one copies.
        let traced = p.traced_for(self.i, self.j);
        for k in 0..p.sample_count() {
            let at = p.sample_point(traced.0, traced.1, k);
            let packet = p.packet::<K>(&[at]);
            let color = match self.visit.as_deref_mut() {
                Some(visit) => {
                    let mut recorder = Recorder::default();
                    let traced = p.trace(
                        kernel,
                        packet,
                        Candidates::All,
                        exact_stop,
                        &mut 0,
                        &mut recorder,
                    );
                    let sample = recorder.finish(
                        at,
                        K::L::vector_lane(traced.reflection, 0),
                        K::L::vector_lane(traced.color(), 0),
                    );
                    let color = sample.color;
                    if visit(sample).is_break() {
                        return None;
                    }
                    color
                }
                None => {
                    let traced =
                        p.trace(kernel, packet, Candidates::All, exact_stop, &mut 0, &mut ());
                    K::L::vector_lane(traced.color(), 0)
                }
            };
            if k == 0 {
                first = color;
            }
            sum += color;
            clamped_sum += clamped(color);
        }
        // The pixel as [`Prepared::pixels`] makes it.
        let n = f64::from(p.aa);
        let (rgb, rgb8) = if p.aa == 1 {
            (first, u8::pixel(clamped(first)))
        } else {
            (sum / (n * n), u8::pixel(clamped_sum / (n * n)))
        };
        Some(PixelValue {
            traced,
            rgb,
            rgb8,
            samples: p.sample_count(),
        })
    }
}

/// [`Prepared::rays_through`]'s work: each ray traced alone among the
/// tile's candidates, as the render traces it, its rays counted.
struct RaysThrough<'a> {
    points: &'a [(f64, f64)],
    candidates: Candidates<'a>,
}

impl WithKernel for RaysThrough<'_> {
    type Output = u64;
    const ONE_LANE: bool = true;
    fn run<K: Kernel>(self, p: &Prepared, kernel: &K) -> u64 {
        let exact_stop = p.aa == 1 && p.world.early_stop;
        let mut rays = 0;
        for &at in self.points {
            p.trace(
                kernel,
                p.packet::<K>(&[at]),
                self.candidates,
                exact_stop,
                &mut rays,
                &mut (),
            );
        }
        rays
    }
}

/// [`Prepared::render_tile_into`]'s work.
struct TileInto<'a, T> {
    tile: &'a Tile,
    cancel: &'a Cancel,
    out: &'a mut Vec<T>,
}

impl<T: Texel> WithKernel for TileInto<'_, T> {
    type Output = Option<u64>;
    #[inline(always)]
    fn run<K: Kernel>(self, p: &Prepared, kernel: &K) -> Option<u64> {
        p.tile_into(kernel, self.tile, self.cancel, self.out)
    }
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
        // The geometric normal: from the centre for a ball (computed in
        // the lanes), given for a plane, through the matrix for an
        // ellipsoid (one lane at a time).
        let mut centers = [DVec3::ZERO; MAX_LANES];
        let mut given = [DVec3::ZERO; MAX_LANES];
        let mut ball = [false; MAX_LANES];
        for i in 0..L::WIDTH {
            if !alive.lane(i) {
                continue;
            }
            let hit = hits.lane(i);
            let primitive = match hit.primitive {
                PrimitiveRef::Bounded(k) => &p.world.shapes.bounded[k],
                PrimitiveRef::Plane(k) => &p.world.shapes.planes[k],
            };
            match primitive {
                Primitive::Ball { center, .. } => (centers[i], ball[i]) = (*center, true),
                Primitive::Plane(plane) => given[i] = plane.normal,
                Primitive::Ellipsoid(_) => {
                    let ray = Ray::new(L::vector_lane(rays.origin, i), L::vector_lane(rays.dir, i));
                    given[i] = primitive.normal_at(&ray, hit.t);
                }
            }
        }
        let from_center = (m - L::vector_from_fn(|i| centers[i])).normalize();
        let n = L::Vector::select(
            L::Mask::from_fn(|i| ball[i]),
            from_center,
            L::vector_from_fn(|i| given[i]),
        );
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

/// A colour clamped to [0, 1] per channel (NaN to 0), as pixels average
/// their samples.
#[inline(always)]
fn clamped(c: Color) -> Color {
    c.clamp(Color::ZERO, Color::ONE)
}

/// Per channel, the most any one hit can add before weighting: the
/// largest ka C + Σ I (kd + ks) over the objects (the terms the model
/// uses).
pub(super) fn max_local_color(scene: &Scene) -> Color {
    let light_sum = scene.lights.iter().fold(Color::ZERO, |s, l| s + l.color);
    scene.objects.iter().fold(Color::ZERO, |acc, o| {
        let Material { ka, kd, ks, .. } = o.material;
        let direct = match scene.model.illumination {
            Illumination::Ambient => 0.0,
            Illumination::Lambert => kd,
            Illumination::Phong | Illumination::Whitted => kd + ks,
        };
        acc.max(ka * o.color + direct * light_sum)
    })
}

/// Builds the prepared scene.
pub fn prepare(scene: &Scene, options: &RenderOptions) -> Prepared {
    let shapes = Arc::new(Shapes::new(scene, options));
    Prepared::over(shapes, scene, options)
}

impl Shapes {
    /// The primitives of `scene`'s objects, their hierarchy and culling.
    fn new(scene: &Scene, options: &RenderOptions) -> Shapes {
        // Spheres are bounded, planes are not.
        let mut bounded_objects = Vec::with_capacity(
            scene
                .objects
                .iter()
                .filter(|o| o.shape.is_bounded())
                .count(),
        );
        let mut planes = Vec::new();
        let mut plane_objects = Vec::new();
        // Object numbers fit in u32: the loader takes at most MAX_OBJECTS.
        for (index, object) in (0u32..).zip(scene.objects.iter()) {
            if object.shape.is_bounded() {
                bounded_objects.push(index);
            } else {
                planes.push(Primitive::new(object.shape, &object.transform));
                plane_objects.push(index);
            }
        }
        // The primitives with their object numbers, made in the scene's
        // order (its objects read in a row), then put in leaf order by the
        // build itself: leaves read them in a row, and no object is read
        // again in the hierarchy's order (a million scattered reads).
        let mut placed: Vec<(Primitive, u32)> = bounded_objects
            .par_iter()
            .map(|&index| {
                let object = &scene.objects[index as usize];
                (Primitive::new(object.shape, &object.transform), index)
            })
            .collect();
        drop(bounded_objects);
        let bvh = (options.accelerate && placed.len() >= BVH_THRESHOLD).then(|| {
            Bvh::build_over(&mut placed, |(primitive, _)| {
                primitive.bounds().unwrap_or(Aabb::EMPTY)
            })
        });
        let bounded_objects: Vec<u32> = placed.iter().map(|&(_, index)| index).collect();
        // In place: the pairs' memory becomes the primitives' (40 bytes of
        // 48), and the 8 left over go back (a million spheres: 8 MB).
        let mut bounded: Vec<Primitive> =
            placed.into_iter().map(|(primitive, _)| primitive).collect();
        bounded.shrink_to_fit();

        let cull_spheres = if options.accelerate && bounded.len() <= CULL_LIMIT {
            bounded
                .iter()
                .filter_map(|p| p.bounds())
                .map(|b| {
                    let (centre, radius) = (b.centroid(), 0.5 * (b.max - b.min).length());
                    // A box that overflows (a sphere stretched by 1e308)
                    // has no finite centre: it may be anywhere, every tile
                    // keeps it.
                    if centre.is_finite() && radius.is_finite() {
                        (centre, radius)
                    } else {
                        (DVec3::ZERO, f64::INFINITY)
                    }
                })
                .collect()
        } else {
            Vec::new()
        };

        let (bounded32, planes32) = match options.precision {
            Precision::F64 => (Vec::new(), Vec::new()),
            Precision::F32 => (
                bounded.iter().map(Primitive32::new).collect(),
                planes.iter().map(Primitive32::new).collect(),
            ),
        };
        Shapes {
            bounded,
            bounded_objects,
            bvh,
            planes,
            plane_objects,
            cull_spheres,
            cull: options.accelerate,
            precision: options.precision,
            bounded32,
            planes32,
        }
    }
}

impl Prepared {
    /// `scene` prepared over `shapes`, the geometry of its objects' shapes
    /// and transformations with `options`.
    fn over(shapes: Arc<Shapes>, scene: &Scene, options: &RenderOptions) -> Prepared {
        let illumination = scene.model.illumination;
        let max_local = max_local_color(scene);
        let max_ks = scene
            .objects
            .iter()
            .map(|o| o.material.ks)
            .fold(0.0, f64::max);
        let depth = scene.model.reflection_depth();
        let depth = if options.depth_cut {
            depth.saturating_sub(1)
        } else {
            depth
        };
        let tail = if max_ks < 1.0 && depth > 0 {
            let mut tail = Vec::with_capacity(depth as usize + 1);
            let (mut sum, mut power) = (0.0, 1.0);
            tail.push(0.0);
            for _ in 0..depth {
                sum += power;
                power *= max_ks;
                tail.push(sum);
            }
            tail
        } else {
            Vec::new()
        };

        let world = World {
            shapes,
            objects: scene.objects.clone(),
            lights: scene.lights.clone(),
            illumination,
            depth,
            max_local,
            tail,
            early_stop: options.early_stop,
            sphere: options.sphere,
            offset: options.offset,
            draft: options.draft,
        };
        Prepared {
            world: Arc::new(world),
            camera: CameraRays::new(&scene.camera),
            aa: options.aa.max(1),
            pass: Pass::Final,
        }
    }

    /// `scene` prepared with `options`, over this one's geometry when
    /// `scene`'s objects have the shapes and transformations of the scene
    /// this was prepared from, with the same `accelerate` and `precision`
    /// (only colours, materials, lights, the model or the camera changed);
    /// `None` when they do not. The image is the one [`prepare`] gives.
    pub fn with_surfaces(&self, scene: &Scene, options: &RenderOptions) -> Option<Prepared> {
        let world = &self.world;
        let same = world.shapes.cull == options.accelerate
            && world.shapes.precision == options.precision
            && world.objects.len() == scene.objects.len()
            && world.objects.iter().zip(&scene.objects).all(|(a, b)| {
                Arc::ptr_eq(a, b) || (a.shape == b.shape && a.transform == b.transform)
            });
        same.then(|| Prepared::over(Arc::clone(&world.shapes), scene, options))
    }

    /// The same scene seen through `camera` (its size may differ from the
    /// scene's: the coarse passes of a preview) with `aa` × `aa` rays per
    /// pixel. Nothing of the scene is prepared again or copied.
    pub fn with_view(&self, camera: &Camera, aa: u32) -> Prepared {
        Prepared {
            world: Arc::clone(&self.world),
            camera: CameraRays::new(camera),
            aa: aa.max(1),
            pass: self.pass,
        }
    }

    /// The same view computing `pass` in its `f64` texels.
    pub fn for_pass(&self, pass: Pass) -> Prepared {
        Prepared {
            pass,
            ..self.clone()
        }
    }

    /// What this view's `f64` texels hold.
    pub fn pass(&self) -> Pass {
        self.pass
    }

    /// Both are views of one prepared scene (neither was prepared again).
    pub fn same_world(&self, other: &Prepared) -> bool {
        Arc::ptr_eq(&self.world, &other.world)
    }

    /// Both share one geometry (the later one was prepared over the
    /// other's: [`Prepared::with_surfaces`]).
    pub fn same_shapes(&self, other: &Prepared) -> bool {
        Arc::ptr_eq(&self.world.shapes, &other.world.shapes)
    }

    pub fn width(&self) -> u32 {
        self.camera.width()
    }

    /// The whole of this view's image.
    pub fn frame(&self) -> crate::render::region::Region {
        crate::render::region::Region::whole(self.width(), self.height())
    }

    pub fn height(&self) -> u32 {
        self.camera.height()
    }

    pub fn camera(&self) -> &CameraRays {
        &self.camera
    }

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

    /// The colours of a packet of primary rays (the `alive` lanes),
    /// following whitted reflections as a loop; a lane leaves the loop
    /// when its chain ends. `exact_stop`: end a chain once the rest cannot
    /// change the 8-bit value of its colour. `rays` counts the rays traced;
    /// `observer` sees each step (`()`: nothing, and costs nothing).
    ///
    /// The colour is the camera ray's hit's own terms, then the later
    /// bounces: ((ambient + diffuse) + specular) + reflection, where
    /// reflection = Σ_k w_k I_k over the later hits, w_k the product of
    /// the ks met before hit k: the whitted formula I = phong + ks I_r
    /// (docs/scene-format.md, Illumination) unrolled.
    #[inline(always)]
    fn trace<K: Kernel, O: Observer<K::L>>(
        &self,
        kernel: &K,
        (primary, alive): (Ray<Vectors<K>>, Alive<K>),
        candidates: Candidates,
        exact_stop: bool,
        rays: &mut u64,
        observer: &mut O,
    ) -> Traced<K::L> {
        let world = &*self.world;
        let zero = K::L::splat_vector(Color::ZERO);
        let mut traced = Traced::<K::L>::dark();
        // The camera ray's hit's own colour, once known.
        let mut first = zero;
        // Product of the ks of the surfaces met so far.
        let mut weight = K::L::ONE;
        let mut alive = alive;
        let mut ray = kernel.primary(primary);
        for bounce in 0..=world.depth {
            let among = if bounce == 0 {
                candidates
            } else {
                Candidates::All
            };
            *rays += u64::from(alive.count());
            observer.ray(bounce, &kernel.in_f64(&ray));
            let hits = kernel.nearest(self, &ray, alive, among);
            // A miss is black: its lane is done.
            observer.missed(alive & !hits.found);
            alive = alive & hits.found;
            if !alive.any() {
                break;
            }
            // The surface each lane hit.
            // (A plain loop: a closure here could be left out of line,
            // and the lanes' instructions in it with it.)
            let mut surfaces: [&Object; MAX_LANES] = [&world.objects[0]; MAX_LANES];
            for (i, surface) in surfaces.iter_mut().enumerate().take(K::L::WIDTH) {
                if alive.lane(i) {
                    *surface = &world.objects[hits.object.lane(i) as usize];
                }
            }
            let c = K::L::vector_from_fn(|i| surfaces[i].color);
            let material = Material {
                ka: K::L::from_fn(|i| surfaces[i].material.ka),
                kd: K::L::from_fn(|i| surfaces[i].material.kd),
                ks: K::L::from_fn(|i| surfaces[i].material.ks),
                m: K::L::from_fn(|i| surfaces[i].material.m),
            };
            let point = kernel.surface(self, &ray, &hits, alive);
            let terms = local_color(
                world.illumination,
                c,
                &material,
                &world.lights,
                &point,
                observer,
            );
            observer.hit(
                alive,
                hits.object,
                hits.t,
                &point,
                &terms,
                material.ks,
                weight,
            );
            let local = terms.local();
            if bounce == 0 {
                let pick = |v| <Vectors<K>>::select(alive, v, zero);
                traced.terms = Terms {
                    ambient: pick(terms.ambient),
                    diffuse: pick(terms.diffuse),
                    specular: pick(terms.specular),
                };
                traced.normal = pick(point.n);
                traced.t = K::L::select(alive, hits.t, traced.t);
                traced.object = K::L::select(alive, hits.object, traced.object);
                first = pick(local);
            } else {
                traced.reflection = <Vectors<K>>::select(
                    alive,
                    traced.reflection + local.scaled(weight),
                    traced.reflection,
                );
            }
            weight = K::L::select(alive, weight * material.ks, weight);
            if bounce == world.depth {
                observer.ended(alive, Ended::Depth);
                break;
            }
            let mirror = !weight.eq(K::L::ZERO);
            observer.ended(alive & !mirror, Ended::NoMirror);
            alive = alive & mirror;
            if exact_stop && alive.any() {
                let levels = world.depth - bounce;
                let color = first + traced.reflection;
                let mut invisible = [false; MAX_LANES];
                for (i, lane) in invisible.iter_mut().enumerate().take(K::L::WIDTH) {
                    if !alive.lane(i) {
                        continue;
                    }
                    let rest =
                        self.invisible_rest(K::L::vector_lane(color, i), weight.lane(i), levels);
                    if let Some(bound) = rest {
                        *lane = true;
                        let only = <Alive<K>>::from_fn(|k| k == i);
                        observer.ended(only, Ended::EarlyStop { bound });
                    }
                }
                alive = alive & !<Alive<K>>::from_fn(|i| invisible[i]);
            }
            if !alive.any() {
                break;
            }
            ray = kernel.reflected(&point);
        }
        traced
    }

    /// Whether `levels` more reflections, each adding at most
    /// `weight · max_ks^k · max_local`, leave every channel's 8-bit value
    /// where it is: the most they could add when they do not, `None` when
    /// they might. Every term is ≥ 0, so the final colour lies between
    /// `color` and `color + bound`; equal rounding at both ends settles it.
    #[inline(always)]
    fn invisible_rest(&self, color: Color, weight: f64, levels: u32) -> Option<Color> {
        let &series = self.world.tail.get(levels as usize)?;
        // A hair of margin covers the rounding of the sums themselves.
        let bound = weight * series * self.world.max_local * (1.0 + 1e-9) + DVec3::splat(1e-12);
        let high = color + bound;
        (0..3)
            .all(|c| to_8bit(color[c]) == to_8bit(high[c]))
            .then_some(bound)
    }

    /// Runs `work` with the kernel of the method's choices, each dispatched
    /// once, one choice at a time: the sphere test, the precision, then
    /// (f64) the widest lanes.
    #[inline(always)]
    fn with_kernel<W: WithKernel>(&self, work: W) -> W::Output {
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

    /// The 8-bit colour of pixel (i, j): one ray through its centre, or the
    /// mean of `aa × aa` clamped samples on a regular grid.
    pub fn pixel(&self, i: u32, j: u32) -> [u8; 3] {
        self.with_kernel(PixelAt { i, j })
    }

    /// The rays a render of `tile` traces for one camera ray through each
    /// of `points` (image points in pixels, in the tile), reflections
    /// included: what the tile costs there, for one ray a pixel. None in
    /// a tile the render fills without tracing (nothing can be hit from
    /// it). `split`'s estimate of where the work is.
    pub fn rays_through(&self, tile: &Tile, points: &[(f64, f64)]) -> u64 {
        let culled = self.tile_candidates(tile);
        let candidates = match &culled {
            Some(list) if list.is_empty() && self.world.shapes.planes.is_empty() => return 0,
            Some(list) => Candidates::Only(list),
            None => Candidates::All,
        };
        self.with_kernel(RaysThrough { points, candidates })
    }

    /// Why pixel (i, j) has its colour: each of its rays' trees, recorded
    /// from the render's trace ([`super::explain`]); `None` outside the
    /// image. All the trees at once: [`Prepared::explain_each`] hands them
    /// on one at a time. A draft's pixel is explained by the rays the draft
    /// traced for it: those of its 2×2 block's top-left pixel
    /// ([`Explanation::traced`]).
    pub fn explain(&self, i: u32, j: u32) -> Option<Explanation> {
        let mut samples = Vec::new();
        let pixel = self.explain_each(i, j, |sample| {
            samples.push(sample);
            ControlFlow::Continue(())
        })?;
        Some(Explanation {
            x: i,
            y: j,
            traced: pixel.traced,
            illumination: self.world.illumination,
            samples,
            rgb: pixel.rgb,
            rgb8: pixel.rgb8,
        })
    }

    /// [`Prepared::explain`] in bounded memory: each ray's tree in turn to
    /// `visit` (its aa × aa rays in reading order), one held at a time, so
    /// that 256 rays of 10 000 bounces never are in memory together. Then
    /// the pixel they make; `None` outside the image, or once `visit`
    /// stops (`ControlFlow::Break`).
    pub fn explain_each(
        &self,
        i: u32,
        j: u32,
        mut visit: impl FnMut(Sample) -> ControlFlow<()>,
    ) -> Option<PixelValue> {
        if i >= self.width() || j >= self.height() {
            return None;
        }
        self.with_kernel(ExplainAt {
            i,
            j,
            visit: Some(&mut visit),
        })
    }

    /// The pixel [`Prepared::explain`] explains, traced as it traces it
    /// but recording nothing: what a writer needs before the trees (the
    /// JSON's `rgb` comes before its samples). `None` outside the image.
    pub fn explained_pixel(&self, i: u32, j: u32) -> Option<PixelValue> {
        if i >= self.width() || j >= self.height() {
            return None;
        }
        self.with_kernel(ExplainAt { i, j, visit: None })
    }

    /// Rays through each pixel: 1, or aa × aa.
    pub fn samples_per_pixel(&self) -> usize {
        self.sample_count()
    }

    /// The illumination model of the prepared scene.
    pub fn illumination(&self) -> Illumination {
        self.world.illumination
    }

    /// The pixels (8-bit colours, or the values of the view's pass) of up
    /// to a packet's width of pixels into `out`: with one ray per pixel,
    /// one lane per pixel; supersampled, each pixel's samples in lanes,
    /// their clamped colours (or pass values) summed in the order of the
    /// grid.
    #[inline(always)]
    fn pixels<K: Kernel, T: Texel>(
        &self,
        kernel: &K,
        pixels: &[(u32, u32)],
        candidates: Candidates,
        rays: &mut u64,
        out: &mut [[T; 3]; MAX_LANES],
    ) {
        let width = K::L::WIDTH;
        debug_assert!(!pixels.is_empty() && pixels.len() <= width && width <= MAX_LANES);
        // 8-bit texels are the image (known at compile time: the trace
        // then keeps nothing of the passes).
        let pass = if T::UNCLAMPED { self.pass } else { Pass::Final };
        if self.aa == 1 {
            let mut points = [(0.0, 0.0); MAX_LANES];
            for (point, &(i, j)) in points.iter_mut().zip(pixels) {
                *point = (f64::from(i) + 0.5, f64::from(j) + 0.5);
            }
            let traced = self.trace(
                kernel,
                self.packet::<K>(&points[..pixels.len()]),
                candidates,
                self.world.early_stop,
                rays,
                &mut (),
            );
            // One ray: its value as it is (8-bit texels clamp themselves),
            // the terms and final of a pass in f32 (they add up there).
            let value = traced.value(pass);
            for (k, pixel) in out.iter_mut().take(pixels.len()).enumerate() {
                *pixel = T::pixel(if T::UNCLAMPED && pass.is_term_or_final() {
                    traced.value_in_f32(pass, k)
                } else {
                    K::L::vector_lane(value, k)
                });
            }
            return;
        }
        // Supersampled: a sample's own rounding says nothing about the
        // mean's, so every chain runs to its end.
        let n = f64::from(self.aa);
        let mut points = [(0.0, 0.0); MAX_LANES];
        for (pixel, &(i, j)) in out.iter_mut().zip(pixels) {
            let mut sum = DVec3::ZERO;
            for first in (0..self.sample_count()).step_by(width) {
                let count = width.min(self.sample_count() - first);
                for (k, point) in points.iter_mut().take(count).enumerate() {
                    *point = self.sample_point(i, j, first + k);
                }
                let packet = self.packet::<K>(&points[..count]);
                let traced = self.trace(kernel, packet, candidates, false, rays, &mut ());
                let value = traced.value(pass);
                for k in 0..count {
                    let v = K::L::vector_lane(value, k);
                    sum += if pass == Pass::Final { clamped(v) } else { v };
                }
            }
            *pixel = T::pixel(sum / (n * n));
        }
    }

    /// Rays per pixel: aa × aa.
    fn sample_count(&self) -> usize {
        (self.aa * self.aa) as usize
    }

    /// The image point of sample `k` of pixel (i, j): the pixel's centre
    /// with one ray per pixel, else the grid's cells in reading order.
    #[inline(always)]
    fn sample_point(&self, i: u32, j: u32, k: usize) -> (f64, f64) {
        let (aa, n) = (self.aa as usize, f64::from(self.aa));
        let (a, b) = (k % aa, k / aa);
        (
            f64::from(i) + (a as f64 + 0.5) / n,
            f64::from(j) + (b as f64 + 0.5) / n,
        )
    }

    /// A packet of camera rays through image points (at most a packet's
    /// width); lanes past the last point repeat it and stay dark.
    #[inline(always)]
    fn packet<K: Kernel>(&self, points: &[(f64, f64)]) -> (Ray<Vectors<K>>, Alive<K>) {
        let last = points.len() - 1;
        let rays = self.camera.rays(
            K::L::from_fn(|i| points[i.min(last)].0),
            K::L::from_fn(|i| points[i.min(last)].1),
        );
        (rays, <Alive<K>>::from_fn(|i| i <= last))
    }

    /// Renders one tile row-major into `out` (cleared first), three
    /// texels a pixel (RGB8, or the view's pass in f64), checking `cancel`
    /// before every packet of pixels. Returns the number of rays traced,
    /// or `None` when cancelled.
    pub fn render_tile_into<T: Texel>(
        &self,
        tile: &Tile,
        cancel: &Cancel,
        out: &mut Vec<T>,
    ) -> Option<u64> {
        debug_assert!(T::UNCLAMPED || self.pass == Pass::Final);
        self.with_kernel(TileInto { tile, cancel, out })
    }

    /// The side of the blocks one traced pixel stands for: 2 in a draft,
    /// else 1.
    fn draft_step(&self) -> u32 {
        if self.world.draft { 2 } else { 1 }
    }

    /// The pixel whose rays give pixel (i, j) its colour: itself, or in a
    /// draft the top-left of its 2×2 block, which [`Prepared::tile_into`]
    /// traces and copies to the other three.
    pub fn traced_for(&self, i: u32, j: u32) -> (u32, u32) {
        let step = self.draft_step();
        (i - i % step, j - j % step)
    }

    #[inline(always)]
    fn tile_into<K: Kernel, T: Texel>(
        &self,
        kernel: &K,
        tile: &Tile,
        cancel: &Cancel,
        out: &mut Vec<T>,
    ) -> Option<u64> {
        // Every pixel a miss until traced (what a tile that can hit
        // nothing keeps: black, no object, t = ∞).
        let [miss, ..] = T::pixel(f64::vector_lane(Traced::<f64>::dark().value(self.pass), 0));
        out.clear();
        out.resize(tile.width as usize * tile.height as usize * 3, miss);
        // Draft: one pixel in four is traced, the top-left of each 2×2
        // block of the image (even x and y); the other three copy it. A
        // tile of a region may start at an odd row or column: its first
        // pixels copy a block's corner outside it, traced all the same.
        let step = self.draft_step();
        let anchor = |v: u32| v - v % step;
        let traced_area = Tile {
            x: anchor(tile.x),
            y: anchor(tile.y),
            width: tile.width + tile.x % step,
            height: tile.height + tile.y % step,
        };
        let candidates = self.tile_candidates(&traced_area);
        let candidates = match &candidates {
            Some(list) => {
                if list.is_empty() && self.world.shapes.planes.is_empty() {
                    // Nothing can be hit from this tile: every ray misses.
                    return (!cancel.is_cancelled()).then_some(0);
                }
                Candidates::Only(list)
            }
            None => Candidates::All,
        };
        let mut rays = 0;
        let (x_end, row_bytes) = (tile.x + tile.width, tile.width as usize * 3);
        let mut traced = [[T::default(); 3]; MAX_LANES];
        let mut row: Vec<(u32, u32)> = Vec::with_capacity(tile.width as usize);
        for (dj, j) in (tile.y..tile.y + tile.height).enumerate() {
            let line = dj * row_bytes;
            if j != anchor(j) && j != tile.y {
                // A draft's odd row: the row above.
                out.copy_within(line - row_bytes..line, line);
                continue;
            }
            row.clear();
            row.extend(
                (traced_area.x..x_end)
                    .step_by(step as usize)
                    .map(|i| (i, anchor(j))),
            );
            for packet in row.chunks(K::L::WIDTH) {
                if cancel.is_cancelled() {
                    return None;
                }
                self.pixels(kernel, packet, candidates, &mut rays, &mut traced);
                for (&(a, _), rgb) in packet.iter().zip(&traced) {
                    // The traced pixel and, in a draft, the one on its
                    // right: those of them in the tile.
                    for i in (a..a + step).filter(|i| (tile.x..x_end).contains(i)) {
                        let at = line + (i - tile.x) as usize * 3;
                        out[at..at + 3].copy_from_slice(rgb);
                    }
                }
            }
        }
        Some(rays)
    }

    /// The bounded primitives whose bounding sphere reaches into the
    /// tile's frustum (the four planes through the eye and the tile's
    /// edges), or `None` when the scene has too many to cull or culling
    /// is off.
    fn tile_candidates(&self, tile: &Tile) -> Option<Vec<usize>> {
        if !self.world.shapes.cull {
            return None;
        }
        let (x0, y0) = (f64::from(tile.x), f64::from(tile.y));
        let (x1, y1) = (x0 + f64::from(tile.width), y0 + f64::from(tile.height));
        let eye = self.camera.ray(x0, y0).origin;
        let corner = |x, y| self.camera.ray(x, y).dir;
        let (a, b, c, d) = (
            corner(x0, y0),
            corner(x1, y0),
            corner(x1, y1),
            corner(x0, y1),
        );
        let centre = (a + b + c + d).normalize();
        // Side planes through the eye; the cross product of two unit corner
        // directions has length sin θ, θ the angle between them.
        let sides = [a.cross(b), b.cross(c), c.cross(d), d.cross(a)];
        let sin_min = sides
            .iter()
            .map(|n| n.length())
            .fold(f64::INFINITY, f64::min);
        if !(sin_min > 0.0 && sin_min.is_finite() && centre.is_finite()) {
            // A degenerate frustum (a camera squashed flat): no culling.
            return None;
        }
        // Inward unit normals. Their direction is only as good as the
        // corner directions' rounding (~1e-15) over sin θ: a hair of
        // relative slack per unit of distance covers that and the rounding
        // of the dot products.
        let planes = sides.map(|n| {
            let n = n / n.length();
            if n.dot(centre) < 0.0 { -n } else { n }
        });
        let relative = 1e-9 + 1e-13 / sin_min;
        if let Some(bvh) = &self.world.shapes.bvh
            && self.world.shapes.cull_spheres.is_empty()
        {
            let mut found = Vec::new();
            return bvh
                .collect_in_cone(eye, &planes, relative, TILE_CANDIDATES, &mut found)
                .then_some(found);
        }
        let inside = |(centre, radius): &(DVec3, f64)| {
            let to = *centre - eye;
            let slack = radius * (1.0 + 1e-9) + relative * to.length();
            planes.iter().all(|n| n.dot(to) >= -slack)
        };
        Some(
            self.world
                .shapes
                .cull_spheres
                .iter()
                .enumerate()
                .filter(|(_, s)| inside(s))
                .map(|(k, _)| k)
                .collect(),
        )
    }

    /// The object seen through image point (x, y) in pixels, if any: the
    /// app's pick ray.
    pub fn pick(&self, x: f64, y: f64) -> Option<usize> {
        self.nearest_hit(&self.camera.ray(x, y)).map(|h| h.object)
    }
}
