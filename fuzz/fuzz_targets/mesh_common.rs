//! Checks shared by the mesh targets: an accepted mesh has only finite, non-degenerate
//! surfaces, and turning it into a scene (as `beamtrace trace room.obj --tx .. --rx ..` does)
//! does not panic either.

use bt_import::LoadOptions;
use bt_import::mesh::MeshError;
use bt_import::mesh::scene::from_mesh;
use bt_mesh::MeshImport;
use bt_scene::{Terminals, Vec3};

pub fn check(result: Result<MeshImport, MeshError>) {
    let Ok(import) = result else {
        return;
    };
    for s in &import.surfaces {
        assert!(s.vertices.len() >= 3, "{s:?}");
        assert!(s.vertices.iter().all(|v| v.is_finite()), "{s:?}");
        assert!(
            s.normal.is_finite() && (s.normal.length() - 1.0).abs() < 1e-6,
            "{s:?}"
        );
        assert!(s.area_m2.is_finite() && s.area_m2 > 0.0, "{s:?}");
    }
    let options = LoadOptions {
        terminals: Terminals {
            tx: Some(Vec3::new(0.25, 0.5, 1.0)),
            rx: Some(Vec3::new(0.75, 0.25, 1.5)),
        },
        ..LoadOptions::default()
    };
    let _ = from_mesh(import, "fuzz", "fuzz", &options);
}
