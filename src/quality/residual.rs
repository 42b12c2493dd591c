//! The model-based check: how far each configuration's reflectors seem displaced, given a model,
//! from their distances to all the other configurations of the arm — and, for a suspect row, which
//! simple mistake (swapped labels, swapped joint columns, a row of the other arm) would explain it.
//!
//! For configuration `i`, reflector `k` and every other configuration `j`:
//! `Δd_ij = |m_i − m_j| − |p_i − p_j|` (measured minus model distance) and, to first order,
//! `Δd_ij ≈ w_ij · e_i − w_ij · e_j` with `w_ij` the unit measured direction from `j` to `i` and `e` the
//! measurement errors. Treating the others' errors as noise, `e_i` is the Huber (robust least-squares)
//! fit of `w_ij · e_i` to the `Δd_ij`: the others' gross errors are down-weighted, so one bad row does
//! not smear over the good ones.
//!
//! **Cost.** A fit is `O(partners)`: its rows are built once per configuration and reflector into
//! reused column buffers (no allocation per configuration or pair), the least-squares sums once, and
//! each re-weighting only revisits the rows beyond the Huber threshold (all of them when more than a
//! quarter are). Up to [`MAX_PARTNERS`]
//! configurations per arm every other one is a partner (`O(n²)` per arm); beyond it every k-th, so
//! that the screening of large datasets grows as `n · MAX_PARTNERS`.

use super::triangle::RELABELLINGS;
use super::{Flag, FlagKind, ScreenSettings, mpe_mm};
use crate::dataset::{Dataset, Measurement};
use crate::kinematics::{ArmModel, DualArmModel, PerReflector};
use crate::par::prelude::*;
use crate::side::{ConfigId, PerSide, Side};
use crate::stats::{mad_sigma_in_place, median_in_place};
use nalgebra::{Matrix3, Vector3};
use std::cell::RefCell;

/// Fewer configurations than this give no reliable residual screening.
pub const MIN_CONFIGS: usize = 10;
/// Median of the χ distribution with 3 degrees of freedom: `median |e| = 1.5382 σ` for an isotropic
/// Gaussian error of σ per axis.
const CHI3_MEDIAN: f64 = 1.5382;
/// Huber threshold of the pair residuals, in robust standard deviations.
const HUBER_K: f64 = 2.0;
/// Re-weighting iterations, at most.
const IRLS_ITERATIONS: usize = 8;
/// The re-weighting stops early once an iteration moves the estimate by less than this, mm (a
/// picometre: nine orders of magnitude below a tracker's noise, far below any figure printed).
const IRLS_TOLERANCE_MM: f64 = 1e-9;
/// Pairs per reflector used for the residual scale.
const SCALE_PAIRS: usize = 50_000;
/// Each configuration's displacement is fitted against at most this many others of its arm: all of
/// them up to this size, else every k-th (evenly spread over the file), so that the screening grows
/// as n, not n², beyond it. Its estimate's noise then is that of a fit to 1000–2000 distances, far
/// below the tracker's MPE that bounds the threshold from below.
pub const MAX_PARTNERS: usize = 2048;
/// Partial sums kept side by side in the pair loops (SIMD lanes).
const LANES: usize = 2;

/// One arm's measured and model points, and the robust scale of its distance errors per reflector.
pub struct ArmResiduals {
    pub side: Side,
    /// Measured points (tracker frame) and model points (the arm's base frame), per configuration.
    pub measured: Vec<Vec<Vector3<f64>>>,
    pub model: Vec<Vec<Vector3<f64>>>,
    /// Robust standard deviation of the pair distance errors Δd per reflector, mm.
    pub sigma_mm: PerReflector<f64>,
    /// Every `stride`-th configuration is a partner of the displacement fits ([`MAX_PARTNERS`]).
    stride: usize,
    /// The partners' points per reflector, coordinate by coordinate, for the pair loops.
    columns: Vec<PointColumns>,
}

/// One reflector's measured and model points of the partner configurations, as columns.
#[derive(Default)]
struct PointColumns {
    measured: [Vec<f64>; 3],
    model: [Vec<f64>; 3],
}

impl PointColumns {
    fn new(
        measured: &[Vec<Vector3<f64>>],
        model: &[Vec<Vector3<f64>>],
        k: usize,
        stride: usize,
    ) -> Self {
        let column = |points: &[Vec<Vector3<f64>>], axis: usize| -> Vec<f64> {
            points.iter().step_by(stride).map(|p| p[k][axis]).collect()
        };
        Self {
            measured: std::array::from_fn(|a| column(measured, a)),
            model: std::array::from_fn(|a| column(model, a)),
        }
    }
}

/// The rows `(w, r)` of one displacement fit, as columns: `r ≈ w · e` (unused rows are zero).
#[derive(Default)]
struct FitRows {
    w: [Vec<f64>; 3],
    r: Vec<f64>,
    /// Scratch: each row's residual at the current estimate.
    residuals: Vec<f64>,
}

thread_local! {
    /// Each thread's rows, reused from one fit to the next (no allocation per configuration).
    static ROWS: RefCell<FitRows> = RefCell::new(FitRows::default());
}

impl ArmResiduals {
    /// All configurations of `side` (every split) with `arm`'s forward kinematics.
    pub fn new(dataset: &Dataset, arm: &ArmModel, side: Side) -> Self {
        let ms = &dataset.arm(side).measurements;
        let measured: Vec<Vec<Vector3<f64>>> =
            ms.iter().map(|m| m.tracker_points_mm.clone()).collect();
        let model: Vec<Vec<Vector3<f64>>> = ms
            .par_iter()
            .map(|m| arm.reflector_fk(&m.q_rad).points_mm)
            .collect();
        let n = ms.len();
        let reflectors = arm.reflector_count();
        let floor = mpe_mm(dataset, side);
        // The reflectors' scales side by side, each from every configuration's points as columns
        // (`|m_i − m_j| − |p_i − p_j|` in nalgebra's order: the same numbers, in the same order).
        let scales: Vec<f64> = (0..reflectors)
            .into_par_iter()
            .map(|k| {
                let all = PointColumns::new(&measured, &model, k, 1);
                let ([mx, my, mz], [px, py, pz]) = (&all.measured, &all.model);
                let norm = |x: f64, y: f64, z: f64| (x * x + y * y + z * z).sqrt();
                let mut dd = Vec::with_capacity(SCALE_PAIRS.min(n * n.saturating_sub(1) / 2));
                super::sampled_pairs(n, n, true, SCALE_PAIRS, |i, j| {
                    dd.push(
                        norm(mx[i] - mx[j], my[i] - my[j], mz[i] - mz[j])
                            - norm(px[i] - px[j], py[i] - py[j], pz[i] - pz[j]),
                    );
                });
                mad_sigma_in_place(&mut dd).max(floor)
            })
            .collect();
        let sigma_mm = PerReflector::from_slice(&scales);
        let stride = n.div_ceil(MAX_PARTNERS).max(1);
        let columns = (0..reflectors)
            .map(|k| PointColumns::new(&measured, &model, k, stride))
            .collect();
        Self {
            side,
            measured,
            model,
            sigma_mm,
            stride,
            columns,
        }
    }

    /// Configurations of the arm.
    pub fn len(&self) -> usize {
        self.measured.len()
    }

    pub fn is_empty(&self) -> bool {
        self.measured.is_empty()
    }

    /// The configurations the displacement fits use (every one up to [`MAX_PARTNERS`]).
    pub fn partners(&self) -> impl Iterator<Item = usize> + '_ {
        (0..self.len()).step_by(self.stride)
    }

    /// The robust displacement estimate of each reflector of a row with measured points `m` and model
    /// points `p`, against the arm's configurations ([`ArmResiduals::partners`]) but `skip`, mm
    /// (tracker frame).
    pub fn displacement(
        &self,
        m: &[Vector3<f64>],
        p: &[Vector3<f64>],
        skip: Option<usize>,
    ) -> PerReflector<Vector3<f64>> {
        // The row of `skip` among the partners, if it is one.
        let skip = skip
            .filter(|s| s % self.stride == 0)
            .map(|s| s / self.stride);
        ROWS.with(|rows| {
            let mut fresh = FitRows::default();
            let mut borrowed = rows.try_borrow_mut();
            let rows = borrowed.as_deref_mut().unwrap_or(&mut fresh);
            PerReflector::from_fn(self.columns.len(), |k| {
                self.fill_rows(rows, k, &m[k], &p[k], skip);
                huber_fit(rows, HUBER_K * self.sigma_mm[k])
            })
        })
    }

    /// [`ArmResiduals::displacement`] of configuration `i` as measured.
    pub fn displacement_of(&self, i: usize) -> PerReflector<Vector3<f64>> {
        self.displacement(&self.measured[i], &self.model[i], Some(i))
    }

    /// The rows of reflector `k`'s fit for a row measured at `m` with model point `p`: for every
    /// partner `j` the unit measured direction `w` from `j` and the distance error `r` (zero for the
    /// partner row `skip` and for a coincident point, which then add nothing to the fit).
    fn fill_rows(
        &self,
        rows: &mut FitRows,
        k: usize,
        m: &Vector3<f64>,
        p: &Vector3<f64>,
        skip: Option<usize>,
    ) {
        let c = &self.columns[k];
        let n = c.measured[0].len();
        for v in rows.w.iter_mut().chain([&mut rows.r]) {
            // Every element is written below: only a buffer of another length is reset.
            if v.len() != n {
                v.clear();
                v.resize(n, 0.0);
            }
        }
        let [wx, wy, wz] = &mut rows.w;
        fill_columns(m, p, c, wx, wy, wz, &mut rows.r);
        let r = &mut rows.r;
        if let Some(s) = skip.filter(|&s| s < n) {
            wx[s] = 0.0;
            wy[s] = 0.0;
            wz[s] = 0.0;
            r[s] = 0.0;
        }
    }
}

/// The rows of one fit: for every partner `j` (columns `c`) the unit measured direction `w` from it
/// to `m` and the distance error `r` against the model point `p`; zero for a coincident point.
fn fill_columns(
    m: &Vector3<f64>,
    p: &Vector3<f64>,
    c: &PointColumns,
    wx: &mut [f64],
    wy: &mut [f64],
    wz: &mut [f64],
    r: &mut [f64],
) {
    let n = c.measured[0].len();
    let (mx, my, mz) = (
        &c.measured[0][..n],
        &c.measured[1][..n],
        &c.measured[2][..n],
    );
    let (px, py, pz) = (&c.model[0][..n], &c.model[1][..n], &c.model[2][..n]);
    let (wx, wy, wz, r) = (&mut wx[..n], &mut wy[..n], &mut wz[..n], &mut r[..n]);
    for j in 0..n {
        let (vx, vy, vz) = (m.x - mx[j], m.y - my[j], m.z - mz[j]);
        let dm = (vx * vx + vy * vy + vz * vz).sqrt();
        let (ux, uy, uz) = (p.x - px[j], p.y - py[j], p.z - pz[j]);
        let dp = (ux * ux + uy * uy + uz * uz).sqrt();
        // A NaN distance is not above the bound: left out too.
        let used = dm > 1e-9;
        let (inv, rj) = (1.0 / dm, dm - dp);
        let inv = if used { inv } else { 0.0 };
        wx[j] = vx * inv;
        wy[j] = vy * inv;
        wz[j] = vz * inv;
        r[j] = if used { rj } else { 0.0 };
    }
}

/// Running sums of the normal equations, [`LANES`] partial sums each: `Σ ω w wᵀ` (upper triangle xx,
/// xy, xz, yy, yz, zz) and `Σ ω r w`.
#[derive(Clone, Copy, Default)]
struct NormalSums([[f64; LANES]; 9]);

impl NormalSums {
    #[inline(always)]
    fn add(&mut self, l: usize, omega: f64, x: f64, y: f64, z: f64, r: f64) {
        let (ox, oy, oz, or) = (omega * x, omega * y, omega * z, omega * r);
        let a = &mut self.0;
        a[0][l] += ox * x;
        a[1][l] += ox * y;
        a[2][l] += ox * z;
        a[3][l] += oy * y;
        a[4][l] += oy * z;
        a[5][l] += oz * z;
        a[6][l] += or * x;
        a[7][l] += or * y;
        a[8][l] += or * z;
    }

    /// The matrix and the right-hand side.
    fn finish(&self) -> (Matrix3<f64>, Vector3<f64>) {
        let [xx, xy, xz, yy, yz, zz, bx, by, bz]: [f64; 9] =
            std::array::from_fn(|s| self.0[s].iter().sum());
        (
            Matrix3::new(xx, xy, xz, xy, yy, yz, xz, yz, zz),
            Vector3::new(bx, by, bz),
        )
    }
}

/// The ordinary least-squares normal equations of `r ≈ w · e` over all rows.
fn normal_equations(rows: &FitRows) -> (Matrix3<f64>, Vector3<f64>) {
    let [wx, wy, wz] = &rows.w;
    let mut sums = NormalSums::default();
    let chunks = wx
        .chunks_exact(LANES)
        .zip(wy.chunks_exact(LANES))
        .zip(wz.chunks_exact(LANES))
        .zip(rows.r.chunks_exact(LANES));
    for (((x, y), z), r) in chunks {
        for l in 0..LANES {
            sums.add(l, 1.0, x[l], y[l], z[l], r[l]);
        }
    }
    for j in wx.len() - wx.len() % LANES..wx.len() {
        sums.add(0, 1.0, wx[j], wy[j], wz[j], rows.r[j]);
    }
    sums.finish()
}

/// The Huber-weighted normal equations at `e` (threshold `c`): a row whose residual exceeds `c` has
/// weight `ω = c / |res|` instead of 1. The residuals of all rows are written to `residuals` first, in
/// a loop without branches. When few rows are beyond `c` (a few in a hundred on data that fit), the
/// least-squares equations `(a_all, b_all)` less `(1 − ω)` of those rows' terms; when many are (a row
/// of another arm, whose every distance is off), the weighted sums over all rows, so that nothing
/// cancels.
fn huber_equations(
    rows: &FitRows,
    (a_all, b_all): (&Matrix3<f64>, &Vector3<f64>),
    e: &Vector3<f64>,
    c: f64,
    residuals: &mut Vec<f64>,
) -> (Matrix3<f64>, Vector3<f64>) {
    let [wx, wy, wz] = &rows.w;
    let n = wx.len();
    let (wx, wy, wz, r) = (&wx[..n], &wy[..n], &wz[..n], &rows.r[..n]);
    residuals.clear();
    residuals.extend((0..n).map(|j| (r[j] - (wx[j] * e.x + wy[j] * e.y + wz[j] * e.z)).abs()));
    let residuals = &residuals[..n];
    // A NaN residual counts as beyond: it spoils the fit, as its weight would.
    let beyond = |res: f64| res > c || res.is_nan();
    let many = 4 * residuals.iter().filter(|&&res| beyond(res)).count() > n;
    let mut sums = NormalSums::default();
    if many {
        let weight = |res: f64| if beyond(res) { c / res } else { 1.0 };
        for j in 0..n {
            sums.add(j % LANES, weight(residuals[j]), wx[j], wy[j], wz[j], r[j]);
        }
        return sums.finish();
    }
    for (j, &res) in residuals.iter().enumerate() {
        if beyond(res) {
            sums.add(0, 1.0 - c / res, wx[j], wy[j], wz[j], r[j]);
        }
    }
    let (da, db) = sums.finish();
    (a_all - da, b_all - db)
}

/// Huber fit of `e` to rows `(w, r)` with `r ≈ w · e`: iteratively re-weighted least squares from the
/// ordinary least-squares start, until an iteration moves `e` by less than [`IRLS_TOLERANCE_MM`] or
/// after [`IRLS_ITERATIONS`].
fn huber_fit(rows: &mut FitRows, c: f64) -> Vector3<f64> {
    let solve = |a: Matrix3<f64>, b: Vector3<f64>| a.try_inverse().map(|inv| inv * b);
    let (a_all, b_all) = normal_equations(rows);
    let Some(mut e) = solve(a_all, b_all) else {
        return Vector3::repeat(f64::NAN);
    };
    let mut residuals = std::mem::take(&mut rows.residuals);
    for _ in 0..IRLS_ITERATIONS {
        let (a, b) = huber_equations(rows, (&a_all, &b_all), &e, c, &mut residuals);
        let Some(next) = solve(a, b) else {
            break;
        };
        let moved = (next - e).amax();
        e = next;
        if moved <= IRLS_TOLERANCE_MM {
            break;
        }
    }
    rows.residuals = residuals;
    e
}

/// Largest of the reflectors' displacements and its reflector.
fn largest(e: &[Vector3<f64>]) -> (f64, usize) {
    e.iter().enumerate().fold(
        (0.0, 0),
        |b, (k, v)| if v.norm() > b.0 { (v.norm(), k) } else { b },
    )
}

/// Both arms' points under `model` and the scale of their distance errors: what the residual flags
/// and the moved-tracker check of one screening share (computed once per arm and model).
pub fn fits(dataset: &Dataset, model: &DualArmModel) -> PerSide<ArmResiduals> {
    PerSide::par_from_fn(|side| ArmResiduals::new(dataset, model.arm(side), side))
}

/// Every configuration's displacement estimate.
fn estimates(fit: &ArmResiduals) -> Vec<PerReflector<Vector3<f64>>> {
    (0..fit.len())
        .into_par_iter()
        .map(|i| fit.displacement_of(i))
        .collect()
}

/// The displacement estimates of every configuration of `side` under `model`, and the flag threshold,
/// mm; `None` with fewer than [`MIN_CONFIGS`] configurations.
pub fn displacements(
    dataset: &Dataset,
    model: &DualArmModel,
    side: Side,
    settings: &ScreenSettings,
) -> Option<(Vec<PerReflector<Vector3<f64>>>, f64)> {
    if dataset.arm(side).measurements.len() < MIN_CONFIGS {
        return None;
    }
    let e = estimates(&ArmResiduals::new(dataset, model.arm(side), side));
    let tau = threshold(dataset, side, &e, settings);
    Some((e, tau))
}

fn threshold(
    dataset: &Dataset,
    side: Side,
    e: &[PerReflector<Vector3<f64>>],
    settings: &ScreenSettings,
) -> f64 {
    let mut sizes: Vec<f64> = e.iter().flat_map(|v| v.iter()).map(|v| v.norm()).collect();
    let sigma = median_in_place(&mut sizes) / CHI3_MEDIAN;
    (settings.residual_k * sigma).max(settings.mpe_floor * mpe_mm(dataset, side))
}

/// The residual flags of one arm under `model`, each explained where a simple mistake fits.
pub fn flags(
    dataset: &Dataset,
    model: &DualArmModel,
    side: Side,
    settings: &ScreenSettings,
) -> Vec<Flag> {
    flags_with(dataset, model, &fits(dataset, model), side, settings)
}

/// [`flags`] with both arms' [`fits`] under `model` at hand.
pub(crate) fn flags_with(
    dataset: &Dataset,
    model: &DualArmModel,
    fits: &PerSide<ArmResiduals>,
    side: Side,
    settings: &ScreenSettings,
) -> Vec<Flag> {
    let n = dataset.arm(side).measurements.len();
    if n < MIN_CONFIGS {
        return Vec::new();
    }
    let fit = &fits[side];
    let e = estimates(fit);
    let tau = threshold(dataset, side, &e, settings);
    let other =
        (dataset.arm(side.other()).measurements.len() >= MIN_CONFIGS).then(|| &fits[side.other()]);
    let suspects: Vec<usize> = (0..n)
        .filter(|&i| {
            let (size, _) = largest(&e[i]);
            size > tau || size.is_nan()
        })
        .collect();
    suspects
        .into_par_iter()
        .map(|i| {
            let m = &dataset.arm(side).measurements[i];
            let (size, k) = largest(&e[i]);
            let size = if size.is_nan() { f64::INFINITY } else { size };
            let repair = explain(fit, other, model, m, i, size, tau);
            let (kind, reflector, reason) = match repair {
                Some((kind, what, after)) => (
                    kind,
                    None,
                    format!(
                        "{what}: its reflectors seem displaced by up to {size:.3} mm as measured \
                         (threshold {tau:.3} mm), by {after:.3} mm with that correction"
                    ),
                ),
                None => {
                    let single = e[i]
                        .iter()
                        .enumerate()
                        .all(|(j, v)| j == k || v.norm() <= tau);
                    let names = &dataset.reflector_names;
                    let what = if single {
                        format!("reflector {} seems displaced by {size:.3} mm", names[k])
                    } else {
                        let sizes: Vec<String> =
                            e[i].iter().map(|v| format!("{:.3}", v.norm())).collect();
                        format!(
                            "its reflectors seem displaced by {} mm ({})",
                            sizes.join(", "),
                            names.join(", ")
                        )
                    };
                    (
                        FlagKind::Residual,
                        single.then_some(k),
                        format!(
                            "{what}: its distances to the other configurations do not fit the model \
                             (threshold {tau:.3} mm)"
                        ),
                    )
                }
            };
            Flag {
                config: ConfigId::new(side, i),
                id: m.id.clone(),
                line: m.line,
                split: m.split,
                kind,
                size_mm: size,
                threshold_mm: tau,
                reflector,
                reason,
            }
        })
        .collect()
}

/// A simple mistake that makes row `i` fit: its labels permuted, two of its joint columns swapped, or
/// the row belonging to the other arm. Returns the kind, a description and the largest displacement
/// after the correction, if it brings the row within the threshold and to well below its size.
fn explain(
    fit: &ArmResiduals,
    other: Option<&ArmResiduals>,
    model: &DualArmModel,
    m: &Measurement,
    i: usize,
    size: f64,
    tau: f64,
) -> Option<(FlagKind, String, f64)> {
    let arm = model.arm(fit.side);
    let mut candidates: Vec<(FlagKind, String, f64)> = Vec::new();
    // Relabellings of three reflectors (two swapped keep their distances: nothing to tell by).
    let relabellings = if m.tracker_points_mm.len() == 3 {
        &RELABELLINGS[..]
    } else {
        &[]
    };
    for (perm, name) in relabellings {
        let e = fit.displacement(
            &perm.map(|k| m.tracker_points_mm[k]),
            &fit.model[i],
            Some(i),
        );
        candidates.push((
            FlagKind::LabelsSwapped,
            format!("reflector labels look swapped ({name})"),
            largest(&e).0,
        ));
    }
    let nq = m.q_rad.len();
    for a in 0..nq {
        for b in a + 1..nq {
            let mut q = m.q_rad.clone();
            q.swap(a, b);
            let p = arm.reflector_fk(&q).points_mm;
            let e = fit.displacement(&m.tracker_points_mm, &p, Some(i));
            candidates.push((
                FlagKind::JointsSwapped,
                format!(
                    "joint columns q{} and q{} look swapped in this row",
                    a + 1,
                    b + 1
                ),
                largest(&e).0,
            ));
        }
    }
    if let Some(other) = other {
        let p = model.arm(other.side).reflector_fk(&m.q_rad).points_mm;
        let e = other.displacement(&m.tracker_points_mm, &p, None);
        candidates.push((
            FlagKind::OtherArm,
            format!(
                "this row fits the {} arm's measurements: a row of the other arm's file?",
                other.side
            ),
            largest(&e).0,
        ));
    }
    candidates
        .into_iter()
        .filter(|c| c.2.is_finite() && c.2 <= tau && c.2 < 0.25 * size)
        .min_by(|a, b| a.2.total_cmp(&b.2))
}
