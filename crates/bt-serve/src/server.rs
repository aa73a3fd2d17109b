//! The session state and the answer to one request.

use crate::json;
use crate::request::{self, Receivers, Request};
use crate::{BeamOptions, Limits, ServeError};
use bt_beams::{
    BeamPair, BeamRanking, PathReport, RadioOptions, Records, Stats, StepDocument, StepStats,
};
use bt_geom::Vec3;
use bt_scene::dynamic::{DynamicScene, Pose};
use bt_scene::{SceneError, Terminals};
use bt_solve::Tracer;
use bt_solve::partner::Partner;
use bt_solve::pipeline::{TraceError, TraceOptions, Traced};
use serde::Serialize;
use serde_json::Value;
use std::io::Write;
use std::sync::{Arc, Mutex};
use std::time::{Duration, Instant};

/// A long-lived tracer answering requests: one [`Tracer`] for the whole life of the server
/// (its TX tree and caches carry over from request to request), the scene's objects and the
/// session's transmitter, receivers and poses. A clone serves another stream (a connection)
/// from the same state, with caches of its own.
#[derive(Clone)]
pub struct Server {
    pub(crate) tracer: Tracer,
    dynamic: DynamicScene,
    radio: RadioOptions,
    limits: Limits,
    /// The session's state when it starts ([`Server::end_session`] goes back to it).
    initial: Session,
    pub(crate) session: Session,
    /// The object poses of the geometry the tracer holds (aligned with the objects).
    pub(crate) held: Vec<Pose>,
    /// Beam answers, when the server sweeps arrays.
    beams: Option<BeamOptions>,
}

/// What a request may leave out and take from the previous one.
#[derive(Debug, Clone)]
pub(crate) struct Session {
    pub(crate) tx: Option<Vec3>,
    pub(crate) rx: Option<Receivers>,
    pub(crate) poses: Vec<Pose>,
}

/// The answer for one receiver: the fields of `trace --json` a receiver changes.
#[derive(Serialize)]
struct Answer<'a> {
    /// The reply's opening `{"id":ID` for the lone receiver of a request, written before the
    /// fields ([`serialise`]) so that the answer becomes the reply line without a copy
    /// ([`write_reply`]); not a field of the answer.
    #[serde(skip)]
    head: Option<&'a [u8]>,
    tx: [f64; 3],
    rx: [f64; 3],
    paths: &'a [PathReport],
    stats: AnswerStats,
    #[serde(skip_serializing_if = "Option::is_none")]
    beams: Option<BeamsAnswer>,
}

/// The beam sweep of one answer: the codebooks' sizes, the ranking, the best pair (`null` when
/// no power arrives) and the first pairs of the ranking (`beamtrace beams`' records).
#[derive(Serialize)]
struct BeamsAnswer {
    tx_beams: usize,
    rx_beams: usize,
    ranking: BeamRanking,
    best: Option<BeamPair>,
    top: Vec<BeamPair>,
}

/// The stats of `trace --json` for a trace, or of a `--steps` step for a request that moved
/// objects (its `update` counts say what the incremental update did).
#[derive(Serialize)]
#[serde(untagged)]
enum AnswerStats {
    Trace(bt_beams::Stats),
    Step(StepStats),
}

/// One receiver's outcome: its answer object serialised (`{"tx": ..., "stats": {...}}`, the
/// fields of [`Answer`]), or its error. Serialised where it is traced (on its worker thread
/// when receivers run in parallel), so only bytes travel back to the request's line.
pub(crate) type Outcome = Result<Vec<u8>, ServeError>;

/// The entry of `results` for a receiver that could not be traced.
#[derive(Serialize)]
struct EntryError {
    rx: [f64; 3],
    error: String,
}

#[derive(Serialize)]
struct ErrorLine<'a> {
    id: &'a Value,
    error: String,
}

impl Server {
    /// A server tracing `dynamic` (a static scene is one step without objects) under
    /// `options`, reporting with `radio`. The session starts with step 0: its terminals
    /// (the scene's, or `--tx`/`--rx`) and its objects' poses.
    pub fn new(
        dynamic: DynamicScene,
        options: TraceOptions,
        radio: RadioOptions,
        limits: Limits,
    ) -> Self {
        let scene0 = dynamic.step(0).clone();
        let poses: Vec<Pose> = dynamic.objects().iter().map(|o| o.poses[0]).collect();
        let initial = Session {
            tx: scene0.tx_world(),
            rx: scene0.rx_world().map(Receivers::One),
            poses: poses.clone(),
        };
        Server {
            tracer: Tracer::new(scene0, options),
            dynamic,
            radio,
            limits,
            session: initial.clone(),
            initial,
            held: poses,
            beams: None,
        }
    }

    /// The server splitting a lone receiver's walk of the kept tree, report and JSON over a
    /// second core ([`Partner`]), whose thread spins for `window` after each answer before it sleeps (a
    /// stream of requests keeps it awake, at the price of that core); no partner when
    /// `window` is zero, or on one core.
    pub fn with_partner(mut self, window: Duration) -> Self {
        let cores = std::thread::available_parallelism().map_or(1, |n| n.get());
        let partner = match window.is_zero() || cores < 2 {
            true => None,
            false => Partner::new(window).map(Arc::new),
        };
        self.tracer.set_partner(partner);
        self
    }

    /// The server answering with a beam sweep too ([`BeamOptions`]).
    pub fn with_beams(self, beams: BeamOptions) -> Self {
        Server {
            beams: Some(beams),
            ..self
        }
    }

    /// The bounds of every request.
    pub fn limits(&self) -> &Limits {
        &self.limits
    }

    /// The tracer (its scene is the geometry of the last request that moved objects).
    pub fn tracer(&self) -> &Tracer {
        &self.tracer
    }

    /// End a client's session: the next request starts from step 0's terminals and poses
    /// again (a new connection), while the tracer keeps its trees and caches.
    pub fn end_session(&mut self) {
        self.session = self.initial.clone();
    }

    /// Answer one request line into `out` (cleared first; one JSON object, no line break);
    /// false when the answer is an error line.
    pub fn answer_line(&mut self, line: &[u8], out: &mut Vec<u8>) -> bool {
        out.clear();
        let request = match request::parse(line, &self.limits) {
            Ok(r) => r,
            Err((id, e)) => {
                self.write_error(&id, &e, out);
                return false;
            }
        };
        self.answer_request(&request, Instant::now(), out)
    }

    /// Answer a parsed `request` (parsed at `t0`) by appending its line to `out` (without a
    /// line break); false when the answer is an error line.
    pub(crate) fn answer_request(
        &mut self,
        request: &Request,
        t0: Instant,
        out: &mut Vec<u8>,
    ) -> bool {
        let start = out.len();
        match self.answer(request, t0, out) {
            Ok(()) => true,
            Err(e) => {
                out.truncate(start);
                self.write_error(&request.id, &e, out);
                false
            }
        }
    }

    /// The error line `{"id", "error"}` of `e` into `out`.
    pub(crate) fn write_error(&self, id: &Value, e: &ServeError, out: &mut Vec<u8>) {
        let line = ErrorLine {
            id,
            error: e.to_string(),
        };
        let start = out.len();
        if serde_json::to_writer(&mut *out, &line).is_err() {
            out.truncate(start);
            out.extend_from_slice(br#"{"id":null,"error":"the answer could not be written"}"#);
        }
    }

    /// Trace `request` and write its answer; the session takes its positions and poses once
    /// it is answered.
    fn answer(
        &mut self,
        request: &Request,
        t0: Instant,
        out: &mut Vec<u8>,
    ) -> Result<(), ServeError> {
        let tx = request.tx.or(self.session.tx).ok_or_else(|| {
            ServeError::request("tx", "no transmitter yet: give \"tx\": [x, y, z] (or --tx)")
        })?;
        let rx = request.rx.clone().or_else(|| self.session.rx.clone());
        let rx = rx.ok_or_else(|| {
            ServeError::request("rx", "no receiver yet: give \"rx\": [x, y, z] (or --rx)")
        })?;
        let poses = self.poses(request)?;
        let field = |i: usize| rx_field(&rx, i);
        let positions = rx.positions();
        // A lone receiver's answer opens the reply itself.
        let head = match rx {
            Receivers::One(_) => Some(reply_head(&request.id)?),
            Receivers::Many(_) => None,
        };
        let head = head.as_deref();
        let outcomes = match poses != self.held {
            true => self.update_and_trace(tx, positions, &poses, &field, head)?,
            false => self.trace(tx, positions, 0, &field, head)?,
        };
        write_reply(&request.id, &rx, outcomes, t0, out)?;
        self.session = Session {
            tx: Some(tx),
            rx: Some(rx),
            poses,
        };
        Ok(())
    }

    /// The poses a request asks for: the session's, or step `step`'s, then `objects`'.
    fn poses(&self, request: &Request) -> Result<Vec<Pose>, ServeError> {
        let objects = self.dynamic.objects();
        let mut poses = match request.step {
            None => self.session.poses.clone(),
            Some(k) if k < self.dynamic.len() => objects.iter().map(|o| o.poses[k]).collect(),
            Some(k) => {
                let message = format!(
                    "is {k}; the scene has {} step(s), 0 to {}",
                    self.dynamic.len(),
                    self.dynamic.len() - 1
                );
                return Err(ServeError::request("step", message));
            }
        };
        for (name, desc) in &request.objects {
            let location = format!("objects.{}", bt_scene::name::shown(name));
            let Some(i) = objects.iter().position(|o| &o.name == name) else {
                // Names from the scene file, escaped, and a few of them only.
                let mut names: Vec<String> = (objects.iter().take(20))
                    .map(|o| format!("\"{}\"", bt_scene::name::shown(&o.name)))
                    .collect();
                if objects.len() > 20 {
                    names.push(format!("... ({} in all)", objects.len()));
                }
                let known = match names.is_empty() {
                    true => "the scene has no moving objects".to_string(),
                    false => format!("the scene's objects are {}", names.join(", ")),
                };
                return Err(ServeError::request(
                    location,
                    format!("no such object; {known}"),
                ));
            };
            poses[i] = objects[i].pose(desc, &location).map_err(|problems| {
                ServeError::Scene(
                    problems
                        .iter()
                        .map(|p| p.to_string())
                        .collect::<Vec<_>>()
                        .join("; "),
                )
            })?;
        }
        Ok(poses)
    }

    /// Trace `tx` to `positions` (the first of them at index `first` of the request) in the
    /// geometry held, one outcome per receiver; the tracer's scene takes `tx` first, so its
    /// tree is the one kept and reused.
    fn trace(
        &mut self,
        tx: Vec3,
        positions: &[Vec3],
        first: usize,
        field: &Field<'_>,
        head: Option<&[u8]>,
    ) -> Result<Vec<Outcome>, ServeError> {
        if positions.is_empty() {
            return Ok(Vec::new());
        }
        if self.tracer.scene().tx_world() != Some(tx) {
            let scene = self.with_transmitter(tx, positions, first, field)?;
            self.tracer.set_scene(scene);
        }
        self.traced_answers(tx, positions, first, field, head)
    }

    /// Each receiver of `positions` (the first at index `first` of `field`) traced from `tx`
    /// and its answer reported and serialised in the same task: in parallel over the cores
    /// when the tracer runs in parallel and there is more than one receiver (the report and
    /// its JSON cost more than the walk of the kept tree), in order. Fails as a whole only
    /// when the TX cannot be traced ([`Tracer::trace_each`]). `head` opens each answer (a
    /// request's lone receiver: [`Answer::head`]).
    pub(crate) fn traced_answers(
        &mut self,
        tx: Vec3,
        positions: &[Vec3],
        first: usize,
        field: &Field<'_>,
        head: Option<&[u8]>,
    ) -> Result<Vec<Outcome>, ServeError> {
        let partner = self.tracer.partner().filter(|_| positions.len() == 1);
        let reporter = Reporter {
            radio: &self.radio,
            beams: self.beams.as_ref(),
            head,
            partner: partner.as_deref(),
        };
        let traced = self.tracer.trace_each_then(tx, positions, |scene, traced| {
            reporter.trace_answer(scene, &traced)
        });
        let traced = traced.map_err(|e| trace_error(e, &field(first)))?;
        Ok((traced.into_iter().enumerate())
            .map(|(i, outcome)| outcome.unwrap_or_else(|e| Err(trace_error(e, &field(first + i)))))
            .collect())
    }

    /// Whether receivers are traced and answered in parallel (the trace options').
    pub(crate) fn parallel(&self) -> bool {
        self.tracer.options().parallel
    }

    /// The scene held with the transmitter at `tx` and, as its receiver, the first of
    /// `positions` the scene accepts (a bad receiver in a list fails alone, later); when none
    /// is accepted, the first one's error.
    fn with_transmitter(
        &self,
        tx: Vec3,
        positions: &[Vec3],
        first: usize,
        field: &Field<'_>,
    ) -> Result<bt_scene::Scene, ServeError> {
        let mut refusal = None;
        for (i, &rx) in positions.iter().enumerate() {
            match self.tracer.scene().with_terminals(tx, rx) {
                Ok(scene) => return Ok(scene),
                Err(e) => {
                    refusal.get_or_insert_with(|| scene_error(&e, &field(first + i)));
                }
            }
        }
        Err(refusal.unwrap_or_else(|| ServeError::request("rx", "no receiver")))
    }

    /// Move the objects to `poses` and trace the first receiver as the tracer's next time
    /// step (incrementally, as `trace --steps`), the others in that geometry; `head` opens
    /// the answers ([`Answer::head`]).
    fn update_and_trace(
        &mut self,
        tx: Vec3,
        positions: &[Vec3],
        poses: &[Pose],
        field: &Field<'_>,
        head: Option<&[u8]>,
    ) -> Result<Vec<Outcome>, ServeError> {
        let Some(&rx0) = positions.first() else {
            return Ok(Vec::new());
        };
        let terminals = Terminals {
            tx: Some(tx),
            rx: Some(rx0),
        };
        let scene = self.dynamic.posed(poses, terminals);
        let scene = scene.map_err(|e| scene_error(&e, &field(0)))?;
        self.held = poses.to_vec();
        let t0 = Instant::now();
        let step = self
            .tracer
            .update(&scene)
            .map_err(|e| trace_error(e, &field(0)))?;
        let doc = StepDocument::report(&scene, step, &self.radio, t0.elapsed())?;
        let reporter = Reporter {
            radio: &self.radio,
            beams: self.beams.as_ref(),
            head,
            partner: None,
        };
        let first = serialise(&Answer {
            head,
            tx: doc.tx,
            rx: doc.rx,
            beams: reporter.beams_of(&doc.paths, scene.frequency_hz())?,
            paths: &doc.paths,
            stats: AnswerStats::Step(doc.stats),
        });
        let mut outcomes = vec![first];
        outcomes.extend(self.trace(tx, &positions[1..], 1, field, head)?);
        Ok(outcomes)
    }
}

thread_local! {
    /// The path records of the last answer reported on this thread, whose memory the next
    /// answer's records reuse: a serve stream's answers allocate no path records once the
    /// threads have seen a typical answer (the stream's memory stays flat: at most the
    /// largest answer's records and [`Records`]' spares per thread).
    static REPORTS: std::cell::RefCell<Records> = std::cell::RefCell::default();
}

/// The radio side of every answer: the part of a [`Server`] the receivers'
/// answers need, shared by the threads that trace and report them.
#[derive(Clone, Copy)]
struct Reporter<'a> {
    radio: &'a RadioOptions,
    beams: Option<&'a BeamOptions>,
    /// What opens each answer ([`Answer::head`]).
    head: Option<&'a [u8]>,
    /// Who takes half of the report and of the JSON ([`Server::with_partner`]).
    partner: Option<&'a Partner>,
}

impl Reporter<'_> {
    /// The answer of a trace in `scene` (with its TX and RX): the fields `trace --json` writes
    /// ([`bt_beams::TraceDocument::report`]), its paths reported into this thread's [`Records`] (the
    /// previous answer's memory; `REPORTS`).
    fn trace_answer(&self, scene: &bt_scene::Scene, traced: &Traced) -> Outcome {
        REPORTS.with_borrow_mut(|records| {
            let t0 = Instant::now();
            let [tx, rx] = bt_beams::terminals_world(scene)?;
            let found = &traced.result.paths;
            let mut bytes = open_answer(self.head, tx, rx, found.len())?;
            let (mine, theirs) = records.report_halves(
                scene,
                found,
                self.radio,
                self.partner,
                |first| json::write_records(&mut bytes, first),
                |second| match second.is_empty() {
                    true => Ok(None),
                    false => {
                        let mut theirs = answer_buffer();
                        json::write_records(&mut theirs, second).map(|()| Some(theirs))
                    }
                },
            )?;
            mine.map_err(io_error)?;
            if let Some(theirs) = theirs.map_err(io_error)? {
                if bytes.last() != Some(&b'[') {
                    bytes.push(b',');
                }
                bytes.extend_from_slice(&theirs);
                give_back(theirs);
            }
            let paths = records.paths();
            let stats = Stats::of(traced, paths, self.radio, [Duration::ZERO, t0.elapsed()]);
            let beams = self.beams_of(paths, scene.frequency_hz())?;
            close_answer(bytes, &AnswerStats::Trace(stats), beams.as_ref())
        })
    }

    /// The beam sweep of `paths` at `carrier_hz`, when the server sweeps arrays.
    fn beams_of(
        &self,
        paths: &[PathReport],
        carrier_hz: f64,
    ) -> Result<Option<BeamsAnswer>, ServeError> {
        let Some(b) = self.beams else {
            return Ok(None);
        };
        let power = self.radio.tx_power_dbm;
        let sweep = bt_beams::sweep(
            paths,
            &b.tx,
            &b.rx,
            carrier_hz,
            power,
            b.ranking,
            b.max_pairs,
        )?;
        let best = sweep
            .pairs
            .first()
            .filter(|p| p.power_dbm.is_some())
            .cloned();
        Ok(Some(BeamsAnswer {
            tx_beams: sweep.tx_beams,
            rx_beams: sweep.rx_beams,
            ranking: sweep.ranking,
            best,
            top: sweep.pairs.into_iter().take(b.top).collect(),
        }))
    }
}

/// The field of a request's receiver `i` in messages (`rx`, or `rx[i]` in a list); shared by
/// the receivers' parallel answers.
pub(crate) type Field<'a> = dyn Fn(usize) -> String + Sync + 'a;

/// The field of receiver `i` of `rx` in messages: `rx` for one, `rx[i]` in a list.
pub(crate) fn rx_field(rx: &Receivers, i: usize) -> String {
    match rx {
        Receivers::One(_) => "rx".to_string(),
        Receivers::Many(_) => format!("rx[{i}]"),
    }
}

/// Answer buffers whose bytes went into their reply ([`write_reply`]), for the next answers
/// ([`serialise`]): a stream's answers reuse a few buffers instead of allocating (and, for
/// tens of kilobytes, faulting in fresh pages) one each. Shared by the threads, since an
/// answer serialised on a worker is put into its reply on the serving thread.
static SPARE_ANSWERS: Mutex<Vec<Vec<u8>>> = Mutex::new(Vec::new());

/// Buffers [`SPARE_ANSWERS`] keeps at most (a request of many receivers in flight allocates
/// the rest), and the largest it keeps, bytes: its memory stays bounded.
const SPARE_ANSWER_BUFFERS: usize = 16;
const SPARE_ANSWER_BYTES: usize = 1 << 20;

/// An empty answer buffer: a spare one, or a new one.
fn answer_buffer() -> Vec<u8> {
    let spare = SPARE_ANSWERS.lock().ok().and_then(|mut spare| spare.pop());
    spare.unwrap_or_default()
}

/// Give `bytes` (an answer put into its reply) back for a later answer, within the bounds.
fn give_back(mut bytes: Vec<u8>) {
    if bytes.capacity() > SPARE_ANSWER_BYTES {
        return;
    }
    bytes.clear();
    if let Ok(mut spare) = SPARE_ANSWERS.lock()
        && spare.len() < SPARE_ANSWER_BUFFERS
    {
        spare.push(bytes);
    }
}

/// One receiver's answer as JSON bytes, in a spare buffer ([`SPARE_ANSWERS`]) with room made
/// for a typical answer up front: the bytes serde_json writes for [`Answer`], its path records
/// written by hand ([`crate::json`]).
fn serialise(answer: &Answer<'_>) -> Outcome {
    let mut bytes = open_answer(answer.head, answer.tx, answer.rx, answer.paths.len())?;
    json::write_records(&mut bytes, answer.paths).map_err(io_error)?;
    close_answer(bytes, &answer.stats, answer.beams.as_ref())
}

/// An answer's JSON up to its path records: `{"tx":..,"rx":..,"paths":[` (opened by `head`
/// when given, [`Answer::head`]), in a spare buffer with room for `paths` records.
fn open_answer(head: Option<&[u8]>, tx: [f64; 3], rx: [f64; 3], paths: usize) -> Outcome {
    let mut bytes = answer_buffer();
    bytes.reserve(1024 + 1024 * paths);
    match head {
        Some(head) => {
            bytes.extend_from_slice(head);
            bytes.extend_from_slice(b",\"tx\":");
        }
        None => bytes.extend_from_slice(b"{\"tx\":"),
    }
    json::write_reals(&mut bytes, &tx).map_err(io_error)?;
    bytes.extend_from_slice(b",\"rx\":");
    json::write_reals(&mut bytes, &rx).map_err(io_error)?;
    bytes.extend_from_slice(b",\"paths\":[");
    Ok(bytes)
}

/// The rest of an answer opened by [`open_answer`] whose records `bytes` holds: the list's
/// end, `stats`, `beams` when there are some, and the closing brace.
fn close_answer(mut bytes: Vec<u8>, stats: &AnswerStats, beams: Option<&BeamsAnswer>) -> Outcome {
    bytes.extend_from_slice(b"],\"stats\":");
    serde_json::to_writer(&mut bytes, stats)?;
    if let Some(beams) = beams {
        bytes.extend_from_slice(b",\"beams\":");
        serde_json::to_writer(&mut bytes, beams)?;
    }
    bytes.push(b'}');
    Ok(bytes)
}

/// A JSON writer's I/O error (into memory: none in practice) as the serve error.
fn io_error(e: std::io::Error) -> ServeError {
    ServeError::Json(serde_json::Error::io(e))
}

/// `{"id":ID`, the opening of the reply to the request of id `id`, into `out`.
fn write_head(out: &mut Vec<u8>, id: &Value) -> Result<(), ServeError> {
    out.extend_from_slice(b"{\"id\":");
    serde_json::to_writer(&mut *out, id)?;
    Ok(())
}

/// [`write_head`] as its own bytes, for a lone receiver's answer to open ([`Answer::head`]).
fn reply_head(id: &Value) -> Result<Vec<u8>, ServeError> {
    let mut head = Vec::new();
    write_head(&mut head, id)?;
    Ok(head)
}

/// The reply `{"id", ...answer or "results", "latency_us"}` of a request for `rx` appended to
/// `out`, from each receiver's `outcomes` (aligned with `rx`'s positions): one receiver's
/// answer fields at the top level (its error is the request's), a list's as `results`, one
/// entry each (an error entry `{"rx", "error"}` for a receiver that failed alone). A lone
/// receiver's answer opened by its head already is the reply: it becomes `out` when `out` is
/// empty (no copy), and the buffer `out` had goes back to the pool.
/// `latency_us` is the time from the parsed request (`t0`) to the serialised answer, written
/// last. The bytes are those of serde's `{"id": .., #[serde(flatten)] answer}`.
pub(crate) fn write_reply(
    id: &Value,
    rx: &Receivers,
    outcomes: Vec<Outcome>,
    t0: Instant,
    out: &mut Vec<u8>,
) -> Result<(), ServeError> {
    let start = out.len();
    let mut outcomes = outcomes.into_iter();
    match rx {
        Receivers::One(_) => {
            let mut answer = outcomes
                .next()
                .unwrap_or_else(|| Err(ServeError::request("rx", "no answer for the receiver")))?;
            if answer.starts_with(b"{\"id\":") {
                // Opened by its head (`Answer::head`): the reply itself, without its closing
                // brace; taken as it is into an empty `out`.
                answer.pop();
                match out.is_empty() {
                    true => std::mem::swap(out, &mut answer),
                    false => out.extend_from_slice(&answer),
                }
            } else {
                write_head(out, id)?;
                // The answer's fields without its braces: `{"tx": ...}` → `"tx": ...`.
                if let Some(fields) = answer.get(1..answer.len().saturating_sub(1)) {
                    out.push(b',');
                    out.extend_from_slice(fields);
                }
            }
            give_back(answer);
        }
        Receivers::Many(positions) => {
            write_head(out, id)?;
            out.extend_from_slice(b",\"results\":[");
            for (k, (p, outcome)) in positions.iter().zip(outcomes).enumerate() {
                if k > 0 {
                    out.push(b',');
                }
                match outcome {
                    Ok(answer) => {
                        out.extend_from_slice(&answer);
                        give_back(answer);
                    }
                    Err(e) => {
                        let entry = EntryError {
                            rx: p.to_array(),
                            error: e.to_string(),
                        };
                        serde_json::to_writer(&mut *out, &entry)?;
                    }
                }
            }
            out.push(b']');
        }
    }
    debug_assert!(out[start..].starts_with(b"{\"id\":"));
    let latency_us = t0.elapsed().as_nanos() as f64 / 1e3;
    write!(out, ",\"latency_us\":{latency_us}}}").map_err(ServeError::Write)
}

/// A trace's error: the scene's problems with the receiver's field, or the trace's own.
fn trace_error(e: TraceError, rx_field: &str) -> ServeError {
    match e {
        TraceError::Scene(e) => scene_error(&e, rx_field),
        e => ServeError::Trace(e),
    }
}

/// A scene's refusal of a position or pose, one `field: problem` each, the receiver's
/// problems under `rx_field` (`rx[3]` in a list).
fn scene_error(e: &SceneError, rx_field: &str) -> ServeError {
    let SceneError::Invalid { problems, .. } = e else {
        return ServeError::Scene(e.to_string());
    };
    let shown: Vec<String> = (problems.iter().take(bt_scene::MAX_PRINTED_PROBLEMS))
        .map(|p| match p.location.as_str() {
            "rx" => format!("{rx_field}: {}", p.message),
            l if l.starts_with("object ") => format!("objects: {p}"),
            _ => p.to_string(),
        })
        .collect();
    ServeError::Scene(shown.join("; "))
}

#[cfg(test)]
mod tests {
    use super::*;
    use bt_beams::TraceDocument;
    use bt_solve::pipeline::DiffractionOptions;
    use bt_solve::settings::{SolveSettings, SolverKind};

    /// The answers of the living room's receivers under `settings` (with a beam sweep when
    /// `beams`), written by hand and by serde_json: the same bytes.
    fn same_bytes(settings: SolveSettings, beams: bool) -> usize {
        let options = bt_import::LoadOptions::default();
        let dynamic = bt_import::load_dynamic("builtin:living-room", &options, &mut |_| {})
            .unwrap()
            .scene;
        let scene = dynamic.step(0).clone();
        let options = settings.trace_options(&scene).unwrap();
        let radio = RadioOptions::default();
        let sweep = beams.then(|| {
            let arrays = [(Some((2, 4)), 0.5), (None, 0.5)];
            BeamOptions::new(arrays, &radio, BeamRanking::Power, (3, 1 << 20)).unwrap()
        });
        let reporter = Reporter {
            radio: &radio,
            beams: sweep.as_ref(),
            head: None,
            partner: None,
        };
        let tx = scene.tx_world().unwrap();
        let mut tracer = Tracer::new(scene, options);
        let mut records = 0;
        for rx in [
            [1.0, 1.0, 1.0],
            [2.3, 2.1, 0.72],
            [4.1, 3.3, 1.9],
            [0.5, 3.9, 2.3],
        ] {
            let rx = Vec3::from_array(rx);
            let scene = tracer.scene().with_terminals(tx, rx).unwrap();
            let traced = tracer.trace(tx, rx).unwrap();
            let doc = TraceDocument::report(&scene, &options, &traced, &radio, Duration::ZERO);
            let doc = doc.unwrap();
            let answer = Answer {
                head: None,
                tx: doc.tx,
                rx: doc.rx,
                beams: reporter.beams_of(&doc.paths, scene.frequency_hz()).unwrap(),
                paths: &doc.paths,
                stats: AnswerStats::Trace(doc.stats),
            };
            let mine = String::from_utf8(serialise(&answer).unwrap()).unwrap();
            assert_eq!(mine, serde_json::to_string(&answer).unwrap());
            records += answer.paths.len();
        }
        records
    }

    #[test]
    fn answers_are_written_as_serde_writes_them() {
        let base = SolveSettings::default();
        let variants = [
            (base, true),
            (
                SolveSettings {
                    max_order: 2,
                    diffraction: DiffractionOptions::first_order(),
                    ..base
                },
                false,
            ),
            (
                SolveSettings {
                    max_order: 2,
                    diffraction: DiffractionOptions {
                        max_diffractions: 2,
                        min_edge_length: 0.0,
                    },
                    ..base
                },
                false,
            ),
            (
                SolveSettings {
                    transmission: true,
                    ..base
                },
                false,
            ),
            (
                SolveSettings {
                    max_order: 2,
                    solver: SolverKind::Ipc,
                    ..base
                },
                false,
            ),
        ];
        for (settings, beams) in variants {
            let records = same_bytes(settings, beams);
            assert!(records > 10, "{settings:?}: only {records} records");
        }
    }
}
