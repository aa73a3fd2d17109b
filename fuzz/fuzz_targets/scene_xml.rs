//! Mitsuba/Sionna XML scenes: `parse_xml` (elements, `$defaults`, bsdfs, transforms, refs; no
//! file access). Errors are fine; a panic, an abort (huge allocation) or an accepted shape with
//! a non-finite or singular transform is a finding.
#![no_main]

use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    let Ok(text) = std::str::from_utf8(data) else {
        return;
    };
    let Ok(scene) = bt_import::xml::parse_xml(text, "fuzz.xml") else {
        return;
    };
    for shape in &scene.shapes {
        // Affine (last row 0 0 0 1): the 4×4 determinant is that of the linear part.
        assert!(shape.to_world.is_finite(), "{shape:?}");
        assert!(shape.to_world.determinant() != 0.0, "{shape:?}");
        // A mesh has a non-empty file name, a primitive (rectangle, cube) none.
        let primitive = matches!(shape.kind, bt_import::xml::MeshKind::Primitive(_));
        assert_eq!(
            shape.filename.as_deref().map(str::is_empty),
            (!primitive).then_some(false),
            "{shape:?}"
        );
    }
});
