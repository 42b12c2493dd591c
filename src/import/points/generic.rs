//! Any CSV/TXT with a column mapping ([`ColumnMap`]): plain cells, elements of vector and matrix cells
//! as numpy and pandas print them (a quoted cell may span lines), and joints computed from others.

use super::cells;
use super::mapping::{CellRef, ColumnMap, ColumnRef, ColumnRole, Formula, Source};
use super::*;
use std::collections::HashMap;

/// A mapped cell with its column resolved (0-based) and named as the header (or the mapping) does.
#[derive(Clone, Debug)]
struct Cell {
    col: usize,
    index: Vec<usize>,
    /// The column as messages name it: its header name, else its number.
    label: String,
}

/// A role's value: a cell, or a formula's terms (in the file's units).
#[derive(Clone, Debug)]
enum Value {
    Cell(Cell),
    Formula {
        terms: Vec<(f64, Cell)>,
        constant: f64,
    },
}

/// The mapping resolved against the file's header.
struct Plan {
    roles: Vec<(ColumnRole, Value)>,
    /// Fields a row must have.
    needed: usize,
    joints: usize,
    per_point: bool,
}

/// What the rows are read with.
struct Reader<'a> {
    path: &'a Path,
    plan: Plan,
    unit: PointUnit,
    decimal_comma: bool,
    angle_unit: AngleUnit,
}

fn is_comment(line: &str) -> bool {
    line.starts_with('#') || line.starts_with("//")
}

pub(super) fn read_generic(
    path: &Path,
    text: &str,
    map: &ColumnMap,
    o: &ReadOptions,
) -> Result<PointFile, ImportError> {
    check_map(map, o)?;
    let no_rows = || ImportError::Format {
        path: path.to_path_buf(),
        message: "no rows".to_string(),
    };
    let (_, first) = lines(text)
        .find(|(_, t)| !is_comment(t))
        .ok_or_else(no_rows)?;
    let delimiter = Delimiter::of_line(first, o.decimal_comma);
    let dc = o.decimal_comma || delimiter.allows_decimal_comma();
    let records = text::records(text, delimiter, is_comment)
        .map_err(|q| open_quote(path, q, &text::split(first, delimiter)))?;
    let first = records.first().ok_or_else(no_rows)?;
    let (header, rows): (Vec<String>, &[text::Record]) = if has_header(map, &first.fields, dc) {
        let names = first.fields.iter().map(|f| text::name_and_unit(f).0);
        (names.collect(), &records[1..])
    } else {
        (Vec::new(), &records[..])
    };
    let reader = Reader {
        path,
        plan: Plan::new(path, first.line, map, &header)?,
        unit: o.unit.unwrap_or_default(),
        decimal_comma: dc,
        angle_unit: o.angle_unit,
    };
    let table = if reader.plan.per_point {
        PointTable::Points(
            rows.iter()
                .map(|r| reader.point(r))
                .collect::<Result<_, _>>()?,
        )
    } else {
        let names = o.reflector_names;
        PointTable::Rows(
            rows.iter()
                .map(|r| reader.config_row(r, names))
                .collect::<Result<_, _>>()?,
        )
    };
    Ok(PointFile {
        format: PointsFormat::Generic,
        unit: reader.unit,
        frame: None,
        table,
        notes: Vec::new(),
    })
}

/// The mapping against the import's options: a point per row maps no joints, ids or splits; the
/// reflectors mapped are the dataset's, each with x, y and z.
fn check_map(map: &ColumnMap, o: &ReadOptions) -> Result<(), ImportError> {
    let per_point = map
        .entries
        .iter()
        .any(|(r, _)| matches!(r, ColumnRole::Axis(_)));
    for (r, _) in &map.entries {
        if per_point && matches!(r, ColumnRole::Joint(_) | ColumnRole::Split | ColumnRole::Id) {
            return Err(ImportError::Options(format!(
                "`{}` in a mapping of one point per row: joints, ids and splits belong to the \
                 joint log (or map REFLECTOR.x/.y/.z for one configuration per row)",
                r.name()
            )));
        }
        if let ColumnRole::ReflectorAxis(name, _) = r
            && !o.reflector_names.contains(name)
        {
            return Err(ImportError::Options(format!(
                "the column mapping names reflector `{name}`; the dataset's reflectors are {}",
                o.reflector_names.join(", ")
            )));
        }
    }
    let wanted: Vec<ColumnRole> = if per_point {
        (0..3).map(ColumnRole::Axis).collect()
    } else {
        let names = o.reflector_names.iter();
        names
            .flat_map(|n| (0..3).map(|a| ColumnRole::ReflectorAxis(n.clone(), a)))
            .collect()
    };
    for r in wanted {
        if map.get(&r).is_none() {
            let reflectors = if per_point {
                String::new()
            } else {
                format!(
                    " (the dataset's reflectors: {})",
                    o.reflector_names.join(", ")
                )
            };
            return Err(ImportError::Options(format!(
                "the column mapping has no {}{reflectors}",
                r.name()
            )));
        }
    }
    let n = map.joint_count();
    if let Some(k) = (1..=n).find(|&k| map.get(&ColumnRole::Joint(k)).is_none()) {
        return Err(ImportError::Options(format!(
            "the column mapping has q{n} but no q{k}"
        )));
    }
    Ok(())
}

/// A quote opened and never closed: the record's first line and the column (named by the first
/// line, the header where there is one).
fn open_quote(path: &Path, q: text::OpenQuote, first: &[String]) -> ImportError {
    let name = first
        .get(q.field)
        .map(|f| text::name_and_unit(f).0)
        .filter(|n| !n.is_empty() && !n.starts_with('"'));
    ImportError::Cell {
        path: path.to_path_buf(),
        line: q.line,
        field: name.unwrap_or_else(|| (q.field + 1).to_string()),
        message: "a quote (`\"`) opened in this record is not closed before the end of the file"
            .to_string(),
    }
}

/// The cells a source reads.
fn cells_of(source: &Source) -> Vec<&CellRef> {
    match source {
        Source::Cell(c) => vec![c],
        Source::Formula(f) => f.terms.iter().map(|(_, c)| c).collect(),
    }
}

/// Is the first record a header line? When the mapping names a column, or when a mapped numbered
/// coordinate is no number there (or a mapped numbered vector cell no vector).
fn has_header(map: &ColumnMap, first: &[String], decimal_comma: bool) -> bool {
    let cells = || {
        map.entries
            .iter()
            .flat_map(|(r, s)| cells_of(s).into_iter().map(move |c| (r, c)))
    };
    if cells().any(|(_, c)| matches!(c.column, ColumnRef::Name(_))) {
        return true;
    }
    cells().any(|(r, c)| {
        let ColumnRef::Number(n) = c.column else {
            return false;
        };
        let f = n
            .checked_sub(1)
            .and_then(|k| first.get(k))
            .map(String::as_str);
        if !c.index.is_empty() {
            return f.is_none_or(|f| !cells::is_array(f));
        }
        matches!(r, ColumnRole::Axis(_) | ColumnRole::ReflectorAxis(..))
            && f.is_none_or(|f| text::number(f, decimal_comma).is_none())
    })
}

impl Plan {
    fn new(
        path: &Path,
        header_line: usize,
        map: &ColumnMap,
        header: &[String],
    ) -> Result<Plan, ImportError> {
        let find = |name: &str| {
            header
                .iter()
                .position(|h| h == name)
                .or_else(|| header.iter().position(|h| h.eq_ignore_ascii_case(name)))
        };
        let resolve = |c: &CellRef| -> Result<Cell, ImportError> {
            let col = match &c.column {
                ColumnRef::Number(n) => n.checked_sub(1).ok_or_else(|| {
                    ImportError::Options("columns are counted from 1".to_string())
                })?,
                ColumnRef::Name(name) => find(name).ok_or_else(|| ImportError::Header {
                    path: path.to_path_buf(),
                    line: header_line,
                    field: name.clone(),
                    message: format!(
                        "no such column (the mapping names it); the header has: {}",
                        crate::textfile::excerpt(&header.join(", "))
                    ),
                })?,
            };
            let label = match header.get(col) {
                Some(h) if !h.is_empty() => h.clone(),
                _ => (col + 1).to_string(),
            };
            Ok(Cell {
                col,
                index: c.index.clone(),
                label,
            })
        };
        let mut roles = Vec::new();
        for (role, source) in &map.entries {
            let value = match source {
                // A header name with `+`, `-` or `*` in it is that column, not a formula.
                Source::Formula(Formula { text, .. }) if find(text.trim()).is_some() => {
                    Value::Cell(resolve(&CellRef {
                        column: ColumnRef::Name(text.trim().to_string()),
                        index: Vec::new(),
                    })?)
                }
                Source::Formula(f) => Value::Formula {
                    terms: f
                        .terms
                        .iter()
                        .map(|(k, c)| Ok((*k, resolve(c)?)))
                        .collect::<Result<_, ImportError>>()?,
                    constant: f.constant,
                },
                Source::Cell(c) => Value::Cell(resolve(c)?),
            };
            roles.push((role.clone(), value));
        }
        let needed = roles
            .iter()
            .flat_map(|(_, v)| match v {
                Value::Cell(c) => vec![c.col],
                Value::Formula { terms, .. } => terms.iter().map(|(_, c)| c.col).collect(),
            })
            .max()
            .map_or(0, |c| c + 1);
        Ok(Plan {
            per_point: roles.iter().any(|(r, _)| matches!(r, ColumnRole::Axis(_))),
            joints: map.joint_count(),
            roles,
            needed,
        })
    }

    fn get(&self, role: &ColumnRole) -> Option<&Value> {
        self.roles.iter().find(|(r, _)| r == role).map(|(_, v)| v)
    }
}

/// One record's fields, with its vector and matrix cells parsed once.
struct Row<'r> {
    line: usize,
    fields: &'r [String],
    arrays: HashMap<usize, cells::Array>,
}

impl Reader<'_> {
    fn field<'f>(&self, row: &Row<'f>, col: usize) -> Result<&'f str, ImportError> {
        field(self.path, row.line, row.fields, col, self.plan.needed)
    }

    fn cell_error(&self, row: &Row, cell: &Cell, message: String) -> ImportError {
        ImportError::Cell {
            path: self.path.to_path_buf(),
            line: row.line,
            field: cell.label.clone(),
            message,
        }
    }

    /// A cell's number (a plain cell's, or a vector's or matrix's element), in the file's unit;
    /// `expected` says what a plain cell should hold.
    fn number(
        &self,
        row: &mut Row,
        cell: &Cell,
        role: &ColumnRole,
        expected: &dyn Fn() -> String,
    ) -> Result<f64, ImportError> {
        let f = self.field(row, cell.col)?;
        if cell.index.is_empty() {
            if cells::is_array(f) {
                let message = format!(
                    "`{}` is a vector or matrix cell: map one of its elements for {}, e.g. {}[0]",
                    crate::textfile::excerpt(f),
                    role.name(),
                    cell.label
                );
                return Err(self.cell_error(row, cell, message));
            }
            return text::number(f, self.decimal_comma).ok_or_else(|| ImportError::Field {
                path: self.path.to_path_buf(),
                line: row.line,
                field: role.name(),
                expected: expected(),
                found: crate::textfile::excerpt(f),
            });
        }
        let at = |message: String| {
            let index: String = cell.index.iter().map(|i| format!("[{i}]")).collect();
            format!("{}{index} (for {}): {message}", cell.label, role.name())
        };
        if !row.arrays.contains_key(&cell.col) {
            let array = cells::parse(f).map_err(|e| self.cell_error(row, cell, at(e)))?;
            row.arrays.insert(cell.col, array);
        }
        row.arrays[&cell.col]
            .element(&cell.index)
            .map_err(|e| self.cell_error(row, cell, at(e)))
    }

    /// A role's number: its cell's, or its formula's value.
    fn value(
        &self,
        row: &mut Row,
        role: &ColumnRole,
        expected: &dyn Fn() -> String,
    ) -> Result<f64, ImportError> {
        match self.plan.get(role) {
            Some(Value::Cell(c)) => self.number(row, c, role, expected),
            Some(Value::Formula { terms, constant }) => {
                let mut sum = *constant;
                for (k, c) in terms {
                    sum += k * self.number(row, c, role, expected)?;
                }
                Ok(sum)
            }
            None => Err(ImportError::Options(format!(
                "the column mapping has no {}",
                role.name()
            ))),
        }
    }

    /// A text role's cell (`None` when it is not mapped); an empty cell is refused.
    fn text(&self, row: &Row, role: &ColumnRole) -> Result<Option<String>, ImportError> {
        let Some(Value::Cell(c)) = self.plan.get(role) else {
            return Ok(None);
        };
        let f = self.field(row, c.col)?;
        if f.is_empty() {
            return Err(ImportError::Field {
                path: self.path.to_path_buf(),
                line: row.line,
                field: role.name(),
                expected: "a name".to_string(),
                found: String::new(),
            });
        }
        Ok(Some(f.to_string()))
    }

    fn time(&self, row: &Row) -> Result<Option<f64>, ImportError> {
        let col = match self.plan.get(&ColumnRole::Time) {
            Some(Value::Cell(c)) => Some(c.col),
            _ => None,
        };
        time_field(self.path, row.line, row.fields, col, "time")
    }

    fn position_mm(
        &self,
        row: &mut Row,
        axes: [ColumnRole; 3],
    ) -> Result<Vector3<f64>, ImportError> {
        let expected = || format!("a number in {}", self.unit.name());
        let mut p = Vector3::zeros();
        for (a, r) in axes.iter().enumerate() {
            p[a] = self.unit.to_mm(self.value(row, r, &expected)?);
        }
        Ok(p)
    }

    fn point(&self, record: &text::Record) -> Result<Point, ImportError> {
        let mut row = self.row(record);
        Ok(Point {
            target: self.text(&row, &ColumnRole::Target)?,
            position_mm: self.position_mm(&mut row, [0, 1, 2].map(ColumnRole::Axis))?,
            time_s: self.time(&row)?,
            line: row.line,
        })
    }

    fn row<'r>(&self, record: &'r text::Record) -> Row<'r> {
        Row {
            line: record.line,
            fields: &record.fields,
            arrays: HashMap::new(),
        }
    }

    fn config_row(
        &self,
        record: &text::Record,
        reflectors: &[String],
    ) -> Result<ConfigRow, ImportError> {
        let mut row = self.row(record);
        let time_s = self.time(&row)?;
        let mut points_mm = Vec::with_capacity(reflectors.len());
        for name in reflectors {
            let axes = [0, 1, 2].map(|a| ColumnRole::ReflectorAxis(name.clone(), a));
            points_mm.push(self.position_mm(&mut row, axes)?);
        }
        let q_rad = if self.plan.joints == 0 {
            None
        } else {
            let expected = || format!("a joint value in {}", self.angle_unit.name());
            let q = (1..=self.plan.joints)
                .map(|k| self.value(&mut row, &ColumnRole::Joint(k), &expected))
                .map(|v| v.map(|v| self.angle_unit.to_rad(v)));
            Some(q.collect::<Result<Vec<f64>, _>>()?)
        };
        let split = match self.text(&row, &ColumnRole::Split)? {
            None => None,
            Some(s) => Some(parse_split(self.path, row.line, &s)?),
        };
        Ok(ConfigRow {
            id: self.text(&row, &ColumnRole::Id)?,
            points_mm,
            q_rad,
            time_s,
            split,
            line: row.line,
        })
    }
}
