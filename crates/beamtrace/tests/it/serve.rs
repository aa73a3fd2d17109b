//! `beamtrace serve`: requests piped through stdin, a TCP and a Unix socket round trip, and
//! the refusal of a Unix socket path that is a user's file.

use crate::common::{cli, run_json, scratch};
use serde_json::{Value, json};
use std::io::{BufRead, BufReader, Read, Write};
use std::process::{Child, Command, Stdio};

/// Starts `beamtrace ARGS` with piped stdin, stdout and stderr.
fn spawn(args: &[&str]) -> Child {
    Command::new(env!("CARGO_BIN_EXE_beamtrace"))
        .args(args)
        .stdin(Stdio::piped())
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .expect("binary starts")
}

/// Each line of `text` as JSON.
fn answers(text: &str) -> Vec<Value> {
    text.lines()
        .map(|l| serde_json::from_str(l).unwrap_or_else(|e| panic!("{e}: {l}")))
        .collect()
}

#[test]
fn requests_piped_through_serve_get_the_paths_of_trace_json_in_order() {
    let receivers = [[1.0, 1.0, 1.0], [2.3, 2.1, 0.72], [4.5, 3.2, 1.4]];
    let mut lines: Vec<String> = receivers
        .iter()
        .enumerate()
        .map(|(i, rx)| json!({"id": i, "rx": rx}).to_string())
        .collect();
    lines.insert(1, "{\"id\": \"bad\", \"rx\": [1, 2]}".into());
    lines.insert(2, "this is not JSON".into());
    let mut child = spawn(&["serve", "builtin:living-room"]);
    let mut stdin = child.stdin.take().unwrap();
    stdin
        .write_all((lines.join("\n") + "\n").as_bytes())
        .unwrap();
    drop(stdin); // end of input: serve ends cleanly
    let out = child.wait_with_output().unwrap();
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let got = answers(&String::from_utf8(out.stdout).unwrap());
    let ids: Vec<&Value> = got.iter().map(|a| &a["id"]).collect();
    assert_eq!(
        ids,
        [&json!(0), &json!("bad"), &Value::Null, &json!(1), &json!(2)]
    );
    assert!(
        got[1]["error"]
            .as_str()
            .unwrap()
            .starts_with("rx: expected [x, y, z]")
    );
    assert!(
        got[2]["error"]
            .as_str()
            .unwrap()
            .starts_with("request: not valid JSON")
    );
    let traced = [&got[0], &got[3], &got[4]];
    for (answer, rx) in traced.into_iter().zip(receivers) {
        let at = format!("{},{},{}", rx[0], rx[1], rx[2]);
        let one_shot = run_json(&cli("trace builtin:living-room --rx {} --json", &[&at]));
        assert_eq!(answer["paths"], one_shot["paths"], "rx {at}");
        assert_eq!(answer["rx"], one_shot["rx"]);
        assert!(answer["paths"].as_array().unwrap().len() > 10, "rx {at}");
        assert!(answer["latency_us"].as_f64().is_some_and(|t| t > 0.0));
    }
}

/// Reads the child's first stderr line, `listening on KIND:ADDRESS`, and returns the address.
fn listening(child: &mut Child, kind: &str) -> String {
    let mut line = String::new();
    BufReader::new(child.stderr.as_mut().unwrap())
        .read_line(&mut line)
        .unwrap();
    let prefix = format!("listening on {kind}:");
    line.trim_end()
        .strip_prefix(&prefix)
        .unwrap_or_else(|| panic!("not listening: {line}"))
        .to_string()
}

/// Starts `serve builtin:living-room --max-order 1 --listen LISTEN` (`tcp:...` or
/// `unix:...`) and returns it with the address it listens on.
fn start(listen: &str) -> (Child, String) {
    let kind = listen.split(':').next().unwrap_or_default();
    let args = [
        "serve",
        "builtin:living-room",
        "--max-order",
        "1",
        "--listen",
        listen,
    ];
    let mut child = spawn(&args);
    let address = listening(&mut child, kind);
    (child, address)
}

/// Sends `requests` on a connection and reads every answer until the server closes it.
fn round_trip<S: Read + Write>(
    mut stream: S,
    requests: &str,
    close: impl FnOnce(&S),
) -> Vec<Value> {
    stream.write_all(requests.as_bytes()).unwrap();
    close(&stream);
    let mut text = String::new();
    stream.read_to_string(&mut text).unwrap();
    answers(&text)
}

#[test]
fn a_tcp_client_gets_its_answers_and_the_next_client_a_new_session() {
    let (mut child, address) = start("tcp:127.0.0.1:0");
    let shut = |s: &std::net::TcpStream| s.shutdown(std::net::Shutdown::Write).unwrap();
    let first = "{\"id\": 1, \"tx\": [3, 3, 2], \"rx\": [1, 1, 1]}\n{\"id\": 2}\n";
    let a = round_trip(std::net::TcpStream::connect(&address).unwrap(), first, shut);
    let b = round_trip(
        std::net::TcpStream::connect(&address).unwrap(),
        "{\"id\": 3}\n",
        shut,
    );
    child.kill().unwrap();
    child.wait().unwrap();
    assert_eq!(a.len(), 2);
    assert_eq!(
        a[1]["tx"],
        json!([3.0, 3.0, 2.0]),
        "the session keeps its TX"
    );
    assert_eq!(a[0]["paths"], a[1]["paths"]);
    assert_eq!(b[0]["id"], 3);
    assert_eq!(
        b[0]["tx"],
        json!([5.6, 0.6, 2.2]),
        "a new connection starts with the scene's"
    );
    assert_eq!(b[0]["rx"], json!([2.3, 2.1, 0.72]));
}

/// Connections are served at the same time, each its own stream and session: a client that
/// keeps its connection open does not hold back the next one.
#[test]
fn connections_are_served_at_the_same_time_each_its_own_session() {
    let (mut child, address) = start("tcp:127.0.0.1:0");
    let mut open = std::net::TcpStream::connect(&address).unwrap();
    open.write_all(b"{\"id\": \"a\", \"tx\": [3, 3, 2], \"rx\": [1, 1, 1]}\n")
        .unwrap();
    let mut reader = BufReader::new(open.try_clone().unwrap());
    let mut line = String::new();
    reader.read_line(&mut line).unwrap();
    assert_eq!(answers(&line)[0]["tx"], json!([3.0, 3.0, 2.0]));
    // The first connection stays open and idle: the second is answered all the same.
    let shut = |s: &std::net::TcpStream| s.shutdown(std::net::Shutdown::Write).unwrap();
    let other = std::net::TcpStream::connect(&address).unwrap();
    let b = round_trip(other, "{\"id\": \"b\", \"rx\": [1, 1, 1]}\n", shut);
    assert_eq!(b.len(), 1);
    assert_eq!(b[0]["tx"], json!([5.6, 0.6, 2.2]), "its own session");
    // And the first goes on with its own TX.
    open.write_all(b"{\"id\": \"c\"}\n").unwrap();
    line.clear();
    reader.read_line(&mut line).unwrap();
    let c = answers(&line);
    assert_eq!(
        (&c[0]["id"], &c[0]["tx"]),
        (&json!("c"), &json!([3.0, 3.0, 2.0]))
    );
    child.kill().unwrap();
    child.wait().unwrap();
}

#[cfg(unix)]
#[test]
fn a_unix_socket_round_trip_and_a_users_file_is_never_replaced() {
    use std::os::unix::net::UnixStream;
    let dir = scratch("serve-unix");
    let file = dir.join("notes.txt");
    std::fs::write(&file, "mine").unwrap();
    let taken = format!("unix:{}", file.display());
    let out = Command::new(env!("CARGO_BIN_EXE_beamtrace"))
        .args(["serve", "builtin:living-room", "--listen", &taken])
        .output()
        .unwrap();
    let err = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(2), "{err}");
    assert!(err.contains("the path exists and is not a socket"), "{err}");
    assert_eq!(std::fs::read_to_string(&file).unwrap(), "mine");

    let socket = dir.join("serve.sock");
    let listen = format!("unix:{}", socket.display());
    let (mut child, address) = start(&listen);
    assert_eq!(address, socket.display().to_string());
    let shut = |s: &UnixStream| s.shutdown(std::net::Shutdown::Write).unwrap();
    let requests = "{\"id\": \"u\", \"rx\": [[1, 1, 1], [2, 2, 1]]}\n";
    let got = round_trip(UnixStream::connect(&socket).unwrap(), requests, shut);
    // A second server on the live socket is refused; the first is still serving.
    let again = Command::new(env!("CARGO_BIN_EXE_beamtrace"))
        .args(["serve", "builtin:living-room", "--listen", &listen])
        .output()
        .unwrap();
    child.kill().unwrap();
    child.wait().unwrap();
    // The killed server left its socket: the next one replaces it (a socket, no one's data).
    let (mut next, relisten) = start(&listen);
    let later = round_trip(UnixStream::connect(&socket).unwrap(), "{\"id\": 2}\n", shut);
    next.kill().unwrap();
    next.wait().unwrap();
    assert_eq!(relisten, socket.display().to_string());
    assert_eq!(later[0]["id"], 2);
    assert_eq!(got[0]["id"], "u");
    assert_eq!(got[0]["results"].as_array().map(Vec::len), Some(2));
    let err = String::from_utf8_lossy(&again.stderr);
    assert!(err.contains("another server is listening"), "{err}");
}

/// With --tx-array/--rx-array each answer holds the beam sweep of `beams` for its receiver:
/// the best pair and the first --top pairs equal `beams --json`'s ranked list; without arrays
/// no "beams"; an over-budget sweep is refused before the stream starts.
#[test]
fn arrays_give_each_answer_the_beam_sweep_of_beams() {
    let receivers = [[2.3, 2.1, 0.72], [1.0, 1.0, 1.2]];
    let lines: Vec<String> = (receivers.iter().enumerate())
        .map(|(i, rx)| json!({"id": i, "rx": rx}).to_string())
        .collect();
    let arrays = [
        "--tx-array",
        "2x4",
        "--rx-array",
        "1x4",
        "--ranking",
        "paper",
    ];
    let mut child = spawn(&[&["serve", "builtin:living-room", "--top", "3"][..], &arrays].concat());
    let mut stdin = child.stdin.take().unwrap();
    stdin
        .write_all((lines.join("\n") + "\n").as_bytes())
        .unwrap();
    drop(stdin);
    let out = child.wait_with_output().unwrap();
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    for (answer, rx) in answers(&String::from_utf8(out.stdout).unwrap())
        .iter()
        .zip(receivers)
    {
        let at = format!("{},{},{}", rx[0], rx[1], rx[2]);
        let sweep = run_json(
            &[
                &["beams", "builtin:living-room", "--rx", &at, "--json"][..],
                &arrays,
            ]
            .concat(),
        );
        let beams = &answer["beams"];
        let pairs = sweep["pairs"].as_array().unwrap();
        assert_eq!(beams["top"].as_array().unwrap()[..], pairs[..3], "rx {at}");
        assert_eq!(beams["best"], pairs[0]);
        assert_eq!(
            (&beams["tx_beams"], &beams["rx_beams"]),
            (&json!(8), &json!(4))
        );
        assert_eq!(beams["ranking"], "paper");
    }
    let mut plain = spawn(&["serve", "builtin:living-room"]);
    plain
        .stdin
        .take()
        .unwrap()
        .write_all(b"{\"rx\": [1, 1, 1.2]}\n")
        .unwrap();
    let plain = answers(&String::from_utf8(plain.wait_with_output().unwrap().stdout).unwrap());
    assert!(plain[0].get("beams").is_none(), "{}", plain[0]);
    crate::common::assert_clear_error(
        &[
            "serve",
            "builtin:living-room",
            "--tx-array",
            "8x8",
            "--rx-array",
            "8x8",
            "--max-beam-pairs",
            "100",
        ],
        &["beam pairs", "100"],
    );
}

/// SIGTERM to `child`.
fn terminate(child: &Child) {
    let pid = libc::pid_t::try_from(child.id()).unwrap();
    // SAFETY: kill with a child's pid and a standard signal.
    assert_eq!(unsafe { libc::kill(pid, libc::SIGTERM) }, 0);
}

/// SIGTERM ends serve cleanly: while it waits for the next request on stdin (its answers so
/// far written whole), between connections on a Unix socket (the socket it made removed),
/// and in the middle of a connection.
#[test]
fn sigterm_closes_cleanly() {
    let mut child = spawn(&["serve", "builtin:living-room", "--max-order", "1"]);
    let mut stdin = child.stdin.take().unwrap();
    stdin
        .write_all(b"{\"id\": 7, \"rx\": [1, 1, 1]}\n")
        .unwrap();
    let mut out = BufReader::new(child.stdout.take().unwrap());
    let mut first = String::new();
    out.read_line(&mut first).unwrap();
    assert_eq!(answers(&first)[0]["id"], 7);
    terminate(&child); // stdin still open: serve waits for a request
    let status = child.wait().unwrap();
    assert!(status.success(), "{status:?}");
    let mut rest = String::new();
    out.read_to_string(&mut rest).unwrap();
    assert_eq!(rest, "", "nothing after the whole answers");
    drop(stdin);

    let dir = scratch("serve-sigterm");
    let socket = dir.join("s.sock");
    let (mut child, _) = start(&format!("unix:{}", socket.display()));
    assert!(socket.exists());
    terminate(&child);
    assert!(child.wait().unwrap().success());
    assert!(!socket.exists(), "the server's own socket is removed");

    let (mut child, _) = start(&format!("unix:{}", socket.display()));
    let mut stream = std::os::unix::net::UnixStream::connect(&socket).unwrap();
    stream
        .write_all(b"{\"id\": 1, \"rx\": [1, 1, 1]}\n")
        .unwrap();
    let mut line = String::new();
    BufReader::new(&stream).read_line(&mut line).unwrap();
    assert_eq!(answers(&line)[0]["id"], 1);
    terminate(&child); // the connection stays open: serve waits on it
    assert!(child.wait().unwrap().success());
    assert!(!socket.exists());
    std::fs::remove_dir_all(dir).ok();
}
