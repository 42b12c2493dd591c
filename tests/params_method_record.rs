//! The parameter file's `method` record is written and read by explicit spellings (a method's
//! `objective` and name, `Exact`/`Paper`, `Cal`/`Ver`/`All`), never by Rust's `Debug` output: a file
//! written before the methods became a table still reads, and writing its record again gives the
//! same text.

use dualcal::dataset::Split;
use dualcal::params::{MethodRecord, ParamsFile};
use dualcal::solver::{BaseMethod, Method, QpMethod, Reflector};
use std::path::Path;

/// A file as `dualcal calibrate assets/datasets/example --method distance-single --reflector b
/// --base-method absolute --out p.json` wrote it before the methods became a table (`statistics` and
/// `quality` left out, and all but two of each arm's fixed parameters).
const WRITTEN_BEFORE: &str = r#"{
  "format": "dualcal-params/1",
  "units": {"length": "mm", "angle": "rad"},
  "arms": {
    "left": {
      "dh": [
        {"a": -29.836461684878497, "d": 166.0, "theta": 0.0, "alpha": -1.5773617389051138},
        {
          "a": 30.353168781002204,
          "d": -0.1885643797837527,
          "theta": 0.005342210056268388,
          "alpha": 1.5740421206106319
        },
        {
          "a": 40.90343378676616,
          "d": 251.29352175937834,
          "theta": -0.0013215653958718473,
          "alpha": -1.562027453593033
        },
        {
          "a": 40.52172274747211,
          "d": 0.46043251900504606,
          "theta": -1.5743241347543717,
          "alpha": -1.5638045072610567
        },
        {
          "a": -27.06619050438836,
          "d": 264.71689681735114,
          "theta": -0.002111205089216544,
          "alpha": 1.5695017073003648
        },
        {
          "a": 27.066083583885593,
          "d": -0.2070412102410938,
          "theta": 0.00291436867606187,
          "alpha": -1.5683573310701464
        },
        {"a": 0.0, "d": 36.0, "theta": 0.0, "alpha": 0.0}
      ],
      "reflectors": {
        "a": [45.0, 0.0, 40.0],
        "b": [-24.680659860022214, 40.31573897490698, 40.90495764090426],
        "c": [-25.0, -40.0, 40.0]
      }
    },
    "right": {
      "dh": [
        {"a": -29.21518289063107, "d": 166.0, "theta": 0.0, "alpha": -1.5810256377943934},
        {
          "a": 30.958755761472073,
          "d": -0.9072452547986587,
          "theta": -0.0046396652503695,
          "alpha": 1.5685525464437016
        },
        {
          "a": 40.16741024051341,
          "d": 251.11909827407757,
          "theta": -0.0063843277966158865,
          "alpha": -1.5620456852293856
        },
        {
          "a": 40.680025825049626,
          "d": -1.1951739630701321,
          "theta": -1.5807562662496242,
          "alpha": -1.569532294817519
        },
        {
          "a": -26.75255121018903,
          "d": 264.4270328942703,
          "theta": -0.0049175654908241015,
          "alpha": 1.5724962084489473
        },
        {
          "a": 26.774226929259,
          "d": -1.1782883300036888,
          "theta": 0.010248218441395595,
          "alpha": -1.5720114877646552
        },
        {"a": 0.0, "d": 36.0, "theta": 0.0, "alpha": 0.0}
      ],
      "reflectors": {
        "a": [45.0, 0.0, 40.0],
        "b": [-26.658337031498387, 41.81731205471889, 39.09838532586052],
        "c": [-25.0, -40.0, 40.0]
      }
    }
  },
  "right_base_in_left": {
    "translation": [61.38080893870983, -72.85033310801145, -33.05302356924403],
    "rotation": [
      [0.23020012862845957, -0.8775174313692865, 0.42067928214078976],
      [0.8739370001434693, -0.003738013251908423, -0.4860248419959231],
      [0.42806777566137133, 0.47953017100071815, 0.7660344604130727]
    ]
  },
  "method": {
    "arm_method": "distance-single",
    "base_method": "absolute",
    "max_iterations": 200,
    "name": "two-step calibration: step 1 one reflector's distance errors (ref. [26]), step 2 bases in the tracker frame (ref. [28])",
    "objective": "DistanceSingle",
    "progress_tolerance": 1e-08,
    "qp": "Exact",
    "reflector": {"left": "b", "right": "b"},
    "split": "Cal",
    "step_tolerance": 1e-08
  },
  "fixed_parameters": {
    "left": [
      {
        "name": "d1",
        "reason": "unidentifiable from one reflector's distances (joint 1 d: a translation along the first axis moves every point alike and is absorbed by the tracker/base frame)"
      },
      {
        "name": "t_c.z",
        "reason": "not observed: distance-single fits reflector b's distances only; kept at its nominal value"
      }
    ],
    "right": [
      {
        "name": "d1",
        "reason": "unidentifiable from one reflector's distances (joint 1 d: a translation along the first axis moves every point alike and is absorbed by the tracker/base frame)"
      },
      {
        "name": "t_c.z",
        "reason": "not observed: distance-single fits reflector b's distances only; kept at its nominal value"
      }
    ]
  },
  "tracker_frames": {
    "tracker_from_left_base": {
      "translation": [-316.85959672757394, 1063.3335574053356, 2575.8064684397955],
      "rotation": [
        [0.617657284753239, 0.6486028005293948, -0.44476272970729314],
        [0.5096701010722805, -0.7608248863843, -0.40172363675951267],
        [-0.5989456291385955, 0.02144526529897761, -0.800502488398399]
      ]
    },
    "tracker_from_right_base": {
      "translation": [-311.4974700281656, 1163.3220477451237, 2563.939434108592],
      "rotation": [
        [0.51863417977499, -0.7577066676780578, -0.396105028149526],
        [-0.7195518396345385, -0.6370390286613246, 0.2764532981188465],
        [-0.4618048696664805, 0.14163997217752333, -0.8755994407455248]
      ]
    },
    "identified_by": "step 2 (absolute)"
  },
  "termination": [
    {
      "f_mm2": [1811.968406324079, 1.1717147717146859, 3403.5759311210254],
      "iterations": 4,
      "n_configs": 120,
      "psi_mm2": 3403.5759311210254,
      "psi_start_mm2": 103158.65364442715,
      "stage": {"Arm": "left"},
      "termination": "Converged"
    },
    {
      "f_mm2": [17044.41852337969, 1.1326255592361325, 15058.042652677237],
      "iterations": 4,
      "n_configs": 120,
      "psi_mm2": 17044.41852337969,
      "psi_start_mm2": 172765.48543188508,
      "stage": {"Arm": "right"},
      "termination": "Converged"
    },
    {
      "f_mm2": [493.53290134316194, 23.27645268431656, 433.83259275057776],
      "iterations": 3,
      "n_configs": 240,
      "psi_mm2": 493.53290134316194,
      "psi_start_mm2": 494.42172824094143,
      "stage": "Base",
      "termination": "Converged"
    }
  ],
  "provenance": {
    "tool": "dualcal",
    "version": "0.1.0",
    "dataset": "assets/datasets/example",
    "date_utc": "2026-12-02T17:17:18Z"
  }
}"#;

fn parse(text: &str) -> ParamsFile {
    ParamsFile::parse(Path::new("p.json"), text.as_bytes()).expect("a valid parameter file")
}

#[test]
fn a_file_of_the_earlier_format_reads_by_its_spellings() {
    let file = parse(WRITTEN_BEFORE);
    file.to_model().expect("its model");
    let record = file
        .method_record()
        .expect("a method record")
        .expect("it reads");
    assert_eq!(record.method(), Method::DistanceSingle);
    assert_eq!(record.objective, Method::DistanceSingle);
    assert_eq!(record.base_method(), BaseMethod::Absolute);
    assert_eq!(record.qp, QpMethod::Exact);
    assert_eq!(record.split, Split::Cal);
    assert_eq!(record.max_iterations, 200);
    let reflector = record.reflector.expect("the reflector used");
    assert_eq!(reflector.left, Some(Reflector::B));
    // Written again, the record is the same text, spelling for spelling.
    let again = serde_json::to_value(&record).unwrap();
    assert_eq!(Some(&again), file.method.as_ref());
}

#[test]
fn the_oldest_records_without_step_names_read_by_objective() {
    // Files written before `arm_method` and `base_method` existed: `objective` says step 1, step 2 is
    // the paper's minimax.
    let record: MethodRecord = serde_json::from_str(
        r#"{"name": "two-step calibration", "objective": "LeastSquares", "qp": "Paper",
            "split": "All", "max_iterations": 100, "step_tolerance": 1e-8,
            "progress_tolerance": 1e-8}"#,
    )
    .unwrap();
    assert_eq!(record.method(), Method::LeastSquares);
    assert_eq!(record.base_method(), BaseMethod::Minimax);
    assert_eq!(record.qp, QpMethod::Paper);
    assert_eq!(record.split, Split::All);
    let text = serde_json::to_string(&record).unwrap();
    for spelling in [r#""LeastSquares""#, r#""Paper""#, r#""All""#] {
        assert!(text.contains(spelling), "{text}");
    }
}

#[test]
fn an_unknown_spelling_names_the_field_and_the_known_ones() {
    let cases: [(&str, &str, &[&str]); 4] = [
        (r#""qp": "Exact""#, r#""qp": "exact""#, &["Exact", "Paper"]),
        (
            r#""split": "Cal""#,
            r#""split": "cal""#,
            &["Cal", "Ver", "All"],
        ),
        (
            r#""objective": "DistanceSingle""#,
            r#""objective": "Single""#,
            &["DistanceSingle", "LeastSquares"],
        ),
        (
            r#""arm_method": "distance-single""#,
            r#""arm_method": "one""#,
            &["`distance-single`", "`lsq`"],
        ),
    ];
    for (from, to, known) in cases {
        assert!(WRITTEN_BEFORE.contains(from), "{from}");
        let file = parse(&WRITTEN_BEFORE.replace(from, to));
        let err = file
            .method_record()
            .expect("a record")
            .unwrap_err()
            .to_string();
        assert!(err.contains("field `method`"), "{err}");
        for k in known {
            assert!(err.contains(k), "{err} lacks {k}");
        }
    }
    // A free-form method (not a calibration's record) is no record to read.
    let mut file = parse(WRITTEN_BEFORE);
    file.method = Some(serde_json::json!("minimax"));
    assert!(file.method_record().is_none());
}
