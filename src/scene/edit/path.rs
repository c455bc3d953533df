//! Paths: the names of fields and elements (`object[2].material.ka`,
//! `light[1].x`, `camera.transformation[1].angle`, `model.type`), counting
//! from 1 in file order as the panel numbers them; the [`Edit`] values
//! built on them, parsed from and printed as text, and described for
//! people; and what a path names in a scene (the lookups both reading and
//! [`Edited::apply`](super::Edited::apply) use).

use super::{EditError, path_error, value_error};
use crate::math::{Transform, TransformStep, Vec3};
use crate::scene::load::{MAX_SIDE, NumberError, parse_integer, parse_number};
use crate::scene::{Object, Scene, Shape};
use crate::shading::{Illumination, Light, Material, Model};
use std::fmt;

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
    pub(super) fn slot(self, v: &mut Vec3) -> &mut f64 {
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
    /// Every coefficient, in the order of `<material>`'s attributes: what
    /// the panel, the merge and the save-back go through.
    pub const ALL: [Coef; 4] = [Coef::Ka, Coef::Kd, Coef::Ks, Coef::M];

    /// The attribute's name (`ka`).
    pub fn name(self) -> &'static str {
        name_of(&COEFS, self)
    }

    /// What it is, in words (the panel's hint).
    pub fn hint(self) -> &'static str {
        match self {
            Coef::Ka => "ambient coefficient",
            Coef::Kd => "diffuse coefficient",
            Coef::Ks => "specular and reflection coefficient",
            Coef::M => "specular exponent (shininess)",
        }
    }

    /// Its value in `m`.
    pub fn of(self, m: &Material) -> f64 {
        match self {
            Coef::Ka => m.ka,
            Coef::Kd => m.kd,
            Coef::Ks => m.ks,
            Coef::M => m.m,
        }
    }

    pub(super) fn slot(self, m: &mut Material) -> &mut f64 {
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
    pub(super) fn allowed(step: &TransformStep) -> &'static [StepAttr] {
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

    pub(super) fn axis(self) -> Option<Axis> {
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
    pub(super) fn kind(self) -> Kind {
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
pub(super) enum Kind {
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
            NewElement::Object(shape) => Edit::Insert(
                Item::Object(scene.objects.len()),
                Element::Object(Box::new(Object {
                    shape,
                    color: Vec3::ONE,
                    material: Material::default(),
                    transform: Transform::default(),
                })),
            ),
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
                        super::super::names::object_name(n, o.shape.name(), None)
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
    /// An object of this shape.
    Object(Shape),
    Light,
}

impl NewElement {
    /// Every kind, in the order the help names them: each shape
    /// ([`Shape::ALL`]), then the light.
    pub const ALL: &'static [NewElement] = &{
        let mut all = [NewElement::Light; Shape::ALL.len() + 1];
        let mut i = 0;
        while i < Shape::ALL.len() {
            all[i] = NewElement::Object(Shape::ALL[i]);
            i += 1;
        }
        all
    };

    /// The kind's name, as `--add` takes it (the element's tag).
    pub fn name(self) -> &'static str {
        match self {
            NewElement::Object(shape) => shape.name(),
            NewElement::Light => "light",
        }
    }

    pub fn parse(name: &str) -> Result<NewElement, EditError> {
        NewElement::ALL
            .iter()
            .copied()
            .find(|kind| kind.name() == name)
            .ok_or_else(|| {
                let names: Vec<&str> = NewElement::ALL.iter().map(|k| k.name()).collect();
                let (last, first) = names.split_last().unwrap_or((&"", &[]));
                path_error(
                    name,
                    format!(
                        "not an element that can be added; those are {} and {last}",
                        first.join(", ")
                    ),
                )
            })
    }
}

// ----- what a path names in a scene -----

pub(super) fn object_of(scene: &Scene, n: usize) -> Result<&Object, EditError> {
    scene.objects.get(n).map(AsRef::as_ref).ok_or_else(|| {
        path_error(
            Item::Object(n),
            count_message(scene.objects.len(), "object"),
        )
    })
}

pub(super) fn light_of(scene: &Scene, n: usize) -> Result<&Light, EditError> {
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

pub(super) fn step_of(scene: &Scene, owner: Owner, k: usize) -> Result<&TransformStep, EditError> {
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

pub(super) fn step_attr(step: &TransformStep, attr: StepAttr) -> Option<f64> {
    use TransformStep as S;
    match (*step, attr) {
        (S::Translate(v) | S::Scale(v), a) => a.axis().map(|axis| axis.of(v)),
        (S::RotateX(a) | S::RotateY(a) | S::RotateZ(a), StepAttr::Angle) => Some(a),
        (S::UniformScale(f), StepAttr::Factor) => Some(f),
        _ => None,
    }
}

pub(super) fn wrong_attr(field: Field, step: &TransformStep) -> EditError {
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
