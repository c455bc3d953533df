//! The journal of unsaved edits, so that they outlive the process (as
//! VS Code's "hot exit"): a crash, `kill -9`, a logout, the X server
//! dying.
//!
//! For each scene with unsaved edits there are two files in
//! `$XDG_STATE_HOME/rayoflight/journal/` (or `~/.local/state/…`), named by
//! a hash of the scene's absolute path, user-only (0600, the folder 0700),
//! each written atomically (a temporary file renamed into place):
//! - `KEY.base.xml`: the text the edits apply to, the file as last read or
//!   written (written once for each version of the file, not with every
//!   edit);
//! - `KEY.json`: the scene's path, the base's fingerprint and length, when
//!   it was written, and the edits — values by path (`object[2].material.ka`
//!   to `0.9`), elements added as the XML the loader reads back.
//!
//! The app writes them at most [`DELAY`] after an edit, on a thread of its
//! own, and removes them when nothing is unsaved (saved, reverted, undone)
//! or the user discards the edits. On the next start [`read`] gives them
//! back only for the same path, and only whole: a base whose fingerprint
//! is not the recorded one, an edit that does not parse or apply, a file
//! cut short, are a [`JournalError`] (the app says so and leaves the
//! journal alone). The document restores the edits onto the file as it
//! opened when it still holds the base (the base then never read), or
//! onto the base, merged with the file as it is now.

use std::io::Write;
use std::path::{Path, PathBuf};
use std::sync::mpsc;
use std::time::{Duration, SystemTime, UNIX_EPOCH};

use serde_json::{Value as Json, json};

use crate::gui::document::{TextWriter, fingerprint_file};

/// Streams a text (a journal's base).
pub type WriteText = dyn Fn(&mut dyn Write) -> std::io::Result<()>;
use crate::math::{Transform, TransformStep};
use crate::scene::edit::{Edit, Element, Field, Item, Owner};
use crate::scene::{self, Scene, splice};

/// How long after an edit it is in the journal, at the most.
pub const DELAY: Duration = Duration::from_millis(300);

/// What the journal's first key says: the format, for later versions.
const FORMAT: &str = "rayoflight unsaved edits 1";

/// The journal folder in the state home `home` (`$XDG_STATE_HOME`, else
/// `~/.local/state`): `home/rayoflight/journal`, made where missing, and
/// refused unless it and the folders above it up to `home` are the
/// user's and closed to others' writes, the journal itself closed to
/// others ([`crate::files::own_folder`]): else another user could plant
/// edits that a save writes into the user's scene.
pub fn folder_in(home: &Path) -> Result<PathBuf, crate::files::OwnFolderError> {
    crate::files::own_folder(home, &["rayoflight", "journal"], true)
}

/// The unsaved edits of one scene, as journaled.
#[derive(Debug, Clone, PartialEq)]
pub struct Entry {
    /// The scene's absolute path.
    pub scene: PathBuf,
    /// The fingerprint of the base text (the file as the edits found it).
    pub base_fingerprint: u64,
    /// When the entry was written.
    pub saved_at: SystemTime,
    /// The edits, in order, onto the base's scene.
    pub edits: Vec<Edit>,
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

/// Where the journal of `scene` is, in `folder`: (`KEY.json`,
/// `KEY.base.xml`).
pub fn files(folder: &Path, scene: &Path) -> (PathBuf, PathBuf) {
    let scene = crate::files::absolute(scene);
    let mut h = std::hash::DefaultHasher::new();
    std::hash::Hash::hash(scene.as_os_str(), &mut h);
    let stem: String = scene
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
        .collect();
    let key = format!("{stem}-{:016x}", std::hash::Hasher::finish(&h));
    (
        folder.join(format!("{key}.json")),
        folder.join(format!("{key}.base.xml")),
    )
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
    // tempfile creates it 0600.
    {
        let mut w = std::io::BufWriter::new(tmp.as_file_mut());
        write(&mut w)?;
        w.flush()?;
    }
    tmp.as_file().sync_all()?;
    tmp.persist(path).map_err(|e| e.error)?;
    Ok(())
}

/// Writes the journal of `entry.scene`: its base first when `base` is given
/// (`write_base` streams the base text), then the entry.
pub fn write(folder: &Path, entry: &Entry, write_base: Option<&WriteText>) -> std::io::Result<()> {
    make_folder(folder)?;
    let (json_path, base_path) = files(folder, &entry.scene);
    if let Some(write_base) = write_base {
        write_private(&base_path, |w| write_base(w))?;
    }
    let text = to_json(entry).to_string();
    write_private(&json_path, |w| w.write_all(text.as_bytes()))
}

/// Removes the journal of `scene`, if there is one.
pub fn remove(folder: &Path, scene: &Path) {
    let (json_path, base_path) = files(folder, scene);
    // The entry first: a base without an entry is never read.
    let _ = std::fs::remove_file(json_path);
    let _ = std::fs::remove_file(base_path);
}

/// Moves the journal of `scene` aside (a damaged one: never applied, never
/// lost), as `KEY.json.damaged`; returns where it went.
pub fn set_aside(folder: &Path, scene: &Path) -> Option<PathBuf> {
    let (json_path, _) = files(folder, scene);
    let mut aside = json_path.clone().into_os_string();
    aside.push(".damaged");
    let aside = PathBuf::from(aside);
    std::fs::rename(&json_path, &aside).ok().map(|()| aside)
}

/// The journal of `scene`, if there is one: `Ok(None)` when there is none.
pub fn read(folder: &Path, scene: &Path) -> Result<Option<Restored>, JournalError> {
    let (json_path, base_path) = files(folder, scene);
    let text = match std::fs::read_to_string(&json_path) {
        Ok(t) => t,
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => return Ok(None),
        Err(source) => {
            return Err(JournalError::Io {
                path: json_path,
                source,
            });
        }
    };
    let damaged = |why: String| JournalError::Damaged {
        path: json_path.clone(),
        why,
    };
    let json: Json = serde_json::from_str(&text).map_err(|e| damaged(e.to_string()))?;
    let entry = from_json(&json).map_err(damaged)?;
    let wanted = crate::files::absolute(scene);
    if entry.scene != wanted {
        // Another file's journal under this name: never applied here.
        return Ok(None);
    }
    let base_print = fingerprint_file(&base_path)
        .map_err(|_| damaged(format!("its base {} cannot be read", base_path.display())))?;
    if base_print != entry.base_fingerprint {
        return Err(damaged(format!(
            "its base {} is not the text the edits were made on",
            base_path.display()
        )));
    }
    Ok(Some(Restored { entry, base_path }))
}

// ----- the entry as JSON -----

fn to_json(entry: &Entry) -> Json {
    let saved_at = entry
        .saved_at
        .duration_since(UNIX_EPOCH)
        .map_or(0, |d| d.as_secs());
    json!({
        "format": FORMAT,
        "scene": entry.scene.to_string_lossy(),
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
    let base_fingerprint = u64::from_str_radix(text("base_fingerprint")?, 16)
        .map_err(|_| "a bad 'base_fingerprint'".to_owned())?;
    let saved_at = json
        .get("saved_at")
        .and_then(Json::as_u64)
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
        base_fingerprint,
        saved_at: UNIX_EPOCH + Duration::from_secs(saved_at),
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
    Ok(splice::to_xml(&s))
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
            json!({"insert": item.to_string(), "xml": splice::to_xml(&s)})
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
    /// Write this entry; with `base`, write the base first.
    Write {
        entry: Entry,
        base: Option<TextWriter>,
    },
    Remove(PathBuf),
    /// Answer on the channel once everything before is done.
    Flush(mpsc::Sender<()>),
}

/// Writes journal entries on a thread of its own, newest first: a queue of
/// writes for one scene collapses to the last.
pub struct Writer {
    tx: mpsc::Sender<Job>,
    errors: mpsc::Receiver<String>,
}

impl Writer {
    pub fn start(folder: PathBuf) -> Writer {
        let (tx, rx) = mpsc::channel::<Job>();
        let (etx, errors) = mpsc::channel();
        let _ = std::thread::Builder::new()
            .name("journal".to_owned())
            .spawn(move || {
                while let Ok(first) = rx.recv() {
                    let mut jobs = vec![first];
                    jobs.extend(rx.try_iter());
                    // Only the last write of a run counts, but a base must be
                    // kept from any write of the run.
                    let mut base = None;
                    let mut pending: Option<Entry> = None;
                    let mut flushes = Vec::new();
                    for job in jobs {
                        match job {
                            Job::Write { entry, base: b } => {
                                if b.is_some() {
                                    base = b;
                                }
                                pending = Some(entry);
                            }
                            Job::Remove(scene) => {
                                pending = None;
                                base = None;
                                remove(&folder, &scene);
                            }
                            Job::Flush(done) => flushes.push(done),
                        }
                    }
                    if let Some(entry) = pending {
                        let base = base.as_deref().map(|b| b as &WriteText);
                        if let Err(e) = write(&folder, &entry, base) {
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
            });
        Writer { tx, errors }
    }

    pub fn send(&self, job: Job) {
        let _ = self.tx.send(job);
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

#[cfg(test)]
mod tests {
    use super::*;
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
            Edit::add(&s, NewElement::Sphere),
            Edit::add(&s, NewElement::Light),
            Edit::Remove(Item::Object(0)),
            Edit::Transform(Owner::Camera, moved.clone()),
            Edit::Transform(Owner::Object(1), moved),
            Edit::Insert(
                Item::Step(Owner::Camera, 0),
                Element::Step(TransformStep::UniformScale(2.0)),
            ),
        ];
        let entry = Entry {
            scene: scene_path.clone(),
            base_fingerprint: crate::gui::document::fingerprint_text(base),
            saved_at: UNIX_EPOCH + Duration::from_secs(1_700_000_000),
            edits,
        };
        let write_base = |w: &mut dyn Write| w.write_all(base.as_bytes());
        write(dir.path(), &entry, Some(&write_base)).unwrap();
        let back = read(dir.path(), &scene_path).unwrap().unwrap();
        assert_eq!(back.entry, entry);
        assert_eq!(back.base().unwrap(), base);
        #[cfg(unix)]
        {
            use std::os::unix::fs::PermissionsExt;
            for f in [
                files(dir.path(), &scene_path).0,
                files(dir.path(), &scene_path).1,
            ] {
                let mode = std::fs::metadata(&f).unwrap().permissions().mode();
                assert_eq!(mode & 0o777, 0o600, "{}", f.display());
            }
        }

        // Another path: nothing. A damaged entry or base: an error.
        assert!(
            read(dir.path(), &dir.path().join("other.xml"))
                .unwrap()
                .is_none()
        );
        let (json_path, base_path) = files(dir.path(), &scene_path);
        std::fs::write(&base_path, "<scene/>").unwrap();
        assert!(matches!(
            read(dir.path(), &scene_path),
            Err(JournalError::Damaged { .. })
        ));
        let text = std::fs::read_to_string(&json_path).unwrap();
        std::fs::write(&json_path, &text[..text.len() / 2]).unwrap();
        assert!(matches!(
            read(dir.path(), &scene_path),
            Err(JournalError::Damaged { .. })
        ));
        remove(dir.path(), &scene_path);
        assert!(read(dir.path(), &scene_path).unwrap().is_none());
    }
}
