//! The panel's widgets for one value (a number, an angle in degrees, an
//! integer) and the [`Form`] that turns what the user did with them this
//! frame into [`Edit`]s: only a real change of a value is an edit.

use super::PanelOutput;
use crate::scene::Scene;
use crate::scene::edit::{Edit, Field, Value, number_text};
use egui::{DragValue, Response, Ui};
use std::ops::RangeInclusive;

/// Collects the edits of one frame.
pub(super) struct Form<'s> {
    pub(super) scene: &'s Scene,
    pub(super) out: PanelOutput,
    /// The field to mark (outlined), and whether to scroll to it now.
    pub(super) marked: Option<Field>,
    pub(super) reveal: bool,
}

impl Form<'_> {
    /// A drag of the field, or an entry typed in it, ends: Enter, Tab, a
    /// click elsewhere.
    pub(super) fn note(&mut self, response: &Response) {
        if response.drag_stopped() || response.lost_focus() {
            self.out.drag_ended = true;
        }
    }

    /// `field` set to `value` by the widget of `response`. While it is
    /// dragged or typed in (it has the keyboard's focus), its changes
    /// join one undo step: typing "0.19" is one entry, not four.
    pub(super) fn set(&mut self, field: Field, value: Value, response: &Response) {
        self.out.dragging |= response.dragged() || response.has_focus() || response.lost_focus();
        self.out.edits.push(Edit::Set(field, value));
    }

    /// A number field. `range` is what dragging and typing may reach; a
    /// loaded value outside it is shown as it is.
    pub(super) fn number(
        &mut self,
        ui: &mut Ui,
        field: Field,
        speed: f64,
        range: RangeInclusive<f64>,
        prefix: &str,
    ) -> Response {
        let Ok(Value::Number(old)) = field.get(self.scene) else {
            return ui.label("?");
        };
        let mut value = old;
        let response = ui.add(
            DragValue::new(&mut value)
                .speed(speed)
                .range(range)
                .clamp_existing_to_range(false)
                .custom_formatter(|v, _| number_text(v))
                .prefix(prefix),
        );
        self.note(&response);
        if response.changed() && value.to_bits() != old.to_bits() {
            self.set(field, Value::Number(value), &response);
        }
        if self.marked == Some(field) {
            let stroke = ui.visuals().selection.stroke;
            ui.painter().rect_stroke(
                response.rect.expand(2.0),
                3.0,
                egui::Stroke::new(2.0, stroke.color),
                egui::StrokeKind::Outside,
            );
            if self.reveal {
                response.scroll_to_me(Some(egui::Align::Center));
            }
        }
        response
    }

    /// An angle in radians (as the file holds it), shown in degrees to six
    /// decimals (-0.1 rad is -5.729578°).
    pub(super) fn angle(&mut self, ui: &mut Ui, field: Field) -> Response {
        let Ok(Value::Number(radians)) = field.get(self.scene) else {
            return ui.label("?");
        };
        let old = radians.to_degrees();
        let mut degrees = old;
        let response = ui.add(
            DragValue::new(&mut degrees)
                .speed(1.0)
                .custom_formatter(|v, _| degrees_text(v))
                .suffix("°"),
        );
        self.note(&response);
        // Enter on an untouched field reads back the text shown: that is no
        // edit (the file's radians would not survive the round trip).
        let shown = degrees_text(old).parse::<f64>().unwrap_or(old);
        let untouched = degrees.to_bits() == old.to_bits() || degrees.to_bits() == shown.to_bits();
        if response.changed() && !untouched {
            self.set(field, Value::Number(degrees.to_radians()), &response);
        }
        response
    }

    pub(super) fn integer(
        &mut self,
        ui: &mut Ui,
        field: Field,
        range: RangeInclusive<u64>,
    ) -> Response {
        let Ok(Value::Integer(old)) = field.get(self.scene) else {
            return ui.label("?");
        };
        let mut value = old;
        let response = ui.add(
            DragValue::new(&mut value)
                .range(range)
                .clamp_existing_to_range(false),
        );
        self.note(&response);
        if response.changed() && value != old {
            self.set(field, Value::Integer(value), &response);
        }
        response
    }

    pub(super) fn edit(&mut self, edit: Edit) {
        self.out.edits.push(edit);
    }
}

/// Degrees to six decimals, without trailing zeros.
fn degrees_text(v: f64) -> String {
    let text = format!("{v:.6}");
    let text = text.trim_end_matches('0').trim_end_matches('.');
    if text == "-0" {
        "0".to_owned()
    } else {
        text.to_owned()
    }
}
