//! The scenarios: a true scene over time, the access point, the UE's trajectory, and the
//! twins a device could hold of the scene.
//!
//! Positions are world-frame metres; headings are yaw angles in radians from +x towards +y.

use crate::StudyError;
use bt_channel::Orientation;
use bt_geom::{Real, Vec3};
use bt_scene::dynamic::{DynamicScene, Pose};
use bt_scene::{Scene, SurfaceKind, Terminals};
use std::f64::consts::TAU;

/// How the device's scan of the room is made for the extracted twin.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize)]
pub struct ScanSettings {
    /// Points per m² of surface; 0 makes no extracted twin.
    pub density_per_m2: Real,
    /// Gaussian range noise along the surface normal, metres (the issue: 5 mm).
    pub noise_m: Real,
    /// Largest number of points a scan may have (area × density is checked before sampling).
    pub max_points: u64,
    /// Seed of the scan and of RANSAC.
    pub seed: u64,
}

/// One scenario of the study.
#[derive(Debug, Clone)]
pub struct Scenario {
    /// Its name in the outputs (`living-room`, `city`, or the file's stem).
    pub name: String,
    /// The true scene at its time steps (one step for a static scene); decisions in between
    /// interpolate the objects' poses.
    pub truth: DynamicScene,
    /// Access point position.
    pub ap: Vec3,
    /// Orientation of the AP's array (boresight towards the trajectory's centroid).
    pub ap_orientation: Orientation,
    /// The UE's position at each decision.
    pub trajectory: Vec<Vec3>,
    /// The UE's heading (yaw of its array's boresight) at each decision, radians.
    pub headings: Vec<Real>,
    /// Time between decisions, seconds.
    pub decision_period_s: Real,
    /// The room as scanned before the run: objects at their step-0 poses, the moving
    /// blockers (people) absent. `None` when nothing moves (the exact twin is the same).
    pub stale: Option<Scene>,
    /// Planes extracted from a noisy scan of the stale room (or of the static scene);
    /// `None` when no scan was made (see `notes`).
    pub extracted: Option<Scene>,
    /// Why a twin is absent, and what the scan found.
    pub notes: Vec<String>,
    /// Lowest and highest corner of the scene's bounding box: a reported position is kept
    /// [`BOUNDS_MARGIN_M`] inside it (a device knows it is in the room, or in the city).
    pub bounds: [Vec3; 2],
}

/// How far inside the scene's bounding box a reported position is kept, metres.
pub const BOUNDS_MARGIN_M: Real = 0.05;

/// The built-in living room's loop: centre (x, y), semi-axes (x, y) and height, metres; the UE
/// starts at angle 0 and walks it once counter-clockwise, about 10.2 m (a walker at 1 m/s with
/// 10 ms between decisions), never nearer than 1.1 m to the walking person.
pub const LOOP: ([Real; 2], [Real; 2], Real) = ([3.0, 2.25], [1.9, 1.3], 1.2);

/// Time between decisions of the living room (a 100 Hz beam report at walking speed), s.
pub const ROOM_PERIOD_S: Real = 0.01;

/// Time between decisions on a street, s (a car at about 12 m/s over the 1,000 positions).
pub const STREET_PERIOD_S: Real = 0.02;

fn facing(from: Vec3, to: Vec3) -> Orientation {
    let d = to - from;
    let yaw = d.y.atan2(d.x);
    // Orientation's pitch tilts boresight down for positive angles.
    let pitch = (-d.z).atan2(bt_geom::real::hypot(d.x, d.y));
    Orientation {
        yaw,
        pitch,
        roll: 0.0,
    }
}

fn centroid(points: &[Vec3]) -> Vec3 {
    points.iter().fold(Vec3::ZERO, |a, p| a + *p) / points.len().max(1) as Real
}

/// The scene a scenario name loads: `living-room` the built-in dynamic living room, `city`
/// the built-in city, anything else a scene file.
pub fn source_of(name: &str) -> &str {
    match name {
        "living-room" => "builtin:living-room-dynamic",
        "city" => "builtin:city",
        file => file,
    }
}

impl Scenario {
    /// The scenario `name` (see [`source_of`]) over `truth`, the scene loaded from its source:
    /// the living room's loop for `living-room`, a street otherwise; a file's scenario is named
    /// after its stem.
    pub fn named(
        name: &str,
        truth: DynamicScene,
        positions: usize,
        scan: &ScanSettings,
    ) -> Result<Scenario, StudyError> {
        let label = match name {
            "living-room" | "city" => name,
            file => std::path::Path::new(file)
                .file_stem()
                .and_then(|s| s.to_str())
                .unwrap_or("scene"),
        };
        match name {
            "living-room" => Self::living_room(label, truth, positions, scan),
            _ => Self::street(label, truth, positions, scan),
        }
    }

    /// The dynamic living room (`builtin:living-room-dynamic` or a scene like it): the AP at
    /// the scene's TX, the UE walking [`LOOP`] in `positions` decisions while the scene's
    /// objects move through all their steps.
    pub fn living_room(
        name: &str,
        truth: DynamicScene,
        positions: usize,
        scan: &ScanSettings,
    ) -> Result<Scenario, StudyError> {
        let ap = terminal(&truth, name, true)?;
        let ([cx, cy], [a, b], z) = LOOP;
        let angle = |i: usize| TAU * i as Real / positions as Real;
        let trajectory: Vec<Vec3> = (0..positions)
            .map(|i| Vec3::new(cx + a * angle(i).cos(), cy + b * angle(i).sin(), z))
            .collect();
        let headings = (0..positions)
            .map(|i| (b * angle(i).cos()).atan2(-a * angle(i).sin()))
            .collect();
        Self::assemble(name, truth, ap, trajectory, headings, ROOM_PERIOD_S, scan)
    }

    /// A street: the AP at the scene's TX, the UE at the RX's height driving the straight
    /// line through the RX along the horizontal TX→RX direction, from 15 % to 150 % of that
    /// distance past the TX, heading along the line.
    pub fn street(
        name: &str,
        truth: DynamicScene,
        positions: usize,
        scan: &ScanSettings,
    ) -> Result<Scenario, StudyError> {
        let ap = terminal(&truth, name, true)?;
        let rx = terminal(&truth, name, false)?;
        let d = Vec3::new(rx.x - ap.x, rx.y - ap.y, 0.0);
        if d.length() == 0.0 {
            return Err(StudyError::Config(format!(
                "scenario {name}: the receiver is straight below or above the transmitter, so the street has no direction"
            )));
        }
        let start = Vec3::new(ap.x, ap.y, rx.z) + d * 0.15;
        let step = d * (1.35 / (positions.max(2) - 1) as Real);
        let trajectory = (0..positions).map(|i| start + step * i as Real).collect();
        let headings = vec![d.y.atan2(d.x); positions];
        Self::assemble(name, truth, ap, trajectory, headings, STREET_PERIOD_S, scan)
    }

    fn assemble(
        name: &str,
        truth: DynamicScene,
        ap: Vec3,
        trajectory: Vec<Vec3>,
        headings: Vec<Real>,
        decision_period_s: Real,
        scan: &ScanSettings,
    ) -> Result<Scenario, StudyError> {
        let mut notes = Vec::new();
        let stale = stale_twin(&truth)?;
        if stale.is_none() {
            notes
                .push("stale twin: nothing moves in this scene, it would be the exact twin".into());
        }
        let scanned = stale.as_ref().unwrap_or(truth.step(0));
        let step = truth.step(0);
        let corners = (step.surfaces().iter())
            .flat_map(|s| s.polygon.vertices().iter().map(|v| step.to_world(*v)));
        let bounds = corners.fold([Vec3::INFINITY, Vec3::NEG_INFINITY], |[lo, hi], p| {
            [lo.min(p), hi.max(p)]
        });
        let extracted = extracted_twin(scanned, scan, &mut notes)?;
        // The name lands in CSV rows and file-free JSON keys: plain characters only.
        let name: String = (name.chars())
            .map(|c| match c.is_ascii_alphanumeric() || "-_.".contains(c) {
                true => c,
                false => '_',
            })
            .collect();
        Ok(Scenario {
            name,
            ap_orientation: facing(ap, centroid(&trajectory)),
            truth,
            ap,
            trajectory,
            headings,
            decision_period_s,
            stale,
            extracted,
            notes,
            bounds,
        })
    }

    /// `p` moved [`BOUNDS_MARGIN_M`] inside the scene's bounding box (where it is wider).
    pub fn inside(&self, p: Vec3) -> Vec3 {
        let [lo, hi] = self.bounds;
        let m = Vec3::splat(BOUNDS_MARGIN_M).min((hi - lo).max(Vec3::ZERO) * 0.5);
        p.clamp(lo + m, hi - m)
    }

    /// The true scene at decision `i`: every object at its pose interpolated linearly between
    /// the scene's steps, the run's decisions spread evenly over all steps.
    pub fn truth_at(&self, i: usize) -> Result<Scene, StudyError> {
        let steps = self.truth.len();
        if steps <= 1 {
            return Ok(self.truth.step(0).clone());
        }
        let n = self.trajectory.len().max(2);
        let s = (steps - 1) as Real * i.min(n - 1) as Real / (n - 1) as Real;
        let (k, frac) = (
            (s.floor() as usize).min(steps - 2),
            s - s.floor().min((steps - 2) as Real),
        );
        let poses: Vec<Pose> = (self.truth.objects().iter())
            .map(|o| {
                let (p, q) = (o.poses[k], o.poses[k + 1]);
                Pose {
                    offset: p.offset + (q.offset - p.offset) * frac,
                    angle_deg: p.angle_deg + (q.angle_deg - p.angle_deg) * frac,
                    ..p
                }
            })
            .collect();
        self.truth
            .posed(&poses, Terminals::default())
            .map_err(|e| scene_error(&self.name, e))
    }
}

fn scene_error(name: &str, e: impl std::fmt::Display) -> StudyError {
    StudyError::Scene {
        name: name.to_string(),
        message: e.to_string(),
    }
}

fn terminal(truth: &DynamicScene, name: &str, tx: bool) -> Result<Vec3, StudyError> {
    let step = truth.step(0);
    let (p, which) = match tx {
        true => (step.tx_world(), "a transmitter (the access point)"),
        false => (step.rx_world(), "a receiver (where the UE's street is)"),
    };
    p.ok_or_else(|| {
        StudyError::Config(format!(
            "scenario {name}: the scene has no {which}; give it in the scene file"
        ))
    })
}

/// Step 0 without the surfaces of objects made only of blockers (people, carts); `None` when
/// the scene has one step (nothing moves).
fn stale_twin(truth: &DynamicScene) -> Result<Option<Scene>, StudyError> {
    if truth.len() <= 1 {
        return Ok(None);
    }
    let step = truth.step(0);
    let mut gone = Vec::new();
    for o in truth.objects() {
        if o.surfaces
            .iter()
            .all(|&id| step.surface(id).kind == SurfaceKind::Blocker)
        {
            gone.extend(o.surfaces.iter().map(|id| id.0 as usize));
        }
    }
    let mut stored = step.to_stored();
    let mut index = 0;
    stored.surfaces.retain(|_| {
        index += 1;
        !gone.contains(&(index - 1))
    });
    stored.name = format!("{}-stale", stored.name);
    Scene::from_stored(stored, "stale twin")
        .map(Some)
        .map_err(|e| scene_error("stale twin", e))
}

/// Planes extracted from a seeded scan of `scanned` with Gaussian range noise, as a scene of
/// `default` (concrete) surfaces with `scanned`'s terminals and frequency.
fn extracted_twin(
    scanned: &Scene,
    scan: &ScanSettings,
    notes: &mut Vec<String>,
) -> Result<Option<Scene>, StudyError> {
    if scan.density_per_m2 <= 0.0 {
        notes.push("extracted twin: no scan (scan density 0)".into());
        return Ok(None);
    }
    let area: Real = scanned.surfaces().iter().map(|s| s.polygon.area()).sum();
    let estimate = area * scan.density_per_m2;
    if estimate > scan.max_points as Real {
        notes.push(format!(
            "extracted twin: not made, a scan of {area:.0} m² at {} points/m² would have {estimate:.2e} points, over the budget of {} (--max-scan-points)",
            scan.density_per_m2, scan.max_points
        ));
        return Ok(None);
    }
    let polygons: Vec<Vec<Vec3>> = (scanned.surfaces().iter())
        .map(|s| {
            s.polygon
                .vertices()
                .iter()
                .map(|v| scanned.to_world(*v))
                .collect()
        })
        .collect();
    let cloud =
        bt_pointcloud::sample_polygons(&polygons, scan.density_per_m2, scan.noise_m, scan.seed);
    let params = bt_pointcloud::ExtractParams {
        seed: scan.seed,
        ..Default::default()
    };
    let extraction = bt_pointcloud::extract_planes(&cloud, &params)
        .map_err(|e| scene_error("extracted twin", e))?;
    let r = &extraction.report;
    notes.push(format!(
        "extracted twin: {} points (noise {} m) -> {} planes ({} reflectors, {} blockers), RMS {:.4} m, seed {}; every plane concrete",
        r.input_points, scan.noise_m, r.planes_found, r.reflectors, r.blockers, r.rms_m, r.seed
    ));
    let name = format!("{}-extracted", scanned.name());
    let mut desc = bt_import::cloud::cloud_description(
        &extraction,
        &name,
        scanned.tx_world().map(|v| v.to_array()),
        scanned.rx_world().map(|v| v.to_array()),
    );
    desc.frequency_hz = Some(scanned.frequency_hz());
    Scene::from_description(&desc, "extracted twin", Terminals::default())
        .map(Some)
        .map_err(|e| scene_error("extracted twin", e))
}
