//! One arm's CSV file.

use super::error::{DatasetError, read_text};
use super::units::Units;
use super::{MIN_CONFIGS, Measurement, SPLIT_COLUMN, Split, validate};
use crate::side::Side;
use crate::textfile::excerpt;
use nalgebra::Vector3;
use std::path::Path;

/// Names of the reflector columns, in order: `<name>x, <name>y, <name>z` per reflector.
fn point_columns(reflectors: &[String]) -> Vec<String> {
    reflectors
        .iter()
        .flat_map(|r| ["x", "y", "z"].map(|c| format!("{r}{c}")))
        .collect()
}

/// The joint number of a column named `q<N>` (N ≥ 1).
fn joint_column(name: &str) -> Option<usize> {
    name.strip_prefix('q')
        .filter(|d| !d.is_empty() && d.bytes().all(|b| b.is_ascii_digit()) && !d.starts_with('0'))
        .and_then(|d| d.parse().ok())
}

/// The columns of a header with `joints` joint columns (without `split`).
pub(super) fn columns(joints: usize, reflectors: &[String]) -> Vec<String> {
    let mut out = vec!["id".to_string()];
    out.extend((1..=joints).map(|j| format!("q{j}")));
    out.extend(point_columns(reflectors));
    out
}

/// Check the header; returns the number of joint columns and whether it has the `split` column.
fn check_header(
    path: &Path,
    line: usize,
    header: &csv::StringRecord,
    reflectors: &[String],
) -> Result<(usize, bool), DatasetError> {
    let point_columns = point_columns(reflectors);
    let err = |field: &str, message: String| DatasetError::Header {
        path: path.to_path_buf(),
        line,
        field: field.to_string(),
        message,
    };
    let expected = format!("id,q1,…,qN,{},[{SPLIT_COLUMN}]", point_columns.join(","));
    if header.len() == 1 {
        let only = &excerpt(header.get(0).unwrap_or(""));
        if let Some(sep) = [';', '\t', ' '].into_iter().find(|&c| only.contains(c)) {
            return Err(err(
                only,
                format!("fields are separated by {sep:?}; use commas, with the header {expected}"),
            ));
        }
    }
    // The joint columns q1 … qN: as many as there are in sequence after `id`.
    let joints = (1..header.len())
        .take_while(|&i| header.get(i).and_then(joint_column) == Some(i))
        .count();
    // With no joint column at all, q1 is what is missing.
    let wanted = columns(joints.max(1), reflectors);
    for (i, want) in wanted.iter().map(String::as_str).enumerate() {
        let Some(got) = header.get(i) else {
            return Err(err(
                want,
                format!("missing column `{want}`; the header must be {expected}"),
            ));
        };
        if got == want {
            continue;
        }
        let got = &excerpt(got);
        let message = if joint_column(got).is_some() && i > 0 {
            format!(
                "column `{got}` is in position {}, where `q{}` belongs; the joint columns must be \
                 q1, q2, … without gaps, in this order (header {expected})",
                i + 1,
                joints + 1
            )
        } else if point_columns.contains(got) || got == SPLIT_COLUMN || got == "id" {
            format!(
                "column `{got}` is in position {}, where `{want}` belongs; the header must be {expected} in this order",
                i + 1
            )
        } else {
            format!(
                "unknown column `{got}` in position {}, where `{want}` belongs; the header must be {expected}",
                i + 1
            )
        };
        return Err(err(got, message));
    }
    let n = wanted.len();
    match header.len() {
        len if len == n => Ok((joints, false)),
        len if len == n + 1 && header.get(n) == Some(SPLIT_COLUMN) => Ok((joints, true)),
        len if len > n + 1 && header.get(n) == Some(SPLIT_COLUMN) => {
            let got = &excerpt(header.get(n + 1).unwrap_or(""));
            Err(err(
                got,
                format!(
                    "unknown column `{got}` in position {}; nothing may follow `{SPLIT_COLUMN}` (header {expected})",
                    n + 2
                ),
            ))
        }
        _ => {
            let got = &excerpt(header.get(n).unwrap_or(""));
            Err(err(
                got,
                format!(
                    "unknown column `{got}` in position {}; only `{SPLIT_COLUMN}` may follow `{}` (header {expected})",
                    n + 1,
                    point_columns.last().map_or("", String::as_str)
                ),
            ))
        }
    }
}

fn parse_number(path: &Path, line: usize, field: &str, s: &str) -> Result<f64, DatasetError> {
    let err = |message: String| DatasetError::Field {
        path: path.to_path_buf(),
        line,
        field: field.to_string(),
        message,
    };
    if s.is_empty() {
        return Err(err("empty value; expected a number".into()));
    }
    let x: f64 = s
        .parse()
        .map_err(|_| err(format!("`{}` is not a number", excerpt(s))))?;
    if !x.is_finite() {
        return Err(err(format!("`{}` is not a finite number", excerpt(s))));
    }
    Ok(x)
}

/// Finds the 1-based line of CSV records from the byte offset where the reader started each record.
#[derive(Default)]
struct LineCounter {
    /// A byte offset and the line it is on.
    offset: usize,
    line: usize,
}

impl LineCounter {
    /// Line of the first byte of the record read from `start` on: blank lines and `#` comment lines are
    /// skipped as the CSV reader skips them.
    fn record_line(&mut self, text: &str, start: usize) -> usize {
        let bytes = text.as_bytes();
        let mut i = start.min(bytes.len());
        loop {
            match bytes.get(i) {
                Some(b'\r' | b'\n') => i += 1,
                Some(b'#') => match bytes[i..].iter().position(|&b| b == b'\n') {
                    Some(k) => i += k + 1,
                    None => {
                        i = bytes.len();
                        break;
                    }
                },
                _ => break,
            }
        }
        if i < self.offset || self.line == 0 {
            self.offset = 0;
            self.line = 1;
        }
        self.line += bytes[self.offset..i]
            .iter()
            .filter(|&&b| b == b'\n')
            .count();
        self.offset = i;
        self.line
    }
}

/// A CSV reader error as a dataset error at `line`; `last_line` is the file's last line with content
/// and `ends_open` whether the file ends without a line end (a row cut off there was truncated).
fn csv_error(
    path: &Path,
    e: csv::Error,
    line: usize,
    last_line: usize,
    ends_open: bool,
) -> DatasetError {
    match e.kind() {
        csv::ErrorKind::UnequalLengths {
            expected_len, len, ..
        } => DatasetError::FieldCount {
            path: path.to_path_buf(),
            line,
            expected: usize::try_from(*expected_len).unwrap_or(usize::MAX),
            found: usize::try_from(*len).unwrap_or(usize::MAX),
            truncated: ends_open && line == last_line && len < expected_len,
        },
        _ => DatasetError::Content {
            path: path.to_path_buf(),
            message: format!("line {line}: {e}"),
        },
    }
}

/// What the header says a row holds.
#[derive(Clone, Copy)]
struct RowLayout {
    joints: usize,
    reflectors: usize,
    has_split: bool,
    units: Units,
}

/// One data row (its id already checked) in mm and rad; `names` are the header's columns.
fn parse_row(
    path: &Path,
    line: usize,
    rec: &csv::StringRecord,
    names: &[String],
    layout: RowLayout,
) -> Result<Measurement, DatasetError> {
    let RowLayout {
        joints,
        reflectors,
        has_split,
        units,
    } = layout;
    let field = |i: usize| rec.get(i).unwrap_or("");
    let number = |col: usize| parse_number(path, line, &names[col], field(col));
    // Absurd magnitudes are refused with the column (docs/reliability.md).
    let plausible = |col: usize, check: fn(&str, f64) -> Result<(), String>, v: f64| {
        check(field(col), v).map_err(|message| DatasetError::Field {
            path: path.to_path_buf(),
            line,
            field: names[col].clone(),
            message,
        })
    };
    let q_rad = (1..=joints)
        .map(|col| {
            let raw = number(col)?;
            let q = units.angle.to_rad(raw);
            // A prismatic joint's column is a length in the length unit; which columns are is known
            // with the robot only (ArmData::set_linear_joints, which checks them again), so here a
            // value is refused when it is implausible either way.
            validate::joint_magnitude(field(col), q, units.length.to_mm(raw)).map_err(
                |message| DatasetError::Field {
                    path: path.to_path_buf(),
                    line,
                    field: names[col].clone(),
                    message,
                },
            )?;
            Ok(q)
        })
        .collect::<Result<Vec<f64>, DatasetError>>()?;
    let mut tracker_points_mm = vec![Vector3::zeros(); reflectors];
    for (k, p) in tracker_points_mm.iter_mut().enumerate() {
        for c in 0..3 {
            let col = 1 + joints + 3 * k + c;
            p[c] = units.length.to_mm(number(col)?);
            plausible(col, validate::coordinate_magnitude, p[c])?;
        }
    }
    let split = if has_split {
        match field(names.len()) {
            "cal" => Split::Cal,
            "ver" => Split::Ver,
            other => {
                return Err(DatasetError::Field {
                    path: path.to_path_buf(),
                    line,
                    field: SPLIT_COLUMN.into(),
                    message: format!(
                        "unknown split `{}`; expected `cal` or `ver`",
                        excerpt(other)
                    ),
                });
            }
        }
    } else {
        Split::Cal
    };
    Ok(Measurement {
        id: field(0).to_string(),
        q_rad,
        tracker_points_mm,
        split,
        line,
    })
}

/// Read one arm's CSV into measurements in mm and rad.
pub(super) fn read_arm(
    files: &dyn crate::source::FileSource,
    path: &Path,
    side: Side,
    units: Units,
    nominal_reflectors_mm: &[Vector3<f64>],
    reflector_names: &[String],
) -> Result<Vec<Measurement>, DatasetError> {
    let text = read_text(files, path)?;
    let mut reader = csv::ReaderBuilder::new()
        .has_headers(false)
        .comment(Some(b'#'))
        .flexible(false)
        .trim(csv::Trim::All)
        .from_reader(text.as_bytes());
    // csv's positions point just past the previous record (before skipped comment and blank lines),
    // so the line of a record is found by skipping those from there.
    let mut lines = LineCounter::default();
    let mut line_at = |pos: Option<&csv::Position>, fallback: usize| match pos {
        Some(p) => lines.record_line(&text, usize::try_from(p.byte()).unwrap_or(usize::MAX)),
        None => fallback,
    };
    let content_lines = text.trim_end().lines().count();
    let ends_open = !text.is_empty() && !text.ends_with('\n');
    let map_csv_err =
        |e: csv::Error, line: usize| csv_error(path, e, line, content_lines, ends_open);

    let mut records = reader.records();
    let end_line = text.lines().count() + 1;
    let header = match records.next() {
        None => return Err(missing_header(path, end_line, &text, reflector_names)),
        Some(Ok(r)) => r,
        Some(Err(e)) => {
            let line = line_at(e.position(), 1);
            return Err(map_csv_err(e, line));
        }
    };
    let header_line = line_at(header.position(), 1);
    let (joints, has_split) = check_header(path, header_line, &header, reflector_names)?;
    let names = columns(joints, reflector_names);

    let mut out = Vec::new();
    let mut first_line_of_id: std::collections::HashMap<String, usize> = Default::default();
    let mut last_line = header_line;
    for rec in records {
        let rec = match rec {
            Ok(r) => r,
            Err(e) => {
                let line = line_at(e.position(), last_line + 1);
                return Err(map_csv_err(e, line));
            }
        };
        let line = line_at(rec.position(), last_line + 1);
        last_line = line;
        let id = rec.get(0).unwrap_or("");
        check_id(path, line, id, &first_line_of_id)?;
        first_line_of_id.insert(id.to_string(), line);
        out.push(parse_row(
            path,
            line,
            &rec,
            &names,
            RowLayout {
                joints,
                reflectors: reflector_names.len(),
                has_split,
                units,
            },
        )?);
    }
    if out.len() < MIN_CONFIGS {
        return Err(DatasetError::TooFewConfigurations {
            path: path.to_path_buf(),
            side,
            found: out.len(),
            min: MIN_CONFIGS,
        });
    }
    validate::check_arm(
        path,
        &out,
        units.length,
        nominal_reflectors_mm,
        reflector_names,
    )?;
    Ok(out)
}

/// The refusal of a CSV without a header line (`line`: where the header was expected).
fn missing_header(
    path: &Path,
    line: usize,
    text: &str,
    reflector_names: &[String],
) -> DatasetError {
    DatasetError::Header {
        path: path.to_path_buf(),
        line,
        field: "id".into(),
        message: format!(
            "missing header{}; expected id,q1,…,qN,{},[{SPLIT_COLUMN}] after any `#` comment \
             lines",
            if text.trim().is_empty() {
                " (the file is empty)"
            } else {
                ""
            },
            point_columns(reflector_names).join(",")
        ),
    }
}

/// A row's id: not empty, usable, and not that of an earlier row (`first_line_of_id`: the line of
/// each id so far).
fn check_id(
    path: &Path,
    line: usize,
    id: &str,
    first_line_of_id: &std::collections::HashMap<String, usize>,
) -> Result<(), DatasetError> {
    if id.is_empty() {
        return Err(DatasetError::Field {
            path: path.to_path_buf(),
            line,
            field: "id".into(),
            message: "empty id; every row needs a unique id".into(),
        });
    }
    if let Err(message) = validate::usable_id(id) {
        return Err(DatasetError::Field {
            path: path.to_path_buf(),
            line,
            field: "id".into(),
            message,
        });
    }
    if let Some(&first_line) = first_line_of_id.get(id) {
        return Err(DatasetError::DuplicateId {
            path: path.to_path_buf(),
            line,
            id: excerpt(id),
            first_line,
        });
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn line_counter_skips_comments_and_blank_lines() {
        let text = "# c\r\n\r\nid\n# x\n\nrow\n";
        let mut lc = LineCounter::default();
        assert_eq!(lc.record_line(text, 0), 3);
        assert_eq!(lc.record_line(text, 10), 6);
        // Going backwards recounts.
        assert_eq!(lc.record_line(text, 0), 3);
    }
}
