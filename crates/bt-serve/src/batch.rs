//! Consecutive receiver moves answered together: the receivers of several requests traced and
//! reported in parallel over the cores, their answers written in request order.
//!
//! A request joins a batch only when its answer cannot depend on the requests before it in
//! the batch: it gives its receivers (`rx`), moves no object, and keeps the transmitter the
//! tracer already holds (the session's), so the only state it changes is the session's last
//! receivers, which no later member reads. Anything else is answered alone, after the batch.

use crate::request::Request;
use crate::server::{Outcome, rx_field, write_reply};
use crate::{ServeError, Server};
use std::time::Instant;

/// Requests waiting to be answered together, each with the instant it was parsed.
#[derive(Default)]
pub(crate) struct Batch {
    requests: Vec<(Request, Instant)>,
    receivers: usize,
}

impl Batch {
    /// Whether nothing waits.
    pub fn is_empty(&self) -> bool {
        self.requests.is_empty()
    }

    /// Receivers waiting, over all requests.
    pub fn receivers(&self) -> usize {
        self.receivers
    }
}

impl Server {
    /// Receivers a batch gathers before it is answered: eight per core, so each core has
    /// work between the batch's serial steps (reading, writing) and the uneven traces even out,
    /// while a waiting request's answer stays a few traces away. A batch only fills when
    /// requests queue up (it is answered as soon as no whole line waits); with two per core a
    /// 10,000-move stream took 1.59-1.74 s of CPU, with eight 1.35-1.48 s (the same build
    /// otherwise, run alternately).
    /// One when the tracer runs on one thread: each request is answered as it comes.
    pub(crate) fn batch_receivers(&self) -> usize {
        match self.parallel() {
            true => 8 * rayon::current_num_threads().max(2),
            false => 1,
        }
    }

    /// Whether `request` may wait in a batch (the module's rule).
    pub(crate) fn batchable(&self, request: &Request) -> bool {
        let tx = self.session.tx;
        request.rx.is_some()
            && !request.moves_objects()
            && self.session.poses == self.held
            && tx.is_some()
            && request.tx.is_none_or(|t| Some(t) == tx)
            && self.tracer.scene().tx_world() == tx
    }

    /// Add `request` (parsed at `t0`; [`Server::batchable`]) to `batch`.
    pub(crate) fn enqueue(&self, batch: &mut Batch, request: Request, t0: Instant) {
        batch.receivers += request.rx.as_ref().map_or(0, |rx| rx.positions().len());
        batch.requests.push((request, t0));
    }

    /// Answer every request of `batch` (emptied) in order, each line followed by a line break
    /// in `out`; the number of error lines. The receivers of all its requests are traced by
    /// one call (the kept TX tree walked in parallel) and reported in parallel. Should the
    /// trace fail as a whole (the TX's tree over its budget), each request is answered alone,
    /// so that each gets the error a lone request gets.
    pub(crate) fn answer_batch(&mut self, batch: &mut Batch, out: &mut Vec<u8>) -> u64 {
        if batch.is_empty() {
            return 0;
        }
        let requests = std::mem::take(&mut batch.requests);
        batch.receivers = 0;
        let Some(tx) = self.session.tx else {
            return self.answer_each(requests, out);
        };
        let mut positions = Vec::new();
        let mut starts = Vec::with_capacity(requests.len());
        for (request, _) in &requests {
            starts.push(positions.len());
            positions.extend_from_slice(request.rx.as_ref().map_or(&[], |rx| rx.positions()));
        }
        // Receiver `g` of the batch is receiver `g - starts[j]` of request `j`.
        let field = |g: usize| {
            let j = starts.partition_point(|&s| s <= g).saturating_sub(1);
            match &requests[j].0.rx {
                Some(rx) => rx_field(rx, g - starts[j]),
                None => "rx".to_string(),
            }
        };
        let outcomes = match self.traced_answers(tx, &positions, 0, &field, None) {
            Ok(outcomes) => outcomes,
            Err(_) => return self.answer_each(requests, out),
        };
        let mut outcomes = outcomes.into_iter();
        let mut errors = 0;
        for (request, t0) in requests {
            let Some(rx) = request.rx else {
                continue; // not batchable: never here
            };
            let mine: Vec<Outcome> = outcomes.by_ref().take(rx.positions().len()).collect();
            let start = out.len();
            match write_reply(&request.id, &rx, mine, t0, out) {
                Ok(()) => self.session.rx = Some(rx),
                Err(e) => {
                    out.truncate(start);
                    self.write_error(&request.id, &e, out);
                    errors += 1;
                }
            }
            out.push(b'\n');
        }
        errors
    }

    /// Answer `requests` one by one, each line followed by a line break; the error lines.
    fn answer_each(&mut self, requests: Vec<(Request, Instant)>, out: &mut Vec<u8>) -> u64 {
        let mut errors = 0;
        for (request, t0) in requests {
            errors += u64::from(!self.answer_request(&request, t0, out));
            out.push(b'\n');
        }
        errors
    }
}

/// An error of a request that never reached a batch, for the stream's own lines.
pub(crate) fn refusal(bytes: usize, max: usize) -> ServeError {
    let message = format!(
        "the line has {bytes} bytes, more than the budget of {max} bytes per request; split \
         the request"
    );
    ServeError::request("request", message)
}
