//! Typed import errors: every variant names the file and, inside a file, the line (1-based) and the
//! field (column), and says what was expected — as the dataset readers do.

use crate::dataset::DatasetError;
use crate::output::{FileError, OutputError};
use std::path::PathBuf;

/// Why an import was refused.
#[derive(Debug, thiserror::Error)]
pub enum ImportError {
    /// A file is missing or unreadable, or writing one failed.
    #[error(transparent)]
    File(#[from] FileError),
    /// A file is not text we can read (UTF-16, binary data).
    #[error("{path}: {message}")]
    Encoding { path: PathBuf, message: String },
    /// The file's format could not be recognised, or is not the one forced.
    #[error("{path}: {message}")]
    Format { path: PathBuf, message: String },
    /// A header line is missing a column, or names one twice.
    #[error("{path}:{line}: header, column `{field}`: {message}")]
    Header {
        path: PathBuf,
        line: usize,
        field: String,
        message: String,
    },
    /// A value is wrong: `expected` says what was expected, `found` what the file has.
    #[error("{path}:{line}: field `{field}`: expected {expected}, found `{found}`")]
    Field {
        path: PathBuf,
        line: usize,
        field: String,
        expected: String,
        found: String,
    },
    /// A cell is malformed, or lacks the element a mapping refers to: a bracket or quote not closed,
    /// an index beyond a vector's length, matrix rows of different lengths, text where a number was
    /// expected, an element reference on a plain cell. `line` is the first line of the record (a
    /// quoted cell may span lines), `field` the column as the mapping or the header names it.
    #[error("{path}:{line}: column `{field}`: {message}")]
    Cell {
        path: PathBuf,
        line: usize,
        field: String,
        message: String,
    },
    /// A row has fewer fields than the columns that are read.
    #[error("{path}:{line}: expected at least {expected} fields, found {found}")]
    FieldCount {
        path: PathBuf,
        line: usize,
        expected: usize,
        found: usize,
    },
    /// A message of a ROS 2 bag is wrong: `at` names the topic, the message's number on it and its
    /// time; `field` the message's field.
    #[error("{path}: {at}: field `{field}`: {message}")]
    Stream {
        path: PathBuf,
        at: String,
        field: String,
        message: String,
    },
    /// Two rows of a joint log share an id.
    #[error("{path}:{line}: field `id`: duplicate id `{id}` (first used on line {first_line})")]
    DuplicateId {
        path: PathBuf,
        line: usize,
        id: String,
        first_line: usize,
    },
    /// The import's options are inconsistent (reflectors, column mapping, joint order, matching rule).
    #[error("{0}")]
    Options(String),
    /// Too few configurations matched, or an arm's data cannot make a dataset.
    #[error("{path}: {message}")]
    Content { path: PathBuf, message: String },
    /// The output would replace files.
    #[error(transparent)]
    Output(#[from] OutputError),
    /// Writing the dataset failed, or the result is not a valid dataset.
    #[error(transparent)]
    Dataset(#[from] DatasetError),
}

impl ImportError {
    /// The 1-based line of the file the error is about, where it is about one.
    pub fn line(&self) -> Option<usize> {
        match self {
            ImportError::Header { line, .. }
            | ImportError::Field { line, .. }
            | ImportError::Cell { line, .. }
            | ImportError::FieldCount { line, .. }
            | ImportError::DuplicateId { line, .. } => Some(*line),
            _ => None,
        }
    }

    /// The field (column) the error is about, where it is about one.
    pub fn field(&self) -> Option<&str> {
        match self {
            ImportError::Header { field, .. }
            | ImportError::Field { field, .. }
            | ImportError::Cell { field, .. }
            | ImportError::Stream { field, .. } => Some(field),
            ImportError::DuplicateId { .. } => Some("id"),
            _ => None,
        }
    }

    /// The file the error is about, where it is about one.
    pub fn path(&self) -> Option<&std::path::Path> {
        match self {
            ImportError::File(e) => Some(e.path()),
            ImportError::Encoding { path, .. }
            | ImportError::Format { path, .. }
            | ImportError::Header { path, .. }
            | ImportError::Field { path, .. }
            | ImportError::Cell { path, .. }
            | ImportError::FieldCount { path, .. }
            | ImportError::DuplicateId { path, .. }
            | ImportError::Stream { path, .. }
            | ImportError::Content { path, .. } => Some(path),
            _ => None,
        }
    }
}
