//! Methods are data: a step-1 method defined here, outside the crate's table, runs through the one
//! executor (stages, observers, termination, the parameter file, the typed errors) with nothing but
//! its `MethodSpec`; and the documentation lists exactly the table's methods.

mod common;

use dualcal::dataset::Split;
use dualcal::metrics::evaluate;
use dualcal::params::ParamsFile;
use dualcal::robot::RobotDescription;
use dualcal::simulate::{self, SimOptions, SimOutput};
use dualcal::solver::least_squares::{DistanceLeastSquares, LsqAlgorithm};
use dualcal::solver::methods::set_up::{ArmSetUp, ArmStage, least_squares_solver};
use dualcal::solver::{
    BaseMethod, CalibrationError, CalibrationEvent, CalibrationSettings, Calibrator, Method,
    MethodSpec, Observes, SolverKind, Stage,
};

/// Gauss–Newton (step halving) on all three reflectors' distance errors: the set-up of `lsq` with
/// another algorithm, written the way a new method's file is.
const GAUSS_NEWTON_ALL: MethodSpec = MethodSpec {
    name: "gauss-newton-all",
    objective: "GaussNewtonAll",
    aliases: &[],
    label: "Gauss–Newton, all reflectors",
    summary: "Minimises the sum of all three reflectors' squared distance errors (Gauss–Newton).",
    fits: "Gauss–Newton on the distance errors",
    table_label: "Gauss–Newton",
    paper: None,
    observes: Observes::ThreeReflectors,
    count_rule: "9n − 18 independent distances (test method)",
    min_configurations: dualcal::solver::min_configurations,
    identifies_tracker_frame: false,
    takes_reflector: false,
    solver: SolverKind::LeastSquares,
    set_up: gauss_newton_all,
    tree_set_up: None,
};

fn gauss_newton_all(s: &ArmSetUp) -> Result<ArmStage, CalibrationError> {
    let start = s.all_distances()?;
    let problem = DistanceLeastSquares {
        problem: start.problem,
        reflectors: vec![true; 3],
    };
    Ok(ArmStage {
        solver: least_squares_solver(problem, LsqAlgorithm::GaussNewton, &s.options),
        identifiability: start.report,
        reflector: None,
    })
}

const TEST_METHOD: Method = Method::new(&GAUSS_NEWTON_ALL);

/// The built-in robot's simulation without collision checks, noise-free.
fn noise_free(seed: u64, n: usize, cal: usize) -> SimOutput {
    let robot = RobotDescription::builtin_irb14000();
    let nominal = robot.nominal_model(SimOptions::default_reflectors());
    let mut opts = simulate::paper_options(seed, n, cal);
    opts.tracker.mpe_um = 0.0;
    opts.tracker.mpe_um_per_m = 0.0;
    simulate::simulate(&opts, &nominal, &|_, _| false).expect("simulation")
}

#[test]
fn a_method_outside_the_table_runs_through_the_one_executor() {
    let sim = noise_free(5, 60, 40);
    let settings = CalibrationSettings {
        method: TEST_METHOD,
        ..CalibrationSettings::default()
    };
    let mut started = Vec::new();
    let mut iterations = 0;
    let mut observer = |e: &CalibrationEvent| match e {
        CalibrationEvent::StageStarted { stage, .. } => started.push(*stage),
        CalibrationEvent::Iteration(r) => {
            iterations += 1;
            // A least-squares stage reports no reflector weights.
            assert!(r.lambda.is_none() || r.stage == Stage::Base, "{r:?}");
        }
        CalibrationEvent::StageFinished { .. } => {}
    };
    let result = Calibrator::new(&sim.dataset, &sim.nominal)
        .settings(settings.clone())
        .observer(&mut observer)
        .run()
        .expect("calibration");
    assert_eq!(started.len(), 3, "{started:?}");
    assert!(iterations > 3);
    assert!(result.is_converged(), "{:?}", result.warnings());
    assert_eq!(result.settings.method, TEST_METHOD);
    assert_ne!(result.settings.method, Method::LeastSquares);
    assert!(!result.uses_sqp(Stage::Arm(dualcal::side::Side::Left)));
    assert!(
        result.uses_sqp(Stage::Base),
        "step 2 is the paper's minimax"
    );
    // Gauss–Newton on noise-free distances recovers the truth (as `lsq` does).
    let v = evaluate(&sim.dataset, &result.calibrated, Split::Ver).unwrap();
    for s in [
        v.relative_left.unwrap(),
        v.relative_right.unwrap(),
        v.collaborative.unwrap(),
    ] {
        assert!(s.pos_rms_mm < 1e-5, "{s:?}");
    }
    // The parameter file names it by its spellings.
    let file = ParamsFile::from_calibration(&result, &sim.dataset);
    let method = file.method.as_ref().unwrap();
    assert_eq!(method["arm_method"], "gauss-newton-all");
    assert_eq!(method["objective"], "GaussNewtonAll");
    assert_eq!(
        method["name"],
        "two-step calibration: step 1 Gauss–Newton on the distance errors, step 2 minimax (paper \
         Algorithm II)"
    );
    // Only the table's methods are found by name.
    assert_eq!(Method::named("gauss-newton-all"), None);
    // Its count rule and minimum are its own.
    let few = sim.dataset.with_cal_subset(3);
    let err = Calibrator::new(&few, &sim.nominal)
        .settings(settings)
        .run()
        .unwrap_err();
    assert!(
        matches!(err, CalibrationError::TooFewConfigurations { method, .. } if method == TEST_METHOD.name()),
        "{err}"
    );
    assert!(err.to_string().contains("(test method)"), "{err}");
}

/// The backquoted names in the first cells of the markdown table whose header starts with `header`.
fn first_column(doc: &str, header: &str) -> Vec<String> {
    doc.lines()
        .skip_while(|l| !l.starts_with(header))
        .skip(2)
        .take_while(|l| l.starts_with('|'))
        .filter_map(|l| {
            let cell = l.split('|').nth(1)?;
            let name = cell.split('`').nth(1)?;
            Some(name.to_string())
        })
        .collect()
}

#[test]
fn docs_describe_every_method_of_the_table() {
    let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("docs/solver.md");
    let doc = std::fs::read_to_string(path).unwrap();
    let step1: Vec<&str> = Method::ALL.iter().map(|m| m.name()).collect();
    let step2: Vec<&str> = BaseMethod::ALL.iter().map(|m| m.name()).collect();
    assert_eq!(first_column(&doc, "| step 1 `--method`"), step1);
    assert_eq!(first_column(&doc, "| step 2 `--base-method`"), step2);
}
