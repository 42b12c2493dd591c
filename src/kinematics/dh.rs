//! Standard Denavit–Hartenberg kinematics of one 7-joint arm (the built-in IRB 14000), reflector
//! forward kinematics and the analytic identification Jacobian (paper eq. 4) with respect to all 37
//! parameters.
//!
//! Chain convention (paper Table 3): `T_i = Rz(q_i + theta_i) · Tz(d_i) · Tx(a_i) · Rx(alpha_i)`,
//! lengths in mm, angles in rad. Joint order is the physical chain order (ABB axes 1, 2, 7, 3, 4, 5, 6).
//! Frame 0 is the arm's DH base frame, frame 7 the flange; the three reflectors `t_a, t_b, t_c` are
//! constant points in frame 7.

use super::{ArmJacobians, REFLECTOR_NAMES, ReflectorFk};
use nalgebra::{Isometry3, Matrix3xX, SMatrix, SVector, Translation3, UnitQuaternion, Vector3};
use serde::{Deserialize, Serialize};
use std::f64::consts::FRAC_PI_2;

/// Number of joints of one arm of the built-in IRB 14000.
pub const N_JOINTS: usize = 7;
/// DH parameters of one arm (4 per joint).
pub const N_DH: usize = 4 * N_JOINTS;
/// All identification parameters of one DH arm: 28 DH values and 3 × 3 reflector coordinates.
pub const N_PARAMS: usize = N_DH + 9;

/// A parameter vector of one DH arm, ordered `[a_1, d_1, theta_1, alpha_1, …, a_7, …, alpha_7, t_a,
/// t_b, t_c]`.
pub type ParamVector = SVector<f64, N_PARAMS>;
/// Jacobian of one reflector point (mm) with respect to the 37 parameters.
pub type PointJacobian = SMatrix<f64, 3, N_PARAMS>;

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

/// Names of the 37 DH parameters, in [`ParamVector`] order (joint numbers are chain positions 1–7).
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

/// Is DH parameter `k` an angle (rad) rather than a length (mm)?
pub fn param_is_angle(k: usize) -> bool {
    k < N_DH && (k % 4 == 2 || k % 4 == 3)
}

/// Flatten a DH table and three reflectors into the 37-vector.
pub fn to_vector(dh: &[DhRow; N_JOINTS], reflectors_mm: &[Vector3<f64>; 3]) -> ParamVector {
    let mut v = ParamVector::zeros();
    write_dh(dh, v.as_mut_slice());
    for (r, t) in reflectors_mm.iter().enumerate() {
        for c in 0..3 {
            v[N_DH + 3 * r + c] = t[c];
        }
    }
    v
}

/// Write the 28 DH values into the first 28 entries of `v`.
pub fn write_dh(dh: &[DhRow; N_JOINTS], v: &mut [f64]) {
    for (i, row) in dh.iter().enumerate() {
        v[4 * i] = row.a_mm;
        v[4 * i + 1] = row.d_mm;
        v[4 * i + 2] = row.theta_rad;
        v[4 * i + 3] = row.alpha_rad;
    }
}

/// Joint `i`'s value; a missing one (a vector of the wrong length, refused before it gets here)
/// counts as zero.
fn joint(q_rad: &[f64], i: usize) -> f64 {
    debug_assert_eq!(q_rad.len(), N_JOINTS);
    q_rad.get(i).copied().unwrap_or(0.0)
}

/// Frames 0..=7 in the base frame (frame 0 is the identity).
pub fn frames(dh: &[DhRow; N_JOINTS], q_rad: &[f64]) -> [Isometry3<f64>; N_JOINTS + 1] {
    let mut out = [Isometry3::identity(); N_JOINTS + 1];
    for i in 0..N_JOINTS {
        out[i + 1] = out[i] * dh[i].transform(joint(q_rad, i));
    }
    out
}

/// Flange pose in the arm's DH base frame.
pub fn base_from_flange(dh: &[DhRow; N_JOINTS], q_rad: &[f64]) -> Isometry3<f64> {
    dh.iter()
        .enumerate()
        .fold(Isometry3::identity(), |acc, (i, row)| {
            acc * row.transform(joint(q_rad, i))
        })
}

/// Reflector positions and their analytic Jacobians with respect to all `28 + 3r` parameters (eq. 4).
///
/// For standard DH the columns are, with `o_i`, `x_i`, `z_i` the origin and axes of frame i:
/// `∂p/∂θ_i = z_{i−1} × (p − o_{i−1})`, `∂p/∂d_i = z_{i−1}`, `∂p/∂a_i = x_i`,
/// `∂p/∂α_i = x_i × (p − o_i)`, and `∂p_k/∂t_k = R_7`.
pub fn reflector_jacobians(
    dh: &[DhRow; N_JOINTS],
    reflectors_mm: &[Vector3<f64>],
    q_rad: &[f64],
) -> ArmJacobians {
    let frames = frames(dh, q_rad);
    let flange = frames[N_JOINTS];
    let points_mm: Vec<Vector3<f64>> = reflectors_mm
        .iter()
        .map(|t| flange.transform_point(&(*t).into()).coords)
        .collect();
    let r7 = flange.rotation.to_rotation_matrix().into_inner();
    let cols = N_DH + 3 * reflectors_mm.len();
    let mut jac = vec![Matrix3xX::zeros(cols); reflectors_mm.len()];
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
    ArmJacobians {
        fk: ReflectorFk {
            points_mm,
            base_from_flange: flange,
        },
        jacobians: jac,
    }
}

/// Preferred order of the identifiability analysis: the reflector coordinates, joints 2 … 6, joint 1
/// (a, alpha, then d, theta), joint 7.
pub fn preference_order(reflectors: usize) -> Vec<usize> {
    let mut order: Vec<usize> = (N_DH..N_DH + 3 * reflectors).collect();
    order.extend(4..24); // joints 2..6
    order.extend([0, 3, 1, 2]); // joint 1: a, alpha, then d, theta
    order.extend(24..28); // joint 7
    order
}

/// Why a DH parameter cannot be identified from distances, when physics says so.
pub fn physical_reason(k: usize) -> Option<&'static str> {
    match k {
        1 => Some(
            "joint 1 d: a translation along the first axis moves every point alike and is absorbed by the tracker/base frame",
        ),
        2 => Some(
            "joint 1 θ: a rotation about the first axis turns every point alike and is absorbed by the tracker/base frame",
        ),
        24..=27 => {
            Some("joint 7: a constant flange transform is absorbed by the reflector coordinates")
        }
        _ => None,
    }
}
