//! Beam sweep: the received power of every (TX beam, RX beam) pair of two DFT codebooks from
//! the reported paths, ranked by power, or in the paper's order (the pair that best serves
//! each path, paths taken by the paper's rank). `docs/channel.md`.

use crate::{Direction, PathReport, taps};
use bt_channel::codebook::beam_gains;
use bt_channel::{Array, ChannelError, PathDirections, beam_pairs};
use bt_geom::Real;
use serde::Serialize;

/// How beam pairs are ranked.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
#[serde(rename_all = "kebab-case")]
pub enum BeamRanking {
    /// By received power at the carrier, strongest first.
    Power,
    /// The paper's: for each path in rank order (order, length, angle), the pair with the
    /// largest array gain towards its departure and arrival directions; each pair once.
    Paper,
}

/// One ranked beam pair.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct BeamPair {
    /// 1-based rank.
    pub rank: usize,
    /// TX beam index in its codebook.
    pub tx_beam: usize,
    /// RX beam index in its codebook.
    pub rx_beam: usize,
    /// Main-lobe direction of the TX beam (`null` outside the visible region), degrees.
    pub tx_direction_deg: Option<Direction>,
    /// Main-lobe direction of the RX beam, degrees.
    pub rx_direction_deg: Option<Direction>,
    /// Received power with this pair (coherent sum over the paths at the carrier), dBm;
    /// `null` when nothing arrives.
    pub power_dbm: Option<Real>,
    /// Paper ranking: the rank of the path this pair was chosen for.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub path_rank: Option<usize>,
}

/// The result of a sweep.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Sweep {
    /// Beams in the TX codebook.
    pub tx_beams: usize,
    /// Beams in the RX codebook.
    pub rx_beams: usize,
    /// The ranking used.
    pub ranking: BeamRanking,
    /// Ranked pairs (all pairs for `power`, one per distinct best pair for `paper`).
    pub pairs: Vec<BeamPair>,
}

/// Sweep the DFT codebooks of `tx` and `rx` over `paths` at `carrier_hz` with `tx_power_dbm`;
/// more than `max_pairs` beam pairs ([`bt_channel::MAX_BEAM_PAIRS`], `--max-beam-pairs`) are
/// refused before the codebooks are built.
pub fn sweep(
    paths: &[PathReport],
    tx: &Array,
    rx: &Array,
    carrier_hz: Real,
    tx_power_dbm: Real,
    ranking: BeamRanking,
    max_pairs: u64,
) -> Result<Sweep, ChannelError> {
    bt_channel::check_beam_pairs(tx, rx, max_pairs)?;
    let (tx_book, rx_book) = (tx.dft_codebook(), rx.dft_codebook());
    let directions: Vec<PathDirections> = taps(paths)
        .into_iter()
        .zip(paths)
        .map(|(tap, p)| PathDirections {
            tap,
            departure: p.departure,
            arrival: p.arrival,
        })
        .collect();
    let h = beam_pairs(&directions, (tx, &tx_book), (rx, &rx_book), carrier_hz)?;
    let pair = |t: usize, r: usize, path_rank: Option<usize>| BeamPair {
        rank: 0,
        tx_beam: t,
        rx_beam: r,
        tx_direction_deg: tx_book[t].direction.map(Direction::of),
        rx_direction_deg: rx_book[r].direction.map(Direction::of),
        power_dbm: {
            let p = h[t][r].norm_sqr();
            (p > 0.0).then(|| 10.0 * p.log10() + tx_power_dbm)
        },
        path_rank,
    };
    let mut pairs: Vec<BeamPair> = match ranking {
        BeamRanking::Power => {
            let mut all: Vec<BeamPair> = (0..tx_book.len())
                .flat_map(|t| (0..rx_book.len()).map(move |r| (t, r)))
                .map(|(t, r)| pair(t, r, None))
                .collect();
            // Strongest first; ties (and no power) by beam indices: a total, stable order.
            all.sort_by(|a, b| {
                let key = |p: &BeamPair| p.power_dbm.unwrap_or(Real::NEG_INFINITY);
                key(b)
                    .total_cmp(&key(a))
                    .then((a.tx_beam, a.rx_beam).cmp(&(b.tx_beam, b.rx_beam)))
            });
            all
        }
        BeamRanking::Paper => {
            let gt = beam_gains(tx, &tx_book, paths.iter().map(|p| p.departure));
            let gr = beam_gains(rx, &rx_book, paths.iter().map(|p| p.arrival));
            let best = |g: &[bt_channel::Complex64]| {
                (0..g.len())
                    .max_by(|&a, &b| g[a].norm().total_cmp(&g[b].norm()).then(b.cmp(&a)))
                    .unwrap_or(0)
            };
            let mut chosen: Vec<BeamPair> = Vec::new();
            for (k, p) in paths.iter().enumerate() {
                let (t, r) = (best(&gt[k]), best(&gr[k]));
                if !chosen.iter().any(|c| (c.tx_beam, c.rx_beam) == (t, r)) {
                    chosen.push(pair(t, r, Some(p.rank)));
                }
            }
            chosen
        }
    };
    for (i, p) in pairs.iter_mut().enumerate() {
        p.rank = i + 1;
    }
    Ok(Sweep {
        tx_beams: tx_book.len(),
        rx_beams: rx_book.len(),
        ranking,
        pairs,
    })
}
