//! Planning the measurement (issue 23), simulated: the planner's configurations against random ones of
//! the same number, measured on the same true robot by the same tracker, calibrated alike and judged
//! on the same verification configurations against what the true parameters give there.

mod common;
mod plan_sim;
#[path = "fixtures/robots.rs"]
mod robots;

use dualcal::collision::CollisionWorld;
use dualcal::dataset::Dataset;
use dualcal::plan::{PlanOptions, plan};
use dualcal::robot::RobotDescription;
use dualcal::side::{PerSide, Side};
use dualcal::simulate::{default_reflectors_for, paper_options, simulate_with_robot};
use dualcal::solver::{CalibrationSettings, Method};
use nalgebra::Vector3;
use plan_sim::{
    measured, noise_seed, planned_and_random, ratio_to_truth_by, simulation_and_options,
};

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
        // The plan's prediction over the region (the workspace, where the simulator verifies) for
        // the default method: within 5 % of the minimax fit's measured ratio, on either side (one
        // noise draw and one random verification set; docs/planning.md). The candidates'
        // least-squares prediction (`o.predicted`) is optimistic for a workspace (issue 44).
        let region = |side: Side| {
            planned[side]
                .prediction
                .as_ref()
                .expect("a prediction over the region")
                .default_method
                .mean
        };
        let predicted = 0.5 * (region(Side::Left) + region(Side::Right));
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
        // The plan's prediction by positions over the region, within 6 % on either side (before
        // issue 44 the candidates' efficient-fit figure, `o.efficient`, optimistic for a workspace).
        let position = |side: Side| {
            planned[side]
                .prediction
                .as_ref()
                .expect("a prediction over the region")
                .position
                .mean
        };
        let efficient = 0.5 * (position(Side::Left) + position(Side::Right));
        eprintln!(
            "seed {seed}: verification RMS over the truth's — planned {rp:.3} (by positions \
             {by_position:.3}, predicted {efficient:.3}), random {rr:.3}"
        );
        assert!(
            (by_position / efficient - 1.0).abs() < 0.06,
            "seed {seed}: by positions {by_position:.3}, predicted {efficient:.3}"
        );
        // Per seed the planned set may lose (one noise draw: seed 3 measures 1.100 against
        // 1.087 since issue 44's region criterion); on average and in spread it wins (below).
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
    assert!(spread(|r| r.0) < spread(|r| r.1));
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

/// `--target` (issue 44): the plan's N is the smallest tried whose predicted accuracy over the region
/// (the default method's mean) reaches the target, every smaller N tried misses it, and the one just
/// below was tried; the curve is sorted by N.
#[test]
fn a_target_plans_the_smallest_number_that_reaches_it() {
    let robot = RobotDescription::builtin_irb14000();
    let target = 1.3;
    let options = PlanOptions {
        candidates: 120,
        region_samples: 30,
        prediction_draws: 12,
        robust_draws: 2,
        tracker_in_body_mm: Vector3::new(2000.0, 0.0, 500.0),
        target: Some(target),
        ..PlanOptions::default()
    };
    let planned = plan(&robot, &default_reflectors_for(&robot), &options).unwrap();
    let reaches = |p: &Option<dualcal::plan::RegionPrediction>| {
        p.as_ref().unwrap().default_method.mean <= target
    };
    for side in Side::BOTH {
        let p = &planned[side];
        let n = p.configs.len();
        assert!(reaches(&p.prediction), "{side}: {:?}", p.curve);
        assert!(p.curve.windows(2).all(|w| w[0].0 < w[1].0), "{side}");
        assert!(p.curve.iter().any(|(m, _)| *m == n), "{side}");
        for (m, pred) in p.curve.iter().filter(|(m, _)| *m < n) {
            assert!(!reaches(pred), "{side}: {m} configurations reach it too");
        }
        assert!(
            n == 6 || p.curve.iter().any(|(m, _)| *m == n - 1),
            "{side}: {n} chosen, {:?} tried",
            p.curve.iter().map(|c| c.0).collect::<Vec<_>>()
        );
    }
}
