//! Point files: SpatialAnalyzer exports, Leica Tracker Pilot CSV, figaroh calibration CSV and any
//! CSV/TXT with a column mapping ([`ColumnMap`]). Each reader gives a [`PointFile`]: one measured point
//! per row ([`PointTable::Points`], matched to a joint log afterwards), or one configuration per row with
//! every reflector and possibly the joints ([`PointTable::Rows`]).

use super::error::ImportError;
use super::text::{self, Delimiter, PointUnit};
use crate::dataset::{AngleUnit, Split};
use nalgebra::Vector3;
use std::path::Path;

/// The formats of point files.
#[derive(Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum)]
pub enum PointsFormat {
    /// SpatialAnalyzer ASCII/CSV export: optional `//` header lines, optional column names, name
    /// columns (`Collection Group Target`, `Group Target`, `Target` or none), then X Y Z.
    #[value(name = "spatial-analyzer", alias = "sa")]
    SpatialAnalyzer,
    /// Leica Tracker Pilot CSV: `X  [mm],Y  [mm],Z  [mm],…,Target,…,Time Stamp,…`.
    Leica,
    /// figaroh's calibration CSV: `x1,y1,z1,…` per marker, then one column per joint (m, rad).
    Figaroh,
    /// Any CSV/TXT with a column mapping (`--columns`).
    Generic,
}

impl PointsFormat {
    pub fn name(self) -> &'static str {
        match self {
            PointsFormat::SpatialAnalyzer => "SpatialAnalyzer export",
            PointsFormat::Leica => "Leica Tracker Pilot CSV",
            PointsFormat::Figaroh => "figaroh calibration CSV",
            PointsFormat::Generic => "CSV with a column mapping",
        }
    }
}

/// One measured point (a row of a point list).
#[derive(Clone, Debug, PartialEq)]
pub struct Point {
    /// The target's name (`L012_a`), when the file names its points.
    pub target: Option<String>,
    pub position_mm: Vector3<f64>,
    /// The time stamp, seconds (see [`text::time_s`]), when the file has one.
    pub time_s: Option<f64>,
    /// 1-based line in the file.
    pub line: usize,
}

/// One configuration per row: every reflector's position and possibly the joints.
#[derive(Clone, Debug, PartialEq)]
pub struct ConfigRow {
    pub id: Option<String>,
    /// One per reflector of the dataset, in its order.
    pub points_mm: Vec<Vector3<f64>>,
    /// In chain order, rad (`None` when the file has no joint columns).
    pub q_rad: Option<Vec<f64>>,
    pub time_s: Option<f64>,
    pub split: Option<Split>,
    pub line: usize,
}

#[derive(Clone, Debug, PartialEq)]
pub enum PointTable {
    Points(Vec<Point>),
    Rows(Vec<ConfigRow>),
}

/// What a point file held.
#[derive(Clone, Debug, PartialEq)]
pub struct PointFile {
    pub format: PointsFormat,
    pub unit: PointUnit,
    /// The working frame named in the header (SpatialAnalyzer), if any.
    pub frame: Option<String>,
    pub table: PointTable,
    /// What the reader decided that the user should know (columns ignored, units assumed).
    pub notes: Vec<String>,
}

/// What a reader is told.
#[derive(Clone, Debug)]
pub struct ReadOptions<'a> {
    /// `None`: recognised from the file.
    pub format: Option<PointsFormat>,
    /// The unit of files that do not say; `None`: the format's (mm; m for figaroh).
    pub unit: Option<PointUnit>,
    /// Numbers written with a decimal comma (`1234,5`); also recognised when fields are separated by
    /// `;`, tabs or spaces.
    pub decimal_comma: bool,
    /// The generic format's mapping.
    pub columns: Option<&'a ColumnMap>,
    /// The dataset's reflectors, in order.
    pub reflector_names: &'a [String],
    /// The arm's joint names in chain order (figaroh's joint columns are named so).
    pub joint_names: Option<&'a [String]>,
    /// The unit of a generic file's joint columns.
    pub angle_unit: AngleUnit,
}

/// The non-empty lines of a text with their 1-based numbers, trimmed.
fn lines(text: &str) -> impl Iterator<Item = (usize, &str)> {
    text.lines()
        .enumerate()
        .map(|(i, l)| (i + 1, l.trim()))
        .filter(|(_, l)| !l.is_empty())
}

/// The format of a point file, recognised from its first line.
pub fn detect(text: &str) -> PointsFormat {
    let Some((_, first)) = lines(text).next() else {
        return PointsFormat::SpatialAnalyzer;
    };
    if first.starts_with("//") {
        return PointsFormat::SpatialAnalyzer;
    }
    let fields = text::split(first, Delimiter::of_line(first, false));
    let has = |name: &str| fields.iter().any(|f| f == name);
    if has("x1") && has("y1") && has("z1") {
        return PointsFormat::Figaroh;
    }
    let bracketed_x = fields.iter().any(|f| {
        let (name, unit) = text::name_and_unit(f);
        name.eq_ignore_ascii_case("x") && unit.is_some()
    });
    if bracketed_x && fields.len() > 3 {
        return PointsFormat::Leica;
    }
    PointsFormat::SpatialAnalyzer
}

/// Read a point file's text.
pub fn read(path: &Path, text: &str, o: &ReadOptions) -> Result<PointFile, ImportError> {
    let format = match (o.format, o.columns) {
        (Some(f), _) => f,
        (None, Some(_)) => PointsFormat::Generic,
        (None, None) => detect(text),
    };
    match format {
        PointsFormat::SpatialAnalyzer => read_spatial_analyzer(path, text, o),
        PointsFormat::Leica => read_leica(path, text, o),
        PointsFormat::Figaroh => read_figaroh(path, text, o),
        PointsFormat::Generic => match o.columns {
            Some(map) => read_generic(path, text, map, o),
            None => Err(ImportError::Options(format!(
                "{}: the generic format needs a column mapping (--columns), e.g. \
                 `target=1,x=2,y=3,z=4`",
                path.display()
            ))),
        },
    }
}

/// Field `k` of a row, or a field-count error.
fn field<'f>(
    path: &Path,
    line: usize,
    fields: &'f [String],
    k: usize,
    needed: usize,
) -> Result<&'f str, ImportError> {
    fields
        .get(k)
        .map(String::as_str)
        .ok_or(ImportError::FieldCount {
            path: path.to_path_buf(),
            line,
            expected: needed,
            found: fields.len(),
        })
}

/// A coordinate of a row, in mm.
#[allow(clippy::too_many_arguments)]
fn coordinate(
    path: &Path,
    line: usize,
    fields: &[String],
    k: usize,
    needed: usize,
    name: &str,
    unit: PointUnit,
    decimal_comma: bool,
) -> Result<f64, ImportError> {
    let f = field(path, line, fields, k, needed)?;
    text::number(f, decimal_comma)
        .map(|v| unit.to_mm(v))
        .ok_or_else(|| ImportError::Field {
            path: path.to_path_buf(),
            line,
            field: name.to_string(),
            expected: format!("a number in {}", unit.name()),
            found: crate::textfile::excerpt(f),
        })
}

fn time_field(
    path: &Path,
    line: usize,
    fields: &[String],
    col: Option<usize>,
    name: &str,
) -> Result<Option<f64>, ImportError> {
    let Some(k) = col else {
        return Ok(None);
    };
    let f = fields.get(k).map_or("", String::as_str);
    if f.is_empty() {
        return Ok(None);
    }
    text::time_s(f).map(Some).ok_or_else(|| ImportError::Field {
        path: path.to_path_buf(),
        line,
        field: name.to_string(),
        expected: "a time stamp (`11.10.2022 15:06:48.043`, `2022-10-11T15:06:48.043` or seconds)"
            .to_string(),
        found: crate::textfile::excerpt(f),
    })
}

fn is_time_name(name: &str) -> bool {
    matches!(
        name.to_lowercase().as_str(),
        "time stamp" | "timestamp" | "time" | "date time" | "datetime" | "time_stamp" | "stamp"
    )
}

fn is_target_name(name: &str) -> bool {
    matches!(
        name.to_lowercase().as_str(),
        "target" | "point" | "point id" | "point name" | "name" | "target name" | "id"
    )
}

/// `// Units: Millimeters`, `// Working Frame: World` and the like.
fn header_comment(comment: &str) -> Option<(String, String)> {
    let (k, v) = comment.split_once([':', '='])?;
    Some((k.trim().to_lowercase(), v.trim().to_string()))
}

/// A column's name and the unit in its brackets.
type NameUnit = (String, Option<String>);

/// The layout of a point list's rows.
struct Layout {
    delimiter: Delimiter,
    target: Option<usize>,
    xyz: [usize; 3],
    time: Option<usize>,
    /// Fields a row must have.
    needed: usize,
}

fn read_spatial_analyzer(
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
                // Column names: `Collection Group Target X Y Z …`.
                let names: Vec<NameUnit> = fields.iter().map(|f| text::name_and_unit(f)).collect();
                let is = |n: &str| names.iter().any(|(m, _)| m.eq_ignore_ascii_case(n));
                if !(is("x") && is("y") && is("z")) {
                    return Err(ImportError::Header {
                        path: path.to_path_buf(),
                        line,
                        field: "X".to_string(),
                        message: format!(
                            "expected column names with X, Y and Z (e.g. `Collection Group Target \
                             X Y Z`) or a row of coordinates, found `{}`",
                            crate::textfile::excerpt(t)
                        ),
                    });
                }
                header = Some((line, names));
                continue;
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
            let from_header = header
                .as_ref()
                .filter(|(_, names)| names.len() == fields.len());
            let l = match from_header {
                Some((hl, names)) => {
                    let col = |n: &str| names.iter().position(|(m, _)| m.eq_ignore_ascii_case(n));
                    let (x, y, z) = (col("x"), col("y"), col("z"));
                    let (Some(x), Some(y), Some(z)) = (x, y, z) else {
                        unreachable!("the header was checked for X, Y, Z")
                    };
                    if let Some(u) = &names[x].1 {
                        match PointUnit::parse(u) {
                            Some(p) if o.unit.is_none() => unit = p,
                            Some(_) => {}
                            None => {
                                return Err(ImportError::Header {
                                    path: path.to_path_buf(),
                                    line: *hl,
                                    field: "X".to_string(),
                                    message: format!(
                                        "unknown unit `{u}`: expected mm, m, µm, in or ft"
                                    ),
                                });
                            }
                        }
                    }
                    let target = names
                        .iter()
                        .position(|(m, _)| is_target_name(m))
                        .or_else(|| x.checked_sub(1).filter(|&k| !numbers[k]));
                    let time = names.iter().position(|(m, _)| is_time_name(m));
                    Layout {
                        delimiter,
                        target,
                        xyz: [x, y, z],
                        time,
                        needed: x.max(y).max(z) + 1,
                    }
                }
                None => {
                    if header.is_some() {
                        notes.push(
                            "the column names do not line up with the rows' fields: columns found \
                             by position (names, then X Y Z)"
                                .to_string(),
                        );
                    }
                    Layout {
                        delimiter,
                        target: i.checked_sub(1),
                        xyz: [i, i + 1, i + 2],
                        time: None,
                        needed: i + 3,
                    }
                }
            };
            layout = Some(l);
        }
        let Some(l) = &layout else { unreachable!() };
        if points.is_empty() {
            // The unit, once: the option, else the header's, else mm.
            if o.unit.is_none() {
                if let Some((ul, u)) = &unit_header {
                    unit = PointUnit::parse(u).ok_or_else(|| ImportError::Header {
                        path: path.to_path_buf(),
                        line: *ul,
                        field: "Units".to_string(),
                        message: format!(
                            "unknown unit `{}`: expected Millimeters, Meters, Inches, … (or give \
                             the unit by option)",
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

fn point_row(
    path: &Path,
    line: usize,
    t: &str,
    l: &Layout,
    unit: PointUnit,
    decimal_comma: bool,
) -> Result<Point, ImportError> {
    let fields = text::split(t, l.delimiter);
    let dc = decimal_comma || l.delimiter.allows_decimal_comma();
    let mut p = Vector3::zeros();
    for (k, name) in ["X", "Y", "Z"].into_iter().enumerate() {
        p[k] = coordinate(path, line, &fields, l.xyz[k], l.needed, name, unit, dc)?;
    }
    let target = match l.target {
        Some(k) => {
            let f = field(path, line, &fields, k, l.needed)?;
            if f.is_empty() {
                return Err(ImportError::Field {
                    path: path.to_path_buf(),
                    line,
                    field: "Target".to_string(),
                    expected: "a target name".to_string(),
                    found: String::new(),
                });
            }
            Some(f.to_string())
        }
        None => None,
    };
    Ok(Point {
        target,
        position_mm: p,
        time_s: time_field(path, line, &fields, l.time, "Time Stamp")?,
        line,
    })
}

fn read_leica(path: &Path, text: &str, o: &ReadOptions) -> Result<PointFile, ImportError> {
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

fn read_figaroh(path: &Path, text: &str, o: &ReadOptions) -> Result<PointFile, ImportError> {
    let mut it = lines(text).filter(|(_, t)| !t.starts_with('#'));
    let Some((hl, header)) = it.next() else {
        return Err(ImportError::Format {
            path: path.to_path_buf(),
            message: "empty file: expected figaroh's header `x1,y1,z1,…,<joint names>`".to_string(),
        });
    };
    let delimiter = Delimiter::of_line(header, false);
    let names = text::split(header, delimiter);
    let col = |n: &str| names.iter().position(|m| m == n);
    let mut markers = Vec::new();
    for k in 1.. {
        let cols = [format!("x{k}"), format!("y{k}"), format!("z{k}")];
        let found: Vec<Option<usize>> = cols.iter().map(|c| col(c)).collect();
        match found.as_slice() {
            [Some(x), Some(y), Some(z)] => markers.push([*x, *y, *z]),
            [None, None, None] => break,
            _ => {
                let missing = cols.iter().zip(&found).find(|(_, f)| f.is_none());
                return Err(ImportError::Header {
                    path: path.to_path_buf(),
                    line: hl,
                    field: missing.map_or_else(String::new, |(c, _)| c.clone()),
                    message: format!("marker {k} needs the three columns x{k}, y{k}, z{k}"),
                });
            }
        }
    }
    if markers.is_empty() {
        return Err(ImportError::Header {
            path: path.to_path_buf(),
            line: hl,
            field: "x1".to_string(),
            message: "expected figaroh's marker columns `x1,y1,z1,…`".to_string(),
        });
    }
    if markers.len() != o.reflector_names.len() {
        return Err(ImportError::Header {
            path: path.to_path_buf(),
            line: hl,
            field: format!("x{}", markers.len()),
            message: format!(
                "{} markers, the dataset has {} reflectors ({}): name as many reflectors",
                markers.len(),
                o.reflector_names.len(),
                o.reflector_names.join(", ")
            ),
        });
    }
    let marker_cols: Vec<usize> = markers.iter().flatten().copied().collect();
    // figaroh's pose markers add orientation columns (`phi1`, …): not used.
    let is_orientation = |n: &str| {
        ["phi", "theta", "psi"].iter().any(|p| {
            n.strip_prefix(p)
                .is_some_and(|r| !r.is_empty() && r.chars().all(|c| c.is_ascii_digit()))
        })
    };
    let mut notes = Vec::new();
    let other: Vec<usize> = (0..names.len())
        .filter(|k| {
            !marker_cols.contains(k) && !names[*k].is_empty() && !is_orientation(&names[*k])
        })
        .collect();
    let joint_cols: Vec<usize> = match o.joint_names {
        Some(joints) => {
            let mut cols = Vec::new();
            for j in joints {
                match col(j) {
                    Some(c) => cols.push(c),
                    None => {
                        return Err(ImportError::Header {
                            path: path.to_path_buf(),
                            line: hl,
                            field: j.clone(),
                            message: format!(
                                "no column for the arm's joint `{j}`: figaroh names one column per \
                                 joint as in the URDF (the arm's joints: {})",
                                joints.join(", ")
                            ),
                        });
                    }
                }
            }
            let ignored: Vec<&str> = other
                .iter()
                .filter(|k| !cols.contains(k))
                .map(|&k| names[k].as_str())
                .collect();
            if !ignored.is_empty() {
                notes.push(format!(
                    "columns not of this arm, ignored: {}",
                    ignored.join(", ")
                ));
            }
            cols
        }
        None => other,
    };
    let unit = o.unit.unwrap_or(PointUnit::M);
    let needed = marker_cols
        .iter()
        .chain(&joint_cols)
        .max()
        .copied()
        .unwrap_or(0)
        + 1;
    let mut rows = Vec::new();
    for (line, t) in it {
        let fields = text::split(t, delimiter);
        let mut points_mm = Vec::new();
        for (m, cols) in markers.iter().enumerate() {
            let mut p = Vector3::zeros();
            for (k, axis) in ["x", "y", "z"].into_iter().enumerate() {
                let name = format!("{axis}{}", m + 1);
                p[k] = coordinate(path, line, &fields, cols[k], needed, &name, unit, false)?;
            }
            points_mm.push(p);
        }
        let mut q_rad = Vec::new();
        for &c in &joint_cols {
            let f = field(path, line, &fields, c, needed)?;
            q_rad.push(text::number(f, false).ok_or_else(|| ImportError::Field {
                path: path.to_path_buf(),
                line,
                field: names[c].clone(),
                expected: "a joint value in rad".to_string(),
                found: crate::textfile::excerpt(f),
            })?);
        }
        rows.push(ConfigRow {
            id: None,
            points_mm,
            q_rad: Some(q_rad),
            time_s: None,
            split: None,
            line,
        });
    }
    Ok(PointFile {
        format: PointsFormat::Figaroh,
        unit,
        frame: None,
        table: PointTable::Rows(rows),
        notes,
    })
}

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

fn read_generic(
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

/// `cal` or `ver` (any case).
pub fn parse_split(path: &Path, line: usize, s: &str) -> Result<Split, ImportError> {
    match s.trim().to_lowercase().as_str() {
        "cal" => Ok(Split::Cal),
        "ver" => Ok(Split::Ver),
        _ => Err(ImportError::Field {
            path: path.to_path_buf(),
            line,
            field: "split".to_string(),
            expected: "`cal` or `ver`".to_string(),
            found: crate::textfile::excerpt(s),
        }),
    }
}
