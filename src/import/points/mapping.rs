//! The generic format's column mapping (`--columns`, `--left-columns`, `--right-columns`): which
//! column — or which element of a vector or matrix cell, or which linear combination of them — holds
//! each value. The grammar is in docs/formats.md ("Generic CSV/TXT"); [`ColumnMap::parse`] refuses a
//! mapping it cannot read with a message that says what was expected.

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

impl ColumnRole {
    /// The role as the mapping writes it (`q3`, `a.x`).
    pub fn name(&self) -> String {
        const XYZ: [&str; 3] = ["x", "y", "z"];
        match self {
            ColumnRole::Id => "id".to_string(),
            ColumnRole::Target => "target".to_string(),
            ColumnRole::Axis(a) => XYZ[*a].to_string(),
            ColumnRole::ReflectorAxis(n, a) => format!("{n}.{}", XYZ[*a]),
            ColumnRole::Joint(k) => format!("q{k}"),
            ColumnRole::Time => "time".to_string(),
            ColumnRole::Split => "split".to_string(),
        }
    }
}

/// A column: its 1-based number or its name in the header line.
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum ColumnRef {
    Number(usize),
    Name(String),
}

impl std::fmt::Display for ColumnRef {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            ColumnRef::Number(n) => write!(f, "{n}"),
            ColumnRef::Name(s) => f.write_str(s),
        }
    }
}

/// A cell, or an element of a vector or matrix cell as numpy and pandas print them: `COL` (the
/// cell), `COL[i]` (element i of a vector, 0-based), `COL[i][j]` (element j of row i of a matrix).
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct CellRef {
    pub column: ColumnRef,
    /// No index for a plain cell; one for a vector's element; two for a matrix's.
    pub index: Vec<usize>,
}

impl std::fmt::Display for CellRef {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "{}", self.column)?;
        for i in &self.index {
            write!(f, "[{i}]")?;
        }
        Ok(())
    }
}

/// A joint value computed from others (a passive joint coupled to two leaders): the sum of
/// `coefficient · cell` over `terms`, plus `constant`, in the file's units.
#[derive(Clone, Debug, PartialEq)]
pub struct Formula {
    pub terms: Vec<(f64, CellRef)>,
    pub constant: f64,
    /// The formula as written: a header name with `+`, `-` or `*` in it is that column.
    pub text: String,
}

/// Where a role's value comes from.
#[derive(Clone, Debug, PartialEq)]
pub enum Source {
    Cell(CellRef),
    /// Joints only.
    Formula(Formula),
}

/// The generic format's mapping, written `ROLE=SOURCE,…`: `target=1,x=2,y=3,z=4` (a point per row) or
/// `id=1,a.x=2,a.y=3,a.z=4,b.x=…,q1=11,…` (a configuration per row); `q=11-17` maps a range of
/// columns to the next joints, `q=joints[10-16]` a range of a vector cell's elements, `q4=-joints[1]
/// -joints[2]` a joint computed from others; `time=COL`, `split=COL`. Columns are 1-based numbers or
/// header names, `COL[i]`/`COL[i][j]` elements of vector and matrix cells.
#[derive(Clone, Debug, PartialEq)]
pub struct ColumnMap {
    pub entries: Vec<(ColumnRole, Source)>,
}

/// A mapping error: the entry and what was expected.
type Parsed<T> = Result<T, String>;

impl ColumnMap {
    pub fn parse(spec: &str) -> Result<ColumnMap, String> {
        let mut entries: Vec<(ColumnRole, Source)> = Vec::new();
        for item in spec.split(',').map(str::trim).filter(|s| !s.is_empty()) {
            let (role, source) = item
                .split_once('=')
                .ok_or_else(|| format!("`{item}`: expected ROLE=COLUMN (e.g. x=2)"))?;
            let (role, source) = (role.trim(), source.trim());
            let err = |e: String| format!("`{item}`: {e}");
            if role.eq_ignore_ascii_case("q") {
                // Appended after the joints mapped so far.
                let first = joint_count(&entries) + 1;
                for (k, s) in joint_sources(source).map_err(err)?.into_iter().enumerate() {
                    push(&mut entries, ColumnRole::Joint(first + k), s, item)?;
                }
                continue;
            }
            let r = parse_role(role).map_err(err)?;
            let s = match r {
                ColumnRole::Joint(_) => joint_source(source),
                ColumnRole::Axis(_) | ColumnRole::ReflectorAxis(..) => {
                    cell(source).map(Source::Cell)
                }
                _ => text_cell(source).map(Source::Cell),
            };
            push(&mut entries, r, s.map_err(err)?, item)?;
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

    pub(super) fn get(&self, role: &ColumnRole) -> Option<&Source> {
        self.entries.iter().find(|(r, _)| r == role).map(|(_, c)| c)
    }

    /// The number of joints mapped (q1 … qN).
    pub fn joint_count(&self) -> usize {
        joint_count(&self.entries)
    }
}

fn joint_count(entries: &[(ColumnRole, Source)]) -> usize {
    entries
        .iter()
        .filter_map(|(r, _)| match r {
            ColumnRole::Joint(k) => Some(*k),
            _ => None,
        })
        .max()
        .unwrap_or(0)
}

fn push(
    entries: &mut Vec<(ColumnRole, Source)>,
    role: ColumnRole,
    source: Source,
    item: &str,
) -> Result<(), String> {
    if entries.iter().any(|(e, _)| *e == role) {
        return Err(format!("`{item}`: `{}` mapped twice", role.name()));
    }
    entries.push((role, source));
    Ok(())
}

fn parse_role(role: &str) -> Parsed<ColumnRole> {
    let axis = |a: &str| {
        ["x", "y", "z"]
            .iter()
            .position(|x| a.eq_ignore_ascii_case(x))
    };
    let lower = role.to_lowercase();
    Ok(match lower.as_str() {
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
                    "unknown role `{role}`: expected id, target, x, y, z, REFLECTOR.x/.y/.z, \
                     q1…qN, q=…, time or split"
                ));
            }
        }
    })
}

/// A column as written: `N` (1-based), `$N`, or a header name.
fn column(text: &str) -> Parsed<ColumnRef> {
    let t = text.trim();
    let number = |n: &str| match n.parse::<usize>() {
        Ok(0) => Err("columns are counted from 1".to_string()),
        Ok(n) => Ok(ColumnRef::Number(n)),
        Err(_) => Err(format!("`{t}`: expected a column number after `$`")),
    };
    if let Some(n) = t.strip_prefix('$') {
        return number(n);
    }
    if t.is_empty() {
        return Err("no column".to_string());
    }
    if t.bytes().all(|b| b.is_ascii_digit()) {
        return number(t);
    }
    Ok(ColumnRef::Name(t.to_string()))
}

/// The text of a cell reference split into the column and its bracketed indices (`joints[1-3]` is
/// (`joints`, [`1-3`])), or `None` when it has no brackets.
fn brackets(text: &str) -> Parsed<Option<(&str, Vec<&str>)>> {
    let Some(open) = text.find('[') else {
        if text.contains(']') {
            return Err(format!("`{text}`: a `]` without `[`"));
        }
        return Ok(None);
    };
    let (col, mut rest) = (&text[..open], &text[open..]);
    if col.trim().is_empty() {
        return Err(format!(
            "`{text}`: no column before `[` (write COLUMN[i], e.g. joints[0])"
        ));
    }
    let mut parts = Vec::new();
    while !rest.is_empty() {
        let inner = rest
            .strip_prefix('[')
            .and_then(|r| r.split_once(']'))
            .ok_or_else(|| {
                format!("`{text}`: expected [INDEX] after the column, e.g. joints[0]")
            })?;
        parts.push(inner.0.trim());
        rest = inner.1.trim_start();
    }
    if parts.len() > 2 {
        return Err(format!(
            "`{text}`: at most two indices (a matrix's row and element)"
        ));
    }
    Ok(Some((col, parts)))
}

fn index(text: &str, whole: &str) -> Parsed<usize> {
    text.parse::<usize>().map_err(|_| {
        format!("`{whole}`: `[{text}]` is not an index (0, 1, 2, …: elements are counted from 0)")
    })
}

/// `COL`, `COL[i]` or `COL[i][j]`.
fn cell(text: &str) -> Parsed<CellRef> {
    match brackets(text)? {
        None => Ok(CellRef {
            column: column(text)?,
            index: Vec::new(),
        }),
        Some((col, parts)) => Ok(CellRef {
            column: column(col)?,
            index: parts
                .iter()
                .map(|p| index(p, text))
                .collect::<Parsed<_>>()?,
        }),
    }
}

/// A cell of text (an id, a name, a time stamp, a split): a plain cell.
fn text_cell(text: &str) -> Parsed<CellRef> {
    let c = cell(text)?;
    if !c.index.is_empty() {
        return Err(format!(
            "`{text}`: ids, targets, times and splits are plain cells (no [index])"
        ));
    }
    Ok(c)
}

/// The joints of `q=…`, appended in order: `FIRST-LAST` (columns), `COL[i-j]` (a vector's elements i…j)
/// or one joint (a cell or a formula).
fn joint_sources(text: &str) -> Parsed<Vec<Source>> {
    let numbers = text.split_once('-').and_then(|(a, b)| {
        Some((
            a.trim().parse::<usize>().ok()?,
            b.trim().parse::<usize>().ok()?,
        ))
    });
    if let Some((a, b)) = numbers {
        if a < 1 || b < a {
            return Err("expected q=FIRST-LAST with 1 ≤ FIRST ≤ LAST (column numbers)".to_string());
        }
        return Ok((a..=b)
            .map(|c| {
                Source::Cell(CellRef {
                    column: ColumnRef::Number(c),
                    index: Vec::new(),
                })
            })
            .collect());
    }
    if let Ok(Some((col, parts))) = brackets(text)
        && let [range] = parts.as_slice()
        && let Some((a, b)) = range.split_once('-')
    {
        let (a, b) = (index(a.trim(), text)?, index(b.trim(), text)?);
        if b < a {
            return Err(format!(
                "`{text}`: the range's last element is before its first"
            ));
        }
        let column = column(col)?;
        return Ok((a..=b)
            .map(|i| {
                Source::Cell(CellRef {
                    column: column.clone(),
                    index: vec![i],
                })
            })
            .collect());
    }
    Ok(vec![joint_source(text)?])
}

/// Where `+`, `-` or `*` stand outside brackets (a formula rather than a cell).
fn has_operator(text: &str) -> bool {
    let mut depth = 0i32;
    text.chars().any(|c| {
        match c {
            '[' => depth += 1,
            ']' => depth -= 1,
            _ => {}
        }
        depth == 0 && matches!(c, '+' | '-' | '*')
    })
}

/// A joint's source: a cell, or a formula when the text has an operator.
fn joint_source(text: &str) -> Parsed<Source> {
    if has_operator(text) {
        formula(text).map(Source::Formula)
    } else {
        cell(text).map(Source::Cell)
    }
}

/// Does `term` (so far) end in a number's exponent, so that a following `+`/`-` is its sign?
fn in_exponent(term: &str) -> bool {
    let t = term.trim();
    let t = t.rsplit_once('*').map_or(t, |(_, b)| b.trim());
    t.strip_suffix(['e', 'E'])
        .is_some_and(|m| !m.is_empty() && m.parse::<f64>().is_ok() && !m.starts_with(['+', '-']))
}

/// `[±] TERM {± TERM}`, a term `NUMBER`, `CELL` or `NUMBER*CELL`; in a formula a bare number is a
/// constant, a column by number `$N`.
fn formula(text: &str) -> Parsed<Formula> {
    let mut signed: Vec<(f64, String)> = Vec::new();
    let (mut sign, mut term, mut depth) = (1.0, String::new(), 0i32);
    let mut leading_sign = false;
    for c in text.chars() {
        match c {
            '[' => depth += 1,
            ']' => depth -= 1,
            _ => {}
        }
        if depth == 0 && matches!(c, '+' | '-') && !in_exponent(&term) {
            let s = if c == '-' { -1.0 } else { 1.0 };
            if term.trim().is_empty() {
                if !signed.is_empty() || leading_sign {
                    return Err(format!("`{text}`: two operators in a row"));
                }
                leading_sign = true;
                sign = s;
            } else {
                signed.push((sign, std::mem::take(&mut term)));
                sign = s;
            }
            continue;
        }
        term.push(c);
    }
    if term.trim().is_empty() {
        return Err(format!("`{text}`: ends with an operator"));
    }
    signed.push((sign, term));
    let mut f = Formula {
        terms: Vec::new(),
        constant: 0.0,
        text: text.to_string(),
    };
    for (sign, t) in &signed {
        formula_term(*sign, t.trim(), text, &mut f)?;
    }
    if f.terms.is_empty() {
        return Err(format!(
            "`{text}`: a formula needs a column (a constant joint value is not read)"
        ));
    }
    Ok(f)
}

fn formula_term(sign: f64, t: &str, whole: &str, f: &mut Formula) -> Parsed<()> {
    let number = |n: &str| n.trim().parse::<f64>().ok().filter(|x| x.is_finite());
    if let Some((a, b)) = t.split_once('*') {
        let k = number(a).ok_or_else(|| {
            format!(
                "`{whole}`: `{}` before `*` is not a number (write NUMBER*COLUMN)",
                a.trim()
            )
        })?;
        let b = b.trim();
        if number(b).is_some() || b.contains('*') {
            return Err(format!("`{whole}`: `{t}`: expected NUMBER*COLUMN"));
        }
        f.terms.push((sign * k, formula_cell(b, whole)?));
    } else if let Some(x) = number(t) {
        f.constant += sign * x;
    } else {
        f.terms.push((sign, formula_cell(t, whole)?));
    }
    Ok(())
}

/// A cell in a formula (a bare number there is a constant: numbered columns are `$N` or `N[i]`).
fn formula_cell(t: &str, whole: &str) -> Parsed<CellRef> {
    if t.is_empty() {
        return Err(format!("`{whole}`: an empty term"));
    }
    cell(t)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn el(name: &str, index: &[usize]) -> CellRef {
        CellRef {
            column: ColumnRef::Name(name.to_string()),
            index: index.to_vec(),
        }
    }

    fn joints(m: &ColumnMap) -> Vec<(usize, Source)> {
        m.entries
            .iter()
            .filter_map(|(r, s)| match r {
                ColumnRole::Joint(k) => Some((*k, s.clone())),
                _ => None,
            })
            .collect()
    }

    #[test]
    fn the_dlr_mapping_reads_elements_ranges_and_a_formula() {
        let m = ColumnMap::parse(
            "id=1,q=joints[0-2],q=-joints[1]-joints[2],q=joints[10-16],\
             m.x=markers[1][0],m.y=markers[1][1],m.z=markers[1][2]",
        )
        .unwrap();
        let j = joints(&m);
        assert_eq!(j.len(), 11);
        assert_eq!(j[0], (1, Source::Cell(el("joints", &[0]))));
        assert_eq!(j[2], (3, Source::Cell(el("joints", &[2]))));
        let Source::Formula(f) = &j[3].1 else {
            panic!("{:?}", j[3])
        };
        assert_eq!(j[3].0, 4);
        assert_eq!(
            f.terms,
            [(-1.0, el("joints", &[1])), (-1.0, el("joints", &[2]))]
        );
        assert_eq!(f.constant, 0.0);
        assert_eq!(j[4], (5, Source::Cell(el("joints", &[10]))));
        assert_eq!(j[10], (11, Source::Cell(el("joints", &[16]))));
        assert_eq!(
            m.get(&ColumnRole::ReflectorAxis("m".into(), 1)),
            Some(&Source::Cell(el("markers", &[1, 1])))
        );
        assert_eq!(
            m.get(&ColumnRole::Id),
            Some(&Source::Cell(CellRef {
                column: ColumnRef::Number(1),
                index: vec![]
            }))
        );
        assert_eq!(el("markers", &[1, 2]).to_string(), "markers[1][2]");
    }

    #[test]
    fn formulas_coefficients_constants_and_exponents() {
        let f = |s: &str| match joint_source(s).unwrap() {
            Source::Formula(f) => (f.terms, f.constant),
            other => panic!("{other:?}"),
        };
        assert_eq!(
            f("0.5*joints[1]+joints[2]+0.1"),
            (
                vec![(0.5, el("joints", &[1])), (1.0, el("joints", &[2]))],
                0.1
            )
        );
        assert_eq!(
            f(" - 2.5e-1 * $3 + 1e+1 - tilt"),
            (
                vec![
                    (
                        -0.25,
                        CellRef {
                            column: ColumnRef::Number(3),
                            index: vec![]
                        }
                    ),
                    (-1.0, el("tilt", &[]))
                ],
                10.0
            )
        );
        // A name with a minus is a formula that the reader takes as the column when the header
        // has it; a plain cell stays a cell.
        assert!(matches!(joint_source("joint-1"), Ok(Source::Formula(_))));
        assert_eq!(
            joint_source("7"),
            Ok(Source::Cell(CellRef {
                column: ColumnRef::Number(7),
                index: vec![]
            }))
        );
    }

    #[test]
    fn q_entries_append_and_plain_ranges_keep_working() {
        let m = ColumnMap::parse("q1=5,q=6-7,q=angles[3],a.x=1,a.y=2,a.z=3").unwrap();
        let j = joints(&m);
        assert_eq!(j.iter().map(|(k, _)| *k).collect::<Vec<_>>(), [1, 2, 3, 4]);
        assert_eq!(j[3].1, Source::Cell(el("angles", &[3])));
        assert_eq!(m.joint_count(), 4);
        // A q entry mapped again is refused.
        let e = ColumnMap::parse("q=5-6,q2=7,a.x=1,a.y=2,a.z=3").unwrap_err();
        assert!(e.contains("`q2` mapped twice"), "{e}");
    }

    #[test]
    fn malformed_mappings_say_what_was_expected() {
        let err = |s: &str| ColumnMap::parse(&format!("a.x=1,a.y=2,a.z=3,{s}")).unwrap_err();
        for (spec, want) in [
            ("q4=--joints[1]", "two operators in a row"),
            ("q4=joints[1]-", "ends with an operator"),
            ("q4=x*joints[1]", "before `*` is not a number"),
            ("q4=2*3", "expected NUMBER*COLUMN"),
            ("q4=1+2", "a formula needs a column"),
            ("q=joints[a]", "not an index"),
            ("q=joints[3-1]", "before its first"),
            ("q=joints[1", "expected [INDEX]"),
            ("q=[1]", "no column before `[`"),
            ("q=m[1][2][3]", "at most two indices"),
            ("q=7-3", "1 ≤ FIRST ≤ LAST"),
            ("q4=$0", "counted from 1"),
            ("q4=$x", "column number after `$`"),
            ("id=x]", "without `[`"),
            ("x.y.w=1", "unknown role"),
            ("id=names[0]", "plain cells"),
        ] {
            let e = err(spec);
            assert!(e.contains(want), "{spec}: {e}");
            assert!(e.starts_with(&format!("`{spec}`")), "{spec}: {e}");
        }
    }
}
