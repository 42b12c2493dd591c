//! Point files: SpatialAnalyzer exports, Leica Tracker Pilot CSV, figaroh calibration CSV and any
//! CSV/TXT with a column mapping ([`ColumnMap`]). Each reader gives a [`PointFile`]: one measured point
//! per row ([`PointTable::Points`], matched to a joint log afterwards), or one configuration per row with
//! every reflector and possibly the joints ([`PointTable::Rows`]).

use super::error::ImportError;
use super::text::{self, Delimiter, PointUnit};
use crate::dataset::{AngleUnit, Split};
use nalgebra::Vector3;
use std::path::Path;

mod cells;
mod figaroh;
mod generic;
mod leica;
mod mapping;
mod spatial_analyzer;

pub use cells::Array;
pub use mapping::{CellRef, ColumnMap, ColumnRef, ColumnRole, Formula, Source};

/// The formats of point files.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum PointsFormat {
    /// SpatialAnalyzer ASCII/CSV export: optional `//` header lines, optional column names, name
    /// columns (`Collection Group Target`, `Group Target`, `Target` or none), then X Y Z.
    SpatialAnalyzer,
    /// Leica Tracker Pilot CSV: `X  [mm],Y  [mm],Z  [mm],…,Target,…,Time Stamp,…`.
    Leica,
    /// figaroh's calibration CSV: `x1,y1,z1,…` per marker, then one column per joint (m, rad).
    Figaroh,
    /// Any CSV/TXT with a column mapping (`--columns`).
    Generic,
}

impl crate::choice::Choice for PointsFormat {
    const WHAT: &'static str = "point file format";

    fn all() -> &'static [Self] {
        &[
            PointsFormat::SpatialAnalyzer,
            PointsFormat::Leica,
            PointsFormat::Figaroh,
            PointsFormat::Generic,
        ]
    }

    fn spelling(self) -> &'static str {
        match self {
            PointsFormat::SpatialAnalyzer => "spatial-analyzer",
            PointsFormat::Leica => "leica",
            PointsFormat::Figaroh => "figaroh",
            PointsFormat::Generic => "generic",
        }
    }

    fn aliases(self) -> &'static [&'static str] {
        match self {
            PointsFormat::SpatialAnalyzer => &["sa"],
            _ => &[],
        }
    }

    fn help(self) -> Option<&'static str> {
        Some(match self {
            PointsFormat::SpatialAnalyzer => {
                "SpatialAnalyzer ASCII/CSV export: optional `//` header lines, optional column \
                 names, name columns (`Collection Group Target`, `Group Target`, `Target` or none), \
                 then X Y Z"
            }
            PointsFormat::Leica => {
                "Leica Tracker Pilot CSV: `X  [mm],Y  [mm],Z  [mm],…,Target,…,Time Stamp,…`"
            }
            PointsFormat::Figaroh => {
                "figaroh's calibration CSV: `x1,y1,z1,…` per marker, then one column per joint (m, rad)"
            }
            PointsFormat::Generic => "Any CSV/TXT with a column mapping (`--columns`)",
        })
    }
}

impl std::str::FromStr for PointsFormat {
    type Err = crate::choice::UnknownChoice;

    fn from_str(text: &str) -> Result<Self, Self::Err> {
        <PointsFormat as crate::choice::Choice>::parse_choice(text)
    }
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
        PointsFormat::SpatialAnalyzer => spatial_analyzer::read_spatial_analyzer(path, text, o),
        PointsFormat::Leica => leica::read_leica(path, text, o),
        PointsFormat::Figaroh => figaroh::read_figaroh(path, text, o),
        PointsFormat::Generic => match o.columns {
            Some(map) => generic::read_generic(path, text, map, o),
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
