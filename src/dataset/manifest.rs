//! `dataset.toml`: the manifest.

use super::error::{DatasetError, line_col};
use super::units::{AngleUnit, LengthUnit, Units};
use super::{ArmLinks, DATASET_FORMAT, TrackerSpec};
use crate::side::{PerSide, Side};
use crate::source::FileSource;
use crate::textfile::excerpt;
use nalgebra::Vector3;
use std::path::{Path, PathBuf};
use toml::Spanned;

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
    measured_together: Option<bool>,
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

/// `[reflectors]`: any names, each an `[x, y, z]`; their file order is recovered from the spans.
type RawReflectors = std::collections::BTreeMap<Spanned<String>, Spanned<toml::Value>>;

/// The longest reflector name.
const MAX_REFLECTOR_NAME: usize = 32;

#[derive(serde::Deserialize)]
#[serde(deny_unknown_fields)]
struct RawArm {
    name: Option<Spanned<String>>,
    file: Option<Spanned<String>>,
    base_link: Option<Spanned<String>>,
    tip_link: Option<Spanned<String>>,
    station: Option<Spanned<String>>,
    reflectors: Option<Spanned<RawReflectors>>,
}

/// One `[[arms]]` entry: its CSV and, optionally, its chain in the robot description and the tracker
/// station it was measured from.
pub(super) struct ManifestArm {
    pub file: PathBuf,
    pub links: Option<ArmLinks>,
    pub station: Option<String>,
    /// The arm's own nominal reflector coordinates (`[[arms]] reflectors = {…}`: the dataset's names,
    /// in its order), mm.
    pub reflectors_mm: Option<Vec<Vector3<f64>>>,
}

/// What `dataset.toml` says, validated and in mm.
pub(super) struct Manifest {
    pub units: Units,
    pub robot: Option<PathBuf>,
    pub tracker: TrackerSpec,
    pub reflectors_mm: Vec<Vector3<f64>>,
    /// The reflectors' names, in the manifest's order (the CSV's column order).
    pub reflector_names: Vec<String>,
    /// CSV path and chain links of each arm; `None`: the arm was not measured (a dataset of one arm).
    pub arms: PerSide<Option<ManifestArm>>,
    /// Both hands measured at one instant (rows of one id in both files are one pose).
    pub measured_together: bool,
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
            // The parser's message may quote the input: keep it short.
            message: crate::textfile::excerpt_n(e.message().trim(), 200),
        }
    }
}

/// Parse and validate `dataset.toml` (`path`, in directory `dir`, with contents `text`).
pub(super) fn parse(
    files: &dyn FileSource,
    path: &Path,
    dir: &Path,
    text: &str,
) -> Result<Manifest, DatasetError> {
    let cx = ManifestCtx { path, text };
    // Syntax errors and the format tag first, so that a file of another format gets the right message.
    let head: RawFormatOnly = toml::from_str(text).map_err(|e| cx.toml_err(&e))?;
    check_format(&cx, head.format)?;
    let raw: RawManifest = toml::from_str(text).map_err(|e| cx.toml_err(&e))?;
    let units = parse_units(&cx, raw.units)?;
    let robot = parse_robot(&cx, files, dir, raw.robot)?;
    let tracker = match raw.tracker {
        None => TrackerSpec::default(),
        Some(t) => parse_tracker(&cx, t)?,
    };
    let (reflector_names, reflectors_mm) = parse_reflectors(&cx, raw.reflectors, units.length)?;
    let arms = parse_arms(
        &cx,
        dir,
        raw.arms.unwrap_or_default(),
        &reflector_names,
        units.length,
    )?;
    Ok(Manifest {
        units,
        robot,
        tracker,
        reflectors_mm,
        reflector_names,
        arms,
        measured_together: raw.measured_together.unwrap_or(false),
    })
}

fn check_format(cx: &ManifestCtx, tag: Option<Spanned<toml::Value>>) -> Result<(), DatasetError> {
    let Some(tag) = tag else {
        return Err(cx.err(
            None,
            "format",
            format!("missing; expected `format = \"{DATASET_FORMAT}\"` at the top"),
        ));
    };
    match tag.get_ref() {
        toml::Value::String(s) if s == DATASET_FORMAT => Ok(()),
        other => Err(cx.err(
            Some(cx.line_of(tag.span())),
            "format",
            format!(
                "unknown format tag {}; expected \"{DATASET_FORMAT}\"",
                excerpt(&other.to_string())
            ),
        )),
    }
}

/// `[units]`: `length = "mm" | "m"`, `angle = "deg" | "rad"`.
fn parse_units(cx: &ManifestCtx, raw: Option<Spanned<RawUnits>>) -> Result<Units, DatasetError> {
    let Some(units_t) = raw else {
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
                    excerpt(s.get_ref())
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
                    excerpt(s.get_ref())
                ),
            )
        })?,
    };
    Ok(Units { length, angle })
}

/// `robot`: a robot description relative to the dataset directory (absent: the built-in IRB 14000).
fn parse_robot(
    cx: &ManifestCtx,
    files: &dyn FileSource,
    dir: &Path,
    raw: Option<Spanned<String>>,
) -> Result<Option<PathBuf>, DatasetError> {
    let Some(r) = raw else {
        return Ok(None);
    };
    let line = Some(cx.line_of(r.span()));
    if r.get_ref().trim().is_empty() {
        return Err(cx.err(
            line,
            "robot",
            "empty path; leave `robot` out for the built-in IRB 14000",
        ));
    }
    super::validate::usable_path(r.get_ref()).map_err(|m| cx.err(line, "robot", m))?;
    let p = dir.join(r.get_ref());
    if !files.is_file(&p) {
        return Err(cx.err(
            line,
            "robot",
            format!(
                "robot description {} not found (paths are relative to the dataset directory)",
                p.display()
            ),
        ));
    }
    Ok(Some(p))
}

/// `[tracker]`: `mpe_um` and `mpe_um_per_m`, both finite and non-negative.
fn parse_tracker(cx: &ManifestCtx, t: Spanned<RawTracker>) -> Result<TrackerSpec, DatasetError> {
    let line = Some(cx.line_of(t.span()));
    let t = t.into_inner();
    let get = |v: Option<Spanned<f64>>, name: &str| -> Result<f64, DatasetError> {
        let field = format!("tracker.{name}");
        match v {
            None => Err(cx.err(line, &field, "missing; expected a number of micrometres")),
            Some(v) => {
                let x = *v.get_ref();
                if !(x.is_finite() && x >= 0.0) {
                    Err(cx.err(
                        Some(cx.line_of(v.span())),
                        &field,
                        format!("{x} is not a finite, non-negative number of micrometres"),
                    ))
                } else if x > super::validate::MAX_MPE_UM {
                    Err(cx.err(
                        Some(cx.line_of(v.span())),
                        &field,
                        format!(
                            "{x} µm is not a plausible tracker MPE (at most {} µm: laser trackers \
                             measure to tens of micrometres); the values are micrometres whatever \
                             [units] says",
                            super::validate::MAX_MPE_UM
                        ),
                    ))
                } else {
                    Ok(x)
                }
            }
        }
    };
    Ok(TrackerSpec {
        mpe_um: get(t.mpe_um, "mpe_um")?,
        mpe_um_per_m: get(t.mpe_um_per_m, "mpe_um_per_m")?,
    })
}

/// Is `name` usable as a reflector name (its CSV columns are `<name>x`, `<name>y`, `<name>z`)?
fn reflector_name_problem(name: &str) -> Option<String> {
    if name.is_empty() {
        return Some("an empty reflector name".into());
    }
    if name.len() > MAX_REFLECTOR_NAME {
        return Some(format!(
            "a reflector name of {} bytes; at most {MAX_REFLECTOR_NAME}",
            name.len()
        ));
    }
    let first_ok = name.starts_with(|c: char| c.is_ascii_alphabetic());
    if !first_ok || !name.chars().all(|c| c.is_ascii_alphanumeric() || c == '_') {
        return Some(format!(
            "reflector name `{}`: a name is a letter followed by letters, digits or `_` (its CSV \
             columns are `<name>x`, `<name>y`, `<name>z`)",
            excerpt(name)
        ));
    }
    None
}

/// `[reflectors]`: one or more named reflectors (`a = [x, y, z]`, in the tip link's frame), in the
/// file's order, converted to mm.
fn parse_reflectors(
    cx: &ManifestCtx,
    raw: Option<Spanned<RawReflectors>>,
    length: LengthUnit,
) -> Result<(Vec<String>, Vec<Vector3<f64>>), DatasetError> {
    let Some(refl) = raw else {
        return Err(cx.err(
            None,
            "reflectors",
            "missing [reflectors] table with the nominal coordinates of each reflector in the tip \
             link's frame (e.g. a = [x, y, z]; the paper's set-up has a, b, c)",
        ));
    };
    let refl_line = Some(cx.line_of(refl.span()));
    let mut entries: Vec<(Spanned<String>, Spanned<toml::Value>)> =
        refl.into_inner().into_iter().collect();
    crate::sort::sort_by_key(&mut entries, |(k, _)| k.span().start);
    if entries.is_empty() {
        return Err(cx.err(
            refl_line,
            "reflectors",
            "no reflector; expected at least one, e.g. a = [x, y, z] in the tip link's frame",
        ));
    }
    if entries.len() > crate::kinematics::MAX_REFLECTORS {
        return Err(cx.err(
            Some(cx.line_of(entries[crate::kinematics::MAX_REFLECTORS].0.span())),
            "reflectors",
            format!(
                "{} reflectors; dualcal takes 1 to {} per flange",
                entries.len(),
                crate::kinematics::MAX_REFLECTORS
            ),
        ));
    }
    let mut names = Vec::with_capacity(entries.len());
    let mut reflectors_mm = Vec::with_capacity(entries.len());
    for (key, v) in entries {
        let name = key.get_ref().clone();
        let field = format!("reflectors.{}", excerpt(&name));
        if let Some(problem) = reflector_name_problem(&name) {
            return Err(cx.err(Some(cx.line_of(key.span())), &field, problem));
        }
        let expected = format!("expected 3 numbers [x, y, z] in {}", length.name());
        let line = Some(cx.line_of(v.span()));
        let bad = |found: &str| {
            cx.err(
                line,
                &field,
                format!("{expected}, found {}", excerpt(found)),
            )
        };
        let toml::Value::Array(items) = v.get_ref() else {
            return Err(bad(&v.get_ref().to_string()));
        };
        if items.len() != 3 {
            return Err(bad(&format!("{} values", items.len())));
        }
        let mut p = Vector3::zeros();
        for (c, item) in items.iter().enumerate() {
            let x = match item {
                toml::Value::Float(x) => *x,
                toml::Value::Integer(i) => *i as f64,
                other => return Err(bad(&format!("{other}"))),
            };
            if !x.is_finite() {
                return Err(bad(&format!("{x}")));
            }
            p[c] = length.to_mm(x);
        }
        names.push(name);
        reflectors_mm.push(p);
    }
    if let Err(message) = super::validate::nominal_triangle(&reflectors_mm, length) {
        return Err(cx.err(refl_line, "reflectors", message));
    }
    Ok((names, reflectors_mm))
}

/// `base_link` and `tip_link` of an `[[arms]]` entry: both or neither, non-empty.
fn parse_links(
    cx: &ManifestCtx,
    line: usize,
    base: Option<Spanned<String>>,
    tip: Option<Spanned<String>>,
) -> Result<Option<ArmLinks>, DatasetError> {
    let check = |v: &Spanned<String>, field: &str| {
        if v.get_ref().trim().is_empty() {
            Err(cx.err(Some(cx.line_of(v.span())), field, "empty link name"))
        } else {
            Ok(v.get_ref().trim().to_string())
        }
    };
    match (base, tip) {
        (None, None) => Ok(None),
        (Some(b), Some(t)) => Ok(Some(ArmLinks::new(
            check(&b, "arms.base_link")?,
            check(&t, "arms.tip_link")?,
        ))),
        (Some(_), None) => Err(cx.err(
            Some(line),
            "arms.tip_link",
            "missing; base_link and tip_link go together (the arm's chain from base_link to tip_link)",
        )),
        (None, Some(_)) => Err(cx.err(
            Some(line),
            "arms.base_link",
            "missing; base_link and tip_link go together (the arm's chain from base_link to tip_link)",
        )),
    }
}

/// `[[arms]]`: one entry per measured arm — both, or one alone — with its `name` (`left`/`right`), CSV
/// `file` and optionally its chain (`base_link`, `tip_link`), station and own reflector coordinates.
fn parse_arms(
    cx: &ManifestCtx,
    dir: &Path,
    arms: Vec<Spanned<RawArm>>,
    names: &[String],
    length: LengthUnit,
) -> Result<PerSide<Option<ManifestArm>>, DatasetError> {
    let mut files: PerSide<Option<ManifestArm>> = PerSide::default();
    let mut arm_lines: PerSide<usize> = PerSide::default();
    let mut station_lines: PerSide<usize> = PerSide::default();
    for arm in arms {
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
        let side = match name.get_ref().as_str() {
            "left" => Side::Left,
            "right" => Side::Right,
            other => {
                return Err(cx.err(
                    Some(name_line),
                    "arms.name",
                    format!(
                        "unknown arm \"{}\"; expected \"left\" or \"right\"",
                        excerpt(other)
                    ),
                ));
            }
        };
        if files[side].is_some() {
            return Err(cx.err(
                Some(name_line),
                "arms.name",
                format!(
                    "duplicate arm \"{}\" (already listed on line {})",
                    name.get_ref(),
                    arm_lines[side]
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
        let path = super::validate::data_file_in(dir, file.get_ref())
            .map_err(|message| cx.err(Some(cx.line_of(file.span())), "arms.file", message))?;
        let links = parse_links(cx, line, arm.base_link, arm.tip_link)?;
        let station = match arm.station {
            None => None,
            Some(s) => {
                station_lines[side] = cx.line_of(s.span());
                Some(parse_station(cx, &s)?)
            }
        };
        let reflectors_mm = match arm.reflectors {
            None => None,
            Some(r) => Some(parse_arm_reflectors(cx, side, r, names, length)?),
        };
        files[side] = Some(ManifestArm {
            file: path,
            links,
            station,
            reflectors_mm,
        });
        arm_lines[side] = name_line;
    }
    if files.values().all(Option::is_none) {
        return Err(cx.err(
            None,
            "arms",
            "no [[arms]] entry; expected one with name = \"left\" and/or one with name = \"right\" \
             (both arms, or the one arm measured)",
        ));
    }
    check_stations(cx, &files, &station_lines)?;
    Ok(files)
}

/// `[[arms]] station`: the name of the tracker station (1 to 255 characters, one line).
fn parse_station(cx: &ManifestCtx, s: &Spanned<String>) -> Result<String, DatasetError> {
    let text = s.get_ref().trim();
    if text.is_empty() || text.len() > 255 || text.chars().any(char::is_control) {
        return Err(cx.err(
            Some(cx.line_of(s.span())),
            "arms.station",
            "expected the name of the tracker station (1 to 255 characters, one line)",
        ));
    }
    Ok(text.to_string())
}

/// `[[arms]] reflectors`: an arm's own coordinates of the dataset's reflectors (the same names), in
/// the dataset's order (the CSV's columns).
fn parse_arm_reflectors(
    cx: &ManifestCtx,
    side: Side,
    r: Spanned<RawReflectors>,
    names: &[String],
    length: LengthUnit,
) -> Result<Vec<Vector3<f64>>, DatasetError> {
    let line = Some(cx.line_of(r.span()));
    let (own, coords) = parse_reflectors(cx, Some(r), length)?;
    let mut ordered = Vec::with_capacity(names.len());
    for name in names {
        let Some(k) = own.iter().position(|n| n == name) else {
            return Err(cx.err(
                line,
                "arms.reflectors",
                format!(
                    "the {side} arm's reflectors name {} but [reflectors] names {}: an arm's own \
                     coordinates are for the dataset's reflectors (the same names; the CSV columns \
                     are theirs)",
                    own.join(", "),
                    names.join(", ")
                ),
            ));
        };
        ordered.push(coords[k]);
    }
    if own.len() != names.len() {
        return Err(cx.err(
            line,
            "arms.reflectors",
            format!(
                "the {side} arm's reflectors name {} but [reflectors] names {}",
                own.join(", "),
                names.join(", ")
            ),
        ));
    }
    Ok(ordered)
}

/// Stations: on both arms or on neither (one station, as files without the key). An arm measured
/// alone may name its station.
fn check_stations(
    cx: &ManifestCtx,
    files: &PerSide<Option<ManifestArm>>,
    station_lines: &PerSide<usize>,
) -> Result<(), DatasetError> {
    for side in Side::BOTH {
        let other = side.other();
        if let (Some(a), Some(b)) = (&files[side], &files[other])
            && a.station.is_some()
            && b.station.is_none()
        {
            return Err(cx.err(
                Some(station_lines[side]),
                "arms.station",
                format!(
                    "the {side} arm names a tracker station, the {other} arm none; name both arms' \
                     stations (the same name when one station measured both) or neither"
                ),
            ));
        }
    }
    Ok(())
}
