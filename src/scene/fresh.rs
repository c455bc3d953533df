//! A fresh scene file for a scene that has no text yet ("Save as" of the
//! built-in example, a new scene): [`to_xml`], and the lines of XML an
//! element is written as, which save-back ([`super::splice`]) also writes
//! the elements it adds with.
//!
//! The two write by different rules, on purpose: a fresh file gives each
//! object its colour and its full material, to be easy to edit by hand,
//! and the model its depth under whitted; an element added to an existing
//! text holds only what differs from the defaults. Numbers are written
//! with Rust's shortest round-trip formatting ([`num`]), so the text parses
//! back to exactly the values written.

use super::edit::{Coef, number_text as num};
use super::{Color, Illumination, Material, Model, Object, Scene};
use crate::math::{TransformStep, Vec3};
use crate::shading::Light;

/// A fresh scene file for `scene`, indented by two spaces:
/// `parse(&to_xml(scene), path) == Ok(scene)` for every valid scene.
///
/// Objects come first, then lights, the camera and the model. Each object
/// gets its colour and its full material, so that the file is easy to edit
/// by hand; a transformation is written when it has steps, a light colour
/// when it is not white.
pub fn to_xml(scene: &Scene) -> String {
    let mut lines: Lines = vec![(0, "<scene>".to_owned())];
    for object in &scene.objects {
        let name = object.shape.name();
        lines.push((1, format!("<{name}>")));
        lines.push((2, color_tag(object.color)));
        lines.push((2, material_tag(&object.material, false)));
        push_nested(
            &mut lines,
            2,
            transformation_lines(object.transform.steps()),
        );
        lines.push((1, format!("</{name}>")));
    }
    for light in &scene.lights {
        push_nested(&mut lines, 1, light_lines(light));
    }
    let camera = &scene.camera;
    let camera_tag = format!(
        "camera width=\"{}\" height=\"{}\" eyeDistance=\"{}\"",
        camera.width,
        camera.height,
        num(camera.eye_distance)
    );
    if camera.transform.steps().is_empty() {
        lines.push((1, format!("<{camera_tag}/>")));
    } else {
        lines.push((1, format!("<{camera_tag}>")));
        push_nested(
            &mut lines,
            2,
            transformation_lines(camera.transform.steps()),
        );
        lines.push((1, "</camera>".to_owned()));
    }
    let model = scene.model;
    let depth = if model.depth != 1 || model.illumination == Illumination::Whitted {
        format!(" depth=\"{}\"", model.depth)
    } else {
        String::new()
    };
    lines.push((
        1,
        format!("<model type=\"{}\"{depth}/>", model.illumination.name()),
    ));
    lines.push((0, "</scene>".to_owned()));

    let mut out = String::from("<?xml version=\"1.0\"?>\n");
    for (level, line) in lines {
        out.push_str(&"  ".repeat(level));
        out.push_str(&line);
        out.push('\n');
    }
    out
}

// ----- writing elements -----

/// Lines of XML, each with its nesting level relative to the first.
pub(super) type Lines = Vec<(usize, String)>;

fn push_nested(lines: &mut Lines, level: usize, nested: Lines) {
    lines.extend(nested.into_iter().map(|(l, s)| (l + level, s)));
}

pub(super) fn color_tag(c: Color) -> String {
    format!(
        "<color red=\"{}\" green=\"{}\" blue=\"{}\"/>",
        num(c.x),
        num(c.y),
        num(c.z)
    )
}

/// `<material .../>`; with `only_changed`, the attributes equal to their
/// defaults are left out.
pub(super) fn material_tag(m: &Material, only_changed: bool) -> String {
    let d = Material::default();
    let mut tag = String::from("<material");
    for coef in Coef::ALL {
        let v = coef.of(m);
        if !only_changed || v != coef.of(&d) {
            tag.push_str(&format!(" {}=\"{}\"", coef.name(), num(v)));
        }
    }
    tag.push_str("/>");
    tag
}

fn xyz(v: Vec3) -> String {
    format!("x=\"{}\" y=\"{}\" z=\"{}\"", num(v.x), num(v.y), num(v.z))
}

pub(super) fn step_tag(step: &TransformStep) -> String {
    match *step {
        TransformStep::Translate(v) => format!("<translate {}/>", xyz(v)),
        TransformStep::RotateX(a) => format!("<rotate-x angle=\"{}\"/>", num(a)),
        TransformStep::RotateY(a) => format!("<rotate-y angle=\"{}\"/>", num(a)),
        TransformStep::RotateZ(a) => format!("<rotate-z angle=\"{}\"/>", num(a)),
        TransformStep::UniformScale(f) => format!("<scale factor=\"{}\"/>", num(f)),
        TransformStep::Scale(v) => format!("<scale {}/>", xyz(v)),
    }
}

/// `<transformation>` with its steps; nothing when there are none.
pub(super) fn transformation_lines(steps: &[TransformStep]) -> Lines {
    if steps.is_empty() {
        return Vec::new();
    }
    let mut lines = vec![(0, "<transformation>".to_owned())];
    lines.extend(steps.iter().map(|s| (1, step_tag(s))));
    lines.push((0, "</transformation>".to_owned()));
    lines
}

/// A new object element: only what differs from the defaults.
pub(super) fn object_lines(object: &Object) -> Lines {
    let name = object.shape.name();
    let mut inner: Lines = Vec::new();
    if object.color != Vec3::ONE {
        inner.push((0, color_tag(object.color)));
    }
    if object.material != Material::default() {
        inner.push((0, material_tag(&object.material, true)));
    }
    inner.extend(transformation_lines(object.transform.steps()));
    wrap(name, "", inner)
}

pub(super) fn light_lines(light: &Light) -> Lines {
    let inner = if light.color == Vec3::ONE {
        Vec::new()
    } else {
        vec![(0, color_tag(light.color))]
    };
    wrap("light", &format!(" {}", xyz(light.position)), inner)
}

pub(super) fn model_tag(model: &Model) -> String {
    let depth = if model.depth == 1 {
        String::new()
    } else {
        format!(" depth=\"{}\"", model.depth)
    };
    format!("<model type=\"{}\"{depth}/>", model.illumination.name())
}

/// `<name attrs/>`, or `<name attrs>` + `inner` one level deeper + `</name>`.
fn wrap(name: &str, attrs: &str, inner: Lines) -> Lines {
    if inner.is_empty() {
        return vec![(0, format!("<{name}{attrs}/>"))];
    }
    let mut lines = vec![(0, format!("<{name}{attrs}>"))];
    push_nested(&mut lines, 1, inner);
    lines.push((0, format!("</{name}>")));
    lines
}
