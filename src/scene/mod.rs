//! The scene as the file describes it: objects, lights, camera and
//! illumination model, with defaults filled in and every value validated
//! (docs/scene-format.md: Elements, Transformations, Numbers and Everything
//! else in the file).
//!
//! [`load`](fn@load) reads a file, [`parse`] a string; both return a [`Scene`] or a
//! [`LoadError`] that carries the file and the `line:column` of the culprit.
//! A `Scene` holds no render state: `render::prepare` turns it into what the
//! tracer needs.
//!
//! [`edit`] is the one way a scene changes (the app's panel and undo, the
//! command line's `edit` and `--set`); [`splice`] writes those changes back
//! into the file's text, keeping every byte that was not edited, by the
//! places [`layout`] finds in it; [`fresh`] writes a new file for a scene
//! that has no text yet; [`merge`]
//! replays unsaved edits onto a version of the file another program saved;
//! [`names`] names objects for people (`#2 RED sphere`). [`grammar`] is the
//! format's elements and attributes as data, which the loader reads with
//! and [`schema`] writes as an XML Schema for editors; [`language`] answers
//! what an editor asks of a text (errors, completion, hover, outline).
//! [`generated`] makes scenes by program (n spheres on a floor) for the
//! bench and for tests that want many objects.

pub mod edit;
mod error;
pub mod fresh;
pub mod generated;
pub mod grammar;
pub mod identity;
pub mod language;
pub mod layout;
mod load;
pub mod merge;
pub mod names;
pub mod schema;
pub mod source;
pub mod splice;
mod xml;

pub use error::{LoadError, LoadErrorKind, Position};
pub use load::{
    Layout, LoadProgress, Loaded, MAX_FILE_BYTES, MAX_LIGHTS, MAX_OBJECTS, MAX_PIXELS, PackedLoad,
    Reading, Reread, Span, load, load_counting, load_like, load_packed, load_sharing,
    load_with_text, parse, parse_sharing,
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

/// The pinhole camera (docs/scene-format.md, Coordinates).
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
/// ([`Scene::same_but_camera`]). Change one with [`Arc::make_mut`].
#[derive(Debug, Clone)]
pub struct Scene {
    pub objects: Objects,
    pub lights: Vec<Light>,
    pub camera: Camera,
    pub model: Model,
}

/// A scene's list of objects, itself shared between copies of the scene
/// until one of them changes it: a million objects' list is 8 MB, and the
/// app holds half a dozen copies of its scene (the file's, the edited one,
/// the one being rendered, the world's, the journal's).
///
/// It reads as the [`Vec`] it holds. Writing through it (`&mut`) first
/// makes the list this copy's own ([`Arc::make_mut`]: copied if another
/// copy shares it), never the objects, which stay shared until each is
/// changed with [`Arc::make_mut`] in turn.
///
/// What a reader works out of every object (the render's largest `ks`,
/// the scene's reach) is kept with the list ([`Objects::memo`]) until the
/// list changes: a scene whose lights or camera changed walks no object.
#[derive(Debug, Clone, Default)]
pub struct Objects(Arc<List>);

/// The list behind [`Objects`], with what was worked out of it.
#[derive(Default)]
struct List {
    items: Vec<Arc<Object>>,
    memo: std::sync::OnceLock<Arc<dyn std::any::Any + Send + Sync>>,
}

/// A copy is a list of its own: nothing worked out comes with it.
impl Clone for List {
    fn clone(&self) -> List {
        List {
            items: self.items.clone(),
            memo: std::sync::OnceLock::new(),
        }
    }
}

impl std::fmt::Debug for List {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        self.items.fmt(f)
    }
}

impl Objects {
    /// Whether both are the one same list (so equal without a look).
    pub fn same_list(&self, other: &Objects) -> bool {
        Arc::ptr_eq(&self.0, &other.0)
    }

    /// What `make` works out of the objects, made once for this list and
    /// kept with it (shared by its copies) until it changes. One kind of
    /// thing is kept (the render's: `T`); another is made each time.
    pub fn memo<T: Send + Sync + 'static>(&self, make: impl FnOnce(&[Arc<Object>]) -> T) -> Arc<T> {
        if let Some(kept) = self.0.memo.get() {
            if let Ok(kept) = Arc::clone(kept).downcast::<T>() {
                return kept;
            }
            return Arc::new(make(&self.0.items));
        }
        let made = Arc::new(make(&self.0.items));
        let _ = self
            .0
            .memo
            .set(Arc::clone(&made) as Arc<dyn std::any::Any + Send + Sync>);
        made
    }

    /// The list as this copy's own to change: copied where shared, what
    /// was worked out of it dropped.
    fn own(&mut self) -> &mut Vec<Arc<Object>> {
        let list = Arc::make_mut(&mut self.0);
        list.memo = std::sync::OnceLock::new();
        &mut list.items
    }
}

impl std::ops::Deref for Objects {
    type Target = Vec<Arc<Object>>;
    fn deref(&self) -> &Vec<Arc<Object>> {
        &self.0.items
    }
}

impl std::ops::DerefMut for Objects {
    fn deref_mut(&mut self) -> &mut Vec<Arc<Object>> {
        self.own()
    }
}

impl From<Vec<Arc<Object>>> for Objects {
    fn from(items: Vec<Arc<Object>>) -> Objects {
        Objects(Arc::new(List {
            items,
            memo: std::sync::OnceLock::new(),
        }))
    }
}

impl FromIterator<Arc<Object>> for Objects {
    fn from_iter<I: IntoIterator<Item = Arc<Object>>>(iter: I) -> Objects {
        Objects::from(iter.into_iter().collect::<Vec<_>>())
    }
}

impl<'a> IntoIterator for &'a Objects {
    type Item = &'a Arc<Object>;
    type IntoIter = std::slice::Iter<'a, Arc<Object>>;
    fn into_iter(self) -> Self::IntoIter {
        self.0.items.iter()
    }
}

impl<'a> IntoIterator for &'a mut Objects {
    type Item = &'a mut Arc<Object>;
    type IntoIter = std::slice::IterMut<'a, Arc<Object>>;
    fn into_iter(self) -> Self::IntoIter {
        self.own().iter_mut()
    }
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
        (self.objects.same_list(&other.objects)
            || self.objects.len() == other.objects.len()
                && self
                    .objects
                    .iter()
                    .zip(&other.objects)
                    .all(|(a, b)| Arc::ptr_eq(a, b) || a == b))
            && self.lights == other.lights
            && self.model == other.model
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_copy_shares_the_list_until_one_changes_it_and_then_only_the_list() {
        let scene = parse(crate::EXAMPLE_SCENE, std::path::Path::new("example.xml")).unwrap();
        let mut copy = scene.clone();
        assert!(copy.objects.same_list(&scene.objects));
        assert!(copy.same_but_camera(&scene));

        // Changing one object gives the copy its own list, and its own
        // copy of that object; every other object is still the scene's.
        Arc::make_mut(&mut copy.objects[1]).material.ka = 0.75;
        assert!(!copy.objects.same_list(&scene.objects));
        assert!(!Arc::ptr_eq(&copy.objects[1], &scene.objects[1]));
        assert!(
            (0..scene.objects.len())
                .filter(|&n| n != 1)
                .all(|n| Arc::ptr_eq(&copy.objects[n], &scene.objects[n]))
        );
        assert_eq!(scene.objects[1].material.ka, 0.4);
        assert!(!copy.same_but_camera(&scene));

        // A list that is not shared is changed where it is.
        let mut own = copy.clone();
        drop(copy);
        let before = own.objects.as_ptr();
        own.objects.pop();
        assert_eq!(own.objects.as_ptr(), before);
    }

    /// What is worked out of a list is made once, kept by its copies, and
    /// made again once the list changes.
    #[test]
    fn a_memo_lives_as_long_as_its_list_is_unchanged() {
        use std::sync::atomic::{AtomicUsize, Ordering};
        let scene = parse(crate::EXAMPLE_SCENE, std::path::Path::new("example.xml")).unwrap();
        let made = AtomicUsize::new(0);
        let count = |objects: &[Arc<Object>]| {
            made.fetch_add(1, Ordering::Relaxed);
            objects.len()
        };
        let n = scene.objects.len();
        assert_eq!(*scene.objects.memo(count), n);
        let mut copy = scene.clone();
        assert_eq!(*copy.objects.memo(count), n);
        assert_eq!(made.load(Ordering::Relaxed), 1);
        copy.objects.pop();
        assert_eq!(*copy.objects.memo(count), n - 1);
        assert_eq!(*scene.objects.memo(count), n);
        assert_eq!(made.load(Ordering::Relaxed), 2);
    }
}
