//! Point clouds (PLY and PCD, ASCII and binary) through `parse_any`: an accepted cloud has only
//! finite points and normals, and allocation stays bounded by the input length.
#![no_main]

use bt_import::cloud::{NonFinitePolicy, ReadOptions, parse_any};
use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    for non_finite in [NonFinitePolicy::Skip, NonFinitePolicy::Reject] {
        let options = ReadOptions {
            non_finite,
            ..ReadOptions::default()
        };
        let Ok(loaded) = parse_any(data, &options) else {
            continue;
        };
        let cloud = &loaded.cloud;
        assert!(cloud.points().iter().all(|p| p.is_finite()));
        if let Some(normals) = cloud.normals() {
            assert_eq!(normals.len(), cloud.len());
            assert!(normals.iter().all(|n| n.is_finite()));
        }
    }
});
