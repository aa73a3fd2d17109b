//! Malformed input gives the expected error variant, with a useful message, and never a
//! panic or a huge allocation.

use bt_import::cloud::CloudError as E;
use bt_import::cloud::{
    NonFinitePolicy, PcdData, PlyFormat, ReadOptions, parse_any, parse_pcd, parse_ply, write_pcd,
    write_ply,
};
use bt_pointcloud::{PointCloud, sample_polygons};
use glam::DVec3;
use proptest::prelude::*;

fn cloud() -> PointCloud {
    let sq = vec![DVec3::ZERO, DVec3::X, DVec3::new(1.0, 1.0, 0.0), DVec3::Y];
    sample_polygons(&[sq], 50.0, 0.0, 1)
}

fn ply(f: PlyFormat) -> Vec<u8> {
    let mut v = Vec::new();
    write_ply(&cloud(), &mut v, f).unwrap();
    v
}

fn pcd(d: PcdData) -> Vec<u8> {
    let mut v = Vec::new();
    write_pcd(&cloud(), &mut v, d).unwrap();
    v
}

const OPTS: ReadOptions = ReadOptions {
    non_finite: NonFinitePolicy::Skip,
    max_points: bt_import::cloud::DEFAULT_MAX_POINTS,
    max_file_bytes: bt_import::MAX_FILE_BYTES.limit,
};

#[test]
fn truncated_binary_ply_and_pcd() {
    for b in [
        ply(PlyFormat::BinaryLittleEndian),
        ply(PlyFormat::BinaryBigEndian),
    ] {
        let cut = &b[..b.len() - 5];
        match parse_ply(cut, &OPTS) {
            Err(e @ E::Truncated { expected: 50, .. }) => {
                assert!(e.to_string().contains("point 49"), "{e}")
            }
            other => panic!("{other:?}"),
        }
    }
    let a = pcd(PcdData::Ascii);
    let text = String::from_utf8(a).unwrap();
    let cut: String = text
        .lines()
        .take(text.lines().count() - 3)
        .map(|l| format!("{l}\n"))
        .collect();
    match parse_pcd(cut.as_bytes(), &OPTS) {
        Err(e @ E::Truncated { expected: 50, .. }) => {
            assert!(e.to_string().contains("point 47"), "{e}")
        }
        other => panic!("{other:?}"),
    }
    let b = pcd(PcdData::Binary);
    assert!(
        matches!(parse_pcd(&b[..b.len() - 1], &OPTS), Err(E::Truncated { at, .. }) if at.element == 49)
    );
}

#[test]
fn truncated_ascii_ply_names_the_line() {
    let text = String::from_utf8(ply(PlyFormat::Ascii)).unwrap();
    // Drop the last two points but keep enough bytes that the count check passes.
    let mut lines: Vec<&str> = text.lines().collect();
    lines.truncate(lines.len() - 2);
    let padded = format!("{}\n", lines.join("\n"));
    match parse_ply(padded.as_bytes(), &OPTS) {
        Err(e @ E::Truncated { .. }) => assert!(e.to_string().contains("line"), "{e}"),
        other => panic!("{other:?}"),
    }
}

#[test]
fn bad_headers() {
    let cases: &[&[u8]] = &[
        b"plx\nformat ascii 1.0\nend_header\n",
        b"ply\nformat ascii 2.0\nend_header\n",
        b"ply\nformat ascii 1.0\nelement vertex -3\nend_header\n",
        b"ply\nformat ascii 1.0\nproperty float x\nend_header\n",
        b"ply\nformat ascii 1.0\nelement vertex 1\nproperty quad x\nend_header\n",
        b"ply\nformat ascii 1.0\nelement vertex 1\nproperty float x\n",
        b"ply\nelement vertex 1\nproperty float x\nproperty float y\nproperty float z\nend_header\n0 0 0\n",
    ];
    let e = parse_ply(cases[4], &OPTS).unwrap_err();
    assert!(e.to_string().contains("line 4"), "{e}");
    let pcd_cases: &[&[u8]] = &[
        b"VERSION 0.7\nFIELDS x y z\nSIZE 4 4\nTYPE F F F\nWIDTH 1\nPOINTS 1\nDATA ascii\n0 0 0\n",
        b"VERSION 0.7\nFIELDS x y z\nSIZE 4 4 4\nTYPE F F Q\nWIDTH 1\nPOINTS 1\nDATA ascii\n0 0 0\n",
        b"VERSION 0.7\nFIELDS x y z\nSIZE 4 4 3\nTYPE F F F\nWIDTH 1\nPOINTS 1\nDATA ascii\n0 0 0\n",
        b"VERSION 0.7\nFIELDS x y z\nSIZE 4 4 4\nTYPE F F F\nWIDTH 2\nHEIGHT 1\nPOINTS 1\nDATA ascii\n0 0 0\n",
        b"VERSION 0.7\nFIELDS x y z\nSIZE 4 4 4\nTYPE F F F\nWIDTH 1\nPOINTS 1\n",
    ];
    // Every case of both formats is a header error (numbered from 0 per format).
    let ply = cases
        .iter()
        .enumerate()
        .map(|(k, c)| ("ply", k, parse_ply(c, &OPTS)));
    let pcd = pcd_cases
        .iter()
        .enumerate()
        .map(|(k, c)| ("pcd", k, parse_pcd(c, &OPTS)));
    for (format, k, parsed) in ply.chain(pcd) {
        assert!(
            matches!(parsed, Err(E::Header { .. })),
            "{format} case {k}: {parsed:?}"
        );
    }
    assert!(matches!(
        parse_any(b"hello", &OPTS),
        Err(E::UnknownFormat { .. })
    ));
}

#[test]
fn absurd_counts_are_rejected_before_allocating() {
    let ply_le = b"ply\nformat binary_little_endian 1.0\nelement vertex 3000000000\nproperty float x\nproperty float y\nproperty float z\nend_header\n";
    let mut f = ply_le.to_vec();
    f.extend(std::iter::repeat_n(0u8, 1024));
    match parse_ply(&f, &OPTS) {
        Err(
            e @ E::CountExceedsData {
                claimed: 3_000_000_000,
                available: 1024,
                ..
            },
        ) => {
            assert!(e.to_string().contains("3000000000"), "{e}")
        }
        other => panic!("{other:?}"),
    }
    // Claim hidden in an element before the vertices.
    let pre = b"ply\nformat ascii 1.0\nelement junk 18446744073709551615\nproperty uchar a\nelement vertex 1\nproperty float x\nproperty float y\nproperty float z\nend_header\n0 0 0\n";
    assert!(matches!(
        parse_ply(pre, &OPTS),
        Err(E::CountExceedsData { .. })
    ));
    let pcd = b"VERSION 0.7\nFIELDS x y z\nSIZE 4 4 4\nTYPE F F F\nWIDTH 4000000000\nHEIGHT 4000000000\nDATA binary\n\0\0\0\0";
    assert!(matches!(
        parse_pcd(pcd, &OPTS),
        Err(E::CountExceedsData { .. } | E::Header { .. })
    ));
    let pcd = b"VERSION 0.7\nFIELDS x y z\nSIZE 4 4 4\nTYPE F F F\nWIDTH 3000000000\nHEIGHT 1\nPOINTS 3000000000\nDATA ascii\n0 0 0\n";
    assert!(matches!(
        parse_pcd(pcd, &OPTS),
        Err(E::CountExceedsData {
            claimed: 3_000_000_000,
            ..
        })
    ));
}

#[test]
fn missing_coordinate_fields() {
    let p = b"ply\nformat ascii 1.0\nelement vertex 1\nproperty float x\nproperty float z\nend_header\n0 0\n";
    match parse_ply(p, &OPTS) {
        Err(E::MissingField { field, .. }) => assert_eq!(field, "y"),
        other => panic!("{other:?}"),
    }
    let c = b"VERSION 0.7\nFIELDS x y rgb\nSIZE 4 4 4\nTYPE F F F\nWIDTH 1\nPOINTS 1\nDATA ascii\n0 0 0\n";
    match parse_pcd(c, &OPTS) {
        Err(E::MissingField { field, .. }) => assert_eq!(field, "z"),
        other => panic!("{other:?}"),
    }
}

#[test]
fn nan_points_are_skipped_or_rejected() {
    let p = b"ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\nproperty float z\nend_header\n0 0 0\nnan 0 0\n1 inf 2\n";
    let ok = parse_ply(p, &OPTS).unwrap();
    assert_eq!((ok.cloud.len(), ok.skipped_non_finite), (1, 2));
    match parse_ply(
        p,
        &ReadOptions {
            non_finite: NonFinitePolicy::Reject,
            ..ReadOptions::default()
        },
    ) {
        Err(e @ E::NonFinite { .. }) => assert!(e.to_string().contains("line 9 (point 1)"), "{e}"),
        other => panic!("{other:?}"),
    }
    let mut b = b"ply\nformat binary_little_endian 1.0\nelement vertex 2\nproperty double x\nproperty double y\nproperty double z\nend_header\n".to_vec();
    for v in [1.0f64, 2.0, 3.0, f64::NAN, 0.0, 0.0] {
        b.extend(v.to_le_bytes());
    }
    assert_eq!(parse_ply(&b, &OPTS).unwrap().skipped_non_finite, 1);
    assert!(matches!(
        parse_ply(&b, &ReadOptions { non_finite: NonFinitePolicy::Reject, ..ReadOptions::default() }),
        Err(E::NonFinite { at, .. }) if at.element == 1 && at.line.is_none()
    ));
    assert!(matches!(
        PointCloud::new(vec![DVec3::NAN]),
        Err(bt_pointcloud::PointCloudError::InvalidCloud { .. })
    ));
}

#[test]
fn bad_values_and_unsupported_encodings() {
    let p = b"ply\nformat ascii 1.0\nelement vertex 2\nproperty float x\nproperty float y\nproperty float z\nend_header\n0 0 0\n0 zero 0\n";
    match parse_ply(p, &OPTS) {
        Err(e @ E::BadValue { .. }) => assert!(
            e.to_string().contains("line 9") && e.to_string().contains("zero"),
            "{e}"
        ),
        other => panic!("{other:?}"),
    }
    let c = b"VERSION 0.7\nFIELDS x y z\nSIZE 4 4 4\nTYPE F F F\nWIDTH 1\nPOINTS 1\nDATA binary_compressed\n\0\0\0\0\0\0\0\0";
    assert!(matches!(
        parse_pcd(c, &OPTS),
        Err(E::Unsupported { line: 7, .. })
    ));
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 256, ..ProptestConfig::default() })]

    /// Any prefix of a valid file, with any single byte changed, parses or fails cleanly.
    #[test]
    fn mutated_files_never_panic(which in 0usize..5, cut in 0.0f64..1.0, pos in 0.0f64..1.0, byte in any::<u8>()) {
        let src = match which {
            0 => ply(PlyFormat::Ascii),
            1 => ply(PlyFormat::BinaryLittleEndian),
            2 => ply(PlyFormat::BinaryBigEndian),
            3 => pcd(PcdData::Ascii),
            _ => pcd(PcdData::Binary),
        };
        let mut b = src[..((src.len() as f64 * cut) as usize)].to_vec();
        if !b.is_empty() {
            let i = ((b.len() - 1) as f64 * pos) as usize;
            b[i] = byte;
        }
        let _ = parse_any(&b, &OPTS);
        let _ = parse_ply(&b, &OPTS);
        let _ = parse_pcd(&b, &OPTS);
    }

    /// Arbitrary bytes after a plausible header never panic.
    #[test]
    fn random_bodies_never_panic(body in proptest::collection::vec(any::<u8>(), 0..512), count in any::<u64>()) {
        let mut b = format!("ply\nformat binary_big_endian 1.0\nelement vertex {count}\nproperty float x\nproperty float y\nproperty float z\nproperty list uchar int idx\nend_header\n").into_bytes();
        b.extend(&body);
        let _ = parse_ply(&b, &OPTS);
        let mut c = format!("VERSION 0.7\nFIELDS x y z\nSIZE 4 4 4\nTYPE F F F\nWIDTH {count}\nHEIGHT 1\nDATA ascii\n").into_bytes();
        c.extend(&body);
        let _ = parse_pcd(&c, &OPTS);
    }
}
