//! The planner on the independent simulator (issue 44): `tools/indep_sim.py` draws a true robot apart
//! from dualcal's models (errors in all six components of every joint origin, zero offsets, reflector
//! offsets, distance-dependent noise, the station drawn around the nominal one) and measures the
//! planned configurations; `dualcal calibrate` and `dualcal evaluate` judge the result on the
//! verification configurations (random, within 80 % of the joint limits). Small sizes: a debug build
//! runs it. The acceptance study itself is `tools/plan_accept.py` (docs/planning.md).

mod common;

use std::path::Path;
use std::process::Command;

/// The standard output of `command`, which must succeed (else its standard error, as `what`).
fn succeed(mut command: Command, what: &str) -> String {
    let out = command.output().unwrap_or_else(|e| panic!("{what}: {e}"));
    assert!(
        out.status.success(),
        "{what}: {}",
        String::from_utf8_lossy(&out.stderr)
    );
    String::from_utf8(out.stdout).expect("utf-8")
}

fn dualcal(args: &[&str]) -> String {
    let mut command = Command::new(env!("CARGO_BIN_EXE_dualcal"));
    command.args(args);
    succeed(command, &format!("dualcal {args:?}"))
}

fn indep_sim(args: &[&str]) -> String {
    let mut command = Command::new(common::python("numpy"));
    command
        .arg(Path::new(env!("CARGO_MANIFEST_DIR")).join("tools/indep_sim.py"))
        .args(args);
    succeed(command, &format!("indep_sim.py {args:?}"))
}

/// Both arms' mean verification relative positioning RMS of `dualcal evaluate … --json`.
fn relative_rms(json: &str) -> f64 {
    let v: serde_json::Value = serde_json::from_str(json).expect("evaluate --json");
    let arm = |k: &str| v[k]["pos_rms_mm"].as_f64().expect("pos_rms_mm");
    0.5 * (arm("relative_left") + arm("relative_right"))
}

/// The prediction the plan printed for `method` ("default method" or "by positions"), per arm.
fn predicted(plan_output: &str, method: &str) -> Vec<f64> {
    plan_output
        .lines()
        .filter_map(|l| l.split_once(&format!("{method} ")))
        .filter_map(|(_, rest)| rest.split('×').next()?.trim().parse().ok())
        .collect()
}

#[test]
fn the_independent_simulator_agrees_with_the_model_and_the_plan_predicts_what_it_measures() {
    let dir = tempfile::tempdir().unwrap();
    let d = |p: &str| dir.path().join(p).to_string_lossy().into_owned();
    let urdf = Path::new(env!("CARGO_MANIFEST_DIR")).join("assets/irb14000.urdf");
    let urdf = urdf.to_string_lossy();
    let plan = dualcal(&[
        "plan",
        "--tracker",
        "2000,0,500",
        "--n",
        "15",
        "--candidates",
        "150",
        "--region-samples",
        "40",
        "--out",
        &d("plan"),
    ]);
    let (def, pos) = (
        predicted(&plan, "default method"),
        predicted(&plan, "by positions"),
    );
    assert_eq!((def.len(), pos.len()), (2, 2), "{plan}");
    // Without noise the true robot's own URDF, read by dualcal, gives the simulator's points: the
    // independent kinematics and the model agree on the perturbed description.
    indep_sim(&[
        "measure",
        "--urdf",
        &urdf,
        "--configs",
        &d("plan"),
        "--seed",
        "3",
        "--builtin",
        "--noise-scale",
        "0",
        "--nver",
        "30",
        "--out",
        &d("exact"),
    ]);
    let exact = relative_rms(&dualcal(&[
        "evaluate",
        &d("exact/truth"),
        "--nominal",
        "--split",
        "all",
        "--json",
    ]));
    let nominal = relative_rms(&dualcal(&[
        "evaluate",
        &d("exact/data"),
        "--nominal",
        "--split",
        "ver",
        "--json",
    ]));
    assert!(
        exact < 1e-5,
        "the truth's own error without noise: {exact} mm"
    );
    assert!(
        nominal > 0.2,
        "the drawn errors move the points: {nominal} mm"
    );
    // With noise: the calibrated model within the prediction's reach of the noise floor.
    indep_sim(&[
        "measure",
        "--urdf",
        &urdf,
        "--configs",
        &d("plan"),
        "--seed",
        "3",
        "--builtin",
        "--nver",
        "60",
        "--out",
        &d("sim"),
    ]);
    let floor = relative_rms(&dualcal(&[
        "evaluate",
        &d("sim/truth"),
        "--nominal",
        "--split",
        "ver",
        "--json",
    ]));
    for (method, prediction) in [("minimax", &def), ("position", &pos)] {
        let params = d(&format!("{method}.json"));
        dualcal(&[
            "calibrate",
            &d("sim/data"),
            "--method",
            method,
            "--out",
            &params,
            "--quiet",
        ]);
        let calibrated = relative_rms(&dualcal(&[
            "evaluate",
            &d("sim/data"),
            "--params",
            &params,
            "--split",
            "ver",
            "--json",
        ]));
        let measured = calibrated / floor;
        let predicted = 0.5 * (prediction[0] + prediction[1]);
        println!("{method}: measured {measured:.3}, predicted {predicted:.3}");
        assert!(
            measured > 1.0 && nominal / floor > 10.0 * measured,
            "{method}: calibrated {measured:.3}× the floor, nominal {:.1}×",
            nominal / floor
        );
        // One simulation scatters about the mean (±0.1 at N = 15, docs/planning.md): a loose check
        // that still fails a prediction off by the 25 %.
        assert!(
            (measured - predicted).abs() <= 0.15 * measured,
            "{method}: measured {measured:.3}× the floor, predicted {predicted:.3}×"
        );
    }
}
