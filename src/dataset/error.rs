//! Typed loading and saving errors, and reading a text file.

use crate::atomic::OutputError;
use crate::side::Side;
use std::path::{Path, PathBuf};

/// `path:line` or `path` when the line is unknown.
fn at(path: &Path, line: &Option<usize>) -> String {
    match line {
        Some(l) => format!("{}:{l}", path.display()),
        None => path.display().to_string(),
    }
}

/// Typed loading and saving errors. Every variant names the file; errors inside a file name the line
/// (1-based) and, where there is one, the field (CSV column or TOML key).
#[derive(Debug, thiserror::Error)]
pub enum DatasetError {
    /// A file is missing or unreadable.
    #[error("{path}: cannot read: {source}")]
    Io {
        path: PathBuf,
        #[source]
        source: std::io::Error,
    },
    /// A file could not be written.
    #[error("{path}: cannot write: {source}")]
    Write {
        path: PathBuf,
        #[source]
        source: std::io::Error,
    },
    /// A file is not valid UTF-8 text.
    #[error("{path}:{line}: not valid UTF-8 text (byte {byte} of the file); save it as UTF-8")]
    Encoding {
        path: PathBuf,
        line: usize,
        byte: usize,
    },
    /// `dataset.toml` is not valid TOML or a value has the wrong type.
    #[error("{}: {message} (in `{text}`)", at(.path, .line))]
    Toml {
        path: PathBuf,
        line: Option<usize>,
        /// The offending line of the file, trimmed.
        text: String,
        message: String,
    },
    /// `dataset.toml` parses but a value is wrong (format tag, unit, arm, reflector, ...).
    #[error("{}: field `{field}`: {message}", at(.path, .line))]
    Manifest {
        path: PathBuf,
        line: Option<usize>,
        field: String,
        message: String,
    },
    /// The CSV header is missing or its columns are unknown, missing or out of order.
    #[error("{path}:{line}: header, column `{field}`: {message}")]
    Header {
        path: PathBuf,
        line: usize,
        field: String,
        message: String,
    },
    /// A CSV value is wrong (not a number, not finite, empty, unknown split).
    #[error("{path}:{line}: field `{field}`: {message}")]
    Field {
        path: PathBuf,
        line: usize,
        field: String,
        message: String,
    },
    /// A CSV row has a different number of fields than the header.
    #[error("{path}:{line}: expected {expected} fields (as in the header), found {found}")]
    FieldCount {
        path: PathBuf,
        line: usize,
        expected: usize,
        found: usize,
    },
    /// Two CSV rows share an id.
    #[error("{path}:{line}: field `id`: duplicate id `{id}` (first used on line {first_line})")]
    DuplicateId {
        path: PathBuf,
        line: usize,
        id: String,
        first_line: usize,
    },
    /// An arm has fewer configurations than the calibration needs.
    #[error(
        "{path}: the {side} arm has {found} configurations (rows); at least {min} are needed (paper Table 2)"
    )]
    TooFewConfigurations {
        path: PathBuf,
        side: Side,
        found: usize,
        min: usize,
    },
    /// An output would replace existing files.
    #[error(transparent)]
    Output(#[from] OutputError),
    /// Other content problems (also data that cannot be saved faithfully).
    #[error("{path}: {message}")]
    Content { path: PathBuf, message: String },
}

/// 1-based line and column of byte `offset` in `text`, and the trimmed text of that line.
pub(super) fn line_col(text: &str, offset: usize) -> (usize, usize, String) {
    let offset = offset.min(text.len());
    let before = text.as_bytes().get(..offset).unwrap_or(&[]);
    let line = before.iter().filter(|&&b| b == b'\n').count() + 1;
    let line_start = before
        .iter()
        .rposition(|&b| b == b'\n')
        .map_or(0, |p| p + 1);
    let col = offset - line_start + 1;
    let line_text = text
        .get(line_start..)
        .unwrap_or("")
        .lines()
        .next()
        .unwrap_or("")
        .trim()
        .to_string();
    (line, col, line_text)
}

/// Read a text file: UTF-8, an optional byte-order mark is dropped.
pub(super) fn read_text(path: &Path) -> Result<String, DatasetError> {
    let bytes = std::fs::read(path).map_err(|source| DatasetError::Io {
        path: path.to_path_buf(),
        source,
    })?;
    let (bom, body) = match bytes.strip_prefix(b"\xEF\xBB\xBF") {
        Some(rest) => (3, rest),
        None => (0, &bytes[..]),
    };
    match std::str::from_utf8(body) {
        Ok(s) => Ok(s.to_owned()),
        Err(e) => {
            let pos = e.valid_up_to();
            let line = body[..pos].iter().filter(|&&b| b == b'\n').count() + 1;
            Err(DatasetError::Encoding {
                path: path.to_path_buf(),
                line,
                byte: pos + bom + 1,
            })
        }
    }
}
