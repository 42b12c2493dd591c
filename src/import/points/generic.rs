//! Any CSV/TXT with a column mapping ([`ColumnMap`]).

use super::*;

/// What a column of a generic file holds.
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum ColumnRole {
    /// The configuration's id (one configuration per row).
    Id,
    /// The point's name (one point per row).
    Target,
    /// A coordinate of the row's point: 0, 1, 2 for x, y, z.
    Axis(usize),
    /// A coordinate of a reflector: `a.x` is (`a`, 0).
    ReflectorAxis(String, usize),
    /// Joint `k` (1-based) in chain order.
    Joint(usize),
    Time,
    Split,
}

/// A column: its 1-based number or its name in the header line.
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum ColumnRef {
    Number(usize),
    Name(String),
}

/// The generic format's mapping, written `role=column,…`: `target=1,x=2,y=3,z=4` (a point per row)
/// or `id=1,a.x=2,a.y=3,a.z=4,b.x=…,q1=11,…` (a configuration per row); `q=11-17` maps a range of
/// columns to q1…q7; `time=COL`, `split=COL`. Columns are 1-based numbers or header names.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct ColumnMap {
    pub entries: Vec<(ColumnRole, ColumnRef)>,
}

impl ColumnMap {
    pub fn parse(spec: &str) -> Result<ColumnMap, String> {
        let mut entries = Vec::new();
        for item in spec.split(',').map(str::trim).filter(|s| !s.is_empty()) {
            let (role, col) = item
                .split_once('=')
                .ok_or_else(|| format!("`{item}`: expected ROLE=COLUMN (e.g. x=2)"))?;
            let (role, col) = (role.trim(), col.trim());
            let column = |c: &str| match c.parse::<usize>() {
                Ok(0) => Err(format!("`{item}`: columns are counted from 1")),
                Ok(n) => Ok(ColumnRef::Number(n)),
                Err(_) if !c.is_empty() => Ok(ColumnRef::Name(c.to_string())),
                Err(_) => Err(format!("`{item}`: no column")),
            };
            let axis = |a: &str| {
                ["x", "y", "z"]
                    .iter()
                    .position(|x| a.eq_ignore_ascii_case(x))
            };
            let lower = role.to_lowercase();
            if lower == "q" {
                let (a, b) = col
                    .split_once('-')
                    .and_then(|(a, b)| {
                        Some((
                            a.trim().parse::<usize>().ok()?,
                            b.trim().parse::<usize>().ok()?,
                        ))
                    })
                    .filter(|&(a, b)| a >= 1 && b >= a)
                    .ok_or_else(|| format!("`{item}`: expected q=FIRST-LAST (column numbers)"))?;
                for (k, c) in (a..=b).enumerate() {
                    entries.push((ColumnRole::Joint(k + 1), ColumnRef::Number(c)));
                }
                continue;
            }
            let r = match lower.as_str() {
                "id" => ColumnRole::Id,
                "target" | "name" => ColumnRole::Target,
                "time" => ColumnRole::Time,
                "split" => ColumnRole::Split,
                _ => {
                    if let Some(a) = axis(role) {
                        ColumnRole::Axis(a)
                    } else if let Some((name, a)) =
                        role.rsplit_once('.').and_then(|(n, a)| Some((n, axis(a)?)))
                    {
                        ColumnRole::ReflectorAxis(name.to_string(), a)
                    } else if let Some(k) = lower
                        .strip_prefix('q')
                        .and_then(|k| k.parse::<usize>().ok())
                        .filter(|&k| k >= 1)
                    {
                        ColumnRole::Joint(k)
                    } else {
                        return Err(format!(
                            "`{item}`: unknown role `{role}`: expected id, target, x, y, z, \
                             REFLECTOR.x/.y/.z, q1…qN, q=FIRST-LAST, time or split"
                        ));
                    }
                }
            };
            if entries.iter().any(|(e, _)| *e == r) {
                return Err(format!("`{item}`: `{role}` mapped twice"));
            }
            entries.push((r, column(col)?));
        }
        if entries.is_empty() {
            return Err("an empty column mapping".to_string());
        }
        let per_point = entries
            .iter()
            .any(|(r, _)| matches!(r, ColumnRole::Axis(_)));
        let per_config = entries
            .iter()
            .any(|(r, _)| matches!(r, ColumnRole::ReflectorAxis(..)));
        if per_point == per_config {
            return Err(
                "map either x, y, z (one point per row) or REFLECTOR.x, .y, .z (one configuration \
                 per row)"
                    .to_string(),
            );
        }
        Ok(ColumnMap { entries })
    }

    fn get(&self, role: &ColumnRole) -> Option<&ColumnRef> {
        self.entries.iter().find(|(r, _)| r == role).map(|(_, c)| c)
    }
}

pub(super) fn read_generic(
    path: &Path,
    text: &str,
    map: &ColumnMap,
    o: &ReadOptions,
) -> Result<PointFile, ImportError> {
    let mut it = lines(text)
        .filter(|(_, t)| !t.starts_with('#') && !t.starts_with("//"))
        .peekable();
    let Some(&(first_line, first)) = it.peek() else {
        return Err(ImportError::Format {
            path: path.to_path_buf(),
            message: "no rows".to_string(),
        });
    };
    let delimiter = Delimiter::of_line(first, o.decimal_comma);
    let dc = o.decimal_comma || delimiter.allows_decimal_comma();
    let first_fields = text::split(first, delimiter);
    // A header line when a name is mapped, or when a mapped coordinate is no number on the first line.
    let names_used = map
        .entries
        .iter()
        .any(|(_, c)| matches!(c, ColumnRef::Name(_)));
    let coordinate_cols: Vec<usize> = map
        .entries
        .iter()
        .filter(|(r, _)| matches!(r, ColumnRole::Axis(_) | ColumnRole::ReflectorAxis(..)))
        .filter_map(|(_, c)| match c {
            ColumnRef::Number(n) => n.checked_sub(1),
            ColumnRef::Name(_) => None,
        })
        .collect();
    let has_header = names_used
        || coordinate_cols.iter().any(|&k| {
            first_fields
                .get(k)
                .is_none_or(|f| text::number(f, dc).is_none())
        });
    let header: Vec<String> = if has_header {
        it.next();
        first_fields
            .iter()
            .map(|f| text::name_and_unit(f).0)
            .collect()
    } else {
        Vec::new()
    };
    let resolve = |role: &ColumnRole| -> Result<Option<usize>, ImportError> {
        match map.get(role) {
            None => Ok(None),
            Some(ColumnRef::Number(n)) => n
                .checked_sub(1)
                .map(Some)
                .ok_or_else(|| ImportError::Options("columns are counted from 1".to_string())),
            Some(ColumnRef::Name(name)) => header
                .iter()
                .position(|h| h == name || h.eq_ignore_ascii_case(name))
                .map(Some)
                .ok_or_else(|| ImportError::Header {
                    path: path.to_path_buf(),
                    line: first_line,
                    field: name.clone(),
                    message: format!(
                        "no such column (the mapping names it); the header has: {}",
                        crate::textfile::excerpt(&header.join(", "))
                    ),
                }),
        }
    };
    let unit = o.unit.unwrap_or_default();
    let role_name = |r: &ColumnRole| match r {
        ColumnRole::Id => "id".to_string(),
        ColumnRole::Target => "target".to_string(),
        ColumnRole::Axis(a) => ["x", "y", "z"][*a].to_string(),
        ColumnRole::ReflectorAxis(n, a) => format!("{n}.{}", ["x", "y", "z"][*a]),
        ColumnRole::Joint(k) => format!("q{k}"),
        ColumnRole::Time => "time".to_string(),
        ColumnRole::Split => "split".to_string(),
    };
    let mut needed = 0;
    let mut cols = Vec::new();
    for (r, _) in &map.entries {
        let c = resolve(r)?.unwrap_or(0);
        needed = needed.max(c + 1);
        cols.push((r.clone(), c));
    }
    let col_of = |r: &ColumnRole| cols.iter().find(|(x, _)| x == r).map(|(_, c)| *c);
    let joints = {
        let n = cols
            .iter()
            .filter(|(r, _)| matches!(r, ColumnRole::Joint(_)))
            .count();
        for k in 1..=n {
            if col_of(&ColumnRole::Joint(k)).is_none() {
                return Err(ImportError::Options(format!(
                    "the column mapping has {n} joints but no q{k}"
                )));
            }
        }
        n
    };
    let text_field =
        |line: usize, fields: &[String], r: &ColumnRole| -> Result<Option<String>, ImportError> {
            match col_of(r) {
                None => Ok(None),
                Some(c) => {
                    let f = field(path, line, fields, c, needed)?;
                    if f.is_empty() {
                        return Err(ImportError::Field {
                            path: path.to_path_buf(),
                            line,
                            field: role_name(r),
                            expected: "a name".to_string(),
                            found: String::new(),
                        });
                    }
                    Ok(Some(f.to_string()))
                }
            }
        };
    let per_point = col_of(&ColumnRole::Axis(0)).is_some();
    let mut points = Vec::new();
    let mut rows = Vec::new();
    for (line, t) in it {
        let fields = text::split(t, delimiter);
        let time_s = time_field(path, line, &fields, col_of(&ColumnRole::Time), "time")?;
        if per_point {
            let mut p = Vector3::zeros();
            for a in 0..3 {
                let r = ColumnRole::Axis(a);
                let c = col_of(&r).ok_or_else(|| {
                    ImportError::Options(format!("the column mapping has no {}", role_name(&r)))
                })?;
                p[a] = coordinate(path, line, &fields, c, needed, &role_name(&r), unit, dc)?;
            }
            points.push(Point {
                target: text_field(line, &fields, &ColumnRole::Target)?,
                position_mm: p,
                time_s,
                line,
            });
            continue;
        }
        let mut points_mm = Vec::new();
        for name in o.reflector_names {
            let mut p = Vector3::zeros();
            for a in 0..3 {
                let r = ColumnRole::ReflectorAxis(name.clone(), a);
                let c = col_of(&r).ok_or_else(|| {
                    ImportError::Options(format!(
                        "the column mapping has no {} (the dataset's reflectors: {})",
                        role_name(&r),
                        o.reflector_names.join(", ")
                    ))
                })?;
                p[a] = coordinate(path, line, &fields, c, needed, &role_name(&r), unit, dc)?;
            }
            points_mm.push(p);
        }
        let q_rad = if joints == 0 {
            None
        } else {
            let mut q = Vec::new();
            for k in 1..=joints {
                let r = ColumnRole::Joint(k);
                let c = col_of(&r).unwrap_or(0);
                let f = field(path, line, &fields, c, needed)?;
                q.push(o.angle_unit.to_rad(text::number(f, dc).ok_or_else(|| {
                    ImportError::Field {
                        path: path.to_path_buf(),
                        line,
                        field: role_name(&r),
                        expected: format!("a joint value in {}", o.angle_unit.name()),
                        found: crate::textfile::excerpt(f),
                    }
                })?));
            }
            Some(q)
        };
        let split = match text_field(line, &fields, &ColumnRole::Split)? {
            None => None,
            Some(s) => Some(parse_split(path, line, &s)?),
        };
        rows.push(ConfigRow {
            id: text_field(line, &fields, &ColumnRole::Id)?,
            points_mm,
            q_rad,
            time_s,
            split,
            line,
        });
    }
    if per_point {
        for (r, _) in &cols {
            if matches!(r, ColumnRole::Joint(_) | ColumnRole::Split | ColumnRole::Id) {
                return Err(ImportError::Options(format!(
                    "`{}` in a mapping of one point per row: joints, ids and splits belong to the \
                     joint log (or map REFLECTOR.x/.y/.z for one configuration per row)",
                    role_name(r)
                )));
            }
        }
    }
    for name in map.entries.iter().filter_map(|(r, _)| match r {
        ColumnRole::ReflectorAxis(n, _) => Some(n),
        _ => None,
    }) {
        if !o.reflector_names.contains(name) {
            return Err(ImportError::Options(format!(
                "the column mapping names reflector `{name}`; the dataset's reflectors are {}",
                o.reflector_names.join(", ")
            )));
        }
    }
    Ok(PointFile {
        format: PointsFormat::Generic,
        unit,
        frame: None,
        table: if per_point {
            PointTable::Points(points)
        } else {
            PointTable::Rows(rows)
        },
        notes: Vec::new(),
    })
}
