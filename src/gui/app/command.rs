//! What the user can ask for: the [`Command`] enum that the menus and the
//! keys produce, and the one place that carries it out
//! ([`RayOfLightApp::run`]), asking first when a command would drop unsaved
//! edits.

use super::dialogs::{Confirm, DialogKind, PathPrompt};
use super::picture::View;
use super::{Interaction, RayOfLightApp};
use crate::gui::document::Document;
use egui::{Key, KeyboardShortcut, Modifiers};
use std::path::{Path, PathBuf};

/// Everything the menus and keys can ask for.
#[derive(Debug, Clone, PartialEq)]
pub enum Command {
    /// The Open dialog.
    Open,
    /// The plain path field for opening.
    OpenPath,
    /// Open this file (Recent, a drop, a dialog's or field's answer).
    OpenFile(PathBuf),
    OpenBuiltin,
    /// Read the file again, dropping unsaved edits.
    Reload,
    Save,
    /// The Save as dialog.
    SaveAs,
    /// The plain path field for Save as.
    SaveAsPath,
    /// Save to this file (asks first if it is another existing file).
    SaveTo(PathBuf),
    Export,
    ExportPath,
    RevertEdits,
    Undo,
    Redo,
    Quit,
    Fit,
    OneToOne,
    ZoomIn,
    ZoomOut,
    CancelRender,
    Study,
    /// Back to the camera the file has (Home).
    CameraFromFile,
    /// Show or hide the list of keys and mouse actions (F1, `?`).
    Help,
    /// Move the selected object with the mouse (G).
    Grab,
    /// The next click on the picture explains its pixel (E).
    Explain,
    /// Show this render pass in place of the picture (View › Pass).
    ShowPass(crate::render::Pass),
    /// Render the scene again (F5): after a cancelled render.
    Render,
    /// Show or hide what is drawn over the picture: light markers, the
    /// selection's outline, the explained ray's path (O).
    Overlays,
    /// Render the preview and exports with N×N rays a pixel (View ›
    /// Anti-aliasing).
    AntiAliasing(u32),
}

/// What runs a command from the keyboard.
#[derive(Debug, Clone, Copy)]
pub(super) enum Trigger {
    /// A chord that works everywhere, also while a text field is typed in.
    Chord(KeyboardShortcut),
    /// A chord that belongs to a text field while one is typed in (undo,
    /// redo).
    EditChord(KeyboardShortcut),
    /// A key pressed alone, not while typing.
    Key(Key),
    /// A character typed, not in a text field (`?`).
    Char(&'static str),
}

impl Trigger {
    /// As the menus and the help show it: `Ctrl+S`, `F1`, `?`.
    pub(super) fn text(&self, ctx: &egui::Context) -> String {
        match self {
            Trigger::Chord(chord) | Trigger::EditChord(chord) => ctx.format_shortcut(chord),
            Trigger::Key(key) => key.symbol_or_name().to_owned(),
            Trigger::Char(c) => (*c).to_owned(),
        }
    }
}

/// A command, its menu label and its keys: the one table the keys, the
/// menus (their shortcut text) and the help window (F1) are made from.
pub(super) struct Binding {
    pub command: Command,
    /// The menu item's text; `""` where no menu shows the command.
    pub label: &'static str,
    /// The keys, the first one shown in the menu.
    pub keys: &'static [Trigger],
    /// What the help window says the keys do; `""`: not listed.
    pub help: &'static str,
}

const fn chord(modifiers: Modifiers, key: Key) -> KeyboardShortcut {
    KeyboardShortcut::new(modifiers, key)
}

const CTRL: Modifiers = Modifiers::COMMAND;
const CTRL_SHIFT: Modifiers = Modifiers::COMMAND.plus(Modifiers::SHIFT);

/// Every command with a fixed label or a key. The keys are tried in this
/// order, so Redo comes before Undo: Ctrl+Shift+Z also matches Ctrl+Z.
pub(super) const BINDINGS: &[Binding] = &[
    Binding {
        command: Command::Open,
        label: "Open…",
        keys: &[Trigger::Chord(chord(CTRL, Key::O))],
        help: "open a scene",
    },
    Binding {
        command: Command::OpenPath,
        label: "Open path…",
        keys: &[],
        help: "",
    },
    Binding {
        command: Command::OpenBuiltin,
        label: "Open built-in example",
        keys: &[],
        help: "",
    },
    Binding {
        command: Command::Reload,
        label: "Reload from disk",
        keys: &[],
        help: "",
    },
    Binding {
        command: Command::Save,
        label: "Save",
        keys: &[Trigger::Chord(chord(CTRL, Key::S))],
        help: "save (merges with changes made by other programs)",
    },
    Binding {
        command: Command::SaveAs,
        label: "Save as…",
        keys: &[],
        help: "",
    },
    Binding {
        command: Command::SaveAsPath,
        label: "Save as path…",
        keys: &[],
        help: "",
    },
    Binding {
        command: Command::RevertEdits,
        label: "Revert edits",
        keys: &[],
        help: "",
    },
    Binding {
        command: Command::Export,
        label: "Export image…",
        keys: &[Trigger::Chord(chord(CTRL, Key::E))],
        help: "export the image",
    },
    Binding {
        command: Command::ExportPath,
        label: "Export to path…",
        keys: &[],
        help: "",
    },
    Binding {
        command: Command::Quit,
        label: "Quit",
        keys: &[Trigger::Chord(chord(CTRL, Key::Q))],
        help: "quit (asks about unsaved edits)",
    },
    Binding {
        command: Command::Redo,
        label: "Redo",
        keys: &[
            Trigger::EditChord(chord(CTRL_SHIFT, Key::Z)),
            Trigger::EditChord(chord(CTRL, Key::Y)),
        ],
        help: "redo",
    },
    Binding {
        command: Command::Undo,
        label: "Undo",
        keys: &[Trigger::EditChord(chord(CTRL, Key::Z))],
        help: "undo",
    },
    Binding {
        command: Command::Fit,
        label: "Fit",
        keys: &[Trigger::Key(Key::F)],
        help: "fit the picture to the window",
    },
    Binding {
        command: Command::OneToOne,
        label: "1:1",
        keys: &[Trigger::Key(Key::Num1)],
        help: "show the picture 1:1",
    },
    Binding {
        command: Command::ZoomIn,
        label: "",
        keys: &[Trigger::Key(Key::Plus), Trigger::Key(Key::Equals)],
        help: "zoom the picture in",
    },
    Binding {
        command: Command::ZoomOut,
        label: "",
        keys: &[Trigger::Key(Key::Minus)],
        help: "zoom the picture out",
    },
    Binding {
        command: Command::CameraFromFile,
        label: "Camera from file",
        keys: &[Trigger::Key(Key::Home)],
        help: "back to the camera the file has",
    },
    Binding {
        command: Command::Study,
        label: "Study…",
        keys: &[],
        help: "",
    },
    Binding {
        command: Command::Help,
        label: "Keys and mouse…",
        keys: &[Trigger::Key(Key::F1), Trigger::Char("?")],
        help: "this list",
    },
    Binding {
        command: Command::Grab,
        label: "",
        keys: &[Trigger::Key(Key::G)],
        help: "move the selected object in the view plane (click: place; Esc, right click: cancel)",
    },
    Binding {
        command: Command::Explain,
        label: "Explain pixel",
        keys: &[Trigger::Key(Key::E)],
        help: "then click: explain the pixel: its rays, hits and the terms of its colour",
    },
    Binding {
        command: Command::Overlays,
        label: "Overlays",
        keys: &[Trigger::Key(Key::O)],
        help: "show or hide the overlays: light markers, outline, ray path",
    },
    Binding {
        command: Command::Render,
        label: "Render again",
        keys: &[Trigger::Key(Key::F5)],
        help: "render again (after Esc)",
    },
    Binding {
        command: Command::CancelRender,
        label: "",
        keys: &[Trigger::Key(Key::Escape)],
        help: "cancel the move or the explain click, close this list, else stop the render",
    },
];

/// The mouse's actions, for the help window beside [`BINDINGS`]' keys.
pub(super) const MOUSE: &[(&str, &str)] = &[
    (
        "drag on the picture",
        "orbit the camera around the point under the cursor",
    ),
    (
        "Shift+drag, middle drag",
        "pan the camera in its view plane",
    ),
    ("mouse wheel", "dolly toward the point under the cursor"),
    ("click", "select the object under the cursor"),
    ("Alt+drag", "move the selected object in the view plane"),
    ("drag a light's marker", "move the light in the view plane"),
    ("Alt+click", "explain the pixel under the cursor"),
    ("Ctrl+wheel", "zoom the picture"),
    ("Ctrl+drag", "pan the picture"),
];

/// The binding of `command`, if the table has one.
pub(super) fn binding(command: &Command) -> Option<&'static Binding> {
    BINDINGS.iter().find(|b| &b.command == command)
}

impl Command {
    /// Whether carrying it out drops unsaved edits.
    pub(super) fn drops_edits(&self) -> bool {
        matches!(
            self,
            Command::OpenFile(_) | Command::OpenBuiltin | Command::Reload | Command::Quit
        )
    }
}

impl RayOfLightApp {
    /// The help window: the mouse's actions, then every key of
    /// [`BINDINGS`].
    pub(super) fn help_window(&mut self, ctx: &egui::Context) {
        let keys: Vec<(String, &str)> = BINDINGS
            .iter()
            .filter(|b| !b.keys.is_empty() && !b.help.is_empty())
            .map(|b| {
                let keys: Vec<String> = b.keys.iter().map(|k| k.text(ctx)).collect();
                (keys.join(", "), b.help)
            })
            .collect();
        let rows = MOUSE
            .iter()
            .map(|&(what, does)| (what.to_owned(), does))
            .chain(keys);
        egui::Window::new("Keys and mouse")
            .open(&mut self.help_open)
            .resizable(false)
            .collapsible(false)
            .show(ctx, |ui| {
                egui::Grid::new("help")
                    .num_columns(2)
                    .striped(true)
                    .show(ui, |ui| {
                        for (keys, action) in rows {
                            ui.strong(keys);
                            ui.label(action);
                            ui.end_row();
                        }
                    });
            });
    }

    /// Carries out a command from a menu or a key. Commands that would drop
    /// unsaved edits ask first.
    pub fn run(&mut self, command: Command) {
        if command == Command::Quit
            && let Some(saving) = &mut self.saving
        {
            saving.then = Some(Command::Quit);
            self.notify("saving: the window closes when the file is written".into());
            return;
        }
        if command.drops_edits() && self.doc.has_unsaved_edits() {
            self.confirm = Some(Confirm::Discard(command));
            return;
        }
        self.execute(command);
    }

    pub(super) fn execute(&mut self, command: Command) {
        match command {
            Command::Open => self.start_dialog(DialogKind::Open),
            Command::OpenPath => self.path_prompt = Some(PathPrompt::new(DialogKind::Open, None)),
            Command::OpenFile(path) => self.open(&path),
            Command::OpenBuiltin => self.replace_document(Document::builtin()),
            Command::Reload => match self.doc.path().map(Path::to_owned) {
                Some(path) => self.open(&path),
                None => self.replace_document(Document::builtin()),
            },
            Command::Save => self.save(),
            Command::SaveAs => self.start_dialog(DialogKind::SaveAs),
            Command::SaveAsPath => {
                let current = self.doc.path().map(|p| p.display().to_string());
                self.path_prompt = Some(PathPrompt::new(DialogKind::SaveAs, current));
            }
            Command::SaveTo(path) => {
                let other_file = path.exists()
                    && self
                        .doc
                        .path()
                        .is_none_or(|current| !crate::files::same_file(current, &path));
                if other_file {
                    self.confirm = Some(Confirm::Replace(path));
                } else {
                    self.save_as(&path);
                }
            }
            Command::Export => self.start_dialog(DialogKind::Export),
            Command::ExportPath => {
                self.path_prompt = Some(PathPrompt::new(DialogKind::Export, None))
            }
            Command::RevertEdits => {
                self.doc.revert();
                self.after_edit();
            }
            Command::Undo => {
                if let Some(label) = self.doc.undo() {
                    self.notify(format!("undid {label}"));
                    self.after_edit();
                }
            }
            Command::Redo => {
                if let Some(label) = self.doc.redo() {
                    self.notify(format!("redid {label}"));
                    self.after_edit();
                }
            }
            Command::Quit => {
                self.allow_close = true;
                self.ctx.send_viewport_cmd(egui::ViewportCommand::Close);
            }
            Command::Fit => self.view = View::fit(),
            Command::OneToOne => self.view = View::one_to_one(),
            Command::ZoomIn => self.view.zoom_by(1.25),
            Command::ZoomOut => self.view.zoom_by(1.0 / 1.25),
            Command::CancelRender => {
                // Esc puts back an object being moved, else disarms the
                // explain click, closes the help, stops opening a file or
                // stops the render, the first that applies.
                if self.interaction.is_grabbing() {
                    self.grab_end(false);
                } else if self.interaction.is_explain_armed() {
                    self.interaction = Interaction::Idle;
                } else if self.help_open {
                    self.help_open = false;
                } else if !self.cancel_loading() {
                    self.worker.cancel();
                    self.preview.cancel();
                }
            }
            Command::Render => self.request_render(),
            Command::Overlays => self.overlays = !self.overlays,
            Command::Grab => {
                let pointer = self.ctx.input(|i| i.pointer.hover_pos());
                self.grab_start(pointer);
            }
            Command::CameraFromFile => self.camera_from_file(),
            // E arms the explain click, or disarms it; not during a drag.
            Command::Explain => match self.interaction {
                Interaction::Idle => self.interaction = Interaction::ExplainArmed,
                Interaction::ExplainArmed => self.interaction = Interaction::Idle,
                _ => {}
            },
            Command::ShowPass(pass) => self.show_pass(pass),
            Command::Help => self.help_open = !self.help_open,
            Command::Study => {
                self.study.open = true;
                self.study.set_plan(self.doc.scene());
            }
            Command::AntiAliasing(aa) => {
                self.aa = aa;
                self.request_render();
            }
        }
    }

    pub(super) fn shortcuts(&mut self, ctx: &egui::Context) {
        // A question on screen takes the keys.
        if self.confirm.is_some() || self.doc.conflict().is_some() || self.path_prompt.is_some() {
            return;
        }
        // Undo, redo and bare keys belong to a text field while one is
        // being typed in.
        let typing = ctx.egui_wants_keyboard_input();
        let mut commands = Vec::new();
        ctx.input_mut(|i| {
            for binding in BINDINGS {
                let pressed = binding.keys.iter().any(|trigger| match trigger {
                    Trigger::Chord(chord) => i.consume_shortcut(chord),
                    Trigger::EditChord(chord) => !typing && i.consume_shortcut(chord),
                    Trigger::Key(key) => !typing && i.modifiers.is_none() && i.key_pressed(*key),
                    Trigger::Char(c) => {
                        !typing
                            && i.events
                                .iter()
                                .any(|e| matches!(e, egui::Event::Text(t) if t == c))
                    }
                });
                if pressed {
                    commands.push(binding.command.clone());
                }
            }
        });
        let dropped: Option<PathBuf> = ctx.input(|i| {
            i.raw
                .dropped_files
                .iter()
                .map(|f| f.path().to_owned())
                .next()
        });
        if let Some(path) = dropped {
            commands.push(Command::OpenFile(path));
        }
        for command in commands {
            self.run(command);
        }
    }

    pub(super) fn menu_bar(&mut self, ui: &mut egui::Ui) {
        let chosen = std::cell::Cell::new(None);
        let ctx = ui.ctx().clone();
        // A menu item: `text` with its command's first key beside it.
        let item = |ui: &mut egui::Ui,
                    enabled: bool,
                    selected: Option<bool>,
                    text: &str,
                    command: Command| {
            let mut button = match selected {
                Some(on) => egui::Button::selectable(on, text),
                None => egui::Button::new(text),
            };
            if let Some(key) = binding(&command).and_then(|b| b.keys.first()) {
                button = button.shortcut_text(key.text(&ctx));
            }
            if ui.add_enabled(enabled, button).clicked() {
                chosen.set(Some(command));
                ui.close();
            }
        };
        // A command's item with the table's label.
        let pick = |ui: &mut egui::Ui, enabled: bool, command: Command| {
            let label = binding(&command).map_or("", |b| b.label);
            item(ui, enabled, None, label, command);
        };
        let dirty = self.doc.has_unsaved_edits();
        let shown_pass = self.pass;
        let has_file = self.doc.path().is_some();
        let undo = self.doc.undo_label().map(|l| format!("Undo {l}"));
        let redo = self.doc.redo_label().map(|l| format!("Redo {l}"));
        egui::MenuBar::new().ui(ui, |ui| {
            ui.menu_button("File", |ui| {
                pick(ui, true, Command::Open);
                pick(ui, true, Command::OpenPath);
                pick(ui, true, Command::OpenBuiltin);
                ui.menu_button("Recent", |ui| {
                    let recent = self.recent.existing();
                    if recent.is_empty() {
                        ui.label("(none)");
                    }
                    for path in &recent {
                        let text = path.display().to_string();
                        item(ui, true, None, &text, Command::OpenFile(path.clone()));
                    }
                });
                pick(ui, has_file, Command::Reload);
                ui.separator();
                pick(ui, true, Command::Save);
                pick(ui, true, Command::SaveAs);
                pick(ui, true, Command::SaveAsPath);
                pick(ui, dirty, Command::RevertEdits);
                ui.separator();
                pick(ui, true, Command::Export);
                pick(ui, true, Command::ExportPath);
                ui.separator();
                pick(ui, true, Command::Quit);
            });
            ui.menu_button("Edit", |ui| {
                let undo_text = undo.as_deref().unwrap_or("Undo");
                item(ui, undo.is_some(), None, undo_text, Command::Undo);
                let redo_text = redo.as_deref().unwrap_or("Redo");
                item(ui, redo.is_some(), None, redo_text, Command::Redo);
            });
            ui.menu_button("View", |ui| {
                pick(ui, true, Command::Fit);
                pick(ui, true, Command::OneToOne);
                pick(ui, true, Command::CameraFromFile);
                pick(ui, true, Command::Study);
                pick(ui, true, Command::Help);
                pick(ui, true, Command::Explain);
                let overlays = binding(&Command::Overlays).map_or("", |b| b.label);
                item(ui, true, Some(self.overlays), overlays, Command::Overlays);
                pick(ui, true, Command::Render);
                ui.menu_button("Pass", |ui| {
                    for pass in crate::render::Pass::ALL {
                        let selected = Some(pass == shown_pass);
                        item(ui, true, selected, pass.name(), Command::ShowPass(pass));
                    }
                });
                ui.separator();
                ui.label("Anti-aliasing");
                for aa in [1, 2, 3, 4] {
                    let text = format!("{aa}×{aa} rays per pixel");
                    item(
                        ui,
                        true,
                        Some(self.aa == aa),
                        &text,
                        Command::AntiAliasing(aa),
                    );
                }
            });
        });
        if let Some(command) = chosen.take() {
            self.run(command);
        }
    }
}
