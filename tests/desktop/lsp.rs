//! `rayoflight lsp` with a real client: Neovim, headless, its
//! own LSP client scripted in Lua (`tests/lsp/client.lua`), on a copy of
//! the example scene. Diagnostics come at the right place after
//! non-ASCII text as the buffer changes, and go when it is fixed;
//! completion, hover and symbols answer; the file is never written.

use crate::common;

use std::fs;
use std::path::Path;
use std::process::Command;

/// Neovim, headless, running `tests/lsp/SCRIPT` in `dir` with the server
/// as `$ROL_BIN` and `vars`; at most a minute.
fn neovim(dir: &Path, script: &str, vars: &[(&str, &std::ffi::OsStr)]) -> std::process::Output {
    let script = Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("tests/lsp")
        .join(script);
    Command::new("timeout")
        .arg("60")
        .args(["nvim", "--headless", "--clean", "-u", "NONE", "-S"])
        .arg(&script)
        .current_dir(dir)
        .env("ROL_BIN", env!("CARGO_BIN_EXE_rayoflight"))
        .env("HOME", dir)
        .env("XDG_STATE_HOME", dir.join("state"))
        .env("XDG_DATA_HOME", dir.join("data"))
        .envs(vars.iter().copied())
        .output()
        .unwrap()
}

#[test]
fn neovim_gets_diagnostics_completion_hover_and_symbols() {
    if !common::tool("nvim", "neovim") {
        return;
    }
    let dir = tempfile::tempdir().unwrap();
    let scene = dir.path().join("s.xml");
    fs::write(&scene, rayoflight::EXAMPLE_SCENE).unwrap();
    let out = dir.path().join("out.json");
    let o = neovim(dir.path(), "client.lua", &[("ROL_OUT", out.as_os_str())]);
    let said = format!(
        "{}{}",
        String::from_utf8_lossy(&o.stdout),
        String::from_utf8_lossy(&o.stderr)
    );
    assert!(o.status.success(), "nvim: {said}");
    let got: serde_json::Value =
        serde_json::from_str(&fs::read_to_string(&out).expect("the client wrote its results"))
            .unwrap();
    assert_eq!(got["initialized"], true, "{got}");
    assert_eq!(got["server_encoding"], "utf-16", "{got}");
    // The typed line: ' <!-- é😀 --><material ka="-1" …'; Neovim gives
    // the column in bytes, converted from the server's UTF-16 units.
    let line = " <!-- é😀 --><material ka=\"-1\"";
    let ka = line.find("ka").unwrap();
    assert_eq!(got["got_diag"], true, "{got}");
    assert_eq!(got["diag"]["lnum"], 4, "{got}");
    assert_eq!(got["diag"]["col"], ka, "{got}");
    assert_eq!(got["diag"]["end_col"], ka + 2, "{got}");
    assert_eq!(
        got["diag"]["message"],
        "<material> attribute ka=\"-1\" must be >= 0"
    );
    assert_eq!(got["cleared"], true, "the fixed text clears it: {got}");
    assert_eq!(
        got["completion"],
        serde_json::json!(["ka", "kd", "ks", "m"]),
        "{got}"
    );
    let hover = got["hover"].as_str().unwrap_or_default();
    assert!(
        hover.starts_with("Ambient coefficient") && hover.ends_with("Default: 0.2."),
        "{got}"
    );
    assert_eq!(
        got["symbols"],
        serde_json::json!([
            "#1 sphere@2",
            "#2 sphere@9",
            "light 1@16",
            "camera@19",
            "model@24"
        ]),
        "{got}"
    );
    assert_eq!(
        fs::read_to_string(&scene).unwrap(),
        rayoflight::EXAMPLE_SCENE
    );
}

/// A runtime folder `run` in `dir` and an app's socket listening in it,
/// as the app makes them (`rayoflight::desktop::editor_link`).
fn listening_app(
    dir: &Path,
) -> (
    std::path::PathBuf,
    rayoflight::desktop::editor_link::Listener,
) {
    use rayoflight::desktop::editor_link;
    let runtime = dir.join("run");
    fs::create_dir(&runtime).unwrap();
    let folder = editor_link::folder_in(&runtime.join("rayoflight")).unwrap();
    (runtime, editor_link::Listener::bind(&folder).unwrap())
}

/// The editor's unsaved text goes to the user's apps over the link
/// (`rayoflight::desktop::editor_link`): a listener in a private runtime folder
/// gets the text whole once, then each edit as a change, which applied to
/// its copy gives the typed text before any save; then "released" when the
/// editor saves.
#[test]
fn the_unsaved_text_reaches_a_listening_app_and_the_save_releases_it() {
    use rayoflight::desktop::editor_link::{self, Message};
    if !common::tool("nvim", "neovim") {
        return;
    }
    let dir = tempfile::tempdir().unwrap();
    let scene = dir.path().join("s.xml");
    fs::write(&scene, rayoflight::EXAMPLE_SCENE).unwrap();
    let (runtime, listener) = listening_app(dir.path());
    let (tx, rx) = std::sync::mpsc::channel();
    std::thread::spawn(move || {
        let Ok(stream) = listener.accept() else {
            return;
        };
        let mut r = std::io::BufReader::new(stream);
        // The app's copy of the editor's text.
        let mut held: Option<String> = None;
        while let Ok(Some(m)) = editor_link::receive(&mut r) {
            let kind = format!("{m:?}")
                .split([' ', '{'])
                .next()
                .unwrap_or_default()
                .to_owned();
            // A change is told as the text it makes.
            let m = match m {
                Message::Buffer { path, text } => {
                    held = Some(text.clone());
                    Message::Buffer { path, text }
                }
                Message::Change {
                    path,
                    range,
                    text,
                    length,
                } => {
                    let copy = held.as_mut().expect("a change after a whole text");
                    copy.replace_range(range, &text);
                    assert_eq!(copy.len(), length, "the change fits the copy");
                    Message::Buffer {
                        path,
                        text: copy.clone(),
                    }
                }
                m => m,
            };
            let on_disk = fs::read_to_string(&scene).unwrap_or_default();
            let _ = tx.send((m, on_disk, kind));
        }
    });
    let o = neovim(
        dir.path(),
        "link.lua",
        &[("XDG_RUNTIME_DIR", runtime.as_os_str())],
    );
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let got: Vec<(Message, String, String)> = rx.try_iter().collect();
    let kinds: Vec<&str> = got.iter().map(|(_, _, kind)| kind.as_str()).collect();
    assert_eq!(
        kinds.iter().filter(|k| **k == "Buffer").count(),
        1,
        "{kinds:?}"
    );
    assert!(
        kinds.contains(&"Change"),
        "edits travel as edits: {kinds:?}"
    );
    let got: Vec<(Message, String)> = got.into_iter().map(|(m, d, _)| (m, d)).collect();
    let path = fs::canonicalize(dir.path()).unwrap().join("s.xml");
    let typed = rayoflight::EXAMPLE_SCENE.replacen("ka=\"0.3\"", "ka=\"0.9\"", 1);
    let unsaved = got.iter().position(|(m, on_disk)| {
        *m == Message::Buffer {
            path: path.clone(),
            text: typed.clone(),
        } && on_disk == rayoflight::EXAMPLE_SCENE
    });
    assert!(unsaved.is_some(), "the typed text before the save: {got:?}");
    let released = got
        .iter()
        .position(|(m, _)| *m == Message::Released { path: path.clone() });
    assert!(released > unsaved, "released after the text: {got:?}");
}

/// Two spheres, the second one's start tag after non-ASCII text on its
/// line (UTF-16 columns differ from bytes and from characters there).
const TWO_SPHERES: &str = "<scene>\n  <sphere>\n    <color red=\"1\" green=\"0\" blue=\"0\"/>\n  </sphere>\n  <!-- é😀 --><sphere>\n    <color red=\"0\" green=\"1\" blue=\"0\"/>\n    <transformation><translate x=\"2\"/></transformation>\n  </sphere>\n  <camera width=\"8\" height=\"6\" eyeDistance=\"2\"/>\n</scene>\n";

/// Picture ↔ source over the link: the editor's cursor in the second
/// sphere's element selects it in a listening app (and the editor's
/// answer highlights its start tag), and the app's click on it becomes a
/// `window/showDocument` request for the element's whole range, leaving
/// the focus where it is.
#[test]
fn the_cursor_selects_in_the_app_and_a_click_shows_the_element() {
    use rayoflight::desktop::editor_link::{self, Message};
    if !common::tool("nvim", "neovim") {
        return;
    }
    let dir = tempfile::tempdir().unwrap();
    let scene = dir.path().join("s.xml");
    fs::write(&scene, TWO_SPHERES).unwrap();
    let (runtime, listener) = listening_app(dir.path());
    let path = fs::canonicalize(&scene).unwrap();
    let (tx, rx) = std::sync::mpsc::channel();
    std::thread::spawn(move || {
        let Ok(stream) = listener.accept() else {
            return;
        };
        let peers = editor_link::Peers::default();
        peers.add(&stream).unwrap();
        let mut r = std::io::BufReader::new(stream);
        while let Ok(Some(m)) = editor_link::receive(&mut r) {
            // The app's answer to the cursor: a click on the same object.
            if let Message::Select {
                path,
                under: Some(editor_link::Under::Object(object)),
            } = &m
            {
                let show = Message::Show {
                    path: path.clone(),
                    object: *object,
                };
                assert_eq!(peers.tell(&show), 1);
            }
            let _ = tx.send(m);
        }
    });
    let out = dir.path().join("out.json");
    let line = TWO_SPHERES
        .lines()
        .position(|l| l.contains("green=\"1\""))
        .unwrap();
    // Then the camera's line: in no object's element.
    let leave = TWO_SPHERES
        .lines()
        .position(|l| l.contains("<camera"))
        .unwrap();
    let o = neovim(
        dir.path(),
        "show.lua",
        &[
            ("XDG_RUNTIME_DIR", runtime.as_os_str()),
            ("ROL_FILE", scene.as_os_str()),
            ("ROL_OUT", out.as_os_str()),
            ("ROL_CURSOR_LINE", line.to_string().as_ref()),
            ("ROL_LEAVE_LINE", leave.to_string().as_ref()),
        ],
    );
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let got: serde_json::Value =
        serde_json::from_str(&fs::read_to_string(&out).expect("the client wrote its results"))
            .unwrap();
    let said: Vec<Message> = rx.try_iter().collect();
    assert!(
        said.contains(&Message::Select {
            path: path.clone(),
            under: Some(editor_link::Under::Object(1))
        }),
        "{said:?}"
    );
    // The cursor left every element: the app is told to select nothing,
    // and the editor highlights nothing.
    let selects: Vec<&Message> = said
        .iter()
        .filter(|m| matches!(m, Message::Select { .. }))
        .collect();
    assert_eq!(
        selects.last(),
        Some(&&Message::Select {
            path: path.clone(),
            under: None
        }),
        "{said:?}"
    );
    assert_eq!(got["left_highlight"], serde_json::json!([]), "{got}");
    // The second sphere's start tag, after "  <!-- é😀 -->": 14 UTF-16
    // units (é is one, 😀 two; 16 bytes, 13 characters) on line 4.
    let tag_line = 4;
    let tag = TWO_SPHERES.lines().nth(tag_line).unwrap();
    let column = tag[..tag.find("<sphere>").unwrap()].encode_utf16().count();
    assert_eq!(column, 14);
    let at =
        |line: usize, character: usize| serde_json::json!({"line": line, "character": character});
    assert_eq!(
        got["highlight"],
        serde_json::json!([{"range": {"start": at(tag_line, column), "end": at(tag_line, column + 8)}, "kind": 1}]),
        "{got}"
    );
    assert_eq!(got["shown"], true, "the server asked to show it: {got}");
    let show = &got["show"];
    assert_eq!(show["takeFocus"], false, "{got}");
    assert_eq!(show["external"], false, "{got}");
    let (end_line, _) = TWO_SPHERES
        .lines()
        .enumerate()
        .filter(|(_, l)| *l == "  </sphere>")
        .nth(1)
        .unwrap();
    assert_eq!(
        show["selection"],
        serde_json::json!({"start": at(tag_line, column), "end": at(end_line, "  </sphere>".len())}),
        "{got}"
    );
    assert_eq!(
        editor_link::uri_path(show["uri"].as_str().unwrap_or_default()).as_deref(),
        Some(path.as_path()),
        "{got}"
    );
    // Neovim put its cursor on the element (1-based line, byte column).
    let byte_column = tag.find("<sphere>").unwrap();
    assert_eq!(
        got["cursor_after_show"],
        serde_json::json!([tag_line + 1, byte_column]),
        "{got}"
    );
    assert_eq!(fs::read_to_string(&scene).unwrap(), TWO_SPHERES);
}

/// The server as a client starts it, on pipes, with `messages` written to
/// its input in the protocol's framing; `close` closes its input after
/// them. What it did within 5 s: its exit status (`None`: still running,
/// then killed) and what it wrote.
fn lsp_session(messages: &[serde_json::Value], close: bool) -> (Option<i32>, String) {
    use std::io::{Read, Write};
    let mut server = Command::new(env!("CARGO_BIN_EXE_rayoflight"))
        .arg("lsp")
        .stdin(std::process::Stdio::piped())
        .stdout(std::process::Stdio::piped())
        .stderr(std::process::Stdio::piped())
        .spawn()
        .unwrap();
    let mut input = server.stdin.take().unwrap();
    for message in messages {
        let body = message.to_string();
        write!(input, "Content-Length: {}\r\n\r\n{body}", body.len()).unwrap();
    }
    input.flush().unwrap();
    // Held open, as an editor holds it, until the end, unless `close`.
    let input = (!close).then_some(input);
    let start = std::time::Instant::now();
    let status = loop {
        if let Some(status) = server.try_wait().unwrap() {
            break status.code();
        }
        if start.elapsed() > std::time::Duration::from_secs(5) {
            server.kill().unwrap();
            server.wait().unwrap();
            break None;
        }
        std::thread::sleep(std::time::Duration::from_millis(20));
    };
    drop(input);
    let mut said = String::new();
    server
        .stdout
        .take()
        .unwrap()
        .read_to_string(&mut said)
        .unwrap();
    server
        .stderr
        .take()
        .unwrap()
        .read_to_string(&mut said)
        .unwrap();
    (status, said)
}

/// The server ends as the protocol says: at `exit`, with status 0 after a
/// `shutdown` and 1 without; and when the editor goes without a word (its
/// end of the pipe closed), with status 1. A server that stayed was left
/// running by every editor that quit, with nobody to read what it wrote.
#[test]
fn the_server_ends_at_exit_and_when_the_editor_goes() {
    use serde_json::json;
    let initialize = json!({"jsonrpc": "2.0", "id": 1, "method": "initialize",
        "params": {"capabilities": {}, "processId": null, "rootUri": null}});
    let initialized = json!({"jsonrpc": "2.0", "method": "initialized", "params": {}});
    let open = json!({"jsonrpc": "2.0", "method": "textDocument/didOpen", "params": {
        "textDocument": {"uri": "file:///tmp/s.xml", "languageId": "xml", "version": 1,
            "text": rayoflight::EXAMPLE_SCENE}}});
    let shutdown = json!({"jsonrpc": "2.0", "id": 2, "method": "shutdown"});
    let exit = json!({"jsonrpc": "2.0", "method": "exit"});
    let start = [initialize, initialized, open];

    let with = |more: &[&serde_json::Value]| {
        let mut all: Vec<_> = start.to_vec();
        all.extend(more.iter().map(|m| (*m).clone()));
        all
    };
    let (status, said) = lsp_session(&with(&[&shutdown, &exit]), false);
    assert_eq!(status, Some(0), "shutdown, exit: {said}");
    assert!(said.contains(r#""id":2,"result":null"#), "{said}");
    let (status, said) = lsp_session(&with(&[&exit]), false);
    assert_eq!(status, Some(1), "exit without shutdown: {said}");
    let (status, said) = lsp_session(&with(&[]), true);
    assert_eq!(status, Some(1), "the editor gone: {said}");
    let (status, said) = lsp_session(&with(&[&shutdown]), true);
    assert_eq!(status, Some(1), "gone after shutdown: {said}");
}

/// Writes one message of the protocol's framing whose body is `body`
/// with `fill` bytes of `a` in the middle, streamed (never held whole).
fn write_framed(
    input: &mut impl std::io::Write,
    head: &str,
    fill: usize,
    tail: &str,
) -> std::io::Result<()> {
    write!(
        input,
        "Content-Length: {}\r\n\r\n{head}",
        head.len() + fill + tail.len()
    )?;
    let chunk = vec![b'a'; 1 << 20];
    let mut left = fill;
    while left > 0 {
        let n = left.min(chunk.len());
        input.write_all(&chunk[..n])?;
        left -= n;
    }
    input.write_all(tail.as_bytes())
}

/// A header cannot exhaust the server. A length of a
/// terabyte announced, with or without its bytes, aborted it ("memory
/// allocation of 1000000000000 bytes failed"); now the message is
/// refused for its size, said to the editor and on stderr, and the
/// session goes on. Under an address-space limit, a document too large
/// for the memory left is refused the same way, not an abort.
#[test]
fn a_message_too_large_is_refused_and_the_session_goes_on() {
    use std::io::{Read, Write};
    use std::process::Stdio;
    let initialize = r#"{"jsonrpc":"2.0","id":1,"method":"initialize","params":{"capabilities":{},"processId":null,"rootUri":null}}"#;
    let end = [
        r#"{"jsonrpc":"2.0","id":2,"method":"shutdown"}"#,
        r#"{"jsonrpc":"2.0","method":"exit"}"#,
    ];
    let open_head = r#"{"jsonrpc":"2.0","method":"textDocument/didOpen","params":{"textDocument":{"uri":"file:///tmp/big.xml","languageId":"xml","version":1,"text":"<!-- "#;
    let open_tail = r#" -->"}}}"#;
    // (limit of the address space, bytes announced, bytes sent)
    for (limit, announced, fill) in [
        (None, Some(1_000_000_000_000u64), 0),
        (Some(512u64 << 20), None, 300usize << 20),
    ] {
        let mut cmd = match limit {
            Some(bytes) => {
                let mut c = Command::new("prlimit");
                c.arg(format!("--as={bytes}"))
                    .arg("--")
                    .arg(env!("CARGO_BIN_EXE_rayoflight"));
                c
            }
            None => Command::new(env!("CARGO_BIN_EXE_rayoflight")),
        };
        let mut server = cmd
            .arg("lsp")
            .stdin(Stdio::piped())
            .stdout(Stdio::piped())
            .stderr(Stdio::piped())
            .spawn()
            .unwrap();
        let mut input = server.stdin.take().unwrap();
        let mut out = server.stdout.take().unwrap();
        let reading = std::thread::spawn(move || {
            let mut said = String::new();
            out.read_to_string(&mut said).unwrap();
            said
        });
        write_framed(&mut input, initialize, 0, "").unwrap();
        write_framed(
            &mut input,
            r#"{"jsonrpc":"2.0","method":"initialized","params":{}}"#,
            0,
            "",
        )
        .unwrap();
        match announced {
            // The length announced and its bytes never sent: the server
            // waits for them holding nothing, and the editor ends.
            Some(n) => write!(input, "Content-Length: {n}\r\n\r\n").unwrap(),
            None => {
                write_framed(&mut input, open_head, fill, open_tail).unwrap();
                for m in end {
                    write_framed(&mut input, m, 0, "").unwrap();
                }
            }
        }
        drop(input);
        let status = server.wait().unwrap();
        let said = reading.join().unwrap();
        let mut err = String::new();
        server
            .stderr
            .take()
            .unwrap()
            .read_to_string(&mut err)
            .unwrap();
        assert!(!err.contains("memory allocation"), "{err}");
        match announced {
            Some(_) => {
                assert_eq!(status.code(), Some(1), "the editor gone: {err}");
                assert!(said.contains(r#""id":1"#), "{said}");
                // Said as soon as the header is read.
                let why = "rayoflight lsp: a message of 1000000000000 bytes is over the limit \
                           of 537 MB (536870912 bytes); the message was dropped";
                assert_eq!(err.lines().next(), Some(why), "{err}");
                assert!(said.contains(why), "{said}");
            }
            None => {
                assert_eq!(status.code(), Some(0), "{err}");
                let length = open_head.len() + fill + open_tail.len();
                let why = format!("rayoflight lsp: a message of {length} bytes needs");
                assert!(err.starts_with(&why), "{err}");
                assert!(err.contains("; the message was dropped"), "{err}");
                assert!(said.contains(r#""method":"window/showMessage""#), "{said}");
                assert!(said.contains(&why), "{said}");
                assert!(said.contains(r#""id":2,"result":null"#), "{said}");
            }
        }
    }
}

/// A server on pipes, talked to a message at a time as an editor talks.
struct Server {
    child: std::process::Child,
    input: std::process::ChildStdin,
    output: std::io::BufReader<std::process::ChildStdout>,
}

impl Server {
    /// `rayoflight lsp` with `env` changed, initialized.
    fn start(env: &[(&str, Option<&str>)]) -> Server {
        use std::process::Stdio;
        let mut command = Command::new(env!("CARGO_BIN_EXE_rayoflight"));
        command
            .arg("lsp")
            .stdin(Stdio::piped())
            .stdout(Stdio::piped());
        for (name, value) in env {
            match value {
                Some(value) => command.env(name, value),
                None => command.env_remove(name),
            };
        }
        let mut child = command.spawn().unwrap();
        let input = child.stdin.take().unwrap();
        let output = std::io::BufReader::new(child.stdout.take().unwrap());
        let mut server = Server {
            child,
            input,
            output,
        };
        server.request(
            0,
            "initialize",
            serde_json::json!({"capabilities": {}, "processId": null, "rootUri": null}),
        );
        server.notify("initialized", serde_json::json!({}));
        server
    }

    fn send(&mut self, message: serde_json::Value) {
        use std::io::Write;
        let body = message.to_string();
        write!(self.input, "Content-Length: {}\r\n\r\n{body}", body.len()).unwrap();
        self.input.flush().unwrap();
    }

    fn notify(&mut self, method: &str, params: serde_json::Value) {
        self.send(serde_json::json!({"jsonrpc": "2.0", "method": method, "params": params}));
    }

    /// The next message the server sends.
    fn receive(&mut self) -> serde_json::Value {
        use std::io::{BufRead, Read};
        let mut length = 0;
        loop {
            let mut line = String::new();
            assert!(
                self.output.read_line(&mut line).unwrap() > 0,
                "the server ended"
            );
            if line.trim().is_empty() {
                break;
            }
            if let Some(n) = line.to_ascii_lowercase().strip_prefix("content-length:") {
                length = n.trim().parse().unwrap();
            }
        }
        let mut body = vec![0; length];
        self.output.read_exact(&mut body).unwrap();
        serde_json::from_slice(&body).unwrap()
    }

    /// The answer to a request, what came before it passed over.
    fn request(&mut self, id: u64, method: &str, params: serde_json::Value) -> serde_json::Value {
        self.send(
            serde_json::json!({"jsonrpc": "2.0", "id": id, "method": method, "params": params}),
        );
        loop {
            let message = self.receive();
            if message["id"] == id && message.get("method").is_none() {
                return message;
            }
        }
    }

    /// The first notification of `method` (others passed over).
    fn notification(&mut self, method: &str) -> serde_json::Value {
        loop {
            let message = self.receive();
            if message["method"] == method {
                return message["params"].clone();
            }
        }
    }

    fn end(mut self) {
        self.request(99, "shutdown", serde_json::Value::Null);
        self.notify("exit", serde_json::Value::Null);
        assert!(self.child.wait().unwrap().success());
    }
}

/// The preview is one command away: a code lens on the root's start tag
/// and a code action anywhere run `rayoflight.preview`, which starts the
/// app on the document; with no display to open a window on, the app's
/// own word comes back to the editor as an error message. A bad argument
/// is an error answer.
#[test]
fn the_preview_command_is_offered_and_starts_the_app() {
    let dir = tempfile::tempdir().unwrap();
    let scene = dir.path().join("s.xml");
    fs::write(&scene, rayoflight::EXAMPLE_SCENE).unwrap();
    let uri = format!("file://{}", scene.display());
    let mut server = Server::start(&[
        ("DISPLAY", None),
        ("WAYLAND_DISPLAY", None),
        ("XDG_RUNTIME_DIR", Some(dir.path().to_str().unwrap())),
    ]);
    let text = rayoflight::EXAMPLE_SCENE;
    server.notify(
        "textDocument/didOpen",
        serde_json::json!({"textDocument": {"uri": uri, "languageId": "xml", "version": 1, "text": text}}),
    );
    let document = serde_json::json!({"uri": uri});
    let lenses = server.request(
        1,
        "textDocument/codeLens",
        serde_json::json!({"textDocument": document}),
    );
    let lens = &lenses["result"][0];
    let root_line = text.lines().position(|l| l.contains("<scene")).unwrap();
    assert_eq!(lens["range"]["start"]["line"], root_line, "{lenses}");
    assert_eq!(lens["command"]["command"], "rayoflight.preview");
    assert_eq!(lens["command"]["arguments"], serde_json::json!([uri]));
    let range = serde_json::json!({"start": {"line": 5, "character": 0}, "end": {"line": 5, "character": 0}});
    let actions = server.request(
        2,
        "textDocument/codeAction",
        serde_json::json!({"textDocument": document, "range": range, "context": {"diagnostics": []}}),
    );
    assert_eq!(
        actions["result"][0]["command"], "rayoflight.preview",
        "{actions}"
    );
    let bad = server.request(
        3,
        "workspace/executeCommand",
        serde_json::json!({"command": "rayoflight.preview", "arguments": ["http://example.com/s.xml"]}),
    );
    assert!(
        bad["error"]["message"]
            .as_str()
            .unwrap()
            .contains("not a file"),
        "{bad}"
    );
    let started = server.request(
        4,
        "workspace/executeCommand",
        serde_json::json!({"command": "rayoflight.preview", "arguments": [uri]}),
    );
    assert_eq!(started["result"], serde_json::Value::Null, "{started}");
    let said = server.notification("window/showMessage");
    assert_eq!(said["type"], 1, "an error: {said}");
    let message = said["message"].as_str().unwrap();
    assert!(
        message.contains("display") && message.contains("--no-gui"),
        "{message}"
    );
    server.end();
    assert_eq!(fs::read_to_string(&scene).unwrap(), text, "nothing written");
}

/// An outline too long to list: a million-object scene's symbols are a
/// group with the first objects and a "more" entry, and any object is
/// found by name (`workspace/symbol`).
#[test]
fn a_long_outline_is_grouped_and_any_object_found_by_name() {
    let n = 20_000;
    let mut text = String::from("<scene>\n<camera width=\"2\" height=\"2\" eyeDistance=\"1\"/>\n");
    for _ in 0..n {
        text.push_str("<sphere/>\n");
    }
    text.push_str("</scene>\n");
    let uri = "file:///tmp/long.xml";
    let mut server = Server::start(&[]);
    server.notify(
        "textDocument/didOpen",
        serde_json::json!({"textDocument": {"uri": uri, "languageId": "xml", "version": 1, "text": text}}),
    );
    let answer = server.request(
        1,
        "textDocument/documentSymbol",
        serde_json::json!({"textDocument": {"uri": uri}}),
    );
    let symbols = answer["result"].as_array().unwrap();
    let names: Vec<&str> = symbols
        .iter()
        .map(|s| s["name"].as_str().unwrap())
        .collect();
    assert_eq!(names, ["camera", "20000 objects"]);
    let group = symbols[1]["children"].as_array().unwrap();
    assert_eq!(group.len(), rayoflight::scene::language::SYMBOLS_LISTED + 1);
    assert_eq!(group.last().unwrap()["name"], "… 19500 more objects");
    assert_eq!(group.last().unwrap()["range"]["end"]["line"], n + 1);
    assert!(
        answer.to_string().len() < 200_000,
        "{} bytes",
        answer.to_string().len()
    );
    let found = server.request(
        2,
        "workspace/symbol",
        serde_json::json!({"query": "#12345 "}),
    );
    let found = found["result"].as_array().unwrap();
    assert_eq!(found.len(), 1, "{found:?}");
    assert_eq!(found[0]["name"], "#12345 sphere");
    assert_eq!(found[0]["location"]["range"]["start"]["line"], 12345 + 1);
    server.end();
}
