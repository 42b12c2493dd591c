//! The planning studies' simulations (issue 23), shared by tests/plan.rs and the studies of
//! examples/plan_study.rs: the planner's configurations against random ones of the same number,
//! measured on the same true robot by the same tracker, calibrated alike and judged on the same
//! verification configurations against what the true parameters give there. Each includer uses part
//! of it (and includes `tests/common/mod.rs` as `common`).
#![allow(dead_code)]

use dualcal::collision::CollisionWorld;
use dualcal::dataset::{Dataset, Measurement, Split};
use dualcal::metrics::evaluate;
use dualcal::plan::{PlanOptions, plan};
use dualcal::robot::RobotDescription;
use dualcal::side::{PerSide, Side};
use dualcal::simulate::{SimOutput, default_reflectors_for, paper_options, simulate_with_robot};
use dualcal::solver::{CalibrationSettings, Method};
use nalgebra::{Point3, Vector3};
use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;
use rand_distr::{Distribution, StandardNormal};

/// The true robot of `sim` at `configs`, seen by its tracker with the simulator's noise (half the
/// MPE at the distance, per axis), as calibration measurements.
pub fn measured(sim: &SimOutput, side: Side, configs: &[Vec<f64>], seed: u64) -> Vec<Measurement> {
    measured_as(sim, side, configs, seed, Split::Cal)
}

/// [`measured`] in the split `split` (verification measurements named `V…`/`W…`).
pub fn measured_as(
    sim: &SimOutput,
    side: Side,
    configs: &[Vec<f64>],
    seed: u64,
    split: Split,
) -> Vec<Measurement> {
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let tracker = sim.dataset.tracker;
    let tracker_from_base = sim.tracker_from_left_base * sim.truth.left_base_from(side);
    // `DUALCAL_PLAN_CAL_NOISE=0` measures the calibration configurations without noise (0.1 a tenth
    // of it, …): what is left of the ratio is then the model's and the solver's, not the noise's.
    let scale = match split {
        Split::Cal => std::env::var("DUALCAL_PLAN_CAL_NOISE")
            .ok()
            .and_then(|v| v.parse::<f64>().ok())
            .unwrap_or(1.0),
        _ => 1.0,
    };
    let prefix = match (side, split) {
        (Side::Left, Split::Ver) => 'V',
        (Side::Right, Split::Ver) => 'W',
        (Side::Left, _) => 'P',
        (Side::Right, _) => 'Q',
    };
    configs
        .iter()
        .enumerate()
        .map(|(i, q)| {
            let fk = sim.truth.arm(side).reflector_fk(q);
            let tracker_points_mm = fk
                .points_mm
                .iter()
                .map(|p| {
                    let p = tracker_from_base.transform_point(&Point3::from(*p)).coords;
                    let sigma =
                        scale * 0.5e-3 * (tracker.mpe_um + tracker.mpe_um_per_m * p.norm() / 1e3);
                    let n: [f64; 3] = std::array::from_fn(|_| StandardNormal.sample(&mut rng));
                    p + sigma * Vector3::from(n)
                })
                .collect();
            Measurement {
                id: format!("{prefix}{:03}", i + 1),
                q_rad: q.clone(),
                tracker_points_mm,
                split,
                line: i + 2,
            }
        })
        .collect()
}

/// The mean of both arms' relative verification RMS of the model calibrated on `configs`, over that of
/// the true parameters (by the curve's method: `DUALCAL_PLAN_METHOD=lsq`, or any step-1 method's
/// name — `position`, … —; minimax by default).
/// Judged on the simulator's verification configurations, or on `verification` where given (measured
/// with the noise of `seed`, the same for every design of one draw).
pub fn ratio_to_truth(
    sim: &SimOutput,
    configs: &PerSide<Vec<Vec<f64>>>,
    verification: Option<&PerSide<Vec<Vec<f64>>>>,
    seed: u64,
) -> f64 {
    let method = std::env::var("DUALCAL_PLAN_METHOD").ok().map(|name| {
        Method::named(&name)
            .unwrap_or_else(|| panic!("DUALCAL_PLAN_METHOD={name}: no step-1 method of that name"))
    });
    ratio_to_truth_by(sim, configs, verification, seed, method)
}

/// [`ratio_to_truth`] calibrating by `method` (the default method where `None`).
pub fn ratio_to_truth_by(
    sim: &SimOutput,
    configs: &PerSide<Vec<Vec<f64>>>,
    verification: Option<&PerSide<Vec<Vec<f64>>>>,
    seed: u64,
    method: Option<Method>,
) -> f64 {
    let mut ds: Dataset = sim.dataset.clone();
    for side in Side::BOTH {
        let ver: Vec<Measurement> = match verification {
            Some(v) => measured_as(sim, side, &v[side], seed + 50 + side as u64, Split::Ver),
            None => ds
                .arm(side)
                .select(Split::Ver)
                .into_iter()
                .cloned()
                .collect(),
        };
        let mut ms = measured(sim, side, &configs[side], seed + side as u64);
        ms.extend(ver);
        ds.arms[side].measurements = ms;
    }
    let settings = CalibrationSettings {
        method: method.unwrap_or(CalibrationSettings::default().method),
        ..CalibrationSettings::default()
    };
    let result = crate::common::calibrate(&ds, &sim.nominal, &settings);
    let rms = |model| {
        let r = evaluate(&ds, model, Split::Ver).unwrap();
        0.5 * (r.relative_left.unwrap().pos_rms_mm + r.relative_right.unwrap().pos_rms_mm)
    };
    rms(&result.calibrated) / rms(&sim.truth)
}

/// What one simulation gives at one N: the planned and the first `n` random calibration
/// configurations' ratios to the truth, the plans, and what the plans predict per arm: the
/// verification ratio (least squares), the bound on any design of `n` of the candidates, and the
/// chosen design's ratio with an efficient fit of its distances.
pub struct Outcome {
    pub planned: f64,
    pub random: f64,
    /// Both ratios for each of the noise draws ([`noise_seeds`]; the first is `planned`, `random`).
    pub draws: Vec<(f64, f64)>,
    pub plans: PerSide<dualcal::plan::ArmPlan>,
    pub options: PlanOptions,
    pub predicted: PerSide<f64>,
    pub bound: PerSide<f64>,
    pub efficient: PerSide<f64>,
}

/// The simulation of `seed` and the options planning `n` per arm for it (the tracker where the
/// simulation put it).
pub fn simulation_and_options(
    robot: &RobotDescription,
    seed: u64,
    n: usize,
) -> (SimOutput, PlanOptions) {
    let sim = simulate_with_robot(&paper_options(seed, 220, 120), robot).unwrap();
    let tracker_in_body = robot.body_from_arm_base(Side::Left)
        * sim
            .tracker_from_left_base
            .inverse_transform_point(&Point3::origin());
    // `DUALCAL_PLAN_CANDIDATES` tries another pool size in the curve below (600 by default).
    let candidates = std::env::var("DUALCAL_PLAN_CANDIDATES")
        .ok()
        .and_then(|v| v.parse().ok())
        .unwrap_or(600);
    let options = PlanOptions {
        per_arm: n,
        candidates,
        seed,
        tracker_in_body_mm: tracker_in_body.coords,
        ..PlanOptions::default()
    };
    (sim, options)
}

/// The measurement's noise draws of the simulation of `seed` (`DUALCAL_PLAN_NOISE=k` draws it
/// otherwise, `DUALCAL_PLAN_NOISE=0,1,2,3` several times over the same plans; 0 by default).
pub fn noise_seeds(seed: u64) -> Vec<u64> {
    let draws: Vec<u64> = std::env::var("DUALCAL_PLAN_NOISE").map_or_else(
        |_| vec![0],
        |v| v.split(',').filter_map(|n| n.trim().parse().ok()).collect(),
    );
    draws.into_iter().map(|k| 100 * seed + k).collect()
}

/// The first of [`noise_seeds`].
pub fn noise_seed(seed: u64) -> u64 {
    noise_seeds(seed)[0]
}

/// Whether the random calibration sets and the verification configurations are drawn as the planner
/// draws its candidates (`DUALCAL_PLAN_DRAWS=candidates`: facing the tracker within the incidence
/// limit and range, clear of collisions, every reflector in the tracker's line of sight, the joint
/// margins kept) — what a tracker could measure — instead of the simulator's own (facing and
/// collisions only).
pub fn drawn_as_candidates() -> bool {
    std::env::var("DUALCAL_PLAN_DRAWS").is_ok_and(|v| v == "candidates")
}

/// `count` configurations per arm passing the planner's checks, from a pool of their own (`stream`
/// keeps the random sets' and the verification's draws apart from each other and from the plan's).
pub fn drawn_like_candidates(
    robot: &RobotDescription,
    options: &PlanOptions,
    stream: u64,
    count: usize,
) -> PerSide<Vec<Vec<f64>>> {
    let world = CollisionWorld::new(robot);
    let nominal = robot.nominal_model(default_reflectors_for(robot).to_vec());
    let options = PlanOptions {
        candidates: count,
        seed: options.seed + 1_000_003 * stream,
        ..options.clone()
    };
    PerSide::from_fn(|side| {
        dualcal::plan::candidates(robot, nominal.arm(side), side, &world, &options)
            .unwrap()
            .0
    })
}

/// Plan `n` per arm for the simulation of `seed` and calibrate on the plan and on random
/// configurations ([`Outcome`]).
pub fn planned_and_random(robot: &RobotDescription, seed: u64, n: usize) -> Outcome {
    let (sim, options) = simulation_and_options(robot, seed, n);
    let planned = plan(robot, &default_reflectors_for(robot), &options).unwrap();
    let equal_terms = drawn_as_candidates();
    // On equal terms: 100 verification configurations per arm (as the simulator's) and the random
    // sets from the planner's checks; the first `n` of a stream are the same at every N.
    let verification = equal_terms.then(|| drawn_like_candidates(robot, &options, 2, 100));
    let planned_configs = planned.as_ref().map(|_, p| p.configs.clone());
    let nominal = robot.nominal_model(default_reflectors_for(robot).to_vec());
    let predicted = PerSide::from_fn(|side| {
        dualcal::solver::uncertainty::predicted_for_tracker(
            robot,
            nominal.arm(side),
            side,
            &planned[side].configs,
            &planned[side].sample,
            &sim.dataset.tracker,
            &options.tracker_in_body_mm,
        )
        .and_then(|d| d.verification_ratio)
        .unwrap()
    });
    // The same prediction on the simulator's own verification configurations (where the ratio is
    // measured) rather than on the unchosen candidates.
    let on_ver = PerSide::from_fn(|side| {
        let arm = nominal.arm(side);
        let free = dualcal::solver::identifiability::identifiable_at(arm, &planned[side].configs);
        let ver: Vec<Vec<f64>> = match &verification {
            Some(v) => v[side].clone(),
            None => sim
                .dataset
                .arm(side)
                .select(Split::Ver)
                .iter()
                .map(|m| m.q_rad.clone())
                .collect(),
        };
        dualcal::solver::uncertainty::predicted_verification_ratio(
            arm,
            &planned[side].configs,
            &ver,
            &free,
            0.01,
        )
        .unwrap()
    });
    let bound = PerSide::from_fn(|side| planned[side].bound.as_ref().unwrap().ratio());
    let efficient = PerSide::from_fn(|side| planned[side].bound.as_ref().unwrap().design_ratio());
    let mean = |v: &PerSide<f64>| 0.5 * (v.left + v.right);
    eprintln!(
        "seed {seed}, N {n}: predicted verification ratio {:.3} (least squares; {:.3} on the \
         verification configurations), {:.3} with an efficient fit; bound on any design {:.3}",
        mean(&predicted),
        mean(&on_ver),
        mean(&efficient),
        mean(&bound)
    );
    let random = if equal_terms {
        drawn_like_candidates(robot, &options, 1, n)
    } else {
        PerSide::from_fn(|side| {
            sim.dataset
                .arm(side)
                .select(Split::Cal)
                .iter()
                .take(n)
                .map(|m| m.q_rad.clone())
                .collect::<Vec<_>>()
        })
    };
    let draws: Vec<(f64, f64)> = noise_seeds(seed)
        .into_iter()
        .map(|noise| {
            (
                ratio_to_truth(&sim, &planned_configs, verification.as_ref(), noise),
                ratio_to_truth(&sim, &random, verification.as_ref(), noise),
            )
        })
        .collect();
    Outcome {
        planned: draws[0].0,
        random: draws[0].1,
        draws,
        plans: planned,
        options,
        predicted,
        bound,
        efficient,
    }
}
