//! SpatialAnalyzer ASCII/CSV exports: optional `//` header lines, name columns, X Y Z.

use super::*;

pub(super) fn read_spatial_analyzer(
    path: &Path,
    text: &str,
    o: &ReadOptions,
) -> Result<PointFile, ImportError> {
    let mut unit_header: Option<(usize, String)> = None;
    let mut frame = None;
    let mut notes = Vec::new();
    let mut header: Option<(usize, Vec<NameUnit>)> = None;
    let mut layout: Option<Layout> = None;
    let mut unit = o.unit.unwrap_or_default();
    let mut points = Vec::new();
    for (line, t) in lines(text) {
        if let Some(comment) = t.strip_prefix("//") {
            if let Some((key, value)) = header_comment(comment) {
                if key.contains("unit") {
                    unit_header = Some((line, value));
                } else if key.contains("frame") {
                    frame = Some(value);
                }
            }
            continue;
        }
        if t.starts_with('#') {
            continue;
        }
        if layout.is_none() {
            match first_line(path, line, t, o, header.as_ref(), &mut unit, &mut notes)? {
                FirstLine::Names(names) => {
                    header = Some((line, names));
                    continue;
                }
                FirstLine::Row(l) => layout = Some(l),
            }
        }
        let Some(l) = &layout else { unreachable!() };
        if points.is_empty() && o.unit.is_none() {
            // The unit, once: the option, else the header's, else mm.
            if let Some((ul, u)) = &unit_header {
                unit = PointUnit::parse(u).ok_or_else(|| ImportError::Header {
                    path: path.to_path_buf(),
                    line: *ul,
                    field: "Units".to_string(),
                    message: format!(
                        "unknown unit `{}`: expected Millimeters, Meters, Inches, … (or give the \
                         unit by option)",
                        crate::textfile::excerpt(u)
                    ),
                })?;
            } else if header
                .as_ref()
                .is_none_or(|(_, n)| n.iter().all(|(_, u)| u.is_none()))
            {
                notes.push("no unit in the file: read as mm".to_string());
            }
        }
        points.push(point_row(path, line, t, l, unit, o.decimal_comma)?);
    }
    if layout.is_none() {
        return Err(ImportError::Format {
            path: path.to_path_buf(),
            message: "no points: expected rows of (names) X Y Z".to_string(),
        });
    }
    Ok(PointFile {
        format: PointsFormat::SpatialAnalyzer,
        unit,
        frame,
        table: PointTable::Points(points),
        notes,
    })
}

/// What the first line that is no comment says: the column names, or (the first row) where the
/// columns are.
enum FirstLine {
    Names(Vec<NameUnit>),
    Row(Layout),
}

/// The first line `t` (line `line`) that is no comment, after the column names `header` if any: names
/// (`Collection Group Target X Y Z …`) or a row, whose layout comes from the names when they line up
/// with its fields (their unit into `unit` unless the option gave one), else by position.
fn first_line(
    path: &Path,
    line: usize,
    t: &str,
    o: &ReadOptions,
    header: Option<&(usize, Vec<NameUnit>)>,
    unit: &mut PointUnit,
    notes: &mut Vec<String>,
) -> Result<FirstLine, ImportError> {
    let delimiter = Delimiter::of_line(t, o.decimal_comma);
    let dc = o.decimal_comma || delimiter.allows_decimal_comma();
    let fields = text::split(t, delimiter);
    let numbers: Vec<bool> = fields
        .iter()
        .map(|f| text::number(f, dc).is_some())
        .collect();
    let first_xyz = (0..fields.len().saturating_sub(2))
        .find(|&i| numbers[i] && numbers[i + 1] && numbers[i + 2]);
    if header.is_none() && first_xyz.is_none() {
        let names: Vec<NameUnit> = fields.iter().map(|f| text::name_and_unit(f)).collect();
        let is = |n: &str| names.iter().any(|(m, _)| m.eq_ignore_ascii_case(n));
        if !(is("x") && is("y") && is("z")) {
            return Err(ImportError::Header {
                path: path.to_path_buf(),
                line,
                field: "X".to_string(),
                message: format!(
                    "expected column names with X, Y and Z (e.g. `Collection Group Target X Y Z`) \
                     or a row of coordinates, found `{}`",
                    crate::textfile::excerpt(t)
                ),
            });
        }
        return Ok(FirstLine::Names(names));
    }
    let Some(i) = first_xyz else {
        return Err(ImportError::Field {
            path: path.to_path_buf(),
            line,
            field: "X".to_string(),
            expected: "three numbers X Y Z after the name columns".to_string(),
            found: crate::textfile::excerpt(t),
        });
    };
    let lined_up = header.filter(|(_, names)| names.len() == fields.len());
    let Some((hl, names)) = lined_up else {
        if header.is_some() {
            notes.push(
                "the column names do not line up with the rows' fields: columns found by position \
                 (names, then X Y Z)"
                    .to_string(),
            );
        }
        return Ok(FirstLine::Row(Layout {
            delimiter,
            target: i.checked_sub(1),
            xyz: [i, i + 1, i + 2],
            time: None,
            needed: i + 3,
        }));
    };
    let col = |n: &str| names.iter().position(|(m, _)| m.eq_ignore_ascii_case(n));
    let (Some(x), Some(y), Some(z)) = (col("x"), col("y"), col("z")) else {
        unreachable!("the header was checked for X, Y, Z")
    };
    if let Some(u) = &names[x].1 {
        match PointUnit::parse(u) {
            Some(p) if o.unit.is_none() => *unit = p,
            Some(_) => {}
            None => {
                return Err(ImportError::Header {
                    path: path.to_path_buf(),
                    line: *hl,
                    field: "X".to_string(),
                    message: format!("unknown unit `{u}`: expected mm, m, µm, in or ft"),
                });
            }
        }
    }
    let target = names
        .iter()
        .position(|(m, _)| is_target_name(m))
        .or_else(|| x.checked_sub(1).filter(|&k| !numbers[k]));
    let time = names.iter().position(|(m, _)| is_time_name(m));
    Ok(FirstLine::Row(Layout {
        delimiter,
        target,
        xyz: [x, y, z],
        time,
        needed: x.max(y).max(z) + 1,
    }))
}
