//! Safe output files: atomic writes (temporary file in the same directory, then rename) and guards that
//! keep outputs from silently replacing a user's files.
//!
//! A reader never sees a half-written file: either the old content or the new one. Writers in dualcal
//! go through [`write_atomic`]; commands that write next to their inputs check [`refuse_overwrite_input`]
//! first, and writers of whole directories check [`refuse_existing`] unless the user asked to overwrite.

use std::io::Write;
use std::path::{Path, PathBuf};

/// Whether an output may replace files that already exist.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
pub enum Overwrite {
    /// Refuse if any output file exists (the default).
    #[default]
    Refuse,
    /// Replace existing output files (the user passed an explicit flag such as `--force`).
    Allow,
}

/// Why an output was refused.
#[derive(Debug, thiserror::Error)]
pub enum OutputError {
    /// The output path is one of the command's input files.
    #[error("{out}: refusing to overwrite the input file {input}")]
    WouldOverwriteInput { out: PathBuf, input: PathBuf },
    /// The output exists and overwriting was not requested.
    #[error("{path}: already exists; refusing to overwrite it without an explicit overwrite flag")]
    Exists { path: PathBuf },
}

/// A file that could not be read or written, with the system's reason: what the dataset, import and
/// parameter-file errors say of it. (The message includes `error`'s, so it is not also the error's
/// `source`, which `{:#}` would print a second time.)
#[derive(Debug, thiserror::Error)]
pub enum FileError {
    /// A file is missing or unreadable.
    #[error("{path}: cannot read: {error}")]
    Read {
        path: PathBuf,
        error: std::io::Error,
    },
    /// A file could not be written.
    #[error("{path}: cannot write: {error}")]
    Write {
        path: PathBuf,
        error: std::io::Error,
    },
}

impl FileError {
    /// `path` could not be read.
    pub fn read(path: &Path, error: std::io::Error) -> Self {
        FileError::Read {
            path: path.to_path_buf(),
            error,
        }
    }

    /// `path` could not be written.
    pub fn write(path: &Path, error: std::io::Error) -> Self {
        FileError::Write {
            path: path.to_path_buf(),
            error,
        }
    }

    /// The file the error is about.
    pub fn path(&self) -> &Path {
        match self {
            FileError::Read { path, .. } | FileError::Write { path, .. } => path,
        }
    }
}

/// Write `bytes` to `path` atomically: a temporary file in the same directory is written, flushed to
/// disk and renamed over `path`. The parent directory must exist. On any error (a full disk, no
/// permission, `path` is a directory) the temporary file is removed, an existing `path` is left as it
/// was, and the error says so.
pub fn write_atomic(path: &Path, bytes: &[u8]) -> std::io::Result<()> {
    write_atomic_with(path, |file| file.write_all(bytes))
}

/// [`write_atomic`] with the content written by `write` (which may fail half-way: the old file is kept).
pub fn write_atomic_with(
    path: &Path,
    write: impl FnOnce(&mut std::fs::File) -> std::io::Result<()>,
) -> std::io::Result<()> {
    write_atomic_inner(path, write).map_err(|e| {
        let kept = if path.symlink_metadata().is_ok() {
            "the existing file was left unchanged"
        } else {
            "nothing was written"
        };
        std::io::Error::new(e.kind(), format!("{e}; {kept}"))
    })
}

fn write_atomic_inner(
    path: &Path,
    write: impl FnOnce(&mut std::fs::File) -> std::io::Result<()>,
) -> std::io::Result<()> {
    let dir = match path.parent() {
        Some(p) if !p.as_os_str().is_empty() => p,
        _ => Path::new("."),
    };
    if path.file_name().is_none() {
        return Err(std::io::Error::new(
            std::io::ErrorKind::InvalidInput,
            "output path has no file name",
        ));
    }
    if path.is_dir() {
        return Err(std::io::Error::new(
            std::io::ErrorKind::IsADirectory,
            "the output path is a directory",
        ));
    }
    let mut builder = tempfile::Builder::new();
    builder.prefix(".dualcal-").suffix(".tmp");
    // Ordinary file permissions (0644 less the umask), not the private 0600 of a temporary file.
    #[cfg(unix)]
    {
        use std::os::unix::fs::PermissionsExt;
        builder.permissions(std::fs::Permissions::from_mode(0o644));
    }
    // Dropping `tmp` on an error below removes the temporary file.
    let mut tmp = builder.tempfile_in(dir)?;
    write(tmp.as_file_mut())?;
    tmp.flush()?;
    tmp.as_file().sync_all()?;
    tmp.persist(path).map_err(|e| e.error)?;
    Ok(())
}

/// The absolute, symlink-free form of `path`, also when `path` itself does not exist yet (its parent is
/// canonicalised and the file name appended). Falls back to the path as given.
fn normalised(path: &Path) -> PathBuf {
    if let Ok(p) = path.canonicalize() {
        return p;
    }
    match (path.parent(), path.file_name()) {
        (Some(parent), Some(name)) => {
            let parent = if parent.as_os_str().is_empty() {
                Path::new(".")
            } else {
                parent
            };
            match parent.canonicalize() {
                Ok(p) => p.join(name),
                Err(_) => path.to_path_buf(),
            }
        }
        _ => path.to_path_buf(),
    }
}

/// Refuse when `out` names the same file as one of `inputs` (after resolving `.`/`..` and symlinks).
pub fn refuse_overwrite_input(out: &Path, inputs: &[&Path]) -> Result<(), OutputError> {
    let out_n = normalised(out);
    for input in inputs {
        if normalised(input) == out_n {
            return Err(OutputError::WouldOverwriteInput {
                out: out.to_path_buf(),
                input: input.to_path_buf(),
            });
        }
    }
    Ok(())
}

/// With [`Overwrite::Refuse`], refuse when any of `outputs` exists; with [`Overwrite::Allow`], accept.
pub fn refuse_existing(outputs: &[&Path], overwrite: Overwrite) -> Result<(), OutputError> {
    if overwrite == Overwrite::Allow {
        return Ok(());
    }
    for out in outputs {
        // `symlink_metadata` also sees dangling symlinks, which a rename would replace.
        if out.symlink_metadata().is_ok() {
            return Err(OutputError::Exists {
                path: out.to_path_buf(),
            });
        }
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn write_atomic_creates_and_replaces() {
        let dir = tempfile::tempdir().unwrap();
        let p = dir.path().join("out.txt");
        write_atomic(&p, b"first").unwrap();
        assert_eq!(std::fs::read(&p).unwrap(), b"first");
        write_atomic(&p, b"second, longer").unwrap();
        assert_eq!(std::fs::read(&p).unwrap(), b"second, longer");
        // No temporary files are left behind.
        let names: Vec<_> = std::fs::read_dir(dir.path())
            .unwrap()
            .map(|e| e.unwrap().file_name())
            .collect();
        assert_eq!(names, vec![std::ffi::OsString::from("out.txt")]);
    }

    /// A disk that fills up half-way through the write: the old file stays, no temporary file is left
    /// behind, and the error says the old file was kept.
    #[test]
    fn a_failed_write_keeps_the_old_file() {
        let dir = tempfile::tempdir().unwrap();
        let p = dir.path().join("params.json");
        write_atomic(&p, b"old content").unwrap();
        let err = write_atomic_with(&p, |f| {
            f.write_all(b"new con")?;
            Err(std::io::Error::new(
                std::io::ErrorKind::StorageFull,
                "No space left on device",
            ))
        })
        .unwrap_err();
        assert_eq!(err.kind(), std::io::ErrorKind::StorageFull);
        assert!(err.to_string().contains("left unchanged"), "{err}");
        assert_eq!(std::fs::read(&p).unwrap(), b"old content");
        assert_eq!(std::fs::read_dir(dir.path()).unwrap().count(), 1);
        // A new file that fails: nothing is left.
        let q = dir.path().join("new.json");
        let err = write_atomic_with(&q, |_| Err(std::io::Error::other("boom"))).unwrap_err();
        assert!(err.to_string().contains("nothing was written"), "{err}");
        assert!(!q.exists());
        // A directory in the way is not replaced.
        std::fs::create_dir(dir.path().join("out")).unwrap();
        let err = write_atomic(&dir.path().join("out"), b"x").unwrap_err();
        assert!(err.to_string().contains("directory"), "{err}");
        assert!(dir.path().join("out").is_dir());
    }

    #[test]
    fn write_atomic_fails_cleanly_without_parent() {
        let dir = tempfile::tempdir().unwrap();
        let p = dir.path().join("missing").join("out.txt");
        assert!(write_atomic(&p, b"x").is_err());
        assert!(!p.exists());
    }

    #[test]
    fn refuses_to_overwrite_an_input_by_another_name() {
        let dir = tempfile::tempdir().unwrap();
        let input = dir.path().join("data.csv");
        std::fs::write(&input, "x").unwrap();
        std::fs::create_dir(dir.path().join("sub")).unwrap();
        let same = dir.path().join("sub").join("..").join("data.csv");
        let err =
            refuse_overwrite_input(&same, &[Path::new("/nonexistent/a"), &input]).unwrap_err();
        assert!(matches!(err, OutputError::WouldOverwriteInput { .. }));
        assert!(err.to_string().contains("data.csv"));
        let other = dir.path().join("other.csv");
        refuse_overwrite_input(&other, &[&input]).unwrap();
    }

    #[test]
    fn refuse_existing_respects_the_flag() {
        let dir = tempfile::tempdir().unwrap();
        let p = dir.path().join("dataset.toml");
        let q = dir.path().join("left.csv");
        refuse_existing(&[&p, &q], Overwrite::Refuse).unwrap();
        std::fs::write(&q, "x").unwrap();
        let err = refuse_existing(&[&p, &q], Overwrite::Refuse).unwrap_err();
        assert!(matches!(err, OutputError::Exists { ref path } if path == &q));
        refuse_existing(&[&p, &q], Overwrite::Allow).unwrap();
    }
}
