//! `beamtrace serve`: the arguments become a `bt_serve::Server`, whose loop runs over
//! stdin/stdout or over each connection of a TCP or Unix socket, each on its own thread with
//! its own copy of the server (`docs/serve.md`).

use crate::args::{Listen, ServeArgs};
use crate::load::load_dynamic;
use anyhow::{Context, bail};
use bt_serve::{Limits, Server};
use std::io::{BufReader, BufWriter, ErrorKind};
use std::path::Path;
use std::process::ExitCode;
use std::time::Duration;

pub fn run(args: &ServeArgs) -> anyhow::Result<ExitCode> {
    let loaded = load_dynamic(&args.scene)?;
    let dynamic = loaded.scene;
    for w in dynamic.step(0).warnings() {
        eprintln!("warning: {w}");
    }
    let options = crate::trace::options_for(&args.solve, dynamic.step(0))?;
    let radio = args.radio.options()?;
    let limits = Limits {
        max_line_bytes: usize::try_from(args.max_line_bytes).context("--max-line-bytes")?,
        max_receivers: usize::try_from(args.max_receivers).context("--max-receivers")?,
    };
    let max_connections = usize::try_from(args.max_connections).context("--max-connections")?;
    stop::install();
    let spin = std::time::Duration::from_micros(args.partner_spin_us);
    let mut server = Server::new(dynamic, options, radio, limits).with_partner(spin);
    if args.arrays.tx_array.is_some() || args.arrays.rx_array.is_some() {
        let beams = crate::channel::beam_options(&args.arrays, &radio, args.top)?;
        server = server.with_beams(beams);
    }
    match &args.listen {
        None => {
            let input = std::io::stdin().lock();
            let output = BufWriter::new(std::io::stdout().lock());
            server.serve_until(input, output, &stop::requested)?;
        }
        Some(Listen::Tcp(address)) => serve_tcp(&server, address, max_connections)?,
        Some(Listen::Unix(path)) => serve_unix(&server, path, max_connections)?,
    }
    Ok(ExitCode::SUCCESS)
}

/// Serve the connections to `address`, each on its own thread, until the process is stopped.
fn serve_tcp(server: &Server, address: &str, max: usize) -> anyhow::Result<()> {
    let listener = std::net::TcpListener::bind(address)
        .with_context(|| format!("--listen tcp:{address}: cannot listen"))?;
    let bound = listener
        .local_addr()
        .context("--listen: the bound address")?;
    eprintln!("listening on tcp:{bound}");
    listener
        .set_nonblocking(true)
        .context("--listen: a non-blocking socket")?;
    serve_connections(server, || listener.accept().map(|(s, _)| s), max)
}

/// Serve the connections to the Unix socket `path`, each on its own thread, until the process
/// is stopped. A path that exists is refused unless it is a socket nobody listens on (one left
/// by a server that was stopped): a user's file is never replaced.
#[cfg(unix)]
fn serve_unix(server: &Server, path: &Path, max: usize) -> anyhow::Result<()> {
    use std::os::unix::fs::FileTypeExt;
    use std::os::unix::net::{UnixListener, UnixStream};
    let shown = path.display();
    if let Ok(meta) = std::fs::symlink_metadata(path) {
        if !meta.file_type().is_socket() {
            bail!("--listen unix:{shown}: the path exists and is not a socket; not replacing it");
        }
        if UnixStream::connect(path).is_ok() {
            bail!("--listen unix:{shown}: another server is listening on this socket");
        }
        std::fs::remove_file(path)
            .with_context(|| format!("--listen unix:{shown}: removing the stale socket"))?;
    }
    let listener = UnixListener::bind(path)
        .with_context(|| format!("--listen unix:{shown}: cannot listen"))?;
    eprintln!("listening on unix:{shown}");
    let served = listener
        .set_nonblocking(true)
        .context("--listen: a non-blocking socket")
        .and_then(|()| serve_connections(server, || listener.accept().map(|(s, _)| s), max));
    // Stopped (or failed): the socket this server made goes with it.
    std::fs::remove_file(path).ok();
    served
}

#[cfg(not(unix))]
fn serve_unix(_: &Server, path: &Path, _: usize) -> anyhow::Result<()> {
    bail!(
        "--listen unix:{}: Unix sockets need a Unix system",
        path.display()
    )
}

/// How often a listener without a waiting client looks again (and whether it was stopped).
const POLL: Duration = Duration::from_millis(20);

/// A connected socket, TCP or Unix.
trait Connection: Send + Sized + 'static {
    /// Another handle of the same socket.
    fn handle(&self) -> std::io::Result<Self>;
    /// Blocking reads and writes (the listener's sockets are non-blocking).
    fn blocking(&self) -> std::io::Result<()>;
    /// End the reading side: a read waiting for a request returns the end of input.
    fn end_reading(&self);
}

/// [`Connection`] for a standard socket type: both have the same methods under these names.
macro_rules! connection {
    ($stream:ty) => {
        impl Connection for $stream {
            fn handle(&self) -> std::io::Result<Self> {
                self.try_clone()
            }
            fn blocking(&self) -> std::io::Result<()> {
                self.set_nonblocking(false)
            }
            fn end_reading(&self) {
                self.shutdown(std::net::Shutdown::Read).ok();
            }
        }
    };
}
connection!(std::net::TcpStream);
#[cfg(unix)]
connection!(std::os::unix::net::UnixStream);

/// Serve every client `accept` (non-blocking) gives, each on its own thread with its own copy
/// of `server` (its own session and tracer; answers in its own request order), at most `max`
/// at a time, until the process is stopped: then every connection's reading side is ended,
/// so each writes the answer in hand and ends, and all are waited for.
fn serve_connections<S: Connection>(
    server: &Server,
    mut accept: impl FnMut() -> std::io::Result<S>,
    max: usize,
) -> anyhow::Result<()>
where
    for<'a> &'a S: std::io::Read + std::io::Write,
{
    let mut live: Vec<(std::thread::JoinHandle<()>, S)> = Vec::new();
    let mut accepted = 0usize;
    while !stop::requested() {
        live.retain(|(thread, _)| !thread.is_finished());
        if live.len() >= max {
            std::thread::sleep(POLL);
            continue;
        }
        let stream = match accept() {
            Ok(stream) => stream,
            Err(e) if e.kind() == ErrorKind::WouldBlock || e.kind() == ErrorKind::Interrupted => {
                std::thread::sleep(POLL);
                continue;
            }
            Err(e) => return Err(e).context("--listen: accepting a connection"),
        };
        accepted += 1;
        let n = accepted;
        let handle = stream
            .blocking()
            .and_then(|()| stream.handle())
            .context("--listen: setting up a connection")?;
        let mut server = server.clone();
        let thread = std::thread::spawn(move || {
            let outcome = server.serve_until(
                BufReader::new(&stream),
                BufWriter::new(&stream),
                &stop::requested,
            );
            if let Err(e) = outcome {
                eprintln!("warning: connection {n}: {e}");
            }
        });
        live.push((thread, handle));
    }
    for (_, stream) in &live {
        stream.end_reading();
    }
    for (thread, _) in live {
        thread.join().ok();
    }
    Ok(())
}

/// SIGTERM and SIGINT stop the server cleanly: the answer in hand is written and flushed, a
/// read waiting for a request ends (the handler leaves reads interruptible; with `--listen`
/// the listener sees the stop within [`POLL`] and ends every connection's reading side).
#[cfg(unix)]
mod stop {
    use std::sync::atomic::{AtomicBool, AtomicU64, Ordering};

    static STOP: AtomicBool = AtomicBool::new(false);
    /// The thread that installed the handler (the one reading stdin), as a `pthread_t`.
    static READER: AtomicU64 = AtomicU64::new(0);

    /// The kernel hands a process's signal to any thread that does not block it, e.g. an idle
    /// worker of the tracing pool, whose wait just resumes: the reader's blocked `read` would
    /// never return. So a handler running elsewhere passes the signal on to the reader
    /// (`pthread_self` and `pthread_kill` are async-signal-safe).
    extern "C" fn on_signal(signal: libc::c_int) {
        STOP.store(true, Ordering::SeqCst);
        // SAFETY: `pthread_self` has no preconditions; READER holds a live thread's id (the
        // reader outlives the signal handling: it is the thread that returns from `serve`).
        unsafe {
            let reader = READER.load(Ordering::SeqCst) as libc::pthread_t;
            if libc::pthread_self() != reader {
                libc::pthread_kill(reader, signal);
            }
        }
    }

    /// Handle SIGTERM and SIGINT (without `SA_RESTART`, so a blocked read returns), on behalf
    /// of the calling thread: the one that then reads the requests.
    pub fn install() {
        // SAFETY: `pthread_self` has no preconditions; a zeroed sigaction with an extern "C"
        // handler and an empty mask is valid.
        unsafe {
            READER.store(libc::pthread_self() as u64, Ordering::SeqCst);
            let mut action: libc::sigaction = std::mem::zeroed();
            action.sa_sigaction = on_signal as extern "C" fn(libc::c_int) as usize;
            libc::sigemptyset(&mut action.sa_mask);
            for signal in [libc::SIGTERM, libc::SIGINT] {
                libc::sigaction(signal, &action, std::ptr::null_mut());
            }
        }
    }

    /// Whether a signal asked the server to stop.
    pub fn requested() -> bool {
        STOP.load(Ordering::SeqCst)
    }
}

#[cfg(not(unix))]
mod stop {
    pub fn install() {}
    pub fn requested() -> bool {
        false
    }
}
