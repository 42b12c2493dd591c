//! Leica Tracker Pilot CSV: unit brackets, Windows-1252, time stamps with an apostrophe.

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
            (None, None) => PointUnit::Mm,
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
    let mut notes = Vec::new();
    if l.target.is_none() {
        notes.push("no `Target` column: the points have no names".to_string());
    }
    let points = it
        .map(|(line, t)| point_row(path, line, t, &l, unit, o.decimal_comma))
        .collect::<Result<Vec<_>, _>>()?;
    Ok(PointFile {
        format: PointsFormat::Leica,
        unit,
        frame: None,
        table: PointTable::Points(points),
        notes,
    })
}
