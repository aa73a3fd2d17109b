//! `beamtrace serve`: the arguments become a `bt_serve::Server`, whose loop runs over
//! stdin/stdout or over each connection of a TCP or Unix socket in turn (`docs/serve.md`).

use crate::args::{Listen, ServeArgs};
use crate::load::load_dynamic;
use anyhow::{Context, bail};
use bt_serve::{Limits, Server};
use std::io::{BufReader, BufWriter};
use std::path::Path;
use std::process::ExitCode;

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
    let mut server = Server::new(dynamic, options, radio, limits);
    if args.arrays.tx_array.is_some() || args.arrays.rx_array.is_some() {
        let beams = crate::channel::beam_options(&args.arrays, &radio, args.top)?;
        server = server.with_beams(beams);
    }
    match &args.listen {
        None => {
            let input = std::io::stdin().lock();
            let output = BufWriter::new(std::io::stdout().lock());
            server.serve(input, output)?;
        }
        Some(Listen::Tcp(address)) => serve_tcp(&mut server, address)?,
        Some(Listen::Unix(path)) => serve_unix(&mut server, path)?,
    }
    Ok(ExitCode::SUCCESS)
}

/// Serve each connection to `address` in turn, until the process is stopped.
fn serve_tcp(server: &mut Server, address: &str) -> anyhow::Result<()> {
    let listener = std::net::TcpListener::bind(address)
        .with_context(|| format!("--listen tcp:{address}: cannot listen"))?;
    let bound = listener
        .local_addr()
        .context("--listen: the bound address")?;
    eprintln!("listening on tcp:{bound}");
    for (n, stream) in listener.incoming().enumerate() {
        let stream = stream.context("--listen: accepting a connection")?;
        let outcome = server.serve(BufReader::new(&stream), BufWriter::new(&stream));
        end_connection(server, n, outcome);
    }
    Ok(())
}

/// Serve each connection to the Unix socket `path` in turn, until the process is stopped.
/// A path that exists is refused unless it is a socket nobody listens on (one left by a
/// server that was stopped): a user's file is never replaced.
#[cfg(unix)]
fn serve_unix(server: &mut Server, path: &Path) -> anyhow::Result<()> {
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
    for (n, stream) in listener.incoming().enumerate() {
        let stream = stream.context("--listen: accepting a connection")?;
        let outcome = server.serve(BufReader::new(&stream), BufWriter::new(&stream));
        end_connection(server, n, outcome);
    }
    Ok(())
}

#[cfg(not(unix))]
fn serve_unix(_: &mut Server, path: &Path) -> anyhow::Result<()> {
    bail!(
        "--listen unix:{}: Unix sockets need a Unix system",
        path.display()
    )
}

/// A connection's end: its transport error, if any, on stderr (the server goes on with the
/// next connection); the next client starts a new session.
fn end_connection(
    server: &mut Server,
    n: usize,
    outcome: Result<bt_serve::Summary, bt_serve::ServeError>,
) {
    if let Err(e) = outcome {
        eprintln!("warning: connection {}: {e}", n + 1);
    }
    server.end_session();
}
