//! `rayoflight lsp`: a language server for scene files on stdin and stdout
//! (lsp-server's loop, lsp-types' messages), for completion, hover
//! documentation, errors as you type, an outline (grouped past
//! [`language::SYMBOLS_LISTED`] objects, any of them found by name with
//! `workspace/symbol`) and the app's preview ([`preview`]) in any editor
//! with an LSP client.
//!
//! What it answers comes from `rayoflight::scene::language`; this module
//! only speaks the protocol. Positions are UTF-16 code units (the
//! protocol's default, which the server announces). Documents are synced
//! incrementally: a change is spliced into the document's text and its
//! line index is moved, not rebuilt. Errors are found off the message
//! loop, on a thread of their own that takes the newest text of each
//! changed document (shared, not copied) with the edits made since, and
//! checks it at most every 100 ms, reading only where the edits fall
//! ([`rayoflight::scene::Reading`]): a big buffer makes its errors come
//! later, never the typing slower. The same thread hands the user's
//! running apps ([`rayoflight::desktop::editor_link`]) each text whole once
//! (an app new, or that lost track of it and asked again), then the edits
//! since as one change ([`rayoflight::scene::Span`]: the bytes replaced
//! and what replaces them) before it checks the text, tells them when the editor saves or
//! closes the document, and which object the editor's cursor is in (a
//! `textDocument/documentHighlight` request, which editors send as the
//! cursor moves: the answer highlights that object's start tag). A click
//! on an object in an app comes back over the link and becomes a
//! `window/showDocument` request for its element, which leaves the focus
//! where it is.
//!
//! Messages come and go through [`transport`], which bounds a message's
//! size and memory before taking it ([`json`] takes a big document's text
//! out of its message in place). The server ends at the editor's
//! `exit`, or when the editor's end of stdin closes; every thread sends through one sender, let go then, so
//! that the thread writing to the editor ends too.

mod json;
mod preview;
mod transport;

use super::failure::Failure;
use super::subcommand::Subcommand;
use super::usage::UsageError;
use lsp_server::{Message, Notification, Request, RequestId, Response};
use lsp_types::notification::{
    DidChangeTextDocument, DidCloseTextDocument, DidOpenTextDocument, DidSaveTextDocument, Exit,
    Notification as _, PublishDiagnostics,
};
use lsp_types::notification::{LogMessage, ShowMessage};
use lsp_types::request::{
    CodeActionRequest, CodeLensRequest, Completion, DocumentHighlightRequest,
    DocumentSymbolRequest, ExecuteCommand, HoverRequest, Request as _, ShowDocument,
    WorkspaceSymbolRequest,
};
use lsp_types::{
    CodeActionParams, CodeActionProviderCapability, CodeLensOptions, CodeLensParams,
    CompletionItem, CompletionItemKind, CompletionOptions, CompletionParams, CompletionResponse,
    Diagnostic, DiagnosticSeverity, DidChangeTextDocumentParams, DidCloseTextDocumentParams,
    DidOpenTextDocumentParams, DidSaveTextDocumentParams, DocumentHighlight, DocumentHighlightKind,
    DocumentHighlightParams, DocumentSymbol, DocumentSymbolParams, DocumentSymbolResponse,
    Documentation, ExecuteCommandOptions, ExecuteCommandParams, Hover, HoverContents, HoverParams,
    HoverProviderCapability, Location, LogMessageParams, MarkupContent, MarkupKind, MessageType,
    OneOf, Position, PositionEncodingKind, PublishDiagnosticsParams, Range, ServerCapabilities,
    ShowDocumentParams, ShowMessageParams, SymbolInformation, SymbolKind,
    TextDocumentSyncCapability, TextDocumentSyncKind, TextDocumentSyncOptions, Uri,
    WorkspaceSymbolParams, WorkspaceSymbolResponse,
};
use rayoflight::desktop::editor_link;
use rayoflight::scene::Span;
use rayoflight::scene::language::{self, Lines, Place, Under};
use std::collections::HashMap;
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicBool, AtomicU64, Ordering};
use std::sync::mpsc;
use std::sync::{Arc, Mutex, PoisonError};
use std::time::{Duration, Instant};

/// `value` as JSON (`null` for none).
macro_rules! json {
    ($value:expr) => {
        $value
            .and_then(|v| serde_json::to_value(v).ok())
            .unwrap_or(serde_json::Value::Null)
    };
}

/// An open document: the editor's text, where its lines start, and where
/// a reading of it before a cursor may start again. The text and its
/// lines are shared with the threads that read them ([`Document::copy`]);
/// an edit while one reads copies them first ([`Arc::make_mut`]), so that
/// a document is held once, not once more for each reading.
struct Document {
    text: Arc<String>,
    lines: Arc<Lines>,
    marks: language::Marks,
    /// The edits since its errors were last checked, for the check to
    /// read only where they fall ([`rayoflight::scene::Reading`]).
    edits: Vec<Edit>,
}

/// An edit of a document, as its check is told of it.
enum Edit {
    /// These bytes (of the text as it then was) replaced by so many.
    Spliced(std::ops::Range<usize>, usize),
    /// The whole text replaced.
    Whole,
}

impl Document {
    /// Its text and line index, to scan with the lock let go (the message
    /// loop goes on changing the document meanwhile).
    fn copy(&self) -> (Arc<String>, Arc<Lines>) {
        (Arc::clone(&self.text), Arc::clone(&self.lines))
    }
}

/// The open documents, by URI, shared with the thread that checks them.
type Documents = Arc<Mutex<HashMap<String, Document>>>;

fn lock(documents: &Documents) -> std::sync::MutexGuard<'_, HashMap<String, Document>> {
    documents.lock().unwrap_or_else(PoisonError::into_inner)
}

/// What a notification changed, or where the cursor went.
#[derive(Debug, Clone, PartialEq)]
enum Changed {
    /// The text of a document (by key and URI).
    Text(String, Uri),
    /// The editor saved it: its text is the file's.
    Released(Uri),
    /// The editor closed it.
    Closed(String, Uri),
    /// The editor's cursor is at this byte of the document: the request
    /// to answer with the object there.
    Cursor(String, Uri, usize, RequestId),
    /// The app at this socket lost track of a text: it is handed every
    /// document whole again.
    Resend(PathBuf),
}

/// How the server sends a message to the editor, from any thread: false
/// once the editor has gone.
type Send = Arc<dyn Fn(Message) -> bool + std::marker::Send + Sync>;

/// The least time between two checks of the documents' errors.
const DIAGNOSE_EVERY: Duration = Duration::from_millis(100);

/// How often the runtime folder is looked at for apps started since.
const LOOK_FOR_APPS_EVERY: Duration = Duration::from_secs(1);

/// A language server for scene files, on stdin and stdout (LSP).
///
/// Errors as you type, at their line and column; completion of
/// elements, attributes and the model's types; what a name means on
/// hover; the objects, lights and camera as the document's symbols.
/// Start it from the editor's LSP client; see the README.
#[derive(clap::Args, Debug, Clone, PartialEq)]
#[command(override_usage = "rayoflight lsp")]
pub(super) struct LspFlags {}

impl Subcommand for LspFlags {
    type Args = LspFlags;

    fn resolve(self, _: &clap::ArgMatches) -> Result<LspFlags, UsageError> {
        Ok(self)
    }

    /// The protocol's messages are its own, not lines to check.
    fn prints(_: &LspFlags) -> bool {
        false
    }

    fn run(_: LspFlags, _: fn() -> clap::Command) -> Result<(), Failure> {
        serve().map_err(Failure::Error)
    }
}

/// Runs the server until the client says exit or goes (its end of stdin
/// closed); an error is the protocol's, or an end without a shutdown
/// (status 1, as the protocol asks).
fn serve() -> Result<(), String> {
    let (connection, io_threads) = transport::stdio();
    let capabilities = ServerCapabilities {
        position_encoding: Some(PositionEncodingKind::UTF16),
        text_document_sync: Some(TextDocumentSyncCapability::Options(
            TextDocumentSyncOptions {
                open_close: Some(true),
                change: Some(TextDocumentSyncKind::INCREMENTAL),
                save: Some(true.into()),
                ..TextDocumentSyncOptions::default()
            },
        )),
        completion_provider: Some(CompletionOptions {
            trigger_characters: Some(vec!["<".into(), " ".into(), "\"".into()]),
            ..CompletionOptions::default()
        }),
        hover_provider: Some(HoverProviderCapability::Simple(true)),
        document_symbol_provider: Some(OneOf::Left(true)),
        workspace_symbol_provider: Some(OneOf::Left(true)),
        code_lens_provider: Some(CodeLensOptions {
            resolve_provider: Some(false),
        }),
        code_action_provider: Some(CodeActionProviderCapability::Simple(true)),
        execute_command_provider: Some(ExecuteCommandOptions {
            commands: vec![preview::COMMAND.to_owned()],
            ..ExecuteCommandOptions::default()
        }),
        document_highlight_provider: Some(OneOf::Left(true)),
        ..ServerCapabilities::default()
    };
    let capabilities = serde_json::to_value(capabilities).map_err(|e| e.to_string())?;
    let client = connection
        .initialize(capabilities)
        .map_err(|e| format!("lsp: {e}"))?;
    // Every thread sends through this one sender, let go when the server
    // ends: the thread that writes to the editor ends when no sender is
    // left (a link to an app may still hold `send` then).
    let sender = Arc::new(Mutex::new(Some(connection.sender.clone())));
    let send: Send = {
        let sender = Arc::clone(&sender);
        Arc::new(move |m| {
            let sender = sender.lock().unwrap_or_else(PoisonError::into_inner);
            sender.as_ref().is_some_and(|s| s.send(m).is_ok())
        })
    };
    let documents: Documents = Arc::default();
    let shows = client["capabilities"]["window"]["showDocument"]["support"].as_bool() == Some(true);
    let (diagnose, changes) = mpsc::channel::<Changed>();
    let from_apps = from_apps(
        Arc::clone(&documents),
        Arc::clone(&send),
        shows,
        diagnose.clone(),
    );
    diagnosis_thread(
        Arc::clone(&documents),
        Arc::clone(&send),
        from_apps,
        changes,
    );
    let mut shut_down = false;
    for message in &connection.receiver {
        match message {
            Message::Request(request) => {
                // A shutdown is answered, then the `exit` waited for.
                if connection
                    .handle_shutdown(&request)
                    .map_err(|e| format!("lsp: {e}"))?
                {
                    shut_down = true;
                    break;
                }
                let response = if request.method == DocumentHighlightRequest::METHOD {
                    // Answered by the thread that tells the apps.
                    match cursor(&documents, request) {
                        Ok(change) => {
                            let _ = diagnose.send(change);
                            continue;
                        }
                        Err(response) => *response,
                    }
                } else {
                    answer(&documents, request, &send)
                };
                connection
                    .sender
                    .send(Message::Response(response))
                    .map_err(|e| format!("lsp: {e}"))?;
            }
            Message::Notification(n) if n.method == Exit::METHOD => break,
            Message::Notification(n) => {
                if let Some(change) = changed(&documents, n) {
                    // The thread has gone only if the server is ending.
                    let _ = diagnose.send(change);
                }
            }
            Message::Response(_) => {}
        }
    }
    drop(diagnose);
    sender.lock().unwrap_or_else(PoisonError::into_inner).take();
    drop(connection);
    io_threads.join().map_err(|e| format!("lsp: {e}"))?;
    if shut_down {
        Ok(())
    } else {
        // The protocol's status for an end without a shutdown.
        Err("lsp: the editor ended the session without a shutdown".to_owned())
    }
}

/// A document opened, changed, saved or closed: the key of the one that
/// changed, and whether the editor let go of its text (saved or closed).
fn changed(documents: &Documents, n: Notification) -> Option<Changed> {
    match n.method.as_str() {
        DidOpenTextDocument::METHOD => {
            let p: DidOpenTextDocumentParams = serde_json::from_value(n.params).ok()?;
            let (uri, text) = (p.text_document.uri, p.text_document.text);
            let key = uri.to_string();
            let lines = Arc::new(Lines::new(&text));
            let document = Document {
                text: Arc::new(text),
                lines,
                marks: language::Marks::default(),
                edits: vec![Edit::Whole],
            };
            lock(documents).insert(key.clone(), document);
            Some(Changed::Text(key, uri))
        }
        DidChangeTextDocument::METHOD => {
            let p: DidChangeTextDocumentParams = serde_json::from_value(n.params).ok()?;
            let key = p.text_document.uri.to_string();
            let mut all = lock(documents);
            let document = all.get_mut(&key)?;
            for change in p.content_changes {
                let Document {
                    text,
                    lines,
                    marks,
                    edits,
                } = &mut *document;
                match change.range {
                    Some(range) => {
                        let start = lines.offset(text, place(range.start));
                        let end = lines.offset(text, place(range.end)).max(start);
                        let text = Arc::make_mut(text);
                        text.replace_range(start..end, &change.text);
                        Arc::make_mut(lines).edit(text, start..end, change.text.len());
                        marks.edited(start..end, change.text.len());
                        edits.push(Edit::Spliced(start..end, change.text.len()));
                    }
                    None => {
                        edits.push(Edit::Whole);
                        *lines = Arc::new(Lines::new(&change.text));
                        *text = Arc::new(change.text);
                        *marks = language::Marks::default();
                    }
                }
            }
            Some(Changed::Text(key, p.text_document.uri))
        }
        DidSaveTextDocument::METHOD => {
            let p: DidSaveTextDocumentParams = serde_json::from_value(n.params).ok()?;
            Some(Changed::Released(p.text_document.uri))
        }
        DidCloseTextDocument::METHOD => {
            let p: DidCloseTextDocumentParams = serde_json::from_value(n.params).ok()?;
            let key = p.text_document.uri.to_string();
            lock(documents).remove(&key);
            Some(Changed::Closed(key, p.text_document.uri))
        }
        _ => None,
    }
}

/// Where a `textDocument/documentHighlight` request puts the cursor, for
/// the thread that answers it; an answer at once for a document the
/// editor has not opened or a request that does not parse.
fn cursor(documents: &Documents, request: Request) -> Result<Changed, Box<Response>> {
    let id = request.id.clone();
    let p: DocumentHighlightParams = serde_json::from_value(request.params).map_err(|e| {
        Box::new(Response::new_err(
            id.clone(),
            lsp_server::ErrorCode::InvalidParams as i32,
            e.to_string(),
        ))
    })?;
    let at = p.text_document_position_params;
    let key = at.text_document.uri.to_string();
    let offset = lock(documents)
        .get(&key)
        .map(|d| d.lines.offset(&d.text, place(at.position)));
    match offset {
        Some(offset) => Ok(Changed::Cursor(key, at.text_document.uri, offset, id)),
        None => Err(Box::new(Response::new_ok(id, serde_json::Value::Null))),
    }
}

fn place(p: Position) -> Place {
    Place {
        line: p.line,
        column: p.character,
    }
}

fn position(p: Place) -> Position {
    Position {
        line: p.line,
        character: p.column,
    }
}

fn range(text: &str, lines: &Lines, bytes: std::ops::Range<usize>) -> Range {
    Range {
        start: position(lines.place(text, bytes.start)),
        end: position(lines.place(text, bytes.end)),
    }
}

/// The thread that checks the documents: told which changed, it copies
/// the newest text of each, publishes its errors and hands it to the
/// user's apps, at most every [`DIAGNOSE_EVERY`]; a document closed gets an
/// empty list, and the apps are told when the editor saves or closes one,
/// and which object the cursor is in. Between changes it looks for apps
/// started since, every [`LOOK_FOR_APPS_EVERY`].
fn diagnosis_thread(
    documents: Documents,
    send: Send,
    from_apps: FromApps,
    rx: mpsc::Receiver<Changed>,
) {
    std::thread::spawn(move || {
        let mut apps = Apps::new(from_apps);
        // The object or light each document's cursor was last in, told to
        // the apps.
        let mut told: HashMap<String, Option<Under>> = HashMap::new();
        // What each document's last check knew, for the next to read only
        // where the edits since fall.
        let mut readings: HashMap<String, rayoflight::scene::Reading> = HashMap::new();
        let mut last = Instant::now() - DIAGNOSE_EVERY;
        loop {
            let mut changed = match rx.recv_timeout(LOOK_FOR_APPS_EVERY) {
                Ok(first) => {
                    std::thread::sleep(DIAGNOSE_EVERY.saturating_sub(last.elapsed()));
                    vec![first]
                }
                Err(mpsc::RecvTimeoutError::Timeout) => Vec::new(),
                Err(mpsc::RecvTimeoutError::Disconnected) => return,
            };
            // Only a batch of changes makes the next one wait.
            let quiet = changed.is_empty();
            for next in rx.try_iter() {
                // The newest cursor of a document wins; the one it
                // replaces is answered with no highlight.
                if let Changed::Cursor(key, ..) = &next
                    && let Some(old) = changed
                        .iter()
                        .position(|c| matches!(c, Changed::Cursor(k, ..) if k == key))
                    && let Changed::Cursor(.., id) = changed.remove(old)
                    && !send(Message::Response(Response::new_ok(
                        id,
                        Vec::<DocumentHighlight>::new(),
                    )))
                {
                    return;
                }
                if !changed.contains(&next) {
                    changed.push(next);
                }
            }
            apps.look();
            // Apps new, or that lost track, are handed every document
            // whole, each as it is read next (the others its edits).
            for change in &changed {
                if let Changed::Resend(socket) = change
                    && apps.connections.contains_key(socket)
                    && !apps.fresh.contains(socket)
                {
                    apps.fresh.push(socket.clone());
                }
            }
            if !apps.fresh.is_empty() {
                let keys: Vec<String> = lock(&documents).keys().cloned().collect();
                for key in keys {
                    if let Ok(uri) = key.parse::<Uri>() {
                        let text = Changed::Text(key, uri);
                        if !changed.contains(&text) {
                            changed.push(text);
                        }
                    }
                }
            }
            for change in changed {
                let (key, uri) = match change {
                    Changed::Resend(_) => continue,
                    Changed::Released(uri) => {
                        apps.released(&uri);
                        continue;
                    }
                    Changed::Closed(key, uri) => {
                        apps.released(&uri);
                        told.remove(&key);
                        readings.remove(&key);
                        (key, uri)
                    }
                    Changed::Text(key, uri) => (key, uri),
                    Changed::Cursor(key, uri, offset, id) => {
                        let answer = under_cursor(&documents, &key, offset);
                        let under = answer.as_ref().map(|(under, _)| *under);
                        // The apps hear of a move into another element or
                        // out of every one (not of the first cursor in
                        // none).
                        if told.get(&key).copied().flatten() != under {
                            apps.selected(&uri, under);
                        }
                        told.insert(key, under);
                        let highlights: Vec<DocumentHighlight> = answer
                            .map(|(_, range)| DocumentHighlight {
                                range,
                                kind: Some(DocumentHighlightKind::TEXT),
                            })
                            .into_iter()
                            .collect();
                        if !send(Message::Response(Response::new_ok(id, highlights))) {
                            return;
                        }
                        continue;
                    }
                };
                // Shared, so that the message loop goes on changing it; the
                // edits it made, told to the document's reading.
                let snapshot = lock(&documents).get_mut(&key).map(|d| {
                    let edits = std::mem::take(&mut d.edits);
                    (Arc::clone(&d.text), Arc::clone(&d.lines), edits)
                });
                let diagnostics = match snapshot {
                    Some((text, lines, edits)) => {
                        let reading = readings.entry(key).or_default();
                        // The edits as one, for the apps.
                        let mut told = Some(None);
                        for edit in edits {
                            match edit {
                                Edit::Spliced(range, inserted) => {
                                    told = told.map(|span| {
                                        Some(Span::then(span, range.clone(), inserted))
                                    });
                                    reading.edited(range, inserted);
                                }
                                Edit::Whole => {
                                    told = None;
                                    reading.forget();
                                }
                            }
                        }
                        apps.text(&uri, &text, told);
                        language::diagnostics_after(reading, &text, &lines)
                            .into_iter()
                            .map(|d| Diagnostic {
                                range: range(&text, &lines, d.range),
                                severity: Some(DiagnosticSeverity::ERROR),
                                source: Some("rayoflight".into()),
                                message: d.message,
                                ..Diagnostic::default()
                            })
                            .collect()
                    }
                    None => Vec::new(),
                };
                let params = PublishDiagnosticsParams {
                    uri,
                    diagnostics,
                    version: None,
                };
                let n = Notification::new(PublishDiagnostics::METHOD.to_owned(), params);
                if !send(Message::Notification(n)) {
                    return;
                }
            }
            apps.fresh.clear();
            if !quiet {
                last = Instant::now();
            }
        }
    });
}

/// The object whose element holds byte `offset` of the document, and its
/// start tag's range: scanned in a copy, the message loop going on.
fn under_cursor(documents: &Documents, key: &str, offset: usize) -> Option<(Under, Range)> {
    let (text, lines) = lock(documents).get(key)?.copy();
    let (under, tag) = language::element_at(&text, offset)?;
    Some((under, range(&text, &lines, tag)))
}

/// What an app says over the link, handled on that connection's thread.
type FromApps = Arc<dyn Fn(&Path, editor_link::Message) + std::marker::Send + Sync>;

/// What the apps say: a click on an object asks the editor to show its
/// element (`window/showDocument`, the element selected, the focus left
/// where it is) if the editor can, else says once that it cannot; an app
/// that lost track of a text is handed the texts whole again (by the
/// thread that tells the apps, `diagnose`).
fn from_apps(
    documents: Documents,
    send: Send,
    shows: bool,
    diagnose: mpsc::Sender<Changed>,
) -> FromApps {
    let said_cannot = AtomicBool::new(false);
    let requests = AtomicU64::new(0);
    let diagnose = Mutex::new(diagnose);
    Arc::new(move |socket, message| {
        let (path, object) = match message {
            editor_link::Message::Show { path, object } => (path, object),
            editor_link::Message::Resend { .. } => {
                let diagnose = diagnose.lock().unwrap_or_else(PoisonError::into_inner);
                let _ = diagnose.send(Changed::Resend(socket.to_owned()));
                return;
            }
            _ => return,
        };
        let Some((uri, selection)) = object_element(&documents, &path, object) else {
            return;
        };
        if !shows {
            if !said_cannot.swap(true, Ordering::Relaxed) {
                let message =
                    "RayOfLight: this editor does not show a document when a server asks \
                               (window/showDocument), so a click in the app cannot show you the \
                               object's element"
                        .to_owned();
                let params = ShowMessageParams {
                    typ: MessageType::INFO,
                    message,
                };
                send(Message::Notification(Notification::new(
                    ShowMessage::METHOD.to_owned(),
                    params,
                )));
            }
            let line = selection.start.line + 1;
            let params = LogMessageParams {
                typ: MessageType::LOG,
                message: format!("object {} is at line {line} of {uri:?}", object + 1),
            };
            send(Message::Notification(Notification::new(
                LogMessage::METHOD.to_owned(),
                params,
            )));
            return;
        }
        let n = requests.fetch_add(1, Ordering::Relaxed);
        let params = ShowDocumentParams {
            uri,
            external: Some(false),
            take_focus: Some(false),
            selection: Some(selection),
        };
        let id = RequestId::from(format!("rayoflight-show-{n}"));
        send(Message::Request(Request::new(
            id,
            ShowDocument::METHOD.to_owned(),
            params,
        )));
    })
}

/// The URI of the open document that is the file at `path`, and the range
/// of its object `object`'s element.
fn object_element(documents: &Documents, path: &Path, object: usize) -> Option<(Uri, Range)> {
    let (key, text, lines) = {
        let all = lock(documents);
        let (key, document) = all.iter().find(|(key, _)| {
            editor_link::uri_path(key)
                .is_some_and(|p| rayoflight::system::files::same_file(&p, path))
        })?;
        let (text, lines) = document.copy();
        (key.clone(), text, lines)
    };
    let element = language::object_element(&text, object)?;
    let uri = key.parse::<Uri>().ok()?;
    Some((uri, range(&text, &lines, element)))
}

/// The user's running apps ([`rayoflight::desktop::editor_link`]), connected to as
/// they come and dropped as they go; what each says is read on a thread of
/// its own.
struct Apps {
    connections: HashMap<PathBuf, editor_link::Stream>,
    /// Those connected since the last batch of changes, or that asked
    /// for the texts again: they are handed each text whole.
    fresh: Vec<PathBuf>,
    from_apps: FromApps,
}

/// Ends the connection both ways, for the app and for the thread that
/// reads what it says (which holds a copy of the socket).
fn hang_up(stream: &editor_link::Stream) {
    let _ = stream.shutdown(std::net::Shutdown::Both);
}

/// The server is ending: each app's reading thread sees its connection
/// end (and lets go of the editor's channel, which lsp-server waits on).
impl Drop for Apps {
    fn drop(&mut self) {
        for stream in self.connections.values() {
            hang_up(stream);
        }
    }
}

impl Apps {
    fn new(from_apps: FromApps) -> Apps {
        Apps {
            connections: HashMap::new(),
            fresh: Vec::new(),
            from_apps,
        }
    }

    /// Connects to the apps started since it last looked (each is
    /// [`Apps::fresh`]: handed every text whole next); drops those gone.
    fn look(&mut self) {
        let Ok(folder) = editor_link::folder() else {
            return;
        };
        let sockets = editor_link::apps(&folder);
        self.connections.retain(|socket, stream| {
            let here = sockets.contains(socket);
            if !here {
                hang_up(stream);
            }
            here
        });
        for socket in sockets {
            if self.connections.contains_key(&socket) {
                continue;
            }
            let Ok(stream) = editor_link::connect(&socket) else {
                continue;
            };
            let Ok(reader) = stream.try_clone() else {
                continue;
            };
            let from_apps = Arc::clone(&self.from_apps);
            let at = socket.clone();
            std::thread::spawn(move || {
                let mut r = std::io::BufReader::new(reader);
                while let Ok(Some(message)) = editor_link::receive(&mut r) {
                    from_apps(&at, message);
                }
            });
            self.fresh.push(socket.clone());
            self.connections.insert(socket, stream);
        }
    }

    /// Sends `message` to every app connected.
    fn tell(&mut self, message: &editor_link::Message) {
        self.connections.retain(|_, stream| {
            let sent = editor_link::send(stream, message).is_ok();
            if !sent {
                hang_up(stream);
            }
            sent
        });
    }

    /// Hands every app the newest `text` of `uri`: whole to those
    /// [`Apps::fresh`] and where the edits since the last are not known
    /// (`edits` none), else as the one change they make (nothing where
    /// there was none).
    fn text(&mut self, uri: &Uri, text: &str, edits: Option<Option<Span>>) {
        if self.connections.is_empty() {
            return;
        }
        let Some(path) = editor_link::uri_path(uri.as_str()) else {
            return;
        };
        let whole = || editor_link::Message::Buffer {
            path: path.clone(),
            text: text.to_owned(),
        };
        let change = match edits {
            Some(Some(span)) => Some(editor_link::Message::Change {
                path: path.clone(),
                range: span.start..span.end,
                text: text[span.now()].to_owned(),
                length: text.len(),
            }),
            Some(None) => None,
            None => Some(whole()),
        };
        let fresh = &self.fresh;
        let mut buffer = None;
        self.connections.retain(|socket, stream| {
            let message = match fresh.contains(socket) {
                true => buffer.get_or_insert_with(whole),
                false => match &change {
                    Some(change) => change,
                    None => return true,
                },
            };
            let sent = editor_link::send(stream, message).is_ok();
            if !sent {
                hang_up(stream);
            }
            sent
        });
    }

    fn released(&mut self, uri: &Uri) {
        if let Some(path) = editor_link::uri_path(uri.as_str()) {
            self.tell(&editor_link::Message::Released { path });
        }
    }

    fn selected(&mut self, uri: &Uri, under: Option<Under>) {
        if let Some(path) = editor_link::uri_path(uri.as_str()) {
            self.tell(&editor_link::Message::Select { path, under });
        }
    }
}

/// The answer to a request, or an error response for what it does not
/// know.
fn answer(documents: &Documents, request: Request, send: &Send) -> Response {
    let id = request.id.clone();
    let result = match request.method.as_str() {
        Completion::METHOD => serde_json::from_value::<CompletionParams>(request.params).map(|p| {
            let at = p.text_document_position;
            json!(with_document(documents, &at.text_document.uri, |d| {
                let offset = d.lines.offset(&d.text, place(at.position));
                CompletionResponse::Array(completion_items(&d.text, offset, &mut d.marks))
            }))
        }),
        HoverRequest::METHOD => serde_json::from_value::<HoverParams>(request.params).map(|p| {
            let at = p.text_document_position_params;
            json!(with_document(documents, &at.text_document.uri, |d| {
                let offset = d.lines.offset(&d.text, place(at.position));
                language::hover(&d.text, offset, &mut d.marks).map(|(doc, bytes)| Hover {
                    contents: HoverContents::Markup(MarkupContent {
                        kind: MarkupKind::PlainText,
                        value: doc,
                    }),
                    range: Some(range(&d.text, &d.lines, bytes)),
                })
            }))
        }),
        DocumentSymbolRequest::METHOD => {
            serde_json::from_value::<DocumentSymbolParams>(request.params).map(|p| {
                json!(with_document(documents, &p.text_document.uri, |d| {
                    DocumentSymbolResponse::Nested(document_symbols(
                        language::symbols(&d.text),
                        &d.text,
                        &d.lines,
                    ))
                }))
            })
        }
        CodeLensRequest::METHOD => {
            serde_json::from_value::<CodeLensParams>(request.params).map(|p| {
                let uri = p.text_document.uri;
                json!(with_document(documents, &uri, |d| preview::lenses(
                    &d.text, &d.lines, &uri
                )))
            })
        }
        CodeActionRequest::METHOD => serde_json::from_value::<CodeActionParams>(request.params)
            .map(|p| {
                let uri = p.text_document.uri;
                json!(with_document(documents, &uri, |_| preview::actions(&uri)))
            }),
        ExecuteCommand::METHOD => {
            let p = match serde_json::from_value::<ExecuteCommandParams>(request.params) {
                Ok(p) => p,
                Err(e) => return invalid(id, e.to_string()),
            };
            if p.command != preview::COMMAND {
                return invalid(id, format!("rayoflight lsp has no command {}", p.command));
            }
            return match preview::start(&p.arguments, Arc::clone(send)) {
                Ok(()) => Response::new_ok(id, serde_json::Value::Null),
                Err(message) => invalid(id, message),
            };
        }
        WorkspaceSymbolRequest::METHOD => {
            serde_json::from_value::<WorkspaceSymbolParams>(request.params)
                .map(|p| json!(Some(workspace_symbols(documents, &p.query))))
        }
        _ => return unknown(id, &request.method),
    };
    match result {
        Ok(value) => Response::new_ok(id, value),
        Err(e) => invalid(id, e.to_string()),
    }
}

/// An error answer: what the request asked cannot be done.
fn invalid(id: RequestId, message: String) -> Response {
    Response::new_err(id, lsp_server::ErrorCode::InvalidParams as i32, message)
}

fn unknown(id: RequestId, method: &str) -> Response {
    Response::new_err(
        id,
        lsp_server::ErrorCode::MethodNotFound as i32,
        format!("rayoflight lsp does not answer {method}"),
    )
}

/// `f` of the document's text, if the client opened it.
/// `f` of the open document at `uri`, under the lock.
fn with_document<T>(
    documents: &Documents,
    uri: &Uri,
    f: impl FnOnce(&mut Document) -> T,
) -> Option<T> {
    let mut all = lock(documents);
    let document = all.get_mut(&uri.to_string())?;
    Some(f(document))
}

fn completion_items(text: &str, offset: usize, marks: &mut language::Marks) -> Vec<CompletionItem> {
    language::completions(text, offset, marks)
        .into_iter()
        .map(|c| CompletionItem {
            kind: Some(match c.kind {
                language::CompletionKind::Element => CompletionItemKind::CLASS,
                language::CompletionKind::Attribute => CompletionItemKind::PROPERTY,
                language::CompletionKind::Value => CompletionItemKind::ENUM_MEMBER,
            }),
            documentation: Some(Documentation::String(c.doc)),
            insert_text: Some(c.insert),
            label: c.label,
            ..CompletionItem::default()
        })
        .collect()
}

#[allow(deprecated)] // DocumentSymbol's `deprecated` field must be given.
fn document_symbols(
    symbols: Vec<language::Symbol>,
    text: &str,
    lines: &Lines,
) -> Vec<DocumentSymbol> {
    symbols
        .into_iter()
        .map(|s| DocumentSymbol {
            name: s.name,
            detail: None,
            kind: symbol_kind(s.kind),
            tags: None,
            deprecated: None,
            range: range(text, lines, s.range),
            selection_range: range(text, lines, s.selection),
            children: (!s.children.is_empty()).then(|| document_symbols(s.children, text, lines)),
        })
        .collect()
}

fn symbol_kind(kind: language::SymbolKind) -> SymbolKind {
    match kind {
        language::SymbolKind::Object => SymbolKind::OBJECT,
        language::SymbolKind::Light => SymbolKind::EVENT,
        language::SymbolKind::Camera => SymbolKind::FIELD,
        language::SymbolKind::Model => SymbolKind::PROPERTY,
    }
}

/// The most symbols a `workspace/symbol` answer holds.
const WORKSPACE_SYMBOLS: usize = 200;

/// The symbols of the open documents whose names hold `query`: how an
/// object of an outline too long to list ([`language::SYMBOLS_LISTED`])
/// is found, at most [`WORKSPACE_SYMBOLS`] in all.
#[allow(deprecated)] // SymbolInformation's `deprecated` field must be given.
fn workspace_symbols(documents: &Documents, query: &str) -> WorkspaceSymbolResponse {
    let all = lock(documents);
    let mut found = Vec::new();
    for (key, d) in all.iter() {
        let Ok(uri) = key.parse::<Uri>() else {
            continue;
        };
        let left = WORKSPACE_SYMBOLS - found.len();
        let (symbols, _) = language::find_symbols(&d.text, query, left);
        found.extend(symbols.into_iter().map(|s| SymbolInformation {
            name: s.name,
            kind: symbol_kind(s.kind),
            tags: None,
            deprecated: None,
            location: Location {
                uri: uri.clone(),
                range: range(&d.text, &d.lines, s.selection),
            },
            container_name: None,
        }));
        if found.len() >= WORKSPACE_SYMBOLS {
            break;
        }
    }
    WorkspaceSymbolResponse::Flat(found)
}
