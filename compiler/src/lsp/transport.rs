//! The stdio transport: LSP frames (`Content-Length` header, JSON body) read
//! on one thread and written on another. Unlike `lsp_server::Connection::stdio`,
//! a frame that is not JSON or not a JSON-RPC message gets an error response
//! (JSON-RPC 2.0: -32700 parse error, -32600 invalid request) and reading goes
//! on; a frame over [`MAX_FRAME_BYTES`] is skipped with an error response.

use crossbeam_channel::{bounded, Receiver, Sender};
use lsp_server::{ErrorCode, Message};
use serde_json::Value;
use std::io::{self, BufRead, Read, Write};

/// Largest frame read (bytes): a document of the spec size limit, escaped as
/// JSON, fits with room to spare.
pub const MAX_FRAME_BYTES: usize = 64 << 20;

/// The channels of the stdio connection and the threads serving them.
pub struct Stdio {
    /// Messages to the client.
    pub sender: Sender<Message>,
    /// Messages from the client (closed at the end of input).
    pub receiver: Receiver<Message>,
    writer: std::thread::JoinHandle<()>,
}

impl Stdio {
    /// Starts reading stdin and writing stdout.
    pub fn start() -> io::Result<Stdio> {
        let (to_client, outgoing) = bounded::<Message>(64);
        let (incoming, from_client) = bounded::<Message>(64);
        let writer = std::thread::Builder::new()
            .name("lsp-writer".into())
            .spawn(move || {
                for msg in outgoing {
                    let out = io::stdout();
                    let mut out = out.lock();
                    if msg.write(&mut out).is_err() {
                        break;
                    }
                }
            })?;
        std::thread::Builder::new()
            .name("lsp-reader".into())
            .spawn(move || read_loop(&mut io::stdin().lock(), &incoming))?;
        Ok(Stdio {
            sender: to_client,
            receiver: from_client,
            writer,
        })
    }

    /// Closes the outgoing channel and waits until everything is written.
    pub fn finish(self) {
        drop(self.sender);
        let _ = self.writer.join();
    }
}

/// What one frame turned out to be.
#[derive(Debug)]
pub enum Frame {
    /// A message.
    Message(Message),
    /// An error to answer with (the id, JSON `null` when unknown, the code and the text).
    Error(serde_json::Value, ErrorCode, String),
}

fn read_loop(input: &mut impl BufRead, incoming: &Sender<Message>) {
    loop {
        match read_frame(input) {
            Ok(None) | Err(_) => return,
            Ok(Some(Frame::Message(m))) => {
                let exit = matches!(&m, Message::Notification(n) if n.method == "exit");
                if incoming.send(m).is_err() || exit {
                    return;
                }
            }
            Ok(Some(Frame::Error(id, code, message))) => {
                let body = serde_json::json!({
                    "jsonrpc": "2.0",
                    "id": id,
                    "error": { "code": code as i32, "message": message },
                })
                .to_string();
                let out = io::stdout();
                let mut out = out.lock();
                let written = write!(out, "Content-Length: {}\r\n\r\n{body}", body.len())
                    .and_then(|()| out.flush());
                if written.is_err() {
                    return;
                }
            }
        }
    }
}

/// Reads one frame: `None` at the end of input; an I/O error for a broken header.
pub fn read_frame(input: &mut impl BufRead) -> io::Result<Option<Frame>> {
    let mut length: Option<usize> = None;
    let mut line = String::new();
    loop {
        line.clear();
        let n = input.by_ref().take(4096).read_line(&mut line)?;
        if n == 0 {
            return Ok(None);
        }
        let header = line.trim_end_matches(['\r', '\n']);
        if header.is_empty() {
            if length.is_some() {
                break;
            }
            continue; // stray blank line between frames
        }
        if let Some((name, value)) = header.split_once(':') {
            if name.eq_ignore_ascii_case("content-length") {
                length = value.trim().parse().ok();
                if length.is_none() {
                    return Err(io::Error::new(
                        io::ErrorKind::InvalidData,
                        "bad Content-Length",
                    ));
                }
            }
        }
    }
    let length = length.unwrap_or(0);
    if length > MAX_FRAME_BYTES {
        io::copy(&mut input.by_ref().take(length as u64), &mut io::sink())?;
        return Ok(Some(Frame::Error(
            serde_json::Value::Null,
            ErrorCode::InvalidRequest,
            format!("message of {length} bytes is over the limit of {MAX_FRAME_BYTES}"),
        )));
    }
    let mut body = vec![0u8; length];
    input.read_exact(&mut body)?;
    Ok(Some(parse(&body)))
}

/// A frame's body as a message, or the error response it gets.
pub fn parse(body: &[u8]) -> Frame {
    let value: serde_json::Value = match serde_json::from_slice(body) {
        Ok(v) => v,
        Err(e) => {
            return Frame::Error(
                serde_json::Value::Null,
                ErrorCode::ParseError,
                format!("not JSON: {e}"),
            )
        }
    };
    let id = value.get("id").cloned().unwrap_or_default();
    // A response carries `result` or `error`; without them and without a
    // `method`, serde would read any object with an id as an empty response.
    let shaped = value.get("method").is_some_and(Value::is_string)
        || value.get("result").is_some()
        || value.get("error").is_some();
    match serde_json::from_value::<Message>(value) {
        Ok(m) if shaped => Frame::Message(m),
        Ok(_) => Frame::Error(
            id,
            ErrorCode::InvalidRequest,
            "not a JSON-RPC request, response or notification: no method, result or error".into(),
        ),
        Err(e) => Frame::Error(
            id,
            ErrorCode::InvalidRequest,
            format!("not a JSON-RPC request, response or notification: {e}"),
        ),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn frame(body: &str) -> Vec<u8> {
        format!("Content-Length: {}\r\n\r\n{body}", body.len()).into_bytes()
    }

    #[test]
    fn frames_and_errors() {
        let mut bytes = frame(r#"{"jsonrpc":"2.0","id":1,"method":"shutdown"}"#);
        bytes.extend(frame("{not json"));
        bytes.extend(frame(r#"{"jsonrpc":"2.0","id":7,"params":3}"#));
        let mut input = io::Cursor::new(bytes);
        let first = read_frame(&mut input).unwrap().unwrap();
        assert!(matches!(first, Frame::Message(Message::Request(r)) if r.method == "shutdown"));
        let second = read_frame(&mut input).unwrap().unwrap();
        assert!(matches!(
            second,
            Frame::Error(serde_json::Value::Null, ErrorCode::ParseError, _)
        ));
        let third = read_frame(&mut input).unwrap().unwrap();
        assert!(
            matches!(&third, Frame::Error(id, ErrorCode::InvalidRequest, _) if id == 7),
            "{third:?}"
        );
        assert!(read_frame(&mut input).unwrap().is_none());
    }
}
