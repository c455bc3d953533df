//! The window's names under X11, as ICCCM wants them and window managers
//! read them: `WM_CLASS` with an instance name, and a `WM_NAME` in
//! Latin-1 beside the UTF-8 `_NET_WM_NAME`.
//!
//! What eframe and winit write is wrong in two places, and neither lets
//! the app say otherwise: egui-winit gives winit the app id as the class
//! with an empty instance (`WM_CLASS` "", "io.github…"), and winit writes
//! the title's UTF-8 bytes as `WM_NAME`, a property of type STRING that
//! is Latin-1, so a window manager that reads it shows `RayOfLight â€”
//! scène.xml`. `_NET_WM_NAME` (UTF8_STRING), which winit also writes, is
//! right and is left alone.
//!
//! So the app keeps its own connection to the X server for its window:
//! before the window is first shown (eframe maps it after the first
//! frame; ICCCM wants `WM_CLASS` set while the window is withdrawn) it
//! writes `WM_CLASS`, and a thread then watches the two title properties
//! and writes `WM_NAME` again, in Latin-1, each time winit writes it or
//! the title changes. Properties live in the server, so writing them from
//! a second connection is as good as from winit's; watching instead of
//! writing after each title change is what makes the order of the two
//! connections' writes not matter. Under Wayland there is nothing to do.

use raw_window_handle::{HasWindowHandle, RawWindowHandle};
use x11rb::connection::Connection;
use x11rb::protocol::Event;
use x11rb::protocol::xproto::{
    Atom, AtomEnum, ChangeWindowAttributesAux, ConnectionExt as _, EventMask, PropMode, Window,
};
use x11rb::rust_connection::RustConnection;
use x11rb::wrapper::ConnectionExt as _;

/// The longest title read back, in 32-bit units (16 KiB).
const TITLE_WORDS: u32 = 4096;

/// Sets `WM_CLASS` on the app's window to (`instance`, `class`) and keeps
/// its `WM_NAME` the Latin-1 form of its title, for as long as the window
/// lives. Does nothing for a window that is not an X11 one; an X server
/// that cannot be reached or that refuses is no reason to stop the app,
/// so it is then left as winit made it.
pub fn watch(window: &impl HasWindowHandle, instance: &str, class: &str) {
    let id = match window.window_handle().map(|h| h.as_raw()) {
        Ok(RawWindowHandle::Xlib(handle)) => handle.window as Window,
        Ok(RawWindowHandle::Xcb(handle)) => handle.window.get(),
        _ => return,
    };
    let Ok(names) = Names::connect(id) else {
        return;
    };
    if names.set_class(instance, class).is_err() {
        return;
    }
    let _ = std::thread::Builder::new()
        .name("x11-names".into())
        .spawn(move || names.keep_title_latin1());
}

/// The app's own connection to the server that shows its window.
struct Names {
    conn: RustConnection,
    window: Window,
    net_wm_name: Atom,
    utf8_string: Atom,
}

type Failed = Box<dyn std::error::Error>;

impl Names {
    fn connect(window: Window) -> Result<Names, Failed> {
        // The display winit opened: the same DISPLAY.
        let (conn, _screen) = x11rb::connect(None)?;
        let net_wm_name = conn.intern_atom(false, b"_NET_WM_NAME")?;
        let utf8_string = conn.intern_atom(false, b"UTF8_STRING")?;
        Ok(Names {
            window,
            net_wm_name: net_wm_name.reply()?.atom,
            utf8_string: utf8_string.reply()?.atom,
            conn,
        })
    }

    /// Writes `WM_CLASS` and asks for the window's property changes and
    /// its end, then waits for the server to have done both: the window
    /// is still withdrawn then, eframe showing it after the first frame.
    fn set_class(&self, instance: &str, class: &str) -> Result<(), Failed> {
        let mut value = latin1(instance);
        value.push(0);
        value.extend(latin1(class));
        value.push(0);
        self.conn.change_property8(
            PropMode::REPLACE,
            self.window,
            AtomEnum::WM_CLASS,
            AtomEnum::STRING,
            &value,
        )?;
        self.conn.change_window_attributes(
            self.window,
            &ChangeWindowAttributesAux::new()
                .event_mask(EventMask::PROPERTY_CHANGE | EventMask::STRUCTURE_NOTIFY),
        )?;
        self.conn.get_input_focus()?.reply()?;
        Ok(())
    }

    /// Until the window is destroyed or the connection fails: each time
    /// either title property changes, `WM_NAME` is made the Latin-1 form
    /// of `_NET_WM_NAME` if it is not already (so its own change, which
    /// comes back as an event too, ends there).
    fn keep_title_latin1(self) {
        let _ = self.fix_title();
        while let Ok(event) = self.conn.wait_for_event() {
            let done = match event {
                Event::PropertyNotify(e) if e.window == self.window => {
                    let title =
                        e.atom == self.net_wm_name || e.atom == Atom::from(AtomEnum::WM_NAME);
                    title && self.fix_title().is_err()
                }
                Event::DestroyNotify(e) => e.window == self.window,
                _ => false,
            };
            if done {
                return;
            }
        }
    }

    fn fix_title(&self) -> Result<(), Failed> {
        let title = self.property(self.net_wm_name, self.utf8_string)?;
        if title.is_empty() {
            // Not written yet: its own event follows.
            return Ok(());
        }
        let wanted = latin1(&String::from_utf8_lossy(&title));
        if self.property(AtomEnum::WM_NAME.into(), AtomEnum::STRING.into())? != wanted {
            self.conn.change_property8(
                PropMode::REPLACE,
                self.window,
                AtomEnum::WM_NAME,
                AtomEnum::STRING,
                &wanted,
            )?;
            self.conn.flush()?;
        }
        Ok(())
    }

    fn property(&self, name: Atom, of_type: Atom) -> Result<Vec<u8>, Failed> {
        let reply = self
            .conn
            .get_property(false, self.window, name, of_type, 0, TITLE_WORDS)?
            .reply()?;
        Ok(reply.value8().map(Iterator::collect).unwrap_or_default())
    }
}

/// `text` in Latin-1 (ISO 8859-1), the encoding of a STRING property:
/// its characters up to U+00FF as they are, the dashes, bullet, quotes
/// and ellipsis a title holds as their nearest ASCII, anything else `?`.
pub fn latin1(text: &str) -> Vec<u8> {
    let mut bytes = Vec::with_capacity(text.len());
    for c in text.chars() {
        match c {
            '\0' => {}
            c if u32::from(c) <= 0xFF => bytes.push(u32::from(c) as u8),
            '\u{2010}'..='\u{2015}' | '\u{2212}' => bytes.push(b'-'),
            '\u{2022}' => bytes.push(b'*'),
            '\u{2018}' | '\u{2019}' => bytes.push(b'\''),
            '\u{201C}' | '\u{201D}' => bytes.push(b'"'),
            '\u{2026}' => bytes.extend_from_slice(b"..."),
            _ => bytes.push(b'?'),
        }
    }
    bytes
}

/// The instance name of `WM_CLASS` as ICCCM says a client finds it:
/// `RESOURCE_NAME` from the environment, else the name the program was
/// started as (the last part of `argv[0]`), else `fallback`.
pub fn instance_name(fallback: &str) -> String {
    std::env::var("RESOURCE_NAME")
        .ok()
        .filter(|name| !name.is_empty())
        .or_else(|| {
            let argv0 = std::env::args_os().next()?;
            let name = std::path::Path::new(&argv0).file_name()?;
            Some(name.to_string_lossy().into_owned())
        })
        .unwrap_or_else(|| fallback.to_owned())
}

#[cfg(test)]
mod tests {
    use super::latin1;

    #[test]
    fn a_title_is_written_in_latin1_with_the_nearest_ascii_for_the_rest() {
        assert_eq!(latin1("RayOfLight"), b"RayOfLight");
        assert_eq!(
            latin1("RayOfLight — scène.xml •"),
            b"RayOfLight - sc\xE8ne.xml *"
        );
        assert_eq!(latin1("loading a.xml…"), b"loading a.xml...");
        assert_eq!(latin1("“é” ‘ß’"), b"\"\xE9\" '\xDF'");
        assert_eq!(latin1("雪.xml"), b"?.xml");
        assert_eq!(latin1("a\0b"), b"ab");
    }
}
