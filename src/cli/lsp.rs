//! `rayoflight lsp`: a language server for scene files on stdin and stdout
//! (lsp-server's loop, lsp-types' messages), for completion, hover
//! documentation, errors as you type and an outline in any editor with an
//! LSP client.
//!
//! What it answers comes from `rayoflight::scene::language`; this module
//! only speaks the protocol. Positions are UTF-16 code units (the
//! protocol's default, which the server announces). Documents are synced
//! incrementally. Errors are found off the message loop, on a thread of
//! their own that takes the newest text of each document and checks it at
//! most every 100 ms: a big buffer makes its errors come later, never the
//! typing slower.

use lsp_server::{Connection, Message, Notification, Request, RequestId, Response};
use lsp_types::notification::{
    DidChangeTextDocument, DidCloseTextDocument, DidOpenTextDocument, Notification as _,
    PublishDiagnostics,
};
use lsp_types::request::{Completion, DocumentSymbolRequest, HoverRequest, Request as _};
use lsp_types::{
    CompletionItem, CompletionItemKind, CompletionOptions, CompletionParams, CompletionResponse,
    Diagnostic, DiagnosticSeverity, DidChangeTextDocumentParams, DidCloseTextDocumentParams,
    DidOpenTextDocumentParams, DocumentSymbol, DocumentSymbolParams, DocumentSymbolResponse,
    Documentation, Hover, HoverContents, HoverParams, HoverProviderCapability, MarkupContent,
    MarkupKind, OneOf, Position, PositionEncodingKind, PublishDiagnosticsParams, Range,
    ServerCapabilities, SymbolKind, TextDocumentSyncCapability, TextDocumentSyncKind, Uri,
};
use rayoflight::scene::language::{self, Lines, Place};
use std::collections::HashMap;
use std::sync::Arc;
use std::sync::mpsc;
use std::time::{Duration, Instant};

/// `value` as JSON (`null` for none).
macro_rules! json {
    ($value:expr) => {
        $value
            .and_then(|v| serde_json::to_value(v).ok())
            .unwrap_or(serde_json::Value::Null)
    };
}

/// The least time between two checks of the documents' errors.
const DIAGNOSE_EVERY: Duration = Duration::from_millis(100);

/// Runs the server until the client says exit; an error is the protocol's.
pub fn run() -> Result<(), String> {
    let (connection, io_threads) = Connection::stdio();
    let capabilities = ServerCapabilities {
        position_encoding: Some(PositionEncodingKind::UTF16),
        text_document_sync: Some(TextDocumentSyncCapability::Kind(
            TextDocumentSyncKind::INCREMENTAL,
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
    let diagnose = diagnosis_thread(move |m| sender.send(m).is_ok());
    let mut documents: HashMap<String, Arc<String>> = HashMap::new();
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
                if let Some((uri, text)) = changed(&mut documents, n) {
                    // The thread has gone only if the server is ending.
                    let _ = diagnose.send((uri, text));
                }
            }
            Message::Response(_) => {}
        }
    }
    drop(diagnose);
    io_threads.join().map_err(|e| format!("lsp: {e}"))
}

/// A document opened, changed or closed: its new text (`None`: closed).
fn changed(
    documents: &mut HashMap<String, Arc<String>>,
    n: Notification,
) -> Option<(Uri, Option<Arc<String>>)> {
    match n.method.as_str() {
        DidOpenTextDocument::METHOD => {
            let p: DidOpenTextDocumentParams = serde_json::from_value(n.params).ok()?;
            let text = Arc::new(p.text_document.text);
            documents.insert(p.text_document.uri.to_string(), Arc::clone(&text));
            Some((p.text_document.uri, Some(text)))
        }
        DidChangeTextDocument::METHOD => {
            let p: DidChangeTextDocumentParams = serde_json::from_value(n.params).ok()?;
            let key = p.text_document.uri.to_string();
            let mut text = documents
                .get(&key)
                .map_or_else(String::new, |t| (**t).clone());
            for change in p.content_changes {
                match change.range {
                    Some(range) => {
                        let lines = Lines::new(&text);
                        let start = lines.offset(&text, place(range.start));
                        let end = lines.offset(&text, place(range.end)).max(start);
                        text.replace_range(start..end, &change.text);
                    }
                    None => text = change.text,
                }
            }
            let text = Arc::new(text);
            documents.insert(key, Arc::clone(&text));
            Some((p.text_document.uri, Some(text)))
        }
        DidCloseTextDocument::METHOD => {
            let p: DidCloseTextDocumentParams = serde_json::from_value(n.params).ok()?;
            documents.remove(&p.text_document.uri.to_string());
            Some((p.text_document.uri, None))
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

/// The thread that checks the documents: it keeps the newest text of each
/// and publishes its errors, at most every [`DIAGNOSE_EVERY`].
fn diagnosis_thread(
    send: impl Fn(Message) -> bool + Send + 'static,
) -> mpsc::Sender<(Uri, Option<Arc<String>>)> {
    let (tx, rx) = mpsc::channel::<(Uri, Option<Arc<String>>)>();
    std::thread::spawn(move || {
        let mut last = Instant::now() - DIAGNOSE_EVERY;
        while let Ok(first) = rx.recv() {
            // Not more often than every DIAGNOSE_EVERY; what came meanwhile
            // replaces what was waiting.
            std::thread::sleep(DIAGNOSE_EVERY.saturating_sub(last.elapsed()));
            let mut newest: Vec<(Uri, Option<Arc<String>>)> = vec![first];
            for (uri, text) in rx.try_iter() {
                match newest.iter_mut().find(|(u, _)| *u == uri) {
                    Some(slot) => slot.1 = text,
                    None => newest.push((uri, text)),
                }
            }
            for (uri, text) in newest {
                let diagnostics = match &text {
                    Some(text) => {
                        let lines = Lines::new(text);
                        language::diagnostics(text)
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
            last = Instant::now();
        }
    });
    tx
}

/// The answer to a request, or an error response for what it does not
/// know.
fn answer(documents: &HashMap<String, Arc<String>>, request: Request) -> Response {
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
fn with_text<T>(
    documents: &HashMap<String, Arc<String>>,
    uri: &Uri,
    f: impl FnOnce(&str, &Lines) -> T,
) -> Option<T> {
    let text = documents.get(&uri.to_string())?;
    Some(f(text, &Lines::new(text)))
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
