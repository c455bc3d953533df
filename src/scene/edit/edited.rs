//! The edited scene: a [`Scene`] together with where each of its objects,
//! lights and transformation steps came from in the text it was loaded
//! from (its *origin*), and [`Edited::apply`], the one place an [`Edit`]
//! changes it, with the loader's rules, returning the [`Undo`].

use super::path::{Kind, light_of, object_of, step_attr, step_of, transform_of, wrong_attr};
use super::{
    Edit, EditError, Element, Field, Item, Owner, StepAttr, Value, number_text, path_error,
    value_error,
};
use crate::math::{Transform, TransformError, TransformStep};
use crate::scene::{Camera, MAX_LIGHTS, MAX_OBJECTS, MAX_PIXELS, Object, Scene};
use crate::shading::{Light, Model};
use std::borrow::Cow;
use std::sync::Arc;

fn set_step_attr(step: &mut TransformStep, attr: StepAttr, value: f64) {
    use TransformStep as S;
    match (step, attr) {
        (S::Translate(v) | S::Scale(v), a) => {
            if let Some(axis) = a.axis() {
                *axis.slot(v) = value;
            }
        }
        (S::RotateX(a) | S::RotateY(a) | S::RotateZ(a), StepAttr::Angle) => *a = value,
        (S::UniformScale(f), StepAttr::Factor) => *f = value,
        _ => {}
    }
}

/// Where an object came from: its index among the text's objects and the
/// origins of its transformation steps.
#[derive(Debug, Clone, PartialEq, Eq)]
pub(crate) struct ObjectOrigin {
    pub(crate) index: usize,
    pub(crate) steps: Vec<Option<usize>>,
}

/// Where an object came from, as [`Edited::origin_of`] tells it: its
/// index among the text's objects and the origins of its steps.
#[derive(Debug, Clone, PartialEq, Eq)]
pub(crate) struct OriginOf<'a> {
    pub(crate) index: usize,
    pub(crate) steps: Cow<'a, [Option<usize>]>,
}

/// The origins of an element's own steps as loaded: `Some(0), Some(1), …`
/// (borrowed for the usual few steps).
fn own_steps(len: usize) -> Cow<'static, [Option<usize>]> {
    const OWN: [Option<usize>; 16] = {
        let mut own = [None; 16];
        let mut k = 0;
        while k < own.len() {
            own[k] = Some(k);
            k += 1;
        }
        own
    };
    match OWN.get(..len) {
        Some(own) => Cow::Borrowed(own),
        None => Cow::Owned((0..len).map(Some).collect()),
    }
}

/// Where each object of an [`Edited`] came from.
#[derive(Debug, Clone, Default)]
pub(crate) struct ObjectOrigins(
    /// `None` while every object is the text's object of its own number
    /// with its own steps (as loaded, and after edits of values only): a
    /// million objects need no list of a million origins (80 MB) until
    /// an edit adds, removes or moves an object or a step. The list is
    /// shared between copies until one changes it.
    Option<Arc<Vec<Option<ObjectOrigin>>>>,
);

/// A scene and, for each of its elements, where it came from in the text
/// it was loaded from (`None`: added since).
#[derive(Debug, Clone)]
pub struct Edited {
    scene: Scene,
    objects: ObjectOrigins,
    pub(crate) lights: Vec<Option<usize>>,
    pub(crate) camera_steps: Vec<Option<usize>>,
}

impl PartialEq for Edited {
    /// The same scene with the same origins, however they are held.
    fn eq(&self, other: &Edited) -> bool {
        self.scene == other.scene
            && self.lights == other.lights
            && self.camera_steps == other.camera_steps
            && match (&self.objects.0, &other.objects.0) {
                (None, None) => true,
                (Some(a), Some(b)) if Arc::ptr_eq(a, b) => true,
                _ => (0..self.scene.objects.len()).all(|n| self.origin_of(n) == other.origin_of(n)),
            }
    }
}

/// What undoes an applied edit: the inverse edit, and the origin the
/// element it brings back had, so that save-back finds its text again.
#[derive(Debug, Clone, PartialEq)]
pub struct Undo {
    edit: Edit,
    restore: Restore,
}

#[derive(Debug, Clone, PartialEq)]
enum Restore {
    Nothing,
    Object(Option<ObjectOrigin>),
    Light(Option<usize>),
    Step(Option<usize>),
    /// The origins of a transformation's steps.
    Steps(Vec<Option<usize>>),
}

impl Undo {
    /// The inverse edit.
    pub fn edit(&self) -> &Edit {
        &self.edit
    }
}

impl Edited {
    /// Whether this is `scene` as just loaded (`*self ==
    /// Edited::new(scene.clone())`, without the copy).
    pub fn is_as_loaded(&self, scene: &Scene) -> bool {
        let own = |origins: &[Option<usize>], len: usize| *origins == *own_steps(len);
        self.scene == *scene
            && (0..scene.objects.len()).all(|n| {
                self.origin_of(n).is_some_and(|o| {
                    o.index == n && o.steps == own_steps(scene.objects[n].transform.steps().len())
                })
            })
            && own(&self.lights, scene.lights.len())
            && own(&self.camera_steps, scene.camera.transform.steps().len())
    }

    /// A scene just loaded from a text: every element is its own origin.
    pub fn new(scene: Scene) -> Edited {
        let lights = (0..scene.lights.len()).map(Some).collect();
        let camera_steps = own_steps(scene.camera.transform.steps().len()).into_owned();
        Edited {
            scene,
            objects: ObjectOrigins::default(),
            lights,
            camera_steps,
        }
    }

    pub fn scene(&self) -> &Scene {
        &self.scene
    }

    /// Every object is the loaded text's object of its own number, with
    /// its own steps: only values were edited (a save may then pass over
    /// the unchanged objects' places).
    pub(crate) fn objects_in_place(&self) -> bool {
        self.objects.0.is_none()
    }

    /// The index, among the loaded text's objects, that object `n` came
    /// from; `None` for an object added since.
    pub fn object_origin(&self, n: usize) -> Option<usize> {
        match &self.objects.0 {
            None => (n < self.scene.objects.len()).then_some(n),
            Some(list) => list.get(n)?.as_ref().map(|o| o.index),
        }
    }

    /// The index, among the loaded text's lights, that light `n` came from.
    pub fn light_origin(&self, n: usize) -> Option<usize> {
        *self.lights.get(n)?
    }

    /// Where object `n` came from: its index among the loaded text's
    /// objects and its steps' origins; `None` for an object added since.
    pub(crate) fn origin_of(&self, n: usize) -> Option<OriginOf<'_>> {
        match &self.objects.0 {
            None => self.scene.objects.get(n).map(|o| OriginOf {
                index: n,
                steps: own_steps(o.transform.steps().len()),
            }),
            Some(list) => list.get(n)?.as_ref().map(|o| OriginOf {
                index: o.index,
                steps: Cow::Borrowed(&o.steps),
            }),
        }
    }

    /// The list of the objects' origins, made from the scene as it is now
    /// if it was not held yet: before an edit that adds, removes or moves
    /// an object or a step.
    fn object_origins_mut(&mut self) -> &mut Vec<Option<ObjectOrigin>> {
        let scene = &self.scene;
        let list = self.objects.0.get_or_insert_with(|| {
            Arc::new(
                scene
                    .objects
                    .iter()
                    .enumerate()
                    .map(|(index, o)| {
                        Some(ObjectOrigin {
                            index,
                            steps: own_steps(o.transform.steps().len()).into_owned(),
                        })
                    })
                    .collect(),
            )
        });
        Arc::make_mut(list)
    }

    /// Sets the origins of every object (tools that pair elements up by
    /// their place, [`super::super::splice::rewrite_by_index`]).
    pub(crate) fn set_object_origins(&mut self, origins: Vec<Option<ObjectOrigin>>) {
        self.objects.0 = Some(Arc::new(origins));
    }

    /// Applies `edit` if the result is a valid scene, and returns what undoes
    /// it; on an error nothing changes.
    pub fn apply(&mut self, edit: &Edit) -> Result<Undo, EditError> {
        self.apply_restoring(edit, Restore::Nothing)
    }

    /// Applies an [`Undo`] (or a redo: undoing returns the redo) and returns
    /// what undoes that in turn.
    pub fn undo(&mut self, undo: Undo) -> Result<Undo, EditError> {
        self.apply_restoring(&undo.edit, undo.restore)
    }

    fn apply_restoring(&mut self, edit: &Edit, restore: Restore) -> Result<Undo, EditError> {
        // An edit that adds, removes or moves objects or their steps needs
        // the list of the objects' origins, made before anything changes.
        if let Edit::Insert(Item::Object(_) | Item::Step(Owner::Object(_), _), _)
        | Edit::Remove(Item::Object(_) | Item::Step(Owner::Object(_), _))
        | Edit::Transform(Owner::Object(_), _) = edit
        {
            self.object_origins_mut();
        }
        match edit {
            Edit::Set(field, value) => {
                let old = field.get(&self.scene)?;
                self.set(*field, *value)?;
                Ok(Undo {
                    edit: Edit::Set(*field, old),
                    restore: Restore::Nothing,
                })
            }
            Edit::Insert(item, element) => self.insert(*item, element, restore),
            Edit::Remove(item) => self.remove(*item),
            Edit::Transform(owner, steps) => {
                let path = format!("{owner}.transformation");
                let transform = Transform::from_steps(steps.clone())
                    .map_err(|e| value_error(&path, refused(e)))?;
                let old_steps = transform_of(&self.scene, *owner)?.steps().to_vec();
                let old_origins = self.step_origins_mut(*owner).map(|o| o.clone());
                if let Some(origins) = self.step_origins_mut(*owner) {
                    *origins = match restore {
                        Restore::Steps(restored) if restored.len() == steps.len() => restored,
                        // Steps of the same kind at the same place keep
                        // their origin: the move changed their values.
                        _ => steps
                            .iter()
                            .enumerate()
                            .map(|(k, s)| {
                                old_steps
                                    .get(k)
                                    .filter(|o| {
                                        std::mem::discriminant(*o) == std::mem::discriminant(s)
                                    })
                                    .and_then(|_| origins.get(k).copied().flatten())
                            })
                            .collect(),
                    };
                }
                *transform_mut(&mut self.scene, *owner)? = transform;
                Ok(Undo {
                    edit: Edit::Transform(*owner, old_steps),
                    restore: old_origins.map_or(Restore::Nothing, Restore::Steps),
                })
            }
        }
    }

    fn set(&mut self, field: Field, value: Value) -> Result<(), EditError> {
        let scene = &mut self.scene;
        let number = |value: Value| match value {
            Value::Number(v) if v.is_finite() => Ok(v),
            Value::Number(v) => Err(value_error(
                field,
                format!("must be a finite number, got {v}"),
            )),
            other => Err(value_error(field, format!("must be a number, got {other}"))),
        };
        let at_least_zero = |value: Value| {
            let v = number(value)?;
            if v >= 0.0 {
                Ok(v)
            } else {
                Err(value_error(
                    field,
                    format!("must be >= 0, got {}", number_text(v)),
                ))
            }
        };
        let integer = |value: Value| match (value, field.kind()) {
            (Value::Integer(v), Kind::Integer { min, max }) if (min..=max).contains(&v) => Ok(v),
            (_, Kind::Integer { min, max }) => Err(value_error(
                field,
                format!("must be a whole number from {min} to {max}, got {value}"),
            )),
            _ => Err(value_error(field, "not a whole-number field")),
        };
        match field {
            Field::ModelType => match value {
                Value::Model(m) => scene.model.illumination = m,
                other => {
                    return Err(value_error(
                        field,
                        format!("must be a model name, got {other}"),
                    ));
                }
            },
            Field::ModelDepth => {
                scene.model.depth = u32::try_from(integer(value)?).unwrap_or(Model::MAX_DEPTH);
            }
            Field::CameraWidth | Field::CameraHeight => {
                let v = integer(value)?;
                let camera: &mut Camera = &mut scene.camera;
                let (w, h) = if field == Field::CameraWidth {
                    (v, u64::from(camera.height))
                } else {
                    (u64::from(camera.width), v)
                };
                if w.saturating_mul(h) > MAX_PIXELS {
                    return Err(value_error(
                        field,
                        format!("a {w}x{h} image has more than the limit of {MAX_PIXELS} pixels"),
                    ));
                }
                let v = u32::try_from(v).map_err(|_| value_error(field, "too large"))?;
                if field == Field::CameraWidth {
                    camera.width = v;
                } else {
                    camera.height = v;
                }
            }
            Field::CameraEyeDistance => {
                let v = number(value)?;
                if v <= 0.0 {
                    return Err(value_error(
                        field,
                        format!("must be > 0, got {}", number_text(v)),
                    ));
                }
                scene.camera.eye_distance = v;
            }
            Field::Step { owner, step, attr } => {
                let v = number(value)?;
                let transform = transform_of(scene, owner)?;
                let mut steps = transform.steps().to_vec();
                let s = step_of(scene, owner, step)?;
                if step_attr(s, attr).is_none() {
                    return Err(wrong_attr(field, s));
                }
                if let Some(s) = steps.get_mut(step) {
                    set_step_attr(s, attr, v);
                }
                let t = Transform::from_steps(steps).map_err(|e| value_error(field, refused(e)))?;
                *transform_mut(scene, owner)? = t;
            }
            Field::Color { object, channel } => {
                let v = at_least_zero(value)?;
                let o = object_mut(scene, object)?;
                *channel.axis().slot(&mut o.color) = v;
            }
            Field::Material { object, coef } => {
                let v = at_least_zero(value)?;
                let o = object_mut(scene, object)?;
                *coef.slot(&mut o.material) = v;
            }
            Field::LightPosition { light, axis } => {
                let v = number(value)?;
                let l = light_mut(scene, light)?;
                *axis.slot(&mut l.position) = v;
            }
            Field::LightColor { light, channel } => {
                let v = at_least_zero(value)?;
                let l = light_mut(scene, light)?;
                *channel.axis().slot(&mut l.color) = v;
            }
        }
        Ok(())
    }

    fn insert(
        &mut self,
        item: Item,
        element: &Element,
        restore: Restore,
    ) -> Result<Undo, EditError> {
        let past_end = |len: usize, what: &str| {
            path_error(
                item,
                format!("can insert at most one past the last {what} ({})", len + 1),
            )
        };
        match (item, element) {
            (Item::Object(n), Element::Object(object)) => {
                let len = self.scene.objects.len();
                if n > len {
                    return Err(past_end(len, "object"));
                }
                if len >= MAX_OBJECTS {
                    return Err(path_error(
                        item,
                        format!("the scene has the most objects allowed ({MAX_OBJECTS})"),
                    ));
                }
                check_object(item, object)?;
                let origin = match restore {
                    Restore::Object(origin) => origin,
                    _ => None,
                };
                self.scene
                    .objects
                    .insert(n, Arc::new(object.as_ref().clone()));
                self.object_origins_mut().insert(
                    n,
                    origin.filter(|o| o.steps.len() == object.transform.steps().len()),
                );
            }
            (Item::Light(n), Element::Light(light)) => {
                let len = self.scene.lights.len();
                if n > len {
                    return Err(past_end(len, "light"));
                }
                if len >= MAX_LIGHTS {
                    return Err(path_error(
                        item,
                        format!("the scene has the most lights allowed ({MAX_LIGHTS})"),
                    ));
                }
                check_light(item, light)?;
                let origin = match restore {
                    Restore::Light(origin) => origin,
                    _ => None,
                };
                self.scene.lights.insert(n, *light);
                self.lights.insert(n, origin);
            }
            (Item::Step(owner, k), Element::Step(step)) => {
                let mut steps = transform_of(&self.scene, owner)?.steps().to_vec();
                if k > steps.len() {
                    return Err(past_end(steps.len(), "step"));
                }
                steps.insert(k, *step);
                let t = Transform::from_steps(steps).map_err(|e| value_error(item, refused(e)))?;
                *transform_mut(&mut self.scene, owner)? = t;
                let origin = match restore {
                    Restore::Step(origin) => origin,
                    _ => None,
                };
                if let Some(origins) = self.step_origins_mut(owner) {
                    origins.insert(k.min(origins.len()), origin);
                }
            }
            _ => {
                return Err(path_error(item, "the element inserted is not of this kind"));
            }
        }
        Ok(Undo {
            edit: Edit::Remove(item),
            restore: Restore::Nothing,
        })
    }

    fn remove(&mut self, item: Item) -> Result<Undo, EditError> {
        let (element, restore) = match item {
            Item::Object(n) => {
                object_of(&self.scene, n)?;
                let object = self.scene.objects.remove(n);
                let origin = take(self.object_origins_mut(), n);
                (
                    Element::Object(Box::new(Arc::unwrap_or_clone(object))),
                    Restore::Object(origin),
                )
            }
            Item::Light(n) => {
                light_of(&self.scene, n)?;
                let light = self.scene.lights.remove(n);
                let origin = take(&mut self.lights, n);
                (Element::Light(light), Restore::Light(origin))
            }
            Item::Step(owner, k) => {
                let step = *step_of(&self.scene, owner, k)?;
                let mut steps = transform_of(&self.scene, owner)?.steps().to_vec();
                steps.remove(k);
                // Removing a step can make the rest overflow (a scale of
                // 1e300 that another step undid).
                let t = Transform::from_steps(steps).map_err(|e| value_error(item, refused(e)))?;
                *transform_mut(&mut self.scene, owner)? = t;
                let origin = self.step_origins_mut(owner).and_then(|o| take(o, k));
                (Element::Step(step), Restore::Step(origin))
            }
        };
        Ok(Undo {
            edit: Edit::Insert(item, element),
            restore,
        })
    }

    fn step_origins_mut(&mut self, owner: Owner) -> Option<&mut Vec<Option<usize>>> {
        match owner {
            Owner::Camera => Some(&mut self.camera_steps),
            Owner::Object(n) => match self.object_origins_mut().get_mut(n)? {
                Some(origin) => Some(&mut origin.steps),
                None => None,
            },
        }
    }
}

/// Removes entry `n` of `v` (if there) and returns its content.
fn take<T>(v: &mut Vec<Option<T>>, n: usize) -> Option<T> {
    if n < v.len() { v.remove(n) } else { None }
}

/// Why an edit's steps make no transformation.
fn refused(e: TransformError) -> &'static str {
    match e {
        TransformError::Singular { .. } => "the transformation would be singular (a zero scale)",
        TransformError::Overflow { .. } => {
            "the composed transformation would overflow (its matrix or its inverse not finite)"
        }
    }
}

fn object_mut(scene: &mut Scene, n: usize) -> Result<&mut Object, EditError> {
    object_of(scene, n)?;
    scene
        .objects
        .get_mut(n)
        .map(Arc::make_mut)
        .ok_or_else(|| path_error(Item::Object(n), "no such object"))
}

fn light_mut(scene: &mut Scene, n: usize) -> Result<&mut Light, EditError> {
    light_of(scene, n)?;
    scene
        .lights
        .get_mut(n)
        .ok_or_else(|| path_error(Item::Light(n), "no such light"))
}

fn transform_mut(scene: &mut Scene, owner: Owner) -> Result<&mut Transform, EditError> {
    match owner {
        Owner::Camera => Ok(&mut scene.camera.transform),
        Owner::Object(n) => Ok(&mut object_mut(scene, n)?.transform),
    }
}

/// An inserted object must hold values the loader accepts.
fn check_object(item: Item, o: &Object) -> Result<(), EditError> {
    let m = o.material;
    let values = [o.color.x, o.color.y, o.color.z, m.ka, m.kd, m.ks, m.m];
    if values.iter().all(|v| v.is_finite() && *v >= 0.0) {
        Ok(())
    } else {
        Err(value_error(
            item,
            "colour and material values must be finite and >= 0",
        ))
    }
}

fn check_light(item: Item, l: &Light) -> Result<(), EditError> {
    let ok = l.position.is_finite() && l.color.is_finite() && l.color.min_element() >= 0.0;
    if ok {
        Ok(())
    } else {
        Err(value_error(
            item,
            "position must be finite and colour finite and >= 0",
        ))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::scene::edit::{Field, Value};

    fn example() -> Edited {
        let text = crate::scene::generated::spheres_on_floor(20, 8, 6);
        Edited::new(crate::scene::parse(&text, std::path::Path::new("s.xml")).unwrap())
    }

    #[test]
    fn edits_of_values_make_no_list_of_origins() {
        let original = example();
        let mut e = original.clone();
        for path in ["object[3].material.ka", "object[2].transformation[2].x"] {
            e.apply(&Edit::Set(Field::parse(path).unwrap(), Value::Number(0.25)))
                .unwrap();
        }
        assert!(e.objects.0.is_none(), "values only: no list");
        assert_eq!(e.object_origin(4), Some(4));
        let steps = e.scene().objects[2].transform.steps().len();
        assert_eq!(
            e.origin_of(2).map(|o| o.steps.into_owned()),
            Some((0..steps).map(Some).collect())
        );
        assert!(!e.is_as_loaded(original.scene()));

        // Removing an object makes the list, from the scene before it.
        let undo = e.apply(&Edit::Remove(Item::Object(1))).unwrap();
        assert!(e.objects.0.is_some());
        assert_eq!(e.object_origin(1), Some(2));
        e.undo(undo).unwrap();
        assert_eq!(e.object_origin(1), Some(1));
        // Equal to a copy that never made it: the same origins.
        let mut values_only = original.clone();
        for path in ["object[3].material.ka", "object[2].transformation[2].x"] {
            values_only
                .apply(&Edit::Set(Field::parse(path).unwrap(), Value::Number(0.25)))
                .unwrap();
        }
        assert_eq!(e, values_only);
        assert_ne!(e, original);

        // A step added to an object: its origins from before the step.
        let mut s = original.clone();
        let add = Edit::add_step(
            s.scene(),
            Owner::Object(0),
            TransformStep::UniformScale(2.0),
        )
        .unwrap();
        s.apply(&add).unwrap();
        let steps = original.scene().objects[0].transform.steps().len();
        let mut expected: Vec<_> = (0..steps).map(Some).collect();
        expected.push(None);
        assert_eq!(s.origin_of(0).unwrap().steps.into_owned(), expected);
        assert_eq!(s.origin_of(1), original.origin_of(1));
    }

    #[test]
    fn own_steps_are_borrowed_for_a_few_and_made_for_more() {
        assert!(matches!(own_steps(2), Cow::Borrowed(&[Some(0), Some(1)])));
        assert_eq!(own_steps(0).len(), 0);
        let many = own_steps(20);
        assert!(matches!(many, Cow::Owned(_)));
        assert_eq!(many[19], Some(19));
    }
}
