//! Every numeric option of every command, fed `nan`, `inf`, `-1` and `1e300`: refused with an
//! error naming the flag (exit 1 or 2, never a panic), or — for the few listed with a reason —
//! accepted with no NaN or infinity in the output. The commands and their options come from
//! the binary's own `--help`, so a new command or flag is covered without editing this file;
//! only a new command with numeric flags needs its cheap base line below.

use super::*;
use crate::common::stdout;
use std::collections::BTreeMap;

/// The hostile values, each passed as `--flag=VALUE` (so `-1` is never taken for a flag).
const VALUES: [&str; 4] = ["nan", "inf", "-1", "1e300"];

/// A cheap valid command line per command with numeric options (relative paths resolve in
/// a scratch folder; `cloud.ply` is sampled there first).
const BASES: &[(&str, &str)] = &[
    ("trace", "trace builtin:living-room --max-order 1"),
    ("demo", "demo --max-order 1"),
    ("serve", "serve builtin:living-room --max-order 1"),
    ("scene check", "scene check builtin:living-room"),
    ("wvrn", "wvrn builtin:living-room --max-order 1"),
    (
        "sweep",
        "sweep builtin:living-room --max-order 1 --grid 1:2:1,1:2:1,1.2 --out sweep",
    ),
    (
        "view",
        "view builtin:living-room --max-order 1 -o view.html",
    ),
    (
        "channel",
        "channel builtin:living-room --max-order 1 --out cir.csv --cfr cfr.csv --subcarriers 4",
    ),
    (
        "beams",
        "beams builtin:living-room --max-order 1 --tx-array 1x2 --rx-array 1x2",
    ),
    (
        "sample",
        "sample builtin:living-room -o sampled.ply --density 1",
    ),
    ("extract", "extract cloud.ply -o extracted.json"),
    (
        "hls gen",
        "hls gen builtin:living-room -o hls --max-order 1 --plan-only",
    ),
    (
        "study 2d",
        "study 2d --rooms 1 --steps 1 --max-order 1 --out s2d",
    ),
    (
        "study living-room",
        "study living-room --max-order 1 --out slr",
    ),
    (
        "study beam-management",
        "study beam-management --scenario living-room --positions 2 --scan-density 0 --position-sigmas 0 --latencies-ms 0 --top-k 1 --out sbm",
    ),
];

/// Options whose value is no single number (paths, names, vectors, grids, shapes), so the
/// four values test nothing about numbers there. Enumerations (`[possible values: ...]`) are
/// recognised from the help.
const NOT_NUMBERS: &[&str] = &[
    // files and folders
    "out",
    "output",
    "cfr",
    "pdp",
    "report",
    "paths",
    "steps-from",
    // a scenario name or scene file
    "scenario",
    // a transport, tcp:HOST:PORT or unix:PATH
    "listen",
    // X,Y,Z vectors (each coordinate checked finite by `parse_vec3`, tested in small.rs)
    "tx",
    "rx",
    "tx-orientation",
    "rx-orientation",
    // a grid x0:x1:dx,y0:y1:dy,z; a material itu:NAME or custom:EPS,SIGMA; ROWSxCOLUMNS
    "grid",
    "material",
    "tx-array",
    "rx-array",
    // names (parsed by the library's `FromStr`)
    "tx-pattern",
    "rx-pattern",
    "tx-polarization",
    "rx-polarization",
];

/// `(flag, value, reason)`: values a flag accepts on purpose.
const ACCEPTED: &[(&str, &str, &str)] = &[
    (
        "tx-power-dbm",
        "-1",
        "a power below 1 mW (any power in ±300 dBm)",
    ),
    (
        "min-reflector-area",
        "1e300",
        "no upper bound: every surface then only blocks",
    ),
];

#[test]
fn every_numeric_flag_refuses_nan_inf_negative_and_huge_values_naming_itself() {
    let dir = scratch("numbers");
    let cloud = beamtrace_in(
        &dir,
        &cli("sample builtin:living-room -o cloud.ply --density 20", &[]),
    );
    assert_ok(&cloud);
    let bases: BTreeMap<&str, &str> = BASES.iter().copied().collect();
    let mut cases = 0;
    for command in commands(&[]) {
        let flags = numeric_flags(&command);
        if flags.is_empty() {
            continue;
        }
        let name = command.join(" ");
        let base = bases
            .get(name.as_str())
            .unwrap_or_else(|| panic!("`{name}` has numeric flags {flags:?}: add a base line"));
        for flag in &flags {
            for value in VALUES {
                check_case(&dir, base, flag, value);
                cases += 1;
            }
        }
    }
    assert!(cases > 100, "only {cases} cases: is the help parsed?");
}

/// Runs `base` with `--flag=value` (replacing the flag's own value in `base`, if any).
fn check_case(dir: &Path, base: &str, flag: &str, value: &str) {
    let long = format!("--{flag}");
    let mut args: Vec<String> = Vec::new();
    let mut words = base.split_whitespace();
    while let Some(w) = words.next() {
        if w == long {
            words.next();
        } else {
            args.push(w.to_string());
        }
    }
    args.push(format!("{long}={value}"));
    let args: Vec<&str> = args.iter().map(String::as_str).collect();
    let o = beamtrace_in(dir, &args);
    let t = text(&o);
    let what = format!("{args:?}: exit {:?}\n{t}", o.status.code());
    assert!(
        o.status.code() != Some(101) && !t.contains("panicked"),
        "{what}"
    );
    let accepted = ACCEPTED.iter().any(|(f, v, _)| *f == flag && *v == value);
    if accepted {
        if o.status.success() {
            assert!(!has_non_finite(&stdout(&o)), "non-finite output: {what}");
        } else {
            assert!(matches!(o.status.code(), Some(1 | 2)), "{what}");
        }
    } else {
        assert!(matches!(o.status.code(), Some(1 | 2)), "accepted: {what}");
        assert!(t.contains(&long), "the error does not name {long}: {what}");
    }
}

/// Any word of `text` that is a NaN or an infinity as Rust, JSON or CSV would print it.
fn has_non_finite(text: &str) -> bool {
    text.split(|c: char| !(c.is_alphanumeric() || c == '_'))
        .any(|w| matches!(w.to_ascii_lowercase().as_str(), "nan" | "inf" | "infinity"))
}

/// Every leaf command (`["trace"]`, `["study", "2d"]`, ...) under `prefix`, from the help.
fn commands(prefix: &[String]) -> Vec<Vec<String>> {
    let help = help_of(prefix);
    let names: Vec<String> = section(&help, "Commands:")
        .filter_map(|l| l.split_whitespace().next())
        .filter(|n| *n != "help")
        .map(str::to_string)
        .collect();
    if names.is_empty() {
        return vec![prefix.to_vec()];
    }
    names
        .into_iter()
        .flat_map(|n| commands(&[prefix.to_vec(), vec![n]].concat()))
        .collect()
}

/// The long names of the options of `command` that take a value and are numbers: neither
/// listed in [`NOT_NUMBERS`] nor an enumeration.
fn numeric_flags(command: &[String]) -> Vec<String> {
    let help = help_of(command);
    let mut flags = Vec::new();
    let lines: Vec<&str> = section(&help, "Options:").collect();
    for (i, line) in lines.iter().enumerate() {
        let Some(long) = option_taking_value(line) else {
            continue;
        };
        let block = lines[i + 1..]
            .iter()
            .take_while(|l| option_taking_value(l).is_none() && !is_flag_line(l));
        let is_enum = block
            .clone()
            .any(|l| l.to_ascii_lowercase().contains("possible values:"));
        if !is_enum && !NOT_NUMBERS.contains(&long.as_str()) {
            flags.push(long);
        }
    }
    flags
}

fn is_flag_line(line: &str) -> bool {
    let t = line.trim_start();
    line.starts_with("  ") && t.starts_with('-')
}

/// `--name` of a help line `  -o, --name <VALUE>` or `      --name <VALUE>`.
fn option_taking_value(line: &str) -> Option<String> {
    if !is_flag_line(line) {
        return None;
    }
    let (_, rest) = line.split_once("--")?;
    let (name, after) = rest.split_once(' ')?;
    after.starts_with('<').then(|| name.to_string())
}

/// The lines after `title` up to the next section title.
fn section<'a>(help: &'a str, title: &'a str) -> impl Iterator<Item = &'a str> + Clone {
    help.lines()
        .skip_while(move |l| *l != title)
        .skip(1)
        .take_while(|l| l.is_empty() || l.starts_with(' '))
}

fn help_of(command: &[String]) -> String {
    let mut args: Vec<&str> = command.iter().map(String::as_str).collect();
    args.push("--help");
    let o = beamtrace(&args);
    assert_ok(&o);
    stdout(&o)
}
