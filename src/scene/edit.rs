//! The edit engine: every change to a scene is an [`Edit`] value, applied in
//! one place ([`Edited::apply`]) with the loader's rules, and undone by the
//! [`Undo`] that applying it returns.
//!
//! The app's panel, its keys and its undo stack, `rayoflight edit` and the
//! render's `--set` all produce and apply these same values, so a value can
//! only change through here and can never become one the loader refuses.
//!
//! Fields and elements are named by paths that count from 1 in file order,
//! as the panel numbers them: `object[2].material.ka`, `light[1].x`,
//! `camera.transformation[1].angle`, `model.type` ([`Field`], [`Item`]).
//!
//! [`Edited`] is a scene together with where each of its objects, lights
//! and transformation steps came from in the text it was loaded from (its
//! *origin*, or none for an element added since). Save-back
//! ([`super::splice`]) writes the edits into that text by these origins,
//! never by matching elements up again.

use std::fmt;
use std::sync::Arc;

use super::load::{MAX_SIDE, NumberError, parse_integer, parse_number};
use super::{Camera, MAX_LIGHTS, MAX_OBJECTS, MAX_PIXELS, Object, Scene, Shape};
use crate::math::{Transform, TransformError, TransformStep, Vec3};
use crate::shading::{Illumination, Light, Material, Model};

/// Why an edit, or a save of edits, could not be done.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum EditError {
    /// A path that does not parse or names nothing in this scene
    /// (`object[5]: the scene has 3 objects`).
    #[error("{path}: {message}")]
    Path { path: String, message: String },
    /// A value the loader would refuse (`object[1].material.ka: must be >= 0,
    /// got -1`).
    #[error("{path}: {message}")]
    Value { path: String, message: String },
    /// The source text is not a valid scene.
    #[error("the scene text does not load: {0}")]
    Parse(Box<super::LoadError>),
    /// The edited text would not load (a bug: every value was checked).
    #[error("the edited scene cannot be saved: {0}")]
    Invalid(Box<super::LoadError>),
    /// Something the editor did not expect (a bug).
    #[error("cannot write the edited scene back into its text: {0}")]
    Internal(String),
}

fn path_error(path: impl fmt::Display, message: impl Into<String>) -> EditError {
    EditError::Path {
        path: path.to_string(),
        message: message.into(),
    }
}

fn value_error(path: impl fmt::Display, message: impl Into<String>) -> EditError {
    EditError::Value {
        path: path.to_string(),
        message: message.into(),
    }
}

// ----- paths -----

/// A coordinate of a position, translation or scale.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum Axis {
    X,
    Y,
    Z,
}

/// A component of a colour.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum Channel {
    Red,
    Green,
    Blue,
}

/// A material coefficient.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum Coef {
    Ka,
    Kd,
    Ks,
    M,
}

/// An attribute of a transformation step.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum StepAttr {
    X,
    Y,
    Z,
    Angle,
    Factor,
}

/// Whose `<transformation>`.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum Owner {
    Camera,
    /// Object index from 0.
    Object(usize),
}

/// One value of the scene. Indices count from 0 here and from 1 in paths.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum Field {
    ModelType,
    ModelDepth,
    CameraWidth,
    CameraHeight,
    CameraEyeDistance,
    Step {
        owner: Owner,
        step: usize,
        attr: StepAttr,
    },
    Color {
        object: usize,
        channel: Channel,
    },
    Material {
        object: usize,
        coef: Coef,
    },
    LightPosition {
        light: usize,
        axis: Axis,
    },
    LightColor {
        light: usize,
        channel: Channel,
    },
}

/// An element that can be added or removed. Indices count from 0.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum Item {
    /// A sphere or plane: objects count spheres and planes together.
    Object(usize),
    Light(usize),
    /// A step of a transformation.
    Step(Owner, usize),
}

/// A value as a field holds it.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Value {
    Number(f64),
    /// `camera.width`, `camera.height`, `model.depth`.
    Integer(u64),
    Model(Illumination),
}

/// The contents of an element being inserted.
#[derive(Debug, Clone, PartialEq)]
pub enum Element {
    Object(Box<Object>),
    Light(Light),
    Step(TransformStep),
}

/// One change to a scene.
#[derive(Debug, Clone, PartialEq)]
pub enum Edit {
    /// Set one value.
    Set(Field, Value),
    /// Insert an element at `Item`'s index (its length appends).
    Insert(Item, Element),
    /// Remove an element.
    Remove(Item),
    /// Replace the camera's or an object's whole transformation (the
    /// viewport's edits: moving the camera, moving an object).
    Transform(Owner, Vec<TransformStep>),
}

const AXES: [(Axis, &str); 3] = [(Axis::X, "x"), (Axis::Y, "y"), (Axis::Z, "z")];
const CHANNELS: [(Channel, &str); 3] = [
    (Channel::Red, "red"),
    (Channel::Green, "green"),
    (Channel::Blue, "blue"),
];
const COEFS: [(Coef, &str); 4] = [
    (Coef::Ka, "ka"),
    (Coef::Kd, "kd"),
    (Coef::Ks, "ks"),
    (Coef::M, "m"),
];
const STEP_ATTRS: [(StepAttr, &str); 5] = [
    (StepAttr::X, "x"),
    (StepAttr::Y, "y"),
    (StepAttr::Z, "z"),
    (StepAttr::Angle, "angle"),
    (StepAttr::Factor, "factor"),
];

fn name_of<T: PartialEq + Copy>(table: &[(T, &'static str)], value: T) -> &'static str {
    table
        .iter()
        .find(|(v, _)| *v == value)
        .map_or("?", |(_, n)| n)
}

fn from_name<T: Copy>(table: &[(T, &'static str)], name: &str) -> Option<T> {
    table.iter().find(|(_, n)| *n == name).map(|(v, _)| *v)
}

impl Axis {
    pub fn name(self) -> &'static str {
        name_of(&AXES, self)
    }
    pub(crate) fn of(self, v: Vec3) -> f64 {
        match self {
            Axis::X => v.x,
            Axis::Y => v.y,
            Axis::Z => v.z,
        }
    }
    fn slot(self, v: &mut Vec3) -> &mut f64 {
        match self {
            Axis::X => &mut v.x,
            Axis::Y => &mut v.y,
            Axis::Z => &mut v.z,
        }
    }
}

impl Channel {
    pub fn name(self) -> &'static str {
        name_of(&CHANNELS, self)
    }
    pub(crate) fn axis(self) -> Axis {
        match self {
            Channel::Red => Axis::X,
            Channel::Green => Axis::Y,
            Channel::Blue => Axis::Z,
        }
    }
}

impl Coef {
    pub fn name(self) -> &'static str {
        name_of(&COEFS, self)
    }
    fn slot(self, m: &mut Material) -> &mut f64 {
        match self {
            Coef::Ka => &mut m.ka,
            Coef::Kd => &mut m.kd,
            Coef::Ks => &mut m.ks,
            Coef::M => &mut m.m,
        }
    }
}

impl StepAttr {
    pub fn name(self) -> &'static str {
        name_of(&STEP_ATTRS, self)
    }

    /// The attributes a step of this kind has.
    fn allowed(step: &TransformStep) -> &'static [StepAttr] {
        match step {
            TransformStep::Translate(_) | TransformStep::Scale(_) => {
                &[StepAttr::X, StepAttr::Y, StepAttr::Z]
            }
            TransformStep::RotateX(_) | TransformStep::RotateY(_) | TransformStep::RotateZ(_) => {
                &[StepAttr::Angle]
            }
            TransformStep::UniformScale(_) => &[StepAttr::Factor],
        }
    }

    fn axis(self) -> Option<Axis> {
        match self {
            StepAttr::X => Some(Axis::X),
            StepAttr::Y => Some(Axis::Y),
            StepAttr::Z => Some(Axis::Z),
            StepAttr::Angle | StepAttr::Factor => None,
        }
    }
}

/// The element name of a step (`translate`, `rotate-x`, `scale`, ...).
pub fn step_name(step: &TransformStep) -> &'static str {
    match step {
        TransformStep::Translate(_) => "translate",
        TransformStep::RotateX(_) => "rotate-x",
        TransformStep::RotateY(_) => "rotate-y",
        TransformStep::RotateZ(_) => "rotate-z",
        TransformStep::UniformScale(_) | TransformStep::Scale(_) => "scale",
    }
}

impl fmt::Display for Owner {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Owner::Camera => write!(f, "camera"),
            Owner::Object(n) => write!(f, "object[{}]", n + 1),
        }
    }
}

impl fmt::Display for Item {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Item::Object(n) => write!(f, "object[{}]", n + 1),
            Item::Light(n) => write!(f, "light[{}]", n + 1),
            Item::Step(owner, k) => write!(f, "{owner}.transformation[{}]", k + 1),
        }
    }
}

impl fmt::Display for Field {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match *self {
            Field::ModelType => write!(f, "model.type"),
            Field::ModelDepth => write!(f, "model.depth"),
            Field::CameraWidth => write!(f, "camera.width"),
            Field::CameraHeight => write!(f, "camera.height"),
            Field::CameraEyeDistance => write!(f, "camera.eyeDistance"),
            Field::Step { owner, step, attr } => {
                write!(f, "{}.{}", Item::Step(owner, step), attr.name())
            }
            Field::Color { object, channel } => {
                write!(f, "object[{}].color.{}", object + 1, channel.name())
            }
            Field::Material { object, coef } => {
                write!(f, "object[{}].material.{}", object + 1, coef.name())
            }
            Field::LightPosition { light, axis } => {
                write!(f, "light[{}].{}", light + 1, axis.name())
            }
            Field::LightColor { light, channel } => {
                write!(f, "light[{}].color.{}", light + 1, channel.name())
            }
        }
    }
}

impl fmt::Display for Value {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Value::Number(v) => f.write_str(&number_text(*v)),
            Value::Integer(v) => write!(f, "{v}"),
            Value::Model(m) => f.write_str(m.name()),
        }
    }
}

/// A number as it is written into a scene file: Rust's shortest text that
/// reads back to the same `f64`, in exponent form for magnitudes where the
/// plain form would write many zeros.
pub fn number_text(v: f64) -> String {
    let a = v.abs();
    if a != 0.0 && !(1e-6..1e16).contains(&a) {
        format!("{v:e}")
    } else {
        format!("{v}")
    }
}

/// One `name` or `name[N]` segment of a path; N counts from 1.
struct Segment<'a> {
    name: &'a str,
    index: Option<usize>,
}

fn segments(path: &str) -> Result<Vec<Segment<'_>>, EditError> {
    path.split('.')
        .map(|part| {
            let Some((name, rest)) = part.split_once('[') else {
                if part.is_empty() {
                    return Err(path_error(path, "empty name between dots"));
                }
                return Ok(Segment {
                    name: part,
                    index: None,
                });
            };
            let number = rest
                .strip_suffix(']')
                .ok_or_else(|| path_error(path, format!("'{part}': missing ']'")))?;
            let n = parse_integer(number)
                .filter(|&n| n >= 1 && number.bytes().all(|b| b.is_ascii_digit()))
                .and_then(|n| usize::try_from(n).ok())
                .ok_or_else(|| {
                    path_error(
                        path,
                        format!("'{number}' is not an index: they count from 1"),
                    )
                })?;
            Ok(Segment {
                name,
                index: Some(n - 1),
            })
        })
        .collect()
}

const FIELD_PATHS: &str = "model.type, model.depth, camera.width, camera.height, \
camera.eyeDistance, camera.transformation[K].<x|y|z|angle|factor>, \
object[N].color.<red|green|blue>, object[N].material.<ka|kd|ks|m>, \
object[N].transformation[K].<x|y|z|angle|factor>, light[N].<x|y|z>, \
light[N].color.<red|green|blue>";

const ITEM_PATHS: &str = "object[N], light[N], object[N].transformation[K], \
camera.transformation[K]";

/// The element a path's first segments name: `camera`, `object[N]`,
/// `light[N]`, `model`, maybe followed by `transformation[K]`.
fn owner_of(path: &str, first: &Segment<'_>) -> Result<Option<Owner>, EditError> {
    match (first.name, first.index) {
        ("camera", None) => Ok(Some(Owner::Camera)),
        ("object", Some(n)) => Ok(Some(Owner::Object(n))),
        ("object" | "light", None) => Err(path_error(
            path,
            format!("{} needs an index: {}[N], N from 1", first.name, first.name),
        )),
        _ => Ok(None),
    }
}

impl Field {
    /// Parses a path such as `object[2].material.ka`.
    pub fn parse(path: &str) -> Result<Field, EditError> {
        let s = segments(path)?;
        let unknown = || path_error(path, format!("no such value; paths are {FIELD_PATHS}"));
        let plain = |i: usize| s.get(i).filter(|s| s.index.is_none()).map(|s| s.name);
        let field = match (s.first().map(|s| (s.name, s.index)), s.len()) {
            (Some(_), 3) if s[1].name == "transformation" => {
                let owner = owner_of(path, &s[0])?.ok_or_else(unknown)?;
                let step = match (s[1].name, s[1].index) {
                    ("transformation", Some(k)) => k,
                    _ => return Err(unknown()),
                };
                let attr = plain(2)
                    .and_then(|n| from_name(&STEP_ATTRS, n))
                    .ok_or_else(unknown)?;
                Field::Step { owner, step, attr }
            }
            (Some(("model", None)), 2) => match plain(1) {
                Some("type") => Field::ModelType,
                Some("depth") => Field::ModelDepth,
                _ => return Err(unknown()),
            },
            (Some(("camera", None)), 2) => match plain(1) {
                Some("width") => Field::CameraWidth,
                Some("height") => Field::CameraHeight,
                Some("eyeDistance") => Field::CameraEyeDistance,
                _ => return Err(unknown()),
            },
            (Some(("light", Some(light))), 2) => {
                let axis = plain(1).and_then(|n| from_name(&AXES, n));
                Field::LightPosition {
                    light,
                    axis: axis.ok_or_else(unknown)?,
                }
            }
            (Some(("light", Some(light))), 3) if plain(1) == Some("color") => {
                let channel = plain(2).and_then(|n| from_name(&CHANNELS, n));
                Field::LightColor {
                    light,
                    channel: channel.ok_or_else(unknown)?,
                }
            }
            (Some(("object", Some(object))), 3) => match plain(1) {
                Some("color") => Field::Color {
                    object,
                    channel: plain(2)
                        .and_then(|n| from_name(&CHANNELS, n))
                        .ok_or_else(unknown)?,
                },
                Some("material") => Field::Material {
                    object,
                    coef: plain(2)
                        .and_then(|n| from_name(&COEFS, n))
                        .ok_or_else(unknown)?,
                },
                _ => return Err(unknown()),
            },
            (Some(_), _) => {
                owner_of(path, &s[0])?;
                return Err(unknown());
            }
            (None, _) => return Err(unknown()),
        };
        Ok(field)
    }

    /// What the field holds: for reading a typed value.
    fn kind(self) -> Kind {
        match self {
            Field::ModelType => Kind::Model,
            Field::ModelDepth => Kind::Integer {
                min: 0,
                max: u64::from(Model::MAX_DEPTH),
            },
            Field::CameraWidth | Field::CameraHeight => Kind::Integer {
                min: 1,
                max: MAX_SIDE,
            },
            _ => Kind::Number,
        }
    }

    /// Reads `text` as a value of this field, by the loader's rules for its
    /// attribute (the range is checked when the edit is applied).
    pub fn parse_value(self, text: &str) -> Result<Value, EditError> {
        match self.kind() {
            Kind::Number => match parse_number(text) {
                Ok(v) => Ok(Value::Number(v)),
                Err(NumberError::NotFinite) => Err(value_error(
                    self,
                    format!("must be a finite number, got '{text}'"),
                )),
                Err(NumberError::Invalid) => {
                    Err(value_error(self, format!("not a number: '{text}'")))
                }
            },
            Kind::Integer { min, max } => parse_integer(text)
                .filter(|v| (min..=max).contains(v))
                .map(Value::Integer)
                .ok_or_else(|| {
                    value_error(
                        self,
                        format!("must be a whole number from {min} to {max}, got '{text}'"),
                    )
                }),
            Kind::Model => Illumination::from_name(text.trim_ascii())
                .map(Value::Model)
                .ok_or_else(|| {
                    let names: Vec<_> = Illumination::ALL.iter().map(|m| m.name()).collect();
                    value_error(
                        self,
                        format!("must be one of {}, got '{text}'", names.join(", ")),
                    )
                }),
        }
    }

    /// The field's value in `scene`.
    pub fn get(self, scene: &Scene) -> Result<Value, EditError> {
        Ok(match self {
            Field::ModelType => Value::Model(scene.model.illumination),
            Field::ModelDepth => Value::Integer(u64::from(scene.model.depth)),
            Field::CameraWidth => Value::Integer(u64::from(scene.camera.width)),
            Field::CameraHeight => Value::Integer(u64::from(scene.camera.height)),
            Field::CameraEyeDistance => Value::Number(scene.camera.eye_distance),
            Field::Step { owner, step, attr } => {
                let s = *step_of(scene, owner, step)?;
                Value::Number(step_attr(&s, attr).ok_or_else(|| wrong_attr(self, &s))?)
            }
            Field::Color { object, channel } => {
                Value::Number(channel.axis().of(object_of(scene, object)?.color))
            }
            Field::Material { object, coef } => {
                let mut m = object_of(scene, object)?.material;
                Value::Number(*coef.slot(&mut m))
            }
            Field::LightPosition { light, axis } => {
                Value::Number(axis.of(light_of(scene, light)?.position))
            }
            Field::LightColor { light, channel } => {
                Value::Number(channel.axis().of(light_of(scene, light)?.color))
            }
        })
    }

    /// The element the field belongs to, if it is an object, a light or a
    /// transformation step.
    pub fn item(self) -> Option<Item> {
        match self {
            Field::Color { object, .. } | Field::Material { object, .. } => {
                Some(Item::Object(object))
            }
            Field::LightPosition { light, .. } | Field::LightColor { light, .. } => {
                Some(Item::Light(light))
            }
            Field::Step { owner, step, .. } => Some(Item::Step(owner, step)),
            _ => None,
        }
    }

    /// The attribute's name, for labels ("ka", "eyeDistance", "angle").
    pub fn attribute(self) -> &'static str {
        match self {
            Field::ModelType => "type",
            Field::ModelDepth => "depth",
            Field::CameraWidth => "width",
            Field::CameraHeight => "height",
            Field::CameraEyeDistance => "eyeDistance",
            Field::Step { attr, .. } => attr.name(),
            Field::Color { channel, .. } | Field::LightColor { channel, .. } => channel.name(),
            Field::Material { coef, .. } => coef.name(),
            Field::LightPosition { axis, .. } => axis.name(),
        }
    }
}

#[derive(Clone, Copy)]
enum Kind {
    Number,
    Integer { min: u64, max: u64 },
    Model,
}

impl Item {
    /// Parses a path such as `object[2]` or `camera.transformation[1]`.
    pub fn parse(path: &str) -> Result<Item, EditError> {
        let s = segments(path)?;
        let unknown = || path_error(path, format!("not an element; elements are {ITEM_PATHS}"));
        match s.as_slice() {
            [one] => match (one.name, one.index) {
                ("object", Some(n)) => Ok(Item::Object(n)),
                ("light", Some(n)) => Ok(Item::Light(n)),
                _ => {
                    owner_of(path, one)?;
                    Err(unknown())
                }
            },
            [first, second] => {
                let owner = owner_of(path, first)?.ok_or_else(unknown)?;
                match (second.name, second.index) {
                    ("transformation", Some(k)) => Ok(Item::Step(owner, k)),
                    _ => Err(unknown()),
                }
            }
            _ => Err(unknown()),
        }
    }
}

impl Edit {
    /// A new sphere, plane or light with the default values, appended.
    pub fn add(scene: &Scene, kind: NewElement) -> Edit {
        match kind {
            NewElement::Sphere | NewElement::Plane => {
                let shape = if kind == NewElement::Sphere {
                    Shape::Sphere
                } else {
                    Shape::Plane
                };
                Edit::Insert(
                    Item::Object(scene.objects.len()),
                    Element::Object(Box::new(Object {
                        shape,
                        color: Vec3::ONE,
                        material: Material::default(),
                        transform: Transform::default(),
                    })),
                )
            }
            NewElement::Light => Edit::Insert(
                Item::Light(scene.lights.len()),
                Element::Light(Light {
                    position: Vec3::new(0.0, -5.0, -5.0),
                    color: Vec3::ONE,
                }),
            ),
        }
    }

    /// A step appended to `owner`'s transformation.
    pub fn add_step(scene: &Scene, owner: Owner, step: TransformStep) -> Result<Edit, EditError> {
        let len = transform_of(scene, owner)?.steps().len();
        Ok(Edit::Insert(Item::Step(owner, len), Element::Step(step)))
    }

    /// What the edit does, for the Edit menu ("ka of #2 sphere").
    pub fn describe(&self, scene: &Scene) -> String {
        let item_name = |item: Item| -> String {
            match item {
                Item::Object(n) => scene
                    .objects
                    .get(n)
                    .map_or(format!("object {}", n + 1), |o| {
                        format!("#{} {}", n + 1, o.shape.name())
                    }),
                Item::Light(n) => format!("light {}", n + 1),
                Item::Step(owner, k) => {
                    let owner = match owner {
                        Owner::Camera => "camera".to_owned(),
                        Owner::Object(n) => format!("#{} object", n + 1),
                    };
                    format!("step {} of {owner}", k + 1)
                }
            }
        };
        match self {
            Edit::Set(field, _) => {
                let of = match field.item() {
                    Some(item) => item_name(item),
                    None => match field {
                        Field::ModelType | Field::ModelDepth => "model".to_owned(),
                        _ => "camera".to_owned(),
                    },
                };
                let attr = match field {
                    Field::Color { .. } | Field::LightColor { .. } => {
                        format!("colour {}", field.attribute())
                    }
                    _ => field.attribute().to_owned(),
                };
                format!("{attr} of {of}")
            }
            Edit::Insert(item, element) => match element {
                Element::Object(o) => format!("add {}", o.shape.name()),
                Element::Light(_) => "add light".to_owned(),
                Element::Step(s) => format!("add {} to {}", step_name(s), {
                    let Item::Step(owner, _) = item else {
                        return "add step".to_owned();
                    };
                    owner.to_string()
                }),
            },
            Edit::Remove(item) => format!("remove {}", item_name(*item)),
            Edit::Transform(Owner::Camera, _) => "camera view".to_owned(),
            Edit::Transform(Owner::Object(n), _) => {
                format!("move {}", item_name(Item::Object(*n)))
            }
        }
    }
}

/// What `--add` and the panel's buttons add.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum NewElement {
    Sphere,
    Plane,
    Light,
}

impl NewElement {
    pub fn parse(name: &str) -> Result<NewElement, EditError> {
        match name {
            "sphere" => Ok(NewElement::Sphere),
            "plane" => Ok(NewElement::Plane),
            "light" => Ok(NewElement::Light),
            _ => Err(path_error(
                name,
                "not an element that can be added; those are sphere, plane and light",
            )),
        }
    }
}

// ----- lookups -----

fn object_of(scene: &Scene, n: usize) -> Result<&Object, EditError> {
    scene.objects.get(n).map(AsRef::as_ref).ok_or_else(|| {
        path_error(
            Item::Object(n),
            count_message(scene.objects.len(), "object"),
        )
    })
}

fn light_of(scene: &Scene, n: usize) -> Result<&Light, EditError> {
    scene
        .lights
        .get(n)
        .ok_or_else(|| path_error(Item::Light(n), count_message(scene.lights.len(), "light")))
}

fn count_message(len: usize, what: &str) -> String {
    match len {
        0 => format!("the scene has no {what}s"),
        1 => format!("the scene has 1 {what}"),
        n => format!("the scene has {n} {what}s"),
    }
}

pub(crate) fn transform_of(scene: &Scene, owner: Owner) -> Result<&Transform, EditError> {
    match owner {
        Owner::Camera => Ok(&scene.camera.transform),
        Owner::Object(n) => Ok(&object_of(scene, n)?.transform),
    }
}

fn step_of(scene: &Scene, owner: Owner, k: usize) -> Result<&TransformStep, EditError> {
    let steps = transform_of(scene, owner)?.steps();
    steps.get(k).ok_or_else(|| {
        path_error(
            Item::Step(owner, k),
            match steps.len() {
                0 => format!("{owner} has no transformation steps"),
                1 => format!("{owner} has 1 transformation step"),
                n => format!("{owner} has {n} transformation steps"),
            },
        )
    })
}

fn step_attr(step: &TransformStep, attr: StepAttr) -> Option<f64> {
    use TransformStep as S;
    match (*step, attr) {
        (S::Translate(v) | S::Scale(v), a) => a.axis().map(|axis| axis.of(v)),
        (S::RotateX(a) | S::RotateY(a) | S::RotateZ(a), StepAttr::Angle) => Some(a),
        (S::UniformScale(f), StepAttr::Factor) => Some(f),
        _ => None,
    }
}

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

fn wrong_attr(field: Field, step: &TransformStep) -> EditError {
    let allowed: Vec<&str> = StepAttr::allowed(step).iter().map(|a| a.name()).collect();
    let what = match step {
        TransformStep::Scale(_) => "a scale by x, y, z".to_owned(),
        TransformStep::UniformScale(_) => "a scale by a factor".to_owned(),
        s => format!("a {}", step_name(s)),
    };
    path_error(
        field,
        format!("this step is {what}: its values are {}", allowed.join(", ")),
    )
}

// ----- the edited scene -----

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

#[cfg(test)]
mod tests {
    use super::*;
    use std::path::Path;

    fn example() -> Edited {
        Edited::new(super::super::parse(crate::EXAMPLE_SCENE, Path::new("e.xml")).unwrap())
    }

    #[test]
    fn paths_read_and_print_the_same() {
        for path in [
            "model.type",
            "model.depth",
            "camera.width",
            "camera.height",
            "camera.eyeDistance",
            "camera.transformation[3].angle",
            "object[2].color.green",
            "object[1].material.m",
            "object[12].transformation[1].factor",
            "light[1].z",
            "light[2].color.blue",
        ] {
            assert_eq!(Field::parse(path).unwrap().to_string(), path);
        }
        for path in [
            "object[3]",
            "light[1]",
            "object[2].transformation[4]",
            "camera.transformation[1]",
        ] {
            assert_eq!(Item::parse(path).unwrap().to_string(), path);
        }
    }

    #[test]
    fn bad_paths_say_what_is_allowed() {
        for (path, expected) in [
            ("object[0].material.ka", "count from 1"),
            ("object.material.ka", "object needs an index"),
            ("object[1].material.kx", "paths are model.type"),
            ("object[1].material[2].ka", "paths are"),
            ("camera..width", "empty name"),
            ("object[x].color.red", "is not an index"),
            ("object[1.color.red", "missing ']'"),
        ] {
            let e = Field::parse(path).unwrap_err().to_string();
            assert!(e.starts_with(&format!("{path}: ")), "{e}");
            assert!(e.contains(expected), "{path}: {e}");
        }
        assert!(
            Item::parse("camera")
                .unwrap_err()
                .to_string()
                .contains("elements are object[N]")
        );
    }

    #[test]
    fn out_of_range_indices_name_the_count() {
        let mut e = example();
        let err = e
            .apply(&Edit::Set(
                Field::parse("object[5].material.ka").unwrap(),
                Value::Number(0.5),
            ))
            .unwrap_err();
        assert_eq!(err.to_string(), "object[5]: the scene has 2 objects");
        let err = e
            .apply(&Edit::Remove(Item::parse("light[2]").unwrap()))
            .unwrap_err();
        assert_eq!(err.to_string(), "light[2]: the scene has 1 light");
    }

    #[test]
    fn values_follow_the_loaders_rules() {
        let mut e = example();
        let before = e.clone();
        for (path, value, message) in [
            ("object[1].material.ka", "-1", "must be >= 0, got -1"),
            ("camera.eyeDistance", "0", "must be > 0, got 0"),
            ("camera.width", "0", "from 1 to"),
            ("camera.width", "1.5", "whole number"),
            ("model.depth", "10001", "from 0 to 10000"),
            ("model.type", "raytrace", "must be one of ambient"),
            ("light[1].x", "inf", "finite"),
            ("light[1].x", "abc", "not a number"),
            ("object[1].color.red", "-0.5", ">= 0"),
        ] {
            let field = Field::parse(path).unwrap();
            let err = field
                .parse_value(value)
                .and_then(|v| e.apply(&Edit::Set(field, v)))
                .unwrap_err();
            assert!(err.to_string().contains(message), "{path}={value}: {err}");
            assert!(err.to_string().starts_with(path), "{err}");
        }
        let err = e
            .apply(&Edit::Set(Field::CameraWidth, Value::Integer(1 << 20)))
            .unwrap_err();
        assert!(err.to_string().contains("limit"), "{err}");
        assert_eq!(e, before, "a refused edit changes nothing");
    }

    #[test]
    fn a_step_that_makes_the_transformation_singular_is_refused() {
        let mut e = example();
        let scale = Edit::add_step(
            e.scene(),
            Owner::Object(0),
            TransformStep::UniformScale(2.0),
        )
        .unwrap();
        e.apply(&scale).unwrap();
        let k = e.scene().objects[0].transform.steps().len();
        let field = Field::parse(&format!("object[1].transformation[{k}].factor")).unwrap();
        let err = e.apply(&Edit::Set(field, Value::Number(0.0))).unwrap_err();
        assert!(err.to_string().contains("singular"), "{err}");
        let err = e
            .apply(&Edit::Set(
                Field::parse(&format!("object[1].transformation[{k}].x")).unwrap(),
                Value::Number(1.0),
            ))
            .unwrap_err();
        assert!(err.to_string().contains("its values are factor"), "{err}");
    }

    #[test]
    fn undo_restores_the_scene_and_the_origins() {
        let original = example();
        let mut e = original.clone();
        let edits = [
            Edit::Set(
                Field::parse("object[2].material.ka").unwrap(),
                Value::Number(0.9),
            ),
            Edit::Remove(Item::Object(0)),
            Edit::add(&original.scene, NewElement::Light),
            Edit::Remove(Item::Light(0)),
            Edit::Set(Field::ModelType, Value::Model(Illumination::Lambert)),
        ];
        let mut undos = Vec::new();
        for edit in &edits {
            undos.push(e.apply(edit).unwrap());
        }
        assert_eq!(e.object_origin(0), Some(1));
        let mut redos = Vec::new();
        while let Some(u) = undos.pop() {
            redos.push(e.undo(u).unwrap());
        }
        assert_eq!(e, original);
        while let Some(r) = redos.pop() {
            e.undo(r).unwrap();
        }
        assert_eq!(e.scene().objects.len(), 1);
        assert_eq!(e.object_origin(0), Some(1));
        assert_eq!(e.lights, vec![None]);
    }

    #[test]
    fn descriptions_name_the_value_and_the_element() {
        let e = example();
        let set = Edit::Set(
            Field::parse("object[2].material.ka").unwrap(),
            Value::Number(0.1),
        );
        assert_eq!(set.describe(e.scene()), "ka of #2 sphere");
        assert_eq!(
            Edit::Remove(Item::Light(0)).describe(e.scene()),
            "remove light 1"
        );
        assert_eq!(
            Edit::add(e.scene(), NewElement::Plane).describe(e.scene()),
            "add plane"
        );
    }
}
