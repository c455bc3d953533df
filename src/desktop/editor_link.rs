//! The link between `rayoflight lsp` (in the user's editor) and the
//! desktop app: the editor's unsaved text of a scene goes to every app of
//! the same user, which renders it if it has that file open; a click on an
//! object in the app asks the editor to show its element, and the editor's
//! cursor in an object's element selects that object in the app.
//!
//! Each app listens on a Unix socket `app-PID.sock` in the user's runtime
//! folder, `$XDG_RUNTIME_DIR/rayoflight/` (made mode 0700; a folder that
//! is not the user's own, or that others may enter, is refused). A
//! connection from a process of another user is closed at once: the
//! kernel says who is at the other end (`SO_PEERCRED`). The language
//! server connects to every socket there (looking again every second, for
//! apps started later, which then get the text of every document it has
//! open) and sends each change of a file it has open; sockets of apps
//! that are gone are removed. The app answers on the same connection
//! ([`Peers`]).
//!
//! Objects are named by their number among the spheres and planes of the
//! text, in file order, as the loader numbers them: the app and the
//! editor hold the same text (the app follows the editor's), so each finds
//! the element in its own copy, and the app's window never scans a text.
//!
//! An edit travels as an edit: an app is handed the whole text of a
//! document once (when it connects, or when it asks: [`Message::Resend`]),
//! then each change as the bytes it replaced and the text that replaces
//! them ([`Message::Change`]), which it applies to its own copy, so a
//! keystroke in a 200 MB scene sends a few bytes, not the scene. A change
//! says the length of the text it makes: an app whose copy does not give
//! that length (it missed a change) asks for the whole text again.
//!
//! A message is one line of JSON (`{"kind":"buffer","path":…,"bytes":N}`)
//! followed by N bytes of text for a buffer or a change.

pub use crate::scene::language::Under;
use std::io::{self, BufRead, Read, Write};
#[cfg(unix)]
use std::os::unix::fs::PermissionsExt;
#[cfg(unix)]
use std::os::unix::net::UnixListener;
use std::path::{Path, PathBuf};
#[cfg(unix)]
use std::sync::atomic::{AtomicU64, Ordering};
#[cfg(unix)]
use std::sync::{Arc, Mutex, PoisonError};
#[cfg(unix)]
use std::time::Duration;

/// Applies a [`Message::Change`] to `text`, the copy of the editor's text
/// it was made for: the bytes `range` replaced by `inserted`, making
/// `length` bytes. False, `text` left as it was, where it does not fit
/// (the copy missed a change: the whole text is asked for again).
pub fn apply_change(
    text: &mut String,
    range: std::ops::Range<usize>,
    inserted: &str,
    length: usize,
) -> bool {
    let fits = range.start <= range.end
        && range.end <= text.len()
        && text.is_char_boundary(range.start)
        && text.is_char_boundary(range.end)
        && text.len() - range.len() + inserted.len() == length;
    if fits {
        text.replace_range(range, inserted);
    }
    fits
}

/// Elsewhere (Windows) there is no link ([`folder`] says so): the type a
/// connection would have, never made.
#[cfg(not(unix))]
pub use std::net::TcpStream as Stream;
/// A connection between a language server and an app: a Unix socket.
#[cfg(unix)]
pub use std::os::unix::net::UnixStream as Stream;
#[cfg(unix)]
use std::os::unix::net::UnixStream;

/// What goes over the link.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum Message {
    /// The editor's text of `path`, unsaved: the app renders it.
    Buffer { path: PathBuf, text: String },
    /// The editor's text of `path` changed since the last [`Message::Buffer`]
    /// or change: the bytes `range` of that text are now `text`, which
    /// makes the text `length` bytes long.
    Change {
        path: PathBuf,
        range: std::ops::Range<usize>,
        text: String,
        length: usize,
    },
    /// The app lost track of the editor's text of `path` (it missed a
    /// change, or opened the file since): the editor's server sends it
    /// whole again.
    Resend { path: PathBuf },
    /// The editor saved or closed `path`: the app is back to the file.
    Released { path: PathBuf },
    /// The app asks the editor to show the element of object `object`
    /// (its number among the spheres and planes of the text, from 0): the
    /// user clicked it.
    Show { path: PathBuf, object: usize },
    /// The editor's cursor moved into the element of an object or a
    /// light (the app selects it), or out of every one (`None`: the app
    /// selects nothing).
    Select { path: PathBuf, under: Option<Under> },
}

/// Why the runtime folder cannot be used.
#[derive(Debug, thiserror::Error)]
pub enum LinkError {
    #[error("no runtime folder: XDG_RUNTIME_DIR is not set")]
    NoRuntimeDir,
    #[error(transparent)]
    Unsafe(#[from] crate::system::files::OwnFolderError),
    #[error("{}: {source}", path.display())]
    Io { path: PathBuf, source: io::Error },
    /// The link runs over Unix sockets; this system has none.
    #[error("the link between an editor and the app needs Unix sockets, which this system lacks")]
    Unsupported,
}

/// `$XDG_RUNTIME_DIR/rayoflight`, made if missing (mode 0700), checked to
/// be the user's own folder that no one else may enter.
pub fn folder() -> Result<PathBuf, LinkError> {
    if cfg!(not(unix)) {
        return Err(LinkError::Unsupported);
    }
    let runtime = std::env::var_os("XDG_RUNTIME_DIR")
        .map(PathBuf::from)
        .filter(|p| p.is_absolute())
        .ok_or(LinkError::NoRuntimeDir)?;
    let path = runtime.join("rayoflight");
    folder_in(&path)
}

/// [`folder`] at `path`: the user's own, closed to others, and so is the
/// folder it is in ([`crate::system::files::own_folder`]).
pub fn folder_in(path: &Path) -> Result<PathBuf, LinkError> {
    let io = |source| LinkError::Io {
        path: path.to_owned(),
        source,
    };
    let (Some(home), Some(name)) = (path.parent(), path.file_name().and_then(|n| n.to_str()))
    else {
        return Err(io(io::Error::other("not a folder's path")));
    };
    Ok(crate::system::files::own_folder(home, &[name], true)?)
}

/// Whether the process at the other end of `stream` is this user's
/// (Linux: `SO_PEERCRED`). Elsewhere (macOS, the BSDs) the kernel is not
/// asked: only this user (or root) can reach a socket in the private
/// folder, whose mode [`folder`] checked.
#[cfg(unix)]
pub fn peer_is_us(stream: &UnixStream) -> bool {
    #[cfg(any(target_os = "linux", target_os = "android"))]
    {
        rustix::net::sockopt::socket_peercred(stream)
            .is_ok_and(|cred| cred.uid == rustix::process::geteuid())
    }
    #[cfg(not(any(target_os = "linux", target_os = "android")))]
    {
        let _ = stream;
        true
    }
}

#[cfg(unix)]
/// An app's socket: removed when dropped.
#[derive(Debug)]
pub struct Listener {
    listener: UnixListener,
    path: PathBuf,
}

#[cfg(unix)]
impl Listener {
    /// Listens on `app-PID.sock` in `folder`.
    pub fn bind(folder: &Path) -> io::Result<Listener> {
        let path = folder.join(format!("app-{}.sock", std::process::id()));
        // A socket left by a process with the same PID long gone.
        let _ = std::fs::remove_file(&path);
        let listener = UnixListener::bind(&path)?;
        std::fs::set_permissions(&path, std::fs::Permissions::from_mode(0o600))?;
        Ok(Listener { listener, path })
    }

    /// The next connection of this user's (another user's is closed
    /// unread, and the wait goes on).
    pub fn accept(&self) -> io::Result<UnixStream> {
        loop {
            let (stream, _) = self.listener.accept()?;
            if peer_is_us(&stream) {
                return Ok(stream);
            }
        }
    }

    pub fn path(&self) -> &Path {
        &self.path
    }
}

#[cfg(unix)]
impl Drop for Listener {
    fn drop(&mut self) {
        let _ = std::fs::remove_file(&self.path);
    }
}

#[cfg(unix)]
/// The editors connected to an app, for the app to write to; each
/// connection is read on a thread of its own. Cloned, it is the same list.
#[derive(Debug, Clone, Default)]
pub struct Peers {
    streams: Arc<Mutex<Vec<(u64, UnixStream)>>>,
}

#[cfg(unix)]
/// How long a write to an editor may take before that editor is dropped:
/// a language server that stops reading never stalls the app's window.
const WRITE_PATIENCE: Duration = Duration::from_millis(200);

#[cfg(unix)]
impl Peers {
    fn lock(&self) -> std::sync::MutexGuard<'_, Vec<(u64, UnixStream)>> {
        self.streams.lock().unwrap_or_else(PoisonError::into_inner)
    }

    /// Adds the editor at the other end of `stream`; the number to
    /// [`Peers::remove`] it by when the connection ends.
    pub fn add(&self, stream: &UnixStream) -> io::Result<u64> {
        static NEXT: AtomicU64 = AtomicU64::new(0);
        let writer = stream.try_clone()?;
        writer.set_write_timeout(Some(WRITE_PATIENCE))?;
        let id = NEXT.fetch_add(1, Ordering::Relaxed);
        self.lock().push((id, writer));
        Ok(id)
    }

    pub fn remove(&self, id: u64) {
        self.lock().retain(|(n, _)| *n != id);
    }

    /// Sends `message` to the editor `id` ([`Peers::add`]), dropping it
    /// where it is not reached; whether it was.
    pub fn tell_one(&self, id: u64, message: &Message) -> bool {
        let mut streams = self.lock();
        let Some(i) = streams.iter().position(|(n, _)| *n == id) else {
            return false;
        };
        let sent = send(&mut streams[i].1, message).is_ok();
        if !sent {
            streams.remove(i);
        }
        sent
    }

    /// Sends `message` to every editor connected, dropping those it does
    /// not reach; how many it reached.
    pub fn tell(&self, message: &Message) -> usize {
        let mut streams = self.lock();
        streams.retain_mut(|(_, stream)| send(stream, message).is_ok());
        streams.len()
    }
}

/// The apps' sockets in `folder`.
pub fn apps(folder: &Path) -> Vec<PathBuf> {
    let Ok(entries) = std::fs::read_dir(folder) else {
        return Vec::new();
    };
    let mut apps: Vec<PathBuf> = entries
        .flatten()
        .map(|e| e.path())
        .filter(|p| {
            let name = p.file_name().and_then(|n| n.to_str()).unwrap_or_default();
            name.starts_with("app-") && name.ends_with(".sock")
        })
        .collect();
    apps.sort();
    apps
}

/// Connects to the app at `socket`, checking it is this user's; a socket
/// nobody listens on any more is removed.
#[cfg(not(unix))]
pub fn connect(_socket: &Path) -> io::Result<Stream> {
    Err(io::ErrorKind::Unsupported.into())
}

/// Connects to the app at `socket`, checking it is this user's; a socket
/// nobody listens on any more is removed.
#[cfg(unix)]
pub fn connect(socket: &Path) -> io::Result<UnixStream> {
    match UnixStream::connect(socket) {
        Ok(stream) if peer_is_us(&stream) => Ok(stream),
        Ok(_) => Err(io::Error::new(
            io::ErrorKind::PermissionDenied,
            "the app at the other end is another user's",
        )),
        Err(e) => {
            if e.kind() == io::ErrorKind::ConnectionRefused {
                let _ = std::fs::remove_file(socket);
            }
            Err(e)
        }
    }
}

/// Writes `message`.
pub fn send(w: &mut impl Write, message: &Message) -> io::Result<()> {
    let path = |p: &Path| p.to_string_lossy().into_owned();
    let (header, body) = match message {
        Message::Buffer { path: p, text } => (
            serde_json::json!({"kind": "buffer", "path": path(p), "bytes": text.len()}),
            text.as_bytes(),
        ),
        Message::Change {
            path: p,
            range,
            text,
            length,
        } => (
            serde_json::json!({"kind": "change", "path": path(p), "start": range.start,
                "end": range.end, "length": length, "bytes": text.len()}),
            text.as_bytes(),
        ),
        Message::Resend { path: p } => (
            serde_json::json!({"kind": "resend", "path": path(p)}),
            &[][..],
        ),
        Message::Released { path: p } => (
            serde_json::json!({"kind": "released", "path": path(p)}),
            &[][..],
        ),
        Message::Show { path: p, object } => (
            serde_json::json!({"kind": "show", "path": path(p), "object": object}),
            &[][..],
        ),
        Message::Select { path: p, under } => {
            let mut header = serde_json::json!({"kind": "select", "path": path(p)});
            match under {
                Some(Under::Object(n)) => header["object"] = (*n).into(),
                Some(Under::Light(n)) => header["light"] = (*n).into(),
                None => {}
            }
            (header, &[][..])
        }
    };
    let mut bytes = header.to_string().into_bytes();
    bytes.push(b'\n');
    bytes.extend_from_slice(body);
    w.write_all(&bytes)?;
    w.flush()
}

/// The largest buffer the link carries: the loader's largest file.
const MAX_BYTES: u64 = crate::scene::MAX_FILE_BYTES;

/// Reads the next message; `None` at the end of the stream.
pub fn receive(r: &mut impl BufRead) -> io::Result<Option<Message>> {
    let bad = |what: &str| io::Error::new(io::ErrorKind::InvalidData, what.to_owned());
    let mut line = String::new();
    if r.by_ref().take(64 * 1024).read_line(&mut line)? == 0 {
        return Ok(None);
    }
    let header: serde_json::Value =
        serde_json::from_str(line.trim_end()).map_err(|_| bad("not a message header"))?;
    let path = header["path"]
        .as_str()
        .map(PathBuf::from)
        .ok_or_else(|| bad("a message without a path"))?;
    let number = |key: &str| {
        header[key]
            .as_u64()
            .ok_or_else(|| bad("a message without its numbers"))
    };
    let size = |key: &str| {
        let n = number(key)?;
        if n > MAX_BYTES {
            return Err(bad("a text larger than a scene may be"));
        }
        usize::try_from(n).map_err(|_| bad("a text larger than a scene may be"))
    };
    let mut body = |bytes: usize| -> io::Result<String> {
        let mut text = Vec::with_capacity(bytes);
        r.by_ref().take(bytes as u64).read_to_end(&mut text)?;
        if text.len() != bytes {
            return Err(bad("a text cut short"));
        }
        String::from_utf8(text).map_err(|_| bad("a text not in UTF-8"))
    };
    Ok(Some(match header["kind"].as_str() {
        Some("buffer") => Message::Buffer {
            path,
            text: body(size("bytes")?)?,
        },
        Some("change") => {
            let (start, end, length) = (size("start")?, size("end")?, size("length")?);
            if start > end {
                return Err(bad("a change that ends before it starts"));
            }
            Message::Change {
                path,
                range: start..end,
                text: body(size("bytes")?)?,
                length,
            }
        }
        Some("resend") => Message::Resend { path },
        Some("released") => Message::Released { path },
        Some("show") => Message::Show {
            path,
            object: usize::try_from(number("object")?)
                .map_err(|_| bad("an object out of range"))?,
        },
        Some("select") => {
            let index = |key: &str| match header.get(key) {
                None => Ok(None),
                Some(_) => usize::try_from(number(key)?)
                    .map(Some)
                    .map_err(|_| bad("an index out of range")),
            };
            let under = match (index("object")?, index("light")?) {
                (Some(n), None) => Some(Under::Object(n)),
                (None, Some(n)) => Some(Under::Light(n)),
                (None, None) => None,
                (Some(_), Some(_)) => return Err(bad("an object and a light at once")),
            };
            Message::Select { path, under }
        }
        _ => return Err(bad("an unknown message")),
    }))
}

/// The file path of a `file:` URI (`file:///home/me/a%20b.xml`), if it is
/// one.
pub fn uri_path(uri: &str) -> Option<PathBuf> {
    let rest = uri.strip_prefix("file://")?;
    // `file://host/path`: only the local host, written empty or localhost.
    let rest = rest.strip_prefix("localhost").unwrap_or(rest);
    if !rest.starts_with('/') {
        return None;
    }
    let bytes = rest.as_bytes();
    let mut out = Vec::with_capacity(bytes.len());
    let mut i = 0;
    while i < bytes.len() {
        if bytes[i] == b'%' {
            let hex = std::str::from_utf8(bytes.get(i + 1..i + 3)?).ok()?;
            out.push(u8::from_str_radix(hex, 16).ok()?);
            i += 3;
        } else {
            out.push(bytes[i]);
            i += 1;
        }
    }
    #[cfg(unix)]
    {
        use std::os::unix::ffi::OsStringExt;
        Some(PathBuf::from(std::ffi::OsString::from_vec(out)))
    }
    #[cfg(not(unix))]
    {
        // Windows: `file:///C:/scenes/a.xml` names `C:/scenes/a.xml`.
        let text = String::from_utf8(out).ok()?;
        let drive = matches!(text.as_bytes(), [b'/', d, b':', ..] if d.is_ascii_alphabetic());
        Some(PathBuf::from(if drive { &text[1..] } else { &text[..] }))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn messages_read_back_as_written() {
        let messages = [
            Message::Buffer {
                path: "/a b/é.xml".into(),
                text: "<scene>\n\u{1F600}\n</scene>".into(),
            },
            Message::Change {
                path: "/s.xml".into(),
                range: 3..5,
                text: "é\n".into(),
                length: 40,
            },
            Message::Resend {
                path: "/s.xml".into(),
            },
            Message::Released {
                path: "/s.xml".into(),
            },
            Message::Show {
                path: "/s.xml".into(),
                object: 1,
            },
            Message::Select {
                path: "/s.xml".into(),
                under: Some(Under::Object(0)),
            },
            Message::Select {
                path: "/s.xml".into(),
                under: Some(Under::Light(2)),
            },
            Message::Select {
                path: "/s.xml".into(),
                under: None,
            },
        ];
        let mut bytes = Vec::new();
        for m in &messages {
            send(&mut bytes, m).unwrap();
        }
        let mut r = io::BufReader::new(&bytes[..]);
        for m in &messages {
            assert_eq!(receive(&mut r).unwrap().as_ref(), Some(m));
        }
        assert_eq!(receive(&mut r).unwrap(), None);
        // The first buffer cut short, five bytes into its text.
        let header = bytes.iter().position(|&b| b == b'\n').unwrap();
        let mut cut = io::BufReader::new(&bytes[..header + 6]);
        assert!(receive(&mut cut).is_err());
    }

    #[test]
    fn file_uris_give_their_paths() {
        assert_eq!(
            uri_path("file:///home/me/a%20b.xml"),
            Some("/home/me/a b.xml".into())
        );
        assert_eq!(uri_path("file://localhost/s.xml"), Some("/s.xml".into()));
        assert_eq!(uri_path("file:///%C3%A9.xml"), Some("/é.xml".into()));
        assert_eq!(uri_path("untitled:1"), None);
        assert_eq!(uri_path("file://other/s.xml"), None);
        assert_eq!(uri_path("file:///bad%zz"), None);
    }

    #[test]
    fn the_folder_is_ours_alone_and_an_app_is_reached_through_it() {
        let dir = tempfile::tempdir().unwrap();
        let folder = folder_in(&dir.path().join("rayoflight")).unwrap();
        let mode = std::fs::metadata(&folder).unwrap().permissions().mode() & 0o777;
        assert_eq!(mode, 0o700);
        let open = dir.path().join("open");
        std::fs::create_dir(&open).unwrap();
        std::fs::set_permissions(&open, std::fs::Permissions::from_mode(0o755)).unwrap();
        assert!(matches!(folder_in(&open), Err(LinkError::Unsafe(_))));

        let listener = Listener::bind(&folder).unwrap();
        assert_eq!(apps(&folder), [listener.path().to_owned()]);
        let sent = Message::Released {
            path: "/s.xml".into(),
        };
        let writer = {
            let socket = listener.path().to_owned();
            let sent = sent.clone();
            std::thread::spawn(move || {
                let mut stream = connect(&socket).unwrap();
                send(&mut stream, &sent).unwrap();
            })
        };
        let stream = listener.accept().unwrap();
        writer.join().unwrap();
        let mut r = io::BufReader::new(stream);
        assert_eq!(receive(&mut r).unwrap(), Some(sent));
        let path = listener.path().to_owned();
        drop(listener);
        assert!(!path.exists());
    }
}
