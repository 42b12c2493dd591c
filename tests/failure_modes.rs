//! How a calibration ends when it cannot succeed: never a panic, never a silent wrong answer. Data of
//! another robot make the solver run away (`Diverged`, with the last plausible parameters and a
//! warning naming the parameter); too few configurations after exclusions are refused; exclusions are
//! honoured; identifiability is re-checked at the solution.

use dualcal::dataset::{Dataset, Split};
use dualcal::kinematics::DualArmModel;
use dualcal::robot::RobotDescription;
use dualcal::side::{ConfigId, Side};
use dualcal::simulate::{self, SimOptions, SimOutput};
use dualcal::solver::{
    CalibrationError, CalibrationEvent, CalibrationSettings, Calibrator, DIVERGED_ANGLE_RAD,
    DIVERGED_LENGTH_MM, Method, Stage, Termination,
};

fn small(seed: u64, n: usize, cal: usize) -> SimOutput {
    let robot = RobotDescription::builtin_irb14000();
    let nominal = robot.nominal_model(SimOptions::default_reflectors());
    let opts = simulate::paper_options(seed, n, cal);
    simulate::simulate(&opts, &nominal, &|_, _| false).expect("simulation")
}

fn n_configs_per_stage(ds: &Dataset, nominal: &DualArmModel, s: CalibrationSettings) -> Vec<usize> {
    let mut sizes = Vec::new();
    let mut obs = |e: &CalibrationEvent| {
        if let CalibrationEvent::StageStarted { n_configs, .. } = e {
            sizes.push(*n_configs);
        }
    };
    Calibrator::new(ds, nominal)
        .settings(s)
        .observer(&mut obs)
        .run()
        .unwrap();
    sizes
}

#[test]
fn data_of_another_robot_diverge_with_the_last_plausible_parameters() {
    let sim = small(1, 40, 40);
    // The user's nominal model has a link 300 mm too short: no calibration, a runaway.
    let mut nominal = sim.nominal.clone();
    let mut v = nominal.arms.left.to_vector();
    v[8] -= 300.0; // a3
    nominal.arms.left = nominal.arms.left.with_vector(&v);
    let result = Calibrator::new(&sim.dataset, &nominal).run().unwrap();
    let left = result.stage(Stage::Arm(Side::Left)).unwrap();
    assert_eq!(left.termination, Termination::Diverged, "{left:?}");
    assert!(!result.is_converged());
    // The parameters kept are plausible: within the bounds of the nominal model.
    let moved = result.calibrated.arms.left.to_vector() - nominal.arms.left.to_vector();
    for k in 0..moved.len() {
        let bound = if nominal.arms.left.param_is_angle(k) {
            DIVERGED_ANGLE_RAD
        } else {
            DIVERGED_LENGTH_MM
        };
        assert!(moved[k].abs() <= bound, "parameter {k} moved {}", moved[k]);
    }
    let warnings = result.warnings().join("\n");
    assert!(warnings.contains("diverged"), "{warnings}");
    assert!(warnings.contains("from its nominal value"), "{warnings}");
    // The other stages still ran, and the right arm converged.
    let right = result.stage(Stage::Arm(Side::Right)).unwrap();
    assert!(right.termination.is_converged(), "{right:?}");
    assert!(result.stage(Stage::Base).is_some());
    // The result can be written: every value is finite.
    let file = dualcal::params::ParamsFile::from_calibration(&result, &sim.dataset);
    assert_eq!(file.converged, Some(false));
    file.to_model().unwrap();
}

#[test]
fn exclusions_are_left_out_and_too_few_are_refused() {
    let sim = small(2, 30, 20);
    let excluded = vec![
        ConfigId::new(Side::Left, 0),
        ConfigId::new(Side::Left, 5),
        ConfigId::new(Side::Right, 25), // a verification configuration: no change
    ];
    let sizes = n_configs_per_stage(
        &sim.dataset,
        &sim.nominal,
        CalibrationSettings {
            exclude: excluded.clone(),
            ..Default::default()
        },
    );
    assert_eq!(sizes, [18, 20, 38]);
    // Down to 5 calibration configurations of the left arm: refused, naming the arm and the minimum.
    let exclude: Vec<ConfigId> = (0..15).map(|i| ConfigId::new(Side::Left, i)).collect();
    let err = Calibrator::new(&sim.dataset, &sim.nominal)
        .settings(CalibrationSettings {
            exclude,
            ..Default::default()
        })
        .run()
        .unwrap_err();
    assert!(
        matches!(
            err,
            CalibrationError::TooFewConfigurations {
                side: Side::Left,
                found: 5,
                needed: 6,
                params: 31,
                method,
                ..
            } if method == Method::Minimax.name()
        ),
        "{err}"
    );
    // The dataset view without them.
    let kept = sim.dataset.excluding(&excluded);
    assert_eq!(kept.arms.left.measurements.len(), 28);
    assert_eq!(kept.arms.right.measurements.len(), 29);
    assert_eq!(kept.arms.left.measurements[0].id, "L002");
    assert_eq!(
        sim.dataset.config_by_id("L006"),
        Ok(ConfigId::new(Side::Left, 5))
    );
    assert_eq!(
        sim.dataset.config_by_id("right:R002"),
        Ok(ConfigId::new(Side::Right, 1))
    );
    assert!(sim.dataset.config_by_id("left:R002").is_err());
}

#[test]
fn identifiability_is_rechecked_at_the_solution() {
    let sim = small(3, 60, 60);
    let result = Calibrator::new(&sim.dataset, &sim.nominal).run().unwrap();
    assert!(result.is_converged(), "{:?}", result.warnings());
    for side in Side::BOTH {
        let start = result.identifiability[side].as_ref().unwrap();
        let end = result.identifiability_at_solution[side].as_ref().unwrap();
        assert_eq!(start.free, end.free, "{side}");
        assert!(end.condition_after.is_finite());
    }
    assert!(result.warnings().is_empty(), "{:?}", result.warnings());
    // No configuration in the selected split: refused cleanly.
    let err = Calibrator::new(&sim.dataset, &sim.nominal)
        .settings(CalibrationSettings {
            split: Split::Ver,
            ..Default::default()
        })
        .run()
        .unwrap_err();
    assert!(matches!(
        err,
        CalibrationError::TooFewConfigurations { found: 0, .. }
    ));
}
