//! The bundled example dataset (ours: `dualcal simulate --seed 1`), compiled into the binary so an
//! installed or moved binary opens it too.

use std::path::{Path, PathBuf};

/// The bundled example dataset, compiled into the binary (it is ours: `dualcal simulate --seed 1`).
pub(super) const EXAMPLE_FILES: [(&str, &[u8]); 4] = [
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
    let mut hasher = std::hash::DefaultHasher::new();
    EXAMPLE_FILES.hash(&mut hasher);
    let dir = root.join(format!("example-{:016x}", hasher.finish()));
    std::fs::create_dir_all(&dir)?;
    for (name, bytes) in EXAMPLE_FILES {
        let path = dir.join(name);
        if !path.exists() {
            crate::output::write_atomic(&path, bytes)?;
        }
    }
    Ok(dir)
}
