//! The scene format's grammar as data (docs/scene-format.md: Elements,
//! Transformations and Numbers): which
//! elements hold which, which attributes each takes, and for every
//! attribute what it means, its type, its range, and whether it is required
//! or what it defaults to.
//!
//! The loader ([`super::load`](mod@super::load)) reads with these lists of names: an element
//! or attribute not in them is refused. [`super::schema`] writes the whole
//! table as an XML Schema for editors. The loader's own checks (required,
//! ranges, defaults) and this table are held to each other by tests that
//! load a scene for every row (`scene::schema` tests).

use crate::geometry::Shape;
use crate::shading::Illumination;

/// `<scene>`'s children: every shape ([`Shape::ALL`]), then the light,
/// the camera and the model.
pub(crate) const SCENE_CHILDREN: &[&str] = &{
    const OTHERS: [&str; 3] = ["light", "camera", "model"];
    let mut names = [""; Shape::ALL.len() + OTHERS.len()];
    let mut i = 0;
    while i < Shape::ALL.len() {
        names[i] = Shape::ALL[i].name();
        i += 1;
    }
    let mut k = 0;
    while k < OTHERS.len() {
        names[i + k] = OTHERS[k];
        k += 1;
    }
    names
};
pub(crate) const OBJECT_CHILDREN: &[&str] = &["color", "material", "transformation"];
pub(crate) const LIGHT_CHILDREN: &[&str] = &["color"];
pub(crate) const CAMERA_CHILDREN: &[&str] = &["transformation"];
pub(crate) const TRANSFORM_CHILDREN: &[&str] =
    &["translate", "rotate-x", "rotate-y", "rotate-z", "scale"];
pub(crate) const NONE: &[&str] = &[];

pub(crate) const COLOR_ATTRS: &[&str] = &["red", "green", "blue"];
pub(crate) const MATERIAL_ATTRS: &[&str] = &["ka", "kd", "ks", "m"];
pub(crate) const LIGHT_ATTRS: &[&str] = &["x", "y", "z"];
pub(crate) const CAMERA_ATTRS: &[&str] = &["width", "height", "eyeDistance"];
pub(crate) const MODEL_ATTRS: &[&str] = &["type", "depth"];
pub(crate) const TRANSLATE_ATTRS: &[&str] = &["x", "y", "z"];
pub(crate) const ROTATE_ATTRS: &[&str] = &["angle"];
pub(crate) const SCALE_ATTRS: &[&str] = &["factor", "x", "y", "z"];

/// The XML Schema instance namespace: `<scene>` may declare it to name its
/// schema, and takes no other attribute.
pub const XSI_NAMESPACE: &str = "http://www.w3.org/2001/XMLSchema-instance";
/// `<scene>`'s only attributes: the declaration of [`XSI_NAMESPACE`] and
/// the schema's location, as editors write them.
pub(crate) const SCENE_ATTRS: &[&str] = &["xmlns:xsi", "xsi:noNamespaceSchemaLocation"];

/// How often the children of an element may appear.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Repeat {
    /// Each at most once, in any order.
    EachOnce,
    /// Any number of each, in any order (the steps of a transformation).
    Any,
    /// `<scene>`: exactly one `one` (the camera), at most one `at_most_one`
    /// (the model), any number of the others, in any order.
    Scene {
        one: &'static str,
        at_most_one: &'static str,
    },
}

/// One element of the format.
#[derive(Debug, Clone, Copy)]
pub struct Element {
    pub name: &'static str,
    /// What it is, as editors show it on hover.
    pub doc: &'static str,
    pub children: &'static [&'static str],
    pub repeat: Repeat,
    pub attributes: &'static [&'static str],
    /// A rule the schema cannot say (XSD 1.0), said in the documentation.
    pub also: Option<&'static str>,
}

/// What an attribute's value may be.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Value {
    /// A finite decimal number (docs/scene-format.md, Numbers), at least
    /// `min` if set (`min_exclusive`: greater than it).
    Number {
        min: Option<f64>,
        min_exclusive: bool,
    },
    /// ASCII digits with an optional `+`, from `min` to `max`.
    Integer { min: u64, max: u64 },
    /// One of these names.
    Choice(&'static [&'static str]),
}

impl Value {
    const ANY: Value = Value::Number {
        min: None,
        min_exclusive: false,
    };
    const NON_NEGATIVE: Value = Value::Number {
        min: Some(0.0),
        min_exclusive: false,
    };
    const POSITIVE: Value = Value::Number {
        min: Some(0.0),
        min_exclusive: true,
    };
}

/// One attribute of one element.
#[derive(Debug)]
pub struct Attribute {
    pub element: &'static str,
    pub name: &'static str,
    pub value: Value,
    pub presence: Presence,
    pub doc: &'static str,
}

/// Whether an attribute must be given, and what it is when it is not.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Presence {
    Required,
    /// Absent, it has this value.
    Default(&'static str),
    /// Absent, another attribute says (`scale`'s `factor`).
    Optional,
}

/// The illumination models' names, as `<model type>` takes them: every
/// one of [`Illumination::ALL`].
const MODELS: &[&str] = &{
    let mut names = [""; Illumination::ALL.len()];
    let mut i = 0;
    while i < names.len() {
        names[i] = Illumination::ALL[i].name();
        i += 1;
    }
    names
};

/// The element of an object of shape `shape`.
const fn object_element(shape: Shape) -> Element {
    Element {
        name: shape.name(),
        doc: shape.doc(),
        children: OBJECT_CHILDREN,
        repeat: Repeat::EachOnce,
        attributes: NONE,
        also: None,
    }
}

/// Every element, the root first, then the objects' (one for each of
/// [`Shape::ALL`]), then the others.
pub const ELEMENTS: &[Element] = &{
    let mut all = [SCENE_ELEMENT; 1 + Shape::ALL.len() + OTHER_ELEMENTS.len()];
    let mut i = 0;
    while i < Shape::ALL.len() {
        all[1 + i] = object_element(Shape::ALL[i]);
        i += 1;
    }
    let mut k = 0;
    while k < OTHER_ELEMENTS.len() {
        all[1 + i + k] = OTHER_ELEMENTS[k];
        k += 1;
    }
    all
};

/// The root element.
const SCENE_ELEMENT: Element = Element {
    name: "scene",
    doc: "A scene: objects (<sphere>, <plane>), <light>s, exactly one <camera> and at most one <model>, in any order.",
    children: SCENE_CHILDREN,
    repeat: Repeat::Scene {
        one: "camera",
        at_most_one: "model",
    },
    attributes: NONE,
    also: Some(
        "It may name its schema with xmlns:xsi and xsi:noNamespaceSchemaLocation, and takes no other attribute. At most 10 000 000 objects and 1 000 000 lights.",
    ),
};

/// The elements other than the root and the objects'.
const OTHER_ELEMENTS: &[Element] = &[
    Element {
        name: "light",
        doc: "A point light at world position (x, y, z); its optional <color> is its intensity. Lights cast no shadows.",
        children: LIGHT_CHILDREN,
        repeat: Repeat::EachOnce,
        attributes: LIGHT_ATTRS,
        also: None,
    },
    Element {
        name: "camera",
        doc: "The pinhole camera: the screen is the plane z = 0 of camera space, its shorter side spanning [-1, 1]; the eye is at (0, 0, -eyeDistance), looking along +z. Its optional <transformation> maps camera space to world space.",
        children: CAMERA_CHILDREN,
        repeat: Repeat::EachOnce,
        attributes: CAMERA_ATTRS,
        also: Some("width × height is at most 268 435 456 pixels (2^28)."),
    },
    Element {
        name: "model",
        doc: "The illumination model (default: phong, when the scene has no <model>).",
        children: NONE,
        repeat: Repeat::EachOnce,
        attributes: MODEL_ATTRS,
        also: None,
    },
    Element {
        name: "color",
        doc: "A colour, each component from 0 (none) up; above 1 is brighter (a light of 2 is twice as bright). Default for objects and lights: white (1, 1, 1).",
        children: NONE,
        repeat: Repeat::EachOnce,
        attributes: COLOR_ATTRS,
        also: None,
    },
    Element {
        name: "material",
        doc: "How the surface reflects light: I = ka C + Σ I_l (kd cos θ + ks (cos α)^m), and for whitted + ks I_r. Each attribute defaults on its own.",
        children: NONE,
        repeat: Repeat::EachOnce,
        attributes: MATERIAL_ATTRS,
        also: None,
    },
    Element {
        name: "transformation",
        doc: "Steps applied in document order, the first listed first to the object (as in POV-Ray): M = T_n ··· T_2 T_1.",
        children: TRANSFORM_CHILDREN,
        repeat: Repeat::Any,
        attributes: NONE,
        also: Some("The whole must be invertible with a finite inverse: no zero scale."),
    },
    Element {
        name: "translate",
        doc: "A translation by (x, y, z).",
        children: NONE,
        repeat: Repeat::EachOnce,
        attributes: TRANSLATE_ATTRS,
        also: None,
    },
    Element {
        name: "rotate-x",
        doc: "A right-hand rotation about the x axis: (y, z) → (y cos a − z sin a, y sin a + z cos a).",
        children: NONE,
        repeat: Repeat::EachOnce,
        attributes: ROTATE_ATTRS,
        also: None,
    },
    Element {
        name: "rotate-y",
        doc: "A right-hand rotation about the y axis: (z, x) → (z cos a − x sin a, z sin a + x cos a).",
        children: NONE,
        repeat: Repeat::EachOnce,
        attributes: ROTATE_ATTRS,
        also: None,
    },
    Element {
        name: "rotate-z",
        doc: "A right-hand rotation about the z axis: (x, y) → (x cos a − y sin a, x sin a + y cos a).",
        children: NONE,
        repeat: Repeat::EachOnce,
        attributes: ROTATE_ATTRS,
        also: None,
    },
    Element {
        name: "scale",
        doc: "A scale about the origin: uniform by factor, or by x, y, z. Negative values mirror; zero is refused.",
        children: NONE,
        repeat: Repeat::EachOnce,
        attributes: SCALE_ATTRS,
        also: Some("factor cannot be given with x, y or z."),
    },
];

/// Every attribute of every element.
pub const ATTRIBUTES: &[Attribute] = &[
    Attribute {
        element: "light",
        name: "x",
        value: Value::ANY,
        presence: Presence::Required,
        doc: "The light's world position, x (to the right).",
    },
    Attribute {
        element: "light",
        name: "y",
        value: Value::ANY,
        presence: Presence::Required,
        doc: "The light's world position, y (down: y = -4 is above the origin).",
    },
    Attribute {
        element: "light",
        name: "z",
        value: Value::ANY,
        presence: Presence::Required,
        doc: "The light's world position, z (forward, away from the viewer).",
    },
    Attribute {
        element: "camera",
        name: "width",
        value: Value::Integer {
            min: 1,
            max: u32::MAX as u64,
        },
        presence: Presence::Required,
        doc: "The image's width in pixels.",
    },
    Attribute {
        element: "camera",
        name: "height",
        value: Value::Integer {
            min: 1,
            max: u32::MAX as u64,
        },
        presence: Presence::Required,
        doc: "The image's height in pixels.",
    },
    Attribute {
        element: "camera",
        name: "eyeDistance",
        value: Value::POSITIVE,
        presence: Presence::Required,
        doc: "The eye's distance behind the screen, in camera units (the screen's shorter side is 2): larger is a narrower view.",
    },
    Attribute {
        element: "model",
        name: "type",
        value: Value::Choice(MODELS),
        presence: Presence::Required,
        doc: "ambient: I = ka C; lambert: + Σ I_l kd cos θ; phong: + Σ I_l ks (cos α)^m; whitted: phong + ks I_r, the mirror reflection.",
    },
    Attribute {
        element: "model",
        name: "depth",
        value: Value::Integer {
            min: 0,
            max: crate::shading::Model::MAX_DEPTH as u64,
        },
        presence: Presence::Default("1"),
        doc: "Reflected rays followed from one primary ray (whitted only; 0 is exactly phong).",
    },
    Attribute {
        element: "color",
        name: "red",
        value: Value::NON_NEGATIVE,
        presence: Presence::Required,
        doc: "Red, from 0 up (1 is full).",
    },
    Attribute {
        element: "color",
        name: "green",
        value: Value::NON_NEGATIVE,
        presence: Presence::Required,
        doc: "Green, from 0 up (1 is full).",
    },
    Attribute {
        element: "color",
        name: "blue",
        value: Value::NON_NEGATIVE,
        presence: Presence::Required,
        doc: "Blue, from 0 up (1 is full).",
    },
    Attribute {
        element: "material",
        name: "ka",
        value: Value::NON_NEGATIVE,
        presence: Presence::Default("0.2"),
        doc: "Ambient coefficient: the share of the object's colour C it shows unlit (ka C).",
    },
    Attribute {
        element: "material",
        name: "kd",
        value: Value::NON_NEGATIVE,
        presence: Presence::Default("0.6"),
        doc: "Diffuse coefficient: I_l kd cos θ from each light (not multiplied by C).",
    },
    Attribute {
        element: "material",
        name: "ks",
        value: Value::NON_NEGATIVE,
        presence: Presence::Default("0.2"),
        doc: "Specular coefficient: the highlight I_l ks (cos α)^m, and for whitted the share of the reflection ks I_r.",
    },
    Attribute {
        element: "material",
        name: "m",
        value: Value::NON_NEGATIVE,
        presence: Presence::Default("10"),
        doc: "Shininess: the highlight's exponent (larger is a smaller, sharper highlight).",
    },
    Attribute {
        element: "translate",
        name: "x",
        value: Value::ANY,
        presence: Presence::Default("0"),
        doc: "The translation along x.",
    },
    Attribute {
        element: "translate",
        name: "y",
        value: Value::ANY,
        presence: Presence::Default("0"),
        doc: "The translation along y.",
    },
    Attribute {
        element: "translate",
        name: "z",
        value: Value::ANY,
        presence: Presence::Default("0"),
        doc: "The translation along z.",
    },
    Attribute {
        element: "rotate-x",
        name: "angle",
        value: Value::ANY,
        presence: Presence::Required,
        doc: "The angle in radians.",
    },
    Attribute {
        element: "rotate-y",
        name: "angle",
        value: Value::ANY,
        presence: Presence::Required,
        doc: "The angle in radians.",
    },
    Attribute {
        element: "rotate-z",
        name: "angle",
        value: Value::ANY,
        presence: Presence::Required,
        doc: "The angle in radians.",
    },
    Attribute {
        element: "scale",
        name: "factor",
        value: Value::ANY,
        presence: Presence::Optional,
        doc: "A uniform scale (not with x, y, z); negative mirrors, zero is refused.",
    },
    Attribute {
        element: "scale",
        name: "x",
        value: Value::ANY,
        presence: Presence::Default("1"),
        doc: "The scale along x; negative mirrors, zero is refused.",
    },
    Attribute {
        element: "scale",
        name: "y",
        value: Value::ANY,
        presence: Presence::Default("1"),
        doc: "The scale along y; negative mirrors, zero is refused.",
    },
    Attribute {
        element: "scale",
        name: "z",
        value: Value::ANY,
        presence: Presence::Default("1"),
        doc: "The scale along z; negative mirrors, zero is refused.",
    },
];

impl Element {
    /// What it is and the rules the schema cannot say: the text editors
    /// show for it.
    pub fn documentation(&self) -> String {
        match self.also {
            Some(rule) => format!("{} {rule}", self.doc),
            None => self.doc.to_owned(),
        }
    }
}

impl Attribute {
    /// What it means, its range and its default: the text editors show
    /// for it.
    pub fn documentation(&self) -> String {
        let range = match self.value {
            Value::Number { min: None, .. } => "Any finite number.".to_owned(),
            Value::Number {
                min: Some(min),
                min_exclusive,
            } => format!("A number {} {min}.", if min_exclusive { ">" } else { "≥" }),
            Value::Integer { min, max } => format!("An integer from {min} to {max}."),
            Value::Choice(names) => format!("One of {}.", names.join(", ")),
        };
        let presence = match self.presence {
            Presence::Required => "Required.".to_owned(),
            Presence::Default(v) => format!("Default: {v}."),
            Presence::Optional => "Optional.".to_owned(),
        };
        format!("{} {range} {presence}", self.doc)
    }
}

/// The element named `name`.
pub fn element(name: &str) -> Option<&'static Element> {
    ELEMENTS.iter().find(|e| e.name == name)
}

/// The attribute `name` of `element`.
pub fn attribute(element: &str, name: &str) -> Option<&'static Attribute> {
    ATTRIBUTES
        .iter()
        .find(|a| a.element == element && a.name == name)
}
