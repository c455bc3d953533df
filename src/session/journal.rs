//! The journal of unsaved edits, so that they outlive the process (as
//! VS Code's "hot exit"): a crash, `kill -9`, a logout, the X server
//! dying.
//!
//! Each window (each app process) keeps an entry of its own, so that two
//! windows on one file never write over each other's edits. In
//! `$XDG_STATE_HOME/rayoflight/journal/` (or `~/.local/state/…`),
//! user-only (the folder 0700, the files 0600), each file written
//! atomically (a temporary file renamed into place):
//! - `ID.lock`: locked by the window `ID` for as long as it lives
//!   ([`Own`]). The system lets go of a lock when its process ends, however
//!   it ends, so a lock that can be taken is a window that is gone.
//! - `STEM-ID.base.xml`: the text the edits apply to, the file as last
//!   read or written (written once for each version of the file, not with
//!   every edit);
//! - `STEM-ID.json`: the scene's path as opened and with its links
//!   resolved, the file's identity (device and inode), the base's
//!   fingerprint, when it was written, and the edits — values by path
//!   (`object[2].material.ka` to `0.9`), elements added as the XML the
//!   loader reads back.
//!
//! The app writes its entry at most [`DELAY`] after an edit, on a thread
//! of its own ([`Writer`]), and removes it when nothing is unsaved (saved,
//! reverted, undone) or the user discards the edits.
//!
//! When a scene opens, [`find`] reads the other windows' entries. One
//! whose window still lives is left to it (and counted, for the status);
//! one whose window is gone is *claimed* — its lock taken, so that two
//! windows opening at once never both take it — when it was made on this
//! file: the same path once links are resolved, or the same file (its
//! identity) moved or renamed since. It comes back as a [`Claimed`], whole
//! or not at all: a base whose fingerprint is not the recorded one, an
//! edit that does not parse, a file cut short are a [`JournalError`] (the
//! entry is set aside, never applied, never lost). The app restores every
//! claimed entry into the document (merged through the usual engine,
//! conflicts asked), journals the result as its own, and only then
//! removes them ([`Job::Adopt`]). An entry made at this path on another
//! file (the one there now has another identity and does not hold the
//! base) is [`Match::Replaced`]: offered, never merged unasked.

use std::fs::File;
use std::io::Write;
use std::path::{Path, PathBuf};
use std::sync::mpsc;
use std::time::{Duration, SystemTime, UNIX_EPOCH};

use serde_json::{Value as Json, json};

use crate::session::document::{TextWriter, fingerprint_file};

/// Streams a text (a journal's base).
pub type WriteText = dyn Fn(&mut dyn Write) -> std::io::Result<()>;
use crate::math::{Transform, TransformStep};
use crate::scene::edit::{Edit, Element, Field, Item, Owner};
use crate::scene::{self, Scene, fresh};

/// How long after an edit it is in the journal, at the most.
pub const DELAY: Duration = Duration::from_millis(300);

/// What the journal's first key says: the format, for later versions.
/// (The keys `canonical` and `file` came later; an entry without them is
/// matched by its path alone.)
const FORMAT: &str = "rayoflight unsaved edits 1";

/// The journal folder in the state home `home` (`$XDG_STATE_HOME`, else
/// `~/.local/state`): `home/rayoflight/journal`, made where missing, and
/// refused unless it and the folders above it up to `home` are the
/// user's and closed to others' writes, the journal itself closed to
/// others ([`crate::system::files::own_folder`]): else another user could plant
/// edits that a save writes into the user's scene.
pub fn folder_in(home: &Path) -> Result<PathBuf, crate::system::files::OwnFolderError> {
    crate::system::files::own_folder(home, &["rayoflight", "journal"], true)
}

/// Which file a file's path names, as the journal tells files apart: its
/// device and inode (Unix), so that a file moved or renamed is found
/// again and another file put at its path is not taken for it.
pub type FileId = (u64, u64);

/// The [`FileId`] of the file `path` names (through links), if known.
pub fn file_id(path: &Path) -> Option<FileId> {
    match crate::system::files::identity(path) {
        crate::system::files::FileIdentity::Inode { device, inode } => Some((device, inode)),
        crate::system::files::FileIdentity::Path(_) => None,
    }
}

/// The unsaved edits of one scene, as journaled.
#[derive(Debug, Clone, PartialEq)]
pub struct Entry {
    /// The scene's absolute path, as the window opened it.
    pub scene: PathBuf,
    /// The same with every link resolved (as `scene` when it cannot be).
    pub canonical: PathBuf,
    /// The file the edits were made on, when the system tells files apart.
    pub file: Option<FileId>,
    /// The fingerprint of the base text (the file as the edits found it).
    pub base_fingerprint: u64,
    /// When the entry was written.
    pub saved_at: SystemTime,
    /// The edits, in order, onto the base's scene.
    pub edits: Vec<Edit>,
}

impl Entry {
    /// The entry of `edits` made on the scene at `path` whose text had
    /// `base_fingerprint`, now: the path's links and the file's identity
    /// looked up as it is now.
    pub fn now(path: &Path, base_fingerprint: u64, edits: Vec<Edit>) -> Entry {
        let scene = crate::system::files::absolute(path);
        Entry {
            canonical: std::fs::canonicalize(&scene).unwrap_or_else(|_| scene.clone()),
            file: file_id(&scene),
            scene,
            base_fingerprint,
            saved_at: SystemTime::now(),
            edits,
        }
    }
}

/// An entry read back; its base text is read only when asked for
/// ([`Restored::base`]): a file that still holds it needs none of it.
#[derive(Debug, Clone)]
pub struct Restored {
    pub entry: Entry,
    base_path: PathBuf,
}

impl Restored {
    /// The base text: the file as the edits found it.
    pub fn base(&self) -> Result<String, JournalError> {
        std::fs::read_to_string(&self.base_path).map_err(|source| JournalError::Io {
            path: self.base_path.clone(),
            source,
        })
    }
}

/// Why a journal could not be read back (it is left where it is).
#[derive(Debug, thiserror::Error)]
pub enum JournalError {
    #[error("cannot read the journal {}: {source}", path.display())]
    Io {
        path: PathBuf,
        source: std::io::Error,
    },
    #[error("the journal {} is damaged ({why}); it was not applied", path.display())]
    Damaged { path: PathBuf, why: String },
}

/// The part of a journal file's name that says which scene it is about
/// (for a person looking in the folder, and to tell whose a damaged
/// entry is): the scene's file stem, letters, digits, `-` and `_` only.
fn stem_of(scene: &Path) -> String {
    scene
        .file_stem()
        .map(|s| s.to_string_lossy().into_owned())
        .unwrap_or_default()
        .chars()
        .map(|c| {
            if c.is_ascii_alphanumeric() || c == '-' || c == '_' {
                c
            } else {
                '_'
            }
        })
        .take(40)
        .collect()
}

/// The files of the entry of window `id` about a scene of stem `stem`:
/// (`STEM-ID.json`, `STEM-ID.base.xml`).
fn entry_files(folder: &Path, stem: &str, id: &str) -> (PathBuf, PathBuf) {
    (
        folder.join(format!("{stem}-{id}.json")),
        folder.join(format!("{stem}-{id}.base.xml")),
    )
}

/// The lock file of window `id`.
fn lock_file(folder: &Path, id: &str) -> PathBuf {
    folder.join(format!("{id}.lock"))
}

/// The (stem, window id) of an entry's file name `STEM-ID.json`.
fn parse_name(name: &str) -> Option<(&str, &str)> {
    let key = name.strip_suffix(".json")?;
    let (stem, id) = key.rsplit_once('-')?;
    (!id.is_empty() && id.chars().all(|c| c.is_ascii_hexdigit())).then_some((stem, id))
}

/// Makes `folder` (user-only) if it is not there.
fn make_folder(folder: &Path) -> std::io::Result<()> {
    let mut builder = std::fs::DirBuilder::new();
    builder.recursive(true);
    #[cfg(unix)]
    {
        use std::os::unix::fs::DirBuilderExt;
        builder.mode(0o700);
    }
    builder.create(folder)
}

/// Writes `path` atomically, user-only: a temporary file beside it, synced,
/// renamed into place.
fn write_private(
    path: &Path,
    write: impl FnOnce(&mut dyn Write) -> std::io::Result<()>,
) -> std::io::Result<()> {
    let dir = path.parent().unwrap_or(Path::new("."));
    let mut tmp = tempfile::Builder::new()
        .prefix(".journal-")
        .tempfile_in(dir)?;
    // tempfile creates it 0600. Locked while written, so that a window
    // sweeping the folder tells it from one a killed window left.
    let _ = tmp.as_file().try_lock();
    {
        let mut w = std::io::BufWriter::new(tmp.as_file_mut());
        write(&mut w)?;
        w.flush()?;
    }
    tmp.as_file().sync_all()?;
    tmp.persist(path).map_err(|e| e.error)?;
    Ok(())
}

/// A fresh window id: 16 hexadecimal digits, from the process's random
/// hash keys, its number and the time.
fn random_id() -> String {
    use std::hash::{BuildHasher, Hasher};
    let mut h = std::collections::hash_map::RandomState::new().build_hasher();
    h.write_u32(std::process::id());
    h.write_u128(
        SystemTime::now()
            .duration_since(UNIX_EPOCH)
            .map_or(0, |d| d.as_nanos()),
    );
    format!("{:016x}", h.finish())
}

/// Whether `file` (open, locked) is still the file `path` names: a
/// claimer that finished with a lock file removes it, and a lock taken
/// on a removed file guards nothing.
fn still_named(file: &File, path: &Path) -> bool {
    match (file.metadata(), std::fs::metadata(path)) {
        (Ok(a), Ok(b)) => crate::system::files::same_metadata(&a, &b),
        _ => false,
    }
}

/// Opens (making it where missing) and locks the lock file `path`:
/// `Ok(None)` when another process holds it.
fn take_lock(path: &Path, new: bool) -> std::io::Result<Option<File>> {
    for _ in 0..4 {
        let mut options = std::fs::OpenOptions::new();
        options.read(true).write(true);
        if new {
            options.create_new(true);
        } else {
            options.create(true);
        }
        #[cfg(unix)]
        {
            use std::os::unix::fs::OpenOptionsExt;
            options.mode(0o600);
        }
        let file = options.open(path)?;
        match file.try_lock() {
            Ok(()) => {}
            Err(std::fs::TryLockError::WouldBlock) => return Ok(None),
            Err(std::fs::TryLockError::Error(e)) => return Err(e),
        }
        if still_named(&file, path) {
            return Ok(Some(file));
        }
    }
    Ok(None)
}

/// This window's place in the journal: its id, and the lock that tells
/// other windows it lives (held until it is dropped, or the process
/// ends). Its entry is written and removed through it.
pub struct Own {
    folder: PathBuf,
    id: String,
    _lock: File,
    /// The entry's files as last written: (json, base).
    entry: Option<(PathBuf, PathBuf)>,
    /// The base file and the fingerprint of the text it holds.
    base: Option<(PathBuf, u64)>,
}

impl Own {
    /// Takes a fresh window id in `folder` (made user-only where missing).
    pub fn take(folder: &Path) -> std::io::Result<Own> {
        make_folder(folder)?;
        for _ in 0..16 {
            let id = random_id();
            match take_lock(&lock_file(folder, &id), true) {
                Ok(Some(lock)) => {
                    return Ok(Own {
                        folder: folder.to_owned(),
                        id,
                        _lock: lock,
                        entry: None,
                        base: None,
                    });
                }
                Ok(None) => {}
                Err(e) if e.kind() == std::io::ErrorKind::AlreadyExists => {}
                Err(e) => return Err(e),
            }
        }
        Err(std::io::Error::other(
            "no free name for this window's journal",
        ))
    }

    /// The window's id.
    pub fn id(&self) -> &str {
        &self.id
    }

    /// Writes the window's entry: its base first where the base file does
    /// not hold the entry's base yet (`write_base` streams the base text),
    /// then the entry; the files of an entry about another scene go.
    pub fn write(&mut self, entry: &Entry, write_base: Option<&WriteText>) -> std::io::Result<()> {
        make_folder(&self.folder)?;
        let (json_path, base_path) = entry_files(&self.folder, &stem_of(&entry.scene), &self.id);
        let base = Some((base_path.clone(), entry.base_fingerprint));
        if self.base != base {
            let write_base = write_base.ok_or_else(|| {
                std::io::Error::other("the text the edits were made on is not at hand")
            })?;
            write_private(&base_path, |w| write_base(w))?;
            self.base = base;
        }
        let text = to_json(entry).to_string();
        write_private(&json_path, |w| w.write_all(text.as_bytes()))?;
        if let Some((old_json, old_base)) = self.entry.replace((json_path, base_path))
            && self.entry.as_ref().map(|e| &e.0) != Some(&old_json)
        {
            let _ = std::fs::remove_file(old_json);
            let _ = std::fs::remove_file(old_base);
        }
        Ok(())
    }

    /// Removes the window's entry, if it has one.
    pub fn remove(&mut self) {
        if let Some((json_path, base_path)) = self.entry.take() {
            // The entry first: a base without an entry is never read.
            let _ = std::fs::remove_file(json_path);
            let _ = std::fs::remove_file(base_path);
        }
        self.base = None;
    }
}

impl Drop for Own {
    /// A window without an entry leaves nothing behind; one with an entry
    /// leaves its lock file, free, for the window that claims the entry.
    fn drop(&mut self) {
        if self.entry.is_none() {
            let _ = std::fs::remove_file(lock_file(&self.folder, &self.id));
        }
    }
}

/// How a claimed entry was made on the scene being opened.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum Match {
    /// On this file, at this path (or through a link to it).
    Same,
    /// On this file when it was at another path (moved or renamed since).
    Moved { from: PathBuf },
    /// At this path, but on a file that has been replaced since by
    /// another (another program's save, or an unrelated file).
    Replaced,
}

/// How `entry` was made on the file `scene` (absolute, with links
/// resolved `canonical`, identity `id`), if it was.
fn matching(entry: &Entry, scene: &Path, canonical: &Path, id: Option<FileId>) -> Option<Match> {
    let same_file = entry.file.is_some() && entry.file == id;
    let same_path = entry.canonical == canonical || entry.scene == scene;
    match (same_file, same_path) {
        (true, true) => Some(Match::Same),
        (true, false) => Some(Match::Moved {
            from: entry.scene.clone(),
        }),
        (false, true) if entry.file.is_none() || id.is_none() => Some(Match::Same),
        (false, true) => Some(Match::Replaced),
        (false, false) => None,
    }
}

/// The entry of a window that is gone, locked by this window until it is
/// removed ([`Claimed::remove`], once its edits are in this window's own
/// entry) or let go (dropped: left for a later window).
pub struct Claimed {
    pub restored: Restored,
    pub how: Match,
    json: PathBuf,
    lock: PathBuf,
    _held: File,
}

impl std::fmt::Debug for Claimed {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Claimed")
            .field("json", &self.json)
            .field("how", &self.how)
            .finish_non_exhaustive()
    }
}

impl Claimed {
    /// The entry's file.
    pub fn path(&self) -> &Path {
        &self.json
    }

    /// Removes the entry and its lock file.
    pub fn remove(self) {
        let _ = std::fs::remove_file(&self.json);
        let _ = std::fs::remove_file(&self.restored.base_path);
        let _ = std::fs::remove_file(&self.lock);
    }

    /// Moves the entry aside (one that cannot be applied: never applied,
    /// never lost), as `….json.damaged`, its base beside it as
    /// `….base.xml.damaged`; returns where the entry went.
    pub fn set_aside(self) -> Option<PathBuf> {
        set_aside(&self.json)
    }
}

/// Moves the entry `json` aside as `json.damaged`, and its base (if
/// any) as `….base.xml.damaged`, so that neither is read again nor left
/// without the other.
fn set_aside(json: &Path) -> Option<PathBuf> {
    let damaged = |path: &Path| {
        let mut aside = path.to_owned().into_os_string();
        aside.push(".damaged");
        PathBuf::from(aside)
    };
    let aside = damaged(json);
    std::fs::rename(json, &aside).ok()?;
    if let Some(name) = json.file_name().and_then(|n| n.to_str())
        && let Some(key) = name.strip_suffix(".json")
    {
        let base = json.with_file_name(format!("{key}.base.xml"));
        let _ = std::fs::rename(&base, damaged(&base));
    }
    Some(aside)
}

/// What [`find`] found about a scene in the journal.
#[derive(Debug, Default)]
pub struct Found {
    /// Entries of windows that are gone, made on this scene, oldest first.
    pub claimed: Vec<Claimed>,
    /// Entries of windows still open on this scene (theirs to keep).
    pub live: usize,
    /// Entries about this scene that cannot be read back, set aside (where
    /// they went, if they could be moved).
    pub damaged: Vec<(JournalError, Option<PathBuf>)>,
}

/// The entries in `folder` about the scene at `scene`, but window `own`'s
/// ([`Found`]); lock files left by windows that are gone without an entry
/// are removed on the way.
pub fn find(folder: &Path, scene: &Path, own: Option<&str>) -> Found {
    let mut found = Found::default();
    let Ok(listing) = std::fs::read_dir(folder) else {
        return found;
    };
    let abs = crate::system::files::absolute(scene);
    let canonical = std::fs::canonicalize(&abs).unwrap_or_else(|_| abs.clone());
    let id_now = file_id(&abs);
    let stems = [stem_of(&abs), stem_of(&canonical)];
    let mut names: Vec<String> = listing
        .flatten()
        .filter_map(|e| e.file_name().to_str().map(str::to_owned))
        .collect();
    names.sort();
    let mut with_entries = std::collections::BTreeSet::new();
    for name in &names {
        let Some((stem, id)) = parse_name(name) else {
            continue;
        };
        with_entries.insert(id.to_owned());
        if Some(id) == own {
            continue;
        }
        let json_path = folder.join(name);
        // Whether it is about this scene, read before claiming it; read
        // again once claimed (its claimer may have finished with it).
        let about_this = match read_entry(&json_path) {
            Ok(Some(entry)) => matching(&entry, &abs, &canonical, id_now).is_some(),
            Ok(None) => false,
            Err(_) => stems.iter().any(|s| s == stem),
        };
        if !about_this {
            continue;
        }
        let lock = lock_file(folder, id);
        let held = match take_lock(&lock, false) {
            Ok(Some(held)) => held,
            Ok(None) => {
                found.live += 1;
                continue;
            }
            Err(_) => continue,
        };
        let base_path = json_path.with_file_name(format!("{stem}-{id}.base.xml"));
        match read_entry(&json_path).and_then(|entry| {
            let Some(entry) = entry else { return Ok(None) };
            let Some(how) = matching(&entry, &abs, &canonical, id_now) else {
                return Ok(None);
            };
            check_base(&json_path, &base_path, &entry)?;
            Ok(Some((entry, how)))
        }) {
            Ok(Some((entry, how))) => found.claimed.push(Claimed {
                restored: Restored { entry, base_path },
                how,
                json: json_path,
                lock,
                _held: held,
            }),
            Ok(None) => {
                if !json_path.exists() {
                    let _ = std::fs::remove_file(&lock);
                }
            }
            Err(e) => {
                let aside = set_aside(&json_path);
                found.damaged.push((e, aside));
            }
        }
    }
    // Windows gone without an entry, and the temporary files of writes
    // that a kill cut short (a base as big as the scene).
    for name in &names {
        if name.starts_with(".journal-") {
            let path = folder.join(name);
            let quiet = std::fs::metadata(&path)
                .and_then(|m| m.modified())
                .is_ok_and(|t| t.elapsed().is_ok_and(|age| age >= Duration::from_secs(2)));
            if quiet
                && let Ok(file) = File::open(&path)
                && file.try_lock().is_ok()
                && still_named(&file, &path)
            {
                let _ = std::fs::remove_file(&path);
            }
            continue;
        }
        if let Some(id) = name.strip_suffix(".lock")
            && Some(id) != own
            && !with_entries.contains(id)
        {
            let path = folder.join(name);
            if let Ok(Some(_held)) = take_lock(&path, false) {
                let _ = std::fs::remove_file(&path);
            }
        }
    }
    found.claimed.sort_by_key(|c| c.restored.entry.saved_at);
    found
}

/// The entry in `json_path`: `Ok(None)` when there is none.
fn read_entry(json_path: &Path) -> Result<Option<Entry>, JournalError> {
    let text = match std::fs::read_to_string(json_path) {
        Ok(t) => t,
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => return Ok(None),
        Err(source) => {
            return Err(JournalError::Io {
                path: json_path.to_owned(),
                source,
            });
        }
    };
    let damaged = |why: String| JournalError::Damaged {
        path: json_path.to_owned(),
        why,
    };
    let json: Json = serde_json::from_str(&text).map_err(|e| damaged(e.to_string()))?;
    from_json(&json).map(Some).map_err(damaged)
}

/// Whether the base beside `entry` is the text its edits were made on.
fn check_base(json_path: &Path, base_path: &Path, entry: &Entry) -> Result<(), JournalError> {
    let damaged = |why: String| JournalError::Damaged {
        path: json_path.to_owned(),
        why,
    };
    let base_print = fingerprint_file(base_path)
        .map_err(|_| damaged(format!("its base {} cannot be read", base_path.display())))?;
    if base_print != entry.base_fingerprint {
        return Err(damaged(format!(
            "its base {} is not the text the edits were made on",
            base_path.display()
        )));
    }
    Ok(())
}

// ----- the entry as JSON -----

fn to_json(entry: &Entry) -> Json {
    // Seconds, to the millisecond: which of two windows' entries came
    // first decides the order they are restored in.
    let saved_at = entry
        .saved_at
        .duration_since(UNIX_EPOCH)
        .map_or(0.0, |d| d.as_millis() as f64 / 1000.0);
    json!({
        "format": FORMAT,
        "scene": entry.scene.to_string_lossy(),
        "canonical": entry.canonical.to_string_lossy(),
        "file": entry.file.map(|(device, inode)| format!("{device}:{inode}")),
        "base_fingerprint": format!("{:016x}", entry.base_fingerprint),
        "saved_at": saved_at,
        "edits": entry.edits.iter().map(edit_to_json).collect::<Vec<_>>(),
    })
}

fn from_json(json: &Json) -> Result<Entry, String> {
    if json.get("format").and_then(Json::as_str) != Some(FORMAT) {
        return Err(format!("not a journal of the format '{FORMAT}'"));
    }
    let text = |key: &str| {
        json.get(key)
            .and_then(Json::as_str)
            .ok_or_else(|| format!("no '{key}'"))
    };
    let scene = PathBuf::from(text("scene")?);
    let canonical = json
        .get("canonical")
        .and_then(Json::as_str)
        .map_or_else(|| scene.clone(), PathBuf::from);
    let file = match json.get("file") {
        None | Some(Json::Null) => None,
        Some(file) => {
            let bad = || "a bad 'file'".to_owned();
            let (device, inode) = file
                .as_str()
                .and_then(|f| f.split_once(':'))
                .ok_or_else(bad)?;
            Some((
                device.parse().map_err(|_| bad())?,
                inode.parse().map_err(|_| bad())?,
            ))
        }
    };
    let base_fingerprint = u64::from_str_radix(text("base_fingerprint")?, 16)
        .map_err(|_| "a bad 'base_fingerprint'".to_owned())?;
    let saved_at = json
        .get("saved_at")
        .and_then(Json::as_f64)
        .filter(|s| s.is_finite() && *s >= 0.0)
        .ok_or("no 'saved_at'")?;
    let edits = json
        .get("edits")
        .and_then(Json::as_array)
        .ok_or("no 'edits'")?
        .iter()
        .enumerate()
        .map(|(i, e)| edit_from_json(e).map_err(|why| format!("edit {}: {why}", i + 1)))
        .collect::<Result<Vec<_>, _>>()?;
    Ok(Entry {
        scene,
        canonical,
        file,
        base_fingerprint,
        saved_at: UNIX_EPOCH + Duration::from_millis((saved_at * 1000.0).round() as u64),
        edits,
    })
}

/// A scene holding only what an element needs, to write and read it with
/// the loader's own rules.
fn holder() -> Scene {
    scene::parse(
        "<scene><camera width=\"1\" height=\"1\" eyeDistance=\"1\"/></scene>",
        Path::new("journal"),
    )
    .expect("the holder scene is valid")
}

/// A sphere holding `steps`, as XML.
fn steps_xml(steps: &[TransformStep]) -> Result<String, String> {
    let transform = Transform::from_steps(steps.to_vec()).map_err(|e| e.to_string())?;
    let mut s = holder();
    s.objects.push(std::sync::Arc::new(scene::Object {
        shape: scene::Shape::Sphere,
        color: crate::math::Vec3::ONE,
        material: scene::Material::default(),
        transform,
    }));
    Ok(fresh::to_xml(&s))
}

fn edit_to_json(edit: &Edit) -> Json {
    match edit {
        Edit::Set(field, value) => json!({"set": field.to_string(), "to": value.to_string()}),
        Edit::Remove(item) => json!({"remove": item.to_string()}),
        Edit::Insert(item, element) => {
            let mut s = holder();
            match element {
                Element::Object(o) => s.objects.push(std::sync::Arc::new(o.as_ref().clone())),
                Element::Light(l) => s.lights.push(*l),
                Element::Step(step) => {
                    return json!({
                        "insert": item.to_string(),
                        "xml": steps_xml(std::slice::from_ref(step)).unwrap_or_default(),
                    });
                }
            }
            json!({"insert": item.to_string(), "xml": fresh::to_xml(&s)})
        }
        Edit::Transform(owner, steps) => json!({
            "transform": owner.to_string(),
            "xml": steps_xml(steps).unwrap_or_default(),
        }),
    }
}

fn edit_from_json(json: &Json) -> Result<Edit, String> {
    let text = |key: &str| json.get(key).and_then(Json::as_str);
    let xml_scene = || -> Result<Scene, String> {
        let xml = text("xml").ok_or("no 'xml'")?;
        scene::parse(xml, Path::new("journal")).map_err(|e| e.to_string())
    };
    if let Some(path) = text("set") {
        let field = Field::parse(path).map_err(|e| e.to_string())?;
        let value = field
            .parse_value(text("to").ok_or("no 'to'")?)
            .map_err(|e| e.to_string())?;
        return Ok(Edit::Set(field, value));
    }
    if let Some(path) = text("remove") {
        return Ok(Edit::Remove(Item::parse(path).map_err(|e| e.to_string())?));
    }
    if let Some(path) = text("insert") {
        let item = Item::parse(path).map_err(|e| e.to_string())?;
        let s = xml_scene()?;
        let element = match item {
            Item::Object(_) => Element::Object(Box::new(
                s.objects
                    .first()
                    .ok_or("no object in 'xml'")?
                    .as_ref()
                    .clone(),
            )),
            Item::Light(_) => Element::Light(*s.lights.first().ok_or("no light in 'xml'")?),
            Item::Step(..) => Element::Step(
                *s.objects
                    .first()
                    .and_then(|o| o.transform.steps().first())
                    .ok_or("no step in 'xml'")?,
            ),
        };
        return Ok(Edit::Insert(item, element));
    }
    if let Some(owner) = text("transform") {
        let owner = match owner {
            "camera" => Owner::Camera,
            other => match Item::parse(other).map_err(|e| e.to_string())? {
                Item::Object(n) => Owner::Object(n),
                _ => return Err(format!("not a transformation's owner: '{other}'")),
            },
        };
        let s = xml_scene()?;
        let steps = s
            .objects
            .first()
            .ok_or("no object in 'xml'")?
            .transform
            .steps()
            .to_vec();
        return Ok(Edit::Transform(owner, steps));
    }
    Err("not an edit".to_owned())
}

// ----- the writer thread -----

/// What the journal thread is asked to do.
pub enum Job {
    /// Write this window's entry; `base` streams the text it applies to
    /// (needed once for each base).
    Write {
        entry: Entry,
        base: Option<TextWriter>,
    },
    /// Remove this window's entry: nothing is unsaved.
    Remove,
    /// Remove these entries of windows that are gone once this window's
    /// entry, as last asked, is written (or removed): their edits are in
    /// this window's document now. Let go of them, left in place, if it
    /// could not be written.
    Adopt(Vec<Claimed>),
    /// Answer on the channel once everything before is done.
    Flush(mpsc::Sender<()>),
}

/// Writes this window's entry on a thread of its own, newest first: a
/// queue of writes collapses to the last. Dropping it waits for the
/// thread to finish what it was given.
pub struct Writer {
    tx: Option<mpsc::Sender<Job>>,
    errors: mpsc::Receiver<String>,
    folder: PathBuf,
    id: Option<String>,
    thread: Option<std::thread::JoinHandle<()>>,
}

impl Writer {
    /// The writer of a new window's entry in `folder`. A folder where no
    /// window id can be taken leaves the window without a journal: each
    /// write is an error ([`Writer::error`]).
    pub fn start(folder: PathBuf) -> Writer {
        let (tx, rx) = mpsc::channel::<Job>();
        let (etx, errors) = mpsc::channel();
        let mut own = Own::take(&folder).map_err(|e| e.to_string());
        let id = own.as_ref().ok().map(|o| o.id().to_owned());
        let journal = folder.clone();
        let thread = std::thread::Builder::new()
            .name("journal".to_owned())
            .spawn(move || {
                // The base of the last write that brought one.
                let mut base: Option<TextWriter> = None;
                while let Ok(first) = rx.recv() {
                    let mut jobs = vec![first];
                    jobs.extend(rx.try_iter());
                    let mut pending: Option<Option<Entry>> = None;
                    let mut adopted = Vec::new();
                    let mut flushes = Vec::new();
                    for job in jobs {
                        match job {
                            Job::Write { entry, base: b } => {
                                if b.is_some() {
                                    base = b;
                                }
                                pending = Some(Some(entry));
                            }
                            Job::Remove => pending = Some(None),
                            Job::Adopt(claims) => adopted.extend(claims),
                            Job::Flush(done) => flushes.push(done),
                        }
                    }
                    let done = match (&mut own, pending) {
                        (_, None) => Ok(()),
                        (Ok(own), Some(None)) => {
                            own.remove();
                            base = None;
                            Ok(())
                        }
                        (Ok(own), Some(Some(entry))) => {
                            let base = base.as_deref().map(|b| b as &WriteText);
                            own.write(&entry, base).map_err(|e| e.to_string())
                        }
                        (Err(e), Some(_)) => Err(e.clone()),
                    };
                    match done {
                        Ok(()) => adopted.into_iter().for_each(Claimed::remove),
                        Err(e) => {
                            let _ = etx.send(format!(
                                "cannot keep the unsaved edits in {}: {e}",
                                folder.display()
                            ));
                        }
                    }
                    for done in flushes {
                        let _ = done.send(());
                    }
                }
            })
            .ok();
        Writer {
            tx: Some(tx),
            errors,
            folder: journal,
            id,
            thread,
        }
    }

    /// The journal folder.
    pub fn folder(&self) -> Option<&Path> {
        Some(&self.folder)
    }

    /// This window's id in the journal (none without one).
    pub fn id(&self) -> Option<&str> {
        self.id.as_deref()
    }

    pub fn send(&self, job: Job) {
        if let Some(tx) = &self.tx {
            let _ = tx.send(job);
        }
    }

    /// Waits (at most `limit`) until every job sent is done.
    pub fn flush(&self, limit: Duration) {
        let (tx, rx) = mpsc::channel();
        self.send(Job::Flush(tx));
        let _ = rx.recv_timeout(limit);
    }

    /// An error the thread met since last asked.
    pub fn error(&self) -> Option<String> {
        self.errors.try_iter().last()
    }
}

impl Drop for Writer {
    fn drop(&mut self) {
        self.tx = None;
        if let Some(thread) = self.thread.take() {
            let _ = thread.join();
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::scene::Shape;
    use crate::scene::edit::{Coef, NewElement, Value};

    #[test]
    fn entries_read_back_as_written() {
        let dir = tempfile::tempdir().unwrap();
        let scene_path = dir.path().join("a scene.xml");
        let base = crate::EXAMPLE_SCENE;
        let s = scene::parse(base, &scene_path).unwrap();
        let mut moved = s.objects[0].transform.steps().to_vec();
        moved.push(TransformStep::RotateZ(0.25));
        let edits = vec![
            Edit::Set(
                Field::Material {
                    object: 1,
                    coef: Coef::Ka,
                },
                Value::Number(0.1 + 0.2),
            ),
            Edit::add(&s, NewElement::Object(Shape::Sphere)),
            Edit::add(&s, NewElement::Light),
            Edit::Remove(Item::Object(0)),
            Edit::Transform(Owner::Camera, moved.clone()),
            Edit::Transform(Owner::Object(1), moved),
            Edit::Insert(
                Item::Step(Owner::Camera, 0),
                Element::Step(TransformStep::UniformScale(2.0)),
            ),
        ];
        std::fs::write(&scene_path, base).unwrap();
        let folder = dir.path().join("journal");
        let entry = Entry {
            saved_at: UNIX_EPOCH + Duration::from_secs(1_700_000_000),
            ..Entry::now(
                &scene_path,
                crate::session::document::fingerprint_text(base),
                edits,
            )
        };
        assert_eq!(entry.file, file_id(&scene_path));
        let write_base = |w: &mut dyn Write| w.write_all(base.as_bytes());
        let mut window = Own::take(&folder).unwrap();
        window.write(&entry, Some(&write_base)).unwrap();
        let (json_path, base_path) = entry_files(&folder, "a_scene", window.id());
        #[cfg(unix)]
        {
            use std::os::unix::fs::PermissionsExt;
            let mode = |p: &Path| std::fs::metadata(p).unwrap().permissions().mode() & 0o777;
            assert_eq!(mode(&folder), 0o700);
            for f in [&json_path, &base_path, &lock_file(&folder, window.id())] {
                assert_eq!(mode(f), 0o600, "{}", f.display());
            }
        }
        // The window's own entry is not found by itself, and another
        // window leaves it alone while it lives.
        let own = find(&folder, &scene_path, Some(window.id()));
        assert!(own.claimed.is_empty() && own.live == 0);
        let other = find(&folder, &scene_path, None);
        assert!(other.claimed.is_empty());
        assert_eq!(other.live, 1);
        // Gone: claimed whole, by one window at a time.
        drop(window);
        let mut found = find(&folder, &scene_path, None);
        assert_eq!(found.claimed.len(), 1);
        let claimed = found.claimed.remove(0);
        assert_eq!(claimed.restored.entry, entry);
        assert_eq!(claimed.how, Match::Same);
        assert_eq!(claimed.restored.base().unwrap(), base);
        let meanwhile = find(&folder, &scene_path, None);
        assert!(meanwhile.claimed.is_empty());
        assert_eq!(meanwhile.live, 1, "a claimed entry is held");
        drop(claimed);

        // Another path: nothing.
        let other = find(&folder, &dir.path().join("other.xml"), None);
        assert!(other.claimed.is_empty() && other.live == 0 && other.damaged.is_empty());

        // A damaged base or entry: set aside, said.
        let text = std::fs::read_to_string(&json_path).unwrap();
        std::fs::write(&base_path, "<scene/>").unwrap();
        let found = find(&folder, &scene_path, None);
        assert!(found.claimed.is_empty());
        assert!(matches!(
            found.damaged.as_slice(),
            [(JournalError::Damaged { .. }, Some(_))]
        ));
        assert!(!json_path.exists());
        std::fs::write(&json_path, &text[..text.len() / 2]).unwrap();
        let found = find(&folder, &scene_path, None);
        assert_eq!(found.damaged.len(), 1, "cut short, yet known by its name");
        // A damaged entry of another scene is not this one's to report.
        std::fs::write(&json_path, &text[..text.len() / 2]).unwrap();
        let other = find(&folder, &dir.path().join("other.xml"), None);
        assert!(other.damaged.is_empty());
        assert!(json_path.exists());
    }

    #[cfg(unix)]
    #[test]
    fn an_entry_follows_its_file_and_not_its_path() {
        let dir = tempfile::tempdir().unwrap();
        let folder = dir.path().join("journal");
        let scene_path = dir.path().join("s.xml");
        let text = crate::EXAMPLE_SCENE;
        std::fs::write(&scene_path, text).unwrap();
        let link = dir.path().join("link.xml");
        std::os::unix::fs::symlink(&scene_path, &link).unwrap();
        let fingerprint = crate::session::document::fingerprint_text(text);
        let write_base = |w: &mut dyn Write| w.write_all(text.as_bytes());
        // Made through the link.
        let mut window = Own::take(&folder).unwrap();
        window
            .write(
                &Entry::now(&link, fingerprint, Vec::new()),
                Some(&write_base),
            )
            .unwrap();
        drop(window);
        let how = |path: &Path| {
            find(&folder, path, None)
                .claimed
                .first()
                .map(|c| c.how.clone())
        };
        assert_eq!(how(&scene_path), Some(Match::Same), "the real path");
        assert_eq!(how(&link), Some(Match::Same));
        // Moved: found at its new path, by its identity.
        std::fs::create_dir(dir.path().join("moved")).unwrap();
        let moved = dir.path().join("moved/s.xml");
        std::fs::rename(&scene_path, &moved).unwrap();
        assert_eq!(how(&moved), Some(Match::Moved { from: link.clone() }));
        // Another file at the old path: not the same file.
        std::fs::write(&scene_path, text).unwrap();
        assert_eq!(how(&scene_path), Some(Match::Replaced));
        assert_eq!(how(&dir.path().join("unrelated.xml")), None);
    }
}
