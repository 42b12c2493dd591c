//! The `dualcal-dataset/1` measurement format: a directory with `dataset.toml` and one CSV per arm.
//! See `docs/formats.md`. Everything is converted to mm and rad on load.

pub use crate::atomic::Overwrite;
use crate::atomic::{OutputError, refuse_existing, write_atomic};
use crate::kinematics::{N_JOINTS, Side};
use nalgebra::Vector3;
use std::path::{Path, PathBuf};
use toml::Spanned;

/// The format tag written in `dataset.toml`.
pub const DATASET_FORMAT: &str = "dualcal-dataset/1";
/// Minimum number of configurations per arm (paper Table 2: 4 configurations make the truss rigid).
pub const MIN_CONFIGS: usize = 4;

/// Calibration or verification configuration.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum Split {
    Cal,
    Ver,
}

/// Which configurations an operation uses.
#[derive(
    Clone, Copy, Debug, PartialEq, Eq, Hash, Default, serde::Serialize, serde::Deserialize,
)]
#[serde(rename_all = "lowercase")]
pub enum SplitSelect {
    Cal,
    Ver,
    #[default]
    All,
}

impl SplitSelect {
    pub fn accepts(self, split: Split) -> bool {
        match self {
            SplitSelect::All => true,
            SplitSelect::Cal => split == Split::Cal,
            SplitSelect::Ver => split == Split::Ver,
        }
    }
}

/// One measured configuration of one arm.
#[derive(Clone, Debug, PartialEq)]
pub struct Measurement {
    pub id: String,
    /// Joint values in chain order, rad.
    pub q_rad: [f64; N_JOINTS],
    /// Measured reflector positions a, b, c in the tracker frame, mm.
    pub tracker_points_mm: [Vector3<f64>; 3],
    /// `cal` or `ver`; rows without a split column are `cal`.
    pub split: Split,
    /// 1-based line number in the CSV (for messages).
    pub line: usize,
}

/// The tracker's maximum permissible error `mpe_um + mpe_um_per_m · distance`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct TrackerSpec {
    pub mpe_um: f64,
    pub mpe_um_per_m: f64,
}

impl Default for TrackerSpec {
    /// FARO Vantage, as in the paper: 16 µm + 0.8 µm/m.
    fn default() -> Self {
        Self {
            mpe_um: 16.0,
            mpe_um_per_m: 0.8,
        }
    }
}

/// One arm's measurements.
#[derive(Clone, Debug, PartialEq)]
pub struct ArmData {
    pub side: Side,
    pub file: PathBuf,
    pub measurements: Vec<Measurement>,
}

impl ArmData {
    pub fn select(&self, split: SplitSelect) -> Vec<&Measurement> {
        self.measurements
            .iter()
            .filter(|m| split.accepts(m.split))
            .collect()
    }
}

/// A loaded dataset.
#[derive(Clone, Debug, PartialEq)]
pub struct Dataset {
    /// Directory the dataset was loaded from.
    pub dir: PathBuf,
    /// Robot description (resolved path), or `None` for the built-in IRB 14000.
    pub robot: Option<PathBuf>,
    pub tracker: TrackerSpec,
    /// Nominal reflector coordinates in the flange frame, mm.
    pub nominal_reflectors_mm: [Vector3<f64>; 3],
    pub left: ArmData,
    pub right: ArmData,
}

impl Dataset {
    pub fn arm(&self, side: Side) -> &ArmData {
        match side {
            Side::Left => &self.left,
            Side::Right => &self.right,
        }
    }
}

/// Unit of lengths in a dataset's files.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, Default)]
pub enum LengthUnit {
    #[default]
    Mm,
    M,
}

impl LengthUnit {
    /// Millimetres per unit.
    pub fn mm_per_unit(self) -> f64 {
        match self {
            LengthUnit::Mm => 1.0,
            LengthUnit::M => 1000.0,
        }
    }

    /// The name used in files (`mm` or `m`).
    pub fn name(self) -> &'static str {
        match self {
            LengthUnit::Mm => "mm",
            LengthUnit::M => "m",
        }
    }

    /// Parse a file name of the unit (exact, lowercase).
    pub fn parse(s: &str) -> Option<Self> {
        match s {
            "mm" => Some(LengthUnit::Mm),
            "m" => Some(LengthUnit::M),
            _ => None,
        }
    }

    /// A value in this unit, in mm.
    pub fn to_mm(self, v: f64) -> f64 {
        v * self.mm_per_unit()
    }

    /// A value in mm, in this unit.
    pub fn from_mm(self, v_mm: f64) -> f64 {
        match self {
            LengthUnit::Mm => v_mm,
            LengthUnit::M => v_mm / 1000.0,
        }
    }
}

/// Unit of angles in a dataset's files.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, Default)]
pub enum AngleUnit {
    Deg,
    #[default]
    Rad,
}

impl AngleUnit {
    /// The name used in files (`deg` or `rad`).
    pub fn name(self) -> &'static str {
        match self {
            AngleUnit::Deg => "deg",
            AngleUnit::Rad => "rad",
        }
    }

    /// Parse a file name of the unit (exact, lowercase).
    pub fn parse(s: &str) -> Option<Self> {
        match s {
            "deg" => Some(AngleUnit::Deg),
            "rad" => Some(AngleUnit::Rad),
            _ => None,
        }
    }

    /// A value in this unit, in rad.
    pub fn to_rad(self, v: f64) -> f64 {
        match self {
            AngleUnit::Deg => v.to_radians(),
            AngleUnit::Rad => v,
        }
    }

    /// A value in rad, in this unit.
    pub fn from_rad(self, v_rad: f64) -> f64 {
        match self {
            AngleUnit::Deg => v_rad.to_degrees(),
            AngleUnit::Rad => v_rad,
        }
    }
}

/// The units of a dataset's files (`[units]` in `dataset.toml`). In memory everything is mm and rad.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, Default)]
pub struct Units {
    pub length: LengthUnit,
    pub angle: AngleUnit,
}

impl Units {
    /// Millimetres and radians (the internal units).
    pub const MM_RAD: Units = Units {
        length: LengthUnit::Mm,
        angle: AngleUnit::Rad,
    };
    /// Millimetres and degrees (what a robot controller and a tracker usually print).
    pub const MM_DEG: Units = Units {
        length: LengthUnit::Mm,
        angle: AngleUnit::Deg,
    };
}

/// Expected CSV columns, in order (`split` is optional and last).
pub const CSV_COLUMNS: [&str; 17] = [
    "id", "q1", "q2", "q3", "q4", "q5", "q6", "q7", "ax", "ay", "az", "bx", "by", "bz", "cx", "cy",
    "cz",
];
/// The optional last CSV column.
pub const SPLIT_COLUMN: &str = "split";

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
    /// A file is missing or unreadable.
    #[error("{path}: cannot read: {source}")]
    Io {
        path: PathBuf,
        #[source]
        source: std::io::Error,
    },
    /// A file could not be written.
    #[error("{path}: cannot write: {source}")]
    Write {
        path: PathBuf,
        #[source]
        source: std::io::Error,
    },
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
    #[error("{path}:{line}: expected {expected} fields (as in the header), found {found}")]
    FieldCount {
        path: PathBuf,
        line: usize,
        expected: usize,
        found: usize,
    },
    /// Two CSV rows share an id.
    #[error("{path}:{line}: field `id`: duplicate id `{id}` (first used on line {first_line})")]
    DuplicateId {
        path: PathBuf,
        line: usize,
        id: String,
        first_line: usize,
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

/// 1-based line and column of byte `offset` in `text`, and the trimmed text of that line.
fn line_col(text: &str, offset: usize) -> (usize, usize, String) {
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
        .unwrap_or("")
        .trim()
        .to_string();
    (line, col, line_text)
}

/// Read a text file: UTF-8, an optional byte-order mark is dropped.
fn read_text(path: &Path) -> Result<String, DatasetError> {
    let bytes = std::fs::read(path).map_err(|source| DatasetError::Io {
        path: path.to_path_buf(),
        source,
    })?;
    let (bom, body) = match bytes.strip_prefix(b"\xEF\xBB\xBF") {
        Some(rest) => (3, rest),
        None => (0, &bytes[..]),
    };
    match std::str::from_utf8(body) {
        Ok(s) => Ok(s.to_owned()),
        Err(e) => {
            let pos = e.valid_up_to();
            let line = body[..pos].iter().filter(|&&b| b == b'\n').count() + 1;
            Err(DatasetError::Encoding {
                path: path.to_path_buf(),
                line,
                byte: pos + bom + 1,
            })
        }
    }
}

// ---------------------------------------------------------------------------------------------------
// dataset.toml

#[derive(serde::Deserialize)]
struct RawFormatOnly {
    format: Option<Spanned<toml::Value>>,
}

#[derive(serde::Deserialize)]
#[serde(deny_unknown_fields)]
struct RawManifest {
    #[allow(dead_code)]
    format: Option<toml::Value>,
    #[allow(dead_code)]
    description: Option<String>,
    robot: Option<Spanned<String>>,
    units: Option<Spanned<RawUnits>>,
    tracker: Option<Spanned<RawTracker>>,
    reflectors: Option<Spanned<RawReflectors>>,
    arms: Option<Vec<Spanned<RawArm>>>,
}

#[derive(serde::Deserialize)]
#[serde(deny_unknown_fields)]
struct RawUnits {
    length: Option<Spanned<String>>,
    angle: Option<Spanned<String>>,
}

#[derive(serde::Deserialize)]
#[serde(deny_unknown_fields)]
struct RawTracker {
    mpe_um: Option<Spanned<f64>>,
    mpe_um_per_m: Option<Spanned<f64>>,
}

#[derive(serde::Deserialize)]
#[serde(deny_unknown_fields)]
struct RawReflectors {
    a: Option<Spanned<toml::Value>>,
    b: Option<Spanned<toml::Value>>,
    c: Option<Spanned<toml::Value>>,
}

#[derive(serde::Deserialize)]
#[serde(deny_unknown_fields)]
struct RawArm {
    name: Option<Spanned<String>>,
    file: Option<Spanned<String>>,
}

/// What `dataset.toml` says, validated and in mm.
struct Manifest {
    units: Units,
    robot: Option<PathBuf>,
    tracker: TrackerSpec,
    reflectors_mm: [Vector3<f64>; 3],
    /// CSV path of the left and the right arm.
    files: [PathBuf; 2],
}

struct ManifestCtx<'a> {
    path: &'a Path,
    text: &'a str,
}

impl ManifestCtx<'_> {
    fn line_of(&self, span: std::ops::Range<usize>) -> usize {
        line_col(self.text, span.start).0
    }

    fn err(&self, line: Option<usize>, field: &str, message: impl Into<String>) -> DatasetError {
        DatasetError::Manifest {
            path: self.path.to_path_buf(),
            line,
            field: field.to_string(),
            message: message.into(),
        }
    }

    fn toml_err(&self, e: &toml::de::Error) -> DatasetError {
        let (line, text) = match e.span() {
            Some(span) => {
                let (l, _, t) = line_col(self.text, span.start);
                (Some(l), t)
            }
            None => (None, String::new()),
        };
        DatasetError::Toml {
            path: self.path.to_path_buf(),
            line,
            text,
            message: e.message().trim().to_string(),
        }
    }
}

fn parse_manifest(path: &Path, dir: &Path, text: &str) -> Result<Manifest, DatasetError> {
    let cx = ManifestCtx { path, text };

    // Syntax errors and the format tag first, so that a file of another format gets the right message.
    let head: RawFormatOnly = toml::from_str(text).map_err(|e| cx.toml_err(&e))?;
    match head.format {
        None => {
            return Err(cx.err(
                None,
                "format",
                format!("missing; expected `format = \"{DATASET_FORMAT}\"` at the top"),
            ));
        }
        Some(tag) => {
            let line = Some(cx.line_of(tag.span()));
            match tag.get_ref() {
                toml::Value::String(s) if s == DATASET_FORMAT => {}
                other => {
                    return Err(cx.err(
                        line,
                        "format",
                        format!("unknown format tag {other}; expected \"{DATASET_FORMAT}\""),
                    ));
                }
            }
        }
    }
    let raw: RawManifest = toml::from_str(text).map_err(|e| cx.toml_err(&e))?;

    // [units]
    let Some(units_t) = raw.units else {
        return Err(cx.err(
            None,
            "units",
            "missing [units] table; expected length = \"mm\" | \"m\" and angle = \"deg\" | \"rad\"",
        ));
    };
    let units_line = Some(cx.line_of(units_t.span()));
    let units_t = units_t.into_inner();
    let length = match units_t.length {
        None => {
            return Err(cx.err(
                units_line,
                "units.length",
                "missing; expected \"mm\" or \"m\"",
            ));
        }
        Some(s) => LengthUnit::parse(s.get_ref()).ok_or_else(|| {
            cx.err(
                Some(cx.line_of(s.span())),
                "units.length",
                format!(
                    "unknown length unit \"{}\"; expected \"mm\" or \"m\"",
                    s.get_ref()
                ),
            )
        })?,
    };
    let angle = match units_t.angle {
        None => {
            return Err(cx.err(
                units_line,
                "units.angle",
                "missing; expected \"deg\" or \"rad\"",
            ));
        }
        Some(s) => AngleUnit::parse(s.get_ref()).ok_or_else(|| {
            cx.err(
                Some(cx.line_of(s.span())),
                "units.angle",
                format!(
                    "unknown angle unit \"{}\"; expected \"deg\" or \"rad\"",
                    s.get_ref()
                ),
            )
        })?,
    };
    let units = Units { length, angle };

    // robot
    let robot = match raw.robot {
        None => None,
        Some(r) => {
            let line = Some(cx.line_of(r.span()));
            if r.get_ref().trim().is_empty() {
                return Err(cx.err(
                    line,
                    "robot",
                    "empty path; leave `robot` out for the built-in IRB 14000",
                ));
            }
            let p = dir.join(r.get_ref());
            if !p.is_file() {
                return Err(cx.err(
                    line,
                    "robot",
                    format!("robot description {} not found (paths are relative to the dataset directory)", p.display()),
                ));
            }
            Some(p)
        }
    };

    // [tracker]
    let tracker = match raw.tracker {
        None => TrackerSpec::default(),
        Some(t) => {
            let line = Some(cx.line_of(t.span()));
            let t = t.into_inner();
            let get = |v: Option<Spanned<f64>>, name: &str| -> Result<f64, DatasetError> {
                let field = format!("tracker.{name}");
                match v {
                    None => Err(cx.err(line, &field, "missing; expected a number of micrometres")),
                    Some(v) => {
                        let x = *v.get_ref();
                        if x.is_finite() && x >= 0.0 {
                            Ok(x)
                        } else {
                            Err(cx.err(
                                Some(cx.line_of(v.span())),
                                &field,
                                format!("{x} is not a finite, non-negative number of micrometres"),
                            ))
                        }
                    }
                }
            };
            TrackerSpec {
                mpe_um: get(t.mpe_um, "mpe_um")?,
                mpe_um_per_m: get(t.mpe_um_per_m, "mpe_um_per_m")?,
            }
        }
    };

    // [reflectors]
    let Some(refl) = raw.reflectors else {
        return Err(cx.err(
            None,
            "reflectors",
            "missing [reflectors] table with the nominal flange coordinates a, b, c",
        ));
    };
    let refl_line = Some(cx.line_of(refl.span()));
    let refl = refl.into_inner();
    let mut reflectors_mm = [Vector3::zeros(); 3];
    for (k, v) in [refl.a, refl.b, refl.c].into_iter().enumerate() {
        let field = format!("reflectors.{}", crate::kinematics::REFLECTOR_NAMES[k]);
        let expected = format!("expected 3 numbers [x, y, z] in {}", length.name());
        let Some(v) = v else {
            return Err(cx.err(refl_line, &field, format!("missing; {expected}")));
        };
        let line = Some(cx.line_of(v.span()));
        let bad = |found: &str| cx.err(line, &field, format!("{expected}, found {found}"));
        let toml::Value::Array(items) = v.get_ref() else {
            return Err(bad(&v.get_ref().to_string()));
        };
        if items.len() != 3 {
            return Err(bad(&format!("{} values", items.len())));
        }
        for (c, item) in items.iter().enumerate() {
            let x = match item {
                toml::Value::Float(x) => *x,
                toml::Value::Integer(i) => *i as f64,
                other => return Err(bad(&format!("{other}"))),
            };
            if !x.is_finite() {
                return Err(bad(&format!("{x}")));
            }
            reflectors_mm[k][c] = length.to_mm(x);
        }
    }

    // [[arms]]
    let mut files: [Option<PathBuf>; 2] = [None, None];
    let mut arm_lines: [usize; 2] = [0, 0];
    for arm in raw.arms.unwrap_or_default() {
        let line = cx.line_of(arm.span());
        let arm = arm.into_inner();
        let Some(name) = arm.name else {
            return Err(cx.err(
                Some(line),
                "arms.name",
                "missing; expected \"left\" or \"right\"",
            ));
        };
        let name_line = cx.line_of(name.span());
        let slot = match name.get_ref().as_str() {
            "left" => 0,
            "right" => 1,
            other => {
                return Err(cx.err(
                    Some(name_line),
                    "arms.name",
                    format!("unknown arm \"{other}\"; expected \"left\" or \"right\""),
                ));
            }
        };
        if files[slot].is_some() {
            return Err(cx.err(
                Some(name_line),
                "arms.name",
                format!(
                    "duplicate arm \"{}\" (already listed on line {})",
                    name.get_ref(),
                    arm_lines[slot]
                ),
            ));
        }
        let Some(file) = arm.file else {
            return Err(cx.err(
                Some(line),
                "arms.file",
                "missing; expected the CSV file name",
            ));
        };
        if file.get_ref().trim().is_empty() {
            return Err(cx.err(
                Some(cx.line_of(file.span())),
                "arms.file",
                "empty file name",
            ));
        }
        files[slot] = Some(dir.join(file.get_ref()));
        arm_lines[slot] = name_line;
    }
    let [Some(left), Some(right)] = files else {
        let missing = if files[0].is_none() { "left" } else { "right" };
        return Err(cx.err(
            None,
            "arms",
            format!("missing [[arms]] entry with name = \"{missing}\"; both arms are needed"),
        ));
    };

    Ok(Manifest {
        units,
        robot,
        tracker,
        reflectors_mm,
        files: [left, right],
    })
}

// ---------------------------------------------------------------------------------------------------
// CSV

/// Check the header; returns whether it has the `split` column.
fn check_header(
    path: &Path,
    line: usize,
    header: &csv::StringRecord,
) -> Result<bool, DatasetError> {
    let err = |field: &str, message: String| DatasetError::Header {
        path: path.to_path_buf(),
        line,
        field: field.to_string(),
        message,
    };
    let expected = format!("{},[{SPLIT_COLUMN}]", CSV_COLUMNS.join(","));
    if header.len() == 1 {
        let only = header.get(0).unwrap_or("");
        if let Some(sep) = [';', '\t', ' '].into_iter().find(|&c| only.contains(c)) {
            return Err(err(
                only,
                format!("fields are separated by {sep:?}; use commas, with the header {expected}"),
            ));
        }
    }
    for (i, want) in CSV_COLUMNS.iter().enumerate() {
        let Some(got) = header.get(i) else {
            return Err(err(
                want,
                format!("missing column `{want}`; the header must be {expected}"),
            ));
        };
        if got != *want {
            let message = if CSV_COLUMNS.contains(&got) || got == SPLIT_COLUMN {
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
    }
    match header.len() {
        17 => Ok(false),
        18 if header.get(17) == Some(SPLIT_COLUMN) => Ok(true),
        _ => {
            let got = header.get(17).unwrap_or("");
            Err(err(
                got,
                format!(
                    "unknown column `{got}` in position 18; only `{SPLIT_COLUMN}` may follow `cz` (header {expected})"
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
        .map_err(|_| err(format!("`{s}` is not a number")))?;
    if !x.is_finite() {
        return Err(err(format!("`{s}` is not a finite number")));
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

/// Read one arm's CSV into measurements in mm and rad.
fn read_arm_csv(path: &Path, side: Side, units: Units) -> Result<Vec<Measurement>, DatasetError> {
    let text = read_text(path)?;
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
    let map_csv_err = |e: csv::Error, line: usize| -> DatasetError {
        match e.kind() {
            csv::ErrorKind::UnequalLengths {
                expected_len, len, ..
            } => DatasetError::FieldCount {
                path: path.to_path_buf(),
                line,
                expected: usize::try_from(*expected_len).unwrap_or(usize::MAX),
                found: usize::try_from(*len).unwrap_or(usize::MAX),
            },
            _ => DatasetError::Content {
                path: path.to_path_buf(),
                message: format!("line {line}: {e}"),
            },
        }
    };

    let mut records = reader.records();
    let end_line = text.lines().count() + 1;
    let header = match records.next() {
        None => {
            return Err(DatasetError::Header {
                path: path.to_path_buf(),
                line: end_line,
                field: "id".into(),
                message: format!(
                    "missing header; expected {},[{SPLIT_COLUMN}] after any `#` comment lines",
                    CSV_COLUMNS.join(",")
                ),
            });
        }
        Some(Ok(r)) => r,
        Some(Err(e)) => {
            let line = line_at(e.position(), 1);
            return Err(map_csv_err(e, line));
        }
    };
    let header_line = line_at(header.position(), 1);
    let has_split = check_header(path, header_line, &header)?;

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
        let field = |i: usize| rec.get(i).unwrap_or("");
        let id = field(0);
        if id.is_empty() {
            return Err(DatasetError::Field {
                path: path.to_path_buf(),
                line,
                field: "id".into(),
                message: "empty id; every row needs a unique id".into(),
            });
        }
        if let Some(&first_line) = first_line_of_id.get(id) {
            return Err(DatasetError::DuplicateId {
                path: path.to_path_buf(),
                line,
                id: id.to_string(),
                first_line,
            });
        }
        first_line_of_id.insert(id.to_string(), line);
        let mut q_rad = [0.0; N_JOINTS];
        for (j, q) in q_rad.iter_mut().enumerate() {
            let col = 1 + j;
            *q = units
                .angle
                .to_rad(parse_number(path, line, CSV_COLUMNS[col], field(col))?);
        }
        let mut tracker_points_mm = [Vector3::zeros(); 3];
        for (k, p) in tracker_points_mm.iter_mut().enumerate() {
            for c in 0..3 {
                let col = 8 + 3 * k + c;
                p[c] = units
                    .length
                    .to_mm(parse_number(path, line, CSV_COLUMNS[col], field(col))?);
            }
        }
        let split = if has_split {
            match field(17) {
                "cal" => Split::Cal,
                "ver" => Split::Ver,
                other => {
                    return Err(DatasetError::Field {
                        path: path.to_path_buf(),
                        line,
                        field: SPLIT_COLUMN.into(),
                        message: format!("unknown split `{other}`; expected `cal` or `ver`"),
                    });
                }
            }
        } else {
            Split::Cal
        };
        out.push(Measurement {
            id: id.to_string(),
            q_rad,
            tracker_points_mm,
            split,
            line,
        });
    }
    if out.len() < MIN_CONFIGS {
        return Err(DatasetError::TooFewConfigurations {
            path: path.to_path_buf(),
            side,
            found: out.len(),
            min: MIN_CONFIGS,
        });
    }
    Ok(out)
}

/// Resolve a dataset path (its directory or its manifest) into (directory, manifest path).
fn resolve(path: &Path) -> (PathBuf, PathBuf) {
    if path.is_dir() {
        (path.to_path_buf(), path.join(MANIFEST_FILE))
    } else {
        let dir = match path.parent() {
            Some(p) if !p.as_os_str().is_empty() => p.to_path_buf(),
            _ => PathBuf::from("."),
        };
        (dir, path.to_path_buf())
    }
}

/// The manifest's file name inside a dataset directory.
pub const MANIFEST_FILE: &str = "dataset.toml";

/// Load a dataset from its directory or from the path of its `dataset.toml`.
pub fn load(path: &Path) -> Result<Dataset, DatasetError> {
    load_with_units(path).map(|(d, _)| d)
}

/// Like [`load`], also returning the units the files were written in (to save back in the same units).
pub fn load_with_units(path: &Path) -> Result<(Dataset, Units), DatasetError> {
    let (dir, manifest_path) = resolve(path);
    let text = read_text(&manifest_path)?;
    let m = parse_manifest(&manifest_path, &dir, &text)?;
    let [left_file, right_file] = m.files;
    let left = read_arm_csv(&left_file, Side::Left, m.units)?;
    let right = read_arm_csv(&right_file, Side::Right, m.units)?;
    Ok((
        Dataset {
            dir,
            robot: m.robot,
            tracker: m.tracker,
            nominal_reflectors_mm: m.reflectors_mm,
            left: ArmData {
                side: Side::Left,
                file: left_file,
                measurements: left,
            },
            right: ArmData {
                side: Side::Right,
                file: right_file,
                measurements: right,
            },
        },
        m.units,
    ))
}

// ---------------------------------------------------------------------------------------------------
// Saving

/// Shortest text that parses back to exactly `x` (Rust's `{:?}` of f64: round-trip, `.0` on integers).
fn num(x: f64) -> String {
    format!("{x:?}")
}

/// A TOML basic string literal.
fn toml_str(s: &str) -> String {
    toml::Value::String(s.to_string()).to_string()
}

fn check_finite(path: &Path, what: &str, values: &[f64]) -> Result<(), DatasetError> {
    if let Some(x) = values.iter().find(|x| !x.is_finite()) {
        return Err(DatasetError::Content {
            path: path.to_path_buf(),
            message: format!("cannot save {what}: {x} is not a finite number"),
        });
    }
    Ok(())
}

fn arm_csv(arm: &ArmData, path: &Path, units: Units) -> Result<Vec<u8>, DatasetError> {
    let content_err = |message: String| DatasetError::Content {
        path: path.to_path_buf(),
        message,
    };
    if arm.measurements.len() < MIN_CONFIGS {
        return Err(DatasetError::TooFewConfigurations {
            path: path.to_path_buf(),
            side: arm.side,
            found: arm.measurements.len(),
            min: MIN_CONFIGS,
        });
    }
    let mut seen = std::collections::HashSet::new();
    let mut bytes = format!(
        "# {DATASET_FORMAT}: {} arm. q1..q7 in chain order (ABB axes 1, 2, 7, 3, 4, 5, 6), {}; \
         reflectors a, b, c in the tracker frame, {}.\n",
        arm.side,
        units.angle.name(),
        units.length.name()
    )
    .into_bytes();
    {
        let mut w = csv::WriterBuilder::new()
            .has_headers(false)
            .from_writer(&mut bytes);
        let mut header: Vec<&str> = CSV_COLUMNS.to_vec();
        header.push(SPLIT_COLUMN);
        w.write_record(&header)
            .map_err(|e| content_err(e.to_string()))?;
        for m in &arm.measurements {
            let id = m.id.as_str();
            if id.is_empty() || id.trim() != id || id.starts_with('#') || id.contains(['\n', '\r'])
            {
                return Err(content_err(format!(
                    "cannot save id {id:?}: ids must be non-empty, one line, without surrounding spaces and not start with `#`"
                )));
            }
            if !seen.insert(id) {
                return Err(content_err(format!("cannot save: duplicate id `{id}`")));
            }
            check_finite(path, &format!("configuration `{id}`"), &m.q_rad)?;
            for p in &m.tracker_points_mm {
                check_finite(path, &format!("configuration `{id}`"), p.as_slice())?;
            }
            let mut row = vec![id.to_string()];
            row.extend(m.q_rad.iter().map(|&q| num(units.angle.from_rad(q))));
            for p in &m.tracker_points_mm {
                row.extend(p.iter().map(|&x| num(units.length.from_mm(x))));
            }
            row.push(
                match m.split {
                    Split::Cal => "cal",
                    Split::Ver => "ver",
                }
                .to_string(),
            );
            w.write_record(&row)
                .map_err(|e| content_err(e.to_string()))?;
        }
        w.flush().map_err(|source| DatasetError::Write {
            path: path.to_path_buf(),
            source,
        })?;
    }
    Ok(bytes)
}

fn manifest_text(
    dataset: &Dataset,
    dir: &Path,
    path: &Path,
    units: Units,
) -> Result<String, DatasetError> {
    let content_err = |message: String| DatasetError::Content {
        path: path.to_path_buf(),
        message,
    };
    let mut s = format!("format = {}\n", toml_str(DATASET_FORMAT));
    if let Some(robot) = &dataset.robot {
        // Relative to the output directory when the robot lives inside it, else absolute.
        let p = match robot.strip_prefix(dir) {
            Ok(rel) => rel.to_path_buf(),
            Err(_) => robot.canonicalize().unwrap_or_else(|_| robot.clone()),
        };
        let p = p
            .to_str()
            .ok_or_else(|| content_err(format!("robot path {} is not valid UTF-8", p.display())))?;
        s += &format!("robot = {}\n", toml_str(p));
    }
    s += &format!(
        "\n[units]\nlength = {}\nangle = {}\n",
        toml_str(units.length.name()),
        toml_str(units.angle.name())
    );
    let t = dataset.tracker;
    check_finite(path, "the tracker MPE", &[t.mpe_um, t.mpe_um_per_m])?;
    s += &format!(
        "\n[tracker]\nmpe_um = {}\nmpe_um_per_m = {}\n",
        num(t.mpe_um),
        num(t.mpe_um_per_m)
    );
    s += "\n[reflectors]\n";
    for (name, r) in crate::kinematics::REFLECTOR_NAMES
        .iter()
        .zip(&dataset.nominal_reflectors_mm)
    {
        check_finite(path, "the nominal reflectors", r.as_slice())?;
        let v: Vec<String> = r.iter().map(|&x| num(units.length.from_mm(x))).collect();
        s += &format!("{name} = [{}]\n", v.join(", "));
    }
    for side in Side::BOTH {
        s += &format!(
            "\n[[arms]]\nname = {}\nfile = {}\n",
            toml_str(side.name()),
            toml_str(&format!("{side}.csv"))
        );
    }
    Ok(s)
}

/// Write `dataset` as a `dualcal-dataset/1` directory (`dataset.toml`, `left.csv`, `right.csv`, with a
/// `split` column) in the given units. Creates `dir` if needed and refuses to replace an existing dataset
/// there (see [`save_with`]). Numbers are written with full f64 precision.
pub fn save(dataset: &Dataset, dir: &Path, units: Units) -> Result<(), DatasetError> {
    save_with(dataset, dir, units, Overwrite::Refuse)
}

/// Like [`save`]; with [`Overwrite::Allow`] existing `dataset.toml`/`left.csv`/`right.csv` in `dir` are
/// replaced. Each file is written atomically; the manifest is written last.
pub fn save_with(
    dataset: &Dataset,
    dir: &Path,
    units: Units,
    overwrite: Overwrite,
) -> Result<(), DatasetError> {
    let manifest_path = dir.join(MANIFEST_FILE);
    let csv_paths = Side::BOTH.map(|s| dir.join(format!("{s}.csv")));
    refuse_existing(&[&manifest_path, &csv_paths[0], &csv_paths[1]], overwrite)?;
    // Build everything before touching the disk.
    let manifest = manifest_text(dataset, dir, &manifest_path, units)?;
    let left = arm_csv(&dataset.left, &csv_paths[0], units)?;
    let right = arm_csv(&dataset.right, &csv_paths[1], units)?;
    std::fs::create_dir_all(dir).map_err(|source| DatasetError::Write {
        path: dir.to_path_buf(),
        source,
    })?;
    for (path, bytes) in [
        (&csv_paths[0], &left[..]),
        (&csv_paths[1], &right[..]),
        (&manifest_path, manifest.as_bytes()),
    ] {
        write_atomic(path, bytes).map_err(|source| DatasetError::Write {
            path: path.clone(),
            source,
        })?;
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand::{Rng, SeedableRng};
    use rand_chacha::ChaCha8Rng;

    fn random_arm(rng: &mut ChaCha8Rng, side: Side, n: usize) -> ArmData {
        let measurements = (0..n)
            .map(|i| Measurement {
                // Ids that need CSV quoting must survive too.
                id: match i {
                    0 => "pose, \"first\"".to_string(),
                    1 => "ü-2".to_string(),
                    _ => format!("{side}{i}"),
                },
                q_rad: std::array::from_fn(|_| rng.random_range(-3.0..3.0)),
                tracker_points_mm: std::array::from_fn(|_| {
                    Vector3::from_fn(|_, _| rng.random_range(-3000.0..3000.0))
                }),
                split: if rng.random_bool(0.3) {
                    Split::Ver
                } else {
                    Split::Cal
                },
                line: 0,
            })
            .collect();
        ArmData {
            side,
            file: PathBuf::new(),
            measurements,
        }
    }

    fn random_dataset(seed: u64) -> Dataset {
        let mut rng = ChaCha8Rng::seed_from_u64(seed);
        Dataset {
            dir: PathBuf::new(),
            robot: None,
            tracker: TrackerSpec {
                mpe_um: 10.0,
                mpe_um_per_m: 1.25,
            },
            nominal_reflectors_mm: std::array::from_fn(|_| {
                Vector3::from_fn(|_, _| rng.random_range(-50.0..50.0))
            }),
            left: random_arm(&mut rng, Side::Left, 9),
            right: random_arm(&mut rng, Side::Right, 7),
        }
    }

    /// Compare everything but paths and line numbers.
    fn assert_close(a: &Dataset, b: &Dataset, tol_mm: f64, tol_rad: f64) {
        assert_eq!(a.tracker, b.tracker);
        for k in 0..3 {
            assert!((a.nominal_reflectors_mm[k] - b.nominal_reflectors_mm[k]).amax() <= tol_mm);
        }
        for side in Side::BOTH {
            let (x, y) = (a.arm(side), b.arm(side));
            assert_eq!(y.side, side);
            assert_eq!(x.measurements.len(), y.measurements.len());
            for (m, n) in x.measurements.iter().zip(&y.measurements) {
                assert_eq!(m.id, n.id);
                assert_eq!(m.split, n.split);
                for j in 0..N_JOINTS {
                    assert!((m.q_rad[j] - n.q_rad[j]).abs() <= tol_rad);
                }
                for k in 0..3 {
                    assert!((m.tracker_points_mm[k] - n.tracker_points_mm[k]).amax() <= tol_mm);
                }
            }
        }
    }

    #[test]
    fn round_trip_in_every_unit() {
        let original = random_dataset(7);
        for length in [LengthUnit::Mm, LengthUnit::M] {
            for angle in [AngleUnit::Rad, AngleUnit::Deg] {
                let units = Units { length, angle };
                let dir = tempfile::tempdir().unwrap();
                let out = dir.path().join("ds");
                save(&original, &out, units).unwrap();
                let (back, read_units) = load_with_units(&out).unwrap();
                assert_eq!(read_units, units);
                assert_eq!(back.dir, out);
                assert_eq!(back.left.file, out.join("left.csv"));
                if units == Units::MM_RAD {
                    // No conversion: bit-exact.
                    assert_close(&original, &back, 0.0, 0.0);
                } else {
                    assert_close(&original, &back, 1e-9, 1e-12);
                }
                // Line numbers point at the rows: comment line 1, header line 2.
                assert_eq!(back.right.measurements[3].line, 6);
            }
        }
    }

    #[test]
    fn save_refuses_to_replace_a_dataset_without_the_flag() {
        let d = random_dataset(3);
        let dir = tempfile::tempdir().unwrap();
        save(&d, dir.path(), Units::MM_DEG).unwrap();
        let before = std::fs::read(dir.path().join("left.csv")).unwrap();
        let other = random_dataset(4);
        let err = save(&other, dir.path(), Units::MM_DEG).unwrap_err();
        assert!(matches!(
            err,
            DatasetError::Output(OutputError::Exists { .. })
        ));
        assert_eq!(std::fs::read(dir.path().join("left.csv")).unwrap(), before);
        save_with(&other, dir.path(), Units::MM_DEG, Overwrite::Allow).unwrap();
        let back = load(dir.path()).unwrap();
        assert_close(&other, &back, 1e-9, 1e-12);
    }

    #[test]
    fn save_refuses_unsavable_data_and_writes_nothing() {
        let dir = tempfile::tempdir().unwrap();
        let mut d = random_dataset(5);
        d.left.measurements[2].q_rad[4] = f64::NAN;
        assert!(matches!(
            save(&d, dir.path(), Units::MM_RAD),
            Err(DatasetError::Content { .. })
        ));
        let mut d = random_dataset(5);
        d.right.measurements[1].id = "#hidden".into();
        assert!(matches!(
            save(&d, dir.path(), Units::MM_RAD),
            Err(DatasetError::Content { .. })
        ));
        let mut d = random_dataset(5);
        d.right.measurements[1].id = d.right.measurements[2].id.clone();
        assert!(matches!(
            save(&d, dir.path(), Units::MM_RAD),
            Err(DatasetError::Content { .. })
        ));
        let mut d = random_dataset(5);
        d.left.measurements.truncate(MIN_CONFIGS - 1);
        assert!(matches!(
            save(&d, dir.path(), Units::MM_RAD),
            Err(DatasetError::TooFewConfigurations { .. })
        ));
        assert_eq!(std::fs::read_dir(dir.path()).unwrap().count(), 0);
    }

    #[test]
    fn robot_path_survives_a_round_trip() {
        let dir = tempfile::tempdir().unwrap();
        let urdf = dir.path().join("robot.urdf");
        std::fs::write(&urdf, "<robot/>").unwrap();
        let mut d = random_dataset(9);
        // Outside the output directory: written as an absolute path.
        d.robot = Some(urdf.clone());
        let out = dir.path().join("a");
        save(&d, &out, Units::MM_DEG).unwrap();
        let back = load(&out).unwrap();
        assert_eq!(
            back.robot.unwrap().canonicalize().unwrap(),
            urdf.canonicalize().unwrap()
        );
        // Inside: written relative, so the directory can move.
        d.robot = Some(dir.path().join("robot.urdf"));
        save_with(&d, dir.path(), Units::MM_DEG, Overwrite::Allow).unwrap();
        let text = std::fs::read_to_string(dir.path().join(MANIFEST_FILE)).unwrap();
        assert!(text.contains("robot = \"robot.urdf\""), "{text}");
        assert_eq!(load(dir.path()).unwrap().robot, Some(urdf));
    }

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
