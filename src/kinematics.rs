//! Standard Denavit–Hartenberg kinematics of one 7-joint arm, reflector forward kinematics and the
//! analytic identification Jacobian (paper eq. 4) with respect to all 37 parameters.
//!
//! Chain convention (paper Table 3): `T_i = Rz(q_i + theta_i) · Tz(d_i) · Tx(a_i) · Rx(alpha_i)`,
//! lengths in mm, angles in rad. Joint order is the physical chain order (ABB axes 1, 2, 7, 3, 4, 5, 6).
//! Frame 0 is the arm's DH base frame, frame 7 the flange; the three reflectors `t_a, t_b, t_c` are
//! constant points in frame 7.

use crate::side::{PerSide, Side};
use nalgebra::{Isometry3, SMatrix, SVector, Translation3, UnitQuaternion, Vector3};
use serde::{Deserialize, Serialize};
use std::f64::consts::FRAC_PI_2;

/// Number of joints of one arm.
pub const N_JOINTS: usize = 7;
/// DH parameters of one arm (4 per joint).
pub const N_DH: usize = 4 * N_JOINTS;
/// All identification parameters of one arm: 28 DH values and 3 × 3 reflector coordinates.
pub const N_PARAMS: usize = N_DH + 9;

/// A parameter vector of one arm, ordered `[a_1, d_1, theta_1, alpha_1, …, a_7, …, alpha_7, t_a, t_b, t_c]`.
pub type ParamVector = SVector<f64, N_PARAMS>;
/// Jacobian of one reflector point (mm) with respect to the 37 parameters.
pub type PointJacobian = SMatrix<f64, 3, N_PARAMS>;

/// Reflector labels in file order.
pub const REFLECTOR_NAMES: [&str; 3] = ["a", "b", "c"];

/// Joint limits in chain order (ABB axes 1, 2, 7, 3, 4, 5, 6), degrees.
pub const JOINT_LIMITS_DEG: [(f64, f64); N_JOINTS] = [
    (-168.5, 168.5),
    (-143.5, 43.5),
    (-168.5, 168.5),
    (-123.5, 80.0),
    (-290.0, 290.0),
    (-88.0, 138.0),
    (-229.0, 229.0),
];

/// Joint limits in chain order, radians.
pub fn joint_limits_rad() -> [(f64, f64); N_JOINTS] {
    JOINT_LIMITS_DEG.map(|(lo, hi)| (lo.to_radians(), hi.to_radians()))
}

/// ABB axis number of each chain position.
pub const ABB_AXIS_OF_CHAIN: [usize; N_JOINTS] = [1, 2, 7, 3, 4, 5, 6];

/// One row of a standard DH table.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct DhRow {
    pub a_mm: f64,
    pub d_mm: f64,
    pub theta_rad: f64,
    pub alpha_rad: f64,
}

impl DhRow {
    pub const fn new(a_mm: f64, d_mm: f64, theta_rad: f64, alpha_rad: f64) -> Self {
        Self {
            a_mm,
            d_mm,
            theta_rad,
            alpha_rad,
        }
    }

    /// `Rz(q + theta) · Tz(d) · Tx(a) · Rx(alpha)`: frame i in frame i−1.
    pub fn transform(&self, q_rad: f64) -> Isometry3<f64> {
        let (st, ct) = (q_rad + self.theta_rad).sin_cos();
        let rotation = UnitQuaternion::from_axis_angle(&Vector3::z_axis(), q_rad + self.theta_rad)
            * UnitQuaternion::from_axis_angle(&Vector3::x_axis(), self.alpha_rad);
        let t = Vector3::new(self.a_mm * ct, self.a_mm * st, self.d_mm);
        Isometry3::from_parts(Translation3::from(t), rotation)
    }
}

/// The nominal DH table of the IRB 14000 (paper Table 3), shared by both arms.
pub const IRB14000_NOMINAL_DH: [DhRow; N_JOINTS] = [
    DhRow::new(-30.0, 166.0, 0.0, -FRAC_PI_2),
    DhRow::new(30.0, 0.0, 0.0, FRAC_PI_2),
    DhRow::new(40.5, 251.5, 0.0, -FRAC_PI_2),
    DhRow::new(40.5, 0.0, -FRAC_PI_2, -FRAC_PI_2),
    DhRow::new(-27.0, 265.0, 0.0, FRAC_PI_2),
    DhRow::new(27.0, 0.0, 0.0, -FRAC_PI_2),
    DhRow::new(0.0, 36.0, 0.0, 0.0),
];

/// Names of the 37 parameters, in [`ParamVector`] order (joint numbers are chain positions 1–7).
pub fn param_name(k: usize) -> String {
    const DH: [&str; 4] = ["a", "d", "theta", "alpha"];
    if k < N_DH {
        format!("{}{}", DH[k % 4], k / 4 + 1)
    } else if k < N_PARAMS {
        let r = (k - N_DH) / 3;
        let c = ["x", "y", "z"][(k - N_DH) % 3];
        format!("t_{}.{}", REFLECTOR_NAMES[r], c)
    } else {
        format!("p{k}")
    }
}

/// Is parameter `k` an angle (rad) rather than a length (mm)?
pub fn param_is_angle(k: usize) -> bool {
    k < N_DH && (k % 4 == 2 || k % 4 == 3)
}

/// The geometric model of one arm: DH table and reflector coordinates in the flange frame.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct ArmModel {
    pub dh: [DhRow; N_JOINTS],
    /// Reflector coordinates `t_a, t_b, t_c` in the flange frame (frame 7), mm.
    pub reflectors_mm: [Vector3<f64>; 3],
}

/// Per-configuration kinematic quantities computed once per iterate and reused across all pairs.
#[derive(Clone, Debug)]
pub struct ReflectorFk {
    /// Reflector positions in the arm's base frame, mm.
    pub points_mm: [Vector3<f64>; 3],
    /// Flange orientation in the base frame.
    pub base_from_flange: Isometry3<f64>,
}

impl ArmModel {
    /// The nominal IRB 14000 arm with the given nominal reflector coordinates.
    pub fn nominal_irb14000(reflectors_mm: [Vector3<f64>; 3]) -> Self {
        Self {
            dh: IRB14000_NOMINAL_DH,
            reflectors_mm,
        }
    }

    /// Flatten into the 37-vector used by the solver.
    pub fn to_vector(&self) -> ParamVector {
        let mut v = ParamVector::zeros();
        for (i, row) in self.dh.iter().enumerate() {
            v[4 * i] = row.a_mm;
            v[4 * i + 1] = row.d_mm;
            v[4 * i + 2] = row.theta_rad;
            v[4 * i + 3] = row.alpha_rad;
        }
        for (r, t) in self.reflectors_mm.iter().enumerate() {
            for c in 0..3 {
                v[N_DH + 3 * r + c] = t[c];
            }
        }
        v
    }

    /// Inverse of [`ArmModel::to_vector`].
    pub fn from_vector(v: &ParamVector) -> Self {
        let mut dh = [DhRow::new(0.0, 0.0, 0.0, 0.0); N_JOINTS];
        for (i, row) in dh.iter_mut().enumerate() {
            *row = DhRow::new(v[4 * i], v[4 * i + 1], v[4 * i + 2], v[4 * i + 3]);
        }
        let t = |r: usize| Vector3::new(v[N_DH + 3 * r], v[N_DH + 3 * r + 1], v[N_DH + 3 * r + 2]);
        Self {
            dh,
            reflectors_mm: [t(0), t(1), t(2)],
        }
    }

    /// Frames 0..=7 in the base frame (frame 0 is the identity).
    pub fn frames(&self, q_rad: &[f64; N_JOINTS]) -> [Isometry3<f64>; N_JOINTS + 1] {
        let mut out = [Isometry3::identity(); N_JOINTS + 1];
        for i in 0..N_JOINTS {
            out[i + 1] = out[i] * self.dh[i].transform(q_rad[i]);
        }
        out
    }

    /// Flange pose in the arm's DH base frame.
    pub fn base_from_flange(&self, q_rad: &[f64; N_JOINTS]) -> Isometry3<f64> {
        self.dh
            .iter()
            .zip(q_rad)
            .fold(Isometry3::identity(), |acc, (row, &q)| {
                acc * row.transform(q)
            })
    }

    /// Reflector positions (base frame, mm) and flange pose (paper eq. 3).
    pub fn reflector_fk(&self, q_rad: &[f64; N_JOINTS]) -> ReflectorFk {
        let base_from_flange = self.base_from_flange(q_rad);
        let points_mm = self
            .reflectors_mm
            .map(|t| base_from_flange.transform_point(&t.into()).coords);
        ReflectorFk {
            points_mm,
            base_from_flange,
        }
    }

    /// Reflector positions and their analytic Jacobians with respect to all 37 parameters (eq. 4).
    ///
    /// For standard DH the columns are, with `o_i`, `x_i`, `z_i` the origin and axes of frame i:
    /// `∂p/∂θ_i = z_{i−1} × (p − o_{i−1})`, `∂p/∂d_i = z_{i−1}`, `∂p/∂a_i = x_i`,
    /// `∂p/∂α_i = x_i × (p − o_i)`, and `∂p_k/∂t_k = R_7`.
    pub fn reflector_jacobians(
        &self,
        q_rad: &[f64; N_JOINTS],
    ) -> (ReflectorFk, [PointJacobian; 3]) {
        let frames = self.frames(q_rad);
        let flange = frames[N_JOINTS];
        let points_mm = self
            .reflectors_mm
            .map(|t| flange.transform_point(&t.into()).coords);
        let r7 = flange.rotation.to_rotation_matrix().into_inner();
        let mut jac = [PointJacobian::zeros(); 3];
        for i in 0..N_JOINTS {
            let prev = &frames[i];
            let cur = &frames[i + 1];
            let o_prev = prev.translation.vector;
            let z_prev = prev.rotation * Vector3::z();
            let o_cur = cur.translation.vector;
            let x_cur = cur.rotation * Vector3::x();
            for (k, p) in points_mm.iter().enumerate() {
                let j = &mut jac[k];
                j.set_column(4 * i, &x_cur);
                j.set_column(4 * i + 1, &z_prev);
                j.set_column(4 * i + 2, &z_prev.cross(&(p - o_prev)));
                j.set_column(4 * i + 3, &x_cur.cross(&(p - o_cur)));
            }
        }
        for (k, j) in jac.iter_mut().enumerate() {
            j.fixed_view_mut::<3, 3>(0, N_DH + 3 * k).copy_from(&r7);
        }
        (
            ReflectorFk {
                points_mm,
                base_from_flange: flange,
            },
            jac,
        )
    }
}

/// The geometric model of the whole dual-arm robot: both arms and the right-arm base in the left-arm base.
#[derive(Clone, Debug, PartialEq)]
pub struct DualArmModel {
    pub arms: PerSide<ArmModel>,
    pub left_base_from_right_base: Isometry3<f64>,
}

impl DualArmModel {
    pub fn arm(&self, side: Side) -> &ArmModel {
        &self.arms[side]
    }

    pub fn arm_mut(&mut self, side: Side) -> &mut ArmModel {
        &mut self.arms[side]
    }

    /// Transform taking points of `side`'s base frame into the left-arm base frame.
    pub fn left_base_from(&self, side: Side) -> Isometry3<f64> {
        match side {
            Side::Left => Isometry3::identity(),
            Side::Right => self.left_base_from_right_base,
        }
    }
}

/// Rotation angle of `R` (norm of its logarithm, the vee of `log(R)`), rad.
pub fn rotation_angle_rad(r: &nalgebra::Rotation3<f64>) -> f64 {
    // Robust near 0 and π: atan2 of |sin| and cos.
    let m = r.matrix();
    let cos = ((m.trace() - 1.0) * 0.5).clamp(-1.0, 1.0);
    let s = Vector3::new(
        m[(2, 1)] - m[(1, 2)],
        m[(0, 2)] - m[(2, 0)],
        m[(1, 0)] - m[(0, 1)],
    );
    (0.5 * s.norm()).atan2(cos)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::finite_difference::{Tolerance, check_jacobian};
    use nalgebra::{DMatrix, DVector};
    use rand::{Rng, SeedableRng};
    use rand_chacha::ChaCha8Rng;

    fn nominal() -> ArmModel {
        ArmModel::nominal_irb14000([
            Vector3::new(45.0, 0.0, 40.0),
            Vector3::new(-25.0, 40.0, 40.0),
            Vector3::new(-25.0, -40.0, 40.0),
        ])
    }

    fn random_q(rng: &mut ChaCha8Rng) -> [f64; N_JOINTS] {
        let lim = joint_limits_rad();
        std::array::from_fn(|i| rng.random_range(lim[i].0..lim[i].1))
    }

    fn perturbed(rng: &mut ChaCha8Rng) -> ArmModel {
        let mut v = nominal().to_vector();
        for k in 0..N_PARAMS {
            v[k] += if param_is_angle(k) {
                rng.random_range(-0.01..0.01)
            } else {
                rng.random_range(-1.0..1.0)
            };
        }
        ArmModel::from_vector(&v)
    }

    #[test]
    fn vector_roundtrip() {
        let m = nominal();
        assert_eq!(ArmModel::from_vector(&m.to_vector()), m);
    }

    #[test]
    fn dh_transform_matches_composition() {
        let row = DhRow::new(12.0, -7.0, 0.3, -1.1);
        let q = 0.77;
        let composed = Isometry3::rotation(Vector3::z() * (q + row.theta_rad))
            * Isometry3::translation(0.0, 0.0, row.d_mm)
            * Isometry3::translation(row.a_mm, 0.0, 0.0)
            * Isometry3::rotation(Vector3::x() * row.alpha_rad);
        let t = row.transform(q);
        assert!((t.to_homogeneous() - composed.to_homogeneous()).abs().max() < 1e-12);
    }

    #[test]
    fn zero_pose_matches_hand_computation() {
        // At q = 0 the flange z axis and position follow from Table 3 by hand:
        // frame 1: x=(1,0,0), z=(0,1,0) after alpha=-pi/2 ... checked through an independent product.
        let m = nominal();
        let q = [0.0; N_JOINTS];
        let mut t = nalgebra::Matrix4::<f64>::identity();
        for row in &m.dh {
            let (st, ct) = row.theta_rad.sin_cos();
            let (sa, ca) = row.alpha_rad.sin_cos();
            #[rustfmt::skip]
            let a = nalgebra::Matrix4::new(
                ct, -st * ca, st * sa, row.a_mm * ct,
                st, ct * ca, -ct * sa, row.a_mm * st,
                0.0, sa, ca, row.d_mm,
                0.0, 0.0, 0.0, 1.0,
            );
            t *= a;
        }
        let f = m.base_from_flange(&q).to_homogeneous();
        assert!((f - t).abs().max() < 1e-9, "{f}\n{t}");
    }

    /// The three reflector Jacobians stacked (rows: t_a x, y, z, t_b …, t_c …), and the reflector
    /// points as a function of the 37 parameters, for [`check_jacobian`].
    fn stacked_jacobian(model: &ArmModel, q: &[f64; N_JOINTS]) -> DMatrix<f64> {
        let (_, jac) = model.reflector_jacobians(q);
        DMatrix::from_fn(9, N_PARAMS, |r, c| jac[r / 3][(r % 3, c)])
    }

    fn stacked_points(q: &[f64; N_JOINTS]) -> impl Fn(&DVector<f64>) -> DVector<f64> {
        let q = *q;
        move |v| {
            let fk = ArmModel::from_vector(&ParamVector::from_column_slice(v.as_slice()))
                .reflector_fk(&q);
            DVector::from_iterator(9, fk.points_mm.iter().flat_map(|p| p.iter().copied()))
        }
    }

    fn step(k: usize) -> f64 {
        if param_is_angle(k) { 1e-6 } else { 1e-4 }
    }

    fn check(model: &ArmModel, q: &[f64; N_JOINTS], jac: &DMatrix<f64>) -> Result<(), String> {
        let x = DVector::from_column_slice(model.to_vector().as_slice());
        check_jacobian(stacked_points(q), &x, jac, step, Tolerance::rel(1e-6)).map_err(|e| {
            e.describe(
                |r| format!("t_{}.{}", REFLECTOR_NAMES[r / 3], ["x", "y", "z"][r % 3]),
                param_name,
            )
        })
    }

    #[test]
    fn analytic_jacobian_matches_central_differences() {
        let mut rng = ChaCha8Rng::seed_from_u64(7);
        for _ in 0..20 {
            let model = perturbed(&mut rng);
            let q = random_q(&mut rng);
            if let Err(e) = check(&model, &q, &stacked_jacobian(&model, &q)) {
                panic!("q {q:?}: {e}");
            }
        }
    }

    #[test]
    fn jacobian_check_detects_a_wrong_column() {
        // The check above must be able to fail: the same check, given a Jacobian whose α4 column is
        // θ5's (a plausible indexing slip), names α4 and nothing else.
        let model = nominal();
        let q = [0.3, -0.5, 0.2, -0.4, 0.6, 0.5, -0.2];
        let alpha4 = 3 * 4 + 3;
        let mut jac = stacked_jacobian(&model, &q);
        check(&model, &q, &jac).expect("the true Jacobian passes");
        let theta5 = jac.column(alpha4 + 1).into_owned();
        jac.set_column(alpha4, &theta5);
        let x = DVector::from_column_slice(model.to_vector().as_slice());
        let err = check_jacobian(stacked_points(&q), &x, &jac, step, Tolerance::rel(1e-6))
            .expect_err("a wrong column must be caught");
        assert_eq!(err.columns(), vec![alpha4], "{err}");
        assert!(check(&model, &q, &jac).unwrap_err().contains("alpha4"));
    }

    #[test]
    fn rotation_angle_is_robust() {
        for &a in &[0.0, 1e-9, 0.3, 1.0, 3.0, std::f64::consts::PI - 1e-7] {
            let r = nalgebra::Rotation3::from_axis_angle(&Vector3::y_axis(), a);
            assert!((rotation_angle_rad(&r) - a).abs() < 1e-9, "{a}");
        }
    }

    #[test]
    fn param_names() {
        assert_eq!(param_name(0), "a1");
        assert_eq!(param_name(2), "theta1");
        assert_eq!(param_name(27), "alpha7");
        assert_eq!(param_name(28), "t_a.x");
        assert_eq!(param_name(36), "t_c.z");
    }
}
