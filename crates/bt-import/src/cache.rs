//! The optional load cache: a validated scene kept on disk so that loading the same inputs
//! with the same options again skips parsing, merging and validation (CLI `--cache`, Python
//! `load(cache=True)`; `docs/reliability.md`, "The load cache").
//!
//! An entry lives in the cache directory only ([`LoadCache::user`]: `$BEAMTRACE_CACHE_DIR`,
//! else `$XDG_CACHE_HOME/beamtrace`, else `$HOME/.cache/beamtrace`), never beside the inputs.
//! Its file name is the key: the SHA-256 of [`CACHE_FORMAT_VERSION`], the source as given, the
//! load options and the named file's content. It holds every other file the load read with the
//! SHA-256 of the bytes the load parsed ([`Loaded::digests`]), checked against the files'
//! current content on every hit, so an edited mesh misses. The entry is
//! `MAGIC | version | payload length | payload (postcard; the scene inside it postcard bytes of
//! its own, decoded while the inputs are hashed) | checksum of all before` (the SHA-256 of the
//! SHA-256s of its 64 KiB pieces, `checksum`); anything
//! that does not decode, check or rebuild (damaged, truncated, foreign, over the file budget)
//! is ignored with a warning and replaced by a fresh load. Writes are atomic (a temporary file
//! in the cache directory, renamed); a failed write is a warning, never a failed load.

use crate::source::{Digest, Format, Source, digest, read_file};
use crate::{ImportError, LoadOptions, LoadProgress, Loaded};
use bt_scene::dynamic::DynamicScene;
use bt_scene::{Scene, StoredScene};
use rayon::prelude::*;
use serde::{Deserialize, Serialize};
use std::path::{Path, PathBuf};

/// The version of the entries' layout and of what they hold; part of every key, so entries of
/// another version are never read. Raise it whenever a load's result could change for the
/// same inputs and options (a reader, the merge, validation, [`StoredScene`]).
pub const CACHE_FORMAT_VERSION: u32 = 4;

/// The first bytes of every entry.
const MAGIC: &[u8; 8] = b"BTLOADC\0";
/// Bytes of the header: magic, version (u32), payload length (u64).
const HEADER: usize = 8 + 4 + 8;

/// A directory of load-cache entries.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct LoadCache {
    dir: PathBuf,
}

/// What an entry holds, as postcard encodes it.
#[derive(Serialize, Deserialize)]
struct Entry<'a> {
    /// The key the entry was written under (its file name), checked on reading.
    key: Digest,
    /// Every file the load read, in [`Loaded::sources`] order, with its SHA-256 as parsed.
    inputs: Vec<(PathBuf, Digest)>,
    warnings: Vec<String>,
    /// The [`StoredScene`], postcard-encoded on its own: a hit decodes it while the inputs
    /// are hashed, instead of before.
    #[serde(borrow)]
    scene: &'a [u8],
}

impl LoadCache {
    /// The cache in `dir` (created on the first write).
    pub fn at(dir: impl Into<PathBuf>) -> LoadCache {
        LoadCache { dir: dir.into() }
    }

    /// The user's cache: `$BEAMTRACE_CACHE_DIR`, else `$XDG_CACHE_HOME/beamtrace`, else
    /// `$HOME/.cache/beamtrace` (empty variables count as unset).
    pub fn user() -> Result<LoadCache, ImportError> {
        let var = |name| std::env::var_os(name).filter(|v| !v.is_empty());
        let dir = match (
            var("BEAMTRACE_CACHE_DIR"),
            var("XDG_CACHE_HOME"),
            var("HOME"),
        ) {
            (Some(dir), _, _) => PathBuf::from(dir),
            (None, Some(xdg), _) => Path::new(&xdg).join("beamtrace"),
            (None, None, Some(home)) => Path::new(&home).join(".cache/beamtrace"),
            (None, None, None) => return Err(ImportError::NoCacheDir),
        };
        Ok(LoadCache::at(dir))
    }

    /// The directory of the entries.
    pub fn dir(&self) -> &Path {
        &self.dir
    }

    /// [`crate::load_dynamic`] through the cache: sources that load as one static step
    /// (meshes, XML scenes) go through [`LoadCache::load`]; scene files with their time
    /// steps, built-ins and point clouds load without the cache.
    pub fn load_dynamic(
        &self,
        source: &str,
        options: &LoadOptions,
        progress: &mut dyn FnMut(LoadProgress),
    ) -> Result<(Loaded<DynamicScene>, Vec<String>), ImportError> {
        let one_step = |path: &Path| {
            matches!(
                Format::of(path),
                Ok(Format::Obj | Format::PlyMesh | Format::Stl | Format::Gltf | Format::Xml)
            )
        };
        match Source::parse(source) {
            Source::File(path) if one_step(&path) => {
                let (loaded, notes) = self.load(source, options, progress)?;
                Ok((loaded.map(DynamicScene::from_static), notes))
            }
            _ => Ok((crate::load_dynamic(source, options, progress)?, vec![])),
        }
    }

    /// [`crate::load_with_progress`] through the cache: the entry of these inputs and options
    /// when there is a sound one, else a fresh load, stored for the next time. Built-in scenes
    /// and point clouds load without the cache. The load equals a fresh load (scene, warnings,
    /// files read); beside it come the cache's own warnings (`load cache: FILE: ...`: a
    /// damaged entry replaced, an entry that could not be written), for stderr.
    pub fn load(
        &self,
        source: &str,
        options: &LoadOptions,
        progress: &mut dyn FnMut(LoadProgress),
    ) -> Result<(Loaded, Vec<String>), ImportError> {
        options.check()?;
        let uncached = |progress| {
            Ok((
                crate::load_with_progress(source, options, progress)?,
                vec![],
            ))
        };
        let Source::File(path) = Source::parse(source) else {
            return uncached(progress);
        };
        if Format::of(&path)? == Format::PointCloud {
            return uncached(progress);
        }
        let named = read_file(&path, options.max_file_bytes).map_err(|e| ImportError::Io {
            path: path.display().to_string(),
            source: e,
        })?;
        let named = digest(&named);
        let key = key(source, options, &named);
        let file = self.dir.join(format!("{}.bin", hex(&key)));
        let mut notes = Vec::new();
        match self.lookup(&file, &key, &named, options.max_file_bytes) {
            Lookup::Hit(loaded) => return Ok((*loaded, notes)),
            Lookup::Miss => {}
            Lookup::Damaged(why) => notes.push(format!(
                "load cache: {}: {why}: ignored and rebuilt",
                file.display()
            )),
        }
        let loaded = crate::load_with_progress(source, options, progress)?;
        // Stored only when the named file the load parsed is the one keyed (it may have
        // changed since it was hashed above) and every file read has its digest.
        let complete = loaded.digests.len() == loaded.sources.len();
        if complete && loaded.digests.first() == Some(&named) {
            if let Err(e) = self.store(&file, key, &loaded) {
                notes.push(format!("load cache: {}: not written: {e}", file.display()));
            }
        }
        Ok((loaded, notes))
    }

    /// The entry in `file`, if it is sound and its inputs are unchanged.
    fn lookup(&self, file: &Path, key: &Digest, named: &Digest, max_bytes: u64) -> Lookup {
        let bytes = match read_file(file, max_bytes) {
            Ok(bytes) => bytes,
            Err(e) if e.kind() == std::io::ErrorKind::NotFound => return Lookup::Miss,
            Err(e) => return Lookup::Damaged(e.to_string()),
        };
        let entry = match decode(&bytes) {
            Ok(entry) if entry.key == *key => entry,
            Ok(_) => return Lookup::Damaged("written under another key".into()),
            Err(why) => return Lookup::Damaged(why),
        };
        let Entry {
            inputs,
            scene,
            warnings,
            ..
        } = entry;
        let Some(((_, first), others)) = inputs.split_first() else {
            return Lookup::Damaged("lists no input".into());
        };
        if first != named {
            return Lookup::Damaged("lists another named file".into());
        }
        // The inputs are read and hashed on all cores (Munich: 2,367 meshes, 11 MB) while the
        // scene is rebuilt beside them; changed or gone, it is a plain miss (the rebuilt scene
        // is dropped unused and the fresh load reports what is wrong).
        let unchanged = |(path, recorded): &(PathBuf, Digest)| {
            read_file(path, max_bytes).is_ok_and(|bytes| digest(&bytes) == *recorded)
        };
        let source = file.display().to_string();
        let rebuild = || {
            let stored: StoredScene =
                postcard::from_bytes(scene).map_err(|e| format!("does not decode: {e}"))?;
            Scene::from_stored(stored, &source).map_err(|e| e.to_string())
        };
        let (unchanged, scene) = rayon::join(|| others.par_iter().all(unchanged), rebuild);
        if !unchanged {
            return Lookup::Miss;
        }
        let scene = match scene {
            Ok(scene) => scene,
            Err(why) => return Lookup::Damaged(why),
        };
        let (sources, digests) = inputs.into_iter().unzip();
        Lookup::Hit(Box::new(Loaded {
            scene,
            warnings,
            sources,
            digests,
        }))
    }

    /// Write the entry of `loaded` to `file` atomically, creating the cache directory.
    fn store(&self, file: &Path, key: Digest, loaded: &Loaded) -> Result<(), String> {
        let scene = postcard::to_stdvec(&loaded.scene.to_stored()).map_err(|e| e.to_string())?;
        let entry = Entry {
            key,
            inputs: (loaded.sources.iter().cloned())
                .zip(loaded.digests.iter().copied())
                .collect(),
            warnings: loaded.warnings.clone(),
            scene: &scene,
        };
        let bytes = seal(&entry)?;
        std::fs::create_dir_all(&self.dir).map_err(|e| format!("{}: {e}", self.dir.display()))?;
        bt_output::write_atomic(file, &bytes).map_err(|e| e.to_string())
    }
}

/// The bytes of a file holding `entry`: header, payload and checksum, as [`decode`] reads them.
fn seal(entry: &Entry<'_>) -> Result<Vec<u8>, String> {
    let payload = postcard::to_stdvec(entry).map_err(|e| e.to_string())?;
    let mut bytes = Vec::with_capacity(HEADER + payload.len() + 32);
    bytes.extend_from_slice(MAGIC);
    bytes.extend_from_slice(&CACHE_FORMAT_VERSION.to_le_bytes());
    bytes.extend_from_slice(&(payload.len() as u64).to_le_bytes());
    bytes.extend_from_slice(&payload);
    bytes.extend_from_slice(&checksum(&bytes));
    Ok(bytes)
}

/// Bytes of an entry hashed apart for its checksum (the last piece may be shorter).
const CHECKSUM_PIECE: usize = 1 << 16;

/// The checksum of an entry's `bytes`: the SHA-256 of the SHA-256s of its pieces of
/// [`CHECKSUM_PIECE`] bytes, the pieces hashed on all cores (a city's 2.8 MB entry was one
/// core's work before anything else of a hit could start).
fn checksum(bytes: &[u8]) -> Digest {
    let pieces: Vec<Digest> = bytes.par_chunks(CHECKSUM_PIECE).map(digest).collect();
    digest(pieces.as_flattened())
}

/// What a look-up found.
enum Lookup {
    /// A sound entry of unchanged inputs.
    Hit(Box<Loaded>),
    /// No entry, or one whose inputs changed.
    Miss,
    /// An entry that cannot be used, and why.
    Damaged(String),
}

/// The entry in `bytes`, or why it is not one: header, length and checksum checked before
/// the payload is decoded.
fn decode(bytes: &[u8]) -> Result<Entry<'_>, String> {
    if bytes.len() < HEADER + 32 || &bytes[..8] != MAGIC {
        return Err("not a beamtrace load-cache entry".into());
    }
    let version = u32::from_le_bytes(bytes[8..12].try_into().unwrap_or_default());
    if version != CACHE_FORMAT_VERSION {
        return Err(format!("version {version}, not {CACHE_FORMAT_VERSION}"));
    }
    let length = u64::from_le_bytes(bytes[12..HEADER].try_into().unwrap_or_default());
    if length != (bytes.len() - HEADER - 32) as u64 {
        return Err("truncated or extended (length differs from its header)".into());
    }
    let (body, checksum) = bytes.split_at(bytes.len() - 32);
    if self::checksum(body) != checksum {
        return Err("checksum differs (damaged)".into());
    }
    postcard::from_bytes(&body[HEADER..]).map_err(|e| format!("does not decode: {e}"))
}

/// The key of a load: what could change its result besides the other files it reads.
fn key(source: &str, options: &LoadOptions, named: &Digest) -> Digest {
    let mut text = Vec::new();
    text.extend_from_slice(b"beamtrace load cache\0");
    text.extend_from_slice(&CACHE_FORMAT_VERSION.to_le_bytes());
    // Every field of the options, exactly (Debug prints floats round-trip): a new option
    // joins the key without an edit here.
    for part in [source.to_string(), format!("{options:?}")] {
        text.extend_from_slice(&(part.len() as u64).to_le_bytes());
        text.extend_from_slice(part.as_bytes());
    }
    text.extend_from_slice(named);
    digest(&text)
}

/// `bytes` in lowercase hexadecimal.
fn hex(bytes: &[u8]) -> String {
    bytes.iter().map(|b| format!("{b:02x}")).collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The checksum of an entry of several pieces notices one changed byte in any piece, and
    /// two pieces swapped.
    #[test]
    fn the_checksum_covers_every_piece_and_their_order() {
        let bytes: Vec<u8> = (0..CHECKSUM_PIECE * 7 / 2)
            .map(|i| (i % 251) as u8)
            .collect();
        let good = checksum(&bytes);
        for piece in 0..4 {
            let mut changed = bytes.clone();
            changed[piece * CHECKSUM_PIECE + 17] ^= 1;
            assert_ne!(checksum(&changed), good, "piece {piece}");
        }
        let mut swapped = bytes[CHECKSUM_PIECE..2 * CHECKSUM_PIECE].to_vec();
        swapped.extend_from_slice(&bytes[..CHECKSUM_PIECE]);
        swapped.extend_from_slice(&bytes[2 * CHECKSUM_PIECE..]);
        assert_ne!(swapped, bytes);
        assert_ne!(checksum(&swapped), good);
        assert_ne!(checksum(&bytes[..bytes.len() - 1]), good, "one byte fewer");
    }

    /// An entry sound to its checksum whose scene bytes are cut short (the checksum guards
    /// the file, the scene's own decoding guards what is inside): ignored, rebuilt, warned.
    #[test]
    fn an_entry_whose_scene_does_not_decode_is_rebuilt() {
        let dir = std::env::temp_dir().join(format!("bt-cache-inner-{}", std::process::id()));
        let _ = std::fs::remove_dir_all(&dir);
        let cache = LoadCache::at(&dir);
        let xml = Path::new(env!("CARGO_MANIFEST_DIR"))
            .join("../../testdata/scenes/sionna-rt/simple_street_canyon/simple_street_canyon.xml");
        let xml = xml.to_str().unwrap();
        let options = LoadOptions::default();
        let (fresh, notes) = cache.load(xml, &options, &mut |_| {}).unwrap();
        assert!(notes.is_empty(), "{notes:?}");
        let file = std::fs::read_dir(&dir)
            .unwrap()
            .next()
            .unwrap()
            .unwrap()
            .path();
        let good = std::fs::read(&file).unwrap();
        let entry = decode(&good).unwrap();
        let cut = Entry {
            scene: &entry.scene[..entry.scene.len() / 2],
            ..entry
        };
        std::fs::write(&file, seal(&cut).unwrap()).unwrap();
        let (loaded, notes) = cache.load(xml, &options, &mut |_| {}).unwrap();
        assert_eq!(notes.len(), 1, "{notes:?}");
        assert!(notes[0].contains("does not decode"), "{notes:?}");
        assert!(notes[0].contains("ignored and rebuilt"), "{notes:?}");
        assert_eq!(loaded.scene.surfaces(), fresh.scene.surfaces());
        assert_eq!(
            std::fs::read(&file).unwrap(),
            good,
            "the entry is written anew"
        );
        std::fs::remove_dir_all(dir).ok();
    }
}
