//! Leica Tracker Pilot CSV: unit brackets, Windows-1252, time stamps with an apostrophe; rows marked
//! in its `Delete` column dropped (and listed), its `U(95)` column summed up in the notes.

use super::*;

pub(super) fn read_leica(
    path: &Path,
    text: &str,
    o: &ReadOptions,
) -> Result<PointFile, ImportError> {
    let mut it = lines(text).filter(|(_, t)| !t.starts_with("//") && !t.starts_with('#'));
    let Some((hl, header)) = it.next() else {
        return Err(ImportError::Format {
            path: path.to_path_buf(),
            message: "empty file: expected Tracker Pilot's header `X  [mm],Y  [mm],Z  [mm],…`"
                .to_string(),
        });
    };
    let delimiter = Delimiter::of_line(header, false);
    let names: Vec<NameUnit> = text::split(header, delimiter)
        .iter()
        .map(|f| text::name_and_unit(f))
        .collect();
    let mut unit = None;
    let mut xyz = [0; 3];
    let mut notes_unit = Vec::new();
    for (k, axis) in ["X", "Y", "Z"].into_iter().enumerate() {
        let Some(col) = names.iter().position(|(n, _)| n == axis) else {
            return Err(ImportError::Header {
                path: path.to_path_buf(),
                line: hl,
                field: format!("{axis}  [mm]"),
                message: format!(
                    "no column `{axis}`: expected Tracker Pilot's header `X  [mm],Y  [mm],Z  [mm],…`"
                ),
            });
        };
        xyz[k] = col;
        let u = match (&names[col].1, o.unit) {
            (Some(u), _) => PointUnit::parse(u).ok_or_else(|| ImportError::Header {
                path: path.to_path_buf(),
                line: hl,
                field: format!("{axis}  [{u}]"),
                message: format!("unknown unit `{u}`: expected mm, m, µm, in or ft"),
            })?,
            (None, Some(u)) => u,
            (None, None) => {
                if k == 0 {
                    notes_unit.push(
                        "unit: the header gives none for X, Y, Z: read as mm (--length-unit)"
                            .to_string(),
                    );
                }
                PointUnit::Mm
            }
        };
        if unit.is_some_and(|v| v != u) {
            return Err(ImportError::Header {
                path: path.to_path_buf(),
                line: hl,
                field: axis.to_string(),
                message: "X, Y and Z in different units".to_string(),
            });
        }
        unit = Some(u);
    }
    let unit = unit.unwrap_or_default();
    let l = Layout {
        delimiter,
        target: names.iter().position(|(n, _)| is_target_name(n)),
        xyz,
        time: names.iter().position(|(n, _)| is_time_name(n)),
        needed: xyz.iter().max().copied().unwrap_or(0) + 1,
    };
    let mut notes = vec![format!(
        "separator: {} (recognised from the header)",
        delimiter.name()
    )];
    notes.append(&mut notes_unit);
    if l.target.is_none() {
        notes.push("no `Target` column: the points have no names".to_string());
    }
    let extra = Extra::of(path, hl, &names)?;
    let mut points = Vec::new();
    let mut deleted = Vec::new();
    let mut u95_mm = Vec::new();
    for (line, t) in it {
        let fields = text::split(t, delimiter);
        if extra.deleted(path, line, &fields)? {
            deleted.push(line);
            continue;
        }
        if let Some(u) = extra.u95_mm(path, line, &fields, o.decimal_comma)? {
            u95_mm.push((u, line));
        }
        points.push(point_row(path, line, t, &l, unit, o.decimal_comma)?);
    }
    if !deleted.is_empty() {
        let lines: Vec<String> = deleted.iter().map(usize::to_string).collect();
        notes.push(format!(
            "deleted in Tracker Pilot (column `Delete`), not imported: {} row{} (line{} {})",
            deleted.len(),
            if deleted.len() == 1 { "" } else { "s" },
            if deleted.len() == 1 { "" } else { "s" },
            lines.join(", ")
        ));
    }
    notes.extend(u95_note(&mut u95_mm));
    Ok(PointFile {
        format: PointsFormat::Leica,
        unit,
        frame: None,
        table: PointTable::Points(points),
        notes,
    })
}

/// Tracker Pilot's columns besides the point's: `Delete` and `U(95)` (with its unit).
struct Extra {
    delete: Option<usize>,
    u95: Option<(usize, PointUnit)>,
}

impl Extra {
    fn of(path: &Path, line: usize, names: &[NameUnit]) -> Result<Self, ImportError> {
        let delete = names.iter().position(|(n, _)| {
            n.eq_ignore_ascii_case("delete") || n.eq_ignore_ascii_case("deleted")
        });
        let u95 = match names
            .iter()
            .position(|(n, _)| n.eq_ignore_ascii_case("u(95)"))
        {
            Some(k) => {
                let unit = match &names[k].1 {
                    Some(u) => PointUnit::parse(u).ok_or_else(|| ImportError::Header {
                        path: path.to_path_buf(),
                        line,
                        field: format!("U(95)  [{u}]"),
                        message: format!("unknown unit `{u}`: expected mm, m, µm, in or ft"),
                    })?,
                    None => PointUnit::Mm,
                };
                Some((k, unit))
            }
            None => None,
        };
        Ok(Self { delete, u95 })
    }

    /// Whether the row is marked deleted: `True`, `Yes`, `1` or `X` (any case) in `Delete`; empty,
    /// `False`, `No` or `0` keep it.
    fn deleted(&self, path: &Path, line: usize, fields: &[String]) -> Result<bool, ImportError> {
        let Some(k) = self.delete else {
            return Ok(false);
        };
        let f = fields.get(k).map_or("", |f| f.trim());
        match f.to_lowercase().as_str() {
            "" | "false" | "no" | "0" => Ok(false),
            "true" | "yes" | "1" | "x" | "deleted" => Ok(true),
            _ => Err(ImportError::Field {
                path: path.to_path_buf(),
                line,
                field: "Delete".to_string(),
                expected: "`True` or `False` (or nothing)".to_string(),
                found: crate::textfile::excerpt(f),
            }),
        }
    }

    /// The row's U(95), mm (`None`: no column, or the field empty).
    fn u95_mm(
        &self,
        path: &Path,
        line: usize,
        fields: &[String],
        decimal_comma: bool,
    ) -> Result<Option<f64>, ImportError> {
        let Some((k, unit)) = self.u95 else {
            return Ok(None);
        };
        let f = fields.get(k).map_or("", |f| f.trim());
        if f.is_empty() {
            return Ok(None);
        }
        match text::number(f, decimal_comma) {
            Some(v) if v >= 0.0 => Ok(Some(unit.to_mm(v))),
            _ => Err(ImportError::Field {
                path: path.to_path_buf(),
                line,
                field: "U(95)".to_string(),
                expected: format!("an uncertainty ≥ 0 in {}", unit.name()),
                found: crate::textfile::excerpt(f),
            }),
        }
    }
}

/// The points' U(95) summed up: the largest (and its line) and the median.
fn u95_note(u95_mm: &mut [(f64, usize)]) -> Option<String> {
    if u95_mm.is_empty() {
        return None;
    }
    u95_mm.sort_by(|a, b| a.0.total_cmp(&b.0));
    let n = u95_mm.len();
    let median = if n % 2 == 1 {
        u95_mm[n / 2].0
    } else {
        0.5 * (u95_mm[n / 2 - 1].0 + u95_mm[n / 2].0)
    };
    let (largest, line) = u95_mm[n - 1];
    Some(format!(
        "U(95) of the {n} points: largest {largest:.4} mm (line {line}), median {median:.4} mm"
    ))
}
