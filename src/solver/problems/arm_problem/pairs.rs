//! The pair passes of the distance problems — the only part of an SQP iteration that grows as n².
//!
//! Per pair and reflector: the model distance d = |p_i − p_j|, the measured one d_m = |m_i − m_j|
//! (kept up to [`KEPT_DISTANCE_PAIRS`] pairs per reflector, recomputed beyond: bounded memory),
//! Δd = d_m − d, Σ Δd², and the per-configuration
//! weights `t_ij = (p_i − p_j) Δd / d` that the gradients are regrouped by (eq. 34; step 2 likewise).
//! Points are kept as struct-of-arrays ([`Points`]) so the inner loop runs in SIMD lanes.
//!
//! Summation order: step 1's passes, up to [`SEQUENTIAL_PAIRS`] pairs per reflector (the paper's size:
//! 7 140 pairs per arm), are one sequential pass in the order of earlier releases — step 1 is
//! bit-identical to theirs. Beyond, and step 2's passes at every size ([`rectangle`]), [`BLOCKS`]
//! blocks of rows with (nearly) equal pair counts, fixed by n alone, summed in [`LANES`] partial sums
//! each and run in parallel; the blocks are reduced in order, so the results do not depend on the
//! number of threads.

use crate::par::prelude::*;
use nalgebra::Vector3;
use std::ops::Range;

/// Pairs per reflector up to which a pass is one sequential sum in the order of earlier releases.
pub const SEQUENTIAL_PAIRS: usize = 1 << 17;
/// Pairs per reflector up to which the measured distances are computed once and kept (8 bytes a
/// pair: 32 MiB per reflector at most; n ≈ 2 900 configurations per arm). Beyond, each pass recomputes
/// them from the measured points (no per-pair memory: 2 × 5000 configurations peak at ~40 MB instead
/// of ~0.9 GB), at the cost of a second square root per pair. Kept or recomputed, a distance is the
/// same number ([`Points::distance`]), so the sums are the same to the bit.
pub const KEPT_DISTANCE_PAIRS: usize = 1 << 22;
/// Row blocks of a larger pass.
pub const BLOCKS: usize = 16;
/// Partial sums per block (SIMD lanes).
pub const LANES: usize = 4;

/// One reflector's point in every configuration, struct-of-arrays, mm.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Points {
    pub x: Vec<f64>,
    pub y: Vec<f64>,
    pub z: Vec<f64>,
}

impl Points {
    pub fn from_fn(n: usize, mut f: impl FnMut(usize) -> Vector3<f64>) -> Self {
        let mut p = Self::zeros(0);
        for i in 0..n {
            let v = f(i);
            p.x.push(v.x);
            p.y.push(v.y);
            p.z.push(v.z);
        }
        p
    }

    pub fn zeros(n: usize) -> Self {
        Self {
            x: vec![0.0; n],
            y: vec![0.0; n],
            z: vec![0.0; n],
        }
    }

    pub fn len(&self) -> usize {
        self.x.len()
    }

    pub fn get(&self, i: usize) -> Vector3<f64> {
        Vector3::new(self.x[i], self.y[i], self.z[i])
    }

    /// |p_i − p_j|, in nalgebra's order (`(p_i − p_j).norm()`).
    pub fn distance(&self, i: usize, j: usize) -> f64 {
        norm(
            self.x[i] - self.x[j],
            self.y[i] - self.y[j],
            self.z[i] - self.z[j],
        )
    }

    fn add(&mut self, other: &Points) {
        for (a, b) in [
            (&mut self.x, &other.x),
            (&mut self.y, &other.y),
            (&mut self.z, &other.z),
        ] {
            for (a, b) in a.iter_mut().zip(b) {
                *a += b;
            }
        }
    }
}

/// |a_i − b_j|, in nalgebra's order (`(a_i − b_j).norm()`).
pub fn distance_between(a: &Points, i: usize, b: &Points, j: usize) -> f64 {
    norm(a.x[i] - b.x[j], a.y[i] - b.y[j], a.z[i] - b.z[j])
}

/// `Vector3::norm` of (x, y, z), same rounding.
#[inline(always)]
fn norm(x: f64, y: f64, z: f64) -> f64 {
    (x * x + y * y + z * z).sqrt()
}

/// How a pass over `pairs` pairs per reflector is cut: one sequential block, or [`BLOCKS`] in lanes.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Plan {
    Sequential,
    Blocked,
}

impl Plan {
    pub fn for_pairs(pairs: usize) -> Self {
        if pairs <= SEQUENTIAL_PAIRS {
            Plan::Sequential
        } else {
            Plan::Blocked
        }
    }
}

/// Rows `0..n` of the pairs (i, j > i) cut into blocks of nearly equal pair counts.
pub fn triangle_blocks(n: usize, plan: Plan) -> Vec<Range<usize>> {
    if plan == Plan::Sequential || n < 2 {
        #[allow(clippy::single_range_in_vec_init)] // one block: all rows
        return vec![0..n];
    }
    let total = n * (n - 1) / 2;
    let mut blocks = Vec::with_capacity(BLOCKS);
    let (mut start, mut done) = (0, 0);
    for b in 1..=BLOCKS {
        let target = total * b / BLOCKS;
        let mut end = start;
        while end < n && done < target {
            done += n - 1 - end;
            end += 1;
        }
        if b == BLOCKS {
            end = n;
        }
        if end > start {
            blocks.push(start..end);
        }
        start = end;
    }
    blocks
}

/// Rows `0..n` cut into [`BLOCKS`] (nearly) equal blocks.
fn rectangle_blocks(n: usize, plan: Plan) -> Vec<Range<usize>> {
    if plan == Plan::Sequential {
        #[allow(clippy::single_range_in_vec_init)] // one block: all rows
        return vec![0..n];
    }
    (0..BLOCKS)
        .map(|b| n * b / BLOCKS..n * (b + 1) / BLOCKS)
        .filter(|r| !r.is_empty())
        .collect()
}

/// The lanes' partial sums, added in order.
#[inline(always)]
fn fold<const L: usize>(lanes: &[f64; L]) -> f64 {
    let mut s = lanes[0];
    for v in &lanes[1..] {
        s += v;
    }
    s
}

/// The measured distances |m_i − m_j| of every pair (i < j), row by row, per reflector — when there are
/// at most [`KEPT_DISTANCE_PAIRS`] pairs per reflector; `None` beyond (the passes recompute them).
pub fn kept_triangle_distances(measured: &[Points]) -> Option<Vec<Vec<f64>>> {
    let n = measured.first().map_or(0, Points::len);
    if n * n.saturating_sub(1) / 2 > KEPT_DISTANCE_PAIRS {
        return None;
    }
    Some(
        measured
            .iter()
            .map(|m| {
                let mut out = vec![0.0; n * n.saturating_sub(1) / 2];
                // Row i (the pairs (i, j), j > i) is n − i − 1 long: split the list into its rows, fill them
                // in parallel.
                let mut rows = Vec::with_capacity(n);
                let mut rest = &mut out[..];
                for i in 0..n {
                    let (row, tail) = rest.split_at_mut(n - i - 1);
                    rows.push(row);
                    rest = tail;
                }
                rows.into_par_iter().enumerate().for_each(|(i, row)| {
                    for (d, j) in row.iter_mut().zip(i + 1..n) {
                        *d = m.distance(i, j);
                    }
                });
                out
            })
            .collect(),
    )
}

/// The measured distances |m_l − n_r| of every pair (l, r), row by row, per reflector, when there are at
/// most [`KEPT_DISTANCE_PAIRS`] pairs per reflector.
pub fn kept_rectangle_distances(left: &[Points], right: &[Points]) -> Option<Vec<Vec<f64>>> {
    let (nl, nr) = (
        left.first().map_or(0, Points::len),
        right.first().map_or(0, Points::len),
    );
    if nl * nr > KEPT_DISTANCE_PAIRS {
        return None;
    }
    Some(
        (0..left.len().min(right.len()))
            .map(|k| {
                let mut out = vec![0.0; nl * nr];
                // Row l (the pairs (l, r)) is nr long: the rows filled in parallel.
                if nr > 0 {
                    out.par_chunks_mut(nr).enumerate().for_each(|(l, row)| {
                        for (r, d) in row.iter_mut().enumerate() {
                            *d = distance_between(&left[k], l, &right[k], r);
                        }
                    });
                }
                out
            })
            .collect(),
    )
}

/// Index of the pair (i, i + 1) in the row-by-row list of the pairs (i < j) of n points.
#[inline(always)]
fn row_start(i: usize, n: usize) -> usize {
    i * n - i * (i + 1) / 2
}

/// Row i of a pass: its model and measured points and, if kept, its measured distances
/// (`kept[j − first]` for the pair (i, j)).
struct Row<'a> {
    p: [f64; 3],
    m: [f64; 3],
    kept: &'a [f64],
    first: usize,
}

/// The pair (i, j) of `row` into lane `l`: Σ Δd² into `sum` and, with `W`, t_ij into `wi` (row i's
/// lanes) and −t_ij into `w[j]`. A function of its own (not a closure) so that it is always inlined
/// into the loops: a call per pair doubled the pass's instructions.
#[inline(always)]
#[allow(clippy::too_many_arguments)] // the loop's state, passed apart to keep the borrows disjoint
fn triangle_pair<const L: usize, const W: bool, const K: bool>(
    row: &Row,
    p: &Points,
    m: &Points,
    j: usize,
    l: usize,
    sum: &mut [f64; L],
    wi: &mut [[f64; L]; 3],
    w: &mut Points,
) {
    let (vx, vy, vz) = (row.p[0] - p.x[j], row.p[1] - p.y[j], row.p[2] - p.z[j]);
    let dist = norm(vx, vy, vz);
    let dm = if K {
        row.kept[j - row.first]
    } else {
        norm(row.m[0] - m.x[j], row.m[1] - m.y[j], row.m[2] - m.z[j])
    };
    let delta = dm - dist;
    sum[l] += delta * delta;
    if W {
        let s = if dist > 0.0 { delta / dist } else { 0.0 };
        let (tx, ty, tz) = (vx * s, vy * s, vz * s);
        wi[0][l] += tx;
        wi[1][l] += ty;
        wi[2][l] += tz;
        w.x[j] -= tx;
        w.y[j] -= ty;
        w.z[j] -= tz;
    }
}

/// Σ Δd² over the pairs (i, j > i) with i in `rows`, in `L` lanes; with `W`, `w_i += Σ_j t_ij` and
/// `w_j −= t_ij` into `w`. With `K`, the measured distances are read from `kept` (row by row, as
/// [`kept_triangle_distances`]) instead of recomputed.
fn triangle_rows<const L: usize, const W: bool, const K: bool>(
    p: &Points,
    m: &Points,
    kept: &[f64],
    rows: Range<usize>,
    w: &mut Points,
) -> f64 {
    let n = p.len();
    let mut sum = [0.0; L];
    for i in rows {
        let (pix, piy, piz) = (p.x[i], p.y[i], p.z[i]);
        let (mix, miy, miz) = (m.x[i], m.y[i], m.z[i]);
        // kept_row[j − i − 1] = |m_i − m_j| for j > i.
        let kept_row = if K {
            let start = row_start(i, n);
            &kept[start..start + (n - 1 - i)]
        } else {
            &[][..]
        };
        let row = Row {
            p: [pix, piy, piz],
            m: [mix, miy, miz],
            kept: kept_row,
            first: i + 1,
        };
        let mut wi = [[0.0; L]; 3];
        let mut j = i + 1;
        while j + L <= n {
            for l in 0..L {
                triangle_pair::<L, W, K>(&row, p, m, j + l, l, &mut sum, &mut wi, w);
            }
            j += L;
        }
        for (l, j) in (j..n).enumerate() {
            triangle_pair::<L, W, K>(&row, p, m, j, l, &mut sum, &mut wi, w);
        }
        if W {
            w.x[i] += fold(&wi[0]);
            w.y[i] += fold(&wi[1]);
            w.z[i] += fold(&wi[2]);
        }
    }
    fold(&sum)
}

/// The pass of one arm's step-1 problem over every pair (i < j) of each reflector: F_k = Σ Δd² and,
/// with `weights`, w_i,k = Σ_{j≠i} t_ij (signed so that ∇F_k = −2 Σ_i J_i,kᵀ w_i,k).
/// `kept`: the measured distances from [`kept_triangle_distances`], if kept.
pub fn triangle(
    model: &[Points],
    measured: &[Points],
    kept: Option<&[Vec<f64>]>,
    weights: bool,
    plan: Plan,
) -> Vec<(f64, Points)> {
    let n = model.first().map_or(0, Points::len);
    let blocks = triangle_blocks(n, plan);
    let tasks: Vec<(usize, Range<usize>)> = (0..model.len())
        .flat_map(|k| blocks.iter().map(move |b| (k, b.clone())))
        .collect();
    let run = |(k, rows): &(usize, Range<usize>)| {
        let (p, m) = (&model[*k], &measured[*k]);
        let mut w = Points::zeros(if weights { n } else { 0 });
        let r = rows.clone();
        let f = match (kept.map(|d| &d[*k][..]), plan, weights) {
            (None, Plan::Sequential, true) => triangle_rows::<1, true, false>(p, m, &[], r, &mut w),
            (None, Plan::Sequential, false) => {
                triangle_rows::<1, false, false>(p, m, &[], r, &mut w)
            }
            (None, Plan::Blocked, true) => {
                triangle_rows::<LANES, true, false>(p, m, &[], r, &mut w)
            }
            (None, Plan::Blocked, false) => {
                triangle_rows::<LANES, false, false>(p, m, &[], r, &mut w)
            }
            (Some(d), Plan::Sequential, true) => triangle_rows::<1, true, true>(p, m, d, r, &mut w),
            (Some(d), Plan::Sequential, false) => {
                triangle_rows::<1, false, true>(p, m, d, r, &mut w)
            }
            (Some(d), Plan::Blocked, true) => {
                triangle_rows::<LANES, true, true>(p, m, d, r, &mut w)
            }
            (Some(d), Plan::Blocked, false) => {
                triangle_rows::<LANES, false, true>(p, m, d, r, &mut w)
            }
        };
        (f, w)
    };
    let parts: Vec<(f64, Points)> = tasks.par_iter().map(run).collect();
    reduce(parts, model.len(), blocks.len())
}

/// Per reflector, the blocks' sums and weights added in block order.
fn reduce(
    parts: Vec<(f64, Points)>,
    reflectors: usize,
    per_reflector: usize,
) -> Vec<(f64, Points)> {
    let mut it = parts.into_iter();
    (0..reflectors)
        .map(|_| {
            let (mut f, mut w) = it.next().unwrap_or_default();
            for _ in 1..per_reflector {
                let (fb, wb) = it.next().unwrap_or_default();
                f += fb;
                w.add(&wb);
            }
            (f, w)
        })
        .collect()
}

/// The pair (l, r) of `row` (its model point already less t) into lane `k`: Σ Δd² into `sum`,
/// `a_r += t_lr` into `a`. Always inlined, as [`triangle_pair`].
#[inline(always)]
fn rectangle_pair<const L: usize, const K: bool>(
    row: &Row,
    right: &Points,
    measured_right: &Points,
    r: usize,
    k: usize,
    sum: &mut [f64; L],
    a: &mut Points,
) {
    let (vx, vy, vz) = (
        row.p[0] - right.x[r],
        row.p[1] - right.y[r],
        row.p[2] - right.z[r],
    );
    let dist = norm(vx, vy, vz);
    let dm = if K {
        row.kept[r - row.first]
    } else {
        norm(
            row.m[0] - measured_right.x[r],
            row.m[1] - measured_right.y[r],
            row.m[2] - measured_right.z[r],
        )
    };
    let delta = dm - dist;
    sum[k] += delta * delta;
    let s = if dist > 0.0 { delta / dist } else { 0.0 };
    a.x[r] += vx * s;
    a.y[r] += vy * s;
    a.z[r] += vz * s;
}

/// Σ Δd² over the pairs (l, r) with l in `rows`, Δd = |m_l − n_r| − |(p_l − t) − q_r|, in `L` lanes;
/// `a_r += t_lr` into `a`. With `K`, the measured distances are read from `kept` (row by row, as
/// [`kept_rectangle_distances`]).
#[allow(clippy::too_many_arguments)] // the pass's inputs, each a different array
fn rectangle_rows<const L: usize, const K: bool>(
    left: &Points,
    right: &Points,
    t: &Vector3<f64>,
    measured_left: &Points,
    measured_right: &Points,
    kept: &[f64],
    rows: Range<usize>,
    a: &mut Points,
) -> f64 {
    let nr = right.len();
    let mut sum = [0.0; L];
    for l in rows {
        let (px, py, pz) = (left.x[l] - t.x, left.y[l] - t.y, left.z[l] - t.z);
        let (mx, my, mz) = (measured_left.x[l], measured_left.y[l], measured_left.z[l]);
        let kept_row = if K {
            &kept[l * nr..(l + 1) * nr]
        } else {
            &[][..]
        };
        let row = Row {
            p: [px, py, pz],
            m: [mx, my, mz],
            kept: kept_row,
            first: 0,
        };
        let mut r = 0;
        while r + L <= nr {
            for k in 0..L {
                rectangle_pair::<L, K>(&row, right, measured_right, r + k, k, &mut sum, a);
            }
            r += L;
        }
        for (k, r) in (r..nr).enumerate() {
            rectangle_pair::<L, K>(&row, right, measured_right, r, k, &mut sum, a);
        }
    }
    fold(&sum)
}

/// The pass of step 2 over every pair (l, r) of each reflector: F_k = Σ Δd² and a_r,k = Σ_l t_lr,k,
/// with `left` the left arm's model points, `right` the right arm's rotated into the left base
/// (R q_r) and `t` the translation (the model point of r is R q_r + t). Always blocked: the sequential
/// order of earlier releases is [`crate::solver::base_problem`]'s own.
/// `kept`: the measured distances from [`kept_rectangle_distances`], if kept.
pub fn rectangle(
    left: &[Points],
    right: &[Points],
    t: &Vector3<f64>,
    measured_left: &[Points],
    measured_right: &[Points],
    kept: Option<&[Vec<f64>]>,
) -> Vec<(f64, Points)> {
    let blocks = rectangle_blocks(left.first().map_or(0, Points::len), Plan::Blocked);
    let nr = right.first().map_or(0, Points::len);
    let tasks: Vec<(usize, Range<usize>)> = (0..left.len())
        .flat_map(|k| blocks.iter().map(move |b| (k, b.clone())))
        .collect();
    let parts: Vec<(f64, Points)> = tasks
        .par_iter()
        .map(|(k, rows)| {
            let mut a = Points::zeros(nr);
            let (p, q, ml, mr) = (
                &left[*k],
                &right[*k],
                &measured_left[*k],
                &measured_right[*k],
            );
            let f = match kept {
                Some(d) => {
                    rectangle_rows::<LANES, true>(p, q, t, ml, mr, &d[*k], rows.clone(), &mut a)
                }
                None => rectangle_rows::<LANES, false>(p, q, t, ml, mr, &[], rows.clone(), &mut a),
            };
            (f, a)
        })
        .collect();
    reduce(parts, left.len(), blocks.len())
}

/// Σ_l u_lr u_lrᵀ for every r (u the unit model direction, as in [`rectangle`]): the six distinct
/// entries xx, xy, xz, yy, yz, zz per right configuration, for step 2's Gauss–Newton matrix.
pub fn rectangle_directions(left: &Points, right: &Points, t: &Vector3<f64>) -> [Vec<f64>; 6] {
    let nr = right.len();
    let blocks = rectangle_blocks(left.len(), Plan::Blocked);
    let parts: Vec<[Vec<f64>; 6]> = blocks
        .par_iter()
        .map(|rows| {
            let mut m: [Vec<f64>; 6] = std::array::from_fn(|_| vec![0.0; nr]);
            for l in rows.clone() {
                let (px, py, pz) = (left.x[l] - t.x, left.y[l] - t.y, left.z[l] - t.z);
                #[allow(clippy::needless_range_loop)] // r indexes several arrays of the same length
                for r in 0..nr {
                    let (vx, vy, vz) = (px - right.x[r], py - right.y[r], pz - right.z[r]);
                    let dist = norm(vx, vy, vz);
                    let inv = if dist > 0.0 { 1.0 / dist } else { 0.0 };
                    let (ux, uy, uz) = (vx * inv, vy * inv, vz * inv);
                    m[0][r] += ux * ux;
                    m[1][r] += ux * uy;
                    m[2][r] += ux * uz;
                    m[3][r] += uy * uy;
                    m[4][r] += uy * uz;
                    m[5][r] += uz * uz;
                }
            }
            m
        })
        .collect();
    let mut total: [Vec<f64>; 6] = std::array::from_fn(|_| vec![0.0; nr]);
    for part in parts {
        for (t, p) in total.iter_mut().zip(&part) {
            for (a, b) in t.iter_mut().zip(p) {
                *a += b;
            }
        }
    }
    total
}

#[cfg(test)]
mod tests {
    use super::*;

    fn cloud(n: usize, seed: u64) -> Points {
        let mut s = seed;
        let mut next = move || {
            s = s
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            (s >> 11) as f64 / (1u64 << 53) as f64 * 800.0 - 400.0
        };
        Points::from_fn(n, |_| Vector3::new(next(), next(), next()))
    }

    /// The definition, pair by pair.
    fn direct(p: &Points, m: &Points) -> (f64, Points) {
        let n = p.len();
        let mut w = Points::zeros(n);
        let mut f = 0.0;
        for i in 0..n {
            for j in i + 1..n {
                let v = p.get(i) - p.get(j);
                let delta = m.distance(i, j) - v.norm();
                f += delta * delta;
                let t = v * (delta / v.norm());
                for (c, wc) in [&mut w.x, &mut w.y, &mut w.z].into_iter().enumerate() {
                    wc[i] += t[c];
                    wc[j] -= t[c];
                }
            }
        }
        (f, w)
    }

    #[test]
    fn blocks_cover_every_row_once() {
        for n in [0, 1, 2, 3, 17, 100, 1001] {
            for plan in [Plan::Sequential, Plan::Blocked] {
                let b = triangle_blocks(n, plan);
                assert_eq!(b.first().map_or(0, |r| r.start), 0);
                assert_eq!(b.last().map_or(n, |r| r.end), n);
                assert!(b.windows(2).all(|w| w[0].end == w[1].start), "{n}: {b:?}");
                let r = rectangle_blocks(n, plan);
                assert_eq!(r.iter().map(|r| r.len()).sum::<usize>(), n);
            }
        }
        // Equal pair counts, to a row.
        let b = triangle_blocks(1000, Plan::Blocked);
        let pairs = |r: &Range<usize>| r.clone().map(|i| 999 - i).sum::<usize>();
        assert_eq!(b.len(), BLOCKS);
        assert!(b.iter().all(|r| pairs(r).abs_diff(499_500 / BLOCKS) < 1000));
    }

    #[test]
    fn both_plans_sum_the_definition() {
        let n = 203;
        let model: [Points; 3] = std::array::from_fn(|k| cloud(n, k as u64));
        let measured: [Points; 3] = std::array::from_fn(|k| cloud(n, 10 + k as u64));
        let kept = kept_triangle_distances(&measured).unwrap();
        for plan in [Plan::Sequential, Plan::Blocked] {
            let with = triangle(&model, &measured, None, true, plan);
            let without = triangle(&model, &measured, None, false, plan);
            // Kept or recomputed, the measured distances are the same numbers: the same sums.
            for weights in [true, false] {
                let recomputed = triangle(&model, &measured, None, weights, plan);
                let read = triangle(&model, &measured, Some(&kept), weights, plan);
                for k in 0..3 {
                    assert_eq!(read[k].0.to_bits(), recomputed[k].0.to_bits());
                    assert_eq!(read[k].1, recomputed[k].1);
                }
            }
            for k in 0..3 {
                let (f, w) = direct(&model[k], &measured[k]);
                assert!((with[k].0 - f).abs() < 1e-12 * f, "{plan:?}");
                assert_eq!(with[k].0, without[k].0);
                for (a, b) in
                    w.x.iter()
                        .chain(&w.y)
                        .chain(&w.z)
                        .zip(with[k].1.x.iter().chain(&with[k].1.y).chain(&with[k].1.z))
                {
                    assert!((a - b).abs() < 1e-9 * (1.0 + a.abs()), "{plan:?}: {a} {b}");
                }
            }
        }
        // The sequential plan is the pair loop of earlier releases, to the bit.
        let seq = triangle(&model, &measured, None, true, Plan::Sequential);
        for k in 0..3 {
            let (f, _) = direct(&model[k], &measured[k]);
            assert_eq!(seq[k].0.to_bits(), f.to_bits());
        }
    }

    #[test]
    fn the_rectangle_sums_the_definition() {
        let (nl, nr) = (37, 29);
        let left: [Points; 3] = std::array::from_fn(|k| cloud(nl, k as u64));
        let right: [Points; 3] = std::array::from_fn(|k| cloud(nr, 5 + k as u64));
        let ml: [Points; 3] = std::array::from_fn(|k| cloud(nl, 10 + k as u64));
        let mr: [Points; 3] = std::array::from_fn(|k| cloud(nr, 15 + k as u64));
        let t = Vector3::new(10.0, -20.0, 5.0);
        let got = rectangle(&left, &right, &t, &ml, &mr, None);
        let kept = kept_rectangle_distances(&ml, &mr).unwrap();
        let read = rectangle(&left, &right, &t, &ml, &mr, Some(&kept));
        for k in 0..3 {
            assert_eq!(read[k].0.to_bits(), got[k].0.to_bits());
            assert_eq!(read[k].1, got[k].1);
        }
        let dirs = rectangle_directions(&left[1], &right[1], &t);
        for k in 0..3 {
            let mut f = 0.0;
            let mut a = Points::zeros(nr);
            for l in 0..nl {
                for r in 0..nr {
                    let v = left[k].get(l) - right[k].get(r) - t;
                    let dm = (ml[k].get(l) - mr[k].get(r)).norm();
                    let delta = dm - v.norm();
                    f += delta * delta;
                    let tv = v * (delta / v.norm());
                    a.x[r] += tv.x;
                    a.y[r] += tv.y;
                    a.z[r] += tv.z;
                }
            }
            assert!((got[k].0 - f).abs() < 1e-12 * f);
            for (x, y) in a.x.iter().zip(&got[k].1.x) {
                assert!((x - y).abs() < 1e-9 * (1.0 + x.abs()));
            }
        }
        #[allow(clippy::needless_range_loop)] // r indexes several arrays of the same length
        for r in 0..nr {
            let mut xy = 0.0;
            for l in 0..nl {
                let u = (left[1].get(l) - right[1].get(r) - t).normalize();
                xy += u.x * u.y;
            }
            assert!((dirs[1][r] - xy).abs() < 1e-12 * nl as f64);
        }
    }
}
