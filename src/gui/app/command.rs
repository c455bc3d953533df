//! What the user can ask for: the [`Command`] enum that the menus and the
//! keys produce, and the one place that carries it out
//! ([`RayOfLightApp::run`]), asking first when a command would drop unsaved
//! edits.

use super::*;

pub(super) const OPEN: KeyboardShortcut = KeyboardShortcut::new(Modifiers::COMMAND, Key::O);

pub(super) const SAVE: KeyboardShortcut = KeyboardShortcut::new(Modifiers::COMMAND, Key::S);

pub(super) const EXPORT: KeyboardShortcut = KeyboardShortcut::new(Modifiers::COMMAND, Key::E);

pub(super) const QUIT: KeyboardShortcut = KeyboardShortcut::new(Modifiers::COMMAND, Key::Q);

pub(super) const UNDO: KeyboardShortcut = KeyboardShortcut::new(Modifiers::COMMAND, Key::Z);

pub(super) const REDO: KeyboardShortcut =
    KeyboardShortcut::new(Modifiers::COMMAND.plus(Modifiers::SHIFT), Key::Z);

pub(super) const REDO_Y: KeyboardShortcut = KeyboardShortcut::new(Modifiers::COMMAND, Key::Y);

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
}

/// Every key and mouse action, for the help window (F1).
pub const HELP: &[(&str, &str)] = &[
    (
        "drag on the picture",
        "orbit the camera around the point under the cursor",
    ),
    (
        "Shift+drag, middle drag",
        "pan the camera in its view plane",
    ),
    ("mouse wheel", "dolly toward the point under the cursor"),
    ("Home", "back to the camera the file has"),
    ("click", "select the object under the cursor"),
    (
        "G, Alt+drag",
        "move the selected object in the view plane (click: place; Esc, right click: cancel)",
    ),
    ("drag a light's marker", "move the light in the view plane"),
    (
        "E then click, Alt+click",
        "explain the pixel: its rays, hits and the terms of its colour",
    ),
    ("Ctrl+wheel, + / -", "zoom the picture"),
    ("Ctrl+drag", "pan the picture"),
    ("F / 1", "fit the picture / show it 1:1"),
    (
        "Esc",
        "cancel the move or the explain click, close this list, else stop the render",
    ),
    ("F5", "render again (after Esc)"),
    (
        "O",
        "show or hide the overlays: light markers, outline, ray path",
    ),
    ("Ctrl+Z", "undo"),
    ("Ctrl+Shift+Z, Ctrl+Y", "redo"),
    (
        "Ctrl+S",
        "save (merges with changes made by other programs)",
    ),
    ("Ctrl+O", "open a scene"),
    ("Ctrl+E", "export the image"),
    ("Ctrl+Q", "quit (asks about unsaved edits)"),
    ("F1, ?", "this list"),
];

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
    /// The help window: [`HELP`] as a table.
    pub(super) fn help_window(&mut self, ctx: &egui::Context) {
        egui::Window::new("Keys and mouse")
            .open(&mut self.help_open)
            .resizable(false)
            .collapsible(false)
            .show(ctx, |ui| {
                egui::Grid::new("help")
                    .num_columns(2)
                    .striped(true)
                    .show(ui, |ui| {
                        for (keys, action) in HELP {
                            ui.strong(*keys);
                            ui.label(*action);
                            ui.end_row();
                        }
                    });
            });
    }

    /// Carries out a command from a menu or a key. Commands that would drop
    /// unsaved edits ask first.
    pub fn run(&mut self, command: Command) {
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
                        .is_none_or(|current| !dialogs::same_file(current, &path));
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
                if self.grab.is_some() {
                    self.grab_end(false);
                } else if self.explain_armed {
                    self.explain_armed = false;
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
            Command::Explain => self.explain_armed = !self.explain_armed,
            Command::ShowPass(pass) => self.show_pass(pass),
            Command::Help => self.help_open = !self.help_open,
            Command::Study => {
                self.study.open = true;
                self.study.set_plan(self.doc.scene());
            }
        }
    }

    pub(super) fn shortcuts(&mut self, ctx: &egui::Context) {
        // A question on screen takes the keys.
        if self.confirm.is_some() || self.doc.conflict().is_some() || self.path_prompt.is_some() {
            return;
        }
        let mut commands = Vec::new();
        // Redo before undo: Ctrl+Shift+Z also matches Ctrl+Z.
        for (shortcut, command) in [
            (OPEN, Command::Open),
            (SAVE, Command::Save),
            (EXPORT, Command::Export),
            (QUIT, Command::Quit),
        ] {
            if ctx.input_mut(|i| i.consume_shortcut(&shortcut)) {
                commands.push(command);
            }
        }
        // Undo and redo belong to a text field while one is being typed in.
        if !ctx.egui_wants_keyboard_input() {
            for (shortcut, command) in [
                (REDO, Command::Redo),
                (REDO_Y, Command::Redo),
                (UNDO, Command::Undo),
            ] {
                if ctx.input_mut(|i| i.consume_shortcut(&shortcut)) {
                    commands.push(command);
                }
            }
            ctx.input(|i| {
                for (key, command) in [
                    (Key::F, Command::Fit),
                    (Key::Num1, Command::OneToOne),
                    (Key::Plus, Command::ZoomIn),
                    (Key::Equals, Command::ZoomIn),
                    (Key::Minus, Command::ZoomOut),
                    (Key::Escape, Command::CancelRender),
                    (Key::Home, Command::CameraFromFile),
                    (Key::F1, Command::Help),
                    (Key::G, Command::Grab),
                    (Key::E, Command::Explain),
                    (Key::F5, Command::Render),
                    (Key::O, Command::Overlays),
                ] {
                    if i.key_pressed(key) && i.modifiers.is_none() {
                        commands.push(command);
                    }
                }
                if i.events
                    .iter()
                    .any(|e| matches!(e, egui::Event::Text(t) if t == "?"))
                {
                    commands.push(Command::Help);
                }
            });
        }
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
        let pick = |ui: &mut egui::Ui, enabled: bool, text: &str, command: Command| {
            if ui.add_enabled(enabled, egui::Button::new(text)).clicked() {
                chosen.set(Some(command));
                ui.close();
            }
        };
        let dirty = self.doc.has_unsaved_edits();
        let shown_pass = self.pass;
        let has_file = self.doc.path().is_some();
        let undo = self.doc.undo_label().map(|l| format!("Undo {l}  Ctrl+Z"));
        let redo = self
            .doc
            .redo_label()
            .map(|l| format!("Redo {l}  Ctrl+Shift+Z"));
        egui::MenuBar::new().ui(ui, |ui| {
            ui.menu_button("File", |ui| {
                pick(ui, true, "Open…  Ctrl+O", Command::Open);
                pick(ui, true, "Open path…", Command::OpenPath);
                pick(ui, true, "Open built-in example", Command::OpenBuiltin);
                ui.menu_button("Recent", |ui| {
                    let recent = self.recent.existing();
                    if recent.is_empty() {
                        ui.label("(none)");
                    }
                    for path in &recent {
                        pick(
                            ui,
                            true,
                            &path.display().to_string(),
                            Command::OpenFile(path.clone()),
                        );
                    }
                });
                pick(ui, has_file, "Reload from disk", Command::Reload);
                ui.separator();
                pick(ui, true, "Save  Ctrl+S", Command::Save);
                pick(ui, true, "Save as…", Command::SaveAs);
                pick(ui, true, "Save as path…", Command::SaveAsPath);
                pick(ui, dirty, "Revert edits", Command::RevertEdits);
                ui.separator();
                pick(ui, true, "Export image…  Ctrl+E", Command::Export);
                pick(ui, true, "Export to path…", Command::ExportPath);
                ui.separator();
                pick(ui, true, "Quit  Ctrl+Q", Command::Quit);
            });
            ui.menu_button("Edit", |ui| {
                pick(
                    ui,
                    undo.is_some(),
                    undo.as_deref().unwrap_or("Undo  Ctrl+Z"),
                    Command::Undo,
                );
                pick(
                    ui,
                    redo.is_some(),
                    redo.as_deref().unwrap_or("Redo  Ctrl+Shift+Z"),
                    Command::Redo,
                );
            });
            ui.menu_button("View", |ui| {
                pick(ui, true, "Fit  F", Command::Fit);
                pick(ui, true, "1:1  1", Command::OneToOne);
                pick(ui, true, "Camera from file  Home", Command::CameraFromFile);
                pick(ui, true, "Study…", Command::Study);
                pick(ui, true, "Keys and mouse…  F1", Command::Help);
                pick(ui, true, "Explain pixel  E", Command::Explain);
                let overlays = self.overlays;
                if ui
                    .add(egui::Button::selectable(overlays, "Overlays  O"))
                    .on_hover_text(
                        "light markers, the selection's outline, the explained ray's path",
                    )
                    .clicked()
                {
                    chosen.set(Some(Command::Overlays));
                    ui.close();
                }
                pick(ui, true, "Render again  F5", Command::Render);
                ui.menu_button("Pass", |ui| {
                    for pass in crate::render::Pass::ALL {
                        let button = egui::Button::selectable(pass == shown_pass, pass.name());
                        if ui.add(button).clicked() {
                            chosen.set(Some(Command::ShowPass(pass)));
                            ui.close();
                        }
                    }
                });
                ui.separator();
                ui.label("Anti-aliasing");
                for aa in [1, 2, 3, 4] {
                    if ui
                        .selectable_label(self.aa == aa, format!("{aa}×{aa} rays per pixel"))
                        .clicked()
                    {
                        self.aa = aa;
                        self.request_render();
                    }
                }
            });
        });
        if let Some(command) = chosen.take() {
            // Quit goes through the window's close, which asks about edits.
            if command == Command::Quit {
                self.ctx.send_viewport_cmd(egui::ViewportCommand::Close);
            } else {
                self.run(command);
            }
        }
    }
}
