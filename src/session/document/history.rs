//! The undo history of a [`Document`]: every edit as an undo step (a whole
//! drag of one value is one step), undo and redo, and reverting to the
//! file's scene.
//!
//! A step either undoes edits (their [`Undo`]s, which bring back removed
//! elements with their origins, so with their text) or puts back a whole
//! [`Version`]: what a reload from disk, a merge or a revert replaced. The
//! steps below such a step were made on the text it puts back, so their
//! origins are good again by the time they are undone: undoing everything
//! gives back the text as first read, byte for byte.

use super::{Document, Version};
use crate::scene::Scene;
use crate::scene::edit::{Edit, EditError, Field, Owner, Undo};

/// One entry of the undo (or redo) stack.
#[derive(Debug, Clone)]
pub(super) struct Step {
    /// "ka of #2 sphere".
    pub(super) label: String,
    pub(super) change: Change,
    /// What is being dragged: the next edit of the same values in the same
    /// drag joins this step.
    pub(super) dragging: Option<DragKey>,
}

/// What undoing (or redoing) a step does.
#[derive(Debug, Clone)]
pub(super) enum Change {
    /// Applies these, last to first.
    Edits(Vec<Undo>),
    /// Puts this version on screen (and the one there in its place on the
    /// other stack).
    Version(Box<Version>),
}

/// What a drag changes: values, or a whole transformation.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(super) enum DragValue {
    Field(Field),
    Transform(Owner),
}

type DragKey = Vec<DragValue>;

/// What `edits` change, if they are edits a drag makes (set values, move
/// the camera).
fn drag_key(edits: &[Edit]) -> Option<DragKey> {
    edits
        .iter()
        .map(|e| match e {
            Edit::Set(field, _) => Some(DragValue::Field(*field)),
            Edit::Transform(owner, _) => Some(DragValue::Transform(*owner)),
            Edit::Insert(..) | Edit::Remove(_) => None,
        })
        .collect()
}

/// "ka of #2 sphere"; "colour of #1 sphere" for a colour's channels set
/// together, "position of light 1" for a light's coordinates.
fn step_label(edits: &[Edit], scene: &Scene) -> String {
    let first = edits
        .first()
        .map_or_else(String::new, |e| e.describe(scene));
    let all = |f: fn(&Field) -> bool| {
        edits.len() > 1
            && edits
                .iter()
                .all(|e| matches!(e, Edit::Set(field, _) if f(field)))
    };
    let colour = all(|f| matches!(f, Field::Color { .. } | Field::LightColor { .. }));
    let position = all(|f| matches!(f, Field::LightPosition { .. }));
    match first.split_once(" of ") {
        Some((_, of)) if colour => format!("colour of {of}"),
        Some((_, of)) if position => format!("position of {of}"),
        _ => first,
    }
}

impl Document {
    /// Applies an edit as one undo step.
    pub fn apply(&mut self, edit: Edit) -> Result<(), EditError> {
        self.apply_step(vec![edit], false)
    }

    /// Applies edits made together (the three channels of a picked colour)
    /// as one undo step; on an error none is applied. With `dragging`, the
    /// edits of the same fields right after ones also made while dragging
    /// join their step: a whole drag is undone at once.
    pub fn apply_step(&mut self, edits: Vec<Edit>, dragging: bool) -> Result<(), EditError> {
        let label = step_label(&edits, self.scene());
        self.apply_as(edits, label, dragging)
    }

    /// Applies edits as one undo step named `label`.
    pub(super) fn apply_labelled(
        &mut self,
        edits: Vec<Edit>,
        label: String,
    ) -> Result<(), EditError> {
        self.apply_as(edits, label, false)
    }

    fn apply_as(
        &mut self,
        edits: Vec<Edit>,
        label: String,
        dragging: bool,
    ) -> Result<(), EditError> {
        if edits.is_empty() {
            return Ok(());
        }
        if self.placeholder {
            return Err(EditError::Path {
                path: "scene".to_owned(),
                message: "no scene has loaded from the file yet".to_owned(),
            });
        }
        if self.editor.is_some() {
            return Err(EditError::Path {
                path: "scene".to_owned(),
                message: "your editor has unsaved text of this file: edit it there, or save or close it there to edit here".to_owned(),
            });
        }
        let mut undos = Vec::new();
        for edit in &edits {
            match self.shown.edited.apply(edit) {
                Ok(undo) => undos.push(undo),
                Err(e) => {
                    // Leave the scene as it was.
                    for undo in undos.into_iter().rev() {
                        let _ = self.shown.edited.undo(undo);
                    }
                    return Err(e);
                }
            }
        }
        let key = if dragging { drag_key(&edits) } else { None };
        let joins = key.is_some()
            && self.redo.is_empty()
            && self.undo.last().is_some_and(|s| s.dragging == key);
        if !joins {
            self.undo.push(Step {
                label,
                change: Change::Edits(undos),
                dragging: key,
            });
        }
        self.redo.clear();
        self.update_dirty();
        Ok(())
    }

    /// Ends a drag: the next edit of the same field is a step of its own.
    pub fn end_drag(&mut self) {
        if let Some(step) = self.undo.last_mut() {
            step.dragging = None;
        }
    }

    /// "Undo ka of #2 sphere", if there is anything to undo.
    pub fn undo_label(&self) -> Option<&str> {
        let step = self.undo.last().filter(|_| self.editor.is_none());
        step.map(|s| s.label.as_str())
    }

    pub fn redo_label(&self) -> Option<&str> {
        let step = self.redo.last().filter(|_| self.editor.is_none());
        step.map(|s| s.label.as_str())
    }

    /// Undoes the last step; returns its label.
    pub fn undo(&mut self) -> Option<String> {
        // The editor's text is on screen: undo there.
        if self.editor.is_some() {
            return None;
        }
        let step = self.undo.pop()?;
        let label = step.label.clone();
        let redo = self.replay(step);
        self.redo.push(redo);
        Some(label)
    }

    /// Redoes the last undone step; returns its label.
    pub fn redo(&mut self) -> Option<String> {
        if self.editor.is_some() {
            return None;
        }
        let step = self.redo.pop()?;
        let label = step.label.clone();
        let undo = self.replay(step);
        self.undo.push(undo);
        Some(label)
    }

    /// Undoes (or redoes) a step and returns the step that reverses it.
    fn replay(&mut self, step: Step) -> Step {
        let change = match step.change {
            Change::Edits(undos) => {
                let mut back = Vec::new();
                for undo in undos.into_iter().rev() {
                    // Each undo reverses an edit that was applied to exactly
                    // this state, so it applies; one that does not is skipped
                    // rather than leaving the stack half done.
                    if let Ok(reverse) = self.shown.edited.undo(undo) {
                        back.push(reverse);
                    }
                }
                // The reverses, applied last to first, undo this in reverse
                // order.
                Change::Edits(back)
            }
            Change::Version(version) => {
                let before = std::mem::replace(&mut self.shown, *version);
                Change::Version(Box::new(before))
            }
        };
        self.update_dirty();
        Step {
            label: step.label,
            change,
            dragging: None,
        }
    }

    /// Puts `version` on screen as one undo step named `label`: undoing it
    /// brings back the version on screen before, whole.
    pub(super) fn show_version(&mut self, label: &str, version: Version) {
        let before = std::mem::replace(&mut self.shown, version);
        for step in &mut self.undo {
            step.dragging = None;
        }
        self.undo.push(Step {
            label: label.to_owned(),
            change: Change::Version(Box::new(before)),
            dragging: None,
        });
        self.redo.clear();
        self.update_dirty();
    }

    /// After every change of the scene on screen (and of the labels).
    pub(super) fn update_dirty(&mut self) {
        self.generation = super::next_generation();
        self.dirty = !self.shown.same_as(&self.file);
    }

    /// Drops the unsaved edits: back to the file's text, as one undo step.
    /// Undoing the revert brings the version on screen before it back.
    pub fn revert(&mut self) {
        if self.editor.is_some() {
            return;
        }
        if !self.dirty {
            return;
        }
        self.show_version("revert edits", self.file.clone());
    }
}
