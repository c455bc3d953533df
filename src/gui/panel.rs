//! The side panel: every value of the scene as a widget. Each function
//! edits the scene in place and returns whether anything changed, so the
//! app can ask for a new render at once.

use crate::math::{Transform, TransformStep, Vec3};
use crate::scene::{Illumination, Light, Material, Model, Object, Scene, Shape};
use egui::{CollapsingHeader, DragValue, Ui};

/// The whole panel. `selected` is the object picked in the image, opened
/// and highlighted here.
pub fn scene_panel(ui: &mut Ui, scene: &mut Scene, selected: &mut Option<usize>) -> bool {
    let mut changed = false;
    ui.heading("Illumination");
    changed |= model_editor(ui, &mut scene.model);
    ui.separator();
    CollapsingHeader::new("Camera")
        .default_open(true)
        .show(ui, |ui| changed |= camera_editor(ui, scene));
    ui.separator();
    changed |= objects_editor(ui, &mut scene.objects, selected);
    ui.separator();
    changed |= lights_editor(ui, &mut scene.lights);
    changed
}

fn model_editor(ui: &mut Ui, model: &mut Model) -> bool {
    let mut changed = false;
    ui.horizontal(|ui| {
        for illumination in Illumination::ALL {
            changed |= ui
                .selectable_value(&mut model.illumination, illumination, illumination.name())
                .changed();
        }
    });
    ui.add_enabled_ui(model.illumination == Illumination::Whitted, |ui| {
        ui.horizontal(|ui| {
            let label = ui.label("Reflection depth");
            changed |= ui
                .add(DragValue::new(&mut model.depth).range(0..=Model::MAX_DEPTH))
                .labelled_by(label.id)
                .on_hover_text("Reflected rays followed from each primary ray (whitted only)")
                .changed();
        });
    });
    changed
}

fn camera_editor(ui: &mut Ui, scene: &mut Scene) -> bool {
    let camera = &mut scene.camera;
    let mut changed = false;
    egui::Grid::new("camera").num_columns(2).show(ui, |ui| {
        let label = ui.label("Width");
        changed |= ui
            .add(DragValue::new(&mut camera.width).range(1..=8192))
            .labelled_by(label.id)
            .changed();
        ui.end_row();
        let label = ui.label("Height");
        changed |= ui
            .add(DragValue::new(&mut camera.height).range(1..=8192))
            .labelled_by(label.id)
            .changed();
        ui.end_row();
        let label = ui.label("Eye distance");
        changed |= ui
            .add(
                DragValue::new(&mut camera.eye_distance)
                    .speed(0.05)
                    .range(1e-6..=1e6),
            )
            .labelled_by(label.id)
            .changed();
        ui.end_row();
    });
    changed |= transform_editor(ui, "camera-transform", &mut camera.transform);
    changed
}

fn objects_editor(ui: &mut Ui, objects: &mut Vec<Object>, selected: &mut Option<usize>) -> bool {
    let mut changed = false;
    ui.horizontal(|ui| {
        ui.heading(format!("Objects ({})", objects.len()));
        if ui.small_button("+ sphere").clicked() {
            objects.push(new_object(Shape::Sphere));
            changed = true;
        }
        if ui.small_button("+ plane").clicked() {
            objects.push(new_object(Shape::Plane));
            changed = true;
        }
    });
    let mut remove = None;
    for (index, object) in objects.iter_mut().enumerate() {
        let is_selected = *selected == Some(index);
        let title = format!("#{} {}", index + 1, object.shape.name());
        let header = CollapsingHeader::new(if is_selected {
            egui::RichText::new(title).strong()
        } else {
            egui::RichText::new(title)
        })
        .id_salt(("object", index));
        let header = if is_selected {
            header.open(Some(true))
        } else {
            header
        };
        let response = header.show(ui, |ui| {
            changed |= color_editor(ui, &mut object.color);
            changed |= material_editor(ui, index, &mut object.material);
            changed |= transform_editor(ui, ("object-transform", index), &mut object.transform);
            if ui.small_button("Remove object").clicked() {
                remove = Some(index);
            }
        });
        if response.header_response.clicked() {
            *selected = Some(index);
        }
        if is_selected {
            response.header_response.scroll_to_me(None);
        }
    }
    if let Some(index) = remove {
        objects.remove(index);
        *selected = None;
        changed = true;
    }
    changed
}

fn new_object(shape: Shape) -> Object {
    Object {
        shape,
        color: Vec3::ONE,
        material: Material::default(),
        transform: Transform::default(),
    }
}

fn lights_editor(ui: &mut Ui, lights: &mut Vec<Light>) -> bool {
    let mut changed = false;
    ui.horizontal(|ui| {
        ui.heading(format!("Lights ({})", lights.len()));
        if ui.small_button("+ light").clicked() {
            lights.push(Light {
                position: Vec3::new(0.0, -5.0, -5.0),
                color: Vec3::ONE,
            });
            changed = true;
        }
    });
    let mut remove = None;
    for (index, light) in lights.iter_mut().enumerate() {
        CollapsingHeader::new(format!("Light {}", index + 1))
            .id_salt(("light", index))
            .default_open(lights_open_by_default(index))
            .show(ui, |ui| {
                ui.horizontal(|ui| {
                    ui.label("Position");
                    changed |= vec3_editor(ui, &mut light.position, 0.05);
                });
                changed |= color_editor(ui, &mut light.color);
                if ui.small_button("Remove light").clicked() {
                    remove = Some(index);
                }
            });
    }
    if let Some(index) = remove {
        lights.remove(index);
        changed = true;
    }
    changed
}

fn lights_open_by_default(index: usize) -> bool {
    index < 4
}

/// A colour: a picker for values in [0, 1] and exact fields, which also
/// take values above 1 (a light of colour 2 is twice as bright).
fn color_editor(ui: &mut Ui, color: &mut Vec3) -> bool {
    let mut changed = false;
    ui.horizontal(|ui| {
        ui.label("Colour");
        let mut rgb = [color.x as f32, color.y as f32, color.z as f32];
        if ui.color_edit_button_rgb(&mut rgb).changed() {
            *color = Vec3::new(f64::from(rgb[0]), f64::from(rgb[1]), f64::from(rgb[2]));
            changed = true;
        }
        for (value, name) in [
            (&mut color.x, "R"),
            (&mut color.y, "G"),
            (&mut color.z, "B"),
        ] {
            changed |= ui
                .add(
                    DragValue::new(value)
                        .speed(0.01)
                        .range(0.0..=f64::MAX)
                        .prefix(format!("{name} ")),
                )
                .changed();
        }
    });
    changed
}

fn material_editor(ui: &mut Ui, index: usize, material: &mut Material) -> bool {
    let mut changed = false;
    egui::Grid::new(("material", index))
        .num_columns(2)
        .show(ui, |ui| {
            for (name, value, max, hint) in [
                ("ka", &mut material.ka, 1.0, "ambient coefficient"),
                ("kd", &mut material.kd, 1.0, "diffuse coefficient"),
                (
                    "ks",
                    &mut material.ks,
                    1.0,
                    "specular and reflection coefficient",
                ),
                ("m", &mut material.m, 200.0, "specular exponent (shininess)"),
            ] {
                let label = ui.label(name).on_hover_text(hint);
                changed |= ui
                    .add(egui::Slider::new(value, 0.0..=max).clamping(egui::SliderClamping::Never))
                    .labelled_by(label.id)
                    .changed();
                if *value < 0.0 {
                    *value = 0.0;
                }
                ui.end_row();
            }
        });
    changed
}

fn vec3_editor(ui: &mut Ui, v: &mut Vec3, speed: f64) -> bool {
    let mut changed = false;
    for (value, name) in [(&mut v.x, "x"), (&mut v.y, "y"), (&mut v.z, "z")] {
        changed |= ui
            .add(
                DragValue::new(value)
                    .speed(speed)
                    .prefix(format!("{name} ")),
            )
            .changed();
    }
    changed
}

/// The steps of a transformation, editable, reorderable by removal and
/// addition. A singular result (a zero scale) is not applied.
fn transform_editor(
    ui: &mut Ui,
    id: impl std::hash::Hash + std::fmt::Debug,
    transform: &mut Transform,
) -> bool {
    let mut steps = transform.steps().to_vec();
    let mut edited = false;
    let mut remove = None;
    let title = match steps.len() {
        1 => "Transformation (1 step)".to_owned(),
        n => format!("Transformation ({n} steps)"),
    };
    CollapsingHeader::new(title).id_salt(id).show(ui, |ui| {
        for (index, step) in steps.iter_mut().enumerate() {
            ui.horizontal(|ui| {
                edited |= step_editor(ui, step);
                if ui
                    .small_button("✖")
                    .on_hover_text("Remove this step")
                    .clicked()
                {
                    remove = Some(index);
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
                if ui.small_button(label).clicked() {
                    steps.push(step);
                    edited = true;
                }
            }
        });
    });
    if let Some(index) = remove {
        steps.remove(index);
        edited = true;
    }
    if !edited {
        return false;
    }
    match Transform::from_steps(steps) {
        Ok(t) => {
            *transform = t;
            true
        }
        Err(_) => false,
    }
}

fn step_editor(ui: &mut Ui, step: &mut TransformStep) -> bool {
    match step {
        TransformStep::Translate(v) => {
            ui.label("translate");
            vec3_editor(ui, v, 0.05)
        }
        TransformStep::RotateX(a) => {
            ui.label("rotate-x");
            angle_editor(ui, a)
        }
        TransformStep::RotateY(a) => {
            ui.label("rotate-y");
            angle_editor(ui, a)
        }
        TransformStep::RotateZ(a) => {
            ui.label("rotate-z");
            angle_editor(ui, a)
        }
        TransformStep::UniformScale(f) => {
            ui.label("scale");
            ui.add(DragValue::new(f).speed(0.01)).changed()
        }
        TransformStep::Scale(v) => {
            ui.label("scale");
            vec3_editor(ui, v, 0.01)
        }
    }
}

/// An angle shown in degrees, stored in radians as the file says.
fn angle_editor(ui: &mut Ui, radians: &mut f64) -> bool {
    let mut degrees = radians.to_degrees();
    let changed = ui
        .add(DragValue::new(&mut degrees).speed(1.0).suffix("°"))
        .changed();
    if changed {
        *radians = degrees.to_radians();
    }
    changed
}
