//! `beamtrace wvrn SCENE [--json | --dot] [-o FILE] [--step K]`: the weak visibility
//! relationship network as a table, JSON or Graphviz DOT, with the candidate reduction it gives.

use crate::args::WvrnArgs;
use crate::load::load_dynamic;
use anyhow::{Context, bail};
use bt_paths::wvrn::{Link, Wvrn, WvrnStats};
use bt_paths::{AllVisible, Node, enumerate};
use bt_scene::Scene;
use bt_scene::dynamic::{DynamicScene, moved_surfaces};
use serde::Serialize;
use std::collections::BTreeSet;
use std::fmt::Write as _;
use std::process::ExitCode;
use std::time::Instant;

#[derive(Debug, Serialize)]
pub struct WvrnDocument {
    pub scene: String,
    pub step: usize,
    pub steps: usize,
    pub nodes: Vec<NodeEntry>,
    /// Linked pairs as node indices `[a, b]`, `a < b`.
    pub edges: Vec<[usize; 2]>,
    /// Pairs that are not linked, with the proof.
    pub pruned: Vec<PrunedEntry>,
    pub stats: WvrnStats,
    pub candidates: Reduction,
    /// Wall-clock seconds to build the network (varies between runs).
    pub build_time_s: f64,
}

#[derive(Debug, Serialize)]
pub struct NodeEntry {
    pub index: usize,
    pub name: String,
    /// `tx`, `rx` or `surface`.
    pub kind: &'static str,
    /// Whether the node moves at some step (dynamic scenes).
    pub moving: bool,
}

#[derive(Debug, Serialize)]
pub struct PrunedEntry {
    pub a: usize,
    pub b: usize,
    /// `coplanar` or `occluded`.
    pub reason: &'static str,
    /// The occluding surface, for `occluded`.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub by: Option<String>,
}

#[derive(Debug, Serialize)]
pub struct Reduction {
    pub max_order: usize,
    /// Candidates of the exhaustive enumeration.
    pub exhaustive: usize,
    /// Candidates routed over the WVRN.
    pub wvrn: usize,
    /// `wvrn / exhaustive`.
    pub ratio: f64,
}

fn node_name(scene: &Scene, node: Node) -> String {
    match node {
        Node::Tx => "TX".into(),
        Node::Rx => "RX".into(),
        Node::Surface(id) => scene.surface(id).name.clone(),
    }
}

/// Pairs of node indices whose link state changes at some step, and nodes that move.
type DynamicParts = (BTreeSet<(usize, usize)>, Vec<bool>);

/// [`DynamicParts`] of every step; fails on a step without both terminals.
fn dynamic_parts(dynamic: &DynamicScene, nodes: &[Node]) -> anyhow::Result<DynamicParts> {
    let mut moving = vec![false; nodes.len()];
    let mut changing = BTreeSet::new();
    if dynamic.len() < 2 {
        return Ok((changing, moving));
    }
    let index = |n: Node| nodes.iter().position(|m| *m == n);
    let mut w = Wvrn::build(dynamic.step(0))?;
    for k in 1..dynamic.len() {
        let (prev, next) = (dynamic.step(k - 1), dynamic.step(k));
        let moved = moved_surfaces(prev, next).unwrap_or_default();
        for id in &moved {
            if let Some(i) = index(Node::Surface(*id)) {
                moving[i] = true;
            }
        }
        moving[0] |= prev.tx() != next.tx();
        moving[1] |= prev.rx() != next.rx();
        for (a, b, _) in w.update(next, &moved)?.changed {
            if let (Some(i), Some(j)) = (index(a), index(b)) {
                changing.insert((i.min(j), i.max(j)));
            }
        }
    }
    Ok((changing, moving))
}

pub fn run(args: &WvrnArgs) -> anyhow::Result<ExitCode> {
    let loaded = load_dynamic(&args.scene)?;
    let dynamic = &loaded.scene;
    crate::load::require_every_step(dynamic.scenes(), &args.scene)?;
    if args.step >= dynamic.len() {
        bail!(
            "--step {} is out of range: the scene has {} step(s)",
            args.step,
            dynamic.len()
        );
    }
    let scene = dynamic.step(args.step);
    bt_solve::pipeline::exhaustive_budget(scene, args.max_order, args.max_candidates)?;
    for step in dynamic.scenes() {
        bt_solve::pipeline::wvrn_budget(step, args.max_wvrn_tests)?;
    }
    let t0 = Instant::now();
    let wvrn = Wvrn::build(scene)?;
    let build_time_s = t0.elapsed().as_secs_f64();
    let nodes = wvrn.nodes().to_vec();
    let (changing, moving) = dynamic_parts(dynamic, &nodes)?;
    let exhaustive = enumerate(scene, args.max_order, &AllVisible)?.len();
    let routed = enumerate(scene, args.max_order, &wvrn)?.len();
    let index = |n: Node| {
        nodes
            .iter()
            .position(|m| *m == n)
            .expect("node of the network")
    };
    let mut edges = Vec::new();
    let mut pruned = Vec::new();
    for (a, b, link) in wvrn.pairs() {
        let (a, b) = (index(a), index(b));
        match link {
            Link::Linked => edges.push([a, b]),
            Link::Coplanar => pruned.push(PrunedEntry {
                a,
                b,
                reason: "coplanar",
                by: None,
            }),
            Link::Occluded { by } => pruned.push(PrunedEntry {
                a,
                b,
                reason: "occluded",
                by: Some(scene.surface(by).name.clone()),
            }),
        }
    }
    let doc = WvrnDocument {
        scene: scene.name().to_string(),
        step: args.step,
        steps: dynamic.len(),
        nodes: nodes
            .iter()
            .enumerate()
            .map(|(index, n)| NodeEntry {
                index,
                name: node_name(scene, *n),
                kind: match n {
                    Node::Tx => "tx",
                    Node::Rx => "rx",
                    Node::Surface(_) => "surface",
                },
                moving: moving[index],
            })
            .collect(),
        edges,
        pruned,
        stats: wvrn.stats(),
        candidates: Reduction {
            max_order: args.max_order,
            exhaustive,
            wvrn: routed,
            ratio: routed as f64 / exhaustive.max(1) as f64,
        },
        build_time_s,
    };
    let text = if args.json {
        serde_json::to_string_pretty(&doc).context("serialising the network")? + "\n"
    } else if args.dot {
        to_dot(&doc, &changing, dynamic.len() > 1)
    } else {
        table(&doc)
    };
    match &args.out {
        Some(path) => {
            let format: &[&str] = if args.json {
                &["json"]
            } else if args.dot {
                &["dot", "gv"]
            } else {
                &["txt"]
            };
            crate::files::write(path, text.as_bytes(), &loaded.sources, format)?
        }
        None => print!("{text}"),
    }
    Ok(ExitCode::SUCCESS)
}

/// A DOT string: the name escaped by the one name rule (quotes, backslashes and control
/// characters such as NUL, which ends a Graphviz file, become escapes).
fn quote(s: &str) -> String {
    format!("\"{}\"", bt_scene::name::escape(s))
}

/// Graphviz DOT: TX/RX as boxes, moving surfaces filled; in a dynamic scene edges whose state
/// changes at some step, or that touch a moving node, are red (the paper's Fig. 11), others green.
fn to_dot(doc: &WvrnDocument, changing: &BTreeSet<(usize, usize)>, dynamic: bool) -> String {
    let mut out = String::new();
    let _ = writeln!(out, "graph wvrn {{");
    let _ = writeln!(
        out,
        "  label={};",
        quote(&format!(
            "WVRN of {} (step {} of {})",
            doc.scene, doc.step, doc.steps
        ))
    );
    let _ = writeln!(out, "  node [fontsize=10];");
    // Nodes are named by index and labelled with their names: a surface named "TX" stays
    // apart from the transmitter, and two nodes never merge by name.
    let id = |i: usize| quote(&format!("n{i}"));
    for (i, n) in doc.nodes.iter().enumerate() {
        let style = match n.kind {
            "tx" => "shape=box, color=red",
            "rx" => "shape=box, color=blue",
            _ if n.moving => "shape=ellipse, style=filled, fillcolor=mistyrose",
            _ => "shape=ellipse",
        };
        let _ = writeln!(out, "  {} [label={}, {style}];", id(i), quote(&n.name));
    }
    for [a, b] in &doc.edges {
        let color = if !dynamic {
            String::new()
        } else if changing.contains(&(*a, *b)) || doc.nodes[*a].moving || doc.nodes[*b].moving {
            " [color=red]".to_string()
        } else {
            " [color=green]".to_string()
        };
        let _ = writeln!(out, "  {} -- {}{color};", id(*a), id(*b));
    }
    let _ = writeln!(out, "}}");
    out
}

fn table(doc: &WvrnDocument) -> String {
    let mut out = String::new();
    let s = &doc.stats;
    let _ = writeln!(
        out,
        "WVRN of {} (step {} of {}): {} nodes, {} of {} pairs linked ({} coplanar, {} occluded), built in {:.3} ms",
        bt_scene::name::escape(&doc.scene),
        doc.step,
        doc.steps,
        s.nodes,
        s.linked,
        s.pairs,
        s.coplanar,
        s.occluded,
        doc.build_time_s * 1e3
    );
    let c = &doc.candidates;
    let _ = writeln!(
        out,
        "candidates up to order {}: {} exhaustive, {} over the WVRN (ratio {:.3})",
        c.max_order, c.exhaustive, c.wvrn, c.ratio
    );
    for p in &doc.pruned {
        let _ = writeln!(
            out,
            "  {:<20} {:<20} {}{}",
            bt_scene::name::escape(&doc.nodes[p.a].name),
            bt_scene::name::escape(&doc.nodes[p.b].name),
            p.reason,
            p.by.as_ref()
                .map(|b| format!(" by {}", bt_scene::name::escape(b)))
                .unwrap_or_default()
        );
    }
    out
}
