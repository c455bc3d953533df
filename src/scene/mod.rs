//! The scene as the file describes it: objects, lights, camera and
//! illumination model, with defaults filled in and every value validated
//! (contract sections 2–4 and 9).
//!
//! [`load`] reads a file, [`parse`] a string; both return a [`Scene`] or a
//! [`LoadError`] that carries the file and the `line:column` of the culprit.
//! A `Scene` holds no render state: `render::prepare` turns it into what the
//! tracer needs.
//!
//! [`edit`] is the one way a scene changes (the app's panel and undo, the
//! command line's `edit` and `--set`); [`splice`] writes those changes back
//! into the file's text, keeping every byte that was not edited; [`merge`]
//! replays unsaved edits onto a version of the file another program saved.

pub mod edit;
mod error;
mod load;
pub mod merge;
pub mod splice;

pub use error::{LoadError, LoadErrorKind, Position};
pub use load::{MAX_FILE_BYTES, MAX_LIGHTS, MAX_OBJECTS, MAX_PIXELS, load, load_with_text, parse};

use crate::math::Transform;
pub use crate::shading::{Color, Illumination, Light, Material, Model};

/// What an object is in its own space.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Shape {
    /// The unit sphere centred on the origin.
    Sphere,
    /// The plane z = 0, infinite and two-sided.
    Plane,
}

impl Shape {
    /// The element name in the scene format.
    pub fn name(self) -> &'static str {
        match self {
            Shape::Sphere => "sphere",
            Shape::Plane => "plane",
        }
    }
}

/// A sphere or plane placed in the world.
#[derive(Debug, Clone, PartialEq)]
pub struct Object {
    pub shape: Shape,
    pub color: Color,
    pub material: Material,
    /// Object space to world space.
    pub transform: Transform,
}

/// The pinhole camera of contract section 1.
#[derive(Debug, Clone, PartialEq)]
pub struct Camera {
    pub width: u32,
    pub height: u32,
    /// Distance from the eye to the screen plane z = 0, in camera units.
    pub eye_distance: f64,
    /// Camera space to world space.
    pub transform: Transform,
}

/// A whole validated scene.
#[derive(Debug, Clone, PartialEq)]
pub struct Scene {
    pub objects: Vec<Object>,
    pub lights: Vec<Light>,
    pub camera: Camera,
    pub model: Model,
}
