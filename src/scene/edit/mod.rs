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
//!
//! `path` holds the paths and the edit values, `edited` the edited
//! scene and the one `apply`.

use std::fmt;

mod edited;
mod path;

pub use edited::*;
pub use path::*;

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

pub(super) fn path_error(path: impl fmt::Display, message: impl Into<String>) -> EditError {
    EditError::Path {
        path: path.to_string(),
        message: message.into(),
    }
}

pub(super) fn value_error(path: impl fmt::Display, message: impl Into<String>) -> EditError {
    EditError::Value {
        path: path.to_string(),
        message: message.into(),
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::math::TransformStep;
    use crate::scene::Shape;
    use crate::shading::Illumination;
    use std::path::Path;

    fn example() -> Edited {
        Edited::new(super::super::parse(crate::EXAMPLE_SCENE, Path::new("e.xml")).unwrap())
    }

    #[test]
    fn the_grammar_and_the_edits_name_the_same_coefficients_and_elements() {
        let coefs: Vec<&str> = Coef::ALL.iter().map(|c| c.name()).collect();
        assert_eq!(coefs, crate::scene::grammar::MATERIAL_ATTRS);
        for kind in NewElement::ALL {
            assert!(
                crate::scene::grammar::SCENE_CHILDREN.contains(&kind.name()),
                "{}",
                kind.name()
            );
        }
        assert_eq!(
            NewElement::parse("cube").unwrap_err().to_string(),
            "cube: not an element that can be added; those are sphere, plane and light"
        );
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
            Edit::add(original.scene(), NewElement::Light),
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
            Edit::add(e.scene(), NewElement::Object(Shape::Plane)).describe(e.scene()),
            "add plane"
        );
    }
}
