//! `rayoflight lsp`: a language server for scene files on stdin and stdout
//! (lsp-server's loop, lsp-types' messages), for completion, hover
//! documentation, errors as you type and an outline in any editor with an
//! LSP client.
//!
//! What it answers comes from `rayoflight::scene::language`; this module
//! only speaks the protocol. Positions are UTF-16 code units (the
//! protocol's default, which the server announces). Documents are synced
//! incrementally: a change is spliced into the document's text and its
//! line index is moved, not rebuilt. Errors are found off the message
//! loop, on a thread of their own that copies the newest text of each
//! changed document and checks it at most every 100 ms: a big buffer makes
//! its errors come later, never the typing slower. The same thread hands
//! each newest text to the user's running apps
//! ([`rayoflight::editor_link`]), and tells them when the editor saves or
//! closes the document.

use lsp_server::{Connection, Message, Notification, Request, RequestId, Response};
use lsp_types::notification::{
    DidChangeTextDocument, DidCloseTextDocument, DidOpenTextDocument, DidSaveTextDocument,
    Notification as _, PublishDiagnostics,
};
use lsp_types::request::{Completion, DocumentSymbolRequest, HoverRequest, Request as _};
use lsp_types::{
    CompletionItem, CompletionItemKind, CompletionOptions, CompletionParams, CompletionResponse,
    Diagnostic, DiagnosticSeverity, DidChangeTextDocumentParams, DidCloseTextDocumentParams,
    DidOpenTextDocumentParams, DidSaveTextDocumentParams, DocumentSymbol, DocumentSymbolParams,
    DocumentSymbolResponse, Documentation, Hover, HoverContents, HoverParams,
    HoverProviderCapability, MarkupContent, MarkupKind, OneOf, Position, PositionEncodingKind,
    PublishDiagnosticsParams, Range, ServerCapabilities, SymbolKind, TextDocumentSyncCapability,
    TextDocumentSyncKind, TextDocumentSyncOptions, Uri,
};
use rayoflight::editor_link;
use rayoflight::scene::language::{self, Lines, Place};
use std::collections::HashMap;
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

/// An open document: the editor's text and where its lines start.
struct Document {
    text: String,
    lines: Lines,
}

/// The open documents, by URI, shared with the thread that checks them.
type Documents = Arc<Mutex<HashMap<String, Document>>>;

fn lock(documents: &Documents) -> std::sync::MutexGuard<'_, HashMap<String, Document>> {
    documents.lock().unwrap_or_else(PoisonError::into_inner)
}

/// What a notification changed.
#[derive(Debug, Clone, PartialEq)]
enum Changed {
    /// The text of a document (by key and URI).
    Text(String, Uri),
    /// The editor saved it: its text is the file's.
    Released(Uri),
    /// The editor closed it.
    Closed(String, Uri),
}

/// The least time between two checks of the documents' errors.
const DIAGNOSE_EVERY: Duration = Duration::from_millis(100);

/// Runs the server until the client says exit; an error is the protocol's.
pub fn run() -> Result<(), String> {
    let (connection, io_threads) = Connection::stdio();
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
        ..ServerCapabilities::default()
    };
    let capabilities = serde_json::to_value(capabilities).map_err(|e| e.to_string())?;
    connection
        .initialize(capabilities)
        .map_err(|e| format!("lsp: {e}"))?;
    let sender = connection.sender.clone();
    let documents: Documents = Arc::default();
    let diagnose = diagnosis_thread(Arc::clone(&documents), move |m| sender.send(m).is_ok());
    for message in &connection.receiver {
        match message {
            Message::Request(request) => {
                if connection
                    .handle_shutdown(&request)
                    .map_err(|e| format!("lsp: {e}"))?
                {
                    break;
                }
                let response = answer(&documents, request);
                connection
                    .sender
                    .send(Message::Response(response))
                    .map_err(|e| format!("lsp: {e}"))?;
            }
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
    io_threads.join().map_err(|e| format!("lsp: {e}"))
}

/// A document opened, changed, saved or closed: the key of the one that
/// changed, and whether the editor let go of its text (saved or closed).
fn changed(documents: &Documents, n: Notification) -> Option<Changed> {
    match n.method.as_str() {
        DidOpenTextDocument::METHOD => {
            let p: DidOpenTextDocumentParams = serde_json::from_value(n.params).ok()?;
            let (uri, text) = (p.text_document.uri, p.text_document.text);
            let key = uri.to_string();
            let lines = Lines::new(&text);
            let document = Document { text, lines };
            lock(documents).insert(key.clone(), document);
            Some(Changed::Text(key, uri))
        }
        DidChangeTextDocument::METHOD => {
            let p: DidChangeTextDocumentParams = serde_json::from_value(n.params).ok()?;
            let key = p.text_document.uri.to_string();
            let mut all = lock(documents);
            let document = all.get_mut(&key)?;
            for change in p.content_changes {
                let Document { text, lines, .. } = &mut *document;
                match change.range {
                    Some(range) => {
                        let start = lines.offset(text, place(range.start));
                        let end = lines.offset(text, place(range.end)).max(start);
                        text.replace_range(start..end, &change.text);
                        lines.edit(text, start..end, change.text.len());
                    }
                    None => {
                        *lines = Lines::new(&change.text);
                        *text = change.text;
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
/// empty list, and the apps are told when the editor saves or closes one.
fn diagnosis_thread(
    documents: Documents,
    send: impl Fn(Message) -> bool + Send + 'static,
) -> mpsc::Sender<Changed> {
    let (tx, rx) = mpsc::channel::<Changed>();
    std::thread::spawn(move || {
        let mut apps = Apps::default();
        let mut last = Instant::now() - DIAGNOSE_EVERY;
        while let Ok(first) = rx.recv() {
            std::thread::sleep(DIAGNOSE_EVERY.saturating_sub(last.elapsed()));
            let mut changed = vec![first];
            for next in rx.try_iter() {
                if !changed.contains(&next) {
                    changed.push(next);
                }
            }
            for change in changed {
                let (key, uri) = match change {
                    Changed::Released(uri) => {
                        apps.released(&uri);
                        continue;
                    }
                    Changed::Closed(key, uri) => {
                        apps.released(&uri);
                        (key, uri)
                    }
                    Changed::Text(key, uri) => (key, uri),
                };
                // A copy, so that the message loop goes on changing it.
                let text = lock(&documents).get(&key).map(|d| d.text.clone());
                let diagnostics = match &text {
                    Some(text) => {
                        let found = language::diagnostics(text);
                        if found.is_empty() {
                            // No error to place: no line index (a scan of
                            // the whole buffer) to build.
                            Vec::new()
                        } else {
                            let lines = Lines::new(text);
                            found
                                .into_iter()
                                .map(|d| Diagnostic {
                                    range: range(text, &lines, d.range),
                                    severity: Some(DiagnosticSeverity::ERROR),
                                    source: Some("rayoflight".into()),
                                    message: d.message,
                                    ..Diagnostic::default()
                                })
                                .collect()
                        }
                    }
                    None => Vec::new(),
                };
                if let Some(text) = text {
                    apps.buffer(&uri, text);
                }
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
            last = Instant::now();
        }
    });
    tx
}

/// The user's running apps ([`rayoflight::editor_link`]), connected to as
/// they come and dropped as they go.
#[derive(Default)]
struct Apps {
    connections: HashMap<std::path::PathBuf, std::os::unix::net::UnixStream>,
}

impl Apps {
    /// Sends `message` to every app in the runtime folder.
    fn tell(&mut self, message: &editor_link::Message) {
        let Ok(folder) = editor_link::folder() else {
            return;
        };
        let sockets = editor_link::apps(&folder);
        self.connections
            .retain(|socket, _| sockets.contains(socket));
        for socket in sockets {
            if !self.connections.contains_key(&socket)
                && let Ok(stream) = editor_link::connect(&socket)
            {
                self.connections.insert(socket.clone(), stream);
            }
            let Some(stream) = self.connections.get_mut(&socket) else {
                continue;
            };
            if editor_link::send(stream, message).is_err() {
                self.connections.remove(&socket);
            }
        }
    }

    fn buffer(&mut self, uri: &Uri, text: String) {
        if let Some(path) = editor_link::uri_path(uri.as_str()) {
            self.tell(&editor_link::Message::Buffer { path, text });
        }
    }

    fn released(&mut self, uri: &Uri) {
        if let Some(path) = editor_link::uri_path(uri.as_str()) {
            self.tell(&editor_link::Message::Released { path });
        }
    }
}

/// The answer to a request, or an error response for what it does not
/// know.
fn answer(documents: &Documents, request: Request) -> Response {
    let id = request.id.clone();
    let result = match request.method.as_str() {
        Completion::METHOD => serde_json::from_value::<CompletionParams>(request.params).map(|p| {
            let at = p.text_document_position;
            json!(with_text(
                documents,
                &at.text_document.uri,
                |text, lines| {
                    let offset = lines.offset(text, place(at.position));
                    CompletionResponse::Array(completion_items(text, offset))
                }
            ))
        }),
        HoverRequest::METHOD => serde_json::from_value::<HoverParams>(request.params).map(|p| {
            let at = p.text_document_position_params;
            json!(with_text(
                documents,
                &at.text_document.uri,
                |text, lines| {
                    let offset = lines.offset(text, place(at.position));
                    language::hover(text, offset).map(|(doc, bytes)| Hover {
                        contents: HoverContents::Markup(MarkupContent {
                            kind: MarkupKind::PlainText,
                            value: doc,
                        }),
                        range: Some(range(text, lines, bytes)),
                    })
                }
            ))
        }),
        DocumentSymbolRequest::METHOD => {
            serde_json::from_value::<DocumentSymbolParams>(request.params).map(|p| {
                json!(with_text(documents, &p.text_document.uri, |text, lines| {
                    DocumentSymbolResponse::Nested(document_symbols(text, lines))
                }))
            })
        }
        _ => return unknown(id, &request.method),
    };
    match result {
        Ok(value) => Response::new_ok(id, value),
        Err(e) => Response::new_err(
            id,
            lsp_server::ErrorCode::InvalidParams as i32,
            e.to_string(),
        ),
    }
}

fn unknown(id: RequestId, method: &str) -> Response {
    Response::new_err(
        id,
        lsp_server::ErrorCode::MethodNotFound as i32,
        format!("rayoflight lsp does not answer {method}"),
    )
}

/// `f` of the document's text, if the client opened it.
fn with_text<T>(documents: &Documents, uri: &Uri, f: impl FnOnce(&str, &Lines) -> T) -> Option<T> {
    let all = lock(documents);
    let document = all.get(&uri.to_string())?;
    Some(f(&document.text, &document.lines))
}

fn completion_items(text: &str, offset: usize) -> Vec<CompletionItem> {
    language::completions(text, offset)
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
fn document_symbols(text: &str, lines: &Lines) -> Vec<DocumentSymbol> {
    language::symbols(text)
        .into_iter()
        .map(|s| DocumentSymbol {
            name: s.name,
            detail: None,
            kind: match s.kind {
                language::SymbolKind::Object => SymbolKind::OBJECT,
                language::SymbolKind::Light => SymbolKind::EVENT,
                language::SymbolKind::Camera => SymbolKind::FIELD,
                language::SymbolKind::Model => SymbolKind::PROPERTY,
            },
            tags: None,
            deprecated: None,
            range: range(text, lines, s.range),
            selection_range: range(text, lines, s.selection),
            children: None,
        })
        .collect()
}
