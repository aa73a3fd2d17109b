//! The load cache (`bt_import::cache`): a cached load equals a fresh one, a changed input
//! misses, a damaged entry is rebuilt with a warning, and nothing is written but the entry in
//! the cache directory.

use bt_import::cache::LoadCache;
use bt_import::{LoadOptions, Loaded};
use std::path::{Path, PathBuf};

/// A fresh, empty folder under the system's temporary directory.
fn scratch(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("bt-cache-{name}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

/// `testdata/scenes/sionna-rt/<scene>/` of the workspace.
fn sionna(scene: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../../testdata/scenes/sionna-rt")
        .join(scene)
}

/// Copy the files of `from` (one level of subfolders) into `to`.
fn copy_scene(from: &Path, to: &Path) {
    for entry in std::fs::read_dir(from).unwrap() {
        let path = entry.unwrap().path();
        let target = to.join(path.file_name().unwrap());
        if path.is_dir() {
            std::fs::create_dir_all(&target).unwrap();
            copy_scene(&path, &target);
        } else {
            std::fs::copy(&path, &target).unwrap();
        }
    }
}

/// Every file under `dir` with its length and modification time.
fn listing(dir: &Path) -> Vec<(PathBuf, u64, std::time::SystemTime)> {
    let mut out = Vec::new();
    for entry in std::fs::read_dir(dir).unwrap() {
        let path = entry.unwrap().path();
        let meta = std::fs::symlink_metadata(&path).unwrap();
        if meta.is_dir() {
            out.extend(listing(&path));
        } else {
            out.push((path, meta.len(), meta.modified().unwrap()));
        }
    }
    out.sort();
    out
}

/// The one entry in the cache directory and its inode (a rewrite renames a new file over it).
fn entry(cache: &Path) -> (PathBuf, u64) {
    use std::os::unix::fs::MetadataExt;
    let files: Vec<PathBuf> = (std::fs::read_dir(cache).unwrap())
        .map(|e| e.unwrap().path())
        .collect();
    assert_eq!(files.len(), 1, "one entry and no leftovers: {files:?}");
    let ino = std::fs::metadata(&files[0]).unwrap().ino();
    (files[0].clone(), ino)
}

/// `a` and `b` hold the same scene, warnings and files read.
fn assert_same(a: &Loaded, b: &Loaded) {
    let (s, t) = (&a.scene, &b.scene);
    assert_eq!(s.surfaces(), t.surfaces());
    assert_eq!(s.materials(), t.materials());
    assert_eq!(
        (s.name(), s.origin(), s.extent()),
        (t.name(), t.origin(), t.extent())
    );
    assert_eq!(
        (s.tx(), s.rx(), s.frequency_hz()),
        (t.tx(), t.rx(), t.frequency_hz())
    );
    assert_eq!(a.warnings, b.warnings);
    assert_eq!(a.sources, b.sources);
    assert_eq!(a.digests, b.digests);
}

#[test]
fn a_cached_load_equals_a_fresh_one_and_writes_only_its_entry() {
    let cache_dir = scratch("equal");
    let cache = LoadCache::at(&cache_dir);
    let scene_dir = sionna("etoile");
    let before = listing(&scene_dir);
    let xml = scene_dir.join("etoile.xml").display().to_string();
    let options = LoadOptions {
        terminals: bt_scene::Terminals {
            tx: Some(bt_scene::Vec3::new(10.0, 20.0, 30.0)),
            rx: None,
        },
        ..LoadOptions::default()
    };
    let fresh = bt_import::load(&xml, &options).unwrap();
    let (first, notes) = cache.load(&xml, &options, &mut |_| {}).unwrap();
    assert_eq!(notes, Vec::<String>::new());
    let (_, written) = entry(&cache_dir);
    let (second, notes) = cache.load(&xml, &options, &mut |_| {}).unwrap();
    assert_eq!(notes, Vec::<String>::new());
    assert_eq!(
        entry(&cache_dir).1,
        written,
        "the second load reads the entry"
    );
    assert_same(&fresh, &first);
    assert_same(&fresh, &second);
    assert!(fresh.scene.surfaces().len() > 1000 && fresh.sources.len() > 500);
    // Other options are another entry.
    let other = LoadOptions {
        min_reflector_area_m2: 1.0,
        ..options
    };
    let (third, _) = cache.load(&xml, &other, &mut |_| {}).unwrap();
    assert_same(&bt_import::load(&xml, &other).unwrap(), &third);
    assert_eq!(std::fs::read_dir(&cache_dir).unwrap().count(), 2);
    assert_eq!(
        listing(&scene_dir),
        before,
        "nothing written beside the inputs"
    );
    std::fs::remove_dir_all(cache_dir).ok();
}

#[test]
fn one_changed_byte_of_a_mesh_misses() {
    let dir = scratch("changed");
    let (scene_dir, cache_dir) = (dir.join("scene"), dir.join("cache"));
    std::fs::create_dir_all(&scene_dir).unwrap();
    copy_scene(&sionna("simple_street_canyon"), &scene_dir);
    let xml = scene_dir.join("simple_street_canyon.xml");
    let xml = xml.to_str().unwrap();
    let cache = LoadCache::at(&cache_dir);
    let options = LoadOptions::default();
    let (original, _) = cache.load(xml, &options, &mut |_| {}).unwrap();
    let (_, written) = entry(&cache_dir);
    // The lowest bit of the first vertex's x: a valid mesh, a vertex moved by one ulp.
    let mesh = scene_dir.join("meshes/building_1.ply");
    let mut bytes = std::fs::read(&mesh).unwrap();
    let data = bytes
        .windows(11)
        .position(|w| w == b"end_header\n")
        .unwrap()
        + 11;
    bytes[data] ^= 1;
    std::fs::write(&mesh, &bytes).unwrap();
    let fresh = bt_import::load(xml, &options).unwrap();
    assert_ne!(fresh.scene.surfaces(), original.scene.surfaces());
    let (cached, notes) = cache.load(xml, &options, &mut |_| {}).unwrap();
    assert_same(&fresh, &cached);
    assert_ne!(entry(&cache_dir).1, written, "the entry was rebuilt");
    assert_eq!(notes, Vec::<String>::new(), "a changed input is no damage");
    std::fs::remove_dir_all(dir).ok();
}

#[test]
fn a_damaged_entry_is_rebuilt_with_a_warning() {
    let cache_dir = scratch("damaged");
    let cache = LoadCache::at(&cache_dir);
    let xml = sionna("simple_street_canyon").join("simple_street_canyon.xml");
    let xml = xml.to_str().unwrap();
    let options = LoadOptions::default();
    let fresh = bt_import::load(xml, &options).unwrap();
    cache.load(xml, &options, &mut |_| {}).unwrap();
    let (file, _) = entry(&cache_dir);
    let good = std::fs::read(&file).unwrap();
    let mut flipped = good.clone();
    let middle = flipped.len() / 2;
    flipped[middle] ^= 0xff;
    flipped[middle + 1] ^= 0x55;
    let mut foreign = b"BTLOADC\0".to_vec();
    foreign.extend_from_slice(&[7; 100]);
    let damages: [(&str, Vec<u8>); 5] = [
        ("checksum", flipped),
        ("truncated", good[..good.len() - 9].to_vec()),
        ("not a beamtrace", good[..10].to_vec()),
        ("version", foreign),
        ("not a beamtrace", b"hello".to_vec()),
    ];
    for (why, bytes) in damages {
        std::fs::write(&file, &bytes).unwrap();
        let (loaded, notes) = cache.load(xml, &options, &mut |_| {}).unwrap();
        assert_eq!(notes.len(), 1, "{why}: {notes:?}");
        let named =
            notes[0].starts_with("load cache: ") && notes[0].contains(&file.display().to_string());
        assert!(named, "{notes:?}");
        assert!(
            notes[0].contains(why) && notes[0].contains("ignored and rebuilt"),
            "{notes:?}"
        );
        assert_same(&fresh, &loaded);
        // Rebuilt: the next load reads it without a warning.
        let (again, notes) = cache.load(xml, &options, &mut |_| {}).unwrap();
        assert_eq!(notes, Vec::<String>::new());
        assert_same(&fresh, &again);
    }
    std::fs::remove_dir_all(cache_dir).ok();
}

/// Every material field survives the cache: a constant-loss material (no radio model), a slab
/// whose material opens it to transmission, the defaults. (Postcard, the entry's encoding, is
/// not self-describing: a field skipped when empty would shift every later byte.)
#[test]
fn every_material_field_survives_the_cache() {
    let dir = scratch("materials");
    std::fs::create_dir_all(&dir).unwrap();
    let file = dir.join("m.json");
    std::fs::write(
        &file,
        r#"{ "materials": { "old": { "reflection_loss_db": 3 },
                          "curtain": { "itu": "wood", "thickness": 0.01, "transmission": true } },
             "surfaces": [
               { "name": "a", "material": "old", "vertices": [[0, 0, 0], [1, 0, 0], [1, 1, 0]] },
               { "name": "b", "material": "curtain", "vertices": [[0, 0, 1], [1, 0, 1], [1, 1, 1]] } ] }"#,
    )
    .unwrap();
    let cache = LoadCache::at(dir.join("cache"));
    let path = file.display().to_string();
    let options = LoadOptions::default();
    let fresh = bt_import::load(&path, &options).unwrap();
    cache.load(&path, &options, &mut |_| {}).unwrap();
    let (cached, notes) = cache.load(&path, &options, &mut |_| {}).unwrap();
    assert_eq!(notes, Vec::<String>::new(), "the entry decodes");
    assert_same(&fresh, &cached);
    assert!(cached.scene.materials()["curtain"].transmission);
    assert!(cached.scene.penetrable(bt_scene::SurfaceId(1)));
    std::fs::remove_dir_all(dir).ok();
}

#[test]
fn a_load_without_digests_is_the_same_load_without_them() {
    let scenes = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../testdata/scenes");
    let sources = [
        sionna("etoile").join("etoile.xml"),
        scenes.join("box-room-binary.ply"),
        scenes.join("box-room.obj"),
        scenes.join("one-wall.json"),
    ];
    let options = LoadOptions::default();
    for source in sources {
        let source = source.display().to_string();
        let hashed = bt_import::load(&source, &options).unwrap();
        let bare = bt_import::load_without_digests(&source, &options, &mut |_| {}).unwrap();
        assert_eq!(hashed.digests.len(), hashed.sources.len(), "{source}");
        assert!(bare.digests.is_empty(), "{source}");
        let digests = hashed.digests.clone();
        assert_same(&hashed, &Loaded { digests, ..bare });
    }
}
