//! Joint logs kept as spreadsheets (`.xlsx`, `.xlsm`, `.xls`, `.ods`): the first sheet, or the one
//! named, read with calamine; its cells as text rows, then read as a CSV joint log is (header
//! `id`, `j1…`/`q1…`/`A1…`/`axis 1…` or the arm's joint names, a unit in brackets; degrees
//! otherwise). Rows are numbered as the spreadsheet numbers them.

use super::error::ImportError;
#[cfg(not(target_arch = "wasm32"))]
use super::joints;
use super::joints::{JointLog, JointLogOptions};
use crate::source::FileSource;
#[cfg(not(target_arch = "wasm32"))]
use calamine::{Data, Reader};
use std::path::Path;

/// The largest spreadsheet read, bytes.
const MAX_SHEET_BYTES: u64 = 64 << 20;

/// Whether a joint log is a spreadsheet (by its extension).
pub fn is_sheet(path: &Path) -> bool {
    path.extension().and_then(|e| e.to_str()).is_some_and(|e| {
        matches!(
            e.to_lowercase().as_str(),
            "xlsx" | "xlsm" | "xlsb" | "xls" | "ods"
        )
    })
}

/// Read a spreadsheet joint log: sheet `sheet` (`None`: the first, noted in the log's notes).
pub fn read(
    files: &dyn FileSource,
    path: &Path,
    sheet: Option<&str>,
    o: &JointLogOptions,
) -> Result<JointLog, ImportError> {
    let bytes = files
        .read_limited(path, MAX_SHEET_BYTES)
        .map_err(|error| crate::output::FileError::read(path, error))?;
    read_book(path, bytes, sheet, o)
}

/// In a browser: no spreadsheet reader in the module (its size budget).
#[cfg(target_arch = "wasm32")]
fn read_book(
    path: &Path,
    _bytes: Vec<u8>,
    _sheet: Option<&str>,
    _o: &JointLogOptions,
) -> Result<JointLog, ImportError> {
    Err(ImportError::Format {
        path: path.to_path_buf(),
        message: "spreadsheets are read by the desktop workbench and `dualcal import`, not in the \
                  browser: save the sheet as CSV (the same header and rows) and choose that"
            .into(),
    })
}

/// The workbook in `bytes`: its sheet `sheet` (`None`: the first) as a joint log.
#[cfg(not(target_arch = "wasm32"))]
fn read_book(
    path: &Path,
    bytes: Vec<u8>,
    sheet: Option<&str>,
    o: &JointLogOptions,
) -> Result<JointLog, ImportError> {
    let format_error = |message: String| ImportError::Format {
        path: path.to_path_buf(),
        message,
    };
    let mut book =
        calamine::open_workbook_auto_from_rs(std::io::Cursor::new(bytes)).map_err(|e| {
            format_error(format!(
                "not a spreadsheet calamine can read (.xlsx, .xls, .ods): {e}"
            ))
        })?;
    let names = book.sheet_names();
    let (name, note) = match sheet {
        Some(s) if names.iter().any(|n| n == s) => (s.to_string(), None),
        Some(s) => {
            return Err(format_error(format!(
                "no sheet `{s}`; its sheets: {}",
                names.join(", ")
            )));
        }
        None => {
            let first = names
                .first()
                .cloned()
                .ok_or_else(|| format_error("no sheets".to_string()))?;
            let note = (names.len() > 1).then(|| {
                format!(
                    "sheet: `{first}`, the first of {} (--sheet to choose another: {})",
                    names.len(),
                    names[1..].join(", ")
                )
            });
            (first, note)
        }
    };
    let range = book
        .worksheet_range(&name)
        .map_err(|e| format_error(format!("sheet `{name}`: {e}")))?;
    let (row0, _) = range.start().unwrap_or((0, 0));
    let rows: Vec<(usize, Vec<String>)> = range
        .rows()
        .enumerate()
        .map(|(k, cells)| (row0 as usize + k + 1, cells.iter().map(cell_text).collect()))
        .filter(|(_, cells): &(usize, Vec<String>)| cells.iter().any(|c| !c.is_empty()))
        .collect();
    let mut log = joints::read_rows(path, &rows, false, o)?;
    log.notes.insert(
        0,
        note.unwrap_or_else(|| format!("sheet: `{name}` (rows numbered as in the spreadsheet)")),
    );
    Ok(log)
}

#[cfg(not(target_arch = "wasm32"))]
/// A cell as the text reader sees it: numbers in their shortest exact form, dates and times as
/// seconds (Excel's day count × 86 400), text as it is.
fn cell_text(cell: &Data) -> String {
    match cell {
        Data::Empty => String::new(),
        Data::Int(i) => i.to_string(),
        Data::Float(v) => format!("{v:?}"),
        Data::String(s) | Data::DateTimeIso(s) | Data::DurationIso(s) => s.trim().to_string(),
        Data::Bool(b) => b.to_string(),
        Data::DateTime(d) => format!("{:?}", d.as_f64() * 86_400.0),
        Data::Error(e) => format!("#{e:?}"),
    }
}
