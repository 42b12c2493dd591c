//! Planning the measurement (issue 23), simulated: the planner's configurations against random ones of
//! the same number, measured on the same true robot by the same tracker, calibrated alike and judged
//! on the same verification configurations against what the true parameters give there.

mod common;
#[path = "fixtures/robots.rs"]
mod robots;

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
fn measured(sim: &SimOutput, side: Side, configs: &[Vec<f64>], seed: u64) -> Vec<Measurement> {
    measured_as(sim, side, configs, seed, Split::Cal)
}

/// [`measured`] in the split `split` (verification measurements named `V…`/`W…`).
fn measured_as(
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
fn ratio_to_truth(
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
fn ratio_to_truth_by(
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
    let result = common::calibrate(&ds, &sim.nominal, &settings);
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
struct Outcome {
    planned: f64,
    random: f64,
    /// Both ratios for each of the noise draws ([`noise_seeds`]; the first is `planned`, `random`).
    draws: Vec<(f64, f64)>,
    plans: PerSide<dualcal::plan::ArmPlan>,
    options: PlanOptions,
    predicted: PerSide<f64>,
    bound: PerSide<f64>,
    efficient: PerSide<f64>,
}

/// The simulation of `seed` and the options planning `n` per arm for it (the tracker where the
/// simulation put it).
fn simulation_and_options(
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
fn noise_seeds(seed: u64) -> Vec<u64> {
    let draws: Vec<u64> = std::env::var("DUALCAL_PLAN_NOISE").map_or_else(
        |_| vec![0],
        |v| v.split(',').filter_map(|n| n.trim().parse().ok()).collect(),
    );
    draws.into_iter().map(|k| 100 * seed + k).collect()
}

/// The first of [`noise_seeds`].
fn noise_seed(seed: u64) -> u64 {
    noise_seeds(seed)[0]
}

/// Whether the random calibration sets and the verification configurations are drawn as the planner
/// draws its candidates (`DUALCAL_PLAN_DRAWS=candidates`: facing the tracker within the incidence
/// limit and range, clear of collisions, every reflector in the tracker's line of sight, the joint
/// margins kept) — what a tracker could measure — instead of the simulator's own (facing and
/// collisions only).
fn drawn_as_candidates() -> bool {
    std::env::var("DUALCAL_PLAN_DRAWS").is_ok_and(|v| v == "candidates")
}

/// `count` configurations per arm passing the planner's checks, from a pool of their own (`stream`
/// keeps the random sets' and the verification's draws apart from each other and from the plan's).
fn drawn_like_candidates(
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
fn planned_and_random(robot: &RobotDescription, seed: u64, n: usize) -> Outcome {
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

/// 20 planned configurations per arm against 20 random ones on four simulations (the IRB 14000, the
/// paper's errors and tracker; each verified on the same 100 random configurations): every planned
/// configuration is free of collisions, its design better than the random one's and the exchange's
/// no worse than the greedy pass's, the bound below the design's prediction, and the planned sets
/// calibrate better on every seed and far more evenly. The target — within 1.10× of the
/// true parameters' accuracy with 20 — is reached by the default method (minimax) on one seed of
/// four (1.114 on average), and on every seed by the absolute positions' fit (`position`), which
/// measures what the efficient fit of the design predicts (docs/planning.md).
#[test]
fn twenty_planned_configurations_calibrate_better_than_twenty_random_ones() {
    let robot = RobotDescription::builtin_irb14000();
    let world = CollisionWorld::new(&robot);
    let mut ratios = Vec::new();
    let mut by_positions = Vec::new();
    for seed in [1, 2, 3, 4] {
        let o = planned_and_random(&robot, seed, 20);
        let (rp, rr, planned, options) = (o.planned, o.random, &o.plans, &o.options);
        let predicted = 0.5 * (o.predicted.left + o.predicted.right);
        // The prediction is a least-squares one from the candidates' spread, linearised: within
        // 5 % of the minimax fit's measured ratio, on either side (one noise draw and one random
        // verification set; docs/planning.md).
        assert!(
            predicted > 1.0 && (rp / predicted - 1.0).abs() < 0.05,
            "seed {seed}: predicted {predicted:.3}, measured {rp:.3}"
        );
        for side in Side::BOTH {
            // The bound holds the design's least-squares prediction (Gauss–Markov: an efficient fit
            // of the same distances does at least as well, and no design of 20 of the candidates
            // does better than the relaxation).
            assert!(
                1.0 < o.bound[side]
                    && o.bound[side] <= o.efficient[side] * (1.0 + 1e-9)
                    && o.efficient[side] <= o.predicted[side] * (1.0 + 1e-9),
                "seed {seed}, {side}: bound {:.4}, efficient {:.4}, least squares {:.4}",
                o.bound[side],
                o.efficient[side],
                o.predicted[side]
            );
            let p = &planned[side];
            // The exchange never worsens the greedy design.
            assert!(p.criterion <= p.criterion_greedy, "{side}");
            assert_eq!(p.configs.len(), 20);
            assert!(
                p.log_det > p.log_det_random,
                "{side}: {} vs {}",
                p.log_det,
                p.log_det_random
            );
            let home = robot.home_q_rad(side.other());
            for q in &p.configs {
                let free = match side {
                    Side::Left => !world.in_collision(q, &home, options.clearance_mm),
                    Side::Right => !world.in_collision(&home, q, options.clearance_mm),
                };
                assert!(free, "{side}: a planned configuration collides");
            }
        }
        // The same planned sets calibrated by the absolute positions with the tracker's pose
        // (`position`, ref. [18]): the efficient fit the bound's design ratio predicts, within 6 %
        // on either side, and within the 1.10× on every seed.
        let configs = o.plans.as_ref().map(|_, p| p.configs.clone());
        let (sim, _) = simulation_and_options(&robot, seed, 20);
        let by_position = ratio_to_truth_by(
            &sim,
            &configs,
            None,
            noise_seed(seed),
            Some(Method::Position),
        );
        let efficient = 0.5 * (o.efficient.left + o.efficient.right);
        eprintln!(
            "seed {seed}: verification RMS over the truth's — planned {rp:.3} (by positions \
             {by_position:.3}, an efficient fit predicting {efficient:.3}), random {rr:.3}"
        );
        assert!(
            (by_position / efficient - 1.0).abs() < 0.06 && by_position < 1.10,
            "seed {seed}: by positions {by_position:.3}, efficient fit predicted {efficient:.3}"
        );
        assert!(rp < rr, "seed {seed}: planned {rp:.3}, random {rr:.3}");
        ratios.push((rp, rr));
        by_positions.push(by_position);
    }
    let by_positions_mean = by_positions.iter().sum::<f64>() / by_positions.len() as f64;
    eprintln!("mean by positions {by_positions_mean:.3}");
    let mean = |f: fn(&(f64, f64)) -> f64| ratios.iter().map(f).sum::<f64>() / ratios.len() as f64;
    let spread = |f: fn(&(f64, f64)) -> f64| {
        let v: Vec<f64> = ratios.iter().map(f).collect();
        v.iter().copied().fold(f64::NEG_INFINITY, f64::max)
            - v.iter().copied().fold(f64::INFINITY, f64::min)
    };
    let (planned, random) = (mean(|r| r.0), mean(|r| r.1));
    eprintln!(
        "mean planned {planned:.3} (spread {:.3}), random {random:.3} (spread {:.3})",
        spread(|r| r.0),
        spread(|r| r.1)
    );
    assert!(planned < random, "{planned} vs {random}");
    assert!(planned < 1.14, "{planned}");
    assert!(spread(|r| r.0) < spread(|r| r.1));
}

/// The curve of docs/planning.md: verification RMS over the truth's against N, planned and random,
/// four simulations each by default (`cargo test --release --test plan -- --ignored --nocapture`;
/// `DUALCAL_PLAN_N=20` for one N, `DUALCAL_PLAN_CANDIDATES=3000` for another pool,
/// `DUALCAL_PLAN_METHOD=lsq` to calibrate by least squares (or any step-1 method's name),
/// `DUALCAL_PLAN_ROBOT=yumi.urdf` for a robot description, `DUALCAL_PLAN_SEEDS=1,2,3,4,5,6,7,8`
/// for other simulations, `DUALCAL_PLAN_NOISE=1` for another draw of the measurement's noise,
/// `DUALCAL_PLAN_NOISE=0,1,2,3` for several over the same plans: every seed and draw is one
/// simulation of the figures; `DUALCAL_PLAN_DRAWS=candidates` draws the random sets and the
/// verification configurations by the planner's own checks, [`drawn_as_candidates`]).
#[test]
#[ignore]
fn accuracy_against_the_number_of_configurations() {
    // `DUALCAL_PLAN_ROBOT=yumi.urdf` plans and simulates a robot description of the user's own (the
    // arms found as `dualcal plan --robot` finds them; the built-in IRB 14000 by default).
    let robot = std::env::var("DUALCAL_PLAN_ROBOT").map_or_else(
        |_| RobotDescription::builtin_irb14000(),
        |path| RobotDescription::load(std::path::Path::new(&path), &Default::default()).unwrap(),
    );
    let ns: Vec<usize> = std::env::var("DUALCAL_PLAN_N").map_or_else(
        |_| vec![10, 15, 20, 30, 40],
        |v| v.split(',').filter_map(|n| n.trim().parse().ok()).collect(),
    );
    let seeds: Vec<u64> = std::env::var("DUALCAL_PLAN_SEEDS").map_or_else(
        |_| vec![1, 2, 3, 4],
        |v| v.split(',').filter_map(|n| n.trim().parse().ok()).collect(),
    );
    eprintln!("N   planned (mean, min–max)   random (mean, min–max)");
    let mut curve = Vec::new();
    for n in ns {
        let outcomes: Vec<Outcome> = seeds
            .iter()
            .map(|&seed| planned_and_random(&robot, seed, n))
            .collect();
        for (seed, o) in seeds.iter().zip(&outcomes) {
            let each: Vec<String> = o
                .draws
                .iter()
                .map(|(p, q)| format!("planned {p:.3}, random {q:.3}"))
                .collect();
            eprintln!("seed {seed}, N {n}: {}", each.join("; "));
        }
        // Every simulation: each seed with each noise draw.
        let r: Vec<(f64, f64)> = outcomes.iter().flat_map(|o| o.draws.clone()).collect();
        let arms = |f: fn(&Outcome) -> &PerSide<f64>| {
            outcomes
                .iter()
                .map(|o| 0.5 * (f(o).left + f(o).right))
                .sum::<f64>()
                / outcomes.len() as f64
        };
        let stats = |f: fn(&(f64, f64)) -> f64| {
            let v: Vec<f64> = r.iter().map(f).collect();
            (
                v.iter().sum::<f64>() / v.len() as f64,
                v.iter().copied().fold(f64::INFINITY, f64::min),
                v.iter().copied().fold(f64::NEG_INFINITY, f64::max),
            )
        };
        let (p, q) = (stats(|x| x.0), stats(|x| x.1));
        eprintln!(
            "{n:<3} {:.3} ({:.3}–{:.3})       {:.3} ({:.3}–{:.3})   planned better on {} of {} \
             simulations; predicted {:.3}, efficient {:.3}, bound {:.3}",
            p.0,
            p.1,
            p.2,
            q.0,
            q.1,
            q.2,
            r.iter().filter(|x| x.0 < x.1).count(),
            r.len(),
            arms(|o| &o.predicted),
            arms(|o| &o.efficient),
            arms(|o| &o.bound)
        );
        curve.push(CurvePoint {
            n,
            planned: p,
            random: q,
            efficient: arms(|o| &o.efficient),
        });
    }
    // `DUALCAL_PLAN_SVG=FILE` draws the curve (docs/planning-curve.svg is such a drawing).
    if let Ok(path) = std::env::var("DUALCAL_PLAN_SVG") {
        let method = std::env::var("DUALCAL_PLAN_METHOD").unwrap_or_else(|_| "minimax".into());
        let draws = if drawn_as_candidates() {
            "random and verification sets drawn by the planner's checks"
        } else {
            "the simulator's random and verification sets"
        };
        let title = format!(
            "calibrated by {method}; {} simulations per N ({draws})",
            seeds.len() * noise_seeds(0).len()
        );
        std::fs::write(&path, curve_svg(&curve, &title)).unwrap();
        eprintln!("curve drawn in {path}");
    }
}

/// One N of the curve: the planned and the random sets' ratios (mean, min, max over the simulations)
/// and the efficient fit's prediction for the planned sets.
struct CurvePoint {
    n: usize,
    planned: (f64, f64, f64),
    random: (f64, f64, f64),
    efficient: f64,
}

/// The curve as an SVG drawing, the analogue of the paper's Fig. 4 for the planner: the verification
/// RMS over the true parameters' against N, planned and random (means, bars from the smallest to the
/// largest simulation), the efficient fit's prediction for the planned sets, and the 1.10.
fn curve_svg(curve: &[CurvePoint], subtitle: &str) -> String {
    use plotters::prelude::*;
    const FONT: &str = "sans-serif";
    let mut svg = String::new();
    {
        let root = SVGBackend::with_string(&mut svg, (900, 560)).into_drawing_area();
        root.fill(&WHITE).unwrap();
        let x_hi = curve.iter().map(|c| c.n).max().unwrap_or(1) as f64 + 5.0;
        let y_hi = curve
            .iter()
            .map(|c| c.planned.2.max(c.random.2))
            .fold(1.2_f64, f64::max)
            .min(3.0)
            + 0.02;
        let mut chart = ChartBuilder::on(&root)
            .caption(
                format!("Verification accuracy against the number of configurations per arm — {subtitle}"),
                (FONT, 14),
            )
            .margin(12)
            .x_label_area_size(44)
            .y_label_area_size(60)
            .build_cartesian_2d(0.0..x_hi, 0.98..y_hi)
            .unwrap();
        chart
            .configure_mesh()
            .x_desc("calibration configurations per arm (N)")
            .y_desc("verification RMS / true parameters' RMS")
            .label_style((FONT, 11))
            .axis_desc_style((FONT, 12))
            .bold_line_style(RGBColor(215, 215, 215))
            .light_line_style(RGBColor(242, 242, 242))
            .draw()
            .unwrap();
        let target = RGBColor(200, 40, 40);
        chart
            .draw_series(LineSeries::new(
                [(0.0, 1.10), (x_hi, 1.10)],
                target.stroke_width(1),
            ))
            .unwrap()
            .label("the issue's target, 1.10")
            .legend(move |(x, y)| PathElement::new(vec![(x, y), (x + 16, y)], target));
        let series = [
            ("random", RGBColor(150, 150, 150), 3.0, 1),
            ("planned", RGBColor(30, 90, 200), -3.0, 0),
        ];
        for (name, colour, shift, which) in series {
            let pick = |c: &CurvePoint| if which == 0 { c.planned } else { c.random };
            chart
                .draw_series(curve.iter().map(|c| {
                    let (mean, lo, hi) = pick(c);
                    ErrorBar::new_vertical(c.n as f64 + shift / 10.0, lo, mean, hi, colour, 6)
                }))
                .unwrap();
            chart
                .draw_series(LineSeries::new(
                    curve.iter().map(|c| (c.n as f64, pick(c).0)),
                    colour.stroke_width(2),
                ))
                .unwrap()
                .label(format!("{name} (mean; bars: smallest to largest)"))
                .legend(move |(x, y)| {
                    PathElement::new(vec![(x, y), (x + 16, y)], colour.stroke_width(2))
                });
        }
        let predicted = RGBColor(30, 90, 200);
        chart
            .draw_series(DashedLineSeries::new(
                curve.iter().map(|c| (c.n as f64, c.efficient)),
                5,
                4,
                predicted.stroke_width(1),
            ))
            .unwrap()
            .label("planned: the efficient fit's prediction")
            .legend(move |(x, y)| PathElement::new(vec![(x, y), (x + 16, y)], predicted));
        chart
            .configure_series_labels()
            .background_style(WHITE.mix(0.9))
            .border_style(RGBColor(200, 200, 200))
            .label_font((FONT, 11))
            .position(SeriesLabelPosition::UpperRight)
            .draw()
            .unwrap();
        root.present().unwrap();
    }
    svg
}

/// The relaxation rounded — the candidates of its N largest weights — against the exchanged design,
/// at N = 20 (`DUALCAL_PLAN_N`) on the curve's simulations: both designs' least-squares predictions
/// on the plan's sample and their measured ratios (`cargo test --release --test plan -- --ignored
/// --nocapture the_relaxation_rounded`).
#[test]
#[ignore]
fn the_relaxation_rounded_against_the_exchanged_design() {
    let robot = RobotDescription::builtin_irb14000();
    let world = CollisionWorld::new(&robot);
    let reflectors = default_reflectors_for(&robot);
    let nominal = robot.nominal_model(reflectors.to_vec());
    let n: usize = std::env::var("DUALCAL_PLAN_N")
        .ok()
        .and_then(|v| v.parse().ok())
        .unwrap_or(20);
    let seeds: Vec<u64> = std::env::var("DUALCAL_PLAN_SEEDS").map_or_else(
        |_| vec![1, 2, 3, 4],
        |v| v.split(',').filter_map(|n| n.trim().parse().ok()).collect(),
    );
    for seed in seeds {
        let (sim, options) = simulation_and_options(&robot, seed, n);
        let planned = plan(&robot, &reflectors, &options).unwrap();
        let mut rounded = PerSide::new(Vec::new(), Vec::new());
        let mut predicted = PerSide::new((0.0, 0.0), (0.0, 0.0));
        for side in Side::BOTH {
            let arm = nominal.arm(side);
            let (pool, _) = dualcal::plan::candidates(&robot, arm, side, &world, &options).unwrap();
            let jac = dualcal::plan::scaled_jacobians(arm, &pool);
            let points: Vec<_> = pool.iter().map(|q| arm.reflector_fk(q).points_mm).collect();
            let index = |q: &Vec<f64>| pool.iter().position(|c| c == q).unwrap();
            let p = &planned[side];
            let design: Vec<usize> = p.configs.iter().map(index).collect();
            let ver: Vec<usize> = p.sample.iter().map(index).collect();
            let bound = dualcal::plan::bound::relaxed_bound(
                &points,
                &jac,
                pool.len(),
                &[],
                n,
                &design,
                &ver,
            )
            .unwrap();
            rounded[side] = bound.largest.iter().map(|&i| pool[i].clone()).collect();
            let free = dualcal::solver::identifiability::identifiable_at(arm, &p.configs);
            let ratio = |design: &[Vec<f64>]| {
                dualcal::solver::uncertainty::predicted_verification_ratio(
                    arm, design, &p.sample, &free, 0.01,
                )
                .unwrap()
            };
            predicted[side] = (ratio(&p.configs), ratio(&rounded[side]));
        }
        let planned_configs = planned.as_ref().map(|_, p| p.configs.clone());
        let noise = noise_seed(seed);
        let (mp, mr) = (
            ratio_to_truth(&sim, &planned_configs, None, noise),
            ratio_to_truth(&sim, &rounded, None, noise),
        );
        eprintln!(
            "seed {seed}, N {n}: predicted (least squares) exchanged {:.3}, rounded {:.3}; \
             measured exchanged {mp:.3}, rounded {mr:.3}",
            0.5 * (predicted.left.0 + predicted.right.0),
            0.5 * (predicted.left.1 + predicted.right.1)
        );
    }
}

/// On a URDF robot the plan is designed and predicted for the parameters its calibration frees. On a
/// YuMi-like description (six corrections per joint origin: 31 of 51 identifiable per arm) the planner
/// took physics' list of unidentifiable parameters, which named four of each joint's axis line where two
/// are, and designed for 19: its prediction was then optimistic (on the public YuMi 1.054 by the
/// efficient fit against 1.104 measured, docs/planning.md). The design's columns, the prediction's
/// parameters and the calibration's free parameters on the planned set are now one set.
#[test]
fn a_urdf_robots_plan_is_designed_for_what_its_calibration_frees() {
    let dir = tempfile::tempdir().unwrap();
    let urdf = robots::write_file(dir.path(), "yumi.urdf", robots::yumi_like_urdf().as_bytes());
    let robot = RobotDescription::load(&urdf, &Default::default()).unwrap();
    let (sim, options) = simulation_and_options(&robot, 3, 12);
    let options = PlanOptions {
        candidates: 150,
        ..options
    };
    let reflectors = default_reflectors_for(&robot);
    let planned = plan(&robot, &reflectors, &options).unwrap();
    let nominal = robot.nominal_model(reflectors.to_vec());
    let mut ds: Dataset = sim.dataset.clone();
    for side in Side::BOTH {
        ds.arms[side].measurements = measured(&sim, side, &planned[side].configs, 40 + side as u64);
    }
    let result = common::calibrate(&ds, &sim.nominal, &CalibrationSettings::default());
    for side in Side::BOTH {
        let arm = nominal.arm(side);
        let configs = &planned[side].configs;
        let designed = dualcal::solver::identifiability::identifiable_at(arm, configs);
        let freed = &result.identifiability[side].as_ref().unwrap().free;
        assert_eq!(&designed, freed, "{side}");
        assert_eq!(designed.len(), 31, "{side}");
        assert_eq!(dualcal::solver::identifiable_params(arm), 31, "{side}");
        let columns = dualcal::plan::scaled_jacobians(arm, configs);
        assert_eq!(columns[0].ncols(), 31, "{side}");
        let predicted = dualcal::solver::uncertainty::predicted_for_tracker(
            &robot,
            arm,
            side,
            configs,
            &planned[side].sample,
            &sim.dataset.tracker,
            &options.tracker_in_body_mm,
        )
        .unwrap();
        assert_eq!(predicted.uncertainty.parameters.len(), 31, "{side}");
    }
}

/// The command writes the two joint tables in visiting order, the manifest and the RAPID modules, and
/// refuses a non-empty output directory.
#[test]
fn the_command_writes_a_dataset_to_fill_in() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("planned");
    let run = |extra: &[&str]| {
        let mut args = vec![
            "plan",
            "--tracker",
            "2000,0,300",
            "--n",
            "8",
            "--candidates",
            "60",
            "--out",
            out.to_str().unwrap(),
        ];
        args.extend_from_slice(extra);
        std::process::Command::new(env!("CARGO_BIN_EXE_dualcal"))
            .args(&args)
            .output()
            .unwrap()
    };
    let first = run(&[]);
    assert!(
        first.status.success(),
        "{}",
        String::from_utf8_lossy(&first.stderr)
    );
    for side in ["left", "right"] {
        let csv = std::fs::read_to_string(out.join(format!("{side}.csv"))).unwrap();
        let rows: Vec<&str> = csv.lines().filter(|l| !l.starts_with('#')).collect();
        assert_eq!(rows[0], "id,q1,q2,q3,q4,q5,q6,q7,split");
        assert_eq!(rows.len(), 9);
        assert!(
            rows[1..]
                .iter()
                .all(|r| r.ends_with(",cal") && r.split(',').count() == 9)
        );
        // The visiting sequence: the 8 configurations, in order, and any via points between them.
        let path = std::fs::read_to_string(out.join(format!("path_{side}.csv"))).unwrap();
        let steps: Vec<Vec<&str>> = path
            .lines()
            .filter(|l| !l.starts_with('#'))
            .skip(1)
            .map(|l| l.split(',').collect())
            .collect();
        let measured: Vec<&str> = steps
            .iter()
            .filter(|f| f[1] == "measure")
            .map(|f| f[2])
            .collect();
        let ids: Vec<&str> = rows[1..]
            .iter()
            .map(|r| r.split(',').next().unwrap())
            .collect();
        assert_eq!(measured, ids);
        let vias = steps.len() - measured.len();
        assert!(
            steps
                .iter()
                .all(|f| f.len() == 10 && (f[1] == "measure" || f[1] == "via"))
        );
        let rapid = std::fs::read_to_string(out.join(format!("plan_{side}.mod"))).unwrap();
        assert_eq!(rapid.matches("CONST jointtarget").count(), 8 + vias);
        assert_eq!(rapid.matches("MoveAbsJ").count(), 8 + vias);
    }
    let manifest = std::fs::read_to_string(out.join("dataset.toml")).unwrap();
    assert!(manifest.contains("[reflectors]") && manifest.matches("[[arms]]").count() == 2);
    let stdout = String::from_utf8_lossy(&first.stdout);
    assert!(stdout.contains("predicted 1σ"), "{stdout}");
    let again = run(&[]);
    assert_eq!(again.status.code(), Some(1));
    assert!(String::from_utf8_lossy(&again.stderr).contains("already exists"));
}

/// A description of the user's own (the lift-and-mimic test robot: a prismatic lift and a coupled
/// joint on 6-variable arms) plans alike: its chains' limits hold (the lift within 0–300 mm).
#[test]
fn a_robot_with_a_lift_and_a_mimic_joint_plans_within_its_limits() {
    let dir = tempfile::tempdir().unwrap();
    let urdf = robots::write_file(
        dir.path(),
        "lift.urdf",
        robots::lift_mimic_urdf().as_bytes(),
    );
    let arms = PerSide::new(
        Some(dualcal::robot::ArmLinks::new(
            robots::LIFT_MIMIC_ARMS[0].0,
            robots::LIFT_MIMIC_ARMS[0].1,
        )),
        Some(dualcal::robot::ArmLinks::new(
            robots::LIFT_MIMIC_ARMS[1].0,
            robots::LIFT_MIMIC_ARMS[1].1,
        )),
    );
    let robot = RobotDescription::load(
        &urdf,
        &dualcal::robot::LoadOptions {
            arms,
            ..Default::default()
        },
    )
    .unwrap();
    let options = PlanOptions {
        per_arm: 10,
        candidates: 80,
        tracker_in_body_mm: Vector3::new(2000.0, 0.0, 800.0),
        ..PlanOptions::default()
    };
    let planned = plan(&robot, &default_reflectors_for(&robot), &options).unwrap();
    for side in Side::BOTH {
        let limits = robot.joint_limits_rad(side);
        assert_eq!(planned[side].configs.len(), 10);
        for q in &planned[side].configs {
            assert_eq!(q.len(), 6);
            for (v, (lo, hi)) in q.iter().zip(&limits) {
                assert!(lo <= v && v <= hi, "{v} outside [{lo}, {hi}]");
            }
            assert!((0.0..=300.0).contains(&q[1]), "lift {}", q[1]);
        }
    }
}

/// A keep-out box (a table in front of the robot) keeps every planned configuration and the candidates
/// clear of it; the check itself sees a box around the robot and not one far away.
#[test]
fn keep_out_boxes_are_respected() {
    use dualcal::collision::KeepOutBox;
    let robot = RobotDescription::builtin_irb14000();
    let world = CollisionWorld::new(&robot);
    let home = PerSide::from_fn(|side| robot.home_q_rad(side));
    let around = KeepOutBox::parse("-2000,-2000,-2000,2000,2000,2000").unwrap();
    let far = KeepOutBox::parse("5000,5000,5000,6000,6000,6000").unwrap();
    assert!(world.in_keep_out(&home.left, &home.right, &[around], 0.0));
    assert!(!world.in_keep_out(&home.left, &home.right, &[far], 0.0));
    assert!(KeepOutBox::parse("1,2,3").is_err());
    let table = KeepOutBox::parse("250,-1000,-300,1200,1000,150").unwrap();
    let options = PlanOptions {
        per_arm: 10,
        candidates: 80,
        keep_out: vec![table],
        ..PlanOptions::default()
    };
    let planned = plan(&robot, &default_reflectors_for(&robot), &options).unwrap();
    let free = plan(
        &robot,
        &default_reflectors_for(&robot),
        &PlanOptions {
            keep_out: Vec::new(),
            ..options.clone()
        },
    )
    .unwrap();
    for side in Side::BOTH {
        for q in &planned[side].configs {
            let (l, r) = match side {
                Side::Left => (q, &home.right),
                Side::Right => (&home.left, q),
            };
            assert!(!world.in_keep_out(l, r, &[table], options.clearance_mm));
        }
        // The table costs draws: some candidates reach into it.
        assert!(
            planned[side].attempts > free[side].attempts,
            "{side}: {} vs {}",
            planned[side].attempts,
            free[side].attempts
        );
    }
}

/// Extending a dataset: its configurations start the design, the new ones are others, and the
/// combined set's information exceeds the existing set's.
#[test]
fn extending_a_dataset_adds_new_configurations() {
    let robot = RobotDescription::builtin_irb14000();
    let sim = simulate_with_robot(&paper_options(5, 30, 20), &robot).unwrap();
    let existing = PerSide::from_fn(|side| {
        sim.dataset
            .arm(side)
            .measurements
            .iter()
            .take(12)
            .map(|m| m.q_rad.clone())
            .collect::<Vec<_>>()
    });
    let options = PlanOptions {
        per_arm: 8,
        candidates: 80,
        existing: existing.clone(),
        ..PlanOptions::default()
    };
    let planned = plan(&robot, &default_reflectors_for(&robot), &options).unwrap();
    for side in Side::BOTH {
        let new = &planned[side].configs;
        assert_eq!(new.len(), 8);
        assert!(new.iter().all(|q| !existing[side].contains(q)));
    }
}

/// The line-of-sight check: from points in front of the robot a tracker behind its body is hidden, one
/// in front is seen.
#[test]
fn the_body_hides_a_tracker_behind_it() {
    let robot = RobotDescription::builtin_irb14000();
    let world = CollisionWorld::new(&robot);
    let home = PerSide::from_fn(|side| robot.home_q_rad(side));
    let points = [
        Vector3::new(400.0, 0.0, 250.0),
        Vector3::new(400.0, 50.0, 250.0),
    ];
    let behind = Vector3::new(-2000.0, 0.0, 250.0);
    let front = Vector3::new(2000.0, 0.0, 250.0);
    assert!(world.line_of_sight_blocked(&home.left, &home.right, &points, &behind, 5.0));
    assert!(!world.line_of_sight_blocked(&home.left, &home.right, &points, &front, 5.0));
}

/// A leg whose straight joint motion collides is re-routed through a via point: with the tracker
/// 2 m in front (the command's example) the 20-configuration plan of seed 1 has such a leg. Every
/// motion of the visiting sequence — the straight legs and both halves of each detour — is then
/// free of collisions at the planner's 2° steps, checked here on its own.
#[test]
fn colliding_legs_are_rerouted_through_via_points() {
    let robot = RobotDescription::builtin_irb14000();
    let world = CollisionWorld::new(&robot);
    let home = PerSide::from_fn(|side| robot.home_q_rad(side));
    let options = PlanOptions {
        tracker_in_body_mm: Vector3::new(2000.0, 0.0, 300.0),
        ..PlanOptions::default()
    };
    let planned = plan(&robot, &default_reflectors_for(&robot), &options).unwrap();
    let collides = |side: Side, a: &[f64], b: &[f64]| {
        let largest = a
            .iter()
            .zip(b)
            .map(|(x, y)| (x - y).abs())
            .fold(0.0, f64::max);
        let steps = (largest / 2f64.to_radians()).ceil().max(1.0) as usize;
        (0..=steps).any(|s| {
            let t = s as f64 / steps as f64;
            let q: Vec<f64> = a.iter().zip(b).map(|(x, y)| x + t * (y - x)).collect();
            let (l, r) = match side {
                Side::Left => (&q, &home.right),
                Side::Right => (&home.left, &q),
            };
            world.in_collision(l, r, options.clearance_mm)
        })
    };
    let mut vias = 0;
    for side in Side::BOTH {
        let p = &planned[side];
        assert!(
            p.colliding_legs.is_empty(),
            "{side}: {:?}",
            p.colliding_legs
        );
        let mut length = 0.0;
        for (k, pair) in p.configs.windows(2).enumerate() {
            let leg = |a: &[f64], b: &[f64]| -> f64 {
                a.iter()
                    .zip(b)
                    .map(|(x, y)| (x - y).powi(2))
                    .sum::<f64>()
                    .sqrt()
            };
            match p.vias.iter().find(|v| v.leg == k) {
                Some(via) => {
                    vias += 1;
                    assert!(
                        collides(side, &pair[0], &pair[1]),
                        "{side} leg {k}: a needless via"
                    );
                    assert!(
                        !collides(side, &pair[0], &via.q),
                        "{side} leg {k}, to the via"
                    );
                    assert!(
                        !collides(side, &via.q, &pair[1]),
                        "{side} leg {k}, from the via"
                    );
                    length += leg(&pair[0], &via.q) + leg(&via.q, &pair[1]);
                }
                None => {
                    assert!(!collides(side, &pair[0], &pair[1]), "{side} leg {k}");
                    length += leg(&pair[0], &pair[1]);
                }
            }
        }
        assert!(
            (length - p.path_length).abs() < 1e-9,
            "{side}: {length} vs {}",
            p.path_length
        );
    }
    assert!(
        vias >= 1,
        "the example plan has a colliding leg to re-route"
    );
}
