//! `rayoflight lsp` with a real client (issue 29): Neovim, headless, its
//! own LSP client scripted in Lua (`tests/lsp/client.lua`), on a copy of
//! the example scene. Diagnostics come at the right place after
//! non-ASCII text as the buffer changes, and go when it is fixed;
//! completion, hover and symbols answer; the file is never written.

mod common;

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

/// The editor's unsaved text goes to the user's apps over the link
/// (`rayoflight::editor_link`): a listener in a private runtime folder
/// gets the typed text before any save, then "released" when the editor
/// saves.
#[test]
fn the_unsaved_text_reaches_a_listening_app_and_the_save_releases_it() {
    use rayoflight::editor_link::{self, Listener, Message};
    if !common::tool("nvim", "neovim") {
        return;
    }
    let dir = tempfile::tempdir().unwrap();
    let scene = dir.path().join("s.xml");
    fs::write(&scene, rayoflight::EXAMPLE_SCENE).unwrap();
    let runtime = dir.path().join("run");
    fs::create_dir(&runtime).unwrap();
    let folder = editor_link::folder_in(&runtime.join("rayoflight")).unwrap();
    let listener = Listener::bind(&folder).unwrap();
    let (tx, rx) = std::sync::mpsc::channel();
    std::thread::spawn(move || {
        let Ok(stream) = listener.accept() else {
            return;
        };
        let mut r = std::io::BufReader::new(stream);
        while let Ok(Some(m)) = editor_link::receive(&mut r) {
            let _ = tx.send((m, fs::read_to_string(&scene).unwrap_or_default()));
        }
    });
    let o = neovim(
        dir.path(),
        "link.lua",
        &[("XDG_RUNTIME_DIR", runtime.as_os_str())],
    );
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let got: Vec<(Message, String)> = rx.try_iter().collect();
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
