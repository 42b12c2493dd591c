//! The bundled example dataset (ours: `dualcal simulate --seed 1`), compiled into the binary so an
//! installed or moved binary opens it too.

use std::path::{Path, PathBuf};

/// The bundled example dataset, compiled into the binary (it is ours: `dualcal simulate --seed 1`).
#[cfg(not(feature = "web-fonts"))]
pub(super) const EXAMPLE_FILES: &[(&str, &[u8])] = &[
    (
        crate::dataset::MANIFEST_FILE,
        include_bytes!("../../assets/datasets/example/dataset.toml"),
    ),
    (
        "left.csv",
        include_bytes!("../../assets/datasets/example/left.csv"),
    ),
    (
        "right.csv",
        include_bytes!("../../assets/datasets/example/right.csv"),
    ),
    (
        "truth.json",
        include_bytes!("../../assets/datasets/example/truth.json"),
    ),
];

/// The browser's modules: the example's files but its two CSVs ([`example_files`] adds them).
#[cfg(feature = "web-fonts")]
pub(super) const EXAMPLE_FILES: &[(&str, &[u8])] = &[
    (
        crate::dataset::MANIFEST_FILE,
        include_bytes!("../../assets/datasets/example/dataset.toml"),
    ),
    (
        "truth.json",
        include_bytes!("../../assets/datasets/example/truth.json"),
    ),
];

/// The example's files as the dataset loader reads them. In the browser's modules (feature
/// `web-fonts`) its two CSVs are compiled in as their numbers (`example_codec`, written by
/// `build.rs`) and written back as text here: the same `f64`s, ~14 KB less of the gzipped module.
#[cfg(feature = "web-fonts")]
pub(super) fn example_files() -> Vec<(&'static str, Vec<u8>)> {
    const COMPACT: [(&str, &[u8]); 2] = [
        (
            "left.csv",
            include_bytes!(concat!(env!("OUT_DIR"), "/web-example/left.bin")),
        ),
        (
            "right.csv",
            include_bytes!(concat!(env!("OUT_DIR"), "/web-example/right.bin")),
        ),
    ];
    let mut files: Vec<(&'static str, Vec<u8>)> = EXAMPLE_FILES
        .iter()
        .map(|(name, bytes)| (*name, bytes.to_vec()))
        .collect();
    for (name, compact) in COMPACT {
        let text = super::example_codec::decode(compact).unwrap_or_default();
        files.push((name, text.into_bytes()));
    }
    files
}

/// The example's files as the dataset loader reads them: the compiled-in files.
#[cfg(not(feature = "web-fonts"))]
pub(super) fn example_files() -> Vec<(&'static str, Vec<u8>)> {
    EXAMPLE_FILES
        .iter()
        .map(|(name, bytes)| (*name, bytes.to_vec()))
        .collect()
}

/// In a browser: where the compiled-in example is mounted in memory (`web.rs`).
pub const IN_MEMORY_EXAMPLE_DIR: &str = "/example";

/// The bundled example dataset: in the source tree when the binary runs from it (`cargo run`), else a
/// copy of the compiled-in files in the user's cache directory; in a browser, the files in memory
/// ([`IN_MEMORY_EXAMPLE_DIR`]).
pub fn bundled_example_path() -> PathBuf {
    if cfg!(target_arch = "wasm32") {
        return PathBuf::from(IN_MEMORY_EXAMPLE_DIR);
    }
    let source = Path::new(env!("CARGO_MANIFEST_DIR")).join("assets/datasets/example");
    if source.join(crate::dataset::MANIFEST_FILE).is_file() {
        return source;
    }
    let cache_root = std::env::var_os("XDG_CACHE_HOME")
        .filter(|v| !v.is_empty())
        .map(PathBuf::from)
        .or_else(|| std::env::var_os("HOME").map(|h| PathBuf::from(h).join(".cache")))
        .unwrap_or_else(std::env::temp_dir);
    // If the copy cannot be written, the source path is returned and opening it reports the error.
    unpack_example(&cache_root.join("dualcal")).unwrap_or(source)
}

/// Write the compiled-in example into `root/example-<content hash>` (files already there are left
/// alone: the directory name changes with the content) and return that directory.
pub fn unpack_example(root: &Path) -> std::io::Result<PathBuf> {
    use std::hash::{Hash, Hasher};
    // A name for this version of the example (a new toolchain may rename it: then it is unpacked again).
    let files = example_files();
    let mut hasher = std::hash::DefaultHasher::new();
    files.hash(&mut hasher);
    let dir = root.join(format!("example-{:016x}", hasher.finish()));
    std::fs::create_dir_all(&dir)?;
    for (name, bytes) in &files {
        let path = dir.join(name);
        if !path.exists() {
            crate::output::write_atomic(&path, bytes)?;
        }
    }
    Ok(dir)
}
