//! The menu bar, the keys and the help window, all read from the one
//! binding table ([`BINDINGS`]), and the one place that carries a
//! [`Command`] out ([`RayOfLightApp::run`]), asking first when a command
//! would drop unsaved edits.

use super::command::{BINDINGS, Command, MOUSE, Trigger, binding};
use super::dialogs::{Confirm, DialogKind, PathPrompt};
use super::picture::View;
use super::{Interaction, RayOfLightApp};
use crate::session::document::Document;
use std::path::{Path, PathBuf};

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
            .open(&mut self.dialogs.help)
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
            && let Some(saving) = &mut self.dialogs.saving
        {
            saving.then = Some(Command::Quit);
            self.notify("saving: the window closes when the file is written".into());
            return;
        }
        if command.drops_edits() && self.doc.has_unsaved_edits() {
            self.dialogs.confirm = Some(Confirm::Discard(command));
            return;
        }
        self.execute(command);
    }

    pub(super) fn execute(&mut self, command: Command) {
        match command {
            Command::Open => self.start_dialog(DialogKind::Open),
            Command::OpenPath => {
                self.dialogs.path_prompt = Some(PathPrompt::new(DialogKind::Open, None))
            }
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
                self.dialogs.path_prompt = Some(PathPrompt::new(DialogKind::SaveAs, current));
            }
            Command::SaveTo(path) => {
                let other_file = path.exists()
                    && self
                        .doc
                        .path()
                        .is_none_or(|current| !crate::system::files::same_file(current, &path));
                if other_file {
                    self.dialogs.confirm = Some(Confirm::Replace(path));
                } else {
                    self.save_as(&path);
                }
            }
            Command::Export => self.start_dialog(DialogKind::Export),
            Command::ExportPath => {
                self.dialogs.path_prompt = Some(PathPrompt::new(DialogKind::Export, None))
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
                self.ending.allow_close = true;
                self.ctx.send_viewport_cmd(egui::ViewportCommand::Close);
            }
            Command::Fit => self.screen.view = View::fit(),
            Command::OneToOne => self.screen.view = View::one_to_one(),
            Command::ZoomIn => self.screen.view.zoom_by(1.25),
            Command::ZoomOut => self.screen.view.zoom_by(1.0 / 1.25),
            Command::CancelRender => {
                // Esc puts back an object being moved, else disarms the
                // explain click, closes the help, stops opening a file or
                // stops the render, the first that applies.
                if self.screen.interaction.is_grabbing() {
                    self.grab_end(false);
                } else if self.screen.interaction.is_explain_armed() {
                    self.screen.interaction = Interaction::Idle;
                } else if self.dialogs.help {
                    self.dialogs.help = false;
                } else if !self.cancel_loading() {
                    self.worker.cancel();
                    self.preview.cancel();
                }
            }
            Command::Render => self.request_render(),
            Command::Overlays => self.overlay.shown = !self.overlay.shown,
            Command::Grab => {
                let pointer = self.ctx.input(|i| i.pointer.hover_pos());
                self.grab_start(pointer);
            }
            Command::CameraFromFile => self.camera_from_file(),
            // E arms the explain click, or disarms it; not during a drag.
            Command::Explain => match self.screen.interaction {
                Interaction::Idle => self.screen.interaction = Interaction::ExplainArmed,
                Interaction::ExplainArmed => self.screen.interaction = Interaction::Idle,
                _ => {}
            },
            Command::ShowPass(pass) => self.show_pass(pass),
            Command::Help => self.dialogs.help = !self.dialogs.help,
            Command::Study => {
                self.study.open = true;
                self.study.set_plan(self.doc.scene());
            }
            Command::AntiAliasing(aa) => {
                self.choice.aa = aa;
                self.request_render();
            }
            Command::OpenInEditor => self.open_in_editor(),
        }
    }

    /// Edit › Open in editor: the scene file, at the selected object's
    /// element (the top of the file when none is selected).
    pub(super) fn open_in_editor(&mut self) {
        use crate::session::editor;
        let Some(path) = self.doc.path().map(Path::to_owned) else {
            self.notify("the built-in example has no file: save it first (File › Save as)".into());
            return;
        };
        let env = editor::Environment::current();
        let Some(chosen) = editor::resolve(&env, self.kept.settings.editor.as_deref()) else {
            self.notify(editor::EditorError::NoEditor.to_string());
            return;
        };
        let selected = self.selection.object;
        let position = selected.and_then(|n| self.doc.object_position(n));
        let (line, column) = position.map_or((1, 1), |p| (p.line, p.column));
        let started = editor::command_line(&chosen, &env, &path, line, column).and_then(|argv| {
            let sender = self.editors.failed.0.clone();
            let ctx = self.ctx.clone();
            editor::start(&argv, chosen.source, move |said| {
                let _ = sender.send(said);
                ctx.request_repaint();
            })
            .map(|()| argv[0].clone())
        });
        let name = path.file_name().map_or_else(
            || path.display().to_string(),
            |n| n.to_string_lossy().into_owned(),
        );
        match started {
            Ok(program) => {
                let mut said = format!("opened {name}:{line} in {program}");
                if selected.is_some() && position.is_none() {
                    said.push_str(" (the selected object is not saved in the file yet)");
                } else if self.doc.has_unsaved_edits() {
                    said.push_str(" (the file, without the unsaved edits)");
                }
                self.notify(said);
            }
            Err(e) => self.notify(e.to_string()),
        }
    }

    pub(super) fn shortcuts(&mut self, ctx: &egui::Context) {
        // A question on screen takes the keys.
        if self.dialogs.confirm.is_some()
            || self.doc.conflict().is_some()
            || self.dialogs.path_prompt.is_some()
        {
            return;
        }
        // Undo, redo and bare keys belong to a text field while one is
        // being typed in.
        let typing = ctx.egui_wants_keyboard_input();
        let mut commands = Vec::new();
        ctx.input_mut(|i| {
            for binding in BINDINGS {
                // Every press counts: five Ctrl+Z that come in one frame
                // (a held key repeats that fast) undo five steps.
                let presses: usize = binding
                    .keys
                    .iter()
                    .map(|trigger| match trigger {
                        Trigger::Chord(chord) => {
                            i.count_and_consume_key(chord.modifiers, chord.logical_key)
                        }
                        Trigger::EditChord(chord) if !typing => {
                            i.count_and_consume_key(chord.modifiers, chord.logical_key)
                        }
                        Trigger::Key(key) if !typing && i.modifiers.is_none() => {
                            i.num_presses(*key)
                        }
                        Trigger::Char(c) if !typing => i
                            .events
                            .iter()
                            .filter(|e| matches!(e, egui::Event::Text(t) if t == c))
                            .count(),
                        _ => 0,
                    })
                    .sum();
                let times = match binding.command.repeats() {
                    true => presses,
                    false => presses.min(1),
                };
                commands.extend(std::iter::repeat_n(binding.command.clone(), times));
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
        let shown_pass = self.passes.pass;
        let has_file = self.doc.path().is_some();
        let undo = self.doc.undo_label().map(|l| format!("Undo {l}"));
        let redo = self.doc.redo_label().map(|l| format!("Redo {l}"));
        egui::MenuBar::new().ui(ui, |ui| {
            ui.menu_button("File", |ui| {
                pick(ui, true, Command::Open);
                pick(ui, true, Command::OpenPath);
                pick(ui, true, Command::OpenBuiltin);
                ui.menu_button("Recent", |ui| {
                    let recent = self.kept.recent.existing();
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
                ui.separator();
                pick(ui, has_file, Command::OpenInEditor);
            });
            ui.menu_button("View", |ui| {
                pick(ui, true, Command::Fit);
                pick(ui, true, Command::OneToOne);
                pick(ui, true, Command::CameraFromFile);
                pick(ui, true, Command::Study);
                pick(ui, true, Command::Explain);
                let overlays = binding(&Command::Overlays).map_or("", |b| b.label);
                item(
                    ui,
                    true,
                    Some(self.overlay.shown),
                    overlays,
                    Command::Overlays,
                );
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
                        Some(self.choice.aa == aa),
                        &text,
                        Command::AntiAliasing(aa),
                    );
                }
            });
            ui.menu_button("Help", |ui| {
                pick(ui, true, Command::Help);
            });
        });
        if let Some(command) = chosen.take() {
            self.run(command);
        }
    }
}
