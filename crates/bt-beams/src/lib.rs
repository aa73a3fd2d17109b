//! What a beam manager needs from each path: length, delay, departure and arrival directions,
//! incidence angles, loss, the polarised complex gain (`bt-channel`, `docs/channel.md`); and the
//! paper's ranking (order first, then length, then angle).
//!
//! Angle conventions (`docs/conventions.md`): azimuth from +x towards +y, in (-180°, 180°];
//! elevation from the horizontal plane, positive up, in [-90°, 90°]. The departure direction is
//! TX towards the first interaction point (or RX); the arrival direction is RX towards the last
//! interaction point (or TX), i.e. where the wave comes from, as Sionna RT and MATLAB report it.
#![warn(missing_docs)]

pub mod document;
mod gain;
mod records;
pub mod sweep;

pub use document::{
    FORMAT_VERSION, Radio, StageTimes, Stats, StepDocument, StepStats, StepsDocument,
    TraceDocument, terminals_world,
};
pub use records::Records;
pub use sweep::{BeamPair, BeamRanking, Sweep, sweep};

use bt_channel::{Complex64, DiffractionCoefficient, SurfaceResponse, Tap};
use bt_geom::{Real, Vec3};
use bt_scene::{Scene, SurfaceId};
use bt_solve::{FoundPath, Interaction};
use serde::{Deserialize, Deserializer, Serialize, Serializer};

/// Speed of light in vacuum, m/s.
pub use bt_channel::{Antenna, ChannelError, Orientation, RadioMaterial, SPEED_OF_LIGHT};

/// Why paths could not be reported.
#[derive(Debug, thiserror::Error)]
pub enum ReportError {
    /// A material has no radio model at the scene's frequency.
    #[error(transparent)]
    Channel(#[from] ChannelError),
    /// The scene lacks a terminal the paths run between
    /// ([`bt_scene::SceneError::MissingTerminal`]): paths belong to a scene with both.
    #[error(transparent)]
    Scene(#[from] bt_scene::SceneError),
}

/// The radio side of a report: antennas at both ends, the transmitted power and the
/// diffraction coefficient of diffracted paths.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct RadioOptions {
    /// Transmitting antenna (default: isotropic, vertical).
    pub tx: Antenna,
    /// Receiving antenna (default: isotropic, vertical).
    pub rx: Antenna,
    /// Transmitted power, dBm (default 0).
    pub tx_power_dbm: Real,
    /// How a diffraction's Jones matrix combines the UTD terms (default: UTD;
    /// `docs/channel.md` §8).
    pub diffraction_coefficient: DiffractionCoefficient,
    /// With the `sionna-rt-2.2` coefficient, the `max_depth` (interactions) of the Sionna RT 2.2
    /// `PathSolver` whose gains to reproduce: Sionna lengthens the diffracted leg of a path
    /// that reflects after its edge and has fewer interactions than that
    /// ([`bt_channel::path_gain_sionna_rt22`], docs/channel.md "Reflections after the edge in
    /// Sionna RT 2.2"). The CLI and Python set it to the trace's maximum order. `None`, or the
    /// `utd` coefficient: UTD's unfolded leg.
    pub sionna_max_depth: Option<usize>,
}

impl RadioOptions {
    /// These options for a trace of at most `max_order` interactions: with the `sionna-rt-2.2`
    /// coefficient, Sionna's `PathSolver` of that `max_depth` ([`RadioOptions::sionna_max_depth`]).
    pub fn for_order(self, max_order: usize) -> Self {
        RadioOptions {
            sionna_max_depth: Some(max_order),
            ..self
        }
    }
}

/// A direction as azimuth and elevation, degrees (`docs/conventions.md`); also what the
/// viewer reads back from a trace document.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct Direction {
    /// From +x towards +y, degrees in (-180, 180].
    pub azimuth: Real,
    /// From the horizontal plane, positive up, degrees in [-90, 90].
    pub elevation: Real,
}

impl Direction {
    /// Direction of the (non-zero) vector `v`.
    pub fn of(v: Vec3) -> Self {
        // The elevation's `atan2` waits for it.
        let h = bt_geom::real::root_sum_squares(v.x, v.y);
        let azimuth = if h == 0.0 {
            0.0
        } else {
            v.y.atan2(v.x).to_degrees()
        };
        let azimuth = if azimuth <= -180.0 {
            azimuth + 360.0
        } else {
            azimuth
        };
        Self {
            azimuth,
            elevation: v.z.atan2(h).to_degrees(),
        }
    }

    /// Unit vector of this direction.
    pub fn unit(&self) -> Vec3 {
        let (az, el) = (self.azimuth.to_radians(), self.elevation.to_radians());
        Vec3::new(el.cos() * az.cos(), el.cos() * az.sin(), el.sin())
    }
}

/// Everything reported about one path: the path record of every document ([`document`]).
/// The fields marked `serde(skip)` serve the libraries and are not part of the document (read
/// back, they are empty or zero).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct PathReport {
    /// 1-based rank by (order, length, largest incidence angle).
    pub rank: usize,
    /// Number of interactions, `len(points)` (0 = line of sight).
    pub order: usize,
    /// What happens at each point, aligned with `points`: "reflection", "diffraction" or
    /// "transmission" (empty for line of sight).
    pub interactions: Vec<InteractionKind>,
    /// The surface of each interaction, aligned with `points`: a reflection's or a crossing's
    /// surface, a wedge's two faces `"A|B"` (face 0, then face n), a free edge's face `"A"`; a diffraction's
    /// names escaped (`\|`, `\\`) by [`bt_scene::name::edge`].
    pub surfaces: Vec<String>,
    /// The reflecting surfaces' ids, TX side first (the diffraction and crossings left out).
    #[serde(skip)]
    pub surface_ids: Vec<SurfaceId>,
    /// The diffractions (which point, which edge), in path order.
    #[serde(skip)]
    pub diffractions: Vec<bt_solve::Diffraction>,
    /// Interaction points, TX side first, metres (TX and RX excluded).
    pub points: Vec<[Real; 3]>,
    /// Total unfolded length, metres.
    pub length_m: Real,
    /// Propagation delay, seconds.
    pub delay_s: Real,
    /// Angle of departure at TX, degrees.
    pub aod_deg: Direction,
    /// Angle of arrival at RX (direction the wave comes from), degrees.
    pub aoa_deg: Direction,
    /// Angle of incidence at each point, from the surface normal, degrees, aligned with
    /// `points`: `null` at a diffraction. A crossing's is the angle of the straight ray
    /// through it.
    pub incidence_deg: Vec<Option<Real>>,
    /// Free-space path loss over the unfolded length at the scene's frequency, dB.
    pub free_space_loss_db: Real,
    /// Sum of the materials' per-reflection losses, dB.
    pub reflection_loss_db: Real,
    /// The diffraction's excess loss over free space along the unfolded length, dB (0 for a
    /// specular path): −20·log10(max(|D_s|, |D_h|)·√(L/(s·s'))), the stronger polarisation's
    /// UTD coefficient with the edge's spreading (docs/output-format.md).
    pub diffraction_loss_db: Real,
    /// Loss of the crossings of penetrable surfaces, dB (0 without): Σ −10·log10 of the mean
    /// of |T_TE|² and |T_TM|² (ITU-R P.2040 slab transmission at each crossing's incidence).
    pub transmission_loss_db: Real,
    /// Total loss: free space plus reflections plus the diffraction plus the crossings, dB.
    pub loss_db: Real,
    /// Complex path gain [re, im] (antennas, polarisation, reflections, λ/(4π·length); no
    /// propagation phase).
    #[serde(
        serialize_with = "complex_pair",
        deserialize_with = "complex_from_pair"
    )]
    pub gain: Complex64,
    /// 20·log10|gain|, dB; `null` when the path carries no power.
    pub gain_db: Option<Real>,
    /// Received power of this path alone, dBm (transmitted power + gain_db); `null` with it.
    pub power_dbm: Option<Real>,
    /// The path is shorter than a wavelength: Friis does not hold (the loss is clamped at 0 dB).
    #[serde(skip)]
    pub near_field: bool,
    /// Unit departure direction at TX (world frame).
    #[serde(skip)]
    pub departure: Vec3,
    /// Unit arrival direction at RX, towards where the wave comes from (world frame).
    #[serde(skip)]
    pub arrival: Vec3,
    /// IPC rounds (IPC solver only).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub iterations: Option<u32>,
    /// IPC's last mean displacement, metres (IPC solver only).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub residual_m: Option<Real>,
}

/// The newtype-struct name a complex number is serialized under ([`PathReport::gain`]): JSON
/// writes a newtype struct as its content, so the document holds `[re, im]`, while a serializer
/// that sees types (the Python columns) can tell a complex number from a pair of reals.
pub const COMPLEX_NEWTYPE: &str = "Complex";

fn complex_pair<S: Serializer>(c: &Complex64, s: S) -> Result<S::Ok, S::Error> {
    s.serialize_newtype_struct(COMPLEX_NEWTYPE, &(c.re, c.im))
}

fn complex_from_pair<'de, D: Deserializer<'de>>(d: D) -> Result<Complex64, D::Error> {
    let [re, im] = <[Real; 2]>::deserialize(d)?;
    Ok(Complex64::new(re, im))
}

impl PathReport {
    /// The path's surfaces as one text for tables and CSV cells ([`bt_scene::name::route`]):
    /// `a > through "b" > c` for a path reflecting on `a`, crossing `b`, reflecting on `c`.
    pub fn route(&self) -> String {
        bt_scene::name::route(&self.surfaces, |k| {
            self.interactions.get(k) == Some(&InteractionKind::Transmission)
        })
    }

    /// A record with nothing in it yet, for [`describe_into`] to fill.
    pub(crate) fn blank() -> Self {
        Self {
            rank: 0,
            order: 0,
            interactions: Vec::new(),
            surfaces: Vec::new(),
            surface_ids: Vec::new(),
            diffractions: Vec::new(),
            points: Vec::new(),
            length_m: 0.0,
            delay_s: 0.0,
            aod_deg: Direction::of(Vec3::X),
            aoa_deg: Direction::of(Vec3::X),
            incidence_deg: Vec::new(),
            free_space_loss_db: 0.0,
            reflection_loss_db: 0.0,
            diffraction_loss_db: 0.0,
            transmission_loss_db: 0.0,
            loss_db: 0.0,
            gain: Complex64::new(0.0, 0.0),
            gain_db: None,
            power_dbm: None,
            near_field: false,
            departure: Vec3::X,
            arrival: Vec3::X,
            iterations: None,
            residual_m: None,
        }
    }

    /// A representative record for code that derives its layout from the serialization (the
    /// Python columns): one reflection, so every list has an element to show its type, and
    /// every optional field set, so every field of the document is written. A field added to
    /// the record is set here too (the compiler asks for it). The numbers are those of a
    /// floor bounce at 28 GHz between terminals 1.5 m high and 4 m apart.
    pub fn example() -> Self {
        let (tx, floor, rx) = (
            Vec3::new(0.0, 0.0, 1.5),
            Vec3::new(2.0, 0.0, 0.0),
            Vec3::new(4.0, 0.0, 1.5),
        );
        let length_m = tx.distance(floor) + floor.distance(rx);
        let free_space_loss_db = free_space_loss_db(length_m, 28e9);
        let reflection_loss_db = 6.0;
        let loss_db = free_space_loss_db + reflection_loss_db;
        let gain = Complex64::from_polar(10.0_f64.powf(-loss_db / 20.0), 0.5);
        let gain_db = power_db(gain.norm_sqr());
        Self {
            rank: 1,
            order: 1,
            interactions: vec![InteractionKind::Reflection],
            surfaces: vec!["floor".to_string()],
            surface_ids: vec![SurfaceId(0)],
            diffractions: Vec::new(),
            points: vec![floor.to_array()],
            length_m,
            delay_s: length_m / SPEED_OF_LIGHT,
            aod_deg: Direction::of(floor - tx),
            aoa_deg: Direction::of(floor - rx),
            incidence_deg: vec![Some((tx - floor).normalize().z.acos().to_degrees())],
            free_space_loss_db,
            reflection_loss_db,
            diffraction_loss_db: 0.0,
            transmission_loss_db: 0.0,
            loss_db,
            gain,
            gain_db,
            power_dbm: gain_db,
            near_field: false,
            departure: (floor - tx).normalize(),
            arrival: (floor - rx).normalize(),
            iterations: Some(3),
            residual_m: Some(1e-12),
        }
    }
}

/// Free-space path loss (Friis), dB, for `length` metres at `frequency_hz`. Friis holds in the
/// far field only: below one wavelength it would turn into a gain (−78.6 dB at 100 nm and
/// 28 GHz), so [`bt_channel::free_space`] (the one home of the clamp) clamps the length to one
/// wavelength and the loss is never below 20 log10(4π) ≈ 21.98 dB.
pub fn free_space_loss_db(length: Real, frequency_hz: Real) -> Real {
    bt_channel::free_space(length, frequency_hz).loss_db
}

/// How a surface of the scene reflects: its radio model, or its constant loss as a scaled
/// conductor when it has none.
pub fn surface_response(scene: &Scene, id: SurfaceId) -> SurfaceResponse {
    let m = scene.material_of(id);
    match m.radio {
        Some(radio) => SurfaceResponse::Radio(radio),
        None => SurfaceResponse::ConstantLoss {
            loss_db: m.reflection_loss_db,
        },
    }
}

/// `value` in dB (10·log10 of a power ratio), `None` for zero.
fn power_db(value: Real) -> Option<Real> {
    (value > 0.0).then(|| 10.0 * value.log10())
}

/// What a path does at one of its points (the document's `interactions`).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum InteractionKind {
    /// A specular reflection.
    Reflection,
    /// An edge diffraction.
    Diffraction,
    /// A crossing of a penetrable surface (thin-slab transmission).
    Transmission,
}

/// The names of a path's interactions in the document, into `names` (its strings reused):
/// the surface's name for a reflection or a crossing, the edge's ([`Scene::edge_name`]:
/// `"A|B"`, its two faces escaped, or `"A"` for a free edge) for a diffraction.
fn interaction_names(scene: &Scene, interactions: &[Interaction], names: &mut Vec<String>) {
    names.truncate(interactions.len());
    for (k, it) in interactions.iter().enumerate() {
        if k == names.len() {
            names.push(String::new());
        }
        let name = &mut names[k];
        match *it {
            Interaction::Reflection(id) | Interaction::Transmission(id) => {
                name.clear();
                name.push_str(&scene.surface(id).name);
            }
            Interaction::Diffraction(e) => *name = scene.edge_name(scene.edges().get(e)),
        }
    }
}

/// The path's vertices TX → points → RX (the terminals `ends`, local frame) into `vertices`
/// (cleared first), and its unfolded length (m): `length_m` when given (the caller's
/// [`unfolded_length`] of the same path), else computed.
fn vertices(
    ends: bt_scene::Endpoints,
    path: &FoundPath,
    vertices: &mut Vec<Vec3>,
    length_m: Option<Real>,
) -> Real {
    let bt_scene::Endpoints { tx, rx } = ends;
    vertices.clear();
    vertices.push(tx);
    vertices.extend_from_slice(&path.points);
    vertices.push(rx);
    length_m.unwrap_or_else(|| unfolded_length(tx, &path.points, rx))
}

/// The length (m) of the polyline `tx` → `points` → `rx`: its legs summed from TX, the one
/// computation of a record's `length_m` (the ranking sorts by it before the records are
/// described, [`Records`], and must see the same bits).
pub(crate) fn unfolded_length(tx: Vec3, points: &[Vec3], rx: Vec3) -> Real {
    let mut length = 0.0;
    let mut from = tx;
    for &to in points.iter().chain(std::iter::once(&rx)) {
        length += from.distance(to);
        from = to;
    }
    length
}

/// Buffers a report's paths reuse one after the other, so that describing a path allocates
/// only what its record keeps: its vertices and its interactions as the channel model sees
/// them.
#[derive(Debug, Default)]
pub(crate) struct Scratch {
    vertices: Vec<Vec3>,
    interactions: Vec<Interaction>,
    channel: Vec<bt_channel::Interaction>,
}

/// Describe one found path (rank 0 until [`report`] ranks it); `scene` is the one it was
/// found in, with both terminals.
pub fn describe(
    scene: &Scene,
    path: &FoundPath,
    radio: &RadioOptions,
) -> Result<PathReport, ReportError> {
    let responses = &mut gain::Responses::new(scene);
    let mut record = PathReport::blank();
    describe_into(
        responses,
        &mut Scratch::default(),
        path,
        radio,
        &mut record,
        None,
    )?;
    Ok(record)
}

/// [`describe`] into `record`, whose vectors and names are reused (cleared and refilled, so a
/// record of a previous report costs no allocation), with the surfaces' responses looked up
/// once for all the paths of a report. `length_m` is the path's [`unfolded_length`] when the
/// caller has it (the ranking computes it first, [`Records`]): the same bits, not made twice.
pub(crate) fn describe_into(
    responses: &mut gain::Responses<'_>,
    scratch: &mut Scratch,
    path: &FoundPath,
    radio: &RadioOptions,
    record: &mut PathReport,
    length_m: Option<Real>,
) -> Result<(), ReportError> {
    let scene = responses.scene();
    let ends = responses.terminals()?;
    let length_m = vertices(ends, path, &mut scratch.vertices, length_m);
    let vertices = &scratch.vertices;
    path.interactions_into(&mut scratch.interactions);
    let interactions = &scratch.interactions;
    let incidence_deg = refill(
        &mut record.incidence_deg,
        (interactions.iter().enumerate()).map(|(k, it)| match it {
            Interaction::Reflection(id) | Interaction::Transmission(id) => {
                let normal = scene.surface(*id).polygon.plane().normal;
                let incoming = (vertices[k] - vertices[k + 1]).normalize();
                Some(incoming.dot(normal).abs().min(1.0).acos().to_degrees())
            }
            Interaction::Diffraction(_) => None,
        }),
    );
    // Fold from +0.0: an empty f64 sum is -0.0, which would print as -0.0 for line of sight.
    let reflection_loss_db = path
        .surfaces
        .iter()
        .map(|id| responses.get(*id).1)
        .fold(0.0, |a, b| a + b);
    let free_space = bt_channel::free_space(length_m, scene.frequency_hz());
    let free_space_loss_db = free_space.loss_db;
    let (gain, diffraction_loss_db) =
        gain::path_gain(responses, &mut scratch.channel, path, interactions, radio)?;
    let transmission_loss_db = gain::transmission_loss_db(responses, vertices, interactions)?;
    let gain_db = power_db(gain.norm_sqr());
    let n = vertices.len();
    let mut surfaces = std::mem::take(&mut record.surfaces);
    interaction_names(scene, interactions, &mut surfaces);
    *record = PathReport {
        rank: 0,
        order: path.points.len(),
        interactions: refill(
            &mut record.interactions,
            interactions.iter().map(|it| match it {
                Interaction::Reflection(_) => InteractionKind::Reflection,
                Interaction::Diffraction(_) => InteractionKind::Diffraction,
                Interaction::Transmission(_) => InteractionKind::Transmission,
            }),
        ),
        surfaces,
        surface_ids: refill(&mut record.surface_ids, path.surfaces.iter().copied()),
        diffractions: refill(&mut record.diffractions, path.diffractions.iter().copied()),
        points: refill(
            &mut record.points,
            (path.points.iter()).map(|p| scene.to_world(*p).to_array()),
        ),
        length_m,
        delay_s: length_m / SPEED_OF_LIGHT,
        aod_deg: Direction::of(vertices[1] - vertices[0]),
        aoa_deg: Direction::of(vertices[n - 2] - vertices[n - 1]),
        incidence_deg,
        free_space_loss_db,
        reflection_loss_db,
        diffraction_loss_db,
        transmission_loss_db,
        loss_db: free_space_loss_db
            + reflection_loss_db
            + diffraction_loss_db
            + transmission_loss_db,
        gain,
        gain_db,
        power_dbm: gain_db.map(|g| g + radio.tx_power_dbm),
        near_field: free_space.near_field,
        departure: (vertices[1] - vertices[0]).normalize(),
        arrival: (vertices[n - 2] - vertices[n - 1]).normalize(),
        iterations: path.iterations,
        residual_m: path.residual,
    };
    Ok(())
}

/// `buffer`'s vector (taken, so the record it came from holds an empty one) refilled with
/// `items`: its capacity is reused.
fn refill<T>(buffer: &mut Vec<T>, items: impl Iterator<Item = T>) -> Vec<T> {
    let mut v = std::mem::take(buffer);
    v.clear();
    v.extend(items);
    v
}

/// The channel taps of reported paths (gain, delay), in report order.
pub fn taps(paths: &[PathReport]) -> Vec<Tap> {
    paths
        .iter()
        .map(|p| Tap {
            gain: p.gain,
            delay_s: p.delay_s,
        })
        .collect()
}

/// Total received power of the paths, dBm: transmitted power + 10·log10 Σ|gain|² (a power sum:
/// the wideband average, without interference between paths); `None` without power.
pub fn received_power_dbm(paths: &[PathReport], tx_power_dbm: Real) -> Option<Real> {
    // `bt_channel::total_power` of the paths' taps, summed in place (no vector of taps).
    let total = (paths.iter())
        .map(|p| p.gain.norm_sqr())
        .fold(0.0, |a, b| a + b);
    power_db(total).map(|g| g + tx_power_dbm)
}

/// Describe and rank all paths: by order, then length, then the largest incidence angle
/// (closer to normal first), then surface ids — the paper's principles, made total. Fails only
/// if a material has no radio model at the scene's frequency (scenes are validated against
/// that) or the scene lacks a terminal (it cannot then have been traced). A caller that
/// reports again and again reuses the records' memory with a [`Records`].
pub fn report(
    scene: &Scene,
    paths: &[FoundPath],
    radio: &RadioOptions,
) -> Result<Vec<PathReport>, ReportError> {
    let mut records = Records::default();
    records.report(scene, paths, radio)?;
    Ok(records.into_paths())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn direction_conventions() {
        let d = Direction::of(Vec3::new(0.0, 1.0, 0.0));
        assert!((d.azimuth - 90.0).abs() < 1e-12 && d.elevation.abs() < 1e-12);
        let d = Direction::of(Vec3::new(-1.0, 0.0, 1.0));
        assert!((d.azimuth - 180.0).abs() < 1e-12 && (d.elevation - 45.0).abs() < 1e-12);
        let v = Vec3::new(0.3, -0.4, 0.2).normalize();
        assert!((Direction::of(v).unit() - v).length() < 1e-12);
    }

    #[test]
    fn example_writes_every_field_and_reads_back() {
        let example = PathReport::example();
        let json = serde_json::to_string(&example).unwrap();
        // The complex newtype leaves the document's bytes as a plain pair.
        let pair = serde_json::to_string(&[example.gain.re, example.gain.im]).unwrap();
        assert!(json.contains(&format!("\"gain\":{pair},")), "{json}");
        for key in [
            "\"iterations\":3",
            "\"residual_m\":1e-12",
            "\"surfaces\":[\"floor\"]",
        ] {
            assert!(json.contains(key), "{key} in {json}");
        }
        // Read back (serde_json parses floats to within an ulp), it writes the same fields.
        let back: PathReport = serde_json::from_str(&json).unwrap();
        let keys = |p: &PathReport| serde_json::to_value(p).unwrap().as_object().unwrap().len();
        assert_eq!(keys(&back), keys(&example));
        assert!((example.incidence_deg[0].unwrap() - 53.130_102_354_155_98).abs() < 1e-9);
    }

    #[test]
    fn friis_is_clamped_below_one_wavelength() {
        let f = 28e9;
        let lambda = SPEED_OF_LIGHT / f;
        let floor = 20.0 * (4.0 * std::f64::consts::PI).log10();
        // Unclamped, 100 nm would give 20 log10(4π · 1e-7 / λ) ≈ -78.6 dB: a gain.
        for length in [1e-7, 1e-3, lambda * 0.5, lambda] {
            let l = free_space_loss_db(length, f);
            assert!((l - floor).abs() < 1e-9, "{length}: {l}");
            assert_eq!(
                bt_channel::free_space(length, f).near_field,
                length < lambda
            );
        }
        assert!(free_space_loss_db(2.0 * lambda, f) > floor + 6.0);
    }

    #[test]
    fn friis_at_one_metre_and_28_ghz() {
        // 20 log10(4 pi f / c) at 28 GHz = 20 log10(1173.68) = 61.391 dB
        assert!((free_space_loss_db(1.0, 28e9) - 61.391).abs() < 1e-3);
        assert!(
            (free_space_loss_db(10.0, 28e9) - free_space_loss_db(1.0, 28e9) - 20.0).abs() < 1e-9
        );
    }

    /// A wall (`north|wall`) whose top edge meets a roof (`roof\tile`) on the far side: a wedge
    /// between TX in front of the wall and RX above the roof, whose record names both faces
    /// so that they split back apart, as do the free edges' single names.
    #[test]
    fn edge_names_holding_separators_split_back_into_their_faces() {
        let (wall, roof) = ("north|wall", "roof\\tile");
        let json = r#"{ "tx": [0.3, -3, 1.8], "rx": [-0.2, 3, 2.1], "surfaces": [
            { "name": "north|wall", "vertices": [[-2, 0, 0], [2, 0, 0], [2, 0, 2], [-2, 0, 2]] },
            { "name": "roof\\tile", "vertices": [[-2, 0, 2], [2, 0, 2], [2, 2, 2], [-2, 2, 2]] }
        ] }"#;
        let desc: bt_scene::SceneDescription = serde_json::from_str(json).unwrap();
        let scene = Scene::from_description(&desc, "wedge", Default::default()).unwrap();
        assert_eq!(scene.surface(SurfaceId(1)).name, roof);
        let options = bt_solve::pipeline::TraceOptions {
            diffraction: bt_solve::pipeline::DiffractionOptions::first_order(),
            ..bt_solve::pipeline::TraceOptions::new(1)
        };
        let (tx, rx) = (scene.tx_world().unwrap(), scene.rx_world().unwrap());
        let traced = bt_solve::Tracer::new(scene.clone(), options)
            .trace(tx, rx)
            .unwrap();
        let reports = report(&scene, &traced.result.paths, &RadioOptions::default()).unwrap();
        let json = serde_json::to_string(&reports).unwrap();
        let read: Vec<PathReport> = serde_json::from_str(&json).unwrap();
        let mut wedges = 0;
        for p in &read {
            let edges = (p.interactions.iter().zip(&p.surfaces))
                .filter(|(kind, _)| **kind == InteractionKind::Diffraction);
            for (_, name) in edges {
                let (face0, face_n) = bt_scene::name::split_edge(name).unwrap();
                match face_n {
                    Some(face_n) => {
                        assert_eq!(name, "north\\|wall|roof\\\\tile");
                        assert_eq!((face0.as_str(), face_n.as_str()), (wall, roof));
                        wedges += 1;
                    }
                    None => assert!([wall, roof].contains(&face0.as_str()), "{name}"),
                }
            }
        }
        assert_eq!(wedges, 1, "one path over the wedge: {json}");
    }
}
