//! Central finite differences, to check analytic derivatives (Jacobians and gradients) in tests.
//!
//! Every analytic derivative in the engine — the identification Jacobian of `kinematics`, the gradients
//! of the solver's minimax problems — is checked against [`check_jacobian`] in a unit test; a new
//! parametrisation or calibration method does the same:
//!
//! ```
//! use dualcal::finite_difference::{Tolerance, check_jacobian};
//! use nalgebra::{DMatrix, DVector};
//!
//! // f(x) = (x0·x1, sin x0): J = [[x1, x0], [cos x0, 0]].
//! let f = |x: &DVector<f64>| DVector::from_vec(vec![x[0] * x[1], x[0].sin()]);
//! let x: DVector<f64> = DVector::from_vec(vec![0.3, -2.0]);
//! let good = DMatrix::from_row_slice(2, 2, &[x[1], x[0], x[0].cos(), 0.0]);
//! check_jacobian(f, &x, &good, |_| 1e-6, Tolerance::default()).unwrap();
//! let wrong = DMatrix::from_row_slice(2, 2, &[x[1], x[0], -x[0].cos(), 0.0]);
//! let err = check_jacobian(f, &x, &wrong, |_| 1e-6, Tolerance::default()).unwrap_err();
//! assert_eq!(err.columns(), vec![0]);
//! ```

use nalgebra::{DMatrix, DVector};
use std::fmt;

/// Central-difference Jacobian of `f` at `x`: column `c` is `(f(x + h e_c) − f(x − h e_c)) / 2h` with
/// `h = step(c)`.
pub fn central_jacobian(
    mut f: impl FnMut(&DVector<f64>) -> DVector<f64>,
    x: &DVector<f64>,
    step: impl Fn(usize) -> f64,
) -> DMatrix<f64> {
    let columns: Vec<DVector<f64>> = (0..x.len())
        .map(|c| {
            let h = step(c);
            let (plus, minus) = (f(&offset(x, c, h)), f(&offset(x, c, -h)));
            (plus - minus) / (2.0 * h)
        })
        .collect();
    if columns.is_empty() {
        let rows = f(x).len();
        return DMatrix::zeros(rows, 0);
    }
    DMatrix::from_columns(&columns)
}

fn offset(x: &DVector<f64>, c: usize, h: f64) -> DVector<f64> {
    let mut y = x.clone();
    y[c] += h;
    y
}

/// How far an analytic entry may be from its central difference.
///
/// An entry passes when `|analytic − fd| ≤ rel · max(|analytic|, |fd|) + abs + round-off`, where the
/// round-off allowance of column `c` is `64 ε ‖f‖∞ / h_c` (the cancellation error of the difference
/// quotient, with `‖f‖∞` the largest value of `f` at the two points). `rel` covers the O(h²)
/// truncation error; a wrong derivative is off by O(1) relative. When `f` is a small result of
/// cancelling much larger intermediate values, its round-off is theirs, which this estimate does not
/// see: allow for it with `abs`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Tolerance {
    pub rel: f64,
    pub abs: f64,
}

impl Default for Tolerance {
    /// `rel = 1e-6`, `abs = 0`.
    fn default() -> Self {
        Self {
            rel: 1e-6,
            abs: 0.0,
        }
    }
}

impl Tolerance {
    pub fn rel(rel: f64) -> Self {
        Self { rel, abs: 0.0 }
    }

    pub fn with_abs(self, abs: f64) -> Self {
        Self { abs, ..self }
    }
}

/// One entry outside the tolerance.
#[derive(Clone, Debug, PartialEq)]
pub struct Mismatch {
    pub row: usize,
    pub col: usize,
    pub analytic: f64,
    pub finite_difference: f64,
    /// The largest difference the tolerance allowed for this entry.
    pub allowed: f64,
}

/// The entries of an analytic Jacobian that disagree with central differences.
#[derive(Clone, Debug, PartialEq)]
pub struct JacobianMismatch {
    /// Worst first (by difference over allowance).
    pub entries: Vec<Mismatch>,
    pub rows: usize,
    pub cols: usize,
}

impl JacobianMismatch {
    /// The columns (variables) with at least one wrong entry, ascending.
    pub fn columns(&self) -> Vec<usize> {
        let mut c: Vec<usize> = self.entries.iter().map(|e| e.col).collect();
        c.sort_unstable();
        c.dedup();
        c
    }

    /// Rename rows and columns in the message (e.g. parameter names).
    pub fn describe(
        &self,
        row_name: impl Fn(usize) -> String,
        col_name: impl Fn(usize) -> String,
    ) -> String {
        let mut s = format!(
            "{} of {}×{} entries differ from central differences (worst first):",
            self.entries.len(),
            self.rows,
            self.cols
        );
        for e in self.entries.iter().take(12) {
            s += &format!(
                "\n  row {} col {}: analytic {:e}, finite difference {:e}, difference {:e} > allowed {:e}",
                row_name(e.row),
                col_name(e.col),
                e.analytic,
                e.finite_difference,
                (e.analytic - e.finite_difference).abs(),
                e.allowed
            );
        }
        if self.entries.len() > 12 {
            s += &format!("\n  … and {} more", self.entries.len() - 12);
        }
        s
    }
}

impl fmt::Display for JacobianMismatch {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(&self.describe(|r| r.to_string(), |c| c.to_string()))
    }
}

impl std::error::Error for JacobianMismatch {}

/// Compare `analytic` (rows = outputs of `f`, columns = components of `x`) with the central-difference
/// Jacobian of `f` at `x` (step `step(c)` for column `c`). A gradient is a one-row Jacobian.
///
/// Panics if the shapes disagree (a bug in the test, not a finding).
pub fn check_jacobian(
    mut f: impl FnMut(&DVector<f64>) -> DVector<f64>,
    x: &DVector<f64>,
    analytic: &DMatrix<f64>,
    step: impl Fn(usize) -> f64,
    tolerance: Tolerance,
) -> Result<(), JacobianMismatch> {
    assert_eq!(
        analytic.ncols(),
        x.len(),
        "the analytic Jacobian has one column per variable"
    );
    let mut entries = Vec::new();
    for c in 0..x.len() {
        let h = step(c);
        assert!(h > 0.0 && h.is_finite(), "step {h} for column {c}");
        let (plus, minus) = (f(&offset(x, c, h)), f(&offset(x, c, -h)));
        assert_eq!(
            plus.len(),
            analytic.nrows(),
            "the analytic Jacobian has one row per output"
        );
        let size = plus.amax().max(minus.amax());
        let round_off = 64.0 * f64::EPSILON * size / h;
        for r in 0..analytic.nrows() {
            let fd = (plus[r] - minus[r]) / (2.0 * h);
            let an = analytic[(r, c)];
            let allowed = tolerance.rel * an.abs().max(fd.abs()) + tolerance.abs + round_off;
            // Tested as "within", so that a NaN on either side is a mismatch.
            let within = (an - fd).abs() <= allowed;
            if !within {
                entries.push(Mismatch {
                    row: r,
                    col: c,
                    analytic: an,
                    finite_difference: fd,
                    allowed,
                });
            }
        }
    }
    if entries.is_empty() {
        return Ok(());
    }
    let badness = |e: &Mismatch| (e.analytic - e.finite_difference).abs() / e.allowed;
    crate::sort::sort_by(&mut entries, |a, b| badness(b).total_cmp(&badness(a)));
    Err(JacobianMismatch {
        entries,
        rows: analytic.nrows(),
        cols: analytic.ncols(),
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    fn f(x: &DVector<f64>) -> DVector<f64> {
        DVector::from_vec(vec![
            x[0] * x[1] * x[1],
            (x[0] - x[1]).exp(),
            1e3 * x[1].cos(),
        ])
    }

    fn jacobian(x: &DVector<f64>) -> DMatrix<f64> {
        let e = (x[0] - x[1]).exp();
        DMatrix::from_row_slice(
            3,
            2,
            &[
                x[1] * x[1],
                2.0 * x[0] * x[1],
                e,
                -e,
                0.0,
                -1e3 * x[1].sin(),
            ],
        )
    }

    #[test]
    fn central_jacobian_is_second_order() {
        let x = DVector::from_vec(vec![0.7, -1.3]);
        let fd = central_jacobian(f, &x, |_| 1e-5);
        assert!((fd - jacobian(&x)).amax() < 1e-6);
    }

    #[test]
    fn a_correct_jacobian_passes_and_a_wrong_entry_is_named() {
        let x = DVector::from_vec(vec![0.7, -1.3]);
        check_jacobian(f, &x, &jacobian(&x), |_| 1e-6, Tolerance::default()).unwrap();
        let mut wrong = jacobian(&x);
        wrong[(1, 1)] *= 1.0 + 1e-4;
        let err = check_jacobian(f, &x, &wrong, |_| 1e-6, Tolerance::default()).unwrap_err();
        assert_eq!(err.entries.len(), 1, "{err}");
        assert_eq!((err.entries[0].row, err.entries[0].col), (1, 1));
        assert_eq!(err.columns(), vec![1]);
        assert!(err.to_string().contains("row 1 col 1"), "{err}");
    }

    #[test]
    fn nan_is_a_mismatch() {
        let x = DVector::from_vec(vec![0.7, -1.3]);
        let mut wrong = jacobian(&x);
        wrong[(2, 0)] = f64::NAN;
        let err = check_jacobian(f, &x, &wrong, |_| 1e-6, Tolerance::default()).unwrap_err();
        assert_eq!(err.columns(), vec![0]);
    }
}
