//! The Kabsch fit: the rigid motion that best maps one point set onto another.

use nalgebra::{Isometry3, Matrix3, Rotation3, Translation3, UnitQuaternion, Vector3};

/// A rigid fit `measured ≈ rotation · model + translation`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct KabschFit {
    pub rotation: Rotation3<f64>,
    pub translation_mm: Vector3<f64>,
    /// RMS of the residuals `|measured − (R·model + t)|` over the points, mm.
    pub rms_mm: f64,
    /// Singular values of the centred cross-covariance, in decreasing order; two (near) zeros mean the
    /// points are collinear and the rotation about their line is undetermined.
    pub singular_values: Vector3<f64>,
}

impl KabschFit {
    /// The fit as a transform `measured_from_model`.
    pub fn isometry(&self) -> Isometry3<f64> {
        Isometry3::from_parts(
            Translation3::from(self.translation_mm),
            UnitQuaternion::from_rotation_matrix(&self.rotation),
        )
    }

    /// Are the points (nearly) collinear, so that the rotation is not determined?
    pub fn is_degenerate(&self) -> bool {
        let largest = self.singular_values.max();
        largest <= 0.0
            || self
                .singular_values
                .iter()
                .filter(|&&x| x <= largest * 1e-12)
                .count()
                >= 2
    }
}

/// Least-squares proper rotation and translation taking `model_pts` onto `measured_pts` (Kabsch, via SVD,
/// `det R = +1`). `None` only if the SVD does not converge (non-finite input).
pub fn kabsch_fit(
    model_pts: &[Vector3<f64>; 3],
    measured_pts: &[Vector3<f64>; 3],
) -> Option<KabschFit> {
    kabsch_fit_points(model_pts, measured_pts)
}

/// [`kabsch_fit`] over any number of point pairs. `None` for no or unequal numbers of points, or
/// non-finite input.
pub fn kabsch_fit_points(
    model_pts: &[Vector3<f64>],
    measured_pts: &[Vector3<f64>],
) -> Option<KabschFit> {
    if model_pts.is_empty() || model_pts.len() != measured_pts.len() {
        return None;
    }
    let n = model_pts.len() as f64;
    let cm = model_pts.iter().sum::<Vector3<f64>>() / n;
    let cq = measured_pts.iter().sum::<Vector3<f64>>() / n;
    let mut h = Matrix3::zeros();
    for (p, q) in model_pts.iter().zip(measured_pts) {
        h += (p - cm) * (q - cq).transpose();
    }
    if !h.iter().all(|x| x.is_finite()) {
        return None;
    }
    let svd = h.try_svd(true, true, f64::EPSILON, 1000)?;
    let (u, v_t) = (svd.u?, svd.v_t?);
    let v = v_t.transpose();
    // Flip the direction of least variance (singular values are sorted, largest first) if the plain
    // solution is a reflection.
    let mut d = Matrix3::identity();
    if (v * u.transpose()).determinant() < 0.0 {
        d[(2, 2)] = -1.0;
    }
    let rotation = Rotation3::from_matrix_unchecked(v * d * u.transpose());
    let translation_mm = cq - rotation * cm;
    let sum_sq: f64 = model_pts
        .iter()
        .zip(measured_pts)
        .map(|(p, q)| (q - (rotation * p + translation_mm)).norm_squared())
        .sum();
    Some(KabschFit {
        rotation,
        translation_mm,
        rms_mm: (sum_sq / n).sqrt(),
        singular_values: svd.singular_values,
    })
}

/// The rotation of [`kabsch_fit`]; the identity if the fit fails (non-finite input).
pub fn kabsch_rotation(
    model_pts: &[Vector3<f64>; 3],
    measured_pts: &[Vector3<f64>; 3],
) -> Rotation3<f64> {
    kabsch_fit(model_pts, measured_pts).map_or_else(Rotation3::identity, |f| f.rotation)
}
