//! Three-way merge at the level of values: the user's unsaved edits,
//! replayed onto a version of the file that another program saved.
//!
//! The edits were made on `base` (the text as the app last read or wrote
//! it); `theirs` is the file as it is now. Each element of `base` is found
//! again in `theirs` by its identity ([`super::identity`]: a diff of the
//! two lists of elements), whatever the other program inserted, removed or
//! moved around it, and each edit goes to that same element. An edit
//! conflicts only where both sides changed the same thing, or where what it
//! edits is gone:
//! - setting a value that `theirs` also changed, to something else;
//! - editing or moving an element that `theirs` removed (reported as gone;
//!   never put on another element);
//! - removing an element that `theirs` changed;
//! - replacing a transformation (the camera's, an object's) that `theirs`
//!   changed, or setting a step of one whose steps `theirs` added or removed
//!   (the same index may be another step).
//!
//! Conflicts are returned with both values; the caller asks the user and
//! merges again with a [`Choice`] for each. Nothing is ever dropped
//! silently: an edit is either applied or reported. (Removing an element
//! the file removed too is agreement, not a conflict.)

use std::collections::BTreeMap;

use super::Scene;
use super::edit::{
    Channel, Coef, Edit, Edited, Element, Field, Item, Owner, StepAttr, Value, transform_of,
};
use super::identity::{self, Matching};
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
    /// What it is about (`object[2].material.ka`), numbered as in the
    /// version merged onto (what the list shows once merged), or as the
    /// user saw it when making the edit where the element is gone.
    pub path: String,
    /// The edit's side, in words or as a value.
    pub yours: String,
    /// The file's side.
    pub theirs: String,
    /// Whether "yours" can still be applied (an element that is gone
    /// cannot be edited).
    pub can_keep_yours: bool,
}

impl Conflict {
    /// "Keep all of mine" for this conflict: the edit where it can still
    /// be applied, the file's version where its element is gone.
    pub fn mine_if_possible(&self) -> Choice {
        if self.can_keep_yours {
            Choice::Mine
        } else {
            Choice::Theirs
        }
    }
}

/// The merged scene (with origins into `theirs`' text), the edits that were
/// applied (the unsaved edits from now on), and the conflicts left open.
#[derive(Debug, Clone)]
pub struct Merged {
    pub edited: Edited,
    pub applied: Vec<Edit>,
    pub conflicts: Vec<Conflict>,
}

/// Where each object and light of the base (as the edits change it) is in
/// theirs (as the applied edits change it).
struct Places {
    objects: Matching,
    lights: Matching,
}

/// An element of the base that theirs no longer has.
struct Gone;

impl Places {
    fn new(base: &Scene, theirs: &Scene) -> Places {
        Places {
            objects: identity::objects(&base.objects, &theirs.objects),
            lights: identity::lights(&base.lights, &theirs.lights),
        }
    }

    fn object(&self, n: usize) -> Result<usize, Gone> {
        self.objects.get(n).copied().flatten().ok_or(Gone)
    }

    fn light(&self, n: usize) -> Result<usize, Gone> {
        self.lights.get(n).copied().flatten().ok_or(Gone)
    }

    fn owner(&self, owner: Owner) -> Result<Owner, Gone> {
        Ok(match owner {
            Owner::Camera => Owner::Camera,
            Owner::Object(n) => Owner::Object(self.object(n)?),
        })
    }

    /// `field` of the base's element, named in theirs.
    fn field(&self, field: Field) -> Result<Field, Gone> {
        Ok(match field {
            Field::Color { object, channel } => Field::Color {
                object: self.object(object)?,
                channel,
            },
            Field::Material { object, coef } => Field::Material {
                object: self.object(object)?,
                coef,
            },
            Field::LightPosition { light, axis } => Field::LightPosition {
                light: self.light(light)?,
                axis,
            },
            Field::LightColor { light, channel } => Field::LightColor {
                light: self.light(light)?,
                channel,
            },
            Field::Step { owner, step, attr } => Field::Step {
                owner: self.owner(owner)?,
                step,
                attr,
            },
            other => other,
        })
    }

    /// `edit` (made on the base) as it applies to theirs.
    fn edit(&self, edit: &Edit, theirs: &Scene) -> Result<Edit, Gone> {
        Ok(match edit {
            Edit::Set(field, value) => Edit::Set(self.field(*field)?, *value),
            Edit::Remove(item) => Edit::Remove(self.item(*item)?),
            Edit::Transform(owner, steps) => Edit::Transform(self.owner(*owner)?, steps.clone()),
            Edit::Insert(item, element) => {
                let item = match *item {
                    Item::Object(n) => {
                        Item::Object(insert_at(&self.objects, n, theirs.objects.len()))
                    }
                    Item::Light(n) => Item::Light(insert_at(&self.lights, n, theirs.lights.len())),
                    Item::Step(owner, k) => {
                        let owner = self.owner(owner)?;
                        let len = steps(theirs, owner).map_or(0, <[TransformStep]>::len);
                        Item::Step(owner, k.min(len))
                    }
                };
                Edit::Insert(item, element.clone())
            }
        })
    }

    fn item(&self, item: Item) -> Result<Item, Gone> {
        Ok(match item {
            Item::Object(n) => Item::Object(self.object(n)?),
            Item::Light(n) => Item::Light(self.light(n)?),
            Item::Step(owner, k) => Item::Step(self.owner(owner)?, k),
        })
    }

    /// Follows `edit`, applied to the base, and `applied`, its translation
    /// applied to theirs (`None`: not applied there).
    fn follow(&mut self, edit: &Edit, applied: Option<&Edit>) {
        let at = |e: Option<&Edit>| match e {
            Some(
                Edit::Insert(Item::Object(m) | Item::Light(m), _)
                | Edit::Remove(Item::Object(m) | Item::Light(m)),
            ) => Some(*m),
            _ => None,
        };
        match edit {
            Edit::Insert(Item::Object(n), _) => inserted(&mut self.objects, *n, at(applied)),
            Edit::Insert(Item::Light(n), _) => inserted(&mut self.lights, *n, at(applied)),
            Edit::Remove(Item::Object(n)) => removed(&mut self.objects, *n, at(applied)),
            Edit::Remove(Item::Light(n)) => removed(&mut self.lights, *n, at(applied)),
            _ => {}
        }
    }
}

/// Where an element inserted at `n` on the base side goes on theirs: just
/// before the next element of the base that theirs still has, or at their
/// end.
fn insert_at(places: &Matching, n: usize, their_len: usize) -> usize {
    places
        .get(n..)
        .into_iter()
        .flatten()
        .find_map(|m| *m)
        .unwrap_or(their_len)
}

/// An element was inserted at `n` on the base side and at `m` on theirs.
fn inserted(places: &mut Matching, n: usize, m: Option<usize>) {
    if let Some(m) = m {
        for k in places.iter_mut().flatten() {
            if *k >= m {
                *k += 1;
            }
        }
    }
    places.insert(n.min(places.len()), m);
}

/// The element at `n` on the base side was removed, and at `m` on theirs.
fn removed(places: &mut Matching, n: usize, m: Option<usize>) {
    if n < places.len() {
        places.remove(n);
    }
    if let Some(m) = m {
        for k in places.iter_mut().flatten() {
            if *k > m {
                *k -= 1;
            }
        }
    }
}

/// What to do with one edit.
enum Verdict {
    Apply(Edit),
    /// Both sides did it already (removed the same element).
    Agreed,
    Conflict(Conflict),
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
    merge_onto(base, Edited::new(theirs.clone()), edits, choices)
}

/// [`merge`] onto a scene that carries the origins of its own text
/// (`theirs` an edited scene, as another window's edits are replayed onto
/// the edits on screen): an element it added or moved keeps where it
/// came from.
pub fn merge_onto(
    base: &Scene,
    theirs: Edited,
    edits: &[Edit],
    choices: &BTreeMap<usize, Choice>,
) -> Merged {
    let mut b = Edited::new(base.clone());
    let mut places = Places::new(base, theirs.scene());
    let mut t = theirs;
    let mut applied = Vec::new();
    let mut conflicts = Vec::new();
    for (i, edit) in edits.iter().enumerate() {
        let verdict = judge(b.scene(), t.scene(), &places, edit);
        // The base follows the edits as they were made.
        if b.apply(edit).is_err() {
            continue;
        }
        let apply = match (verdict, choices.get(&i)) {
            (Verdict::Apply(e), _) => Some(e),
            (Verdict::Agreed, _) => None,
            (Verdict::Conflict(c), Some(Choice::Mine)) if c.can_keep_yours => {
                places.edit(edit, t.scene()).ok()
            }
            (Verdict::Conflict(_), Some(_)) => None,
            (Verdict::Conflict(c), None) => {
                // Numbered as the element is numbered now, where it is
                // still there: the number the list shows.
                let path = places
                    .edit(edit, t.scene())
                    .map_or(c.path, |now| edit_path(&now));
                conflicts.push(Conflict { edit: i, path, ..c });
                None
            }
        };
        let done = apply.and_then(|e| match t.apply(&e) {
            Ok(_) => Some(e),
            // An edit that is valid on the base but not on theirs (a value
            // that makes their transform singular) cannot be applied:
            // report it.
            Err(err) => {
                if !choices.contains_key(&i) {
                    conflicts.push(Conflict {
                        edit: i,
                        path: edit_path(edit),
                        yours: err.to_string(),
                        theirs: "the file's version".to_owned(),
                        can_keep_yours: false,
                    });
                }
                None
            }
        });
        places.follow(edit, done.as_ref());
        applied.extend(done);
    }
    Merged {
        edited: t,
        applied,
        conflicts,
    }
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

/// Whether `edit`, made on `base`, applies to `theirs` as it stands, and
/// as what.
fn judge(base: &Scene, theirs: &Scene, places: &Places, edit: &Edit) -> Verdict {
    let path = edit_path(edit);
    let conflict = |yours: String, their: String, can_keep_yours| {
        Verdict::Conflict(Conflict {
            edit: 0,
            path: path.clone(),
            yours,
            theirs: their,
            can_keep_yours,
        })
    };
    let gone = |yours: String| {
        conflict(
            yours,
            "gone: another program removed it from the file".to_owned(),
            false,
        )
    };
    let yours = match edit {
        Edit::Set(_, value) => value.to_string(),
        Edit::Remove(_) => "removed".to_owned(),
        Edit::Insert(..) => "added".to_owned(),
        Edit::Transform(Owner::Camera, _) => "your view".to_owned(),
        Edit::Transform(Owner::Object(_), _) => "your move".to_owned(),
    };
    let Ok(translated) = places.edit(edit, theirs) else {
        return match edit {
            Edit::Remove(Item::Object(_) | Item::Light(_)) => Verdict::Agreed,
            _ => gone(yours),
        };
    };
    match (edit, &translated) {
        (Edit::Set(field, value), Edit::Set(their_field, _)) => {
            let Ok(their_value) = their_field.get(theirs) else {
                return gone(yours);
            };
            if let Field::Step { owner, step, .. } = *field
                && let Field::Step {
                    owner: their_owner, ..
                } = *their_field
                && steps(base, owner).map(<[_]>::len) != steps(theirs, their_owner).map(<[_]>::len)
                && steps(base, owner).and_then(|s| s.get(step))
                    != steps(theirs, their_owner).and_then(|s| s.get(step))
            {
                return conflict(
                    yours,
                    format!(
                        "{their_value}, but the file added or removed steps: step {} may be another one now",
                        step + 1
                    ),
                    true,
                );
            }
            let Ok(base_value) = field.get(base) else {
                return Verdict::Apply(translated);
            };
            let they_changed = !same_value(&base_value, &their_value);
            if they_changed && !same_value(value, &their_value) {
                conflict(yours, their_value.to_string(), true)
            } else {
                Verdict::Apply(translated)
            }
        }
        (Edit::Remove(item), Edit::Remove(their_item)) => {
            let same = match (*item, *their_item) {
                (Item::Object(n), Item::Object(m)) => base.objects.get(n) == theirs.objects.get(m),
                (Item::Light(n), Item::Light(m)) => base.lights.get(n) == theirs.lights.get(m),
                // A step is the same one while the whole transformation is.
                (Item::Step(owner, _), Item::Step(their_owner, _)) => {
                    match (steps(base, owner), steps(theirs, their_owner)) {
                        (Some(a), Some(b)) => a == b,
                        _ => return gone(yours),
                    }
                }
                _ => false,
            };
            if same {
                Verdict::Apply(translated)
            } else {
                conflict(yours, "changed in the file".to_owned(), true)
            }
        }
        (Edit::Transform(owner, _), Edit::Transform(their_owner, _)) => {
            if steps(base, *owner) == steps(theirs, *their_owner) {
                Verdict::Apply(translated)
            } else {
                conflict(yours, "changed in the file".to_owned(), true)
            }
        }
        _ => Verdict::Apply(translated),
    }
}

/// Values compare by their bits for numbers: -0 and 0 differ in the text.
fn same_value(a: &Value, b: &Value) -> bool {
    match (a, b) {
        (Value::Number(x), Value::Number(y)) => x.to_bits() == y.to_bits(),
        _ => a == b,
    }
}

/// Edits that turn `from` into `to`: what the unsaved edits are when the
/// scene on screen comes from another text than the file's (an undone
/// reload). Elements are paired by their identity ([`super::identity`]):
/// an element the other text lacks is removed or added, one that differs
/// has its values set.
pub fn edits_between(from: &Scene, to: &Scene) -> Vec<Edit> {
    let mut edits = Vec::new();
    let set = |field: Field, edits: &mut Vec<Edit>| {
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
        set(field, &mut edits);
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
        set(field, &mut edits);
    }
    if from.camera.transform != to.camera.transform {
        edits.push(Edit::Transform(
            Owner::Camera,
            to.camera.transform.steps().to_vec(),
        ));
    }

    // Objects: the pairs kept in order are changed in place, the others
    // removed (last first) and added (first first) at their places.
    let kept = in_order(identity::objects(&from.objects, &to.objects));
    for (n, m) in kept
        .iter()
        .enumerate()
        .filter_map(|(n, m)| Some((n, (*m)?)))
    {
        let (a, b) = (&from.objects[n], &to.objects[m]);
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
        for channel in [Channel::Red, Channel::Green, Channel::Blue] {
            fields.push((
                Field::Color { object: n, channel },
                Field::Color { object: m, channel },
            ));
        }
        for coef in Coef::ALL {
            fields.push((
                Field::Material { object: n, coef },
                Field::Material { object: m, coef },
            ));
        }
        for (f, g) in fields {
            if let (Ok(x), Ok(y)) = (f.get(from), g.get(to))
                && !same_value(&x, &y)
            {
                edits.push(Edit::Set(f, y));
            }
        }
        // Steps of the same kinds: each value that differs is set (no
        // step's value can make another singular).
        for (k, (x, y)) in a
            .transform
            .steps()
            .iter()
            .zip(b.transform.steps())
            .enumerate()
        {
            if x == y {
                continue;
            }
            for attr in [
                StepAttr::X,
                StepAttr::Y,
                StepAttr::Z,
                StepAttr::Angle,
                StepAttr::Factor,
            ] {
                let f = |object| Field::Step {
                    owner: Owner::Object(object),
                    step: k,
                    attr,
                };
                if let (Ok(p), Ok(q)) = (f(n).get(from), f(m).get(to))
                    && !same_value(&p, &q)
                {
                    edits.push(Edit::Set(f(n), q));
                }
            }
        }
    }
    push_removes_and_inserts(&kept, to.objects.len(), &mut edits, Item::Object, |m| {
        Element::Object(Box::new(to.objects[m].as_ref().clone()))
    });

    let kept = in_order(identity::lights(&from.lights, &to.lights));
    for (n, m) in kept
        .iter()
        .enumerate()
        .filter_map(|(n, m)| Some((n, (*m)?)))
    {
        let (a, b) = (from.lights[n], to.lights[m]);
        for axis in [
            super::edit::Axis::X,
            super::edit::Axis::Y,
            super::edit::Axis::Z,
        ] {
            let (x, y) = (axis.of(a.position), axis.of(b.position));
            if x.to_bits() != y.to_bits() {
                edits.push(Edit::Set(
                    Field::LightPosition { light: n, axis },
                    Value::Number(y),
                ));
            }
        }
        for channel in [Channel::Red, Channel::Green, Channel::Blue] {
            let (x, y) = (channel.axis().of(a.color), channel.axis().of(b.color));
            if x.to_bits() != y.to_bits() {
                edits.push(Edit::Set(
                    Field::LightColor { light: n, channel },
                    Value::Number(y),
                ));
            }
        }
    }
    push_removes_and_inserts(&kept, to.lights.len(), &mut edits, Item::Light, |m| {
        Element::Light(to.lights[m])
    });
    edits
}

/// The matching with only the pairs whose new indices rise: a moved
/// element is removed and added again.
fn in_order(mut matching: Matching) -> Matching {
    let mut last = None;
    for slot in &mut matching {
        if let Some(m) = *slot {
            if last.is_some_and(|l| m <= l) {
                *slot = None;
            } else {
                last = Some(m);
            }
        }
    }
    matching
}

/// Removes the old elements `kept` does not keep, last first, then adds the
/// new ones no old element became, first first, each at its new index.
fn push_removes_and_inserts(
    kept: &Matching,
    new_len: usize,
    edits: &mut Vec<Edit>,
    item: fn(usize) -> Item,
    element: impl Fn(usize) -> Element,
) {
    for n in (0..kept.len()).rev().filter(|&n| kept[n].is_none()) {
        edits.push(Edit::Remove(item(n)));
    }
    let mut taken = vec![false; new_len];
    for m in kept.iter().flatten() {
        taken[*m] = true;
    }
    for m in (0..new_len).filter(|&m| !taken[m]) {
        edits.push(Edit::Insert(item(m), element(m)));
    }
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
    fn a_conflict_is_numbered_as_the_element_is_now() {
        let base = example();
        let mut theirs = base.clone();
        let inserted = theirs.objects[1].clone();
        theirs.objects.insert(0, inserted);
        std::sync::Arc::make_mut(&mut theirs.objects[1]).material.ka = 0.7;
        let edits = vec![Edit::Set(ka(0), Value::Number(0.5))];
        let m = merge(&base, &theirs, &edits, &BTreeMap::new());
        assert_eq!(m.conflicts.len(), 1);
        assert_eq!(m.conflicts[0].path, "object[2].material.ka");
    }

    #[test]
    fn an_edit_follows_its_element_and_one_on_a_gone_element_is_asked() {
        let base = example();
        let mut theirs = base.clone();
        theirs.objects.remove(0);
        // The second object is the first in theirs: the edit goes there.
        let edits = vec![Edit::Set(ka(1), Value::Number(0.5))];
        let m = merge(&base, &theirs, &edits, &BTreeMap::new());
        assert!(m.conflicts.is_empty());
        assert_eq!(m.edited.scene().objects[0].material.ka, 0.5);
        assert_eq!(m.applied, vec![Edit::Set(ka(0), Value::Number(0.5))]);

        // The first one is gone: asked, never put on another object.
        let edits = vec![Edit::Set(ka(0), Value::Number(0.5))];
        let m = merge(&base, &theirs, &edits, &BTreeMap::from([(0, Choice::Mine)]));
        assert_eq!(m.edited.scene(), &theirs);
        let m = merge(&base, &theirs, &edits, &BTreeMap::new());
        assert_eq!(m.conflicts.len(), 1);
        assert!(!m.conflicts[0].can_keep_yours);
        assert!(
            m.conflicts[0].theirs.contains("gone"),
            "{:?}",
            m.conflicts[0]
        );
        assert_eq!(m.edited.scene(), &theirs);
    }

    #[test]
    fn an_element_inserted_above_does_not_take_the_edit() {
        let base = example();
        let mut theirs = base.clone();
        let mut new = base.objects[1].as_ref().clone();
        new.material.kd = 0.123;
        theirs.objects.insert(0, std::sync::Arc::new(new));
        let edits = vec![
            Edit::Set(ka(0), Value::Number(0.9)),
            Edit::Remove(Item::Object(1)),
        ];
        let m = merge(&base, &theirs, &edits, &BTreeMap::new());
        assert!(m.conflicts.is_empty(), "{:?}", m.conflicts);
        let s = m.edited.scene();
        assert_eq!(s.objects.len(), 2);
        assert_eq!(s.objects[0].material.kd, 0.123, "theirs untouched");
        assert_eq!(s.objects[0].material.ka, base.objects[1].material.ka);
        assert_eq!(s.objects[1].material.ka, 0.9, "the edit on its own object");
    }

    #[test]
    fn added_elements_are_appended_to_theirs() {
        let base = example();
        let mut theirs = base.clone();
        let first = theirs.objects[0].clone();
        theirs.objects.push(first);
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
