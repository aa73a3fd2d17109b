//! Point clouds where a scene is expected: read the cloud, extract its planes with
//! `bt-pointcloud`, and describe them as a scene (`plane-<k>` surfaces, material `default`).

use crate::source::file_stem;
use crate::{ImportError, LoadOptions, LoadProgress, Loaded};
use bt_pointcloud::Extraction;
use bt_scene::{Scene, SceneDescription, SurfaceDesc, SurfaceKind};
use std::path::Path;

/// Bytes of a PLY file searched for `end_header` when deciding mesh or cloud.
const PLY_HEADER_SNIFF_BYTES: usize = 64 * 1024;

/// Whether `path` should be read as a point cloud: `.pcd`, or a `.ply` whose header declares
/// no faces (or zero faces). An unreadable `.ply` counts as a mesh, so the mesh reader reports
/// the error.
pub fn is_point_cloud(path: &Path) -> bool {
    let ext = path
        .extension()
        .and_then(|e| e.to_str())
        .unwrap_or("")
        .to_ascii_lowercase();
    match ext.as_str() {
        "pcd" => true,
        "ply" => ply_has_no_faces(path),
        _ => false,
    }
}

fn ply_has_no_faces(path: &Path) -> bool {
    use std::io::Read;
    let Ok(file) = std::fs::File::open(path) else {
        return false;
    };
    let mut head = Vec::with_capacity(PLY_HEADER_SNIFF_BYTES);
    if file
        .take(PLY_HEADER_SNIFF_BYTES as u64)
        .read_to_end(&mut head)
        .is_err()
    {
        return false;
    }
    crate::formats::ply_declares_faces(&head) == Some(false)
}

/// The scene description of extracted planes: `plane-<k>` surfaces, reflectors or blockers by
/// area, material `default`; TX/RX as given (or absent: supply them when tracing).
pub fn cloud_description(
    extraction: &Extraction,
    name: &str,
    tx: Option<[f64; 3]>,
    rx: Option<[f64; 3]>,
) -> SceneDescription {
    SceneDescription {
        name: Some(name.to_string()),
        tx,
        rx,
        surfaces: extraction
            .planes
            .iter()
            .enumerate()
            .map(|(k, p)| SurfaceDesc {
                name: format!("plane-{k}"),
                kind: Some(if p.reflector {
                    SurfaceKind::Reflector
                } else {
                    SurfaceKind::Blocker
                }),
                vertices: p.polygon.iter().map(|v| v.to_array()).collect(),
                ..Default::default()
            })
            .collect(),
        ..Default::default()
    }
}

/// Read the cloud at `path`, extract its planes with `options.extract` and validate them as a
/// scene with `options.terminals`.
pub(crate) fn load_cloud(
    path: &Path,
    options: &LoadOptions,
    progress: &mut dyn FnMut(LoadProgress),
) -> Result<Loaded, ImportError> {
    let display = path.display().to_string();
    let cloud = super::read_path(path, &options.cloud)?;
    let extraction =
        bt_pointcloud::extract_planes_with_progress(&cloud.cloud, &options.extract, progress)
            .map_err(|e| super::CloudError::from(e).with_path(path))?;
    let mut desc = cloud_description(&extraction, &file_stem(path, "cloud"), None, None);
    desc.frequency_hz = Some(options.frequency_hz);
    let scene = Scene::from_description(&desc, &display, options.terminals)?;
    let mut warnings = Vec::new();
    if cloud.skipped_non_finite > 0 {
        warnings.push(format!(
            "{display}: point cloud: {} points skipped as non-finite",
            cloud.skipped_non_finite
        ));
    }
    warnings.push(format!(
        "{display}: point cloud: extracted {} planes ({} reflectors); `beamtrace extract` writes them as a scene file",
        extraction.report.planes_found, extraction.report.reflectors
    ));
    Ok(Loaded::new(scene, warnings))
}
