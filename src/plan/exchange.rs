//! Improving a design by exchange (module documentation, step 2): the greedy pass's configurations
//! are swapped one at a time for a candidate while that lowers the I-criterion `trace(M⁻¹ P)`
//! ([`super::i_criterion`]) — a modified Fedorov exchange: in each sweep every exchangeable
//! configuration in turn is replaced by the candidate that lowers the criterion most, when one does,
//! until a sweep swaps nothing or [`MAX_SWEEPS`] have been made.
//!
//! A swap `a → c` changes `M` by the distances of `a` and of `c` to the other chosen configurations:
//! `2 (n − 1)` rows per reflector, more than the `p` parameters, so the Woodbury identity gains
//! nothing and each trial refactors `M' = M − H_a + H_c − h_ca` (Cholesky, `p³/3`) instead, with
//! `H_x = Σ_{j chosen} h_xj` kept for every candidate (`h_xj` the information of the distances
//! between x and j, [`super::pair_rows`]) and updated by rank-`2·reflectors` terms after each swap.
//! The rows are whitened by `P` (`J L⁻ᵀ`, `P = L Lᵀ`), so that the criterion is `trace(M'⁻¹)` =
//! `‖L'⁻¹‖²_F`, read off the factor.

use crate::par::prelude::*;
use nalgebra::{DMatrix, Vector3};

/// Sweeps over the design at most.
pub const MAX_SWEEPS: usize = 30;

/// A design after exchange.
#[derive(Clone, Debug, PartialEq)]
pub struct Exchange {
    /// The design (indices into the pool), the fixed positions first and unchanged.
    pub chosen: Vec<usize>,
    /// The I-criterion before (the design given) and after.
    pub before: f64,
    pub after: f64,
    /// Swaps made, and sweeps over the design.
    pub swaps: usize,
    pub sweeps: usize,
}

/// The whitened distance rows of the pool.
struct Rows<'a> {
    points: &'a [Vec<Vector3<f64>>],
    /// Per candidate, `J L⁻ᵀ` row-major: 3 rows per reflector, `p` columns.
    jac: Vec<Vec<f64>>,
    p: usize,
    reflectors: usize,
}

impl Rows<'_> {
    /// The rows of the distances between `c` and `j`, one per reflector, into `out`
    /// (`reflectors × p`, row-major; zero where the two positions coincide).
    fn pair(&self, c: usize, j: usize, out: &mut [f64]) {
        let p = self.p;
        for k in 0..self.reflectors {
            let row = &mut out[k * p..(k + 1) * p];
            let v = self.points[c][k] - self.points[j][k];
            let Some(u) = v.try_normalize(1e-12) else {
                row.fill(0.0);
                continue;
            };
            let (jc, jj) = (&self.jac[c], &self.jac[j]);
            for (col, r) in row.iter_mut().enumerate() {
                let mut acc = 0.0;
                for t in 0..3 {
                    let at = (3 * k + t) * p + col;
                    acc += u[t] * (jc[at] - jj[at]);
                }
                *r = acc;
            }
        }
    }

    /// `m += sign · Σ rᵀ r` over the rows of the pair `c`, `j` (lower triangle).
    fn add_pair(&self, m: &mut [f64], c: usize, j: usize, sign: f64, scratch: &mut [f64]) {
        if c == j {
            return;
        }
        self.pair(c, j, scratch);
        add_outer(m, &scratch[..self.reflectors * self.p], self.p, sign);
    }
}

/// `m += sign · Σ rᵀ r` over the rows `r` of `rows` (`p` each), the lower triangle of `m` (`p × p`,
/// row-major).
fn add_outer(m: &mut [f64], rows: &[f64], p: usize, sign: f64) {
    for r in rows.chunks_exact(p) {
        for i in 0..p {
            let ri = sign * r[i];
            if ri == 0.0 {
                continue;
            }
            let line = &mut m[i * p..i * p + i + 1];
            for (x, y) in line.iter_mut().zip(&r[..=i]) {
                *x += ri * y;
            }
        }
    }
}

/// The Cholesky factor of the symmetric `a` (`n × n` row-major, lower triangle read), in place;
/// `false` where `a` is not positive definite.
pub(super) fn cholesky_in_place(a: &mut [f64], n: usize) -> bool {
    for j in 0..n {
        let mut d = a[j * n + j];
        for k in 0..j {
            d -= a[j * n + k] * a[j * n + k];
        }
        if !(d > 0.0 && d.is_finite()) {
            return false;
        }
        let d = d.sqrt();
        a[j * n + j] = d;
        for i in j + 1..n {
            let mut s = a[i * n + j];
            for k in 0..j {
                s -= a[i * n + k] * a[j * n + k];
            }
            a[i * n + j] = s / d;
        }
    }
    true
}

/// `trace(A⁻¹) = ‖L⁻¹‖²_F` from the factor `l` of `A` ([`cholesky_in_place`]); `column` is scratch of
/// `n`.
fn trace_inverse(l: &[f64], n: usize, column: &mut [f64]) -> f64 {
    let mut sum = 0.0;
    for j in 0..n {
        // Column j of L⁻¹ by forward substitution (zero above the diagonal).
        column[j] = 1.0 / l[j * n + j];
        sum += column[j] * column[j];
        for i in j + 1..n {
            let mut s = 0.0;
            for k in j..i {
                s += l[i * n + k] * column[k];
            }
            column[i] = -s / l[i * n + i];
            sum += column[i] * column[i];
        }
    }
    sum
}

/// `trace(A⁻¹)` of the symmetric `a` (lower triangle read), infinite where it is not positive
/// definite; `work` is scratch of `n² + n`.
fn criterion_of(a: &[f64], n: usize, work: &mut [f64]) -> f64 {
    let (factor, column) = work.split_at_mut(n * n);
    factor.copy_from_slice(a);
    if cholesky_in_place(factor, n) {
        trace_inverse(factor, n, column)
    } else {
        f64::INFINITY
    }
}

/// The candidate (of `0..candidates`, not in the design) whose swap for design member `a` lowers the
/// criterion of `m` (the design's information; `partial`: each candidate's `H_x`) most below
/// `current` by more than rounding; none where no swap does (or every trial is singular).
fn best_swap(
    rows: &Rows,
    m: &[f64],
    partial: &[Vec<f64>],
    a: usize,
    in_design: &[bool],
    candidates: usize,
    current: f64,
) -> Option<usize> {
    let (p, reflectors) = (rows.p, rows.reflectors);
    // M − H_a: the design without a.
    let mut without = m.to_vec();
    for (x, h) in without.iter_mut().zip(&partial[a]) {
        *x -= h;
    }
    let trials: Vec<(usize, f64)> = (0..candidates)
        .into_par_iter()
        .filter(|&c| !in_design[c])
        .map_init(
            || (vec![0.0; p * p], vec![0.0; reflectors * p], vec![0.0; p]),
            |(trial, scratch, column), c| {
                for ((t, w), h) in trial.iter_mut().zip(&without).zip(&partial[c]) {
                    *t = w + h;
                }
                rows.add_pair(trial, c, a, -1.0, scratch);
                let value = if cholesky_in_place(trial, p) {
                    trace_inverse(trial, p, column)
                } else {
                    f64::INFINITY
                };
                (c, value)
            },
        )
        .collect();
    trials
        .into_iter()
        .min_by(|x, y| x.1.total_cmp(&y.1))
        .filter(|&(_, value)| value < current * (1.0 - 1e-9))
        .map(|(c, _)| c)
}

/// Exchange (module documentation) of the design `chosen` (indices into the pool of `points`/`jac`,
/// scaled Jacobians as for [`super::select_by_distances`]; `pool_info` is `P`): its first `fixed`
/// configurations stay (those already measured), the others may be swapped for any of the
/// candidates `0..candidates` not in the design. The design given back is never worse by the
/// criterion; it is the one given where `P` or the design's information is singular.
pub fn exchange(
    points: &[Vec<Vector3<f64>>],
    jac: &[DMatrix<f64>],
    pool_info: &DMatrix<f64>,
    chosen: &[usize],
    fixed: usize,
    candidates: usize,
) -> Exchange {
    let unchanged = |criterion: f64| Exchange {
        chosen: chosen.to_vec(),
        before: criterion,
        after: criterion,
        swaps: 0,
        sweeps: 0,
    };
    let Some(first) = jac.first() else {
        return unchanged(f64::INFINITY);
    };
    let (p, reflectors) = (first.ncols(), first.nrows() / 3);
    let pool = jac.len();
    let candidates = candidates.min(pool);
    // Whitening by P = L Lᵀ (a relative ridge where P is only semi-definite).
    let ridge = 1e-12 * pool_info.trace().max(f64::MIN_POSITIVE) / p.max(1) as f64;
    let whitening = (pool_info + DMatrix::<f64>::identity(p, p) * ridge).cholesky();
    let Some(whitening) = whitening else {
        return unchanged(f64::INFINITY);
    };
    let l = whitening.l();
    let mut whitened = Vec::with_capacity(pool);
    for j in jac {
        let Some(t) = l.solve_lower_triangular(&j.transpose()) else {
            return unchanged(f64::INFINITY);
        };
        // t = L⁻¹ Jᵀ (p × rows): row-major J L⁻ᵀ is t's column-major storage.
        whitened.push(t.as_slice().to_vec());
    }
    let rows = Rows {
        points,
        jac: whitened,
        p,
        reflectors,
    };
    // M's regularisation 1e-9 I, whitened: 1e-9 P⁻¹.
    let regularisation: Vec<f64> = whitening
        .inverse()
        .as_slice()
        .iter()
        .map(|v| v * 1e-9)
        .collect();
    let mut design = chosen.to_vec();
    let mut in_design = vec![false; pool];
    for &c in &design {
        in_design[c] = true;
    }
    let information = |design: &[usize]| -> Vec<f64> {
        let mut m = regularisation.clone();
        let mut scratch = vec![0.0; reflectors * p];
        for (k, &a) in design.iter().enumerate() {
            for &b in &design[..k] {
                rows.add_pair(&mut m, a, b, 1.0, &mut scratch);
            }
        }
        m
    };
    let mut work = vec![0.0; p * p + p];
    let mut m = information(&design);
    let before = criterion_of(&m, p, &mut work);
    if !before.is_finite() || design.len() <= fixed || design.len() < 2 {
        return unchanged(before);
    }
    // H_x for every candidate of the pool.
    let mut partial: Vec<Vec<f64>> = (0..pool)
        .into_par_iter()
        .map(|x| {
            let mut h = vec![0.0; p * p];
            let mut scratch = vec![0.0; reflectors * p];
            for &j in &design {
                rows.add_pair(&mut h, x, j, 1.0, &mut scratch);
            }
            h
        })
        .collect();
    let (mut current, mut swaps, mut sweeps) = (before, 0, 0);
    while sweeps < MAX_SWEEPS {
        sweeps += 1;
        let mut swapped = false;
        for position in fixed..design.len() {
            let a = design[position];
            let Some(c) = best_swap(&rows, &m, &partial, a, &in_design, candidates, current) else {
                continue;
            };
            // Swap a → c: every H_x loses the pair (x, a) and gains (x, c).
            partial.par_iter_mut().enumerate().for_each_init(
                || vec![0.0; reflectors * p],
                |scratch, (x, h)| {
                    rows.add_pair(h, x, c, 1.0, scratch);
                    rows.add_pair(h, x, a, -1.0, scratch);
                },
            );
            in_design[a] = false;
            in_design[c] = true;
            design[position] = c;
            m = information(&design);
            current = criterion_of(&m, p, &mut work);
            swaps += 1;
            swapped = true;
        }
        if !swapped {
            break;
        }
    }
    Exchange {
        chosen: design,
        before,
        after: current,
        swaps,
        sweeps,
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::plan::{i_criterion, pair_information, select_by_distances, synthetic_pool};

    /// On a small made-up pool, from every pair of first picks: the exchange never worsens the
    /// greedy design, its criterion is the one computed afresh, and no single swap improves on it
    /// (checked by trying every one). From a start of two candidates at the same positions (no
    /// distance between them) it finds a strictly better design; the fixed positions stay.
    #[test]
    fn the_exchange_never_worsens_the_greedy_design_and_improves_a_poor_start() {
        let (mut points, mut jac) = synthetic_pool(14, 1, 4, 7);
        points.push(points[0].clone());
        jac.push(jac[0].clone());
        let pool = points.len();
        let info = pair_information(&points, &jac);
        let criterion = |design: &[usize]| i_criterion(&points, &jac, &info, design);
        let n = 5;
        for a in 0..pool {
            for b in a + 1..pool {
                let greedy = select_by_distances(&points, &jac, &info, n, &[a, b]);
                let e = exchange(&points, &jac, &info, &greedy, 0, pool);
                let (before, after) = (criterion(&greedy), criterion(&e.chosen));
                assert!(
                    after <= before * (1.0 + 1e-9),
                    "{a}, {b}: {after} > {before}"
                );
                assert!(
                    (e.after - after).abs() <= 1e-6 * after,
                    "{} vs {after}",
                    e.after
                );
                assert!((e.before - before).abs() <= 1e-6 * before);
                assert!(e.sweeps <= MAX_SWEEPS);
                for position in 0..n {
                    for c in (0..pool).filter(|c| !e.chosen.contains(c)) {
                        let mut swapped = e.chosen.clone();
                        swapped[position] = c;
                        assert!(
                            criterion(&swapped) >= after * (1.0 - 1e-6),
                            "{a}, {b}: swapping position {position} for {c} improves"
                        );
                    }
                }
            }
        }
        let poor = select_by_distances(&points, &jac, &info, n, &[0, pool - 1]);
        let e = exchange(&points, &jac, &info, &poor, 0, pool);
        assert!(e.swaps >= 1);
        assert!(
            criterion(&e.chosen) < 0.99 * criterion(&poor),
            "{} vs {}",
            criterion(&e.chosen),
            criterion(&poor)
        );
        let kept = exchange(&points, &jac, &info, &poor, 2, pool);
        assert_eq!(kept.chosen[..2], poor[..2]);
        assert!(criterion(&kept.chosen) <= criterion(&poor));
        // Candidates beyond `candidates` never enter.
        let limited = exchange(&points, &jac, &info, &poor, 0, 8);
        assert!(limited.chosen.iter().all(|c| *c < 8 || poor.contains(c)));
    }
}
