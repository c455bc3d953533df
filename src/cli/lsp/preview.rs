//! `rayoflight.preview`: the app started from the editor on the document
//! being edited, as typst's preview is one command away. The editor runs
//! it through `workspace/executeCommand`; the server offers it as a code
//! lens on the root element (`▶ Preview in RayOfLight`) and as a code
//! action anywhere in a scene, for editors without lenses (eglot).
//!
//! The app is this same binary, run on the document's file in a process
//! group of its own (the editor's end of the server does not end it). It
//! opens the file, and the server, which looks for new apps every second,
//! hands it the editor's unsaved text: the picture follows the buffer, not
//! the disk. An app that fails to start (no display, a build without the
//! app) is said to the editor with the app's own message.

use std::io::Read;
use std::path::Path;
use std::process::{Command as Process, Stdio};

use lsp_server::Notification;
use lsp_types::notification::{Notification as _, ShowMessage};
use lsp_types::{
    CodeActionOrCommand, CodeActionResponse, CodeLens, Command, MessageType, ShowMessageParams, Uri,
};
use rayoflight::desktop::editor_link;
use rayoflight::scene::language::Lines;

use super::Send;

/// The command's name, as editors call it.
pub const COMMAND: &str = "rayoflight.preview";

/// The command as a lens or an action shows it, on the document at `uri`.
fn command(uri: &Uri) -> Command {
    Command {
        title: "▶ Preview in RayOfLight".to_owned(),
        command: COMMAND.to_owned(),
        arguments: Some(vec![serde_json::Value::String(uri.as_str().to_owned())]),
    }
}

/// The lens over the root's start tag (`<scene`); none without one.
pub fn lenses(text: &str, lines: &Lines, uri: &Uri) -> Vec<CodeLens> {
    let root = text.match_indices("<scene").find(|(at, tag)| {
        text[at + tag.len()..]
            .bytes()
            .next()
            .is_some_and(|b| b.is_ascii_whitespace() || b == b'>' || b == b'/')
    });
    root.map(|(at, tag)| CodeLens {
        range: super::range(text, lines, at..at + tag.len()),
        command: Some(command(uri)),
        data: None,
    })
    .into_iter()
    .collect()
}

/// The code actions of a scene: the preview, wherever the cursor is.
pub fn actions(uri: &Uri) -> CodeActionResponse {
    vec![CodeActionOrCommand::Command(command(uri))]
}

/// Starts the app on the file of `uri` (the command's one argument);
/// what went wrong, for the editor, when it cannot be started. An app
/// that starts and then fails is said to the editor through `send`.
pub fn start(arguments: &[serde_json::Value], send: Send) -> Result<(), String> {
    let uri = match arguments {
        [serde_json::Value::String(uri)] => uri,
        _ => return Err(format!("{COMMAND} takes one argument: the scene's URI")),
    };
    let path = editor_link::uri_path(uri)
        .ok_or_else(|| format!("{COMMAND}: {uri} is not a file on this machine"))?;
    if !cfg!(feature = "gui") {
        return Err(format!(
            "{COMMAND}: this rayoflight was built without the app (the gui feature)"
        ));
    }
    let exe =
        std::env::current_exe().map_err(|e| format!("{COMMAND}: where is rayoflight? {e}"))?;
    let child = app(&exe, &path)
        .spawn()
        .map_err(|e| format!("{COMMAND}: {} did not start: {e}", exe.display()))?;
    std::thread::spawn(move || said_on_failure(child, send));
    Ok(())
}

/// The app's process: on `path`, its output kept from the editor's
/// channel (stdout is the protocol's), in a process group of its own.
fn app(exe: &Path, path: &Path) -> Process {
    let mut app = Process::new(exe);
    app.arg("--")
        .arg(path)
        .stdin(Stdio::null())
        .stdout(Stdio::null())
        .stderr(Stdio::piped());
    #[cfg(unix)]
    std::os::unix::process::CommandExt::process_group(&mut app, 0);
    app
}

/// The most of the app's stderr kept, its end, for the message.
const KEPT: usize = 2048;

/// Waits for the app; when it ends in failure, tells the editor what it
/// said last.
fn said_on_failure(mut child: std::process::Child, send: Send) {
    let mut said = Vec::new();
    if let Some(mut stderr) = child.stderr.take() {
        let mut chunk = [0u8; 4096];
        while let Ok(n @ 1..) = stderr.read(&mut chunk) {
            said.extend_from_slice(&chunk[..n]);
            let over = said.len().saturating_sub(KEPT);
            said.drain(..over);
        }
    }
    let Ok(status) = child.wait() else {
        return;
    };
    if status.success() {
        return;
    }
    let said = String::from_utf8_lossy(&said);
    let message = match said.trim() {
        "" => format!("RayOfLight's preview ended: {status}"),
        said => format!("RayOfLight's preview ended: {said}"),
    };
    let params = ShowMessageParams {
        typ: MessageType::ERROR,
        message,
    };
    send(lsp_server::Message::Notification(Notification::new(
        ShowMessage::METHOD.to_owned(),
        params,
    )));
}
