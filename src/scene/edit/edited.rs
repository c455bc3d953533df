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

/// A scene and, for each of its elements, where it came from in the text
/// it was loaded from (`None`: added since).
#[derive(Debug, Clone, PartialEq)]
pub struct Edited {
    scene: Scene,
    /// Shared between copies until one changes them (a million objects
    /// have a million origins; changing a value changes none).
    pub(crate) objects: Arc<Vec<Option<ObjectOrigin>>>,
    pub(crate) lights: Vec<Option<usize>>,
    pub(crate) camera_steps: Vec<Option<usize>>,
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
        let own = |origins: &[Option<usize>], len: usize| {
            origins.len() == len && origins.iter().enumerate().all(|(k, o)| *o == Some(k))
        };
        self.scene == *scene
            && self.objects.len() == scene.objects.len()
            && self
                .objects
                .iter()
                .zip(&scene.objects)
                .enumerate()
                .all(|(index, (o, object))| {
                    o.as_ref().is_some_and(|o| {
                        o.index == index && own(&o.steps, object.transform.steps().len())
                    })
                })
            && own(&self.lights, scene.lights.len())
            && own(&self.camera_steps, scene.camera.transform.steps().len())
    }

    /// A scene just loaded from a text: every element is its own origin.
    pub fn new(scene: Scene) -> Edited {
        let objects = scene
            .objects
            .iter()
            .enumerate()
            .map(|(index, o)| {
                Some(ObjectOrigin {
                    index,
                    steps: (0..o.transform.steps().len()).map(Some).collect(),
                })
            })
            .collect();
        let lights = (0..scene.lights.len()).map(Some).collect();
        let camera_steps = (0..scene.camera.transform.steps().len())
            .map(Some)
            .collect();
        Edited {
            scene,
            objects: Arc::new(objects),
            lights,
            camera_steps,
        }
    }

    pub fn scene(&self) -> &Scene {
        &self.scene
    }

    /// The index, among the loaded text's objects, that object `n` came
    /// from; `None` for an object added since.
    pub fn object_origin(&self, n: usize) -> Option<usize> {
        self.objects.get(n)?.as_ref().map(|o| o.index)
    }

    /// The index, among the loaded text's lights, that light `n` came from.
    pub fn light_origin(&self, n: usize) -> Option<usize> {
        *self.lights.get(n)?
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
                Arc::make_mut(&mut self.objects).insert(
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
                let origin = take(Arc::make_mut(&mut self.objects), n);
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
            Owner::Object(n) => match Arc::make_mut(&mut self.objects).get_mut(n)? {
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
