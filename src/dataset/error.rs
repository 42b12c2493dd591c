//! Typed loading and saving errors, and reading a text file.

use crate::output::{FileError, OutputError};
use crate::side::Side;
use std::path::{Path, PathBuf};

/// An angle in degrees and radians.
fn deg_rad(x_rad: f64) -> String {
    format!("{:.2}° ({x_rad:.4} rad)", x_rad.to_degrees())
}

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
    /// A file is missing or unreadable, or could not be written.
    #[error(transparent)]
    File(#[from] FileError),
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
    #[error(
        "{path}:{line}: expected {expected} fields (as in the header), found {found}{}",
        if *.truncated { " (the file ends inside this row: was it cut off while copying?)" } else { "" }
    )]
    FieldCount {
        path: PathBuf,
        line: usize,
        expected: usize,
        found: usize,
        /// The row is the file's last and has no line end: the file was probably truncated.
        truncated: bool,
    },
    /// Two CSV rows share an id.
    #[error("{path}:{line}: field `id`: duplicate id `{id}` (first used on line {first_line})")]
    DuplicateId {
        path: PathBuf,
        line: usize,
        id: String,
        first_line: usize,
    },
    /// The same reflector coordinates in two rows (of one file or of both arms): a row pasted twice.
    #[error(
        "{path}:{line}: the reflector coordinates of `{id}` repeat those of `{first_id}` ({}:{first_line}) \
         exactly; a tracker never measures the same values twice: a row pasted twice?",
        .first_path.display()
    )]
    DuplicateRow {
        path: PathBuf,
        line: usize,
        id: String,
        first_path: PathBuf,
        first_line: usize,
        first_id: String,
    },
    /// The three reflectors of a row are (nearly) collinear or coincide: no flange pose can be measured
    /// from them.
    #[error("{path}:{line}: {message}")]
    DegenerateTriangle {
        path: PathBuf,
        line: usize,
        message: String,
    },
    /// The measured coordinates do not fit the declared length unit or the nominal reflectors.
    #[error("{path}: {message}")]
    UnitMismatch { path: PathBuf, message: String },
    /// A prismatic joint's value outside its limits (mm).
    #[error(
        "{path}:{line}: field `{field}`: {value_mm:.3} mm is outside the prismatic joint's limits \
         [{lower_mm:.3}, {upper_mm:.3}] mm of the robot description{hint}"
    )]
    JointTravel {
        path: PathBuf,
        line: usize,
        field: String,
        value_mm: f64,
        lower_mm: f64,
        upper_mm: f64,
        hint: String,
    },
    /// A joint value outside the robot's joint limits.
    #[error(
        "{path}:{line}: field `{field}`: {} is outside the joint's limits [{}, {}] of the robot \
         description{hint}",
        deg_rad(*.value_rad), deg_rad(*.lower_rad), deg_rad(*.upper_rad)
    )]
    JointLimit {
        path: PathBuf,
        line: usize,
        field: String,
        value_rad: f64,
        lower_rad: f64,
        upper_rad: f64,
        /// More values out of range in this file, a likely cause (swapped columns, unit), or nothing.
        hint: String,
    },
    /// A file is not UTF-8 text (UTF-16, binary data) or too large.
    #[error("{path}: {problem}")]
    Text {
        path: PathBuf,
        problem: crate::textfile::TextProblem,
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

/// 1-based line and column of byte `offset` in `text`, and a short excerpt of that line (trimmed).
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
        .unwrap_or("");
    (line, col, crate::textfile::excerpt(line_text.trim()))
}

/// Read a text file: UTF-8, an optional byte-order mark is dropped (see [`crate::textfile`]).
pub(super) fn read_text(
    files: &dyn crate::source::FileSource,
    path: &Path,
) -> Result<String, DatasetError> {
    use crate::textfile::{ReadError, TextProblem};
    crate::textfile::read_from(files, path).map_err(|e| match e {
        ReadError::Io(error) => FileError::read(path, error).into(),
        ReadError::Text(TextProblem::InvalidUtf8 { line, byte }) => DatasetError::Encoding {
            path: path.to_path_buf(),
            line,
            byte,
        },
        ReadError::Text(problem) => DatasetError::Text {
            path: path.to_path_buf(),
            problem,
        },
    })
}
