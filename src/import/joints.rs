//! Joint logs: a controller's or ROS's joint values per configuration, `id,q1,…,qN` (with an optional
//! header, time stamp and split column), in chain order or reordered by a mapping or by joint names.

use super::error::ImportError;
use super::points::parse_split;
use super::text::{self, Delimiter};
use crate::dataset::{AngleUnit, Split};
use std::path::Path;

/// One configuration of a joint log.
#[derive(Clone, Debug, PartialEq)]
pub struct JointRow {
    pub id: String,
    /// Chain order, rad.
    pub q_rad: Vec<f64>,
    pub time_s: Option<f64>,
    /// A still interval of a ROS 2 bag (tracker clock, s): a shot within it is at distance 0.
    pub span_s: Option<(f64, f64)>,
    pub split: Option<Split>,
    /// 1-based line in the file (a bag's: the number of the interval's first message on its topic).
    pub line: usize,
}

impl JointRow {
    /// How far time `t` (s) is from this configuration: from its time span (0 within it), else from
    /// its time stamp.
    pub fn time_distance_s(&self, t: f64) -> Option<f64> {
        match self.span_s {
            Some((a, b)) => Some((a - t).max(t - b).max(0.0)),
            None => self.time_s.map(|s| (s - t).abs()),
        }
    }
}

/// A joint log read.
#[derive(Clone, Debug, PartialEq)]
pub struct JointLog {
    pub rows: Vec<JointRow>,
    pub angle_unit: AngleUnit,
    /// How the file's columns became chain order.
    pub order: String,
    pub notes: Vec<String>,
}

/// What the joint-log reader is told.
#[derive(Clone, Debug, Default)]
pub struct JointLogOptions<'a> {
    /// The unit of the joint values; `None`: the header's (`q1 [deg]`), else degrees.
    pub angle_unit: Option<AngleUnit>,
    /// Chain joint `k` is the file's joint column `order[k]` (1-based): the YuMi's ABB axes 1, 2, 7, 3,
    /// 4, 5, 6 in a log of axes 1…7 is `[1, 2, 7, 3, 4, 5, 6]`.
    pub joint_order: Option<&'a [usize]>,
    /// The arm's joints in chain order (their count is checked; a header naming them reorders).
    pub joint_names: Option<&'a [String]>,
    pub decimal_comma: bool,
    /// Ids of a log without an id column: this prefix and the row's number (`L001`).
    pub id_prefix: &'a str,
}

/// The YuMi's joint order: a log of ABB axes 1…7 in chain order.
pub const YUMI_ABB_ORDER: [usize; 7] = [1, 2, 7, 3, 4, 5, 6];

/// Parse a joint-order mapping: `1,2,7,3,4,5,6` or `yumi-abb`.
pub fn parse_joint_order(s: &str) -> Result<Vec<usize>, String> {
    if matches!(
        s.trim().to_lowercase().as_str(),
        "yumi-abb" | "abb-yumi" | "yumi"
    ) {
        return Ok(YUMI_ABB_ORDER.to_vec());
    }
    let order: Vec<usize> = s
        .split(',')
        .map(|x| {
            x.trim()
                .parse::<usize>()
                .map_err(|_| format!("`{}`: expected a column number", x.trim()))
        })
        .collect::<Result<_, _>>()?;
    let mut sorted = order.clone();
    sorted.sort_unstable();
    if sorted != (1..=order.len()).collect::<Vec<_>>() {
        return Err(format!(
            "`{s}`: expected each of the numbers 1…{} once (chain joint k is the log's joint column \
             given k-th)",
            order.len()
        ));
    }
    Ok(order)
}

fn is_id_name(n: &str) -> bool {
    matches!(
        n.to_lowercase().as_str(),
        "id" | "name" | "target" | "config" | "configuration" | "pose"
    )
}

/// A joint column's name: `j1`, `q1`, `A1`, `axis 1`, `joint 1` (any case, a space or `_` before the
/// number or not), or one of the arm's joint names.
pub fn is_joint_name(n: &str, joint_names: Option<&[String]>) -> bool {
    if joint_names.is_some_and(|j| j.iter().any(|name| name == n)) {
        return true;
    }
    let lower = n.to_lowercase();
    let digits = lower.trim_start_matches(|c: char| c.is_ascii_alphabetic());
    let prefix = lower[..lower.len() - digits.len()].to_string();
    let digits = digits.trim_start_matches([' ', '_']);
    matches!(prefix.as_str(), "j" | "q" | "a" | "axis" | "joint")
        && !digits.is_empty()
        && digits.chars().all(|c| c.is_ascii_digit())
}

fn is_time_name(n: &str) -> bool {
    matches!(
        n.to_lowercase().as_str(),
        "time" | "timestamp" | "time stamp" | "time_stamp" | "stamp" | "t" | "time_s" | "date time"
    )
}

/// A joint log's header: the columns' names and units, and which are the id, time, split and joint
/// columns.
struct Header {
    names: Vec<String>,
    units: Vec<Option<String>>,
    id_col: Option<usize>,
    time_col: Option<usize>,
    split_col: Option<usize>,
    /// The joint columns, in the file's order.
    file_joints: Vec<usize>,
    /// The first row's line; the header's (0 without a header line).
    first_line: usize,
    header_line: usize,
    named: bool,
}

impl Header {
    /// The header of a log whose first row is `first` (line `first_line`): a header line when any
    /// field after the first is no number and no time stamp, else `id,q1,…` made up.
    fn of(
        path: &Path,
        first_line: usize,
        first_fields: &[String],
        dc: bool,
        joint_names: Option<&[String]>,
    ) -> Result<Self, ImportError> {
        let named = first_fields.len() < 2
            || first_fields[1..]
                .iter()
                .any(|f| text::number(f, dc).is_none() && text::time_s(f).is_none());
        let (names, units): (Vec<String>, Vec<Option<String>>) = if named {
            first_fields.iter().map(|f| text::name_and_unit(f)).unzip()
        } else {
            let n = first_fields.len();
            let mut names = vec!["id".to_string()];
            names.extend((1..n).map(|k| format!("q{k}")));
            (names, vec![None; n])
        };
        // The first column is the ids unless it is named as a time, split or joint column.
        let id_col = names
            .iter()
            .position(|n| is_id_name(n))
            .or((!is_time_name(&names[0])
                && names[0] != "split"
                && !(named && is_joint_name(&names[0], joint_names)))
            .then_some(0));
        let time_col = names.iter().position(|n| is_time_name(n));
        let split_col = names.iter().position(|n| n.eq_ignore_ascii_case("split"));
        let file_joints: Vec<usize> = (0..names.len())
            .filter(|&k| Some(k) != id_col && Some(k) != time_col && Some(k) != split_col)
            .filter(|&k| !names[k].is_empty())
            .collect();
        if file_joints.is_empty() {
            return Err(ImportError::Header {
                path: path.to_path_buf(),
                line: first_line,
                field: "q1".to_string(),
                message: "no joint columns: expected `id,q1,…,qN`".to_string(),
            });
        }
        Ok(Self {
            names,
            units,
            id_col,
            time_col,
            split_col,
            file_joints,
            first_line,
            header_line: if named { first_line } else { 0 },
            named,
        })
    }

    fn header_error(&self, path: &Path, line: usize, field: usize, message: String) -> ImportError {
        ImportError::Header {
            path: path.to_path_buf(),
            line,
            field: self.names[field].clone(),
            message,
        }
    }

    /// The columns of the chain's joints, in chain order, and how they were found: the mapping, the
    /// header's joint names, or the file's order. The arm's joint count is checked.
    fn chain_columns(
        &self,
        path: &Path,
        o: &JointLogOptions,
    ) -> Result<(Vec<usize>, String), ImportError> {
        let (names, file_joints) = (&self.names, &self.file_joints);
        let n = file_joints.len();
        let found = if let Some(order) = o.joint_order {
            if order.len() != n {
                return Err(self.header_error(
                    path,
                    self.first_line,
                    file_joints[0],
                    format!(
                        "{n} joint columns, the joint-order mapping has {} entries",
                        order.len()
                    ),
                ));
            }
            let cols = order.iter().map(|&k| file_joints[k - 1]).collect();
            let list: Vec<String> = order.iter().map(usize::to_string).collect();
            (
                cols,
                format!("the log's joint columns {} in chain order", list.join(", ")),
            )
        } else if let Some(joints) = o.joint_names.filter(|j| {
            self.named
                && j.len() == n
                && j.iter()
                    .all(|name| file_joints.iter().any(|&k| &names[k] == name))
        }) {
            let cols = joints
                .iter()
                .map(|name| {
                    file_joints
                        .iter()
                        .copied()
                        .find(|&k| &names[k] == name)
                        .unwrap_or(0)
                })
                .collect();
            (cols, "by the header's joint names".to_string())
        } else {
            (
                file_joints.clone(),
                "the file's order (chain order)".to_string(),
            )
        };
        if let Some(joints) = o.joint_names
            && joints.len() != n
        {
            return Err(self.header_error(
                path,
                self.first_line,
                file_joints[joints.len().min(n - 1)],
                format!(
                    "{n} joint columns, the arm has {} joints ({})",
                    joints.len(),
                    joints.join(", ")
                ),
            ));
        }
        Ok(found)
    }

    /// The unit of the joint values: the option, else the joint columns' brackets, else degrees (with
    /// a note).
    fn angle_unit(
        &self,
        path: &Path,
        o: &JointLogOptions,
        notes: &mut Vec<String>,
    ) -> Result<AngleUnit, ImportError> {
        if let Some(u) = o.angle_unit {
            return Ok(u);
        }
        let header_units: Vec<AngleUnit> = self
            .file_joints
            .iter()
            .filter_map(|&k| self.units[k].as_deref())
            .filter_map(|u| match u.to_lowercase().as_str() {
                "deg" | "°" | "degree" | "degrees" => Some(AngleUnit::Deg),
                "rad" | "radian" | "radians" => Some(AngleUnit::Rad),
                _ => None,
            })
            .collect();
        match header_units.first() {
            Some(&u) if header_units.iter().all(|&v| v == u) => Ok(u),
            Some(_) => Err(self.header_error(
                path,
                self.header_line,
                self.file_joints[0],
                "joint columns in different units".to_string(),
            )),
            None => {
                notes.push("no angle unit given or in the header: read as degrees".to_string());
                Ok(AngleUnit::Deg)
            }
        }
    }

    /// The number of fields a row needs: up to the last column read.
    fn needed_fields(&self, cols: &[usize]) -> usize {
        self.names.len().min(
            [self.id_col, self.time_col, self.split_col]
                .into_iter()
                .flatten()
                .chain(cols.iter().copied())
                .max()
                .unwrap_or(0)
                + 1,
        )
    }
}

/// What reading a row needs besides the header.
struct RowFormat<'a> {
    path: &'a Path,
    header: &'a Header,
    /// The chain's joint columns, in chain order.
    cols: &'a [usize],
    angle_unit: AngleUnit,
    dc: bool,
    needed: usize,
    id_prefix: &'a str,
}

impl RowFormat<'_> {
    /// Row `fields` (line `line`; `index` rows before it; `seen`: the ids so far and their lines).
    fn row(
        &self,
        line: usize,
        fields: &[String],
        index: usize,
        seen: &mut std::collections::HashMap<String, usize>,
    ) -> Result<JointRow, ImportError> {
        let (path, h) = (self.path, self.header);
        let field_error = |k: usize, expected: String, found: &str| ImportError::Field {
            path: path.to_path_buf(),
            line,
            field: h.names[k].clone(),
            expected,
            found: crate::textfile::excerpt(found),
        };
        if fields.len() < self.needed {
            return Err(ImportError::FieldCount {
                path: path.to_path_buf(),
                line,
                expected: self.needed,
                found: fields.len(),
            });
        }
        let id = match h.id_col {
            Some(k) => fields[k].clone(),
            None => format!("{}{:03}", self.id_prefix, index + 1),
        };
        if id.is_empty() {
            return Err(field_error(
                h.id_col.unwrap_or(0),
                "a configuration id".to_string(),
                "",
            ));
        }
        if let Some(first_line) = seen.insert(id.clone(), line) {
            return Err(ImportError::DuplicateId {
                path: path.to_path_buf(),
                line,
                id,
                first_line,
            });
        }
        let q_rad = self
            .cols
            .iter()
            .map(|&k| {
                text::number(&fields[k], self.dc)
                    .map(|v| self.angle_unit.to_rad(v))
                    .ok_or_else(|| {
                        field_error(
                            k,
                            format!("a joint value in {}", self.angle_unit.name()),
                            &fields[k],
                        )
                    })
            })
            .collect::<Result<Vec<f64>, ImportError>>()?;
        let time_s = match h.time_col {
            Some(k) if !fields[k].is_empty() => {
                Some(text::time_s(&fields[k]).ok_or_else(|| {
                    field_error(
                        k,
                        "a time stamp (`11.10.2022 15:06:48.043`, `2022-10-11T15:06:48.043` or \
                     seconds)"
                            .to_string(),
                        &fields[k],
                    )
                })?)
            }
            _ => None,
        };
        let split = match h.split_col {
            Some(k) if !fields[k].is_empty() => Some(parse_split(path, line, &fields[k])?),
            _ => None,
        };
        Ok(JointRow {
            id,
            q_rad,
            time_s,
            span_s: None,
            split,
            line,
        })
    }
}

/// Read a joint log's text.
pub fn read(path: &Path, text: &str, o: &JointLogOptions) -> Result<JointLog, ImportError> {
    let lines: Vec<(usize, &str)> = text
        .lines()
        .enumerate()
        .map(|(i, l)| (i + 1, l.trim()))
        .filter(|(_, l)| !l.is_empty() && !l.starts_with('#') && !l.starts_with("//"))
        .collect();
    let Some(&(_, first)) = lines.first() else {
        return Err(ImportError::Format {
            path: path.to_path_buf(),
            message: "no rows: expected `id,q1,…,qN`".to_string(),
        });
    };
    let delimiter = Delimiter::of_line(first, o.decimal_comma);
    let dc = o.decimal_comma || delimiter.allows_decimal_comma();
    let rows = lines
        .iter()
        .map(|&(line, t)| (line, text::split(t, delimiter)))
        .collect::<Vec<_>>();
    let mut log = read_rows(path, &rows, dc, o)?;
    log.notes.insert(
        0,
        format!(
            "separator: {} (recognised from the first row)",
            delimiter.name()
        ),
    );
    Ok(log)
}

/// Read a joint log's rows (line, fields): a header row or not, then one configuration per row.
pub(super) fn read_rows(
    path: &Path,
    rows: &[(usize, Vec<String>)],
    dc: bool,
    o: &JointLogOptions,
) -> Result<JointLog, ImportError> {
    let Some((first_line, first)) = rows.first() else {
        return Err(ImportError::Format {
            path: path.to_path_buf(),
            message: "no rows: expected `id,q1,…,qN`".to_string(),
        });
    };
    let header = Header::of(path, *first_line, first, dc, o.joint_names)?;
    let it = rows.iter().skip(usize::from(header.named));
    let mut notes = Vec::new();
    let (cols, order) = header.chain_columns(path, o)?;
    let angle_unit = header.angle_unit(path, o, &mut notes)?;
    let format = RowFormat {
        path,
        header: &header,
        cols: &cols,
        angle_unit,
        dc,
        needed: header.needed_fields(&cols),
        id_prefix: o.id_prefix,
    };
    let mut out: Vec<JointRow> = Vec::new();
    let mut seen = std::collections::HashMap::new();
    for (line, fields) in it {
        out.push(format.row(*line, fields, out.len(), &mut seen)?);
    }
    Ok(JointLog {
        rows: out,
        angle_unit,
        order,
        notes,
    })
}
