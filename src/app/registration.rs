//! Tracker → robot registration for drawing: the best-fit rigid transform (Kabsch over all points)
//! that takes the measured reflector points (tracker frame) onto the model's points (left DH base).
//!
//! The calibration itself never needs this (it works on distances); the viewport does, to draw the
//! measured triangles next to the model's.

use nalgebra::{Isometry3, Vector3};

/// Least-squares rigid transform `to_from_from` with `to ≈ T · from` over all point pairs
/// (Kabsch/Umeyama without scale, `det R = +1`, [`crate::metrics::kabsch_fit_points`]). `None` with fewer
/// than 3 pairs, non-finite input or (nearly) collinear points.
pub fn best_fit_rigid(from: &[Vector3<f64>], to: &[Vector3<f64>]) -> Option<Isometry3<f64>> {
    if from.len() != to.len() || from.len() < 3 {
        return None;
    }
    let fit = crate::metrics::kabsch_fit_points(from, to)?;
    (!fit.is_degenerate()).then(|| fit.isometry())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn recovers_a_known_transform_from_noisy_points() {
        let truth = Isometry3::new(
            Vector3::new(1500.0, -300.0, 200.0),
            Vector3::new(0.3, -1.1, 2.0),
        );
        let from: Vec<Vector3<f64>> = (0..50)
            .map(|k| {
                let t = k as f64;
                Vector3::new((t * 0.7).sin() * 400.0, (t * 1.3).cos() * 300.0, t * 10.0)
            })
            .collect();
        let to: Vec<Vector3<f64>> = from
            .iter()
            .enumerate()
            .map(|(k, p)| {
                truth * nalgebra::Point3::from(*p) + Vector3::repeat(0.01 * ((k % 3) as f64 - 1.0))
            })
            .map(|p| p.coords)
            .collect();
        let fit = best_fit_rigid(&from, &to).unwrap();
        let err = (fit.translation.vector - truth.translation.vector).norm();
        assert!(err < 0.05, "translation error {err} mm");
        assert!(fit.rotation.angle_to(&truth.rotation) < 1e-4);
    }

    #[test]
    fn never_returns_a_reflection() {
        // Mirror image: the best proper rotation still has det +1.
        let from = [
            Vector3::new(0.0, 0.0, 0.0),
            Vector3::new(1.0, 0.0, 0.0),
            Vector3::new(0.0, 1.0, 0.0),
            Vector3::new(0.0, 0.0, 1.0),
        ];
        let to: Vec<_> = from.iter().map(|p| Vector3::new(-p.x, p.y, p.z)).collect();
        let fit = best_fit_rigid(&from, &to).unwrap();
        assert!((fit.rotation.to_rotation_matrix().matrix().determinant() - 1.0).abs() < 1e-9);
    }

    #[test]
    fn refuses_degenerate_input() {
        let line: Vec<_> = (0..5).map(|k| Vector3::new(k as f64, 0.0, 0.0)).collect();
        assert!(best_fit_rigid(&line, &line).is_none());
        assert!(best_fit_rigid(&line[..2], &line[..2]).is_none());
        let nan = vec![Vector3::new(f64::NAN, 0.0, 0.0); 4];
        assert!(best_fit_rigid(&nan, &nan).is_none());
    }
}
