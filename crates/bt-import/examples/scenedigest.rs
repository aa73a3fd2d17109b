//! The identity of a loaded scene, to prove a faster load exact (docs/performance.md):
//! `cargo run --release -p bt-import --example scenedigest -- FILE...`. Per file, the SHA-256
//! of the `Debug` text of the whole fresh load (`bt_import::load_without_digests`, as the CLI
//! loads without `--cache`): every surface's name, material, kind and vertex bits (`Debug`
//! prints an `f64` as the shortest text that reads back to the same bits, `-0.0` included),
//! the BVH, the materials, the warnings in order and the files read; then the surface and
//! warning counts. Two builds that print the same line loaded the same scene.

use sha2::Digest as _;

fn main() {
    let options = bt_import::LoadOptions::default();
    for file in std::env::args().skip(1) {
        let loaded = bt_import::load_without_digests(&file, &options, &mut |_| {}).expect("loads");
        let text = format!("{loaded:?}");
        let digest: [u8; 32] = sha2::Sha256::digest(text.as_bytes()).into();
        let hex: String = digest.iter().map(|b| format!("{b:02x}")).collect();
        println!(
            "{hex} {} surfaces, {} warnings, {} bytes of Debug text: {file}",
            loaded.scene.surfaces().len(),
            loaded.warnings.len(),
            text.len()
        );
    }
}
