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
//! replays unsaved edits onto a version of the file another program saved;
//! [`names`] names objects for people (`#2 RED sphere`). [`grammar`] is the
//! format's elements and attributes as data, which the loader reads with
//! and [`schema`] writes as an XML Schema for editors; [`language`] answers
//! what an editor asks of a text (errors, completion, hover, outline).

pub mod edit;
mod error;
pub mod grammar;
pub mod identity;
pub mod language;
mod load;
pub mod merge;
pub mod names;
pub mod schema;
pub mod source;
pub mod splice;
mod xml;

pub use error::{LoadError, LoadErrorKind, Position};
pub use load::{
    LoadProgress, MAX_FILE_BYTES, MAX_LIGHTS, MAX_OBJECTS, MAX_PIXELS, PackedLoad, load,
    load_counting, load_like, load_packed, load_sharing, load_with_text, parse, parse_sharing,
};

pub use crate::geometry::Shape;
use crate::math::Transform;
pub use crate::shading::{Color, Illumination, Light, Material, Model};
use std::sync::Arc;

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
///
/// Objects are shared ([`Arc`]): a copy of a scene shares every object it
/// does not change (the app holds the file's scene, the edited one and the
/// one being rendered; with a million objects each would be 400 MB), and
/// two scenes compare object by object, equal at once where they share it
/// ([`Scene::same_objects`]). Change one with [`Arc::make_mut`].
#[derive(Debug, Clone)]
pub struct Scene {
    pub objects: Vec<Arc<Object>>,
    pub lights: Vec<Light>,
    pub camera: Camera,
    pub model: Model,
}

impl PartialEq for Scene {
    fn eq(&self, other: &Scene) -> bool {
        self.same_but_camera(other) && self.camera == other.camera
    }
}

impl Scene {
    /// Equal but for the camera: what a render prepares of the scene
    /// ([`crate::render::prepare`]) is the same for both.
    pub fn same_but_camera(&self, other: &Scene) -> bool {
        // A shared object is equal to itself without a look at its values.
        self.objects.len() == other.objects.len()
            && self
                .objects
                .iter()
                .zip(&other.objects)
                .all(|(a, b)| Arc::ptr_eq(a, b) || a == b)
            && self.lights == other.lights
            && self.model == other.model
    }
}
