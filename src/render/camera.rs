//! Primary rays of the pinhole camera (contract section 1).

use crate::geometry::Ray;
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
        let to_world = *camera.transform.to_world();
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
        // Screen point in camera space, then world space.
        let sx = (x - f64::from(self.width) / 2.0) * self.s;
        let sy = (y - f64::from(self.height) / 2.0) * self.s;
        let p = self.to_world.transform_point3(DVec3::new(sx, sy, 0.0));
        Ray::new(self.eye, (p - self.eye).normalize())
    }
}
