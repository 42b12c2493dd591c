//! Validation of the simulation options.

use super::{SimError, SimOptions};
use crate::dataset::MIN_CONFIGS;
use crate::kinematics::DualArmModel;

pub(super) fn check_options(opts: &SimOptions, nominal: &DualArmModel) -> Result<(), SimError> {
    let bad =
        |field: &'static str, message: String| Err(SimError::InvalidOption { field, message });
    let nonneg = |field: &'static str, v: f64| {
        if v.is_finite() && v >= 0.0 {
            Ok(())
        } else {
            bad(field, format!("expected a finite value ≥ 0, got {v}"))
        }
    };
    if opts.n_configs < MIN_CONFIGS {
        return bad(
            "n_configs",
            format!("expected at least {MIN_CONFIGS}, got {}", opts.n_configs),
        );
    }
    if opts.n_cal > opts.n_configs {
        return bad(
            "n_cal",
            format!("{} exceeds n_configs = {}", opts.n_cal, opts.n_configs),
        );
    }
    nonneg("dh_error.length_mm", opts.dh_error.length_mm)?;
    nonneg("dh_error.angle_rad", opts.dh_error.angle_rad)?;
    nonneg("reflector_error_mm", opts.reflector_error_mm)?;
    if let Some((lo, hi)) = opts.nominal_rms_target_mm
        && !(lo.is_finite() && hi.is_finite() && lo > 0.0 && lo <= hi)
    {
        return bad(
            "nominal_rms_target_mm",
            format!("expected 0 < min ≤ max, got ({lo}, {hi})"),
        );
    }
    nonneg("base_error_mm", opts.base_error_mm)?;
    nonneg("base_error_rad", opts.base_error_rad)?;
    nonneg("tracker.mpe_um", opts.tracker.mpe_um)?;
    nonneg("tracker.mpe_um_per_m", opts.tracker.mpe_um_per_m)?;
    let (lo, hi) = opts.tracker_distance_m;
    if !(lo.is_finite() && hi.is_finite() && lo > 0.0 && lo <= hi) {
        return bad(
            "tracker_distance_m",
            format!("expected 0 < min ≤ max, got ({lo}, {hi})"),
        );
    }
    nonneg("tracker_azimuth_max_deg", opts.tracker_azimuth_max_deg)?;
    let (elo, ehi) = opts.tracker_elevation_deg;
    if !(elo.is_finite() && ehi.is_finite() && elo <= ehi && elo >= -90.0 && ehi <= 90.0) {
        return bad(
            "tracker_elevation_deg",
            format!("expected −90 ≤ min ≤ max ≤ 90, got ({elo}, {ehi})"),
        );
    }
    let f = opts.facing_max_angle_deg;
    if !(f.is_finite() && f > 0.0 && f <= 180.0) {
        return bad(
            "facing_max_angle_deg",
            format!("expected 0 < angle ≤ 180, got {f}"),
        );
    }
    let m = opts.joint_limit_margin_fraction;
    if !(m.is_finite() && (0.0..0.5).contains(&m)) {
        return bad(
            "joint_limit_margin_fraction",
            format!("expected 0 ≤ fraction < 0.5, got {m}"),
        );
    }
    if opts.max_attempts_per_config == 0 {
        return bad("max_attempts_per_config", "expected at least 1".into());
    }
    if let Some(j) = &opts.joint_error {
        nonneg(
            "joint_error.periodic_amplitude_mrad",
            j.periodic_amplitude_mrad,
        )?;
        if !j.periods_per_rev.is_finite() {
            return bad(
                "joint_error.periods_per_rev",
                format!("expected a finite value, got {}", j.periods_per_rev),
            );
        }
        if !j.compliance_mrad_per_m.is_finite() {
            return bad(
                "joint_error.compliance_mrad_per_m",
                format!("expected a finite value, got {}", j.compliance_mrad_per_m),
            );
        }
    }
    if let Some(o) = &opts.outliers {
        if !(o.fraction.is_finite() && (0.0..=1.0).contains(&o.fraction)) {
            return bad(
                "outliers.fraction",
                format!("expected 0 ≤ fraction ≤ 1, got {}", o.fraction),
            );
        }
        nonneg("outliers.magnitude_mm", o.magnitude_mm)?;
    }
    if nominal.arms.left.reflectors_mm != nominal.arms.right.reflectors_mm {
        return bad(
            "nominal",
            "the dataset has one set of nominal reflectors; both arms must share it".into(),
        );
    }
    Ok(())
}
