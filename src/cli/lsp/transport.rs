//! The server's messages on stdin and stdout, framed as the protocol says
//! (`Content-Length: N`, a blank line, then N bytes of JSON), with the
//! limits lsp-server's own reader lacks: it sizes its buffer by the
//! length a header announces before a byte of the body has come, so one
//! line (`Content-Length: 1000000000000`) aborted the server and a large
//! announced length held that memory while it waited.
//!
//! Here a header line is at most [`MAX_HEADER_LINE`] bytes, a message at
//! most [`MAX_MESSAGE`] (docs/limits.md), and the memory a body takes
//! grows with the bytes received, not announced, after the system has
//! been asked whether the message fits ([`crate::system::resources`] as every
//! command asks). A message refused for its size is read past and
//! dropped, and said to the editor (`window/showMessage`) and on stderr;
//! the session goes on. Broken framing ends it, as an error.

use std::io::{self, BufRead, Read, Write};
use std::thread::JoinHandle;

use crossbeam_channel::{Receiver, Sender, bounded};
use lsp_server::{Connection, Message, Notification};
use lsp_types::notification::{Notification as _, ShowMessage};
use lsp_types::{MessageType, ShowMessageParams};
use rayoflight::system::resources;

/// The largest message taken, in bytes: a scene file of about 2.5 million
/// objects, as JSON, in one `didOpen`.
pub const MAX_MESSAGE: u64 = 512 << 20;

/// The longest header line taken, in bytes (the protocol has two short
/// headers).
const MAX_HEADER_LINE: usize = 8 << 10;

/// The most header lines in one message.
const MAX_HEADERS: usize = 16;

/// Bytes a body is read by.
const CHUNK: usize = 1 << 16;

/// The reading and writing threads; [`Threads::join`] waits for both.
pub struct Threads {
    reader: JoinHandle<io::Result<()>>,
    writer: JoinHandle<io::Result<()>>,
}

impl Threads {
    /// Waits for both threads; the first error either had.
    pub fn join(self) -> io::Result<()> {
        let reader = self.reader.join();
        let writer = self.writer.join();
        for done in [reader, writer] {
            match done {
                Ok(result) => result?,
                Err(_) => return Err(io::Error::other("a thread of the server panicked")),
            }
        }
        Ok(())
    }
}

/// A connection over stdin and stdout, as lsp-server's
/// `Connection::stdio`, with this module's limits.
pub fn stdio() -> (Connection, Threads) {
    let (to_editor, outgoing) = bounded::<Message>(0);
    let (incoming, from_editor) = bounded::<Message>(0);
    let writer = std::thread::Builder::new()
        .name("lsp-writer".to_owned())
        .spawn(move || write_all(outgoing, &mut io::stdout().lock()))
        .expect("a thread starts");
    let tell = to_editor.clone();
    let reader = std::thread::Builder::new()
        .name("lsp-reader".to_owned())
        .spawn(move || read_all(&mut io::stdin().lock(), &incoming, &tell))
        .expect("a thread starts");
    let connection = Connection {
        sender: to_editor,
        receiver: from_editor,
    };
    (connection, Threads { reader, writer })
}

fn write_all(outgoing: Receiver<Message>, out: &mut impl Write) -> io::Result<()> {
    for message in outgoing {
        message.write(out)?;
    }
    Ok(())
}

/// Reads messages until the editor's end closes or says `exit`, handing
/// each to `incoming`; a message refused for its size is told to the
/// editor through `tell` and on stderr.
fn read_all(
    input: &mut impl BufRead,
    incoming: &Sender<Message>,
    tell: &Sender<Message>,
) -> io::Result<()> {
    loop {
        match read_frame(input, resources::available_memory())? {
            Frame::End => return Ok(()),
            Frame::Message(message) => {
                let exit = matches!(&message, Message::Notification(n) if n.method == "exit");
                if incoming.send(message).is_err() || exit {
                    return Ok(());
                }
            }
            Frame::Refused { why, unread } => {
                // Said at once, before the body is read past (it may be
                // long in coming, or never come).
                let text = format!("rayoflight lsp: {why}; the message was dropped");
                eprintln!("{text}");
                let params = ShowMessageParams {
                    typ: MessageType::ERROR,
                    message: text,
                };
                let _ = tell.send(Message::Notification(Notification::new(
                    ShowMessage::METHOD.to_owned(),
                    params,
                )));
                if !skip(input, unread)? {
                    return Ok(());
                }
            }
        }
    }
}

/// Reads past `n` bytes of the input, holding none; false where it ended
/// first.
pub fn skip(input: &mut impl BufRead, n: u64) -> io::Result<bool> {
    Ok(io::copy(&mut input.take(n), &mut io::sink())? == n)
}

/// What one frame of the input was.
#[derive(Debug)]
pub enum Frame {
    Message(Message),
    /// Too large for the limit or the memory left: dropped, its `unread`
    /// bytes still to be read past ([`skip`]).
    Refused {
        why: String,
        unread: u64,
    },
    /// The input ended between messages.
    End,
}

/// Reads one frame. `available`: the memory this process may still take
/// ([`resources::available_memory`]), where known. A body is taken only
/// where twice its length fits (its bytes and what they are parsed into).
pub fn read_frame(input: &mut impl BufRead, available: Option<u64>) -> io::Result<Frame> {
    let invalid = |why: String| io::Error::new(io::ErrorKind::InvalidData, why);
    let mut length = None;
    let mut lines = 0;
    loop {
        let mut line = Vec::new();
        let read = input
            .take(MAX_HEADER_LINE as u64 + 1)
            .read_until(b'\n', &mut line)?;
        if read == 0 && lines == 0 {
            return Ok(Frame::End);
        }
        if !line.ends_with(b"\n") {
            return Err(invalid(match read > MAX_HEADER_LINE {
                true => format!("a header line longer than {MAX_HEADER_LINE} bytes"),
                false => "the input ended inside a header".to_owned(),
            }));
        }
        lines += 1;
        if lines > MAX_HEADERS {
            return Err(invalid(format!("more than {MAX_HEADERS} header lines")));
        }
        let line = String::from_utf8_lossy(&line);
        let line = line.trim_end_matches(['\r', '\n']);
        if line.is_empty() {
            break;
        }
        let Some((name, value)) = line.split_once(':') else {
            return Err(invalid(format!("a header without a colon: {line:?}")));
        };
        if name.trim().eq_ignore_ascii_case("content-length") {
            let value = value.trim();
            length = Some(
                value
                    .parse::<u64>()
                    .map_err(|_| invalid(format!("Content-Length {value:?} is not a length")))?,
            );
        }
    }
    let length = length.ok_or_else(|| invalid("a message without Content-Length".to_owned()))?;
    let refusal = if length > MAX_MESSAGE {
        Some(format!(
            "a message of {length} bytes is over the limit of {} ({MAX_MESSAGE} bytes)",
            resources::size(MAX_MESSAGE)
        ))
    } else {
        let needed = length.saturating_mul(2).saturating_add(resources::MARGIN);
        match available {
            Some(available) if needed > available => Some(format!(
                "a message of {length} bytes {}",
                resources::NotEnoughMemory {
                    needed,
                    available: Some(available),
                }
            )),
            _ => None,
        }
    };
    if let Some(why) = refusal {
        return Ok(Frame::Refused {
            why,
            unread: length,
        });
    }
    // Grown as bytes come, never to the announced length at once.
    let mut body = Vec::new();
    let mut chunk = vec![0; CHUNK];
    let mut left = length;
    while left > 0 {
        let want = left.min(CHUNK as u64) as usize;
        let n = input.read(&mut chunk[..want])?;
        if n == 0 {
            return Ok(Frame::End);
        }
        if body.try_reserve(n).is_err() {
            return Ok(Frame::Refused {
                why: format!(
                    "a message of {length} bytes {}",
                    resources::NotEnoughMemory {
                        needed: length,
                        available: None,
                    }
                ),
                unread: left - n as u64,
            });
        }
        body.extend_from_slice(&chunk[..n]);
        left -= n as u64;
    }
    // A big document's text becomes a string in the body's own memory.
    let message = super::json::message(body).map_err(invalid)?;
    Ok(Frame::Message(message))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn frame(text: &[u8], available: Option<u64>) -> io::Result<Frame> {
        read_frame(&mut io::BufReader::new(text), available)
    }

    #[test]
    fn a_message_is_read_and_the_end_seen() {
        let body = r#"{"jsonrpc":"2.0","method":"exit"}"#;
        let text = format!("Content-Length: {}\r\n\r\n{body}", body.len());
        assert!(matches!(
            frame(text.as_bytes(), None).unwrap(),
            Frame::Message(Message::Notification(n)) if n.method == "exit"
        ));
        assert!(matches!(frame(b"", None).unwrap(), Frame::End));
    }

    #[test]
    fn an_announced_length_takes_no_memory_before_its_bytes() {
        // Over the limit: refused at its header, the body never taken
        // (here, the input ends before it).
        let mut input = io::BufReader::new(&b"Content-Length: 1000000000000\r\n\r\n{}"[..]);
        let Frame::Refused { why, unread } = read_frame(&mut input, None).unwrap() else {
            panic!("taken");
        };
        assert_eq!(
            why,
            "a message of 1000000000000 bytes is over the limit of 537 MB (536870912 bytes)"
        );
        assert_eq!(unread, 1_000_000_000_000);
        assert!(!skip(&mut input, unread).unwrap());
        // Under the limit but over the memory left: refused, read past,
        // and the next message is read.
        let body = format!(
            r#"{{"jsonrpc":"2.0","method":"x","params":"{}"}}"#,
            "a".repeat(1000)
        );
        let next = r#"{"jsonrpc":"2.0","method":"exit"}"#;
        let text = format!(
            "Content-Length: {}\r\n\r\n{body}Content-Length: {}\r\n\r\n{next}",
            body.len(),
            next.len()
        );
        let mut input = io::BufReader::new(text.as_bytes());
        let Frame::Refused { why, unread } = read_frame(&mut input, Some(1000)).unwrap() else {
            panic!("taken");
        };
        let starts = format!("a message of {} bytes needs", body.len());
        assert!(why.starts_with(&starts), "{why}");
        assert!(skip(&mut input, unread).unwrap());
        assert!(matches!(
            read_frame(&mut input, None).unwrap(),
            Frame::Message(_)
        ));
    }

    #[test]
    fn broken_framing_is_an_error() {
        let long = format!("X-Long: {}\r\n", "a".repeat(MAX_HEADER_LINE));
        for text in [
            long.as_str(),
            "Content-Length: -1\r\n\r\n",
            "Content-Type: x\r\n\r\n{}",
            "no colon\r\n\r\n",
            "Content-Length: 2\r\n\r\n{]",
        ] {
            let err = frame(text.as_bytes(), None).unwrap_err();
            assert_eq!(err.kind(), io::ErrorKind::InvalidData, "{text}");
        }
    }
}
