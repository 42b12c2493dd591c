//! The absolute (tracker-frame) problems of the comparison methods: one arm's model and its base in
//! the tracker frame from the measured reflector positions (ref. \[18\], [`AbsoluteData::Position`]) or
//! from tool frames built from the three measured reflectors (ref. \[19\], [`AbsoluteData::Pose`]); and
//! both arms' bases in the tracker frame with the arms held (ref. \[28\], [`BaseAbsoluteProblem`]).
//!
//! The model point of reflector k at configuration i in the tracker frame is
//! `q_ik = T · p_ik(x)` with `T = tracker_from_base = (Exp(ω)·R₀, t₀ + δp)`. Variables, scaled:
//! `y = (free arm parameters, ω, δp)`.
//!
//! - Position: `r = m_ik − q_ik`, three rows per reflector.
//! - Pose: the tool frame of three points `a, b, c` has its origin at their centroid, x towards `a`,
//!   z along `(b − a) × (c − a)` and `y = z × x`; the residual of configuration i is
//!   `(o_m − o_q, L · log(R_m R_qᵀ))` with `L` ([`AbsoluteProblem::rotation_weight_mm`]) the RMS
//!   distance of the nominal reflectors from their centroid, so that a rotation error weighs as the
//!   reflector displacement it causes (the paper's "non-homogeneity" of pose errors, settled by this
//!   weight).

use super::base_problem::left_jacobian_so3;
use super::problem::{LeastSquaresSystem, StageParams};
use crate::kinematics::{ArmModel, nearest_rotation};
use crate::par::prelude::*;
use crate::side::{PerSide, Side};
use crate::solver::algorithms::least_squares::LeastSquaresProblem;
use nalgebra::{
    DMatrix, DVector, Isometry3, Matrix3, Matrix4, Rotation3, SMatrix, Translation3,
    UnitQuaternion, Vector3,
};

/// What the absolute problem fits.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum AbsoluteData {
    /// The three reflectors' positions (ref. \[18\]).
    Position,
    /// The tool frame's pose (ref. \[19\]); rotation errors weighted by `rotation_weight_mm` mm/rad.
    Pose { rotation_weight_mm: f64 },
}

/// A tool frame built from three points (see the module documentation).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ToolFrame {
    pub rotation: Rotation3<f64>,
    pub origin_mm: Vector3<f64>,
}

/// Twice the area of the triangle below which (relative to the longest side squared) three points
/// count as collinear: no tool frame.
pub const COLLINEAR_TOL: f64 = 1e-6;

/// Twice the triangle's area of three points, mm², and whether they are (nearly) collinear.
pub fn triangle_area_mm2(p: &[Vector3<f64>; 3]) -> (f64, bool) {
    let [a, b, c] = *p;
    let w = (b - a).cross(&(c - a));
    let longest = (b - a)
        .norm_squared()
        .max((c - a).norm_squared())
        .max((c - b).norm_squared());
    let area = 0.5 * w.norm();
    (area, !(w.norm() > COLLINEAR_TOL * longest && longest > 0.0))
}

/// The tool frame of three points and its derivatives with respect to them (columns `a.x … c.z`):
/// `d_origin` (3 × 9) and `d_omega` (3 × 9), the rotation's change `dR = [dω]× R`. `None` when the
/// points are (nearly) collinear.
pub fn tool_frame_with_derivatives(
    p: &[Vector3<f64>; 3],
) -> Option<(ToolFrame, SMatrix<f64, 3, 9>, SMatrix<f64, 3, 9>)> {
    if triangle_area_mm2(p).1 {
        return None;
    }
    let [a, b, c] = *p;
    let origin = (a + b + c) / 3.0;
    let v = a - origin;
    let vn = v.norm();
    let w = (b - a).cross(&(c - a));
    let wn = w.norm();
    if vn <= 0.0 {
        return None;
    }
    let x = v / vn;
    let z = w / wn;
    let y = z.cross(&x);
    let rotation = Rotation3::from_matrix_unchecked(Matrix3::from_columns(&[x, y, z]));
    let id = Matrix3::<f64>::identity();
    let mut dv = SMatrix::<f64, 3, 9>::zeros();
    let mut dw = SMatrix::<f64, 3, 9>::zeros();
    let mut d_origin = SMatrix::<f64, 3, 9>::zeros();
    let dw_blocks = [
        (c - b).cross_matrix(),
        -(c - a).cross_matrix(),
        (b - a).cross_matrix(),
    ];
    for (r, dw_r) in dw_blocks.iter().enumerate() {
        let share = if r == 0 { 2.0 / 3.0 } else { -1.0 / 3.0 };
        dv.fixed_view_mut::<3, 3>(0, 3 * r).copy_from(&(id * share));
        dw.fixed_view_mut::<3, 3>(0, 3 * r).copy_from(dw_r);
        d_origin
            .fixed_view_mut::<3, 3>(0, 3 * r)
            .copy_from(&(id / 3.0));
    }
    let dx = (id - x * x.transpose()) / vn * dv;
    let dz = (id - z * z.transpose()) / wn * dw;
    let dy = -x.cross_matrix() * dz + z.cross_matrix() * dx;
    let d_omega = (x.cross_matrix() * dx + y.cross_matrix() * dy + z.cross_matrix() * dz) * 0.5;
    Some((
        ToolFrame {
            rotation,
            origin_mm: origin,
        },
        d_origin,
        d_omega,
    ))
}

/// The tool frame of three points, `None` when they are (nearly) collinear.
pub fn tool_frame(p: &[Vector3<f64>; 3]) -> Option<ToolFrame> {
    tool_frame_with_derivatives(p).map(|(f, _, _)| f)
}

/// The three points of a configuration as a triangle; `None` for any other number of reflectors.
pub fn as_triangle(p: &[Vector3<f64>]) -> Option<&[Vector3<f64>; 3]> {
    p.try_into().ok()
}

/// `measured ≈ T · model` over all points, as ref. \[28\] computes it: the affine map from the
/// Moore–Penrose inverse of the homogeneous model points, `X = M · P⁺` (3 × 4), its linear part
/// projected onto the nearest rotation and the translation refitted to the centroids. `None` when the
/// data are not finite or there are no points.
pub fn moore_penrose_fit(
    model_mm: &[Vector3<f64>],
    measured_mm: &[Vector3<f64>],
) -> Option<Isometry3<f64>> {
    let n = model_mm.len();
    if n == 0 || n != measured_mm.len() {
        return None;
    }
    let p = DMatrix::from_fn(4, n, |r, c| if r < 3 { model_mm[c][r] } else { 1.0 });
    let m = DMatrix::from_fn(3, n, |r, c| measured_mm[c][r]);
    if !p.iter().chain(m.iter()).all(|v| v.is_finite()) {
        return None;
    }
    let x = m * p.pseudo_inverse(1e-12).ok()?;
    let linear = Matrix3::from_fn(|r, c| x[(r, c)]);
    if !linear.iter().all(|v| v.is_finite()) {
        return None;
    }
    let rotation = nearest_rotation(&linear);
    let cm = model_mm.iter().sum::<Vector3<f64>>() / n as f64;
    let cq = measured_mm.iter().sum::<Vector3<f64>>() / n as f64;
    Some(Isometry3::from_parts(
        Translation3::from(cq - rotation * cm),
        UnitQuaternion::from_rotation_matrix(&rotation),
    ))
}

/// The rotation vector (`log(R)^∨`) of `r`, accurate for small angles too (the angle from `atan2` of
/// the skew part's norm and the trace, not `acos` of the trace, which loses half the digits near 0).
pub fn rotation_vector(r: &Rotation3<f64>) -> Vector3<f64> {
    let m = r.matrix();
    let s = Vector3::new(
        m[(2, 1)] - m[(1, 2)],
        m[(0, 2)] - m[(2, 0)],
        m[(1, 0)] - m[(0, 1)],
    ) * 0.5;
    let sin = s.norm();
    let cos = (m.trace() - 1.0) * 0.5;
    let angle = sin.atan2(cos);
    if angle > 3.0 {
        // Near π the skew part vanishes; nalgebra's eigen-based axis is accurate there.
        return r.scaled_axis();
    }
    if sin < 1e-300 {
        return Vector3::zeros();
    }
    s * (angle / sin)
}

/// The transform of a homogeneous 4 × 4 matrix (assumed rigid).
fn isometry_of(h: &Matrix4<f64>) -> Isometry3<f64> {
    let r = nearest_rotation(&h.fixed_view::<3, 3>(0, 0).into_owned());
    Isometry3::from_parts(
        Translation3::new(h[(0, 3)], h[(1, 3)], h[(2, 3)]),
        UnitQuaternion::from_rotation_matrix(&r),
    )
}

/// `left_base_from_right_base = tracker_from_left_base⁺ · tracker_from_right_base` with ⁺ the
/// Moore–Penrose inverse of the homogeneous matrix (ref. \[28\]; for a rigid transform it is its
/// inverse).
pub fn combine_bases(
    tracker_from_left_base: &Isometry3<f64>,
    tracker_from_right_base: &Isometry3<f64>,
) -> Isometry3<f64> {
    let hl = tracker_from_left_base.to_homogeneous();
    let hr = tracker_from_right_base.to_homogeneous();
    if !hl.iter().chain(hr.iter()).all(|v| v.is_finite()) {
        // No SVD of non-finite values (it need not terminate); the executor reports the stage.
        return tracker_from_left_base.inverse() * tracker_from_right_base;
    }
    match hl.pseudo_inverse(1e-12) {
        Ok(inv) => isometry_of(&(inv * hr)),
        Err(_) => tracker_from_left_base.inverse() * tracker_from_right_base,
    }
}

/// One arm's absolute problem.
pub struct AbsoluteProblem {
    data: AbsoluteData,
    side: Side,
    qs: Vec<Vec<f64>>,
    measured: Vec<Vec<Vector3<f64>>>,
    /// Number of reflectors per configuration.
    reflectors: usize,
    /// Tool frames of the measured points (pose data only).
    measured_frames: Vec<ToolFrame>,
    /// The measured reflector triangle in its own tool frame, averaged over the configurations (pose
    /// data only): pose errors do not see the triangle's shape, the measurements do.
    tool_points_mm: Option<[Vector3<f64>; 3]>,
    start: ArmModel,
    x0: DVector<f64>,
    /// Free arm parameters (indices into the arm's parameter vector).
    free: Vec<usize>,
    /// Scales of the free arm parameters, then of ω (3) and δp (3).
    scale: DVector<f64>,
    t0: Isometry3<f64>,
}

/// Names of the six transform variables after the arm's parameters, e.g. `tracker_from_left_base.rx`.
pub fn transform_param_name(side: Side, c: usize) -> String {
    format!(
        "tracker_from_{}_base.{}",
        side.name(),
        ["rx", "ry", "rz", "x", "y", "z"][c]
    )
}

impl AbsoluteProblem {
    /// `measured` in the tracker frame; `t0` the start of `tracker_from_base`. For pose data the
    /// measured tool frames are built here: `Err(index)` names a configuration whose measured
    /// reflectors are collinear (or not three: pose data need three reflectors).
    #[allow(clippy::too_many_arguments)]
    pub fn new(
        data: AbsoluteData,
        side: Side,
        qs: Vec<Vec<f64>>,
        measured: Vec<Vec<Vector3<f64>>>,
        start: &ArmModel,
        t0: Isometry3<f64>,
        free: Vec<usize>,
        scale: DVector<f64>,
    ) -> Result<Self, usize> {
        assert_eq!(qs.len(), measured.len());
        assert_eq!(free.len() + 6, scale.len());
        let measured_frames = match data {
            AbsoluteData::Position => Vec::new(),
            AbsoluteData::Pose { .. } => measured
                .iter()
                .enumerate()
                .map(|(i, m)| as_triangle(m).and_then(tool_frame).ok_or(i))
                .collect::<Result<_, _>>()?,
        };
        let tool_points_mm = (!measured_frames.is_empty()).then(|| {
            let n = measured_frames.len() as f64;
            std::array::from_fn(|k| {
                measured
                    .iter()
                    .zip(&measured_frames)
                    .map(|(m, f): (&Vec<Vector3<f64>>, _)| {
                        f.rotation.inverse() * (m[k] - f.origin_mm)
                    })
                    .sum::<Vector3<f64>>()
                    / n
            })
        });
        Ok(Self {
            data,
            side,
            qs,
            reflectors: start.reflector_count(),
            measured,
            measured_frames,
            tool_points_mm,
            start: start.clone(),
            x0: start.to_vector(),
            free,
            scale,
            t0,
        })
    }

    /// The same problem with another set of free arm parameters and scales (`free.len() + 6` scales).
    pub fn with_free(mut self, free: Vec<usize>, scale: DVector<f64>) -> Self {
        assert_eq!(free.len() + 6, scale.len());
        self.free = free;
        self.scale = scale;
        self
    }

    /// The weight of rotation errors for pose data: the RMS distance of the nominal reflectors from
    /// their centroid, mm per rad.
    pub fn rotation_weight_mm(reflectors_mm: &[Vector3<f64>]) -> f64 {
        let n = reflectors_mm.len().max(1) as f64;
        let c = reflectors_mm.iter().sum::<Vector3<f64>>() / n;
        (reflectors_mm
            .iter()
            .map(|t| (t - c).norm_squared())
            .sum::<f64>()
            / n)
            .sqrt()
    }

    pub fn free(&self) -> &[usize] {
        &self.free
    }

    /// Reflectors per configuration.
    pub fn reflector_count(&self) -> usize {
        self.reflectors
    }

    fn n_free(&self) -> usize {
        self.free.len()
    }

    fn x_of(&self, y: &DVector<f64>) -> DVector<f64> {
        let mut x = self.x0.clone();
        for (c, &k) in self.free.iter().enumerate() {
            x[k] += self.scale[c] * y[c];
        }
        x
    }

    pub fn model_at(&self, y: &DVector<f64>) -> ArmModel {
        self.start.with_vector(&self.x_of(y))
    }

    /// The arm's model at y as the method reports it: for pose data the reflectors are the measured
    /// triangle placed in the tool frame of the fitted ones (the same tool frame, so the same pose
    /// errors; the shape that pose errors cannot see comes from the measured distances).
    pub fn reported_model_at(&self, y: &DVector<f64>) -> ArmModel {
        let mut model = self.model_at(y);
        if let Some(tool) = &self.tool_points_mm
            && let Some(frame) = as_triangle(&model.reflectors_mm).and_then(tool_frame)
        {
            model.reflectors_mm = tool
                .iter()
                .map(|t| frame.rotation * t + frame.origin_mm)
                .collect();
        }
        model
    }

    fn omega(&self, y: &DVector<f64>) -> Vector3<f64> {
        let nf = self.n_free();
        Vector3::from_fn(|i, _| y[nf + i] * self.scale[nf + i])
    }

    /// `tracker_from_base` at y.
    pub fn transform_at(&self, y: &DVector<f64>) -> Isometry3<f64> {
        let nf = self.n_free();
        let dp = Vector3::from_fn(|i, _| y[nf + 3 + i] * self.scale[nf + 3 + i]);
        let r = Rotation3::new(self.omega(y)) * self.t0.rotation.to_rotation_matrix();
        Isometry3::from_parts(
            Translation3::from(self.t0.translation.vector + dp),
            UnitQuaternion::from_rotation_matrix(&r),
        )
    }

    /// Rows of residuals per configuration.
    fn rows_per_config(&self) -> usize {
        match self.data {
            AbsoluteData::Position => 3 * self.reflectors,
            AbsoluteData::Pose { .. } => 6,
        }
    }

    /// Model points of `model` in the tracker frame at y, per configuration.
    fn tracker_points(&self, model: &ArmModel, y: &DVector<f64>) -> Vec<Vec<Vector3<f64>>> {
        let t = self.transform_at(y);
        self.qs
            .par_iter()
            .map(|q| {
                model
                    .reflector_fk(q)
                    .points_mm
                    .iter()
                    .map(|p| t.transform_point(&(*p).into()).coords)
                    .collect()
            })
            .collect()
    }

    /// Residuals of one configuration from its model points.
    fn config_residuals(&self, i: usize, q: &[Vector3<f64>], out: &mut [f64]) {
        match self.data {
            AbsoluteData::Position => {
                for k in 0..self.reflectors {
                    let r = self.measured[i][k] - q[k];
                    out[3 * k..3 * k + 3].copy_from_slice(r.as_slice());
                }
            }
            AbsoluteData::Pose { rotation_weight_mm } => {
                let m = &self.measured_frames[i];
                match as_triangle(q).and_then(tool_frame) {
                    Some(f) => {
                        let ro = m.origin_mm - f.origin_mm;
                        let rr = rotation_vector(&(m.rotation * f.rotation.inverse()))
                            * rotation_weight_mm;
                        out[..3].copy_from_slice(ro.as_slice());
                        out[3..6].copy_from_slice(rr.as_slice());
                    }
                    // The model's reflectors became collinear: no frame, an infinite cost.
                    None => out[..6].fill(f64::INFINITY),
                }
            }
        }
    }

    /// Residual vector at y.
    pub fn residuals(&self, y: &DVector<f64>) -> DVector<f64> {
        let pts = self.tracker_points(&self.model_at(y), y);
        let rows = self.rows_per_config();
        let mut r = DVector::zeros(rows * pts.len());
        for (i, q) in pts.iter().enumerate() {
            self.config_residuals(i, q, &mut r.as_mut_slice()[rows * i..rows * (i + 1)]);
        }
        r
    }

    /// Residuals and Jacobian ∂r/∂y (rows × (free + 6)).
    pub fn jacobian(&self, y: &DVector<f64>) -> (DVector<f64>, DMatrix<f64>) {
        let model = self.model_at(y);
        let t = self.transform_at(y);
        let rot = t.rotation.to_rotation_matrix();
        let jl = left_jacobian_so3(&self.omega(y));
        let nf = self.n_free();
        let dim = nf + 6;
        let rows = self.rows_per_config();
        let blocks: Vec<(Vec<f64>, DMatrix<f64>)> = (0..self.qs.len())
            .into_par_iter()
            .map(|i| {
                let jac = model.reflector_jacobians(&self.qs[i]);
                // dq (3r × dim): the model points' derivatives, reflector by reflector.
                let mut dq = DMatrix::<f64>::zeros(3 * self.reflectors, dim);
                let mut q = vec![Vector3::zeros(); self.reflectors];
                for k in 0..self.reflectors {
                    let rp = rot * jac.fk.points_mm[k];
                    q[k] = rp + t.translation.vector;
                    for (c, &p) in self.free.iter().enumerate() {
                        let col = rot * jac.jacobians[k].column(p) * self.scale[c];
                        dq.fixed_view_mut::<3, 1>(3 * k, c).copy_from(&col);
                    }
                    let dw = -rp.cross_matrix() * jl;
                    for a in 0..3 {
                        let col = dw.column(a) * self.scale[nf + a];
                        dq.fixed_view_mut::<3, 1>(3 * k, nf + a).copy_from(&col);
                        dq[(3 * k + a, nf + 3 + a)] = self.scale[nf + 3 + a];
                    }
                }
                let mut r = vec![0.0; rows];
                self.config_residuals(i, &q, &mut r);
                let j = match self.data {
                    AbsoluteData::Position => -dq,
                    AbsoluteData::Pose { rotation_weight_mm } => {
                        let mut j = DMatrix::<f64>::zeros(6, dim);
                        if let Some((f, d_origin, d_omega)) =
                            as_triangle(&q).and_then(tool_frame_with_derivatives)
                        {
                            let e = rotation_vector(
                                &(self.measured_frames[i].rotation * f.rotation.inverse()),
                            );
                            let jr_inv = left_jacobian_so3(&-e)
                                .try_inverse()
                                .unwrap_or_else(Matrix3::identity);
                            let d_o = DMatrix::from_column_slice(3, 9, d_origin.as_slice());
                            let d_w = DMatrix::from_column_slice(
                                3,
                                9,
                                (jr_inv * d_omega * rotation_weight_mm).as_slice(),
                            );
                            j.rows_mut(0, 3).copy_from(&(-(d_o * &dq)));
                            j.rows_mut(3, 3).copy_from(&(-(d_w * &dq)));
                        }
                        j
                    }
                };
                (r, j)
            })
            .collect();
        let n = blocks.len();
        let mut r = DVector::zeros(rows * n);
        let mut j = DMatrix::zeros(rows * n, dim);
        for (i, (ri, ji)) in blocks.into_iter().enumerate() {
            r.rows_mut(rows * i, rows).copy_from_slice(&ri);
            j.rows_mut(rows * i, rows).copy_from(&ji);
        }
        (r, j)
    }

    /// Per reflector, Σ_i |m_ik − q_ik|² of the reported model, mm².
    fn reflector_sums(&self, y: &DVector<f64>) -> Vec<f64> {
        let pts = self.tracker_points(&self.reported_model_at(y), y);
        (0..self.reflectors)
            .map(|k| {
                pts.iter()
                    .zip(&self.measured)
                    .map(|(q, m)| (m[k] - q[k]).norm_squared())
                    .sum()
            })
            .collect()
    }

    /// The mean Gram matrix `JᵀJ / rows` of the unscaled Jacobian at the start, every arm parameter
    /// then the six transform variables (for the identifiability analysis; build the problem with
    /// every parameter free and unit scales).
    pub fn gram(&self) -> DMatrix<f64> {
        let (_, j) = self.jacobian(&DVector::zeros(self.n_free() + 6));
        j.tr_mul(&j) / j.nrows().max(1) as f64
    }
}

impl LeastSquaresProblem for AbsoluteProblem {
    fn dim(&self) -> usize {
        self.n_free() + 6
    }

    fn params_at(&self, y: &DVector<f64>) -> StageParams {
        StageParams::Arm(Box::new(self.reported_model_at(y)))
    }

    fn cost(&self, y: &DVector<f64>) -> f64 {
        self.residuals(y).norm_squared()
    }

    fn objectives_mm2(&self, y: &DVector<f64>) -> Vec<f64> {
        self.reflector_sums(y)
    }

    fn normal_equations(&self, y: &DVector<f64>) -> LeastSquaresSystem {
        let (r, j) = self.jacobian(y);
        LeastSquaresSystem::of_residuals(&r, &j)
    }

    fn residuals_jacobian(&self, y: &DVector<f64>) -> Option<(DVector<f64>, DMatrix<f64>)> {
        Some(self.jacobian(y))
    }

    fn pair_count(&self) -> usize {
        self.qs.len()
    }

    fn tracker_frames(&self, y: &DVector<f64>) -> PerSide<Option<Isometry3<f64>>> {
        let mut out = PerSide::default();
        out[self.side] = Some(self.transform_at(y));
        out
    }
}

/// Ref. \[28\]'s step 2: each arm's base in the tracker frame from its absolute positioning errors,
/// step 1's arms held; `left_base_from_right_base` is their combination ([`combine_bases`]).
/// Variables: the left problem's six, then the right's.
pub struct BaseAbsoluteProblem {
    pub arms: PerSide<AbsoluteProblem>,
}

impl BaseAbsoluteProblem {
    fn split(y: &DVector<f64>) -> PerSide<DVector<f64>> {
        PerSide::new(y.rows(0, 6).into_owned(), y.rows(6, 6).into_owned())
    }

    /// Both transforms at y.
    pub fn transforms(&self, y: &DVector<f64>) -> PerSide<Isometry3<f64>> {
        let ys = Self::split(y);
        PerSide::from_fn(|s| self.arms[s].transform_at(&ys[s]))
    }
}

impl LeastSquaresProblem for BaseAbsoluteProblem {
    fn dim(&self) -> usize {
        12
    }

    fn params_at(&self, y: &DVector<f64>) -> StageParams {
        let t = self.transforms(y);
        StageParams::Base(combine_bases(&t.left, &t.right))
    }

    fn cost(&self, y: &DVector<f64>) -> f64 {
        let ys = Self::split(y);
        Side::BOTH.iter().map(|&s| self.arms[s].cost(&ys[s])).sum()
    }

    fn objectives_mm2(&self, y: &DVector<f64>) -> Vec<f64> {
        let ys = Self::split(y);
        let (l, r) = (
            self.arms.left.objectives_mm2(&ys.left),
            self.arms.right.objectives_mm2(&ys.right),
        );
        l.iter().zip(&r).map(|(a, b)| a + b).collect()
    }

    fn normal_equations(&self, y: &DVector<f64>) -> LeastSquaresSystem {
        let ys = Self::split(y);
        let mut out = LeastSquaresSystem {
            cost: 0.0,
            jtj: DMatrix::zeros(12, 12),
            jtr: DVector::zeros(12),
        };
        for (c, s) in Side::BOTH.into_iter().enumerate() {
            let sys = self.arms[s].normal_equations(&ys[s]);
            out.cost += sys.cost;
            out.jtj.view_mut((6 * c, 6 * c), (6, 6)).copy_from(&sys.jtj);
            out.jtr.rows_mut(6 * c, 6).copy_from(&sys.jtr);
        }
        out
    }

    fn pair_count(&self) -> usize {
        self.arms.left.pair_count() + self.arms.right.pair_count()
    }

    fn tracker_frames(&self, y: &DVector<f64>) -> PerSide<Option<Isometry3<f64>>> {
        self.transforms(y).map(|_, t| Some(t))
    }
}

#[cfg(test)]
mod tests;
