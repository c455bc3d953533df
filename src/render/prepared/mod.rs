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
//!   the widest lanes the processor has, picked at run time
//!   ([`kernel`]): eight in an AVX-512 register
//!   ([`Avx8`](crate::geometry::Avx8)), four in an AVX2 one
//!   ([`Avx4`](crate::geometry::Avx4)), else four in a pair of SSE2
//!   registers ([`F64x4`](crate::geometry::F64x4)). Every formula is the
//!   scalar one per lane, so the image is the same bit for bit; a lane
//!   leaves the packet when its chain ends. The f32 study method traces
//!   one ray at a time.
//! - Shading data (colour, material) is read once per hit from the
//!   scene's object, shared with the scene, not copied.
//! - Whitted chains stop as soon as nothing the rest of the chain could add
//!   can change the pixel's 8-bit value (exact: the image is unchanged).
//! - The trace keeps the camera ray's terms and the reflected colour apart
//!   ([`Traced`](trace::Traced)) and adds them in one order: a tile's
//!   texels are the 8-bit image or the values of a render pass
//!   ([`super::pass`]). An observer
//!   type parameter sees each step; `()` in renders, the explained pixel's
//!   recorder in [`Prepared::explain`] (one lane, the same code).
//! - All of it but the camera is one shared [`World`]: another view of the
//!   same scene ([`Prepared::with_view`]: a coarse pass, a moved camera, a
//!   pick) prepares nothing again.
//!   Its geometry (the primitives and their hierarchy, [`Shapes`]) is
//!   shared in turn with the next version of the scene when only colours,
//!   materials, lights or the model changed, and copied with the
//!   hierarchy refitted, not built again, when a few objects moved
//!   ([`Prepared::with_surfaces`]). What the render reads of every object
//!   is worked out once per list of objects ([`super::facts`]).
//!
//! Here: the prepared scene itself and how it is built ([`prepare`],
//! [`Prepared::with_surfaces`], [`Prepared::with_view`]). The geometry of
//! each method, what rays hit and the choice of it at run time, is in
//! [`kernel`]; the trace loop and the pixels and tiles it makes, in
//! [`trace`].

use super::{CameraRays, Offset, Pass, Precision, RenderOptions, SphereTest};
use crate::geometry::{Aabb, Bvh, Primitive, Primitive32};
use crate::scene::{Camera, Scene};
use crate::shading::{Color, Illumination, Light};
use glam::DVec3;
use rayon::prelude::*;
use std::sync::Arc;

mod kernel;
mod trace;

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
    /// Which build the hierarchy comes from: kept by a refit
    /// ([`Shapes::moved`]).
    hierarchy: u64,
}

/// Which bounded primitives a primary ray must test.
#[derive(Debug, Clone, Copy)]
enum Candidates<'a> {
    All,
    Only(&'a [usize]),
}

/// Builds the prepared scene.
pub fn prepare(scene: &Scene, options: &RenderOptions) -> Prepared {
    let shapes = Arc::new(Shapes::new(scene, options));
    Prepared::over(shapes, scene, options)
}

/// Bounding sphere (centre, radius) of each of `bounded`, for the tile
/// frustum test, where tiles cull (`accelerate`) and there are few enough
/// ([`CULL_LIMIT`]); else none.
fn cull_spheres(bounded: &[Primitive], accelerate: bool) -> Vec<(DVec3, f64)> {
    if !accelerate || bounded.len() > CULL_LIMIT {
        return Vec::new();
    }
    bounded
        .iter()
        .filter_map(|p| p.bounds())
        .map(|b| {
            let (centre, radius) = (b.centroid(), 0.5 * (b.max - b.min).length());
            // A box that overflows (a sphere stretched by 1e308) has no
            // finite centre: it may be anywhere, every tile keeps it.
            if centre.is_finite() && radius.is_finite() {
                (centre, radius)
            } else {
                (DVec3::ZERO, f64::INFINITY)
            }
        })
        .collect()
}

/// Objects moved at most, of a scene's, for its geometry to be refitted
/// rather than built again ([`Shapes::moved`]): a hierarchy refitted
/// after many moves would be looser than a new one.
const REFIT_MOST: usize = 64;

impl Shapes {
    /// These shapes with the objects `moved` (their numbers, ascending;
    /// each bounded or not as it was) made again from `scene`: their
    /// primitives replaced where they are, the hierarchy refitted
    /// ([`Bvh::refit`]), not built again. The image is the one a new
    /// preparation gives.
    fn moved(&self, scene: &Scene, moved: &[usize]) -> Shapes {
        let made = |index: u32| {
            let object = &scene.objects[index as usize];
            Primitive::new(object.shape, &object.transform)
        };
        let slots = |objects: &[u32]| -> Vec<usize> {
            let mut slots: Vec<usize> = objects
                .iter()
                .enumerate()
                .filter(|(_, o)| moved.binary_search(&(**o as usize)).is_ok())
                .map(|(slot, _)| slot)
                .collect();
            slots.sort_unstable();
            slots
        };
        let mut bounded = self.bounded.clone();
        let mut bounded32 = self.bounded32.clone();
        let bounded_slots = slots(&self.bounded_objects);
        for &slot in &bounded_slots {
            bounded[slot] = made(self.bounded_objects[slot]);
            if let Some(p) = bounded32.get_mut(slot) {
                *p = Primitive32::new(&bounded[slot]);
            }
        }
        let mut planes = self.planes.clone();
        let mut planes32 = self.planes32.clone();
        for slot in slots(&self.plane_objects) {
            planes[slot] = made(self.plane_objects[slot]);
            if let Some(p) = planes32.get_mut(slot) {
                *p = Primitive32::new(&planes[slot]);
            }
        }
        let mut bvh = self.bvh.clone();
        if let Some(bvh) = &mut bvh {
            bvh.refit(&bounded, &bounded_slots, |p| {
                p.bounds().unwrap_or(Aabb::EMPTY)
            });
        }
        Shapes {
            cull_spheres: cull_spheres(&bounded, self.cull),
            bounded,
            bounded_objects: self.bounded_objects.clone(),
            bvh,
            planes,
            plane_objects: self.plane_objects.clone(),
            cull: self.cull,
            precision: self.precision,
            bounded32,
            planes32,
            hierarchy: self.hierarchy,
        }
    }

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

        let cull_spheres = cull_spheres(&bounded, options.accelerate);

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
            hierarchy: next_hierarchy(),
        }
    }
}

/// A number for each hierarchy built ([`Shapes::hierarchy`]).
fn next_hierarchy() -> u64 {
    static NEXT: std::sync::atomic::AtomicU64 = std::sync::atomic::AtomicU64::new(0);
    NEXT.fetch_add(1, std::sync::atomic::Ordering::Relaxed)
}

impl Prepared {
    /// `scene` prepared over `shapes`, the geometry of its objects' shapes
    /// and transformations with `options`.
    fn over(shapes: Arc<Shapes>, scene: &Scene, options: &RenderOptions) -> Prepared {
        let illumination = scene.model.illumination;
        let facts = super::facts::of(&scene.objects);
        let max_local = facts.max_local_color(scene);
        let max_ks = facts.max_ks;
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
    /// over a copy of it with their primitives made again and the
    /// hierarchy refitted where at most [`REFIT_MOST`] objects moved (each
    /// bounded, or not, as it was); `None` otherwise. The image is the
    /// one [`prepare`] gives.
    pub fn with_surfaces(&self, scene: &Scene, options: &RenderOptions) -> Option<Prepared> {
        let world = &self.world;
        if world.shapes.cull != options.accelerate
            || world.shapes.precision != options.precision
            || world.objects.len() != scene.objects.len()
        {
            return None;
        }
        let mut moved = Vec::new();
        if !world.objects.same_list(&scene.objects) {
            for (n, (a, b)) in world.objects.iter().zip(&scene.objects).enumerate() {
                if Arc::ptr_eq(a, b) || (a.shape == b.shape && a.transform == b.transform) {
                    continue;
                }
                if a.shape.is_bounded() != b.shape.is_bounded() || moved.len() == REFIT_MOST {
                    return None;
                }
                moved.push(n);
            }
        }
        let shapes = match moved.is_empty() {
            true => Arc::clone(&world.shapes),
            false => Arc::new(world.shapes.moved(scene, &moved)),
        };
        Some(Prepared::over(shapes, scene, options))
    }

    /// Both share one hierarchy, built once (the later one's refitted
    /// from the other's, [`Prepared::with_surfaces`], or the same).
    pub fn same_hierarchy(&self, other: &Prepared) -> bool {
        self.world.shapes.hierarchy == other.world.shapes.hierarchy
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
}
