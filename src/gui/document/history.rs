//! The undo history of a [`Document`]: every edit as an undo step (a whole
//! drag of one value is one step), undo and redo, and reverting to the
//! file's scene.

use super::*;

/// One entry of the undo (or redo) stack.
#[derive(Debug, Clone)]
pub(super) struct Step {
    /// "ka of #2 sphere".
    pub(super) label: String,
    /// Applied last to first.
    pub(super) undos: Vec<Undo>,
    /// What is being dragged: the next edit of the same values in the same
    /// drag joins this step.
    pub(super) dragging: Option<DragKey>,
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
        if edits.is_empty() {
            return Ok(());
        }
        if self.placeholder {
            return Err(EditError::Path {
                path: "scene".to_owned(),
                message: "no scene has loaded from the file yet".to_owned(),
            });
        }
        let label = step_label(&edits, self.scene());
        let mut undos = Vec::new();
        for edit in &edits {
            match self.edited.apply(edit) {
                Ok(undo) => undos.push(undo),
                Err(e) => {
                    // Leave the scene as it was.
                    for undo in undos.into_iter().rev() {
                        let _ = self.edited.undo(undo);
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
                undos,
                dragging: key,
            });
        }
        self.redo.clear();
        for edit in edits {
            self.log_edit(edit);
        }
        self.update_dirty();
        Ok(())
    }

    /// Adds `edit` to the unsaved edits. A value set again right after it
    /// was set (each step of a drag), or the camera moved again, replaces
    /// the earlier one: a merge replays, and asks about, each value once.
    fn log_edit(&mut self, edit: Edit) {
        let replaces = match (&edit, self.log.last()) {
            (Edit::Set(field, _), Some(Edit::Set(last, _))) => field == last,
            (Edit::Transform(owner, _), Some(Edit::Transform(last, _))) => owner == last,
            _ => false,
        };
        if replaces {
            self.log.pop();
        }
        self.log.push(edit);
    }

    /// Ends a drag: the next edit of the same field is a step of its own.
    pub fn end_drag(&mut self) {
        if let Some(step) = self.undo.last_mut() {
            step.dragging = None;
        }
    }

    /// "Undo ka of #2 sphere", if there is anything to undo.
    pub fn undo_label(&self) -> Option<&str> {
        self.undo.last().map(|s| s.label.as_str())
    }

    pub fn redo_label(&self) -> Option<&str> {
        self.redo.last().map(|s| s.label.as_str())
    }

    /// Undoes the last step; returns its label.
    pub fn undo(&mut self) -> Option<String> {
        let step = self.undo.pop()?;
        let label = step.label.clone();
        let redo = self.replay(step);
        self.redo.push(redo);
        Some(label)
    }

    /// Redoes the last undone step; returns its label.
    pub fn redo(&mut self) -> Option<String> {
        let step = self.redo.pop()?;
        let label = step.label.clone();
        let undo = self.replay(step);
        self.undo.push(undo);
        Some(label)
    }

    /// Applies a step's undos, last first, and returns the step that
    /// reverses it.
    fn replay(&mut self, step: Step) -> Step {
        let mut back = Vec::new();
        for undo in step.undos.into_iter().rev() {
            let edit = undo.edit().clone();
            // Each undo reverses an edit that was applied to exactly this
            // state, so it applies; one that does not is skipped rather than
            // leaving the stack half done.
            if let Ok(reverse) = self.edited.undo(undo) {
                self.log_edit(edit);
                back.push(reverse);
            }
        }
        self.update_dirty();
        // The reverses, applied last to first, undo this in reverse order.
        Step {
            label: step.label,
            undos: back,
            dragging: None,
        }
    }

    /// After every change of the scene on screen (and of the labels).
    pub(super) fn update_dirty(&mut self) {
        self.generation = super::next_generation();
        self.dirty = self.scene() != self.saved.scene();
        if !self.dirty {
            // Back to what the file holds: nothing to replay onto it.
            self.log.clear();
        }
    }

    /// Drops the unsaved edits: back to the file's scene, as one undo step.
    /// Undoing the revert brings the edits back by their paths.
    pub fn revert(&mut self) {
        if !self.dirty {
            return;
        }
        let back = merge::edits_between(self.saved.scene(), self.scene());
        self.edited = self.saved.clone();
        self.undo.push(Step {
            label: "revert edits".to_owned(),
            undos: back.into_iter().rev().map(Undo::from_edit).collect(),
            dragging: None,
        });
        self.redo.clear();
        self.update_dirty();
    }
}
