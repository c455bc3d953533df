//! The desktop previewer (feature `gui`): an eframe/egui window that shows
//! the render beside a panel of every scene value, re-rendering on each
//! edit and each save of the file.
//!
//! - [`app`]: the window: layout, menus, keys, the picture.
//! - [`panel`]: the side panel's widgets; they return edits, never change
//!   the scene themselves.
//! - [`texture`]: the preview's picture on the GPU, uploaded a changed
//!   tile (or a band of rows) at a time.
//! - [`study`]: the Study window and the live preview's choice of method.
//! - `x11_names`: the window's class and Latin-1 title under X11, which
//!   eframe and winit write wrong.
//!
//! What the window shows and changes is the app's model,
//! [`crate::session`]: the document and its undo, the journal, the
//! watcher, the render worker, the settings. This module draws it and
//! turns input into its calls; it reaches the core only through `session`,
//! `scene`, `render`, `study`, `output` and `desktop` (the window's id and
//! icon).

pub mod app;
mod panel;
pub mod study;
pub mod texture;
#[cfg(all(unix, not(target_os = "macos")))]
mod x11_names;

use crate::session::{document, settings};
use std::path::Path;

#[derive(Debug, thiserror::Error)]
pub enum GuiError {
    #[error("no display: set DISPLAY or WAYLAND_DISPLAY, or render without a window with --no-gui")]
    NoDisplay,
    #[error("{0}")]
    Load(#[from] crate::scene::LoadError),
    #[error("the window could not open: {0}; render without a window with --no-gui")]
    Window(String),
}

/// The document the app starts on: `scene` when given (its errors are the
/// user's to see), otherwise the last file if it is still there and opens,
/// otherwise the built-in example.
pub fn first_document(
    scene: Option<&Path>,
    settings: &settings::Settings,
) -> Result<document::Document, GuiError> {
    if let Some(path) = scene {
        return Ok(document::Document::open(path)?);
    }
    Ok(settings
        .last_file
        .as_deref()
        .filter(|p| p.is_file())
        .and_then(|p| document::Document::open(p).ok())
        .unwrap_or_else(document::Document::builtin))
}

/// The app's icon (its 128-pixel PNG), for the window and the task bar.
/// Not the 256: on X11 its 65 538 words overflow a request of the core
/// protocol, and the window gets an empty `_NET_WM_ICON`.
fn window_icon() -> egui::IconData {
    let png = crate::desktop::ICON_PNGS
        .iter()
        .find(|(side, _)| *side == 128)
        .map_or(&[][..], |(_, png)| *png);
    match image::load_from_memory_with_format(png, image::ImageFormat::Png) {
        Ok(icon) => {
            let icon = icon.to_rgba8();
            egui::IconData {
                width: icon.width(),
                height: icon.height(),
                rgba: icon.into_raw(),
            }
        }
        Err(_) => egui::IconData::default(),
    }
}

/// Whether a display server is reachable by the environment's say-so.
pub fn display_available() -> bool {
    ["DISPLAY", "WAYLAND_DISPLAY"]
        .iter()
        .any(|v| std::env::var_os(v).is_some_and(|s| !s.is_empty()))
}

/// Opens the app on `scene` (without one: the file open when it last
/// closed, or the built-in example) and returns when the window is closed.
pub fn run(scene: Option<&Path>) -> Result<(), GuiError> {
    if !display_available() {
        return Err(GuiError::NoDisplay);
    }
    let persisted = settings::Persisted::user();
    // A large file opens once the window is there.
    let later = scene
        .map(Path::to_owned)
        .or_else(|| persisted.settings.last_file.clone())
        .filter(|p| {
            std::fs::metadata(p)
                .is_ok_and(|m| m.is_file() && m.len() >= crate::session::BACKGROUND_BYTES)
        });
    let doc = match &later {
        Some(_) => document::Document::empty(),
        None => first_document(scene, &persisted.settings)?,
    };
    let options = eframe::NativeOptions {
        viewport: egui::ViewportBuilder::default()
            .with_inner_size(persisted.settings.window.unwrap_or([1200.0, 800.0]))
            .with_min_inner_size([480.0, 320.0])
            .with_drag_and_drop(true)
            .with_title("RayOfLight")
            // The desktop entry's id: the shell shows the entry's name and
            // icon for the window (Wayland app id, X11 class).
            .with_app_id(crate::desktop::APP_ID)
            .with_icon(window_icon()),
        // egui dithers every fragment against banding in its gradients;
        // there are none here, the picture's texels are already 8 bits,
        // and with Mesa's software renderer (Xvfb, remote desktops) the
        // dither cost 7 ms of CPU a frame (24 ms against 17 ms for a
        // 1200×800 window): a third of it.
        dithering: false,
        ..Default::default()
    };
    eframe::run_native(
        "RayOfLight",
        options,
        Box::new(move |cc| {
            #[cfg(all(unix, not(target_os = "macos")))]
            x11_names::watch(
                cc,
                &x11_names::instance_name("rayoflight"),
                crate::desktop::APP_ID,
            );
            let mut app = app::RayOfLightApp::new(&cc.egui_ctx, doc, persisted);
            app.end_on_signals();
            // The user's editors' unsaved text, where a private runtime
            // folder is there for the link.
            let folder = crate::desktop::editor_link::folder().ok();
            if let Some(listener) =
                folder.and_then(|f| crate::desktop::editor_link::Listener::bind(&f).ok())
            {
                app.listen_to_editors(listener);
            }
            if let Some(path) = later {
                app.run(app::Command::OpenFile(path));
            }
            Ok(Box::new(app))
        }),
    )
    .map_err(|e| GuiError::Window(e.to_string()))
}
