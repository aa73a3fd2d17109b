//! Writers and readers agree: every format reads back the cloud it was given, ASCII and
//! binary encodings give the same cloud, and files from other writers (ply-rs, PCL-style
//! hand-written files) are read.

use std::io::Cursor;
use std::path::Path;

use bt_import::cloud::{
    NonFinitePolicy, PcdData, PlyFormat, ReadOptions, parse_any, parse_pcd, parse_ply, read_path,
    read_ply, write_path, write_pcd, write_ply,
};
use bt_pointcloud::PointCloud;
use bt_pointcloud::sample_polygons;
use glam::DVec3;

fn sample() -> PointCloud {
    let sq = vec![
        DVec3::ZERO,
        DVec3::new(1.0, 0.0, 0.0),
        DVec3::new(1.0, 0.0, 1.0),
        DVec3::new(0.0, 0.0, 1.0),
    ];
    let tilted = vec![
        DVec3::new(0.0, 0.0, 0.0),
        DVec3::new(0.5, 0.5, 0.1),
        DVec3::new(0.1, 0.7, 0.9),
    ];
    sample_polygons(&[sq, tilted], 300.0, 0.003, 42)
}

fn without_normals(c: &PointCloud) -> PointCloud {
    PointCloud::new(c.points().to_vec()).unwrap()
}

fn ply_bytes(c: &PointCloud, f: PlyFormat) -> Vec<u8> {
    let mut v = Vec::new();
    write_ply(c, &mut v, f).unwrap();
    v
}

fn pcd_bytes(c: &PointCloud, d: PcdData) -> Vec<u8> {
    let mut v = Vec::new();
    write_pcd(c, &mut v, d).unwrap();
    v
}

#[test]
fn ply_round_trips_in_every_encoding() {
    for cloud in [sample(), without_normals(&sample())] {
        for f in [
            PlyFormat::Ascii,
            PlyFormat::BinaryLittleEndian,
            PlyFormat::BinaryBigEndian,
        ] {
            let back = parse_ply(&ply_bytes(&cloud, f), &ReadOptions::default()).unwrap();
            assert_eq!(back.cloud, cloud, "{f:?}");
            assert_eq!(back.skipped_non_finite, 0);
        }
    }
}

#[test]
fn pcd_round_trips_in_both_encodings() {
    for cloud in [sample(), without_normals(&sample())] {
        let a = parse_pcd(&pcd_bytes(&cloud, PcdData::Ascii), &ReadOptions::default()).unwrap();
        let b = parse_pcd(&pcd_bytes(&cloud, PcdData::Binary), &ReadOptions::default()).unwrap();
        assert_eq!(a.cloud, cloud);
        assert_eq!(b.cloud, cloud);
    }
}

#[test]
fn ascii_and_binary_ply_and_pcd_give_the_same_cloud() {
    let c = sample();
    let clouds: Vec<PointCloud> = [
        ply_bytes(&c, PlyFormat::Ascii),
        ply_bytes(&c, PlyFormat::BinaryLittleEndian),
        ply_bytes(&c, PlyFormat::BinaryBigEndian),
        pcd_bytes(&c, PcdData::Ascii),
        pcd_bytes(&c, PcdData::Binary),
    ]
    .iter()
    .map(|b| parse_any(b, &ReadOptions::default()).unwrap().cloud)
    .collect();
    assert!(clouds.windows(2).all(|w| w[0] == w[1]));
}

#[test]
fn reads_float32_ply_written_by_ply_rs() {
    use ply_rs::ply::{
        Addable, DefaultElement, ElementDef, Encoding, Ply, Property, PropertyDef, PropertyType,
        ScalarType,
    };
    use ply_rs::writer::Writer;
    let c = sample();
    for enc in [
        Encoding::Ascii,
        Encoding::BinaryLittleEndian,
        Encoding::BinaryBigEndian,
    ] {
        let mut ply = Ply::<DefaultElement>::new();
        ply.header.encoding = enc;
        let mut el = ElementDef::new("vertex".to_string());
        for name in ["x", "y", "z", "intensity"] {
            el.properties.add(PropertyDef::new(
                name.to_string(),
                PropertyType::Scalar(ScalarType::Float),
            ));
        }
        ply.header.elements.add(el);
        let verts: Vec<DefaultElement> = c
            .points()
            .iter()
            .map(|p| {
                let mut e = DefaultElement::new();
                e.insert("x".into(), Property::Float(p.x as f32));
                e.insert("y".into(), Property::Float(p.y as f32));
                e.insert("z".into(), Property::Float(p.z as f32));
                e.insert("intensity".into(), Property::Float(0.5));
                e
            })
            .collect();
        ply.payload.insert("vertex".to_string(), verts);
        let mut buf = Vec::new();
        Writer::new().write_ply(&mut buf, &mut ply).unwrap();
        let back = read_ply(Cursor::new(buf), &ReadOptions::default())
            .unwrap()
            .cloud;
        assert_eq!(back.len(), c.len());
        assert!(back.normals().is_none());
        for (a, b) in back.points().iter().zip(c.points()) {
            assert_eq!(*a, b.as_vec3().as_dvec3(), "{enc:?}");
        }
    }
}

#[test]
fn reads_hand_written_files_from_testdata() {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("testdata");
    let pcd = read_path(&dir.join("organised_rgb_nan.pcd"), &ReadOptions::default()).unwrap();
    assert_eq!(pcd.cloud.len(), 5);
    assert_eq!(pcd.skipped_non_finite, 1);
    assert_eq!(pcd.cloud.points()[4], DVec3::new(2.5, -1.25, 3.0));
    assert_eq!(pcd.cloud.normals().unwrap()[4], DVec3::Y);
    let err = read_path(
        &dir.join("organised_rgb_nan.pcd"),
        &ReadOptions {
            non_finite: NonFinitePolicy::Reject,
            ..ReadOptions::default()
        },
    )
    .unwrap_err();
    let msg = err.to_string();
    assert!(
        msg.contains("organised_rgb_nan.pcd") && msg.contains("line 14"),
        "{msg}"
    );

    let ply = read_path(&dir.join("mesh_crlf.ply"), &ReadOptions::default()).unwrap();
    assert_eq!(
        ply.cloud.points(),
        &[
            DVec3::new(0.0, 0.0, 0.0),
            DVec3::new(1.0, 0.0, 0.0),
            DVec3::new(1.0, 1.0, 0.0),
            DVec3::new(0.0, 1.0, 0.25)
        ]
    );
}

#[test]
fn write_path_then_read_path() {
    let dir = std::env::temp_dir().join(format!("bt-pointcloud-test-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let c = sample();
    for name in ["a.ply", "a.pcd"] {
        let p = dir.join(name);
        write_path(&c, &p).unwrap();
        assert_eq!(read_path(&p, &ReadOptions::default()).unwrap().cloud, c);
    }
    let _ = std::fs::remove_dir_all(&dir);
}
