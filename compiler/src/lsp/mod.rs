//! `tsfc lsp`: the language server (stdio, LSP 3.17, full document sync).
//!
//! Diagnostics are exactly `tsfc check`'s ([`document`]); hover
//! ([`hover`]), go to definition and references ([`symbols`]), completion
//! ([`complete`]), the outline ([`outline`]) and formatting answer from the
//! document's last analysis. Every request does work bounded by the
//! document's size (at most the spec limit of docs/limits.md; past it the
//! document gets one diagnostic and nothing else); a request that is not
//! understood gets an error response, and a handler that fails answers with
//! an internal error instead of stopping the server. [`transport`] reads and
//! writes the frames.

pub mod complete;
pub mod document;
pub mod hover;
pub mod outline;
pub mod position;
pub mod symbols;
pub mod transport;

use crate::util::output::MAX_SPEC_BYTES;
use document::Document;
use lsp_server::{Connection, ErrorCode, Message, Notification, Request, RequestId, Response};
use lsp_types::notification::{
    DidChangeTextDocument, DidCloseTextDocument, DidOpenTextDocument, Notification as _,
    PublishDiagnostics,
};
use lsp_types::request::{
    Completion, DocumentSymbolRequest, Formatting, GotoDefinition, HoverRequest, References,
    Request as _,
};
use lsp_types::{
    CompletionOptions, CompletionResponse, DocumentSymbolResponse, GotoDefinitionResponse, Hover,
    HoverContents, HoverProviderCapability, InitializeResult, Location, MarkupContent, MarkupKind,
    OneOf, PublishDiagnosticsParams, ServerCapabilities, ServerInfo, TextDocumentSyncCapability,
    TextDocumentSyncKind, TextEdit, Uri,
};
use serde_json::Value;
use std::collections::HashMap;
use std::panic::{catch_unwind, AssertUnwindSafe};
use tsf_lang::Span;

/// Runs the server on stdin/stdout until `exit`; the process's exit code (0
/// after `shutdown`, 1 otherwise, as LSP asks).
pub fn run_stdio() -> u8 {
    let io = match transport::Stdio::start() {
        Ok(io) => io,
        Err(e) => {
            eprintln!("error: cannot start the language server: {e}");
            return 2;
        }
    };
    let connection = Connection {
        sender: io.sender.clone(),
        receiver: io.receiver.clone(),
    };
    let code = serve(&connection);
    drop(connection);
    io.finish();
    code
}

/// Serves `connection` until `exit` or the end of input; the exit code.
pub fn serve(connection: &Connection) -> u8 {
    let mut server = Server::default();
    for msg in &connection.receiver {
        match msg {
            Message::Request(req) => {
                let resp = server.request(req);
                if connection.sender.send(Message::Response(resp)).is_err() {
                    return 1;
                }
            }
            Message::Notification(n) if n.method == "exit" => {
                return if server.shut_down { 0 } else { 1 };
            }
            Message::Notification(n) => {
                for out in server.notification(n) {
                    if connection.sender.send(Message::Notification(out)).is_err() {
                        return 1;
                    }
                }
            }
            Message::Response(_) => {}
        }
    }
    1
}

/// The server's state: the open documents.
#[derive(Default)]
struct Server {
    initialized: bool,
    shut_down: bool,
    docs: HashMap<String, Document>,
}

/// The outcome of a request handler: a result, or an error code and message.
type Answer = Result<Value, (ErrorCode, String)>;

impl Server {
    fn request(&mut self, req: Request) -> Response {
        let id = req.id.clone();
        let answer = if req.method == "initialize" {
            if self.initialized {
                Err((
                    ErrorCode::InvalidRequest,
                    "initialize was already received".into(),
                ))
            } else {
                self.initialized = true;
                Ok(serde_json::to_value(capabilities()).unwrap_or_default())
            }
        } else if !self.initialized {
            Err((
                ErrorCode::ServerNotInitialized,
                "the server is not initialized".into(),
            ))
        } else if self.shut_down {
            Err((ErrorCode::InvalidRequest, "the server is shut down".into()))
        } else if req.method == "shutdown" {
            self.shut_down = true;
            Ok(Value::Null)
        } else {
            catch_unwind(AssertUnwindSafe(|| self.dispatch(&req.method, req.params)))
                .unwrap_or_else(|_| {
                    Err((ErrorCode::InternalError, format!("{} failed", req.method)))
                })
        };
        respond(id, answer)
    }

    fn dispatch(&self, method: &str, params: Value) -> Answer {
        match method {
            HoverRequest::METHOD => self.with_position(params, |doc, offset| {
                let hover = hover::hover(doc, offset).map(|text| Hover {
                    contents: HoverContents::Markup(MarkupContent {
                        kind: MarkupKind::Markdown,
                        value: text,
                    }),
                    range: doc
                        .index
                        .token_at(offset)
                        .map(|t| doc.lines.range(&doc.text, t.span)),
                });
                serde_json::to_value(hover)
            }),
            GotoDefinition::METHOD => {
                let uri = position_uri(&params)?;
                self.with_position(params, |doc, offset| {
                    let found = doc.index.decl_at(offset).map(|(_, d)| {
                        GotoDefinitionResponse::Scalar(Location::new(
                            uri.clone(),
                            doc.lines.range(&doc.text, d.span),
                        ))
                    });
                    serde_json::to_value(found)
                })
            }
            References::METHOD => {
                let uri = position_uri(&params)?;
                let include = params
                    .pointer("/context/includeDeclaration")
                    .and_then(Value::as_bool)
                    .unwrap_or(true);
                self.with_position(params, |doc, offset| {
                    let found: Option<Vec<Location>> = doc.index.decl_at(offset).map(|(k, d)| {
                        doc.index
                            .references(k)
                            .filter(|s| include || *s != d.span)
                            .map(|s| Location::new(uri.clone(), doc.lines.range(&doc.text, s)))
                            .collect()
                    });
                    serde_json::to_value(found)
                })
            }
            Completion::METHOD => self.with_position(params, |doc, offset| {
                serde_json::to_value(CompletionResponse::Array(complete::complete(doc, offset)))
            }),
            DocumentSymbolRequest::METHOD => {
                let doc = self.doc(&params)?;
                serde_json::to_value(DocumentSymbolResponse::Nested(outline::outline(doc)))
                    .map_err(internal)
            }
            Formatting::METHOD => {
                let doc = self.doc(&params)?;
                formatting(doc)
            }
            _ => Err((
                ErrorCode::MethodNotFound,
                format!("method `{method}` is not supported"),
            )),
        }
    }

    /// The open document `params.textDocument.uri`.
    fn doc(&self, params: &Value) -> Result<&Document, (ErrorCode, String)> {
        let uri = params
            .pointer("/textDocument/uri")
            .and_then(Value::as_str)
            .ok_or_else(|| invalid("params.textDocument.uri is missing"))?;
        self.docs
            .get(uri)
            .ok_or_else(|| invalid(&format!("document `{uri}` is not open")))
    }

    /// Runs `f` on the document and byte offset of a text-document-position request.
    fn with_position(
        &self,
        params: Value,
        f: impl FnOnce(&Document, usize) -> serde_json::Result<Value>,
    ) -> Answer {
        let doc = self.doc(&params)?;
        let pos: lsp_types::Position = params
            .get("position")
            .cloned()
            .and_then(|p| serde_json::from_value(p).ok())
            .ok_or_else(|| invalid("params.position is missing or malformed"))?;
        f(doc, doc.lines.offset(&doc.text, pos)).map_err(internal)
    }

    /// Handles a notification; the notifications to send back.
    fn notification(&mut self, n: Notification) -> Vec<Notification> {
        if !self.initialized {
            return Vec::new();
        }
        let opened = match n.method.as_str() {
            DidOpenTextDocument::METHOD => n
                .extract::<lsp_types::DidOpenTextDocumentParams>(DidOpenTextDocument::METHOD)
                .ok()
                .map(|p| (p.text_document.uri, p.text_document.text)),
            DidChangeTextDocument::METHOD => n
                .extract::<lsp_types::DidChangeTextDocumentParams>(DidChangeTextDocument::METHOD)
                .ok()
                .and_then(|p| {
                    // Full sync: the last change is the whole text.
                    let text = p.content_changes.into_iter().last()?.text;
                    Some((p.text_document.uri, text))
                }),
            DidCloseTextDocument::METHOD => {
                let Ok(p) = n
                    .extract::<lsp_types::DidCloseTextDocumentParams>(DidCloseTextDocument::METHOD)
                else {
                    return Vec::new();
                };
                self.docs.remove(p.text_document.uri.as_str());
                return vec![publish(p.text_document.uri, Vec::new())];
            }
            _ => None,
        };
        let Some((uri, text)) = opened else {
            return Vec::new();
        };
        let key = uri.as_str().to_string();
        let doc = catch_unwind(AssertUnwindSafe(|| {
            Document::new(text, self.docs.get(&key))
        }));
        match doc {
            Ok(doc) => {
                let diagnostics = doc.lsp_diagnostics(&uri);
                self.docs.insert(key, doc);
                vec![publish(uri, diagnostics)]
            }
            Err(_) => {
                self.docs.remove(&key);
                Vec::new()
            }
        }
    }
}

/// The capabilities `initialize` announces.
fn capabilities() -> InitializeResult {
    InitializeResult {
        capabilities: ServerCapabilities {
            text_document_sync: Some(TextDocumentSyncCapability::Kind(TextDocumentSyncKind::FULL)),
            hover_provider: Some(HoverProviderCapability::Simple(true)),
            definition_provider: Some(OneOf::Left(true)),
            references_provider: Some(OneOf::Left(true)),
            completion_provider: Some(CompletionOptions {
                trigger_characters: Some(vec![" ".into()]),
                ..Default::default()
            }),
            document_symbol_provider: Some(OneOf::Left(true)),
            document_formatting_provider: Some(OneOf::Left(true)),
            ..Default::default()
        },
        server_info: Some(ServerInfo {
            name: "tsfc".into(),
            version: Some(env!("CARGO_PKG_VERSION").into()),
        }),
    }
}

/// `textDocument/formatting`: one edit replacing the whole document with
/// `tsfc fmt`'s layout; no edit when the document does not parse (or is past
/// the size limit), an empty list when it is already formatted.
fn formatting(doc: &Document) -> Answer {
    if doc.text.len() as u64 > MAX_SPEC_BYTES {
        return Ok(Value::Null);
    }
    let edits = match tsf_lang::format::format_source(&doc.text) {
        Err(_) => return Ok(Value::Null),
        Ok(formatted) if formatted == doc.text => Vec::new(),
        Ok(formatted) => vec![TextEdit {
            range: doc.lines.range(&doc.text, Span::new(0, doc.text.len())),
            new_text: formatted,
        }],
    };
    serde_json::to_value(edits).map_err(internal)
}

fn publish(uri: Uri, diagnostics: Vec<lsp_types::Diagnostic>) -> Notification {
    Notification::new(
        PublishDiagnostics::METHOD.into(),
        PublishDiagnosticsParams {
            uri,
            diagnostics,
            version: None,
        },
    )
}

fn respond(id: RequestId, answer: Answer) -> Response {
    match answer {
        Ok(v) => Response {
            id,
            result: Some(v),
            error: None,
        },
        Err((code, message)) => Response::new_err(id, code as i32, message),
    }
}

fn position_uri(params: &Value) -> Result<Uri, (ErrorCode, String)> {
    params
        .pointer("/textDocument/uri")
        .cloned()
        .and_then(|u| serde_json::from_value(u).ok())
        .ok_or_else(|| invalid("params.textDocument.uri is missing or malformed"))
}

fn invalid(message: &str) -> (ErrorCode, String) {
    (ErrorCode::InvalidParams, message.to_string())
}

fn internal(e: serde_json::Error) -> (ErrorCode, String) {
    (ErrorCode::InternalError, e.to_string())
}
