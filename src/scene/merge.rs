//! Three-way merge at the level of values: the user's unsaved edits,
//! replayed onto a version of the file that another program saved.
//!
//! The edits were made on `base` (the text as the app last read or wrote
//! it); `theirs` is the file as it is now. Each edit is applied to `theirs`
//! by its path, in order. An edit conflicts only where both sides changed
//! the same thing, or where what it edits is gone or may no longer be the
//! same element:
//! - setting a value that `theirs` also changed, to something else;
//! - removing an element that `theirs` changed;
//! - editing an object or light when the file added or removed objects or
//!   lights and the element at that index is not the one in `base`;
//! - replacing a transformation (the camera's, an object's) that `theirs`
//!   changed.
//!
//! Conflicts are returned with both values; the caller asks the user and
//! merges again with a [`Choice`] for each. Nothing is ever dropped
//! silently: an edit is either applied or reported.

use std::collections::BTreeMap;

use super::Scene;
use super::edit::{Edit, Edited, Element, Field, Item, Owner, Value, transform_of};
use crate::math::TransformStep;

/// How a conflict is settled.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Choice {
    /// Apply the edit over the file's change.
    Mine,
    /// Keep the file's version: the edit is dropped.
    Theirs,
}

/// One edit that both sides touched.
#[derive(Debug, Clone, PartialEq)]
pub struct Conflict {
    /// Index of the edit in the list given to [`merge`].
    pub edit: usize,
    /// What it is about (`object[2].material.ka`).
    pub path: String,
    /// The edit's side, in words or as a value.
    pub yours: String,
    /// The file's side.
    pub theirs: String,
    /// Whether "yours" can still be applied (an element that is gone
    /// cannot be edited).
    pub can_keep_yours: bool,
}

/// The merged scene (with origins into `theirs`' text), the edits that were
/// applied (the unsaved edits from now on), and the conflicts left open.
#[derive(Debug, Clone)]
pub struct Merged {
    pub edited: Edited,
    pub applied: Vec<Edit>,
    pub conflicts: Vec<Conflict>,
}

/// Replays `edits` (made on `base`) onto `theirs`. An edit in conflict is
/// applied or dropped as `choices` says; without a choice it is left out
/// and reported in [`Merged::conflicts`].
pub fn merge(
    base: &Scene,
    theirs: &Scene,
    edits: &[Edit],
    choices: &BTreeMap<usize, Choice>,
) -> Merged {
    let mut b = Edited::new(base.clone());
    let mut t = Edited::new(theirs.clone());
    let mut applied = Vec::new();
    let mut conflicts = Vec::new();
    for (i, edit) in edits.iter().enumerate() {
        let conflict = conflict(b.scene(), t.scene(), edit);
        // The base follows the edits as they were made.
        let _ = b.apply(edit);
        let apply = match (&conflict, choices.get(&i)) {
            (None, _) => true,
            (Some(c), Some(Choice::Mine)) => c.can_keep_yours,
            (Some(_), Some(Choice::Theirs)) => false,
            (Some(c), None) => {
                conflicts.push(Conflict {
                    edit: i,
                    ..c.clone()
                });
                false
            }
        };
        if !apply {
            continue;
        }
        let edit = clamp_insert(t.scene(), edit);
        match t.apply(&edit) {
            Ok(_) => applied.push(edit),
            // An edit that is valid on the base but not on theirs (an
            // index past their end, a value that makes their transform
            // singular) cannot be applied: report it.
            Err(e) if !choices.contains_key(&i) => conflicts.push(Conflict {
                edit: i,
                path: edit_path(&edit),
                yours: e.to_string(),
                theirs: "the file's version".to_owned(),
                can_keep_yours: false,
            }),
            Err(_) => {}
        }
    }
    Merged {
        edited: t,
        applied,
        conflicts,
    }
}

/// An insert past the end of `theirs` goes at its end.
fn clamp_insert(theirs: &Scene, edit: &Edit) -> Edit {
    let Edit::Insert(item, element) = edit else {
        return edit.clone();
    };
    let item = match *item {
        Item::Object(n) => Item::Object(n.min(theirs.objects.len())),
        Item::Light(n) => Item::Light(n.min(theirs.lights.len())),
        Item::Step(owner, k) => {
            let len = steps(theirs, owner).map_or(0, <[TransformStep]>::len);
            Item::Step(owner, k.min(len))
        }
    };
    Edit::Insert(item, element.clone())
}

fn edit_path(edit: &Edit) -> String {
    match edit {
        Edit::Set(field, _) => field.to_string(),
        Edit::Insert(item, _) | Edit::Remove(item) => item.to_string(),
        Edit::Transform(owner, _) => format!("{owner}.transformation"),
    }
}

fn steps(scene: &Scene, owner: Owner) -> Option<&[TransformStep]> {
    transform_of(scene, owner).ok().map(|t| t.steps())
}

/// The element `item` names, compared between the two scenes: `None` when
/// `theirs` lacks it, `Some(true)` when both hold the same.
fn same_element(base: &Scene, theirs: &Scene, item: Item) -> Option<bool> {
    Some(match item {
        Item::Object(n) => base.objects.get(n)? == theirs.objects.get(n)?,
        Item::Light(n) => base.lights.get(n)? == theirs.lights.get(n)?,
        Item::Step(owner, k) => steps(base, owner)?.get(k)? == steps(theirs, owner)?.get(k)?,
    })
}

/// Whether the file added or removed elements of `item`'s kind, so that
/// the same index may name another element.
fn count_changed(base: &Scene, theirs: &Scene, item: Item) -> bool {
    match item {
        Item::Object(_) => base.objects.len() != theirs.objects.len(),
        Item::Light(_) => base.lights.len() != theirs.lights.len(),
        Item::Step(owner, _) => {
            steps(base, owner).map(<[_]>::len) != steps(theirs, owner).map(<[_]>::len)
                || matches!(owner, Owner::Object(_)) && base.objects.len() != theirs.objects.len()
        }
    }
}

fn conflict(base: &Scene, theirs: &Scene, edit: &Edit) -> Option<Conflict> {
    let make = |path: String, yours: String, theirs: String, can_keep_yours| {
        Some(Conflict {
            edit: 0,
            path,
            yours,
            theirs,
            can_keep_yours,
        })
    };
    match edit {
        Edit::Set(field, value) => {
            let path = field.to_string();
            let Ok(their_value) = field.get(theirs) else {
                return make(
                    path,
                    value.to_string(),
                    "gone from the file".to_owned(),
                    false,
                );
            };
            if let Some(item) = field.item()
                && count_changed(base, theirs, item)
                && same_element(base, theirs, item) == Some(false)
            {
                return make(
                    path,
                    value.to_string(),
                    format!(
                        "{their_value}, but the file added or removed elements: {item} may be another one now"
                    ),
                    true,
                );
            }
            let base_value = field.get(base).ok()?;
            let they_changed = !same_value(&base_value, &their_value);
            (they_changed && !same_value(value, &their_value)).then(|| Conflict {
                edit: 0,
                path,
                yours: value.to_string(),
                theirs: their_value.to_string(),
                can_keep_yours: true,
            })
        }
        Edit::Remove(item) => match same_element(base, theirs, *item) {
            None => make(
                item.to_string(),
                "removed".to_owned(),
                "gone from the file".to_owned(),
                false,
            ),
            Some(true) => None,
            Some(false) => make(
                item.to_string(),
                "removed".to_owned(),
                "changed in the file".to_owned(),
                true,
            ),
        },
        Edit::Insert(..) => None,
        Edit::Transform(owner, _) => {
            let path = format!("{owner}.transformation");
            let (yours, gone) = match owner {
                Owner::Camera => ("your view", false),
                Owner::Object(n) => ("your move", theirs.objects.get(*n).is_none()),
            };
            let (ours, their) = (steps(base, *owner), steps(theirs, *owner));
            if gone {
                make(
                    path,
                    yours.to_owned(),
                    "gone from the file".to_owned(),
                    false,
                )
            } else if ours != their {
                make(
                    path,
                    yours.to_owned(),
                    "changed in the file".to_owned(),
                    true,
                )
            } else {
                None
            }
        }
    }
}

/// Values compare by their bits for numbers: -0 and 0 differ in the text.
fn same_value(a: &Value, b: &Value) -> bool {
    match (a, b) {
        (Value::Number(x), Value::Number(y)) => x.to_bits() == y.to_bits(),
        _ => a == b,
    }
}

/// Edits that turn `from` into `to`, pairing elements by index: what undoes
/// a reload from disk (the two texts share no origins).
pub fn edits_between(from: &Scene, to: &Scene) -> Vec<Edit> {
    let mut edits = Vec::new();
    let set = |field: Field, from: &Scene, to: &Scene, edits: &mut Vec<Edit>| {
        if let (Ok(a), Ok(b)) = (field.get(from), field.get(to))
            && !same_value(&a, &b)
        {
            edits.push(Edit::Set(field, b));
        }
    };
    for field in [
        Field::ModelType,
        Field::ModelDepth,
        Field::CameraEyeDistance,
    ] {
        set(field, from, to, &mut edits);
    }
    // Width and height one after the other could pass through an image
    // over the pixel limit: shrink first.
    let (w, h) = (Field::CameraWidth, Field::CameraHeight);
    let order = if to.camera.width < from.camera.width {
        [w, h]
    } else {
        [h, w]
    };
    for field in order {
        set(field, from, to, &mut edits);
    }
    if from.camera.transform != to.camera.transform {
        edits.push(Edit::Transform(
            Owner::Camera,
            to.camera.transform.steps().to_vec(),
        ));
    }

    let common = from.objects.len().min(to.objects.len());
    for n in (common..from.objects.len()).rev() {
        edits.push(Edit::Remove(Item::Object(n)));
    }
    for n in 0..common {
        let (a, b) = (&from.objects[n], &to.objects[n]);
        if a == b {
            continue;
        }
        let kinds = |o: &super::Object| -> Vec<std::mem::Discriminant<TransformStep>> {
            o.transform
                .steps()
                .iter()
                .map(std::mem::discriminant)
                .collect()
        };
        if a.shape != b.shape || kinds(a) != kinds(b) {
            edits.push(Edit::Remove(Item::Object(n)));
            edits.push(Edit::Insert(
                Item::Object(n),
                Element::Object(Box::new(b.as_ref().clone())),
            ));
            continue;
        }
        let mut fields = Vec::new();
        for channel in [
            super::edit::Channel::Red,
            super::edit::Channel::Green,
            super::edit::Channel::Blue,
        ] {
            fields.push(Field::Color { object: n, channel });
        }
        for coef in [
            super::edit::Coef::Ka,
            super::edit::Coef::Kd,
            super::edit::Coef::Ks,
            super::edit::Coef::M,
        ] {
            fields.push(Field::Material { object: n, coef });
        }
        // Steps are replaced whole: a step's values set one by one could
        // pass through a singular transformation.
        for _ in 0..a.transform.steps().len() {
            edits.push(Edit::Remove(Item::Step(Owner::Object(n), 0)));
        }
        for field in fields {
            set(field, from, to, &mut edits);
        }
        for (k, step) in b.transform.steps().iter().enumerate() {
            edits.push(Edit::Insert(
                Item::Step(Owner::Object(n), k),
                Element::Step(*step),
            ));
        }
    }
    for (n, object) in to.objects.iter().enumerate().skip(common) {
        edits.push(Edit::Insert(
            Item::Object(n),
            Element::Object(Box::new(object.as_ref().clone())),
        ));
    }

    let common = from.lights.len().min(to.lights.len());
    for n in (common..from.lights.len()).rev() {
        edits.push(Edit::Remove(Item::Light(n)));
    }
    for n in 0..common {
        if from.lights[n] != to.lights[n] {
            edits.push(Edit::Remove(Item::Light(n)));
            edits.push(Edit::Insert(Item::Light(n), Element::Light(to.lights[n])));
        }
    }
    for (n, light) in to.lights.iter().enumerate().skip(common) {
        edits.push(Edit::Insert(Item::Light(n), Element::Light(*light)));
    }
    edits
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::scene::edit::{Coef, NewElement};
    use std::path::Path;

    fn example() -> Scene {
        crate::scene::parse(crate::EXAMPLE_SCENE, Path::new("e.xml")).unwrap()
    }

    fn ka(n: usize) -> Field {
        Field::Material {
            object: n,
            coef: Coef::Ka,
        }
    }

    #[test]
    fn edits_on_values_the_file_did_not_change_apply_silently() {
        let base = example();
        let mut theirs = base.clone();
        std::sync::Arc::make_mut(&mut theirs.objects[0]).material.kd = 0.9;
        theirs.lights[0].position.x = 7.0;
        let edits = vec![
            Edit::Set(ka(0), Value::Number(0.5)),
            Edit::Set(ka(1), Value::Number(0.1)),
        ];
        let m = merge(&base, &theirs, &edits, &BTreeMap::new());
        assert!(m.conflicts.is_empty());
        let s = m.edited.scene();
        assert_eq!(s.objects[0].material.ka, 0.5);
        assert_eq!(s.objects[0].material.kd, 0.9, "their change kept");
        assert_eq!(s.lights[0].position.x, 7.0, "their change kept");
        assert_eq!(s.objects[1].material.ka, 0.1);
        assert_eq!(m.applied, edits);
    }

    #[test]
    fn the_same_value_changed_on_both_sides_is_asked() {
        let base = example();
        let mut theirs = base.clone();
        std::sync::Arc::make_mut(&mut theirs.objects[0]).material.ka = 0.7;
        let edits = vec![Edit::Set(ka(0), Value::Number(0.5))];
        let m = merge(&base, &theirs, &edits, &BTreeMap::new());
        assert_eq!(m.conflicts.len(), 1);
        let c = &m.conflicts[0];
        assert_eq!(
            (c.path.as_str(), c.yours.as_str(), c.theirs.as_str()),
            ("object[1].material.ka", "0.5", "0.7")
        );
        assert_eq!(m.edited.scene().objects[0].material.ka, 0.7);
        let mine = BTreeMap::from([(0, Choice::Mine)]);
        let m = merge(&base, &theirs, &edits, &mine);
        assert!(m.conflicts.is_empty());
        assert_eq!(m.edited.scene().objects[0].material.ka, 0.5);
        // Both sides set the same value: no conflict.
        std::sync::Arc::make_mut(&mut theirs.objects[0]).material.ka = 0.5;
        assert!(
            merge(&base, &theirs, &edits, &BTreeMap::new())
                .conflicts
                .is_empty()
        );
    }

    #[test]
    fn an_edited_element_that_is_gone_or_moved_is_asked() {
        let base = example();
        let mut theirs = base.clone();
        theirs.objects.remove(0);
        let edits = vec![Edit::Set(ka(1), Value::Number(0.5))];
        let m = merge(&base, &theirs, &edits, &BTreeMap::new());
        assert_eq!(m.conflicts.len(), 1);
        assert!(!m.conflicts[0].can_keep_yours);
        assert_eq!(m.edited.scene(), &theirs);

        let edits = vec![Edit::Set(ka(0), Value::Number(0.5))];
        let m = merge(&base, &theirs, &edits, &BTreeMap::new());
        assert_eq!(m.conflicts.len(), 1);
        assert!(m.conflicts[0].theirs.contains("may be another one"));
    }

    #[test]
    fn added_elements_are_appended_to_theirs() {
        let base = example();
        let mut theirs = base.clone();
        theirs.objects.push(theirs.objects[0].clone());
        let edits = vec![Edit::add(&base, NewElement::Light)];
        let m = merge(&base, &theirs, &edits, &BTreeMap::new());
        assert!(m.conflicts.is_empty());
        assert_eq!(m.edited.scene().objects.len(), 3);
        assert_eq!(m.edited.scene().lights.len(), 2);
    }

    #[test]
    fn edits_between_turn_one_scene_into_the_other() {
        let a = example();
        let mut b = a.clone();
        std::sync::Arc::make_mut(&mut b.objects[1]).material.ka = 0.9;
        b.objects.push(a.objects[0].clone());
        b.lights.clear();
        b.camera.width = 33;
        b.model.depth = 5;
        for (from, to) in [(&a, &b), (&b, &a)] {
            let mut e = Edited::new(from.clone());
            for edit in edits_between(from, to) {
                e.apply(&edit).unwrap();
            }
            assert_eq!(e.scene(), to);
        }
    }
}
