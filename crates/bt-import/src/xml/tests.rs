//! The XML reader: every error names the element and its line; transforms compose in Mitsuba's
//! order (checked on hand-computed points); shapes never merge across each other.

use super::*;
use bt_geom::Vec3;
use bt_scene::Terminals;

fn err(xml: &str) -> String {
    parse_xml(xml, "t.xml").unwrap_err().to_string()
}

fn one_shape(transform: &str) -> DMat4 {
    let xml = format!(
        r#"<scene><shape type="ply"><string name="filename" value="a.ply"/><transform name="to_world">{transform}</transform></shape></scene>"#
    );
    parse_xml(&xml, "t.xml").unwrap().shapes[0].to_world
}

fn close(a: Vec3, b: Vec3) -> bool {
    (a - b).length() < 1e-12
}

/// Each document's error mentions every one of its needles.
fn assert_errors_mention(cases: &[(&str, &[&str])]) {
    for (xml, needles) in cases {
        let e = err(xml);
        for n in *needles {
            assert!(e.contains(n), "{n:?} not in: {e}");
        }
    }
}

#[test]
fn unsupported_elements_are_named_with_their_line() {
    let e = err(
        "<scene version=\"2.1.0\">\n  <bsdf type=\"diffuse\" id=\"a\"/>\n  <shapegroup id=\"g\"/>\n</scene>",
    );
    assert_eq!(
        e,
        "t.xml: line 3, column 3: unsupported element <shapegroup> in <scene>"
    );
    let sphere = "<scene>\n\n<shape type=\"sphere\"/></scene>";
    assert!(
        err(sphere).starts_with("t.xml: line 3, column 1: "),
        "{}",
        err(sphere)
    );
    assert_errors_mention(&[
        (sphere, &["<shape type=\"sphere\"> is not supported"]),
        (
            "<scene><shape type=\"ply\">\n <string name=\"filename\" value=\"a.ply\"/>\n <float name=\"radius\" value=\"2\"/></shape></scene>",
            &["line 3", "<float name=\"radius\">"],
        ),
        (
            "<scene><shape type=\"ply\"><string name=\"filename\" value=\"a.ply\"/><transform name=\"to_world\">\n<lookat origin=\"0 0 0\" target=\"1 0 0\"/></transform></shape></scene>",
            &["line 2", "<lookat>", "up"],
        ),
        (
            "<scene><shape type=\"ply\"><string name=\"filename\" value=\"a.ply\"/><transform name=\"to_world\">\n<lookat origin=\"0 0 0\" target=\"1 0 0\" up=\"2, 0, 0\"/></transform></shape></scene>",
            &["line 2", "<lookat> needs a target apart from the origin"],
        ),
        (
            "<scene><shape type=\"ply\"><string name=\"filename\" value=\"a.ply\"/><transform name=\"to_world\">\n<lookat origin=\"1 1 1\" target=\"1 1 1\" up=\"0 0 1\"/></transform></shape></scene>",
            &["line 2", "<lookat> needs a target apart from the origin"],
        ),
        (
            "<scene><shape type=\"ply\"><string name=\"filename\" value=\"a.ply\"/><transform name=\"to_world\">\n<lookat origin=\"1 1\" target=\"1 1 1\" up=\"0 0 1\"/></transform></shape></scene>",
            &["line 2", "origin= needs 3 numbers, got 2"],
        ),
        ("<mitsuba/>", &["expected <scene>"]),
        (
            "<scene>\n<shape type=\"ply\">\n</scene>",
            &["line 3", "not well-formed"],
        ),
        // A DTD is refused.
        (
            "<!DOCTYPE scene [<!ENTITY a \"b\">]><scene/>",
            &["not well-formed"],
        ),
    ]);
}

#[test]
fn references_and_properties_are_checked() {
    let e = err(
        "<scene>\n<shape type=\"obj\" id=\"w\">\n<string name=\"filename\" value=\"w.obj\"/>\n<ref id=\"nope\"/></shape></scene>",
    );
    assert_eq!(
        e,
        "t.xml: line 4, column 1: <shape id=\"w\"> refers to bsdf \"nope\", which the file does not define"
    );
    assert_errors_mention(&[
        (
            "<scene><shape type=\"obj\"/></scene>",
            &["needs <string name=\"filename\""],
        ),
        (
            "<scene><bsdf type=\"itu-radio-material\" id=\"m\">\n<string name=\"type\" value=\"cheese\"/></bsdf></scene>",
            &["line 1", "unknown ITU material \"cheese\""],
        ),
        (
            "<scene><bsdf type=\"radio-material\" id=\"m\"><float name=\"relative_permittivity\" value=\"-2\"/></bsdf></scene>",
            &["relative_permittivity"],
        ),
        (
            "<scene><bsdf type=\"itu-radio-material\" id=\"m\"/></scene>",
            &["needs <string name=\"type\""],
        ),
        (
            "<scene><bsdf type=\"diffuse\" id=\"m\"/><bsdf type=\"diffuse\" id=\"m\"/></scene>",
            &["defined twice"],
        ),
        (
            "<scene><bsdf type=\"itu-radio-material\" id=\"m\"><string name=\"type\" value=\"wood\"/><float name=\"thickness\" value=\"$t\"/></bsdf></scene>",
            &["undefined parameter $t"],
        ),
    ]);
}

#[test]
fn bsdfs_become_radio_materials_as_sionna_names_them() {
    let xml = r#"<scene>
        <default name="t" value="0.25"/>
        <bsdf type="itu-radio-material" id="a"><string name="type" value="very_dry_ground"/><float name="thickness" value="$t"/></bsdf>
        <bsdf type="itu-radio-material" id="b"><string name="type" value="itu_glass"/></bsdf>
        <bsdf type="radio-material" id="c"><float name="conductivity" value="2"/></bsdf>
        <bsdf type="twosided" id="mat-itu_metal"><bsdf type="diffuse"/></bsdf>
        <bsdf type="diffuse" id="paint"/>
    </scene>"#;
    let scene = parse_xml(xml, "t.xml").unwrap();
    let radio: Vec<&XmlRadio> = scene.bsdfs.iter().map(|b| &b.radio).collect();
    assert_eq!(
        radio[0],
        &XmlRadio::Itu {
            name: "very_dry_ground".into(),
            thickness_m: 0.25
        }
    );
    assert_eq!(
        radio[1],
        &XmlRadio::Itu {
            name: "itu_glass".into(),
            thickness_m: SIONNA_DEFAULT_THICKNESS_M
        }
    );
    assert_eq!(
        radio[2],
        &XmlRadio::Custom {
            relative_permittivity: 1.0,
            conductivity: 2.0,
            thickness_m: SIONNA_DEFAULT_THICKNESS_M
        }
    );
    let mut warnings = Vec::new();
    let m = materials(&scene, &mut warnings);
    assert_eq!(m["mat-itu_metal"].itu.as_deref(), Some("itu_metal"));
    assert_eq!(
        m["mat-itu_metal"].thickness, None,
        "Sionna 0.x: a half-space"
    );
    assert_eq!(
        m["paint"].itu.as_deref(),
        Some("concrete"),
        "the default's model"
    );
    assert_eq!(warnings.len(), 1);
    assert!(warnings[0].contains("\"paint\""), "{warnings:?}");
}

#[test]
fn transforms_compose_in_document_order() {
    let p = Vec3::new(1.0, 0.0, 0.0);
    // Rotate first, then translate: (1,0,0) -> (0,1,0) -> (1,1,0).
    let a = one_shape(r#"<rotate z="1" angle="90"/><translate x="1"/>"#);
    assert!(close(a.transform_point3(p), Vec3::new(1.0, 1.0, 0.0)));
    // Translate first, then rotate: (1,0,0) -> (2,0,0) -> (0,2,0).
    let b = one_shape(r#"<translate value="1, 0, 0"/><rotate value="0 0 1" angle="90"/>"#);
    assert!(close(b.transform_point3(p), Vec3::new(0.0, 2.0, 0.0)));
    // A matrix is read row by row: the last column is the translation.
    let m = one_shape(r#"<matrix value="1 0 0 5  0 1 0 6  0 0 1 7  0 0 0 1"/>"#);
    assert!(close(
        m.transform_point3(Vec3::ZERO),
        Vec3::new(5.0, 6.0, 7.0)
    ));
    let s = one_shape(r#"<scale value="2"/><scale y="3"/>"#);
    assert!(close(
        s.transform_point3(Vec3::ONE),
        Vec3::new(2.0, 6.0, 2.0)
    ));
    // Right-handed: +90 degrees about x takes +y to +z.
    let r = one_shape(r#"<rotate x="1" angle="90"/>"#);
    assert!(close(r.transform_point3(Vec3::Y), Vec3::Z));
    let e = err(
        r#"<scene><shape type="ply"><string name="filename" value="a.ply"/><transform name="to_world"><scale z="0"/></transform></shape></scene>"#,
    );
    assert!(e.contains("singular"), "{e}");
    let e = err(
        r#"<scene><shape type="ply"><string name="filename" value="a.ply"/><transform name="to_world"><matrix value="1 2 3"/></transform></shape></scene>"#,
    );
    assert!(e.contains("16 or 9 numbers, got 3"), "{e}");
    let e = err(
        r#"<scene><shape type="ply"><string name="filename" value="a.ply"/><transform name="to_world"><rotate angle="10"/></transform></shape></scene>"#,
    );
    assert!(e.contains("axis"), "{e}");
}

#[test]
fn counts_are_bounded() {
    let shape = r#"<shape type="ply"><string name="filename" value="a.ply"/></shape>"#;
    let xml = format!("<scene>{}</scene>", shape.repeat(MAX_XML_SHAPES + 1));
    let e = err(&xml);
    assert!(
        e.contains(&format!("more than {MAX_XML_SHAPES} shapes")),
        "{e}"
    );
}

#[test]
fn file_names_stay_under_the_xml_folder() {
    let folder = Path::new("/data/scenes");
    assert_eq!(
        resolve(folder, "meshes/a.ply").unwrap(),
        Path::new("/data/scenes/meshes/a.ply")
    );
    assert!(resolve(folder, "../secret.ply").unwrap_err().contains(".."));
    assert!(resolve(folder, "meshes/../../x.ply").is_err());
    assert!(
        resolve(folder, "/etc/x.ply")
            .unwrap_err()
            .contains("absolute")
    );
    assert!(resolve(folder, "").is_err());
}

/// A scratch folder with an XML scene and its meshes.
fn scratch(name: &str, files: &[(&str, &str)]) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("bt-xml-{name}-{}", std::process::id()));
    std::fs::create_dir_all(dir.join("meshes")).unwrap();
    for (file, text) in files {
        std::fs::write(dir.join(file), text).unwrap();
    }
    dir
}

const HALF_FLOOR: &str = "o half\nv 0 0 0\nv 2 0 0\nv 2 2 0\nv 0 2 0\nf 1 2 3 4\n";

fn options() -> LoadOptions {
    LoadOptions {
        terminals: Terminals {
            tx: Some(Vec3::new(1.0, 1.0, 1.0)),
            rx: Some(Vec3::new(3.0, 1.5, 1.5)),
        },
        ..LoadOptions::default()
    }
}

#[test]
fn shapes_never_merge_even_when_coplanar_and_adjacent() {
    // Two halves of one floor, edge to edge in one plane, with different materials.
    let xml = r#"<scene>
        <bsdf type="itu-radio-material" id="wood"><string name="type" value="wood"/></bsdf>
        <bsdf type="itu-radio-material" id="stone"><string name="type" value="marble"/></bsdf>
        <shape type="obj" id="left"><string name="filename" value="meshes/half.obj"/><ref id="wood"/></shape>
        <shape type="obj" id="right"><string name="filename" value="meshes/half.obj"/>
            <transform name="to_world"><translate x="2"/></transform><ref id="stone"/></shape>
    </scene>"#;
    let dir = scratch("merge", &[("s.xml", xml), ("meshes/half.obj", HALF_FLOOR)]);
    let loaded = load_xml(&dir.join("s.xml"), &options()).unwrap();
    let s = &loaded.scene;
    let names: Vec<(&str, &str)> = s
        .surfaces()
        .iter()
        .map(|f| (f.name.as_str(), f.material.as_str()))
        .collect();
    assert_eq!(names, [("left.half_0", "wood"), ("right.half_0", "stone")]);
    let right = &s.surfaces()[1];
    assert!(right.polygon.vertices().iter().all(|v| v.x >= 2.0 - 1e-12));
    assert!(s.materials()["stone"].radio.is_some());
    // The files read: the mesh once, though two shapes name it; through `load`, the XML first.
    let mesh = dir.join("meshes/half.obj");
    assert_eq!(loaded.sources, std::slice::from_ref(&mesh));
    let xml_path = dir.join("s.xml");
    let through_load = crate::load(xml_path.to_str().unwrap(), &options()).unwrap();
    assert_eq!(through_load.sources, [xml_path, mesh]);
    std::fs::remove_dir_all(dir).ok();
}

#[test]
fn missing_files_are_clear_errors() {
    let xml = "<scene>\n<shape type=\"ply\" id=\"gone\"><string name=\"filename\" value=\"meshes/nowhere.ply\"/></shape></scene>";
    let dir = scratch("missing", &[("s.xml", xml)]);
    let e = load_xml(&dir.join("s.xml"), &options())
        .unwrap_err()
        .to_string();
    assert!(
        e.contains("line 2") && e.contains("gone") && e.contains("nowhere.ply"),
        "{e}"
    );
    // Without terminals the missing mesh is still the error: the terminals are not required.
    let e = load_xml(&dir.join("s.xml"), &LoadOptions::default())
        .unwrap_err()
        .to_string();
    assert!(e.contains("nowhere.ply"), "{e}");
    let escape =
        "<scene><shape type=\"ply\"><string name=\"filename\" value=\"../s.xml\"/></shape></scene>";
    std::fs::write(dir.join("escape.xml"), escape).unwrap();
    let e = load_xml(&dir.join("escape.xml"), &options())
        .unwrap_err()
        .to_string();
    assert!(e.contains("must stay under the XML's folder"), "{e}");
    std::fs::remove_dir_all(dir).ok();
}

#[test]
fn xml_without_terminals_loads_as_bare_geometry() {
    let xml = r#"<scene><shape type="obj" id="floor"><string name="filename" value="meshes/half.obj"/></shape></scene>"#;
    let dir = scratch("bare", &[("s.xml", xml), ("meshes/half.obj", HALF_FLOOR)]);
    let scene = load_xml(&dir.join("s.xml"), &LoadOptions::default())
        .unwrap()
        .scene;
    assert_eq!((scene.tx(), scene.rx()), (None, None));
    assert!(
        (scene.extent() - 8.0_f64.sqrt()).abs() < 1e-12,
        "{}",
        scene.extent()
    );
    let e = scene.terminals().unwrap_err();
    assert!(
        matches!(&e, bt_scene::SceneError::MissingTerminal { missing, .. }
            if missing == &[bt_scene::Terminal::Tx, bt_scene::Terminal::Rx]),
        "{e}"
    );
    let placed = scene
        .with_terminals(Vec3::new(1.0, 1.0, 1.0), Vec3::new(3.0, 1.5, 1.5))
        .unwrap();
    let loaded = load_xml(&dir.join("s.xml"), &options()).unwrap().scene;
    assert_eq!(placed.terminals().unwrap(), loaded.terminals().unwrap());
    assert_eq!(placed.extent(), loaded.extent());
    std::fs::remove_dir_all(dir).ok();
}

/// Ten `<default>`s, each ten copies of the one before: 10^10 bytes from a ~1 kB file.
fn default_bomb(levels: usize) -> String {
    let mut xml = String::from("<scene>\n<default name=\"d0\" value=\"xxxxxxxxxx\"/>\n");
    for k in 1..=levels {
        let value = format!("${}", k - 1).replace('$', "$d").repeat(10);
        xml.push_str(&format!("<default name=\"d{k}\" value=\"{value}\"/>\n"));
    }
    xml.push_str("</scene>\n");
    xml
}

#[test]
fn defaults_that_expand_each_other_stop_at_the_substitution_budget() {
    let xml = default_bomb(10);
    assert!(xml.len() < 2000, "{}", xml.len());
    let e = err(&xml);
    assert!(e.contains("substituted bytes budget exceeded"), "{e}");
    assert!(e.contains("--max-xml-substitution"), "{e}");
    assert!(
        e.contains("line 9"),
        "the first default over the budget: {e}"
    );
    // Three levels (100 + 1,000 + 10,000 bytes substituted) fit the default budget, not a
    // budget of 11,099 bytes.
    let small = default_bomb(3);
    assert!(parse_xml(&small, "t.xml").is_ok());
    assert!(parse_xml_with(&small, "t.xml", 11_100).is_ok());
    let e = parse_xml_with(&small, "t.xml", 11_099).unwrap_err();
    assert!(
        e.to_string().contains("more than the budget of 11099"),
        "{e}"
    );
}

mod substitution {
    use super::super::parse_xml_with;
    use proptest::prelude::*;

    /// A default's value: literal text and references to earlier defaults (indices below
    /// its own), as (literal length, reference) pieces.
    fn document() -> impl Strategy<Value = Vec<Vec<(usize, Option<usize>)>>> {
        prop::collection::vec(
            prop::collection::vec((0usize..8, prop::option::of(0usize..64)), 0..12),
            1..24,
        )
    }

    /// The XML of `defaults` and the bytes its substitutions produce (saturating).
    fn render(defaults: &[Vec<(usize, Option<usize>)>]) -> (String, u64) {
        let mut xml = String::from("<scene>");
        let mut lengths: Vec<u64> = Vec::new();
        let mut substituted = 0u64;
        for (k, pieces) in defaults.iter().enumerate() {
            let mut value = String::new();
            let mut length = 0u64;
            for (literal, reference) in pieces {
                value.push_str(&"a".repeat(*literal));
                length = length.saturating_add(*literal as u64);
                if let Some(r) = reference.filter(|_| k > 0).map(|r| r % k) {
                    // '-' ends the name ('_' would continue it).
                    value.push_str(&format!("$d{r}-"));
                    length = length.saturating_add(lengths[r]).saturating_add(1);
                    substituted = substituted.saturating_add(lengths[r]);
                }
            }
            lengths.push(length);
            xml.push_str(&format!("<default name=\"d{k}\" value=\"{value}\"/>"));
        }
        xml.push_str("</scene>");
        (xml, substituted)
    }

    proptest! {
        #![proptest_config(ProptestConfig::with_cases(256))]

        /// Random nestings of defaults: the parse succeeds exactly when the bytes substituted
        /// fit the budget, otherwise it names the option; it never panics, and it never copies
        /// more than the budget (a refused document stops before its over-budget copy).
        #[test]
        fn nested_defaults_never_exceed_the_budget(
            defaults in document(),
            budget in 0u64..200_000,
        ) {
            let (xml, substituted) = render(&defaults);
            match parse_xml_with(&xml, "t.xml", budget) {
                Ok(_) => prop_assert!(substituted <= budget),
                Err(e) => {
                    prop_assert!(substituted > budget, "{e}");
                    prop_assert!(e.to_string().contains("--max-xml-substitution"), "{e}");
                }
            }
        }
    }
}

#[test]
fn the_mesh_budget_holds_for_all_shapes_of_a_scene() {
    // Three shapes of one 4-vertex mesh: 12 vertices in all.
    let shape = |id: &str, z: u32| {
        format!(
            r#"<shape type="obj" id="{id}"><string name="filename" value="meshes/half.obj"/><transform name="to_world"><translate z="{z}"/></transform></shape>"#
        )
    };
    let xml = format!(
        "<scene>\n{}\n{}\n{}\n</scene>",
        shape("a", 0),
        shape("b", 5),
        shape("c", 6)
    );
    let dir = scratch(
        "scene-budget",
        &[("s.xml", &xml), ("meshes/half.obj", HALF_FLOOR)],
    );
    let with_budget = |max_elements| LoadOptions {
        merge: bt_mesh::MergeOptions {
            max_elements,
            ..bt_mesh::MergeOptions::default()
        },
        ..options()
    };
    let loaded = load_xml(&dir.join("s.xml"), &with_budget(12));
    assert!(loaded.is_ok(), "{:?}", loaded.err());
    // Each file fits a budget of 11; the scene does not.
    let e = load_xml(&dir.join("s.xml"), &with_budget(11))
        .unwrap_err()
        .to_string();
    assert!(
        e.contains("line 4") && e.contains("<shape id=\"c\">"),
        "{e}"
    );
    assert!(e.contains("hold at least 12 vertices"), "{e}");
    assert!(
        e.contains("budget of 11 vertices for the whole scene"),
        "{e}"
    );
    assert!(e.contains("--max-mesh-elements"), "{e}");
    // A mesh file over the byte budget is refused from its size.
    let tiny = LoadOptions {
        max_file_bytes: 10,
        ..options()
    };
    let e = load_xml(&dir.join("s.xml"), &tiny).unwrap_err().to_string();
    assert!(e.contains("--max-file-bytes"), "{e}");
    std::fs::remove_dir_all(dir).ok();
}

/// `f` run on a rayon pool of `threads` threads.
fn on_threads<T: Send>(threads: usize, f: impl FnOnce() -> T + Send) -> T {
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(threads)
        .build()
        .unwrap();
    pool.install(f)
}

#[test]
fn meshes_merged_in_parallel_give_the_scene_of_one_thread() {
    // Etoile: 565 shapes, merged largest first on all cores.
    let xml = Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../../testdata/scenes/sionna-rt/etoile/etoile.xml");
    let load = || load_xml(&xml, &LoadOptions::default()).unwrap();
    let one = on_threads(1, load);
    let three = on_threads(3, load);
    assert!(one.scene.surfaces().len() > 1000);
    assert_eq!(one.scene.surfaces(), three.scene.surfaces());
    assert_eq!(one.scene.materials(), three.scene.materials());
    assert_eq!(one.warnings, three.warnings);
    assert_eq!(one.sources, three.sources);
}

#[test]
fn the_first_problem_in_document_order_is_reported_whatever_the_threads() {
    // 300 shapes; shape 5 reads a broken mesh, shapes 7 and 290 name missing
    // files: the broken mesh comes first in the document, so it is the error, though the
    // missing files are found before any mesh is read.
    let shapes: String = (0..300)
        .map(|k| {
            let file = match k {
                5 => "meshes/broken.obj",
                7 | 290 => "meshes/nowhere.obj",
                _ => "meshes/half.obj",
            };
            format!(
                "<shape type=\"obj\" id=\"s{k}\"><string name=\"filename\" value=\"{file}\"/></shape>\n"
            )
        })
        .collect();
    let xml = format!("<scene>\n{shapes}</scene>");
    let dir = scratch(
        "order",
        &[
            ("s.xml", &xml),
            ("meshes/half.obj", HALF_FLOOR),
            ("meshes/broken.obj", "v 0 0 0\nf 1 2 3\n"),
        ],
    );
    for threads in [1, 3] {
        let e = on_threads(threads, || load_xml(&dir.join("s.xml"), &options()))
            .unwrap_err()
            .to_string();
        assert!(e.contains("broken.obj") && !e.contains("nowhere"), "{e}");
    }
    // Without the broken mesh, the first missing file (shape 7, line 9) is the error.
    std::fs::write(dir.join("meshes/broken.obj"), HALF_FLOOR).unwrap();
    for threads in [1, 3] {
        let e = on_threads(threads, || load_xml(&dir.join("s.xml"), &options()))
            .unwrap_err()
            .to_string();
        assert!(e.contains("line 9") && e.contains("\"s7\""), "{e}");
    }
    std::fs::remove_dir_all(dir).ok();
}

#[test]
fn rounds_hold_at_most_their_bytes_and_a_larger_file_alone() {
    let lengths = |sizes: &[u64]| -> Vec<Vec<u64>> {
        rounds(sizes, 10, |&s| s).map(<[u64]>::to_vec).collect()
    };
    assert_eq!(lengths(&[]), Vec::<Vec<u64>>::new());
    assert_eq!(lengths(&[3, 3, 4, 1]), [vec![3, 3, 4], vec![1]]);
    assert_eq!(lengths(&[25, 2, 30]), [vec![25], vec![2], vec![30]]);
    assert_eq!(lengths(&[0, 0, 10, 0]), [vec![0, 0, 10, 0]]);
    assert_eq!(lengths(&[u64::MAX, 1]), [vec![u64::MAX], vec![1]]);
}

#[test]
fn rectangles_and_cubes_are_mitsubas_squares_and_cubes_through_their_transform() {
    // A 4 m × 6 m floor at z = 0.5 (scale 2 × 3, then up), and a 2 m cube turned 90° about z
    // and moved to (10, 0, 1): Mitsuba's rectangle is [-1, 1]² at z = 0, its cube [-1, 1]³.
    let xml = r#"<scene>
        <bsdf type="itu-radio-material" id="stone"><string name="type" value="marble"/></bsdf>
        <shape type="rectangle" id="floor"><ref id="stone"/><boolean name="flip_normals" value="true"/>
            <transform name="to_world"><scale x="2" y="3"/><translate z="0.5"/></transform></shape>
        <shape type="cube" id="box"><ref id="stone"/>
            <transform name="to_world"><rotate z="1" angle="90"/><translate x="10" z="1"/></transform></shape>
    </scene>"#;
    let dir = scratch("primitives", &[("s.xml", xml)]);
    let loaded = load_xml(&dir.join("s.xml"), &LoadOptions::default()).unwrap();
    let surfaces = loaded.scene.surfaces();
    assert_eq!(surfaces.len(), 7);
    let floor = &surfaces[0];
    assert_eq!(
        (floor.name.as_str(), floor.material.as_str()),
        ("floor.face_0", "stone")
    );
    let corners: Vec<Vec3> = floor.polygon.vertices().to_vec();
    for expected in [(-2.0, -3.0), (2.0, -3.0), (2.0, 3.0), (-2.0, 3.0)] {
        let p = Vec3::new(expected.0, expected.1, 0.5);
        assert!(
            corners.iter().any(|&c| close(c, p)),
            "{p} not in {corners:?}"
        );
    }
    assert!((floor.polygon.area() - 24.0).abs() < 1e-12);
    // The cube: six 4 m² faces, every corner at x = 9 or 11, |y| = 1, z = 0 or 2.
    let faces = &surfaces[1..];
    assert!(faces.iter().all(|f| f.name.starts_with("box.")));
    assert!(faces.iter().all(|f| (f.polygon.area() - 4.0).abs() < 1e-12));
    for c in faces.iter().flat_map(|f| f.polygon.vertices()) {
        let near = |v: f64, a: f64| (v - a).abs() < 1e-12;
        assert!(
            (near(c.x, 9.0) || near(c.x, 11.0)) && near(c.y.abs(), 1.0),
            "{c}"
        );
        assert!(near(c.z, 0.0) || near(c.z, 2.0), "{c}");
    }
    // No file is read for either, and neither is a source of the scene.
    assert!(loaded.sources.is_empty());
    std::fs::remove_dir_all(dir).ok();
}

#[test]
fn a_primitive_takes_no_filename_and_a_mesh_needs_one() {
    assert_errors_mention(&[
        (
            "<scene><shape type=\"rectangle\">\n<string name=\"filename\" value=\"a.ply\"/></shape></scene>",
            &["line 2", "has no filename"],
        ),
        (
            "<scene>\n<shape type=\"cube\" id=\"c\"><string name=\"filename\" value=\"a.ply\"/></shape></scene>",
            &["line 2", "has no filename"],
        ),
        (
            "<scene>\n<shape type=\"obj\"/></scene>",
            &["line 2", "needs <string name=\"filename\""],
        ),
        (
            "<scene><shape type=\"disk\"/></scene>",
            &[
                "<shape type=\"disk\"> is not supported",
                "rectangle and cube",
            ],
        ),
    ]);
    let kinds: Vec<MeshKind> = parse_xml(
        "<scene><shape type=\"rectangle\"/><shape type=\"cube\"/></scene>",
        "t.xml",
    )
    .unwrap()
    .shapes
    .iter()
    .map(|s| s.kind)
    .collect();
    assert_eq!(
        kinds,
        [
            MeshKind::Primitive(Primitive::Rectangle),
            MeshKind::Primitive(Primitive::Cube)
        ]
    );
}

#[test]
fn lookat_turns_z_towards_the_target_as_mitsuba_does() {
    // Towards +x with +z up: the object's x goes to +y (up × dir), its y to +z, its z to +x,
    // its origin to (1, 2, 3); then a translation listed after it moves the result.
    let m =
        one_shape(r#"<lookat origin="1, 2, 3" target="5, 2, 3" up="0, 0, 7"/><translate x="10"/>"#);
    for (local, world) in [
        (Vec3::ZERO, Vec3::new(11.0, 2.0, 3.0)),
        (Vec3::X, Vec3::new(11.0, 3.0, 3.0)),
        (Vec3::Y, Vec3::new(11.0, 2.0, 4.0)),
        (Vec3::Z, Vec3::new(12.0, 2.0, 3.0)),
    ] {
        assert!(
            close(m.transform_point3(local), world),
            "{local} -> {}",
            m.transform_point3(local)
        );
    }
}

#[cfg(unix)]
#[test]
fn a_path_is_shown_as_display_shows_it() {
    use std::os::unix::ffi::OsStrExt;
    let odd = std::ffi::OsStr::from_bytes(b"meshes/caf\xe9 \xff.ply");
    for path in [
        Path::new("meshes/Terrain.ply"),
        Path::new("m/ä b.ply"),
        Path::new(odd),
    ] {
        assert_eq!(shown_path(path), path.display().to_string());
    }
}
