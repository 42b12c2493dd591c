//! Where the engine reads its input files from: the operating system's file system ([`OsFiles`]), or
//! files held in memory ([`MemoryFiles`]: the compiled-in example, files a browser user picked or
//! dropped, an unpacked `.zip`). The dataset, robot and mesh loaders read through a [`FileSource`];
//! paths stay the currency (errors name them; a manifest's CSV names, its `robot` entry and a URDF's
//! mesh paths resolve against them as on disk), so files in memory are mounted under a made-up folder
//! such as `/uploads/2/`.
//!
//! [`FileKind`] is the one rule for what a file is by its name (a robot description, a xacro source,
//! a dataset manifest, a `.zip`, a mesh, a CSV): the loaders, the command line and the workbench
//! (dropped files, uploads, file dialogs) all ask it.

use std::collections::BTreeMap;
use std::io::Read as _;
use std::path::{Component, Path, PathBuf};
use std::sync::{Arc, Mutex, PoisonError};

/// A mesh file's format ([`FileKind::Mesh`]).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum MeshFormat {
    /// `.stl` (binary or ASCII).
    Stl,
    /// `.dae` (Collada).
    Collada,
    /// `.obj` (Wavefront).
    Obj,
}

/// What a file is to dualcal, by its name: the one rule every part of the program uses (the robot
/// loader refuses a xacro source by it, the mesh loader picks its reader by it, the workbench opens a
/// dropped or uploaded file by it and filters its file dialogs by it).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum FileKind {
    /// A robot description: `.urdf` (or `.xml`, as URDF files are sometimes named).
    Urdf,
    /// A xacro source of a robot description (`.xacro`, `.urdf.xacro`): refused with the command
    /// that expands it into a URDF.
    Xacro,
    /// A dataset manifest: `dataset.toml` ([`crate::dataset::MANIFEST_FILE`]) or another `.toml`.
    DatasetManifest,
    /// A `.zip` archive of inputs (unpacked into memory, [`unpack_zip`]).
    Zip,
    /// A mesh a robot description refers to.
    Mesh(MeshFormat),
    /// A `.csv` file (one arm's measurements).
    Csv,
    /// Anything else (a folder, a parameter file, a file without an extension).
    Other,
}

/// The extensions of each kind (lower case; compared without regard to case).
const KIND_EXTENSIONS: &[(FileKind, &[&str])] = &[
    (FileKind::Urdf, &["urdf", "xml"]),
    (FileKind::Xacro, &["xacro"]),
    (FileKind::DatasetManifest, &["toml"]),
    (FileKind::Zip, &["zip"]),
    (FileKind::Mesh(MeshFormat::Stl), &["stl"]),
    (FileKind::Mesh(MeshFormat::Collada), &["dae"]),
    (FileKind::Mesh(MeshFormat::Obj), &["obj"]),
    (FileKind::Csv, &["csv"]),
];

impl FileKind {
    /// The kind of the file at `path`, by its extension (case-insensitive).
    pub fn of(path: &Path) -> FileKind {
        let Some(ext) = path.extension().and_then(|e| e.to_str()) else {
            return FileKind::Other;
        };
        KIND_EXTENSIONS
            .iter()
            .find(|(_, exts)| exts.iter().any(|e| e.eq_ignore_ascii_case(ext)))
            .map_or(FileKind::Other, |(kind, _)| *kind)
    }

    /// The extensions of this kind, lower case, without the dot (empty for [`FileKind::Other`]).
    pub fn extensions(self) -> &'static [&'static str] {
        KIND_EXTENSIONS
            .iter()
            .find(|(kind, _)| *kind == self)
            .map_or(&[], |(_, exts)| exts)
    }

    /// A robot description or its xacro source: what opens as the robot (a xacro file then says how
    /// to expand it).
    pub fn is_robot(self) -> bool {
        matches!(self, FileKind::Urdf | FileKind::Xacro)
    }

    /// The extensions of every robot kind ([`FileKind::is_robot`]), for a file dialog's filter.
    pub fn robot_extensions() -> Vec<&'static str> {
        KIND_EXTENSIONS
            .iter()
            .filter(|(kind, _)| kind.is_robot())
            .flat_map(|(_, exts)| exts.iter().copied())
            .collect()
    }
}

/// Read-only access to files by path.
pub trait FileSource: Send + Sync + std::fmt::Debug {
    /// The whole file, at most `limit` bytes: a longer file is an error of kind `FileTooLarge`.
    fn read_limited(&self, path: &Path, limit: u64) -> std::io::Result<Vec<u8>>;
    /// Whether `path` is a regular file.
    fn is_file(&self, path: &Path) -> bool;
    /// Whether `path` is a folder (in memory: a prefix of some file's path).
    fn is_dir(&self, path: &Path) -> bool;
    /// The entries of folder `path` (full paths); empty when it is none.
    fn read_dir(&self, path: &Path) -> Vec<PathBuf>;
}

/// The operating system's file system.
#[derive(Clone, Copy, Debug, Default)]
pub struct OsFiles;

impl FileSource for OsFiles {
    fn read_limited(&self, path: &Path, limit: u64) -> std::io::Result<Vec<u8>> {
        let file = std::fs::File::open(path)?;
        let meta = file.metadata()?;
        // Only regular files (not devices or pipes, whose length is unknown).
        if !meta.is_file() {
            return Err(std::io::Error::new(
                std::io::ErrorKind::InvalidInput,
                "not a regular file",
            ));
        }
        if meta.len() > limit {
            return Err(too_large());
        }
        let mut bytes = Vec::new();
        // `take` bounds a file that grows while it is read.
        file.take(limit + 1).read_to_end(&mut bytes)?;
        if bytes.len() as u64 > limit {
            return Err(too_large());
        }
        Ok(bytes)
    }

    fn is_file(&self, path: &Path) -> bool {
        path.is_file()
    }

    fn is_dir(&self, path: &Path) -> bool {
        path.is_dir()
    }

    fn read_dir(&self, path: &Path) -> Vec<PathBuf> {
        std::fs::read_dir(path)
            .map(|entries| entries.flatten().map(|e| e.path()).collect())
            .unwrap_or_default()
    }
}

fn too_large() -> std::io::Error {
    std::io::Error::new(std::io::ErrorKind::FileTooLarge, "file too large")
}

/// A shared [`FileSource`] to keep in a loader's options (default: the file system).
#[derive(Clone, Debug)]
pub struct Files(pub Arc<dyn FileSource>);

impl Default for Files {
    fn default() -> Self {
        Files(Arc::new(OsFiles))
    }
}

impl std::ops::Deref for Files {
    type Target = dyn FileSource;

    fn deref(&self) -> &Self::Target {
        &*self.0
    }
}

/// Files in memory, keyed by a normalised absolute path. Clones share the same files (one part of a
/// program adds files that another then reads).
#[derive(Clone, Debug, Default)]
pub struct MemoryFiles {
    files: Arc<Mutex<BTreeMap<PathBuf, Arc<[u8]>>>>,
}

impl MemoryFiles {
    pub fn new() -> Self {
        Self::default()
    }

    /// Add or replace a file.
    pub fn insert(&self, path: impl AsRef<Path>, bytes: impl Into<Arc<[u8]>>) {
        let key = normalise(path.as_ref());
        self.lock().insert(key, bytes.into());
    }

    /// Every file's path, sorted.
    pub fn paths(&self) -> Vec<PathBuf> {
        self.lock().keys().cloned().collect()
    }

    fn get(&self, path: &Path) -> Option<Arc<[u8]>> {
        self.lock().get(&normalise(path)).cloned()
    }

    fn lock(&self) -> std::sync::MutexGuard<'_, BTreeMap<PathBuf, Arc<[u8]>>> {
        self.files.lock().unwrap_or_else(PoisonError::into_inner)
    }
}

impl FileSource for MemoryFiles {
    fn read_limited(&self, path: &Path, limit: u64) -> std::io::Result<Vec<u8>> {
        let bytes = self.get(path).ok_or_else(|| {
            std::io::Error::new(
                std::io::ErrorKind::NotFound,
                "no such file among the files given",
            )
        })?;
        if bytes.len() as u64 > limit {
            return Err(too_large());
        }
        Ok(bytes.to_vec())
    }

    fn is_file(&self, path: &Path) -> bool {
        self.get(path).is_some()
    }

    fn is_dir(&self, path: &Path) -> bool {
        let dir = normalise(path);
        self.lock().keys().any(|k| k != &dir && k.starts_with(&dir))
    }

    fn read_dir(&self, path: &Path) -> Vec<PathBuf> {
        let dir = normalise(path);
        let mut entries: Vec<PathBuf> = self
            .lock()
            .keys()
            .filter_map(|k| {
                let first = k.strip_prefix(&dir).ok()?.components().next()?;
                Some(dir.join(first))
            })
            .collect();
        entries.dedup();
        entries
    }
}

/// `/a/./b/../c` → `/a/c`; relative paths are taken from `/`.
fn normalise(path: &Path) -> PathBuf {
    let mut out = PathBuf::from("/");
    for c in path.components() {
        match c {
            Component::Normal(part) => out.push(part),
            Component::ParentDir => {
                out.pop();
            }
            Component::RootDir | Component::CurDir | Component::Prefix(_) => {}
        }
    }
    out
}

/// Why an archive could not be unpacked.
#[derive(Debug, thiserror::Error)]
pub enum ArchiveError {
    #[error("{name}: not a readable .zip archive: {message}")]
    Unreadable { name: String, message: String },
    #[error("{name}: entry `{entry}` cannot be unpacked: {message}")]
    Entry {
        name: String,
        entry: String,
        message: String,
    },
    #[error(
        "{name}: unpacks to more than {} MiB; not a dualcal input",
        MAX_UNPACKED_BYTES / (1024 * 1024)
    )]
    TooLarge { name: String },
}

/// Most a `.zip` may unpack to: 512 MiB (a robot's visual meshes are tens of MB).
pub const MAX_UNPACKED_BYTES: u64 = 512 * 1024 * 1024;

/// Unpack the `.zip` archive `bytes` (called `name` in messages) into `files` under `dir`, keeping
/// its folder layout (so a manifest's CSVs and a URDF's meshes resolve as they did on disk). Entries
/// whose names leave the archive (`..`, absolute) are skipped; folders and macOS resource forks
/// (`__MACOSX/`) too. Returns the paths written.
pub fn unpack_zip(
    files: &MemoryFiles,
    dir: &Path,
    name: &str,
    bytes: &[u8],
) -> Result<Vec<PathBuf>, ArchiveError> {
    let mut archive = zip::ZipArchive::new(std::io::Cursor::new(bytes)).map_err(|e| {
        ArchiveError::Unreadable {
            name: name.into(),
            message: e.to_string(),
        }
    })?;
    let mut written = Vec::new();
    let mut total = 0u64;
    for k in 0..archive.len() {
        let mut entry = archive.by_index(k).map_err(|e| ArchiveError::Unreadable {
            name: name.into(),
            message: e.to_string(),
        })?;
        let Some(relative) = entry.enclosed_name() else {
            continue;
        };
        if entry.is_dir() || relative.starts_with("__MACOSX") {
            continue;
        }
        let entry_err = |message: String| ArchiveError::Entry {
            name: name.into(),
            entry: relative.display().to_string(),
            message,
        };
        let mut content = Vec::new();
        // Bounded by what is left of the total, whatever the entry's header claims.
        let left = MAX_UNPACKED_BYTES.saturating_sub(total);
        (&mut entry)
            .take(left + 1)
            .read_to_end(&mut content)
            .map_err(|e| entry_err(e.to_string()))?;
        total += content.len() as u64;
        if total > MAX_UNPACKED_BYTES {
            return Err(ArchiveError::TooLarge { name: name.into() });
        }
        let path = normalise(&dir.join(&relative));
        files.insert(&path, content);
        written.push(path);
    }
    Ok(written)
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::io::Write as _;

    #[test]
    fn file_kinds_by_name() {
        let kind = |p: &str| FileKind::of(Path::new(p));
        assert_eq!(kind("/a/robot.urdf"), FileKind::Urdf);
        assert_eq!(kind("ROBOT.URDF"), FileKind::Urdf);
        assert_eq!(kind("yumi.xml"), FileKind::Urdf);
        assert_eq!(kind("yumi.urdf.xacro"), FileKind::Xacro);
        assert_eq!(kind("data/dataset.toml"), FileKind::DatasetManifest);
        assert_eq!(kind("other.TOML"), FileKind::DatasetManifest);
        assert_eq!(kind("cell.zip"), FileKind::Zip);
        assert_eq!(kind("m/link.STL"), FileKind::Mesh(MeshFormat::Stl));
        assert_eq!(kind("m/link.dae"), FileKind::Mesh(MeshFormat::Collada));
        assert_eq!(kind("m/link.obj"), FileKind::Mesh(MeshFormat::Obj));
        assert_eq!(kind("left.csv"), FileKind::Csv);
        assert_eq!(kind("params.json"), FileKind::Other);
        assert_eq!(kind("/a/folder"), FileKind::Other);
        assert_eq!(
            kind("/a/.urdf"),
            FileKind::Other,
            "a hidden file has no extension"
        );
        assert!(kind("r.xacro").is_robot() && kind("r.urdf").is_robot());
        assert!(!kind("dataset.toml").is_robot());
        assert_eq!(FileKind::robot_extensions(), ["urdf", "xml", "xacro"]);
        assert_eq!(FileKind::Other.extensions(), [] as [&str; 0]);
        // Every kind's extensions lead back to it.
        for (k, exts) in KIND_EXTENSIONS {
            assert_eq!(k.extensions(), *exts);
            for e in *exts {
                assert_eq!(kind(&format!("f.{e}")), *k);
            }
        }
    }

    #[test]
    fn memory_files_resolve_relative_parts_and_know_their_folders() {
        let files = MemoryFiles::new();
        files.insert("/uploads/1/dataset.toml", b"x".to_vec());
        files.insert("/uploads/1/meshes/a.stl", b"yz".to_vec());
        let shared = files.clone();
        let read = |p: &str| shared.read_limited(Path::new(p), 100);
        assert_eq!(read("/uploads/1/sub/../dataset.toml").unwrap(), b"x");
        assert!(shared.is_file(Path::new("uploads/1/./dataset.toml")));
        assert!(shared.is_dir(Path::new("/uploads/1")));
        assert!(shared.is_dir(Path::new("/uploads")));
        assert!(!shared.is_dir(Path::new("/uploads/1/dataset.toml")));
        assert!(!shared.is_file(Path::new("/uploads/1")));
        assert_eq!(
            shared.read_dir(Path::new("/uploads/1")),
            [
                PathBuf::from("/uploads/1/dataset.toml"),
                PathBuf::from("/uploads/1/meshes")
            ]
        );
        let err = read("/uploads/2/left.csv").unwrap_err();
        assert_eq!(err.kind(), std::io::ErrorKind::NotFound);
        let err = shared
            .read_limited(Path::new("/uploads/1/meshes/a.stl"), 1)
            .unwrap_err();
        assert_eq!(err.kind(), std::io::ErrorKind::FileTooLarge);
    }

    fn zip_of(entries: &[(&str, &[u8])], method: zip::CompressionMethod) -> Vec<u8> {
        let mut writer = zip::ZipWriter::new(std::io::Cursor::new(Vec::new()));
        let options = zip::write::SimpleFileOptions::default().compression_method(method);
        for (name, bytes) in entries {
            writer.start_file(*name, options).unwrap();
            writer.write_all(bytes).unwrap();
        }
        writer.finish().unwrap().into_inner()
    }

    #[test]
    fn a_zip_unpacks_with_its_layout_and_without_escaping_entries() {
        let text = b"id,q1\n".repeat(200);
        let bytes = zip_of(
            &[
                ("data/dataset.toml", b"[units]\n"),
                ("data/left.csv", &text),
                ("../evil.txt", b"no"),
                ("__MACOSX/data/._left.csv", b"fork"),
            ],
            zip::CompressionMethod::Deflated,
        );
        let files = MemoryFiles::new();
        let written = unpack_zip(&files, Path::new("/uploads/3"), "data.zip", &bytes).unwrap();
        assert_eq!(
            written,
            [
                PathBuf::from("/uploads/3/data/dataset.toml"),
                PathBuf::from("/uploads/3/data/left.csv")
            ]
        );
        assert_eq!(
            files
                .read_limited(Path::new("/uploads/3/data/left.csv"), 1 << 20)
                .unwrap(),
            text
        );
        assert_eq!(files.paths().len(), 2);

        let stored = zip_of(&[("a.urdf", b"<robot/>")], zip::CompressionMethod::Stored);
        unpack_zip(&files, Path::new("/u"), "r.zip", &stored).unwrap();
        assert!(files.is_file(Path::new("/u/a.urdf")));

        let err = unpack_zip(&files, Path::new("/v"), "x.zip", b"PK not really").unwrap_err();
        assert!(
            err.to_string().starts_with("x.zip: not a readable .zip"),
            "{err}"
        );
    }
}
