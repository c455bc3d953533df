//! The app on a Linux desktop, for one user: `rayoflight install-desktop`
//! writes the desktop entry (its `Exec` the running binary's absolute
//! path), the icons in the hicolor theme and the MIME type of scenes
//! (files named `*.rayoflight.xml`, and those naming RayOfLight's schema
//! that no other pattern claims: a `*.xml` name makes a file plain XML to
//! gio and xdg-mime) under `$XDG_DATA_HOME` (default `~/.local/share`),
//! and `--uninstall` removes exactly what it wrote.
//!
//! The files are the repository's `assets/linux/`, built in. What was
//! written (each file with a fingerprint of its bytes), and which folders
//! were created for it (the data folder itself included, in a fresh
//! home), is kept in `$XDG_DATA_HOME/rayoflight/installed-files`: an
//! uninstall removes the files whose bytes are still the ones it wrote
//! and names the others, left as they are; an install never writes over
//! a file it did not write or that changed since, nor through a symbolic
//! link it did not make, in the file's name or in a folder's. The desktop databases are brought up to date when their tools
//! (update-desktop-database, update-mime-database) are installed; when the
//! last user type or entry goes, the caches they generated go too.
//!
//! RayOfLight is offered in "Open with" for XML files and is the default
//! only for its own type, `application/x-rayoflight-scene` (other formats
//! use a bare `<scene>` root too). Where the user has chosen no default
//! for XML, gio and xdg-mime would take the first application of the
//! user's own folder, this one: the install writes the application that
//! opened XML until then into the user's `mimeapps.list` ([`defaults`]),
//! recorded with the files, taken out again by the uninstall.
//!
//! The editor link ([`editor_link`]) lives here too: the user's editor's
//! unsaved text, from `rayoflight lsp` to the app, over a socket of the
//! user's own (Unix only: elsewhere the language server works without
//! it).

pub mod defaults;
pub mod editor_link;

use std::path::{Path, PathBuf};
use std::process::Command;

/// The application's id: the desktop entry's, the icon's, the AppStream
/// component's and the window's (Wayland app id, X11 class).
pub const APP_ID: &str = "io.github.rayoflight.RayOfLight";

/// The desktop entry as the repository keeps it (`Exec=rayoflight %f`).
pub const DESKTOP_ENTRY: &str =
    include_str!("../../assets/linux/io.github.rayoflight.RayOfLight.desktop");
/// The shared-mime-info package of `application/x-rayoflight-scene`.
pub const MIME_PACKAGE: &str =
    include_str!("../../assets/linux/io.github.rayoflight.RayOfLight.mime.xml");
/// The scalable icon.
pub const ICON_SVG: &str = include_str!("../../assets/linux/io.github.rayoflight.RayOfLight.svg");

/// The icon as PNGs, side in pixels: the hicolor theme's sizes.
pub const ICON_PNGS: &[(u32, &[u8])] = &[
    (
        16,
        include_bytes!("../../assets/linux/icons/16x16/io.github.rayoflight.RayOfLight.png"),
    ),
    (
        24,
        include_bytes!("../../assets/linux/icons/24x24/io.github.rayoflight.RayOfLight.png"),
    ),
    (
        32,
        include_bytes!("../../assets/linux/icons/32x32/io.github.rayoflight.RayOfLight.png"),
    ),
    (
        48,
        include_bytes!("../../assets/linux/icons/48x48/io.github.rayoflight.RayOfLight.png"),
    ),
    (
        64,
        include_bytes!("../../assets/linux/icons/64x64/io.github.rayoflight.RayOfLight.png"),
    ),
    (
        128,
        include_bytes!("../../assets/linux/icons/128x128/io.github.rayoflight.RayOfLight.png"),
    ),
    (
        256,
        include_bytes!("../../assets/linux/icons/256x256/io.github.rayoflight.RayOfLight.png"),
    ),
    (
        512,
        include_bytes!("../../assets/linux/icons/512x512/io.github.rayoflight.RayOfLight.png"),
    ),
];

/// Where the record of an install lives, under the data folder.
const MANIFEST: &str = "rayoflight/installed-files";

/// What went wrong.
#[derive(Debug, thiserror::Error)]
pub enum DesktopError {
    #[error("no folder for the desktop files: set XDG_DATA_HOME or HOME to an absolute path")]
    NoDataHome,
    #[error(
        "{}: already exists and was not written by install-desktop; nothing was written (remove it first to replace it)",
        path.display()
    )]
    NotOurs { path: PathBuf },
    #[error("{}: {source}", path.display())]
    Io {
        path: PathBuf,
        source: std::io::Error,
    },
    #[error(transparent)]
    Write(#[from] crate::system::files::WriteError),
    #[error("{}: the record of what install-desktop wrote is damaged (line {line}); nothing was removed", path.display())]
    Manifest { path: PathBuf, line: usize },
    #[error(
        "{}: a symbolic link install-desktop did not make; nothing was written (it writes only into real folders)",
        path.display()
    )]
    Link { path: PathBuf },
    #[error(
        "nothing installed: the application that opens XML files could not be kept as the default: {source}"
    )]
    Default { source: Box<DesktopError> },
    #[error(
        "no folder for your settings (mimeapps.list): set XDG_CONFIG_HOME or HOME to an absolute path"
    )]
    NoConfigHome,
    #[error("{}: another program kept changing it; the default applications were left as they were", path.display())]
    Busy { path: PathBuf },
}

/// The types of XML files the desktop entry lists, for "Open with".
const XML_TYPES: &[&str] = &["application/xml", "text/xml"];

/// What an install or an uninstall did.
#[derive(Debug, Default)]
pub struct Done {
    /// The files written or removed, in order.
    pub files: Vec<PathBuf>,
    /// The folders an uninstall removed (made by the install, empty now).
    pub folders: Vec<PathBuf>,
    /// The database tools run (`update-mime-database`), with their folder.
    pub ran: Vec<String>,
    /// Tools that were not found, so not run.
    pub missing: Vec<&'static str>,
    /// Files an uninstall left: changed since they were written (another
    /// program's now, or the user's).
    pub kept: Vec<PathBuf>,
    /// The defaults written into (or taken out of) the user's
    /// `mimeapps.list` (`application/xml=editor.desktop;`).
    pub defaults: Vec<String>,
    /// Defaults an uninstall left: changed since (the user's choice now).
    pub kept_defaults: Vec<String>,
}

/// A fingerprint of bytes written (64-bit FNV-1a: the same in every
/// build, unlike std's hasher), to know them again at an uninstall.
fn fingerprint(bytes: &[u8]) -> u64 {
    bytes.iter().fold(0xcbf2_9ce4_8422_2325, |h, &b| {
        (h ^ u64::from(b)).wrapping_mul(0x0000_0100_0000_01b3)
    })
}

/// Whether `path` is a regular file (not a link) whose bytes have the
/// fingerprint `print`; for a file recorded without one (an install by
/// an earlier version) its bytes are compared with `expected`, what this
/// version writes there.
fn still_ours(path: &Path, print: Option<u64>, expected: Option<&[u8]>) -> bool {
    let regular = std::fs::symlink_metadata(path).is_ok_and(|m| m.file_type().is_file());
    if !regular {
        return false;
    }
    let Ok(bytes) = std::fs::read(path) else {
        return false;
    };
    match print {
        Some(print) => fingerprint(&bytes) == print,
        None => expected.is_some_and(|e| e == bytes),
    }
}

/// The per-user data folder: `$XDG_DATA_HOME`, else `$HOME/.local/share`.
pub fn data_home() -> Result<PathBuf, DesktopError> {
    let absolute = |v: std::ffi::OsString| Some(PathBuf::from(v)).filter(|p| p.is_absolute());
    std::env::var_os("XDG_DATA_HOME")
        .and_then(absolute)
        .or_else(|| {
            std::env::var_os("HOME")
                .and_then(absolute)
                .map(|h| h.join(".local/share"))
        })
        .ok_or(DesktopError::NoDataHome)
}

/// The desktop entry with `Exec` and `TryExec` set to `exec`.
pub fn desktop_entry(exec: &Path) -> String {
    let program = exec_quoted(exec);
    DESKTOP_ENTRY
        .lines()
        .map(|line| {
            if line.starts_with("Exec=") {
                format!("Exec={program} %f")
            } else if line.starts_with("TryExec=") {
                format!("TryExec={}", escaped_string(&exec.to_string_lossy()))
            } else {
                line.to_owned()
            }
        })
        .map(|line| line + "\n")
        .collect()
}

/// A program path as the Desktop Entry Specification's `Exec` key takes
/// it: quoted when it holds a reserved character, `"`, `` ` ``, `$` and
/// `\` escaped in the quotes, then the whole escaped as a string value.
fn exec_quoted(path: &Path) -> String {
    let text = path.to_string_lossy();
    let reserved = |c: char| " \t\n\"'\\><~|&;$*?#()`".contains(c);
    let argument = if text.contains(reserved) {
        let mut quoted = String::from("\"");
        for c in text.chars() {
            if matches!(c, '"' | '`' | '$' | '\\') {
                quoted.push('\\');
            }
            quoted.push(c);
        }
        quoted.push('"');
        quoted
    } else {
        text.into_owned()
    };
    escaped_string(&argument)
}

/// A desktop entry string value: `\`, newline, tab and carriage return
/// escaped. A literal `%` in Exec is `%%`.
fn escaped_string(text: &str) -> String {
    let mut out = String::new();
    for c in text.chars() {
        match c {
            '\\' => out.push_str("\\\\"),
            '\n' => out.push_str("\\n"),
            '\t' => out.push_str("\\t"),
            '\r' => out.push_str("\\r"),
            '%' => out.push_str("%%"),
            c => out.push(c),
        }
    }
    out
}

/// The files an install writes, relative to the data folder, with their
/// bytes.
fn files(exec: &Path) -> Vec<(PathBuf, Vec<u8>)> {
    let mut files = vec![
        (
            PathBuf::from(format!("applications/{APP_ID}.desktop")),
            desktop_entry(exec).into_bytes(),
        ),
        (
            PathBuf::from(format!("mime/packages/{APP_ID}.xml")),
            MIME_PACKAGE.as_bytes().to_vec(),
        ),
        (
            PathBuf::from(format!("icons/hicolor/scalable/apps/{APP_ID}.svg")),
            ICON_SVG.as_bytes().to_vec(),
        ),
    ];
    for (side, png) in ICON_PNGS {
        files.push((
            PathBuf::from(format!("icons/hicolor/{side}x{side}/apps/{APP_ID}.png")),
            png.to_vec(),
        ));
    }
    files
}

/// What the manifest records: the files written (with the fingerprint of
/// their bytes; none from an earlier version), the folders created under
/// the data folder, and the data folder and those above it that the
/// install created (absolute).
#[derive(Debug, Default)]
struct Manifest {
    files: Vec<(PathBuf, Option<u64>)>,
    folders: Vec<PathBuf>,
    made: Vec<PathBuf>,
    /// What was added to the user's `mimeapps.list`.
    pinned: defaults::Pinned,
}

impl Manifest {
    fn read(places: &defaults::Places) -> Result<Option<Manifest>, DesktopError> {
        let home = places.data_home.as_path();
        let path = home.join(MANIFEST);
        let text = match std::fs::read_to_string(&path) {
            Ok(text) => text,
            Err(e) if e.kind() == std::io::ErrorKind::NotFound => return Ok(None),
            Err(source) => return Err(DesktopError::Io { path, source }),
        };
        let mut manifest = Manifest::default();
        for (i, line) in text.lines().enumerate() {
            let damaged = || DesktopError::Manifest {
                path: path.clone(),
                line: i + 1,
            };
            let (kind, mut relative) = line.split_once(' ').ok_or_else(damaged)?;
            let mut print = None;
            if kind == "file"
                && let Some((hex, rest)) = relative.split_once(' ')
                && hex.len() == 16
                && let Ok(p) = u64::from_str_radix(hex, 16)
            {
                print = Some(p);
                relative = rest;
            }
            match (kind, relative) {
                ("default", line) if line.contains('=') => {
                    manifest.pinned.lines.push(line.to_owned());
                    continue;
                }
                ("default-group", n) => {
                    let n = n.parse().ok().filter(|&n| n <= 2).ok_or_else(damaged)?;
                    manifest.pinned.group_after = Some(n);
                    continue;
                }
                ("default-file", "made") => {
                    manifest.pinned.made_file = true;
                    continue;
                }
                ("default-header", "newline") => {
                    manifest.pinned.header_newline = true;
                    continue;
                }
                _ => {}
            }
            let relative = PathBuf::from(relative);
            if kind == "made" {
                // Only the data or config folder and folders above them.
                let above = |f: &Path| relative.is_absolute() && f.starts_with(&relative);
                if !(above(home) || above(&places.config_home)) {
                    return Err(damaged());
                }
                manifest.made.push(relative);
                continue;
            }
            // Only paths inside the data folder, never `..`.
            let inside = relative.is_relative()
                && relative
                    .components()
                    .all(|c| matches!(c, std::path::Component::Normal(_)));
            if !inside {
                return Err(damaged());
            }
            match kind {
                "file" => manifest.files.push((relative, print)),
                "folder" => manifest.folders.push(relative),
                _ => return Err(damaged()),
            }
        }
        Ok(Some(manifest))
    }

    fn text(&self) -> String {
        let mut text = String::new();
        for (f, print) in &self.files {
            match print {
                Some(p) => text.push_str(&format!("file {p:016x} {}\n", f.display())),
                None => text.push_str(&format!("file {}\n", f.display())),
            }
        }
        for d in &self.folders {
            text.push_str(&format!("folder {}\n", d.display()));
        }
        for d in &self.made {
            text.push_str(&format!("made {}\n", d.display()));
        }
        let pinned = &self.pinned;
        for line in &pinned.lines {
            text.push_str(&format!("default {line}\n"));
        }
        if let Some(n) = pinned.group_after {
            text.push_str(&format!("default-group {n}\n"));
        }
        if pinned.made_file {
            text.push_str("default-file made\n");
        }
        if pinned.header_newline {
            text.push_str("default-header newline\n");
        }
        text
    }
}

/// Installs the desktop files for `exec` (the binary's absolute path)
/// under the data folder `home`, made if missing. An earlier install is
/// replaced; a file in the way that it did not write, or that changed
/// since, and a symbolic link in the way (the file's or a folder's), are
/// refused before anything is written. Where the entry would become the
/// default for XML files, the application that is the default until then
/// is written as the user's choice ([`defaults`]).
pub fn install(places: &defaults::Places, exec: &Path) -> Result<Done, DesktopError> {
    let home = places.data_home.as_path();
    let mut done = Done::default();
    let earlier = Manifest::read(places)?.unwrap_or_default();
    let mut to_write: Vec<(PathBuf, Vec<u8>)> = files(exec);
    to_write.push((PathBuf::from(MANIFEST), Vec::new()));
    for (relative, _) in &to_write {
        let path = home.join(relative);
        // Every folder below the data folder a real one, or missing.
        let mut folder = home.to_owned();
        for part in relative.parent().into_iter().flat_map(Path::components) {
            folder.push(part);
            if std::fs::symlink_metadata(&folder).is_ok_and(|m| m.file_type().is_symlink()) {
                return Err(DesktopError::Link { path: folder });
            }
        }
        let Ok(meta) = std::fs::symlink_metadata(&path) else {
            continue;
        };
        if meta.file_type().is_symlink() {
            return Err(DesktopError::Link { path });
        }
        if relative == Path::new(MANIFEST) {
            continue;
        }
        let ours = earlier
            .files
            .iter()
            .find(|(f, _)| f == relative)
            .is_some_and(|(_, print)| match print {
                Some(_) => still_ours(&path, *print, None),
                // An earlier version's record: any regular file it wrote.
                None => meta.is_file(),
            });
        if !ours {
            return Err(DesktopError::NotOurs { path });
        }
    }
    // Who opens XML now, before the entry is there (a reinstall's own
    // entry not counted): where nobody chose it, that choice made.
    let ours = format!("{APP_ID}.desktop");
    let pins: Vec<String> = XML_TYPES
        .iter()
        .filter_map(|mime| match defaults::default_for(places, mime, &ours) {
            // An id is a file name: one with a control character (a
            // newline) would break the list's lines and the record's.
            defaults::Default::Preferred(id) if !id.contains(char::is_control) => {
                Some(format!("{mime}={id};"))
            }
            defaults::Default::Preferred(_) => None,
            defaults::Default::Chosen(_) | defaults::Default::Nobody => None,
        })
        .collect();
    // The earlier record kept until each file is written again: a failure
    // halfway leaves every file there recorded, for a retry or an uninstall.
    let mut manifest = Manifest {
        files: earlier.files,
        folders: earlier.folders,
        made: earlier.made,
        pinned: earlier.pinned,
    };
    // A fresh home: the data folder and those above it, made and recorded.
    make_folder(home, &mut manifest.made)?;
    let result = write_install(places, &to_write, &pins, &mut manifest, &mut done);
    // What was done, whatever failed after the data folder was there.
    let recorded =
        crate::system::files::write_atomic(&home.join(MANIFEST), manifest.text().as_bytes());
    result?;
    recorded?;
    done.defaults = pins;
    refresh(home, &mut done);
    Ok(done)
}

/// Makes `folder` and the folders above it that are missing, top-down,
/// each recorded in `made` once made (an uninstall removes them, empty).
fn make_folder(folder: &Path, made: &mut Vec<PathBuf>) -> Result<(), DesktopError> {
    let mut missing = Vec::new();
    let mut up = Some(folder);
    while let Some(f) = up.filter(|f| !f.as_os_str().is_empty() && !f.exists()) {
        missing.push(f.to_owned());
        up = f.parent();
    }
    for f in missing.into_iter().rev() {
        std::fs::create_dir(&f).map_err(|source| DesktopError::Io {
            path: f.clone(),
            source,
        })?;
        made.push(f);
    }
    Ok(())
}

/// The steps of [`install`] after its checks, each recorded in `manifest`
/// as it is done: the folders under the data folder (the manifest's among
/// them), then the pin (if it fails, no file is written: the entry never
/// takes XML from the application that had it), then the files of
/// `to_write` but the manifest, which the caller writes.
fn write_install(
    places: &defaults::Places,
    to_write: &[(PathBuf, Vec<u8>)],
    pins: &[String],
    manifest: &mut Manifest,
    done: &mut Done,
) -> Result<(), DesktopError> {
    let home = places.data_home.as_path();
    for (relative, _) in to_write {
        let mut missing = Vec::new();
        let mut folder = relative.parent();
        while let Some(f) = folder.filter(|f| !f.as_os_str().is_empty()) {
            if home.join(f).is_dir() {
                break;
            }
            missing.push(f.to_owned());
            folder = f.parent();
        }
        for f in missing.into_iter().rev() {
            let path = home.join(&f);
            std::fs::create_dir(&path).map_err(|source| DesktopError::Io { path, source })?;
            manifest.folders.push(f);
        }
    }
    if !pins.is_empty() {
        pin_defaults(places, pins, manifest).map_err(|e| DesktopError::Default {
            source: Box::new(e),
        })?;
    }
    for (relative, bytes) in to_write.iter().filter(|(f, _)| f != Path::new(MANIFEST)) {
        let path = home.join(relative);
        crate::system::files::write_atomic(&path, bytes)?;
        let print = Some(fingerprint(bytes));
        match manifest.files.iter_mut().find(|(f, _)| f == relative) {
            Some(record) => record.1 = print,
            None => manifest.files.push((relative.clone(), print)),
        }
        done.files.push(path);
    }
    Ok(())
}

/// Adds `pins` to the user's `mimeapps.list`, recorded in `manifest`
/// (with the folders and the file, where it made them).
fn pin_defaults(
    places: &defaults::Places,
    pins: &[String],
    manifest: &mut Manifest,
) -> Result<(), DesktopError> {
    let list = places.user_list();
    make_folder(&places.config_home, &mut manifest.made)?;
    let mut added = None;
    rewrite_list(&list, |text| {
        let (new, pinned) = defaults::pin(text.unwrap_or(""), pins);
        added = Some(defaults::Pinned {
            made_file: text.is_none(),
            ..pinned
        });
        Some(new)
    })?;
    if let Some(added) = added {
        let pinned = &mut manifest.pinned;
        for line in added.lines {
            if !pinned.lines.contains(&line) {
                pinned.lines.push(line);
            }
        }
        pinned.group_after = pinned.group_after.or(added.group_after);
        pinned.made_file |= added.made_file;
        pinned.header_newline |= added.header_newline;
    }
    Ok(())
}

/// Replaces the user's list at `path` by `change` of its text (`None`:
/// there is none), written only if the file still holds the text read
/// (read again just before the rename; another program's change meanwhile
/// is read and `change` applied again). `change` returning `None` leaves
/// the file as it is.
fn rewrite_list(
    path: &Path,
    mut change: impl FnMut(Option<&str>) -> Option<String>,
) -> Result<(), DesktopError> {
    use crate::system::files::{WriteError, write_atomic_with, write_new};
    #[derive(Debug)]
    enum Rewrite {
        Write(WriteError),
        Changed,
    }
    impl From<WriteError> for Rewrite {
        fn from(e: WriteError) -> Rewrite {
            Rewrite::Write(e)
        }
    }
    for _ in 0..8 {
        let old = match std::fs::read(path) {
            Ok(bytes) => Some(bytes),
            Err(e) if e.kind() == std::io::ErrorKind::NotFound => None,
            Err(source) => {
                return Err(DesktopError::Io {
                    path: path.to_owned(),
                    source,
                });
            }
        };
        // Written back as read but for the lines changed: a list that is
        // not UTF-8 (the spec says it is) is not rewritten at all.
        let text = match old.as_deref().map(std::str::from_utf8) {
            Some(Err(_)) => {
                return Err(DesktopError::Io {
                    path: path.to_owned(),
                    source: std::io::Error::other("not UTF-8 text; left as it is"),
                });
            }
            Some(Ok(text)) => Some(text),
            None => None,
        };
        let Some(new) = change(text) else {
            return Ok(());
        };
        let written = match &old {
            // A link to nothing (dotfiles not in place): not made here.
            None if std::fs::symlink_metadata(path).is_ok() => {
                return Err(DesktopError::Io {
                    path: path.to_owned(),
                    source: std::io::Error::other("a symbolic link to nothing"),
                });
            }
            None => write_new(path, new.as_bytes()).map_err(Rewrite::Write),
            Some(old) => write_atomic_with(
                path,
                |w| w.write_all(new.as_bytes()),
                |_| match std::fs::read(path) {
                    Ok(now) if &now == old => Ok(()),
                    _ => Err(Rewrite::Changed),
                },
            ),
        };
        match written {
            Ok(()) => return Ok(()),
            Err(
                Rewrite::Changed
                | Rewrite::Write(WriteError::Moved { .. } | WriteError::Exists { .. }),
            ) => {}
            Err(Rewrite::Write(e)) => return Err(e.into()),
        }
    }
    Err(DesktopError::Busy {
        path: path.to_owned(),
    })
}

/// Removes what [`install`] wrote under the data folder, and the folders
/// it created once they are empty; the defaults it wrote into the user's
/// `mimeapps.list` where they are still as written. Nothing installed:
/// nothing done.
pub fn uninstall(places: &defaults::Places) -> Result<Done, DesktopError> {
    let home = places.data_home.as_path();
    let mut done = Done::default();
    let Some(manifest) = Manifest::read(places)? else {
        return Ok(done);
    };
    if !manifest.pinned.lines.is_empty() {
        let pinned = &manifest.pinned;
        let list = places.user_list();
        let mut kept = Vec::new();
        rewrite_list(&list, |text| {
            let Some(text) = text else {
                kept.clone_from(&pinned.lines);
                return None;
            };
            let (new, missing) = defaults::unpin(text, pinned);
            kept = missing;
            (new != text).then_some(new)
        })?;
        if pinned.made_file && std::fs::read(&list).is_ok_and(|b| b.is_empty()) {
            let _ = std::fs::remove_file(&list);
        }
        done.defaults = pinned
            .lines
            .iter()
            .filter(|l| !kept.contains(l))
            .cloned()
            .collect();
        done.kept_defaults = kept;
    }
    // What this version writes: the bytes of files an earlier version
    // recorded without a fingerprint are compared with them.
    let exec = std::env::current_exe()
        .and_then(std::fs::canonicalize)
        .unwrap_or_default();
    let expected = files(&exec);
    for (relative, print) in &manifest.files {
        let path = home.join(relative);
        if std::fs::symlink_metadata(&path).is_err() {
            continue;
        }
        let now = expected
            .iter()
            .find(|(f, _)| f == relative)
            .map(|(_, b)| b.as_slice());
        if !still_ours(&path, *print, now) {
            done.kept.push(path);
            continue;
        }
        match std::fs::remove_file(&path) {
            Ok(()) => done.files.push(path),
            Err(e) if e.kind() == std::io::ErrorKind::NotFound => {}
            Err(source) => return Err(DesktopError::Io { path, source }),
        }
    }
    refresh(home, &mut done);
    forget_caches(home);
    let manifest_path = home.join(MANIFEST);
    std::fs::remove_file(&manifest_path).map_err(|source| DesktopError::Io {
        path: manifest_path,
        source,
    })?;
    // The deepest first; a folder something else now holds stays.
    let mut folders = manifest.folders;
    folders.sort_by_key(|f| std::cmp::Reverse(f.components().count()));
    // The data folder and those above it, if this install made them.
    let made = manifest.made.into_iter().rev();
    for f in folders.into_iter().map(|f| home.join(f)).chain(made) {
        if std::fs::remove_dir(&f).is_ok() {
            done.folders.push(f);
        }
    }
    Ok(done)
}

/// The database tools, run on the user's folders when installed.
fn refresh(home: &Path, done: &mut Done) {
    let applications = home.join("applications");
    let mime = home.join("mime");
    for (tool, folder, wanted) in [
        (
            "update-desktop-database",
            &applications,
            has_entries(&applications, "desktop"),
        ),
        (
            "update-mime-database",
            &mime,
            has_entries(&mime.join("packages"), "xml"),
        ),
    ] {
        if !wanted {
            continue;
        }
        match Command::new(tool).arg(folder).output() {
            Ok(_) => done.ran.push(format!("{tool} {}", folder.display())),
            Err(_) => done.missing.push(tool),
        }
    }
}

/// Whether `folder` holds a file ending in `.ext`.
fn has_entries(folder: &Path, ext: &str) -> bool {
    std::fs::read_dir(folder).is_ok_and(|entries| {
        entries
            .flatten()
            .any(|e| e.path().extension().is_some_and(|x| x == ext))
    })
}

/// The files update-mime-database generates beside `packages/`.
const MIME_DATABASE: &[&str] = &[
    "aliases",
    "generic-icons",
    "globs",
    "globs2",
    "icons",
    "magic",
    "mime.cache",
    "subclasses",
    "treemagic",
    "types",
    "version",
    "XMLnamespaces",
];

/// With no entry or type of the user's left, the caches generated from
/// them describe nothing: they go, so that an uninstall leaves the folders
/// as they were.
fn forget_caches(home: &Path) {
    let applications = home.join("applications");
    if !has_entries(&applications, "desktop") {
        let _ = std::fs::remove_file(applications.join("mimeinfo.cache"));
    }
    let mime = home.join("mime");
    if has_entries(&mime.join("packages"), "xml") {
        return;
    }
    for name in MIME_DATABASE {
        let _ = std::fs::remove_file(mime.join(name));
    }
    // The folder of each media type (application/, text/…) holds one
    // generated .xml a type.
    let Ok(entries) = std::fs::read_dir(&mime) else {
        return;
    };
    for entry in entries.flatten() {
        let path = entry.path();
        if path.file_name().is_some_and(|n| n == "packages") || !path.is_dir() {
            continue;
        }
        let generated = std::fs::read_dir(&path).is_ok_and(|files| {
            files
                .flatten()
                .all(|f| f.path().extension().is_some_and(|x| x == "xml"))
        });
        if generated {
            let _ = std::fs::remove_dir_all(&path);
        }
    }
}
