//! What the user can ask for: the [`Command`] enum that the menus and the
//! keys produce, and the one table ([`BINDINGS`]) that gives each command
//! its menu label, its keys and its line in the help. The menus, the keys
//! and the help that read the table, and the one place that carries a
//! command out, are in `menus`.

use egui::{Key, KeyboardShortcut, Modifiers};
use std::path::PathBuf;

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
    /// Open the scene in the user's editor at the selected object's
    /// element (Edit › Open in editor, Ctrl+Shift+O).
    OpenInEditor,
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

impl Command {
    /// Whether each press of its key runs it once more (undo, redo,
    /// zoom); the others run once however many presses a frame brings.
    pub(super) fn repeats(&self) -> bool {
        matches!(
            self,
            Command::Undo | Command::Redo | Command::ZoomIn | Command::ZoomOut
        )
    }
}

const fn chord(modifiers: Modifiers, key: Key) -> KeyboardShortcut {
    KeyboardShortcut::new(modifiers, key)
}

const CTRL: Modifiers = Modifiers::COMMAND;
const CTRL_SHIFT: Modifiers = Modifiers::COMMAND.plus(Modifiers::SHIFT);

/// Every command with a fixed label or a key. The keys are tried in this
/// order, so Redo comes before Undo: Ctrl+Shift+Z also matches Ctrl+Z
/// (and Open in editor before Open).
pub(super) const BINDINGS: &[Binding] = &[
    // Before Open: Ctrl+Shift+O also matches Ctrl+O.
    Binding {
        command: Command::OpenInEditor,
        label: "Open in editor",
        keys: &[Trigger::Chord(chord(CTRL_SHIFT, Key::O))],
        help: "open the scene in your editor at the selected object (RAYOFLIGHT_EDITOR, $VISUAL)",
    },
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
