//! `dualcal-params/1`: round trips, unit conversion and refusal of malformed files.

mod common;

use dualcal::kinematics::{ArmModel, DualArmModel, IRB14000_NOMINAL_DH, N_PARAMS};
use dualcal::params::{self, FixedParameter, FixedParameters, ParamsError, ParamsFile, Provenance};
use dualcal::side::PerSide;
use nalgebra::{Isometry3, Matrix3, Rotation3, Translation3, UnitQuaternion, Vector3};
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use std::path::Path;

fn random_model(seed: u64) -> DualArmModel {
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let arm = |rng: &mut ChaCha8Rng| {
        let nominal = ArmModel::nominal_irb14000(common::reflectors_mm());
        let v = nominal.to_vector()
            + nalgebra::DVector::from_fn(N_PARAMS, |_, _| rng.random_range(-0.01..0.01));
        nominal.with_vector(&v)
    };
    let left = arm(&mut rng);
    let right = arm(&mut rng);
    let axis = Vector3::new(rng.random(), rng.random(), rng.random::<f64>()) - Vector3::repeat(0.5);
    let rotation = UnitQuaternion::from_scaled_axis(axis * 4.0);
    let translation = Translation3::new(61.61, -70.77, -34.14);
    DualArmModel {
        arms: PerSide::new(left, right),
        left_base_from_right_base: Isometry3::from_parts(translation, rotation),
    }
}

fn max_model_diff(a: &DualArmModel, b: &DualArmModel) -> (f64, f64, f64) {
    let arms = (a.arms.left.to_vector() - b.arms.left.to_vector())
        .amax()
        .max((a.arms.right.to_vector() - b.arms.right.to_vector()).amax());
    let ra = a.left_base_from_right_base.rotation.to_rotation_matrix();
    let rb = b.left_base_from_right_base.rotation.to_rotation_matrix();
    let rot = (ra.matrix() - rb.matrix()).amax();
    let tr = (a.left_base_from_right_base.translation.vector
        - b.left_base_from_right_base.translation.vector)
        .amax();
    (arms, rot, tr)
}

fn write_text(dir: &Path, text: &str) -> std::path::PathBuf {
    let p = dir.join("params.json");
    std::fs::write(&p, text).unwrap();
    p
}

/// A valid file as text (from a random model), to be edited by the tests.
fn valid_json(seed: u64) -> serde_json::Value {
    serde_json::to_value(ParamsFile::from_model(&random_model(seed))).unwrap()
}

#[test]
fn model_round_trips_through_a_file() {
    let dir = tempfile::tempdir().unwrap();
    for seed in 0..20 {
        let model = random_model(seed);
        let p = dir.path().join(format!("m{seed}.json"));
        params::write_model(&model, &p).unwrap();
        let back = params::read_model(&p).unwrap();
        let (arms, rot, tr) = max_model_diff(&model, &back);
        // serde_json's default float parser may be off by one ulp; well below these bounds.
        assert!(arms < 1e-12, "DH/reflectors differ by {arms}");
        assert!(rot < 1e-12, "rotation differs by {rot}");
        assert!(tr < 1e-12, "translation differs by {tr}");
    }
}

#[test]
fn file_has_the_documented_shape() {
    let v = valid_json(1);
    assert_eq!(v["format"], "dualcal-params/1");
    assert_eq!(v["units"]["length"], "mm");
    assert_eq!(v["units"]["angle"], "rad");
    for side in ["left", "right"] {
        let dh = v["arms"][side]["dh"].as_array().unwrap();
        assert_eq!(dh.len(), 7);
        for key in ["a", "d", "theta", "alpha"] {
            assert!(dh[3][key].is_f64(), "{side} dh[3].{key}");
        }
        for r in ["a", "b", "c"] {
            assert_eq!(
                v["arms"][side]["reflectors"][r].as_array().unwrap().len(),
                3
            );
        }
    }
    assert_eq!(
        v["right_base_in_left"]["translation"]
            .as_array()
            .unwrap()
            .len(),
        3
    );
    let rot = v["right_base_in_left"]["rotation"].as_array().unwrap();
    assert_eq!(rot.len(), 3);
    assert!(rot.iter().all(|r| r.as_array().unwrap().len() == 3));
    // Optional fields are left out when empty.
    assert!(v.get("statistics").is_none() && v.get("provenance").is_none());
    // Rows of the rotation are rows of the matrix: R · e_x is the first column.
    let model = random_model(1);
    let ex = model.left_base_from_right_base.rotation * Vector3::x();
    for i in 0..3 {
        assert_eq!(rot[i][0].as_f64().unwrap(), ex[i]);
    }
    // Nominal values appear where the issue shows them.
    assert!((v["arms"]["left"]["dh"][0]["d"].as_f64().unwrap() - 166.0).abs() < 0.02);
}

#[test]
fn optional_fields_and_unknown_extras_survive() {
    let dir = tempfile::tempdir().unwrap();
    let mut f = ParamsFile::from_model(&random_model(2));
    f.method = Some(serde_json::json!({"name": "minimax", "steps": 2}));
    f.fixed_parameters = Some(FixedParameters {
        left: vec![FixedParameter {
            name: "theta1".into(),
            reason: "coupled with the base".into(),
        }],
        right: vec![FixedParameter {
            name: "t_c.z".into(),
            reason: "not identifiable".into(),
        }],
    });
    f.termination = Some(serde_json::json!({"reason": "Converged", "iterations": 17}));
    f.statistics = Some(serde_json::json!({"pos_rms_mm": 0.12}));
    f.provenance = Some(Provenance::now(Some(Path::new("assets/datasets/sim"))));
    f.extra
        .insert("comment".into(), serde_json::json!("from another tool"));
    let p = dir.path().join("p.json");
    f.write(&p).unwrap();
    let back = ParamsFile::read(&p).unwrap();
    let (arms, rot, tr) = max_model_diff(&f.to_model().unwrap(), &back.to_model().unwrap());
    assert!(arms < 1e-12 && rot < 1e-12 && tr < 1e-12);
    assert_eq!(back.method, f.method);
    assert_eq!(back.fixed_parameters, f.fixed_parameters);
    assert_eq!(back.termination, f.termination);
    assert_eq!(back.statistics, f.statistics);
    assert_eq!(back.provenance, f.provenance);
    assert_eq!(back.extra, f.extra);
    let prov = back.provenance.unwrap();
    assert_eq!(prov.tool, "dualcal");
    assert_eq!(prov.date_utc.as_ref().unwrap().len(), 20);
    assert!(
        std::fs::read_to_string(&p)
            .unwrap()
            .contains("\n  \"format\": \"dualcal-params/1\"")
    );
}

#[test]
fn metres_and_degrees_are_converted() {
    let model = random_model(3);
    let mut v = serde_json::to_value(ParamsFile::from_model(&model)).unwrap();
    v["units"] = serde_json::json!({"length": "m", "angle": "deg"});
    let scale = |x: &mut serde_json::Value, k: f64| *x = serde_json::json!(x.as_f64().unwrap() * k);
    for side in ["left", "right"] {
        for row in v["arms"][side]["dh"].as_array_mut().unwrap() {
            scale(&mut row["a"], 1e-3);
            scale(&mut row["d"], 1e-3);
            scale(&mut row["theta"], 180.0 / std::f64::consts::PI);
            scale(&mut row["alpha"], 180.0 / std::f64::consts::PI);
        }
        for r in ["a", "b", "c"] {
            for x in v["arms"][side]["reflectors"][r].as_array_mut().unwrap() {
                scale(x, 1e-3);
            }
        }
    }
    for x in v["right_base_in_left"]["translation"]
        .as_array_mut()
        .unwrap()
    {
        scale(x, 1e-3);
    }
    let dir = tempfile::tempdir().unwrap();
    let p = write_text(dir.path(), &v.to_string());
    let back = params::read_model(&p).unwrap();
    let (arms, rot, tr) = max_model_diff(&model, &back);
    assert!(arms < 1e-9 && rot < 1e-12 && tr < 1e-9, "{arms} {rot} {tr}");
}

#[test]
fn slightly_non_orthonormal_rotation_is_repaired() {
    let mut v = valid_json(4);
    let r = v["right_base_in_left"]["rotation"][1][2].as_f64().unwrap();
    v["right_base_in_left"]["rotation"][1][2] = serde_json::json!(r + 4e-7);
    let f: ParamsFile = serde_json::from_value(v).unwrap();
    let m = f.to_model().unwrap();
    let rm = m.left_base_from_right_base.rotation.to_rotation_matrix();
    let rm = rm.matrix();
    assert!((rm.transpose() * rm - Matrix3::identity()).amax() < 1e-14);
}

// ---------------------------------------------------------------------------------------------------
// Refusals

fn err_of(text: &str) -> ParamsError {
    let dir = tempfile::tempdir().unwrap();
    let p = write_text(dir.path(), text);
    let e = params::read_model(&p).unwrap_err();
    assert!(e.to_string().contains("params.json"), "{e}");
    e
}

#[test]
fn json_syntax_error_has_line_and_column() {
    let text = serde_json::to_string_pretty(&valid_json(5)).unwrap();
    let broken = text.replacen("\"theta\":", "\"theta\"", 1);
    let line = broken
        .lines()
        .position(|l| l.contains("\"theta\" "))
        .unwrap()
        + 1;
    let e = err_of(&broken);
    assert!(
        matches!(e, ParamsError::Json { line: l, .. } if l == line),
        "{e:?}"
    );
    assert!(
        e.to_string().contains(&format!("params.json:{line}:")),
        "{e}"
    );
}

#[test]
fn missing_field_names_the_field() {
    let mut v = valid_json(5);
    v["arms"]["right"]["dh"][2]
        .as_object_mut()
        .unwrap()
        .remove("alpha");
    let e = err_of(&serde_json::to_string_pretty(&v).unwrap());
    assert!(matches!(e, ParamsError::Json { .. }), "{e:?}");
    assert!(e.to_string().contains("alpha"), "{e}");
}

#[test]
fn wrong_or_missing_format_tag() {
    let mut v = valid_json(6);
    v["format"] = serde_json::json!("dualcal-params/9");
    let e = err_of(&v.to_string());
    assert!(matches!(e, ParamsError::Format { .. }), "{e:?}");
    assert!(e.to_string().contains("dualcal-params/9"));
    v.as_object_mut().unwrap().remove("format");
    assert!(matches!(err_of(&v.to_string()), ParamsError::Format { .. }));
    assert!(matches!(err_of("[1, 2]"), ParamsError::Format { .. }));
    assert!(matches!(err_of(""), ParamsError::Json { .. }));
}

#[test]
fn six_dh_rows_are_refused() {
    let mut v = valid_json(7);
    v["arms"]["left"]["dh"].as_array_mut().unwrap().pop();
    let e = err_of(&v.to_string());
    assert!(
        matches!(e, ParamsError::Invalid { ref field, .. } if field == "arms.left.dh"),
        "{e:?}"
    );
    assert!(e.to_string().contains("6 rows"));
}

#[test]
fn unknown_units_are_refused() {
    let mut v = valid_json(8);
    v["units"]["length"] = serde_json::json!("inch");
    let e = err_of(&v.to_string());
    assert!(
        matches!(e, ParamsError::Invalid { ref field, .. } if field == "units.length"),
        "{e:?}"
    );
    let mut v = valid_json(8);
    v["units"]["angle"] = serde_json::json!("grad");
    let e = err_of(&v.to_string());
    assert!(
        matches!(e, ParamsError::Invalid { ref field, .. } if field == "units.angle"),
        "{e:?}"
    );
}

#[test]
fn non_rotations_are_refused() {
    let mut v = valid_json(9);
    v["right_base_in_left"]["rotation"][0][0] = serde_json::json!(1.5);
    let e = err_of(&v.to_string());
    assert!(
        matches!(e, ParamsError::Invalid { ref field, .. } if field == "right_base_in_left.rotation"),
        "{e:?}"
    );
    // A reflection is orthonormal but not a rotation.
    let mut v = valid_json(9);
    for j in 0..3 {
        let x = v["right_base_in_left"]["rotation"][2][j].as_f64().unwrap();
        v["right_base_in_left"]["rotation"][2][j] = serde_json::json!(-x);
    }
    let e = err_of(&v.to_string());
    assert!(e.to_string().contains("det"), "{e}");
}

#[test]
fn two_by_three_rotation_is_a_json_error() {
    let mut v = valid_json(9);
    v["right_base_in_left"]["rotation"]
        .as_array_mut()
        .unwrap()
        .pop();
    assert!(matches!(err_of(&v.to_string()), ParamsError::Json { .. }));
}

#[test]
fn unknown_fixed_parameter_name_is_refused() {
    let mut v = valid_json(10);
    v["fixed_parameters"] = serde_json::json!({"left": [{"name": "theta8", "reason": "x"}]});
    let e = err_of(&v.to_string());
    assert!(
        matches!(e, ParamsError::Invalid { ref field, .. } if field == "fixed_parameters.left[0].name"),
        "{e:?}"
    );
    // Every real name is accepted.
    let names: Vec<_> = (0..N_PARAMS)
        .map(|k| serde_json::json!({"name": dualcal::kinematics::param_name(k), "reason": "test"}))
        .collect();
    let mut v = valid_json(10);
    v["fixed_parameters"] = serde_json::json!({"right": names});
    let f: ParamsFile = serde_json::from_value(v).unwrap();
    f.to_model().unwrap();
}

#[test]
fn non_finite_values_are_never_written() {
    let dir = tempfile::tempdir().unwrap();
    let mut model = random_model(11);
    model.arms.right.dh_mut().unwrap()[4].theta_rad = f64::NAN;
    let p = dir.path().join("bad.json");
    let e = params::write_model(&model, &p).unwrap_err();
    assert!(
        matches!(e, ParamsError::Invalid { ref field, path: Some(_), .. } if field == "arms.right.dh[4].theta"),
        "{e:?}"
    );
    assert!(!p.exists());
}

#[test]
fn nominal_irb14000_table_survives() {
    let model = DualArmModel {
        arms: PerSide::new(
            ArmModel::nominal_irb14000([Vector3::zeros(); 3]),
            ArmModel::nominal_irb14000([Vector3::zeros(); 3]),
        ),
        left_base_from_right_base: Isometry3::from_parts(
            Translation3::new(1.0, 2.0, 3.0),
            UnitQuaternion::from_rotation_matrix(&Rotation3::from_euler_angles(0.1, 0.2, 0.3)),
        ),
    };
    let back = ParamsFile::from_model(&model).to_model().unwrap();
    assert_eq!(back.arms.left.dh(), Some(&IRB14000_NOMINAL_DH));
}

#[test]
fn utf16_empty_and_binary_files_are_refused() {
    let dir = tempfile::tempdir().unwrap();
    let text = serde_json::to_string_pretty(&valid_json(8)).unwrap();
    let utf16: Vec<u8> = [0xFF, 0xFE]
        .into_iter()
        .chain(text.encode_utf16().flat_map(u16::to_le_bytes))
        .collect();
    let p = dir.path().join("params.json");
    std::fs::write(&p, utf16).unwrap();
    let e = params::read_model(&p).unwrap_err();
    assert!(matches!(e, ParamsError::Text { .. }), "{e:?}");
    assert!(e.to_string().contains("save it as UTF-8"), "{e}");
    std::fs::write(&p, b"{\"format\": \0}").unwrap();
    assert!(matches!(
        params::read_model(&p),
        Err(ParamsError::Text { .. })
    ));
    let e = err_of("  \n");
    assert!(e.to_string().contains("empty"), "{e}");
    // A byte-order mark and CRLF line ends are fine.
    let crlf = format!("\u{feff}{}", text.replace('\n', "\r\n"));
    params::read_model(&write_text(dir.path(), &crlf)).unwrap();
}

#[test]
fn absurd_magnitudes_are_refused() {
    for (pointer, value, field) in [
        ("/arms/left/dh/3/d", 1e12, "arms.left.dh[3].d"),
        ("/arms/right/dh/0/theta", -5e3, "arms.right.dh[0].theta"),
        ("/arms/right/reflectors/b/2", 2e6, "arms.right.reflectors.b"),
        (
            "/right_base_in_left/translation/1",
            1e300,
            "right_base_in_left.translation",
        ),
    ] {
        let mut v = valid_json(9);
        *v.pointer_mut(pointer).unwrap() = serde_json::json!(value);
        let e = err_of(&v.to_string());
        assert!(
            matches!(e, ParamsError::Invalid { field: ref f, .. } if f == field),
            "{pointer}: {e:?}"
        );
        assert!(e.to_string().contains("plausible"), "{e}");
    }
}

#[test]
fn messages_quote_at_most_a_short_excerpt() {
    let mut v = valid_json(10);
    let long = "x".repeat(5000);
    v["arms"]["left"]["dh"][0]["a"] = serde_json::json!(long);
    let e = err_of(&v.to_string());
    assert!(e.to_string().len() < 400, "{e}");
    v["format"] = serde_json::json!(long);
    let e = err_of(&v.to_string());
    assert!(e.to_string().len() < 400, "{e}");
}
