//! Vector and matrix cells as numpy and pandas print them: `[ 9.66e-01 -8.57e-01  0.  ]`,
//! `[[-1.84  2.22  1.58]\n [-3.06  1.67  1.80]]` (elements separated by spaces, line ends or commas —
//! `[1.0, 2.0]`, as Python prints a list), and the elements a mapping refers to.

/// A vector or matrix cell.
#[derive(Clone, Debug, PartialEq)]
pub enum Array {
    Vector(Vec<f64>),
    /// Rows of one length.
    Matrix(Vec<Vec<f64>>),
}

/// A cell that is not a vector or matrix, or an element that is not there: what is wrong, to be
/// named with the file, line and column.
pub type CellError = String;

/// Does the cell hold a bracketed vector or matrix?
pub fn is_array(cell: &str) -> bool {
    cell.trim_start().starts_with('[')
}

/// The vector or matrix of a cell.
pub fn parse(cell: &str) -> Result<Array, CellError> {
    let t = cell.trim();
    let Some(body) = t.strip_prefix('[') else {
        return Err(format!(
            "an element reference on a plain cell `{}`: it holds no bracketed vector",
            crate::textfile::excerpt(t)
        ));
    };
    let (array, rest) = if body.trim_start().starts_with('[') {
        let (rows, rest) = matrix(body.trim_start())?;
        (Array::Matrix(rows), rest)
    } else {
        let (v, rest) = vector(body, None)?;
        (Array::Vector(v), rest)
    };
    if !rest.trim().is_empty() {
        return Err(format!(
            "`{}` after the closing `]`",
            crate::textfile::excerpt(rest.trim())
        ));
    }
    Ok(array)
}

/// Elements up to the closing `]` (the text after it); `row` names the matrix row for messages.
fn vector(body: &str, row: Option<usize>) -> Result<(Vec<f64>, &str), CellError> {
    let where_ = || row.map(|r| format!(" of row {r}")).unwrap_or_default();
    let Some(close) = body.find(']') else {
        return Err(format!("`[` not closed (no `]` after it){}", where_()));
    };
    let inner = &body[..close];
    if inner.contains('[') {
        return Err(match row {
            Some(r) => format!("`[` of row {r} not closed (a `[` follows before its `]`)"),
            None => "a `[` among a vector's elements: a vector `[…]` or a matrix `[[…] […]]` was \
                     expected"
                .to_string(),
        });
    }
    let mut v = Vec::new();
    for (k, token) in inner
        .split(|c: char| c.is_whitespace() || c == ',')
        .filter(|s| !s.is_empty())
        .enumerate()
    {
        if token == "..." {
            return Err(
                "`...`: numpy left elements out when it printed this (print with \
                 np.set_printoptions(threshold=sys.maxsize))"
                    .to_string(),
            );
        }
        let x = token.parse::<f64>().ok().filter(|x| x.is_finite());
        v.push(x.ok_or_else(|| {
            format!(
                "element {k}{} `{}` is not a finite number",
                where_(),
                crate::textfile::excerpt(token)
            )
        })?);
    }
    Ok((v, &body[close + 1..]))
}

/// Rows `[…]` separated by spaces, line ends or commas up to the closing `]`.
fn matrix(mut body: &str) -> Result<(Vec<Vec<f64>>, &str), CellError> {
    let mut rows: Vec<Vec<f64>> = Vec::new();
    loop {
        body = body.trim_start_matches(|c: char| c.is_whitespace() || c == ',');
        if let Some(rest) = body.strip_prefix(']') {
            return Ok((rows, rest));
        }
        let Some(row) = body.strip_prefix('[') else {
            if body.is_empty() {
                return Err("`[[` not closed (no `]` after the last row)".to_string());
            }
            return Err(format!(
                "`{}` between the rows of a matrix (rows are `[…]`)",
                crate::textfile::excerpt(body)
            ));
        };
        if row.trim_start().starts_with('[') {
            return Err(
                "more than two levels of brackets: a vector `[…]` or a matrix `[[…] […]]` was \
                 expected"
                    .to_string(),
            );
        }
        let (v, rest) = vector(row, Some(rows.len()))?;
        if let Some(first) = rows.first()
            && first.len() != v.len()
        {
            return Err(format!(
                "row {} has {} values, row 0 has {}: the rows of a matrix have one length",
                rows.len(),
                v.len(),
                first.len()
            ));
        }
        rows.push(v);
        body = rest;
    }
}

fn plural(n: usize, what: &str) -> String {
    if n == 1 {
        format!("1 {what}")
    } else {
        format!("{n} {what}s")
    }
}

impl Array {
    /// What the cell holds, for messages: "a vector of 19 values", "a 2 × 3 matrix".
    pub fn describe(&self) -> String {
        match self {
            Array::Vector(v) => format!("a vector of {}", plural(v.len(), "value")),
            Array::Matrix(m) => format!("a {} × {} matrix", m.len(), m.first().map_or(0, Vec::len)),
        }
    }

    /// The element at `index` (`[i]` of a vector, `[i][j]` of a matrix).
    pub fn element(&self, index: &[usize]) -> Result<f64, CellError> {
        match (self, index) {
            (Array::Vector(v), [i]) => v.get(*i).copied().ok_or_else(|| {
                format!(
                    "index [{i}] is beyond the vector's {} (indices 0…{})",
                    plural(v.len(), "value"),
                    v.len().saturating_sub(1)
                )
            }),
            (Array::Matrix(m), [i, j]) => {
                let row = m.get(*i).ok_or_else(|| {
                    format!(
                        "row index [{i}] is beyond the matrix's {} ({}: rows 0…{})",
                        plural(m.len(), "row"),
                        self.describe(),
                        m.len().saturating_sub(1)
                    )
                })?;
                row.get(*j).copied().ok_or_else(|| {
                    format!(
                        "index [{i}][{j}] is beyond row {i}'s {} ({}: indices 0…{})",
                        plural(row.len(), "value"),
                        self.describe(),
                        row.len().saturating_sub(1)
                    )
                })
            }
            (Array::Vector(_), [_, _]) => Err(format!(
                "two indices for {}: write one, e.g. [{}]",
                self.describe(),
                index[0]
            )),
            (Array::Matrix(_), [i]) => Err(format!(
                "one index for {}: [{i}] is a row; write [{i}][j] for its element j",
                self.describe()
            )),
            _ => Err(format!("{} indices for {}", index.len(), self.describe())),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn numpy_and_pandas_printouts() {
        assert_eq!(
            parse("[ 9.66545383e-01 -8.56966034e-01  0.  1.]").unwrap(),
            Array::Vector(vec![0.966545383, -0.856966034, 0.0, 1.0])
        );
        assert_eq!(
            parse("[1.0, -2.5, 3]").unwrap(),
            Array::Vector(vec![1.0, -2.5, 3.0])
        );
        assert_eq!(parse("[]").unwrap(), Array::Vector(vec![]));
        let m = parse(
            "[[-1.8412635   2.22621393  1.58426529]\n [-3.06954874  1.67314009  1.80922059]]",
        )
        .unwrap();
        assert_eq!(m.element(&[1, 0]).unwrap(), -3.06954874);
        assert_eq!(m.element(&[0, 2]).unwrap(), 1.58426529);
        assert_eq!(m.describe(), "a 2 × 3 matrix");
        // A vector's wrapped continuation lines (numpy's line width) read as spaces.
        let v = parse("[ 1.  2.\n  3. ]").unwrap();
        assert_eq!(v.element(&[2]).unwrap(), 3.0);
        assert_eq!(
            parse("[[1, 2], [3, 4]]").unwrap().element(&[1, 1]).unwrap(),
            4.0
        );
    }

    #[test]
    fn malformed_cells_and_missing_elements_say_what() {
        let e = |s: &str| parse(s).unwrap_err();
        assert!(e("[1 2 3").contains("`[` not closed"), "{}", e("[1 2 3"));
        assert!(e("[[1 2] [3 4]").contains("not closed"));
        assert!(e("[[1 2 3] [4 5]]").contains("row 1 has 2 values, row 0 has 3"));
        assert!(e("[1 x 3]").contains("element 1 `x` is not a finite number"));
        assert!(e("[1 nan 3]").contains("element 1 `nan`"));
        assert!(e("[[1 2] [3 y]]").contains("element 1 of row 1 `y`"));
        assert!(e("0.5").contains("plain cell `0.5`"));
        assert!(e("[1 2] 3").contains("`3` after the closing"));
        assert!(e("[[[1]]]").contains("more than two levels"));
        assert!(e("[1 ... 9]").contains("threshold"));
        let v = parse("[1 2 3]").unwrap();
        let msg = v.element(&[3]).unwrap_err();
        assert!(
            msg.contains("index [3] is beyond the vector's 3 values (indices 0…2)"),
            "{msg}"
        );
        assert!(v.element(&[0, 1]).unwrap_err().contains("two indices"));
        let m = parse("[[1 2 3] [4 5 6]]").unwrap();
        assert!(
            m.element(&[2, 0])
                .unwrap_err()
                .contains("beyond the matrix's 2 rows")
        );
        assert!(
            m.element(&[1, 3])
                .unwrap_err()
                .contains("[1][3] is beyond row 1's 3 values")
        );
        assert!(e("[[1 2] [3 4]").contains("not closed"));
        assert!(e("[[1 2 [3 4]]").contains("`[` of row 0 not closed"));
        assert!(m.element(&[1]).unwrap_err().contains("[1] is a row"));
    }
}
