//! `dualcal reproduce`: the studies of the paper and of docs/solver.md on simulated data (the
//! outliers and paper studies in their own files).

use super::args::{ReproduceArgs, Study};
use super::paper_study::FIG4_SIZES;
use crate::cli::common::load_workspace;
use crate::dataset::{Dataset, Split};
use crate::kinematics::DualArmModel;
use crate::metrics;
use crate::robot::RobotDescription;
use crate::side::Side;
use crate::simulate::{self, SimOptions};
use crate::solver::{
    self, BaseMethod, CalibrationResult, CalibrationSettings, Calibrator, Method, QpMethod,
    Termination,
};
use anyhow::{Context, Result, bail};

/// Calibrate without progress output. A stage that hits the iteration limit fails the study (its
/// figures would not be those of the method); a stall is reported in the tables.
fn quiet_calibrate(
    ds: &Dataset,
    nominal: &DualArmModel,
    settings: &CalibrationSettings,
) -> Result<CalibrationResult> {
    let result = Calibrator::new(ds, nominal)
        .settings(settings.clone())
        .run()?;
    if let Some(s) = result
        .stages
        .iter()
        .find(|s| s.termination == Termination::MaxIterations)
    {
        bail!(
            "{}: not converged after {} iterations (ψ {:.6} mm²)",
            s.stage,
            s.iterations,
            s.psi_mm2
        );
    }
    Ok(result)
}

/// The simulation of a study: the paper's protocol, with unmodelled joint errors if asked.
fn study_options(a: &ReproduceArgs, seed: u64) -> SimOptions {
    SimOptions {
        joint_error: a.joint_errors(),
        ..simulate::paper_options(seed, 220, 120)
    }
}

/// `dualcal reproduce STUDY`.
pub(crate) fn run(a: &ReproduceArgs) -> Result<()> {
    let robot = RobotDescription::builtin_irb14000();
    if a.study != Study::Paper {
        for (given, flag) in [
            (a.out.is_some(), "--out"),
            (a.force, "--force"),
            (a.quick, "--quick"),
            (a.methods.is_some(), "--methods"),
        ] {
            if given {
                bail!("{flag} is an option of `reproduce paper`");
            }
        }
    }
    match a.study {
        Study::Fig4 => fig4_study(a, &robot)?,
        Study::Qp => qp_study(a, &robot)?,
        Study::Robustness => robustness_study(a, &robot)?,
        Study::Outliers => super::outlier_study::run(a, &robot)?,
        Study::Paper => super::paper_study::run(a, &robot)?,
    }
    Ok(())
}

/// Paper Fig. 4: the accuracy after calibrating with each number of calibration configurations, on
/// `--dataset` or on a simulation of the first seed.
fn fig4_study(a: &ReproduceArgs, robot: &RobotDescription) -> Result<()> {
    let (ds, nominal) = match &a.dataset {
        Some(p) => {
            let ws = load_workspace(p)?;
            (ws.dataset, ws.nominal)
        }
        None => {
            let ds = simulate::simulate_with_robot(&study_options(a, a.seeds[0]), robot)?.dataset;
            let nominal = robot.nominal_model_for(&ds);
            (ds, nominal)
        }
    };
    outln!(
        "Paper Fig. 4: relative accuracy against the number of calibration configurations (per arm)"
    );
    outln!(
        "| configs | left pos RMS cal / ver (mm) | right pos RMS cal / ver (mm) | left ori RMS cal / ver (rad) | right ori RMS cal / ver (rad) |"
    );
    outln!("|---:|---:|---:|---:|---:|");
    for &n in a.sizes.as_deref().unwrap_or(&FIG4_SIZES) {
        let sub = ds.with_cal_subset(n);
        let res = quiet_calibrate(&sub, &nominal, &CalibrationSettings::default())
            .with_context(|| format!("calibrating with {n} configurations"))?;
        let cal = metrics::evaluate(&sub, &res.calibrated, Split::Cal)?;
        let ver = metrics::evaluate(&sub, &res.calibrated, Split::Ver)?;
        outln!(
            "| {n} | {:.4} / {:.4} | {:.4} / {:.4} | {:.5} / {:.5} | {:.5} / {:.5} |",
            cal.relative_or_nan(Side::Left).pos_rms_mm,
            ver.relative_or_nan(Side::Left).pos_rms_mm,
            cal.relative_or_nan(Side::Right).pos_rms_mm,
            ver.relative_or_nan(Side::Right).pos_rms_mm,
            cal.relative_or_nan(Side::Left)
                .ori_rms_rad
                .unwrap_or(f64::NAN),
            ver.relative_or_nan(Side::Left)
                .ori_rms_rad
                .unwrap_or(f64::NAN),
            cal.relative_or_nan(Side::Right)
                .ori_rms_rad
                .unwrap_or(f64::NAN),
            ver.relative_or_nan(Side::Right)
                .ori_rms_rad
                .unwrap_or(f64::NAN)
        );
    }
    Ok(())
}

/// The exact QP against the paper's subgradient QP, per seed, beside the simulation's truth.
fn qp_study(a: &ReproduceArgs, robot: &RobotDescription) -> Result<()> {
    outln!(
        "Exact QP against the paper's subgradient QP (120 cal + 100 ver configurations per arm)"
    );
    outln!(
        "| seed | QP | iterations (L/R/base) | stop (L/R/base) | time (s) | ψ left (mm²) | ψ right (mm²) | ψ base (mm²) | ver pos RMS L/R/collab (mm) | ver ori RMS L/R/collab (rad) |"
    );
    outln!("|---:|---|---|---|---:|---:|---:|---:|---|---|");
    for &seed in &a.seeds {
        let sim = simulate::simulate_with_robot(&study_options(a, seed), robot)?;
        let truth_ver = metrics::evaluate(&sim.dataset, &sim.truth, Split::Ver)?;
        outln!(
            "| {seed} | truth | – | – | – | – | – | – | {:.4} / {:.4} / {:.4} | {:.5} / {:.5} / {:.5} |",
            truth_ver.relative_or_nan(Side::Left).pos_rms_mm,
            truth_ver.relative_or_nan(Side::Right).pos_rms_mm,
            truth_ver.collaborative_or_nan().pos_rms_mm,
            truth_ver
                .relative_or_nan(Side::Left)
                .ori_rms_rad
                .unwrap_or(f64::NAN),
            truth_ver
                .relative_or_nan(Side::Right)
                .ori_rms_rad
                .unwrap_or(f64::NAN),
            truth_ver
                .collaborative_or_nan()
                .ori_rms_rad
                .unwrap_or(f64::NAN)
        );
        for qp in [QpMethod::Exact, QpMethod::Paper] {
            let settings = CalibrationSettings {
                qp,
                max_iterations: 400,
                ..CalibrationSettings::default()
            };
            let res = quiet_calibrate(&sim.dataset, &sim.nominal, &settings)?;
            let ver = metrics::evaluate(&sim.dataset, &res.calibrated, Split::Ver)?;
            let it: Vec<String> = res
                .stages
                .iter()
                .map(|s| s.iterations.to_string())
                .collect();
            let psi: Vec<f64> = res.stages.iter().map(|s| s.psi_mm2).collect();
            let stops: Vec<String> = res
                .stages
                .iter()
                .map(|s| format!("{:?}", s.termination))
                .collect();
            outln!(
                "| {seed} | {qp:?} | {} | {} | {:.3} | {:.6} | {:.6} | {:.6} | {:.4} / {:.4} / {:.4} | {:.5} / {:.5} / {:.5} |",
                it.join(" / "),
                stops.join(" / "),
                res.elapsed_secs,
                psi[0],
                psi[1],
                psi[2],
                ver.relative_or_nan(Side::Left).pos_rms_mm,
                ver.relative_or_nan(Side::Right).pos_rms_mm,
                ver.collaborative_or_nan().pos_rms_mm,
                ver.relative_or_nan(Side::Left)
                    .ori_rms_rad
                    .unwrap_or(f64::NAN),
                ver.relative_or_nan(Side::Right)
                    .ori_rms_rad
                    .unwrap_or(f64::NAN),
                ver.collaborative_or_nan().ori_rms_rad.unwrap_or(f64::NAN)
            );
        }
    }
    Ok(())
}

/// Minimax against least squares on data the model cannot explain: per seed, once with unmodelled joint
/// errors and once more with 5% outliers; prints a table per run and a summary of ratios.
fn robustness_study(a: &ReproduceArgs, robot: &RobotDescription) -> Result<()> {
    let joint_errors = a
        .joint_errors()
        .unwrap_or_else(simulate::unmodelled_joint_errors);
    outln!(
        "Minimax (paper) against least squares (LM) on data with unmodelled errors \
         (gear {} mrad, {} per revolution; compliance {} mrad/m); verification split unless marked cal",
        joint_errors.periodic_amplitude_mrad,
        joint_errors.periods_per_rev,
        joint_errors.compliance_mrad_per_m
    );
    outln!(
        "| seed | data | method | pos max L/R/collab (mm) | pos RMS L/R/collab (mm) | ori max L/R/collab (rad) | ori RMS L/R/collab (rad) | final λ_a/λ_b/λ_c left; right |"
    );
    outln!("|---:|---|---|---|---|---|---|---|");
    let case_names = ["joint errors", "joint errors + 5% outliers of 1 mm"];
    // The indicators compared, each for left / right / collaborative.
    type Pick = fn(&metrics::AccuracyStats) -> f64;
    let worst_reflector: Pick = |s| {
        s.pos_rms_per_reflector_mm
            .iter()
            .copied()
            .fold(0.0, f64::max)
    };
    let indicators: [(&str, bool, Pick); 5] = [
        ("position max", false, |s| s.pos_max_mm),
        ("orientation max", false, |s| {
            s.ori_max_rad.unwrap_or(f64::NAN)
        }),
        ("orientation RMS", false, |s| {
            s.ori_rms_rad.unwrap_or(f64::NAN)
        }),
        ("worst reflector's position RMS", false, worst_reflector),
        (
            "worst reflector's position RMS (cal)",
            true,
            worst_reflector,
        ),
    ];
    // ratios[case][run][indicator][L/R/collab] = minimax / LM
    let mut ratios: [Vec<Vec<[f64; 3]>>; 2] = [Vec::new(), Vec::new()];
    for &seed in &a.seeds {
        for (c, name) in case_names.iter().enumerate() {
            let opts = SimOptions {
                joint_error: Some(joint_errors),
                outliers: (c == 1).then_some(simulate::OutlierModel {
                    fraction: 0.05,
                    magnitude_mm: 1.0,
                }),
                ..simulate::paper_options(seed, 220, 120)
            };
            let sim = simulate::simulate_with_robot(&opts, robot)?;
            let mut values = Vec::new();
            for method in [Method::Minimax, Method::LeastSquares] {
                // Least squares throughout (both steps), as the study compares the objectives.
                let base_method = if method == Method::LeastSquares {
                    BaseMethod::Distance
                } else {
                    BaseMethod::Minimax
                };
                let settings = CalibrationSettings {
                    method,
                    base_method,
                    ..CalibrationSettings::default()
                };
                let res = quiet_calibrate(&sim.dataset, &sim.nominal, &settings)?;
                let ver = metrics::evaluate(&sim.dataset, &res.calibrated, Split::Ver)?;
                let cal = metrics::evaluate(&sim.dataset, &res.calibrated, Split::Cal)?;
                let three = |r: &metrics::AccuracyReport, pick: Pick| {
                    [
                        r.relative_or_nan(Side::Left),
                        r.relative_or_nan(Side::Right),
                        r.collaborative_or_nan(),
                    ]
                    .map(|s| pick(&s))
                };
                let f = |v: [f64; 3], digits: usize| v.map(|x| format!("{x:.digits$}")).join(" / ");
                let final_lambda = |side: Side| {
                    res.history
                        .iter()
                        .rfind(|r| r.stage == solver::Stage::Arm(side))
                        .and_then(|r| r.lambda.clone())
                        .map_or_else(
                            || "–".to_owned(),
                            |l| {
                                l.iter()
                                    .map(|x| format!("{x:.2}"))
                                    .collect::<Vec<_>>()
                                    .join("/")
                            },
                        )
                };
                outln!(
                    "| {seed} | {name} | {} | {} | {} | {} | {} | {}; {} |",
                    method.spec().objective,
                    f(three(&ver, |s| s.pos_max_mm), 4),
                    f(three(&ver, |s| s.pos_rms_mm), 4),
                    f(three(&ver, |s| s.ori_max_rad.unwrap_or(f64::NAN)), 5),
                    f(three(&ver, |s| s.ori_rms_rad.unwrap_or(f64::NAN)), 5),
                    final_lambda(Side::Left),
                    final_lambda(Side::Right),
                );
                values.push(
                    indicators
                        .iter()
                        .map(|&(_, on_cal, pick)| three(if on_cal { &cal } else { &ver }, pick))
                        .collect::<Vec<_>>(),
                );
            }
            ratios[c].push(
                (0..indicators.len())
                    .map(|i| std::array::from_fn(|k| values[0][i][k] / values[1][i][k]))
                    .collect(),
            );
        }
    }
    let labels: Vec<&str> = indicators.iter().map(|(label, _, _)| *label).collect();
    print_ratio_summary(a.seeds.len(), &case_names, &labels, &ratios);
    Ok(())
}

/// The robustness study's summary: per data case and indicator, the mean ratio minimax / least squares
/// over the runs and how often minimax was smaller or equal. `ratios[case][run][indicator]` holds
/// left / right / collaborative.
fn print_ratio_summary(
    n_seeds: usize,
    case_names: &[&str],
    labels: &[&str],
    ratios: &[Vec<Vec<[f64; 3]>>],
) {
    outln!("");
    outln!(
        "Summary over {} seed(s): minimax relative to least squares (below 1: minimax smaller)",
        n_seeds
    );
    outln!(
        "| data | indicator | mean ratio minimax/LM (L / R / collab) | minimax smaller or equal in |"
    );
    outln!("|---|---|---|---:|");
    for (c, name) in case_names.iter().enumerate() {
        for (i, label) in labels.iter().enumerate() {
            let runs = &ratios[c];
            let n = runs.len().max(1) as f64;
            let mean: Vec<String> = (0..3)
                .map(|k| format!("{:.3}", runs.iter().map(|r| r[i][k]).sum::<f64>() / n))
                .collect();
            let wins = runs
                .iter()
                .flat_map(|r| r[i].iter())
                .filter(|&&x| x <= 1.0)
                .count();
            outln!(
                "| {name} | {label} | {} | {wins} of {} |",
                mean.join(" / "),
                3 * runs.len()
            );
        }
    }
}
