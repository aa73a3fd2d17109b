//! The loop over a request stream: bounded lines in, one flushed answer line out per request.

use crate::batch::{Batch, refusal};
use crate::{ServeError, Server, request};
use serde_json::Value;
use std::io::{BufRead, BufReader, ErrorKind, Write};
use std::time::Instant;

/// What a stream did, for the caller's log.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct Summary {
    /// Requests answered (blank lines are no requests).
    pub requests: u64,
    /// Of them, answered with an error line.
    pub errors: u64,
}

/// How a line read by [`read_bounded_line`] ended.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Line {
    /// The line is in the buffer (without its line break).
    Read,
    /// The line had this many bytes, more than the budget: it was skipped to its end and the
    /// buffer is empty.
    TooLong(usize),
}

/// Read the next line of `input` into `buf` (cleared first), holding at most `max` bytes of
/// it: a longer line is consumed to its end without being kept. `None` at the end of input.
/// A trailing `\r` is dropped (CRLF clients).
pub fn read_bounded_line(
    input: &mut impl BufRead,
    buf: &mut Vec<u8>,
    max: usize,
) -> std::io::Result<Option<Line>> {
    read_line_until(input, buf, max, &|| false)
}

/// [`read_bounded_line`], which also ends (`None`, a partial line dropped) when a read is
/// interrupted by a signal and `stop()` says so: a server told to stop (SIGTERM) while it
/// waits for a request.
fn read_line_until(
    input: &mut impl BufRead,
    buf: &mut Vec<u8>,
    max: usize,
    stop: &dyn Fn() -> bool,
) -> std::io::Result<Option<Line>> {
    buf.clear();
    let mut seen = 0usize;
    let mut any = false;
    loop {
        let available = match input.fill_buf() {
            Ok(b) => b,
            Err(e) if e.kind() == ErrorKind::Interrupted && stop() => return Ok(None),
            Err(e) if e.kind() == ErrorKind::Interrupted => continue,
            Err(e) => return Err(e),
        };
        if available.is_empty() {
            break;
        }
        any = true;
        let newline = available.iter().position(|&b| b == b'\n');
        let piece = &available[..newline.unwrap_or(available.len())];
        seen = seen.saturating_add(piece.len());
        if seen <= max {
            buf.extend_from_slice(piece);
        } else {
            buf.clear();
        }
        let used = newline.map_or(piece.len(), |n| n + 1);
        input.consume(used);
        if newline.is_some() {
            break;
        }
    }
    if !any {
        return Ok(None);
    }
    if seen > max {
        return Ok(Some(Line::TooLong(seen)));
    }
    if buf.last() == Some(&b'\r') {
        buf.pop();
    }
    Ok(Some(Line::Read))
}

impl Server {
    /// Answer every request of `input` on `output`, one line each in request order, each
    /// flushed as soon as it is written, until the end of input. Blank lines are skipped.
    /// Only the transport's errors end the stream ([`ServeError::Read`],
    /// [`ServeError::Write`]); memory stays flat: the line and answer buffers are reused, at
    /// most [`crate::Limits::max_line_bytes`] of a line is kept.
    pub fn serve(
        &mut self,
        input: impl BufRead,
        output: impl Write,
    ) -> Result<Summary, ServeError> {
        self.serve_until(input, output, &|| false)
    }

    /// [`Server::serve`], which also ends cleanly once `stop()` holds: after the answers in
    /// hand are written and flushed, or while it waits for a request when a signal interrupts
    /// the read (the binary's SIGTERM handler sets what `stop` reads).
    ///
    /// Receiver moves already waiting in the input are answered together (`docs/serve.md`,
    /// "Parallel answers": a few receivers per core, traced and reported in parallel), each
    /// answer still its own line in request order; a request is never held back for one that
    /// has not arrived: a batch is answered as soon as no whole line waits.
    pub fn serve_until(
        &mut self,
        input: impl BufRead,
        mut output: impl Write,
        stop: &dyn Fn() -> bool,
    ) -> Result<Summary, ServeError> {
        // Our own buffer over the input, so that whether another whole line waits can be
        // seen without blocking.
        let mut input = BufReader::with_capacity(INPUT_BUFFER, input);
        let mut line = Vec::new();
        let mut answer = Vec::new();
        let mut summary = Summary::default();
        let mut batch = Batch::default();
        let max = self.limits().max_line_bytes;
        let per_batch = self.batch_receivers();
        while let Some(read) =
            read_line_until(&mut input, &mut line, max, stop).map_err(ServeError::Read)?
        {
            let blank = matches!(read, Line::Read if line.iter().all(u8::is_ascii_whitespace));
            if !blank {
                summary.requests += 1;
                let parsed = match read {
                    Line::Read => request::parse(&line, self.limits()),
                    Line::TooLong(bytes) => Err((Value::Null, refusal(bytes, max))),
                };
                let t0 = Instant::now();
                match parsed {
                    Ok(request) if self.batchable(&request) => {
                        self.enqueue(&mut batch, request, t0)
                    }
                    parsed => {
                        summary.errors += self.answer_batch(&mut batch, &mut answer);
                        let ok = match parsed {
                            Ok(request) => self.answer_request(&request, t0, &mut answer),
                            Err((id, e)) => {
                                self.write_error(&id, &e, &mut answer);
                                false
                            }
                        };
                        summary.errors += u64::from(!ok);
                        answer.push(b'\n');
                    }
                }
            }
            let waiting = input.buffer().contains(&b'\n');
            if batch.receivers() >= per_batch || !waiting || stop() {
                summary.errors += self.answer_batch(&mut batch, &mut answer);
            }
            if !answer.is_empty() {
                output.write_all(&answer).map_err(ServeError::Write)?;
                output.flush().map_err(ServeError::Write)?;
                answer.clear();
            }
            shrink(&mut line, max);
            shrink(&mut answer, max);
            if stop() {
                break;
            }
        }
        summary.errors += self.answer_batch(&mut batch, &mut answer);
        output.write_all(&answer).map_err(ServeError::Write)?;
        output.flush().map_err(ServeError::Write)?;
        Ok(summary)
    }
}

/// The input buffer of [`Server::serve_until`], bytes: many short requests at once.
const INPUT_BUFFER: usize = 64 * 1024;

/// Give back a buffer's memory once one large request has passed, so a long stream holds no
/// more than one ordinary request's worth.
fn shrink(buf: &mut Vec<u8>, keep: usize) {
    if buf.capacity() > keep {
        buf.clear();
        buf.shrink_to(keep.min(64 * 1024));
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn lines(input: &[u8], max: usize) -> Vec<Result<String, usize>> {
        let mut reader = std::io::BufReader::with_capacity(4, input);
        let mut buf = Vec::new();
        let mut out = Vec::new();
        while let Some(line) = read_bounded_line(&mut reader, &mut buf, max).unwrap() {
            out.push(match line {
                Line::Read => Ok(String::from_utf8(buf.clone()).unwrap()),
                Line::TooLong(n) => Err(n),
            });
        }
        out
    }

    #[test]
    fn lines_are_bounded_and_the_rest_still_read() {
        let got = lines(b"ab\r\n0123456789\n\nlast", 5);
        assert_eq!(
            got,
            [
                Ok("ab".into()),
                Err(10),
                Ok(String::new()),
                Ok("last".into())
            ]
        );
        assert_eq!(lines(b"", 5), []);
        assert_eq!(lines(b"12345\n123456", 5), [Ok("12345".into()), Err(6)]);
    }
}
