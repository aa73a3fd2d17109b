//! Loading the scene a command names: the one place the scene arguments become load options
//! (every command that takes a scene loads through here).

use crate::args::SceneArgs;
use bt_import::cache::LoadCache;
use bt_import::{LoadOptions, Loaded};
use bt_scene::dynamic::DynamicScene;
use bt_scene::{Scene, Terminal, Terminals, Vec3};

/// The load options the scene arguments select: `--material`/`--thickness` give every
/// material of any source that radio model (`--thickness` alone: that slab thickness to each
/// half-space material); `--frequency` is the carrier of sources that carry none (meshes,
/// point clouds, XML scenes).
pub fn load_options(args: &SceneArgs) -> anyhow::Result<LoadOptions> {
    Ok(LoadOptions {
        terminals: Terminals {
            tx: args.tx,
            rx: args.rx,
        },
        merge: bt_mesh::MergeOptions {
            angle_tol_deg: args.merge_angle_deg,
            dist_tol_m: args.merge_distance,
            max_elements: args.max_mesh_elements,
            ..bt_mesh::MergeOptions::default()
        },
        min_reflector_area_m2: args.min_reflector_area,
        cloud: bt_import::cloud::ReadOptions {
            max_points: args.max_cloud_points,
            max_file_bytes: args.max_file_bytes,
            ..Default::default()
        },
        max_file_bytes: args.max_file_bytes,
        max_xml_substitution: args.max_xml_substitution,
        frequency_hz: args
            .material
            .frequency
            .unwrap_or(bt_scene::DEFAULT_FREQUENCY_HZ),
        radio: args.material.radio()?,
        // Used only without --material (whose slab it is then, in `radio`).
        thickness: args.material.thickness,
        ..LoadOptions::default()
    })
}

/// The user's load cache with `--cache`, else none.
fn cache(args: &SceneArgs) -> anyhow::Result<Option<LoadCache>> {
    Ok(match args.cache {
        true => Some(LoadCache::user()?),
        false => None,
    })
}

/// A load without the cache: no cache warnings.
fn uncached<S>(loaded: Loaded<S>) -> (Loaded<S>, Vec<String>) {
    (loaded, Vec::new())
}

/// The load, its cache's warnings printed to stderr (the import's are the command's).
fn cache_warnings<S>((loaded, notes): (Loaded<S>, Vec<String>)) -> Loaded<S> {
    for note in notes {
        eprintln!("warning: {note}");
    }
    loaded
}

/// Load the scene named on the command line (a file or `builtin:NAME`), with a progress bar
/// while a point cloud's planes are extracted, and `--frequency` applied to scene files and
/// built-ins too.
pub fn load_scene(args: &SceneArgs) -> anyhow::Result<Loaded> {
    let options = load_options(args)?;
    let (bar, mut progress) = crate::progress::extraction_progress();
    let loaded = match cache(args)? {
        Some(cache) => cache.load(&args.scene, &options, &mut progress),
        // Without the cache, no file's SHA-256 is needed.
        None => bt_import::load_without_digests(&args.scene, &options, &mut progress).map(uncached),
    };
    bar.finish_and_clear();
    let mut loaded = cache_warnings(loaded?);
    if let Some(f) = args.material.frequency {
        loaded.scene = loaded.scene.with_frequency(f)?;
    }
    Ok(loaded)
}

/// Load a scene as a dynamic scene: JSON/TOML files and built-ins with their steps; meshes
/// (and any other static source) as one step. Import warnings go to stderr; the files read
/// come back with the scene.
pub fn load_dynamic(args: &SceneArgs) -> anyhow::Result<Loaded<DynamicScene>> {
    let options = load_options(args)?;
    let (bar, mut progress) = crate::progress::extraction_progress();
    let loaded = match cache(args)? {
        Some(cache) => cache.load_dynamic(&args.scene, &options, &mut progress),
        None => bt_import::load_dynamic(&args.scene, &options, &mut progress).map(uncached),
    };
    bar.finish_and_clear();
    let mut loaded = cache_warnings(loaded?);
    if let Some(f) = args.material.frequency {
        loaded.scene = loaded.scene.with_frequency(f)?;
    }
    for w in &loaded.warnings {
        eprintln!("warning: {w}");
    }
    Ok(loaded)
}

/// Refuse a scene without the terminals a command needs (`which`), naming the flags that give
/// them: meshes, XML scenes and point clouds carry none, and a scene file may leave them out.
pub fn require_terminals(
    scene: &Scene,
    which: &[Terminal],
    args: &SceneArgs,
) -> anyhow::Result<()> {
    let missing: Vec<Terminal> = which
        .iter()
        .copied()
        .filter(|t| scene.terminal(*t).is_err())
        .collect();
    if missing.is_empty() {
        return Ok(());
    }
    anyhow::bail!(
        "{}",
        Terminal::missing_message(&args.scene, &missing, |t| format!("--{t} X,Y,Z"))
    )
}

/// Refuse a dynamic scene any of whose `steps` lacks a terminal ([`terminals`]).
pub fn require_every_step(steps: &[Scene], args: &SceneArgs) -> anyhow::Result<()> {
    for scene in steps {
        terminals(scene, args)?;
    }
    Ok(())
}

/// Both terminals of `scene`, metres, world frame, or the error of [`require_terminals`].
pub fn terminals(scene: &Scene, args: &SceneArgs) -> anyhow::Result<(Vec3, Vec3)> {
    require_terminals(scene, &[Terminal::Tx, Terminal::Rx], args)?;
    let ends = scene.terminals()?;
    Ok((scene.to_world(ends.tx), scene.to_world(ends.rx)))
}
