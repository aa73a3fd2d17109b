//! The loop over a request stream: bounded lines in, one flushed answer line out per request.

use crate::{ServeError, Server};
use std::io::{BufRead, ErrorKind, Write};

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

    /// [`Server::serve`], which also ends cleanly once `stop()` holds: after the answer in
    /// hand is written and flushed, or while it waits for a request when a signal interrupts
    /// the read (the binary's SIGTERM handler sets what `stop` reads).
    pub fn serve_until(
        &mut self,
        mut input: impl BufRead,
        mut output: impl Write,
        stop: &dyn Fn() -> bool,
    ) -> Result<Summary, ServeError> {
        let mut line = Vec::new();
        let mut answer = Vec::new();
        let mut summary = Summary::default();
        let max = self.limits().max_line_bytes;
        while let Some(read) =
            read_line_until(&mut input, &mut line, max, stop).map_err(ServeError::Read)?
        {
            answer.clear();
            let ok = match read {
                Line::Read if line.iter().all(u8::is_ascii_whitespace) => continue,
                Line::Read => self.answer_line(&line, &mut answer),
                Line::TooLong(bytes) => {
                    let message = format!(
                        "the line has {bytes} bytes, more than the budget of {max} bytes per \
                         request; split the request"
                    );
                    let e = ServeError::request("request", message);
                    self.write_error(&serde_json::Value::Null, &e, &mut answer);
                    false
                }
            };
            summary.requests += 1;
            summary.errors += u64::from(!ok);
            answer.push(b'\n');
            output.write_all(&answer).map_err(ServeError::Write)?;
            output.flush().map_err(ServeError::Write)?;
            shrink(&mut line, max);
            shrink(&mut answer, max);
            if stop() {
                break;
            }
        }
        Ok(summary)
    }
}

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
