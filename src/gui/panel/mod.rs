//! The side panel: every value of the scene as a widget.
//!
//! The panel holds no values of its own and never changes the scene: it
//! shows the document's scene and returns the [`Edit`]s the user made this
//! frame, which the app applies through the document (and so through undo).
//! A widget that is only shown can therefore never change a value: drag
//! ranges come from the loader's limits and never clamp a loaded value,
//! numbers are shown in the shortest form that reads back exactly, and
//! pressing Enter in a field without typing changes nothing. The widgets
//! for one value, and the rule that only a real change is an edit, are in
//! `form`; this file lays out the scene's sections.
//!
//! A scene may hold a million objects, so the objects are a list of
//! one-line rows of which only those on screen are laid out each frame,
//! with a search field above it (by number or by the words of the label,
//! computed again only when the query or the scene changes), and the
//! selected object's values below it.

use std::sync::Arc;

use crate::math::{TransformStep, Vec3};
use crate::scene::edit::{
    Axis, Channel, Coef, Edit, Field, Item, NewElement, Owner, StepAttr, Value,
};
use crate::scene::{Illumination, Model};
use crate::session::document::Document;
use egui::{CollapsingHeader, Ui};

mod form;
use form::Form;

/// The object picked in the picture, or the object or light the
/// editor's cursor is in.
#[derive(Debug, Default, Clone, Copy, PartialEq, Eq)]
pub struct Selection {
    pub object: Option<usize>,
    /// A light selected (its marker drawn so): the editor's cursor is in
    /// its element.
    pub light: Option<usize>,
    /// Open and scroll to it once (set by a pick, cleared when done).
    pub reveal: bool,
    /// A value of the object marked in its editor (a term of an
    /// explained pixel clicked: the coefficient it comes from).
    pub field: Option<Field>,
}

impl Selection {
    /// `object` selected and opened in the panel, once: a click in the
    /// picture, or the editor's cursor in its element.
    pub fn revealed(object: Option<usize>) -> Selection {
        Selection {
            object,
            reveal: true,
            ..Selection::default()
        }
    }

    /// Light `light` selected: its marker shows it.
    pub fn light(light: usize) -> Selection {
        Selection {
            light: Some(light),
            ..Selection::default()
        }
    }
}

/// What the user did in the panel this frame.
#[derive(Debug, Default)]
pub struct PanelOutput {
    /// Edits made together (one undo step), if any.
    pub edits: Vec<Edit>,
    /// The edits come from a drag still in progress.
    pub dragging: bool,
    /// A drag of a value ended this frame.
    pub drag_ended: bool,
}

/// The whole panel for `doc`'s scene.
pub fn scene_panel(ui: &mut Ui, doc: &Document, selection: &mut Selection) -> PanelOutput {
    // A marked field belongs to the selected object.
    if selection
        .field
        .is_some_and(|f| field_object(f) != selection.object)
    {
        selection.field = None;
    }
    let mut form = Form {
        scene: doc.scene(),
        out: PanelOutput::default(),
        marked: selection.field,
        reveal: selection.reveal,
    };
    ui.add_enabled_ui(!doc.is_placeholder() && !doc.is_following(), |ui| {
        ui.heading("Illumination");
        model_editor(ui, &mut form);
        ui.separator();
        CollapsingHeader::new("Camera")
            .default_open(true)
            .show(ui, |ui| camera_editor(ui, &mut form));
        ui.separator();
        objects_editor(ui, &mut form, doc, selection);
        ui.separator();
        lights_editor(ui, &mut form);
    });
    selection.reveal = false;
    form.out
}

/// The object a field belongs to, if any.
fn field_object(field: Field) -> Option<usize> {
    match field {
        Field::Color { object, .. } | Field::Material { object, .. } => Some(object),
        _ => None,
    }
}

fn model_editor(ui: &mut Ui, form: &mut Form<'_>) {
    let model = form.scene.model;
    ui.horizontal(|ui| {
        for illumination in Illumination::ALL {
            if ui
                .selectable_label(model.illumination == illumination, illumination.name())
                .clicked()
                && model.illumination != illumination
            {
                form.edit(Edit::Set(Field::ModelType, Value::Model(illumination)));
            }
        }
    });
    ui.add_enabled_ui(model.illumination == Illumination::Whitted, |ui| {
        ui.horizontal(|ui| {
            let label = ui.label("Reflection depth");
            form.integer(ui, Field::ModelDepth, 0..=u64::from(Model::MAX_DEPTH))
                .labelled_by(label.id)
                .on_hover_text("Reflected rays followed from each primary ray (whitted only)");
        });
    });
}

fn camera_editor(ui: &mut Ui, form: &mut Form<'_>) {
    egui::Grid::new("camera").num_columns(2).show(ui, |ui| {
        for (name, field) in [
            ("Width", Field::CameraWidth),
            ("Height", Field::CameraHeight),
        ] {
            let label = ui.label(name);
            form.integer(ui, field, 1..=u64::from(u32::MAX))
                .labelled_by(label.id);
            ui.end_row();
        }
        let label = ui.label("Eye distance");
        form.number(
            ui,
            Field::CameraEyeDistance,
            0.05,
            f64::MIN_POSITIVE..=f64::MAX,
            "",
        )
        .labelled_by(label.id);
        ui.end_row();
    });
    transform_editor(ui, form, Owner::Camera, "camera-transform");
}

/// Rows of the object list shown at once; the rest scroll.
const LIST_ROWS: f32 = 12.0;

/// The object list's search field and what it last found, kept in egui's
/// memory between frames: finding is a pass over every object, done again
/// only when the query or the document's generation changes.
#[derive(Clone, Default)]
struct Search {
    query: String,
    /// The query and generation `found` was computed for, and the objects
    /// it found (`None` for an empty query: every object).
    found: Option<(String, u64, Arc<Vec<usize>>)>,
}

impl Search {
    /// The objects the query finds, from the cache when still good.
    fn found(&mut self, doc: &Document) -> Option<Arc<Vec<usize>>> {
        let query = self.query.trim();
        if query.is_empty() {
            self.found = None;
            return None;
        }
        let fresh = self
            .found
            .as_ref()
            .is_some_and(|(q, g, _)| q == query && *g == doc.generation());
        if !fresh {
            let found = Arc::new(doc.find_objects(query));
            self.found = Some((query.to_owned(), doc.generation(), found));
        }
        self.found.as_ref().map(|(_, _, f)| f.clone())
    }
}

/// The objects as a list of one-line rows, of which only those on screen
/// are laid out (a scene may hold a million), a search field above it, and
/// below it the selected object's values.
fn objects_editor(ui: &mut Ui, form: &mut Form<'_>, doc: &Document, selection: &mut Selection) {
    let scene = form.scene;
    ui.horizontal(|ui| {
        ui.heading(format!("Objects ({})", scene.objects.len()));
        for &shape in crate::scene::Shape::ALL {
            if ui.small_button(format!("+ {}", shape.name())).clicked() {
                form.edit(Edit::add(scene, NewElement::Object(shape)));
            }
        }
    });
    let id = ui.make_persistent_id("object-search");
    let mut search: Search = ui.data_mut(|d| d.get_temp(id)).unwrap_or_default();
    ui.horizontal(|ui| {
        let label = ui.label("Find");
        ui.add(
            egui::TextEdit::singleline(&mut search.query)
                .hint_text("#12 or words of the label")
                .desired_width(f32::INFINITY),
        )
        .labelled_by(label.id);
    });
    let found = search.found(doc);
    ui.data_mut(|d| d.insert_temp(id, search));
    let rows = found.as_ref().map_or(scene.objects.len(), |f| f.len());
    let object_at = |row: usize| found.as_ref().map_or(Some(row), |f| f.get(row).copied());

    let row_height = ui.spacing().interact_size.y;
    let mut list = egui::ScrollArea::vertical()
        .id_salt("object-list")
        .max_height((row_height + ui.spacing().item_spacing.y) * LIST_ROWS)
        .auto_shrink([false, true]);
    // A pick in the picture scrolls its row into view once.
    let picked = selection.object.filter(|_| selection.reveal);
    if let Some(object) = picked {
        let row = found
            .as_ref()
            .map_or(Some(object), |f| f.binary_search(&object).ok());
        if let Some(row) = row {
            let spaced = row_height + ui.spacing().item_spacing.y;
            let top = (row as f32 - (LIST_ROWS / 2.0).floor()).max(0.0) * spaced;
            list = list.vertical_scroll_offset(top);
        }
    }
    list.show_rows(ui, row_height, rows, |ui, range| {
        for row in range {
            let Some(object) = object_at(row) else {
                continue;
            };
            let is_selected = selection.object == Some(object);
            // The label at the left, like a list's rows (a grow after it
            // takes the rest of the row's width).
            let button =
                egui::Button::selectable(is_selected, doc.object_label(object)).right_text(());
            if ui
                .add_sized([ui.available_width(), row_height], button)
                .clicked()
            {
                selection.object = Some(object);
            }
        }
    });
    if found.as_ref().is_some_and(|f| f.is_empty()) {
        ui.weak("No object found");
    }

    let Some(object) = selection.object.filter(|&o| o < scene.objects.len()) else {
        return;
    };
    let title = egui::RichText::new(format!("Edit {}", doc.object_label(object))).strong();
    let mut header = CollapsingHeader::new(title)
        .id_salt(("object", object))
        .default_open(true);
    // A pick in the picture opens the object once; after that the header
    // folds as the user likes.
    if selection.reveal {
        header = header.open(Some(true));
    }
    let response = header.show(ui, |ui| {
        color_editor(ui, form, |channel| Field::Color { object, channel });
        material_editor(ui, form, object);
        transform_editor(
            ui,
            form,
            Owner::Object(object),
            ("object-transform", object),
        );
        if ui.small_button("Remove object").clicked() {
            form.edit(Edit::Remove(Item::Object(object)));
        }
    });
    // (A marked field scrolls to itself.)
    if selection.reveal && selection.field.is_none() {
        response.header_response.scroll_to_me(None);
    }
}

fn lights_editor(ui: &mut Ui, form: &mut Form<'_>) {
    let scene = form.scene;
    ui.horizontal(|ui| {
        ui.heading(format!("Lights ({})", scene.lights.len()));
        if ui.small_button("+ light").clicked() {
            form.edit(Edit::add(scene, NewElement::Light));
        }
    });
    for light in 0..scene.lights.len() {
        CollapsingHeader::new(format!("Light {}", light + 1))
            .id_salt(("light", light))
            .default_open(light < 4)
            .show(ui, |ui| {
                ui.horizontal(|ui| {
                    ui.label("Position");
                    for axis in [Axis::X, Axis::Y, Axis::Z] {
                        let field = Field::LightPosition { light, axis };
                        let prefix = format!("{} ", axis.name());
                        form.number(ui, field, 0.05, f64::MIN..=f64::MAX, &prefix);
                    }
                });
                color_editor(ui, form, |channel| Field::LightColor { light, channel });
                if ui.small_button("Remove light").clicked() {
                    form.edit(Edit::Remove(Item::Light(light)));
                }
            });
    }
}

/// A colour: a picker for values in [0, 1] and exact fields, which also
/// take values above 1 (a light of colour 2 is twice as bright).
fn color_editor(ui: &mut Ui, form: &mut Form<'_>, field: impl Fn(Channel) -> Field) {
    let channels = [Channel::Red, Channel::Green, Channel::Blue];
    let value = |channel| match field(channel).get(form.scene) {
        Ok(Value::Number(v)) => v,
        _ => 0.0,
    };
    let color = Vec3::new(
        value(Channel::Red),
        value(Channel::Green),
        value(Channel::Blue),
    );
    ui.horizontal(|ui| {
        ui.label("Colour");
        let old = [color.x as f32, color.y as f32, color.z as f32];
        let mut rgb = old;
        let response = ui.color_edit_button_rgb(&mut rgb);
        if response.changed() {
            // Only the channels the picker moved: the others keep their
            // exact values (f32 would round them).
            for (i, channel) in channels.into_iter().enumerate() {
                if rgb[i] != old[i] {
                    form.set(field(channel), Value::Number(f64::from(rgb[i])), &response);
                }
            }
        }
        for channel in channels {
            let prefix = format!("{} ", &channel.name()[..1].to_uppercase());
            form.number(ui, field(channel), 0.01, 0.0..=f64::MAX, &prefix);
        }
    });
}

fn material_editor(ui: &mut Ui, form: &mut Form<'_>, object: usize) {
    egui::Grid::new(("material", object))
        .num_columns(2)
        .show(ui, |ui| {
            for coef in Coef::ALL {
                let label = ui.label(coef.name()).on_hover_text(coef.hint());
                let speed = if coef == Coef::M { 0.5 } else { 0.01 };
                form.number(
                    ui,
                    Field::Material { object, coef },
                    speed,
                    0.0..=f64::MAX,
                    "",
                )
                .labelled_by(label.id);
                ui.end_row();
            }
        });
}

/// The steps of a transformation: each editable or removable, new ones
/// appended.
fn transform_editor(
    ui: &mut Ui,
    form: &mut Form<'_>,
    owner: Owner,
    id: impl std::hash::Hash + std::fmt::Debug,
) {
    let steps: Vec<TransformStep> = match owner {
        Owner::Camera => form.scene.camera.transform.steps().to_vec(),
        Owner::Object(n) => form.scene.objects[n].transform.steps().to_vec(),
    };
    let title = match steps.len() {
        1 => "Transformation (1 step)".to_owned(),
        n => format!("Transformation ({n} steps)"),
    };
    CollapsingHeader::new(title).id_salt(id).show(ui, |ui| {
        for (k, step) in steps.iter().enumerate() {
            // Wrapped, so that a long row does not widen the panel.
            ui.horizontal_wrapped(|ui| {
                step_editor(ui, form, owner, k, step);
                if ui
                    .small_button("×")
                    .on_hover_text("Remove this step")
                    .clicked()
                {
                    form.edit(Edit::Remove(Item::Step(owner, k)));
                }
            });
        }
        ui.horizontal(|ui| {
            ui.label("Add");
            for (label, step) in [
                ("translate", TransformStep::Translate(Vec3::ZERO)),
                ("rotate-x", TransformStep::RotateX(0.0)),
                ("rotate-y", TransformStep::RotateY(0.0)),
                ("rotate-z", TransformStep::RotateZ(0.0)),
                ("scale", TransformStep::UniformScale(1.0)),
            ] {
                if ui.small_button(label).clicked()
                    && let Ok(edit) = Edit::add_step(form.scene, owner, step)
                {
                    form.edit(edit);
                }
            }
        });
    });
}

fn step_editor(ui: &mut Ui, form: &mut Form<'_>, owner: Owner, k: usize, step: &TransformStep) {
    let field = |attr| Field::Step {
        owner,
        step: k,
        attr,
    };
    let xyz = |ui: &mut Ui, form: &mut Form<'_>, speed| {
        for (attr, name) in [
            (StepAttr::X, "x "),
            (StepAttr::Y, "y "),
            (StepAttr::Z, "z "),
        ] {
            form.number(ui, field(attr), speed, f64::MIN..=f64::MAX, name);
        }
    };
    ui.label(crate::scene::edit::step_name(step));
    match step {
        TransformStep::Translate(_) => xyz(ui, form, 0.05),
        TransformStep::Scale(_) => xyz(ui, form, 0.01),
        TransformStep::RotateX(_) | TransformStep::RotateY(_) | TransformStep::RotateZ(_) => {
            form.angle(ui, field(StepAttr::Angle));
        }
        TransformStep::UniformScale(_) => {
            form.number(ui, field(StepAttr::Factor), 0.01, f64::MIN..=f64::MAX, "");
        }
    }
}
