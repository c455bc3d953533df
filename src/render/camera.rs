//! Primary rays of the pinhole camera (docs/scene-format.md, Coordinates).

use crate::geometry::{Lanes, Ray, Vector};
use crate::scene::Camera;
use glam::{DAffine3, DVec3};

/// Generates the primary ray through any point of the image.
#[derive(Debug, Clone)]
pub struct CameraRays {
    width: u32,
    height: u32,
    /// Screen units per pixel: s = 2 / min(width, height).
    s: f64,
    /// The eye, world space: camera · (0, 0, −eyeDistance).
    eye: DVec3,
    to_world: DAffine3,
}

impl CameraRays {
    pub fn new(camera: &Camera) -> CameraRays {
        let to_world = camera.transform.to_world();
        CameraRays {
            width: camera.width,
            height: camera.height,
            s: 2.0 / f64::from(camera.width.min(camera.height)),
            eye: to_world.transform_point3(DVec3::new(0.0, 0.0, -camera.eye_distance)),
            to_world,
        }
    }

    pub fn width(&self) -> u32 {
        self.width
    }

    pub fn height(&self) -> u32 {
        self.height
    }

    /// The ray from the eye through image point (x, y), in pixels from the
    /// top-left corner of the image: pixel (i, j) has its centre at
    /// (i + 0.5, j + 0.5).
    pub fn ray(&self, x: f64, y: f64) -> Ray {
        self.rays::<f64>(x, y)
    }

    /// The rays through image points (x, y), one per lane: each lane's is
    /// [`CameraRays::ray`] of its point, bit for bit (glam's
    /// `transform_point3` and `normalize`, spelled out per lane).
    #[inline(always)]
    pub fn rays<L: Lanes>(&self, x: L, y: L) -> Ray<L::Vector> {
        // Screen point in camera space.
        let sx = (x - L::splat(f64::from(self.width) / 2.0)) * L::splat(self.s);
        let sy = (y - L::splat(f64::from(self.height) / 2.0)) * L::splat(self.s);
        // Then world space: M (sx, sy, 0) + T.
        let m = &self.to_world.matrix3;
        let axis = L::splat_vector;
        let p = axis(m.x_axis).scaled(sx)
            + axis(m.y_axis).scaled(sy)
            + axis(m.z_axis).scaled(L::ZERO)
            + axis(self.to_world.translation);
        let eye = axis(self.eye);
        Ray::new(eye, (p - eye).normalize())
    }
}
