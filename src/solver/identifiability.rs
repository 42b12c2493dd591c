//! Which parameters can distance data identify?
//!
//! The identification Jacobian (rows −u_ijᵀ(J_i − J_j), one per pair and reflector, on a sample of
//! pairs) is summarised by its mean Gram matrix `G = MᵀM / rows` ([`gram_by_product`], or
//! [`gram_by_qr`] for the built-in robot, whose calibrations stay bit-identical to earlier releases).
//! Columns are scaled to unit RMS sensitivity and taken greedily in a preferred order
//! ([`crate::kinematics::ArmModel::identifiability_order`]); a column is kept only if the part of it
//! that the already kept columns cannot explain has norm ≥ [`NEAR_DEPENDENT_TOL`]. That is modified
//! Gram–Schmidt in the G inner product, i.e. a Cholesky factorisation of G in the preference order
//! that skips the columns it cannot extend — a column-pivoted QR with a physically motivated pivot
//! order, so the report can say *what* a fixed parameter depends on. Squaring the condition number puts
//! the residuals' noise floor near √ε ≈ 1e-8, below [`UNIDENTIFIABLE_TOL`]. The fixed parameters stay
//! at their start values.

use nalgebra::DMatrix;
use serde::{Deserialize, Serialize};

/// Relative residual below which a column counts as exactly unidentifiable (numerical zero).
pub const UNIDENTIFIABLE_TOL: f64 = 1e-7;
/// Relative residual below which a column counts as near-dependent and is fixed too.
pub const NEAR_DEPENDENT_TOL: f64 = 2e-3;
/// A column whose norm is below this fraction of the largest column's is unidentifiable outright,
/// before any scaling. URDF angles written as `1.570796325` or `1.5708` leave a parameter that is
/// physically a rigid motion (a shift along joint 1's axis) with a sensitivity of 1e-9 … 1e-6 of the
/// others; scaled to unit norm, such a column looks independent and its value runs off to 1e8 mm.
pub const NEGLIGIBLE_COLUMN: f64 = 1e-6;

/// A fixed parameter and why.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct FixedParameter {
    pub index: usize,
    pub name: String,
    /// Residual norm of its scaled column after projecting out the kept ones (0 = fully dependent).
    pub residual: f64,
    pub reason: String,
}

/// Outcome of the analysis.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct IdentifiabilityReport {
    pub free: Vec<usize>,
    pub fixed: Vec<FixedParameter>,
    /// Condition number of the column-scaled Jacobian with every parameter (∞ when singular).
    pub condition_before: f64,
    /// Condition number with the fixed parameters removed.
    pub condition_after: f64,
}

/// The mean Gram matrix `MMᵀ / count` of `columns` (one column per sampled pair and reflector), as one
/// matrix product.
pub fn gram_by_product(columns: &DMatrix<f64>) -> DMatrix<f64> {
    let n = columns.ncols().max(1);
    columns * columns.transpose() / n as f64
}

/// The mean Gram matrix `RᵀR / count` of `columns` through a thin QR of their transpose (`Mᵀ = Q R`).
/// The same matrix as [`gram_by_product`] up to rounding; the built-in robot's calibrations use it so
/// that they stay bit-identical to earlier releases.
///
/// The Householder QR is nalgebra's (`QR::new`: its reflection axes, and each reflection computed
/// operation for operation as nalgebra computes it), with the columns taken in blocks, the
/// reflections applied on the work pool and compiled for the processor's widest vector instructions:
/// each column's arithmetic is the same whatever the thread and the processor, so `R` is
/// bit-identical to `DMatrix::qr().r()` (a unit test holds it).
pub fn gram_by_qr(columns: &DMatrix<f64>) -> DMatrix<f64> {
    let (p, count) = columns.shape();
    let rows = count.max(p);
    // Mᵀ, padded with zero rows up to p.
    let m = DMatrix::<f64>::from_fn(
        rows,
        p,
        |r, c| {
            if r < count { columns[(c, r)] } else { 0.0 }
        },
    );
    gram_by_qr_of_transposed(m, count)
}

/// [`gram_by_qr`] of `M` given as `Mᵀ` with zero rows appended up to at least `M`'s row count
/// (`arm_problem::pair_jacobian_transposed`), `count` the number of `M`'s columns: the same numbers.
pub fn gram_by_qr_of_transposed(mut m: DMatrix<f64>, count: usize) -> DMatrix<f64> {
    let (rows, p) = m.shape();
    debug_assert!(rows >= count.max(p));
    let diag = householder_in_place(&mut m);
    // `QR::r()`: the upper triangle of the first min(rows, p) rows, |diagonal| on the diagonal.
    let k = rows.min(p);
    let r = DMatrix::from_fn(k, p, |i, j| match i.cmp(&j) {
        std::cmp::Ordering::Less => m[(i, j)],
        std::cmp::Ordering::Equal => diag[i].abs(),
        std::cmp::Ordering::Greater => 0.0,
    });
    r.transpose() * &r / count.max(1) as f64
}

/// Columns reflected together ([`householder_in_place`]): each reflection axis is read once per
/// block instead of once per column, while the block's columns stay in the core's cache.
const QR_BLOCK_COLUMNS: usize = 16;
/// Columns of a block per task on the work pool.
const QR_TASK_COLUMNS: usize = 4;

/// nalgebra's `QR::new` on `m` in place (`householder::clear_column_unchecked` for every column);
/// returns the signed diagonal.
///
/// Column `j` of nalgebra's QR is reflected by the axes `0, 1, …, j − 1` in turn and then gives axis
/// `j`. Here the columns are taken in blocks of [`QR_BLOCK_COLUMNS`]: a block first receives the
/// reflections of every column before it (each axis applied to the block's columns, on the work
/// pool), then is factorised column by column. Every column sees the same reflections in the same
/// order, each computed as nalgebra computes it ([`reflect`]), so `R` is nalgebra's to the bit (unit
/// test `the_parallel_qr_is_nalgebras_to_the_bit`).
fn householder_in_place(m: &mut DMatrix<f64>) -> Vec<f64> {
    use crate::par::prelude::*;
    use nalgebra::DVectorViewMut;
    use nalgebra::linalg::householder::reflection_axis_mut;
    let (rows, p) = m.shape();
    let k = rows.min(p);
    // The signed diagonal, and whether each step reflects at all (a zero column does not).
    let mut diag: Vec<f64> = Vec::with_capacity(k);
    let mut reflects: Vec<bool> = Vec::with_capacity(k);
    let data = m.as_mut_slice();
    for j0 in (0..p).step_by(QR_BLOCK_COLUMNS) {
        let j1 = (j0 + QR_BLOCK_COLUMNS).min(p);
        let (done, rest) = data.split_at_mut(j0 * rows);
        let block = &mut rest[..(j1 - j0) * rows];
        // The reflections of the columns before the block, in order.
        block
            .par_chunks_mut(QR_TASK_COLUMNS * rows)
            .for_each(|columns: &mut [f64]| {
                widest_simd(Reflections {
                    axes: done,
                    first: 0,
                    rows,
                    steps: (0..j0.min(k))
                        .filter(|&i| reflects[i])
                        .map(|i| (i, diag[i].signum())),
                    columns,
                })
            });
        // The block itself, column by column.
        for i in j0..j1.min(k) {
            let (head, tail) = block.split_at_mut((i - j0 + 1) * rows);
            let mut axis = DVectorViewMut::from_slice(&mut head[(i - j0) * rows + i..], rows - i);
            let (norm, not_zero) = reflection_axis_mut(&mut axis);
            diag.push(norm);
            reflects.push(not_zero);
            if not_zero {
                let axes = &head[(i - j0) * rows..];
                // Four columns per task: a column of a few thousand rows is microseconds of work.
                tail.par_chunks_mut(QR_TASK_COLUMNS * rows)
                    .for_each(|columns| {
                        widest_simd(Reflections {
                            axes,
                            first: i,
                            rows,
                            steps: std::iter::once((i, norm.signum())),
                            columns,
                        })
                    });
            }
        }
    }
    diag
}

/// The QR's reflections `steps` (step, sign) applied in turn to each of `columns` (whole columns of
/// `rows` numbers, one after the other), the axis of step `i` below the diagonal of column `i` of the
/// matrix, held in `axes` (its columns from `first` on). Natively a `pulp::WithSimd`, so that the
/// loops are compiled for the widest vector instructions the processor has (AVX2 on most x86-64
/// machines; the build's baseline is SSE2): a wider vector computes each element as a narrower one
/// does, and Rust never fuses a multiply and an add, so the numbers do not depend on the processor.
struct Reflections<'a, I> {
    axes: &'a [f64],
    first: usize,
    rows: usize,
    steps: I,
    columns: &'a mut [f64],
}

impl<I: Iterator<Item = (usize, f64)>> Reflections<'_, I> {
    #[inline(always)]
    fn run(self) {
        let rows = self.rows;
        for (i, sign) in self.steps {
            let c = i - self.first;
            let axis = &self.axes[c * rows + i..(c + 1) * rows];
            let mut groups = self.columns.chunks_exact_mut(4 * rows);
            for group in groups.by_ref() {
                let (a, rest) = group.split_at_mut(rows);
                let (b, rest) = rest.split_at_mut(rows);
                let (c3, d) = rest.split_at_mut(rows);
                reflect4(
                    axis,
                    sign,
                    [&mut a[i..], &mut b[i..], &mut c3[i..], &mut d[i..]],
                );
            }
            for column in groups.into_remainder().chunks_mut(rows) {
                reflect(axis, sign, &mut column[i..]);
            }
        }
    }
}

#[cfg(not(target_arch = "wasm32"))]
impl<I: Iterator<Item = (usize, f64)>> pulp::WithSimd for Reflections<'_, I> {
    type Output = ();

    #[inline(always)]
    fn with_simd<S: pulp::Simd>(self, _simd: S) {
        self.run()
    }
}

/// The reflections compiled for the processor's widest vector instructions (pulp's dispatch at run
/// time), natively.
#[cfg(not(target_arch = "wasm32"))]
fn widest_simd<I: Iterator<Item = (usize, f64)>>(reflections: Reflections<'_, I>) {
    pulp::Arch::new().dispatch(reflections)
}

/// In a browser the module is compiled with WebAssembly's SIMD throughout (`.cargo/config.toml`).
#[cfg(target_arch = "wasm32")]
fn widest_simd<I: Iterator<Item = (usize, f64)>>(reflections: Reflections<'_, I>) {
    reflections.run()
}

/// nalgebra's `dotc` of two vectors, operation for operation: eight partial sums over the whole
/// groups of eight, combined as nalgebra combines them, then the remainder.
#[inline(always)]
fn combine(acc: &[f64; 8], axis_rest: &[f64], y_rest: &[f64]) -> f64 {
    let mut dot = 0.0;
    dot += acc[0] + acc[4];
    dot += acc[1] + acc[5];
    dot += acc[2] + acc[6];
    dot += acc[3] + acc[7];
    for (a, b) in axis_rest.iter().zip(y_rest) {
        dot += a * b;
    }
    dot
}

/// `axpy`'s `y ← factor · x + sign · y` with nalgebra's reflection factor `dot · (sign · −2)`
/// (`Reflection::reflect_with_sign`, bias 0).
#[inline(always)]
fn apply(axis: &[f64], sign: f64, dot: f64, y: &mut [f64]) {
    let factor = (dot - 0.0) * (sign * -2.0);
    for (y, &x) in y.iter_mut().zip(axis) {
        *y = factor * x + sign * *y;
    }
}

/// `y` reflected by the Householder `axis` as nalgebra's `Reflection::reflect_with_sign` (bias 0)
/// does it, operation for operation ([`combine`], [`apply`]).
#[inline(always)]
fn reflect(axis: &[f64], sign: f64, y: &mut [f64]) {
    let n = axis.len().min(y.len());
    let (axis, y) = (&axis[..n], &mut y[..n]);
    let whole = n - n % 8;
    let mut acc = [0.0f64; 8];
    for (a, b) in axis[..whole]
        .chunks_exact(8)
        .zip(y[..whole].chunks_exact(8))
    {
        for t in 0..8 {
            acc[t] += a[t] * b[t];
        }
    }
    let dot = combine(&acc, &axis[whole..], &y[whole..]);
    apply(axis, sign, dot, y);
}

/// [`reflect`] of four vectors by one axis, their dot products' partial sums side by side: each
/// vector's sums are [`reflect`]'s (the same numbers), and the four chains of additions keep the
/// processor's adders busy where one chain waits on its own latency.
#[inline(always)]
fn reflect4(axis: &[f64], sign: f64, ys: [&mut [f64]; 4]) {
    let n = ys.iter().map(|y| y.len()).fold(axis.len(), usize::min);
    let axis = &axis[..n];
    let [y0, y1, y2, y3] = ys;
    let ys = [&mut y0[..n], &mut y1[..n], &mut y2[..n], &mut y3[..n]];
    let whole = n - n % 8;
    let mut acc = [[0.0f64; 8]; 4];
    for start in (0..whole).step_by(8) {
        let a: &[f64; 8] = axis[start..start + 8].try_into().expect("eight");
        for (acc, y) in acc.iter_mut().zip(&ys) {
            let b: &[f64; 8] = y[start..start + 8].try_into().expect("eight");
            for t in 0..8 {
                acc[t] += a[t] * b[t];
            }
        }
    }
    for (acc, y) in acc.iter().zip(ys) {
        let dot = combine(acc, &axis[whole..], &y[whole..]);
        apply(axis, sign, dot, y);
    }
}

/// What the analysis needs to know about the parameters.
pub struct ParameterInfo<'a> {
    /// Order in which the parameters are considered (every index once).
    pub order: &'a [usize],
    /// Parameters that may be free at all (the others are fixed by the user).
    pub allowed: &'a [bool],
    pub name: &'a dyn Fn(usize) -> String,
    /// Why a parameter is unidentifiable, when physics says so.
    pub reason: &'a dyn Fn(usize) -> Option<String>,
    /// What the method fits, for the reasons: `distances` (the paper's and ref. [26]'s methods),
    /// `absolute positions`, `poses`.
    pub data: &'a str,
    /// Why a parameter that is not `allowed` is fixed (e.g. `fixed by the user`).
    pub not_allowed: &'a str,
}

impl ParameterInfo<'_> {
    /// What the distance methods fit.
    pub const DISTANCES: &'static str = "distances";
    /// The reason of a parameter the user held.
    pub const FIXED_BY_USER: &'static str = "fixed by the user";
}

/// Condition number of the scaled Gram submatrix of `idx` (the square root of its eigenvalue ratio).
fn condition(scaled: &DMatrix<f64>, idx: &[usize]) -> f64 {
    if idx.is_empty() {
        return 1.0;
    }
    let sub = DMatrix::from_fn(idx.len(), idx.len(), |i, j| scaled[(idx[i], idx[j])]);
    let ev = sub.symmetric_eigenvalues();
    let (max, min) = (ev.max(), ev.min());
    if min <= max * 1e-15 {
        f64::INFINITY
    } else {
        (max / min).sqrt()
    }
}

/// The kept parameters that column `k` leans on most (largest coefficients of its projection).
fn leaning_on(scaled: &DMatrix<f64>, kept: &[usize], k: usize, info: &ParameterInfo) -> String {
    let g = DMatrix::from_fn(kept.len(), kept.len(), |i, j| scaled[(kept[i], kept[j])]);
    let b = nalgebra::DVector::from_fn(kept.len(), |i, _| scaled[(kept[i], k)]);
    let coef = g
        .svd(true, true)
        .solve(&b, 1e-12)
        .unwrap_or_else(|_| nalgebra::DVector::zeros(kept.len()));
    let mut lean: Vec<(usize, f64)> = kept
        .iter()
        .copied()
        .zip(coef.iter().map(|c| c.abs()))
        .collect();
    lean.sort_by(|x, y| y.1.total_cmp(&x.1));
    let names: Vec<String> = lean.iter().take(3).map(|(j, _)| (info.name)(*j)).collect();
    names.join(", ")
}

/// Analyse the mean Gram matrix `gram` of the unscaled pair Jacobian.
pub fn analyse(gram: &DMatrix<f64>, info: &ParameterInfo) -> IdentifiabilityReport {
    let p = gram.ncols();
    let norms: Vec<f64> = (0..p).map(|k| gram[(k, k)].max(0.0).sqrt()).collect();
    let max_norm = norms.iter().copied().fold(0.0, f64::max).max(1e-300);
    let usable: Vec<bool> = norms
        .iter()
        .map(|&n| n.is_finite() && n > NEGLIGIBLE_COLUMN * max_norm)
        .collect();
    let scaled = DMatrix::from_fn(p, p, |a, b| {
        if usable[a] && usable[b] {
            gram[(a, b)] / (norms[a] * norms[b])
        } else {
            0.0
        }
    });
    let condition_before = if usable.iter().all(|&u| u) {
        condition(&scaled, &(0..p).collect::<Vec<_>>())
    } else {
        f64::INFINITY
    };
    // Rows of the Cholesky factor of the kept columns, in kept order.
    let mut kept: Vec<usize> = Vec::new();
    let mut l: Vec<Vec<f64>> = Vec::new();
    let mut fixed = Vec::new();
    for &k in info.order {
        if !info.allowed.get(k).copied().unwrap_or(false) {
            fixed.push(FixedParameter {
                index: k,
                name: (info.name)(k),
                residual: f64::NAN,
                reason: info.not_allowed.into(),
            });
            continue;
        }
        let res = if usable[k] {
            let mut lk = Vec::with_capacity(kept.len() + 1);
            for (jpos, &j) in kept.iter().enumerate() {
                let dot: f64 = lk.iter().zip(&l[jpos]).map(|(a, b)| a * b).sum();
                lk.push((scaled[(k, j)] - dot) / l[jpos][jpos]);
            }
            let res = (1.0 - lk.iter().map(|v| v * v).sum::<f64>())
                .max(0.0)
                .sqrt();
            if res >= NEAR_DEPENDENT_TOL {
                lk.push(res);
                l.push(lk);
                kept.push(k);
                continue;
            }
            res
        } else {
            0.0
        };
        let reason = if res < UNIDENTIFIABLE_TOL {
            let data = info.data;
            match (info.reason)(k) {
                Some(why) => format!("unidentifiable from {data} ({why})"),
                None if !usable[k] => {
                    format!("unidentifiable from {data}: the {data} do not depend on it")
                }
                None => format!(
                    "unidentifiable from {data}: its column is a combination of the kept ones"
                ),
            }
        } else {
            format!(
                "near-dependent (residual {res:.1e} of its scaled column) on {}",
                leaning_on(&scaled, &kept, k, info)
            )
        };
        fixed.push(FixedParameter {
            index: k,
            name: (info.name)(k),
            residual: res,
            reason,
        });
    }
    kept.sort_unstable();
    fixed.sort_by_key(|f| f.index);
    let condition_after = condition(&scaled, &kept);
    IdentifiabilityReport {
        free: kept,
        fixed,
        condition_before,
        condition_after,
    }
}

mod recheck;
pub use recheck::{GramMethod, at_solution, identifiable_at};

#[cfg(test)]
mod tests;
