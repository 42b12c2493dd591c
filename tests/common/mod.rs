//! Helpers shared by the integration tests (each test file includes this module with `mod common;`
//! and uses what it needs).
#![allow(dead_code)]

use dualcal::dataset::Dataset;
use dualcal::kinematics::DualArmModel;
use dualcal::solver::{CalibrationResult, CalibrationSettings, Calibrator, Termination};
use nalgebra::Vector3;

/// The reflector coordinates (flange frame, mm) the tests' synthetic data use: a = (45, 0, 40),
/// b = (−25, 40, 40), c = (−25, −40, 40). Written out here rather than taken from the simulator, so
/// that the tests' data does not move with its defaults.
pub fn reflectors_mm() -> [Vector3<f64>; 3] {
    [
        Vector3::new(45.0, 0.0, 40.0),
        Vector3::new(-25.0, 40.0, 40.0),
        Vector3::new(-25.0, -40.0, 40.0),
    ]
}

/// Calibrate without observers. Panics when the input is refused or a stage ran out of iterations (a
/// test that means to check those calls [`Calibrator`] itself); a stall is returned for the test to
/// judge.
pub fn calibrate(
    dataset: &Dataset,
    nominal: &DualArmModel,
    settings: &CalibrationSettings,
) -> CalibrationResult {
    let result = Calibrator::new(dataset, nominal)
        .settings(settings.clone())
        .run()
        .expect("calibration");
    // `DUALCAL_DUMP_FAILED=DIR` keeps the dataset of a calibration that ran out of iterations in DIR
    // (a `dualcal-dataset/1` directory; add the robot's `robot = "…"` for a URDF robot) to rerun it
    // with `dualcal calibrate DIR`.
    if let Ok(dir) = std::env::var("DUALCAL_DUMP_FAILED")
        && result
            .stages
            .iter()
            .any(|s| s.termination == Termination::MaxIterations)
    {
        let _ = dualcal::dataset::save(
            dataset,
            std::path::Path::new(&dir),
            dualcal::dataset::Units::default(),
        );
    }
    for stage in &result.stages {
        assert_ne!(
            stage.termination,
            Termination::MaxIterations,
            "{stage:?} ran out of iterations"
        );
    }
    result
}

/// The Python that runs this repository's `tools/*.py`: `DUALCAL_PYTHON` if set, else the first of
/// `python3`, `/usr/bin/python3` that can `import` every module of `imports` (comma-separated, e.g.
/// `"numpy, tomllib"`). Panics — fails the test, never skips it — with a message saying what to install
/// when there is none: `tools/test` installs what the tests need.
pub fn python(imports: &str) -> String {
    use std::collections::HashMap;
    use std::sync::{Mutex, OnceLock};
    static FOUND: OnceLock<Mutex<HashMap<String, Result<String, String>>>> = OnceLock::new();
    let mut found = FOUND
        .get_or_init(Default::default)
        .lock()
        .unwrap_or_else(|e| e.into_inner());
    let result = found
        .entry(imports.to_string())
        .or_insert_with(|| find_python(imports))
        .clone();
    drop(found);
    match result {
        Ok(py) => py,
        Err(tried) => panic!(
            "this test needs a Python 3 that can `import {imports}` (on Debian the packages python3 and \
             python3-numpy, which `tools/test` installs), or DUALCAL_PYTHON naming such a Python; \
             tried {tried}"
        ),
    }
}

fn find_python(imports: &str) -> Result<String, String> {
    let candidates: Vec<String> = match std::env::var("DUALCAL_PYTHON") {
        Ok(p) => vec![p],
        Err(_) => vec!["python3".into(), "/usr/bin/python3".into()],
    };
    let mut tried = Vec::new();
    for py in &candidates {
        match std::process::Command::new(py)
            .args(["-c", &format!("import {imports}")])
            .output()
        {
            Ok(out) if out.status.success() => return Ok(py.clone()),
            Ok(out) => tried.push(format!(
                "`{py}`: {}",
                String::from_utf8_lossy(&out.stderr)
                    .trim()
                    .lines()
                    .last()
                    .unwrap_or("")
            )),
            Err(e) => tried.push(format!("`{py}`: {e}")),
        }
    }
    Err(tried.join("; "))
}

/// Relative (both arms) and collaborative position RMS of a report, labelled, mm.
pub fn position_figures(r: &dualcal::metrics::AccuracyReport) -> [(&'static str, f64); 3] {
    [
        ("relative left", r.relative_left.unwrap().pos_rms_mm),
        ("relative right", r.relative_right.unwrap().pos_rms_mm),
        (
            "collaborative",
            r.collaborative.map_or(f64::NAN, |c| c.pos_rms_mm),
        ),
    ]
}

/// The set-up tests' bar: on the verification split each figure of the calibrated model within 10%
/// of the truth's, the nominal model's more than ten times off (printed as it goes).
pub fn assert_near_truth(
    name: &str,
    nominal: &dualcal::metrics::AccuracyReport,
    truth: &dualcal::metrics::AccuracyReport,
    calibrated: &dualcal::metrics::AccuracyReport,
) {
    for ((label, n), ((_, t), (_, c))) in position_figures(nominal).into_iter().zip(
        position_figures(truth)
            .into_iter()
            .zip(position_figures(calibrated)),
    ) {
        eprintln!("{name} {label}: nominal {n:.4} mm, truth {t:.4} mm, calibrated {c:.4} mm");
        assert!(n > 10.0 * t, "{name} {label}: nominal {n} vs truth {t}");
        assert!(c <= 1.1 * t, "{name} {label}: calibrated {c} vs truth {t}");
    }
}

/// The simulated dataset with its points replaced by the true points plus fresh noise of `sigma_mm`
/// per axis (repeated measurements of one robot at one set of configurations).
pub fn renoised(sim: &dualcal::simulate::SimOutput, seed: u64, sigma_mm: f64) -> Dataset {
    use rand::SeedableRng;
    use rand_distr::Distribution;
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(seed);
    let noise = rand_distr::Normal::new(0.0, sigma_mm).unwrap();
    let mut ds = sim.dataset.clone();
    for side in dualcal::side::Side::BOTH {
        let tracker_from_base = sim.tracker_from_left_base * sim.truth.left_base_from(side);
        for m in &mut ds.arms[side].measurements {
            let fk = sim.truth.arm(side).reflector_fk(&m.q_rad);
            for (p, truth) in m.tracker_points_mm.iter_mut().zip(&fk.points_mm) {
                let t = tracker_from_base
                    .transform_point(&nalgebra::Point3::from(*truth))
                    .coords;
                *p = t + Vector3::from_fn(|_, _| noise.sample(&mut rng));
            }
        }
    }
    ds
}

/// ROS's `check_urdf` accepts the URDF at `path` (Debian's liburdfdom-tools, which `tools/test`
/// installs); `name` labels the failure.
pub fn assert_check_urdf(path: &std::path::Path, name: &str) {
    let o = std::process::Command::new("check_urdf")
        .arg(path)
        .output()
        .unwrap_or_else(|e| {
            panic!(
                "this test needs ROS's check_urdf (Debian: liburdfdom-tools, which tools/test \
                 installs): {e}"
            )
        });
    assert!(
        o.status.success(),
        "{name}: check_urdf: {}{}",
        String::from_utf8_lossy(&o.stdout),
        String::from_utf8_lossy(&o.stderr)
    );
}

/// `tools/urdf_fk.py` (the independent forward kinematics, numpy) on `urdf` from `base` to `tip` at
/// the configurations `qs` (URDF units), with the positions of `links` below the tip: its JSON
/// output (`joints`, `configs[i].tip` 4 × 4 mm, `configs[i].links[name]`). `configs_json` is where
/// the configurations are written for it.
#[allow(dead_code)] // not every test file that includes this module runs the FK
pub fn urdf_fk(
    urdf: &std::path::Path,
    base: &str,
    tip: &str,
    qs: &[Vec<f64>],
    links: &[String],
    configs_json: &std::path::Path,
) -> serde_json::Value {
    std::fs::write(configs_json, serde_json::to_vec(qs).unwrap()).unwrap();
    let out = std::process::Command::new(python("numpy"))
        .arg(std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("tools/urdf_fk.py"))
        .arg(urdf)
        .args([base, tip])
        .arg(configs_json)
        .args(links)
        .output()
        .expect("run tools/urdf_fk.py");
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    serde_json::from_slice(&out.stdout).unwrap()
}
