//! The prepared scene: objects with their world-to-object matrices, lights,
//! camera rays and the model, laid out for tracing.

use super::{CameraRays, RenderOptions, to_8bit};
use crate::geometry::{Ray, intersect_plane, intersect_sphere};
use crate::scene::{Scene, Shape};
use crate::shading::{Color, Illumination, Light, Material, SurfacePoint, local_color, reflect};
use glam::{DAffine3, DMat3, DVec3};

/// An object as the tracer sees it.
#[derive(Debug, Clone)]
struct PreparedObject {
    shape: Shape,
    color: Color,
    material: Material,
    /// World to object space.
    to_object: DAffine3,
    /// Object-space normal to world space: (M⁻¹)ᵀ.
    normal: DMat3,
}

/// The nearest hit of a ray.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Hit {
    /// World distance along the ray (the ray's direction is unit length).
    pub t: f64,
    /// Index of the object in the scene's object list.
    pub object: usize,
    /// Geometric normal at the hit in object space (not normalised).
    object_normal: DVec3,
}

/// What rendering needs, computed once per render.
#[derive(Debug, Clone)]
pub struct Prepared {
    objects: Vec<PreparedObject>,
    lights: Vec<Light>,
    illumination: Illumination,
    /// Reflected rays followed per primary ray (0 unless whitted).
    depth: u32,
    camera: CameraRays,
    aa: u32,
}

/// Builds the prepared scene.
pub fn prepare(scene: &Scene, options: &RenderOptions) -> Prepared {
    let objects = scene
        .objects
        .iter()
        .map(|o| PreparedObject {
            shape: o.shape,
            color: o.color,
            material: o.material,
            to_object: *o.transform.to_object(),
            normal: *o.transform.normal_matrix(),
        })
        .collect();
    Prepared {
        objects,
        lights: scene.lights.clone(),
        illumination: scene.model.illumination,
        depth: scene.model.reflection_depth(),
        camera: CameraRays::new(&scene.camera),
        aa: options.aa.max(1),
    }
}

impl Prepared {
    pub fn width(&self) -> u32 {
        self.camera.width()
    }

    pub fn height(&self) -> u32 {
        self.camera.height()
    }

    pub fn camera(&self) -> &CameraRays {
        &self.camera
    }

    /// The nearest hit with t > 0 in world distance, if any.
    pub fn nearest_hit(&self, ray: &Ray) -> Option<Hit> {
        let mut best: Option<(f64, usize, Ray)> = None;
        for (index, object) in self.objects.iter().enumerate() {
            // The ray in object space; its direction keeps the world scale,
            // so t is a world distance.
            let local = Ray::new(
                object.to_object.transform_point3(ray.origin),
                object.to_object.transform_vector3(ray.dir),
            );
            let t = match object.shape {
                Shape::Sphere => intersect_sphere(&local),
                Shape::Plane => intersect_plane(&local),
            };
            if let Some(t) = t
                && best.is_none_or(|(best_t, _, _)| t < best_t)
            {
                best = Some((t, index, local));
            }
        }
        best.map(|(t, object, local)| Hit {
            t,
            object,
            object_normal: match self.objects[object].shape {
                Shape::Sphere => local.at(t),
                Shape::Plane => DVec3::Z,
            },
        })
    }

    /// The colour of a primary ray, following whitted reflections as a loop.
    pub fn trace(&self, primary: Ray) -> Color {
        let mut color = Color::ZERO;
        // Product of the ks of the surfaces met so far.
        let mut weight = 1.0;
        let mut ray = primary;
        for bounce in 0..=self.depth {
            let Some(hit) = self.nearest_hit(&ray) else {
                break; // a miss is black
            };
            let object = &self.objects[hit.object];
            let m = ray.at(hit.t);
            // Shading normal: world normal flipped to face the ray.
            let mut n = (object.normal * hit.object_normal).normalize();
            if n.dot(ray.dir) > 0.0 {
                n = -n;
            }
            let v = -ray.dir;
            let point = SurfacePoint { m, n, v };
            let local = local_color(
                self.illumination,
                object.color,
                &object.material,
                &self.lights,
                &point,
            );
            color += weight * local;
            weight *= object.material.ks;
            if bounce == self.depth || weight == 0.0 {
                break;
            }
            // Reflected ray R from just off the surface (contract section 5).
            let epsilon = 1e-9 + 1e-12 * m.length();
            ray = Ray::new(m + epsilon * n, reflect(n, v).normalize());
        }
        color
    }

    /// The 8-bit colour of pixel (i, j): one ray through its centre, or the
    /// mean of `aa × aa` clamped samples on a regular grid.
    pub fn pixel(&self, i: u32, j: u32) -> [u8; 3] {
        let (x, y) = (f64::from(i), f64::from(j));
        if self.aa == 1 {
            let c = self.trace(self.camera.ray(x + 0.5, y + 0.5));
            return [to_8bit(c.x), to_8bit(c.y), to_8bit(c.z)];
        }
        let n = f64::from(self.aa);
        let mut sum = DVec3::ZERO;
        for b in 0..self.aa {
            for a in 0..self.aa {
                let ray = self
                    .camera
                    .ray(x + (f64::from(a) + 0.5) / n, y + (f64::from(b) + 0.5) / n);
                sum += self.trace(ray).clamp(DVec3::ZERO, DVec3::ONE);
            }
        }
        let c = sum / (n * n);
        [to_8bit(c.x), to_8bit(c.y), to_8bit(c.z)]
    }

    /// The object seen through image point (x, y) in pixels, if any: the
    /// app's pick ray.
    pub fn pick(&self, x: f64, y: f64) -> Option<usize> {
        self.nearest_hit(&self.camera.ray(x, y)).map(|h| h.object)
    }
}
