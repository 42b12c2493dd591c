//! `dualcal reproduce paper`: the paper's comparison of methods (Tables 4–8, Figs. 4, 6–8) on simulated
//! geometric-only data, and the engine's comparison it is built on.
//!
//! The quick study runs once (it is the slowest part of this file); the tests that read its outputs
//! share it. The orderings asserted are those the paper reports that must hold on data without
//! unmodelled errors: every method better than the nominal model, every method at the noise floor
//! (within 10% of the true parameters' accuracy) on what its model can see.

use dualcal::comparison::{self, METHODS, Observes, Role};
use dualcal::dataset::Split;
use dualcal::simulate;
use dualcal::solver::CalibrationSettings;
use std::collections::HashMap;
use std::path::{Path, PathBuf};
use std::process::{Command, Output};
use std::sync::atomic::AtomicBool;
use std::sync::{Arc, OnceLock};

fn dualcal(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_dualcal"))
        .args(args)
        .env_remove("DISPLAY")
        .env_remove("WAYLAND_DISPLAY")
        .output()
        .expect("run dualcal")
}

fn ok(args: &[&str]) -> String {
    let out = dualcal(args);
    assert!(
        out.status.success(),
        "dualcal {args:?} failed:\n{}\n{}",
        String::from_utf8_lossy(&out.stdout),
        String::from_utf8_lossy(&out.stderr)
    );
    String::from_utf8_lossy(&out.stdout).into_owned()
}

fn fails(args: &[&str]) -> String {
    let out = dualcal(args);
    assert!(
        !out.status.success(),
        "dualcal {args:?} should have failed:\n{}",
        String::from_utf8_lossy(&out.stdout)
    );
    String::from_utf8_lossy(&out.stderr).into_owned()
}

/// The quick study's output directory, run once for all tests of this file.
fn quick_study() -> &'static Path {
    static DIR: OnceLock<(tempfile::TempDir, PathBuf)> = OnceLock::new();
    let (_, out) = DIR.get_or_init(|| {
        let dir = tempfile::tempdir().unwrap();
        let out = dir.path().join("paper");
        ok(&[
            "reproduce",
            "paper",
            "--quick",
            "--out",
            out.to_str().unwrap(),
        ]);
        (dir, out)
    });
    out
}

/// A CSV file as a header and rows of named fields.
fn read_csv(path: &Path) -> (Vec<String>, Vec<HashMap<String, String>>) {
    let mut r = csv::Reader::from_path(path).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
    let header: Vec<String> = r.headers().unwrap().iter().map(str::to_owned).collect();
    let rows = r
        .records()
        .map(|rec| {
            let rec = rec.unwrap_or_else(|e| panic!("{}: {e}", path.display()));
            header
                .iter()
                .cloned()
                .zip(rec.iter().map(str::to_owned))
                .collect()
        })
        .collect();
    (header, rows)
}

/// `mean` of a table's row `row` in column `column`.
fn table_mean(rows: &[HashMap<String, String>], row: &str, column: &str) -> f64 {
    let r = rows
        .iter()
        .find(|r| r["row"] == row && r["column"] == column)
        .unwrap_or_else(|| panic!("no row {row} column {column}"));
    r["mean"]
        .parse()
        .unwrap_or_else(|e| panic!("{row}/{column}: mean `{}`: {e}", r["mean"]))
}

const TABLE_FILES: [&str; 5] = [
    "table4_relative_frequency.csv",
    "table5_relative_accuracy.csv",
    "table6_base_methods.csv",
    "table7_collaborative_frequency.csv",
    "table8_collaborative_accuracy.csv",
];

#[test]
fn quick_study_writes_every_table_and_figure() {
    let dir = quick_study();
    for t in TABLE_FILES {
        let (header, rows) = read_csv(&dir.join(t));
        assert_eq!(
            header,
            [
                "table",
                "row",
                "section",
                "indicator",
                "unit",
                "column",
                "method",
                "paper_column",
                "mean",
                "sd",
                "min",
                "max",
                "n_seeds",
                "paper_value"
            ],
            "{t}"
        );
        assert!(!rows.is_empty(), "{t}");
        for r in &rows {
            let mean: f64 = r["mean"]
                .parse()
                .unwrap_or_else(|e| panic!("{t}: {r:?}: {e}"));
            assert!(mean.is_finite() && mean >= 0.0, "{t}: {r:?}");
            assert_eq!(r["n_seeds"], "1", "{t}: {r:?}");
            if !r["paper_value"].is_empty() {
                let _: f64 = r["paper_value"].parse().unwrap();
            }
        }
        // Nominal, the true parameters and every method of the table's comparison are columns.
        let columns: Vec<&str> = rows.iter().map(|r| r["column"].as_str()).collect();
        assert!(
            columns.contains(&"nominal") && columns.contains(&"truth"),
            "{t}"
        );
        let base = t.starts_with("table6");
        for m in METHODS.iter() {
            let expected = if base {
                m.role.compares_base()
            } else {
                m.role.compares_arms()
            };
            assert_eq!(columns.contains(&m.key), expected, "{t}: {}", m.key);
        }
    }
    // The paper's numbers stand beside ours, each in its own row and column: a join that mixed up
    // the arms, the figures or the methods puts another of the paper's numbers there.
    let (_, t5) = read_csv(&dir.join("table5_relative_accuracy.csv"));
    for (row, column, paper_value) in [
        ("right.pos_rms", "minimax", "0.296"),
        ("left.pos_rms", "minimax", "0.3239"),
        ("right.pos_max", "minimax", "1.2701"),
        ("right.ori_rms", "minimax", "0.0048"),
        ("right.pos_rms", "distance-single", "0.3964"),
        ("right.pos_rms", "pose", "0.3344"),
        ("right.pos_rms", "position", "0.3347"),
        ("right.pos_rms", "nominal", "5.5609"),
    ] {
        let r = t5
            .iter()
            .find(|r| r["row"] == row && r["column"] == column)
            .unwrap_or_else(|| panic!("table 5 has no row {row} in column {column}"));
        assert_eq!(r["paper_value"], paper_value, "{row} {column}");
    }
    // Where the paper published nothing (least squares is ours), the column is empty.
    assert!(
        t5.iter()
            .filter(|r| r["column"] == "lsq")
            .all(|r| r["paper_value"].is_empty())
    );

    let (header, fig4) = read_csv(&dir.join("fig4_configurations.csv"));
    assert_eq!(header[0], "n_configs");
    let sizes: std::collections::BTreeSet<usize> = fig4
        .iter()
        .map(|r| r["n_configs"].parse().unwrap())
        .collect();
    assert!(sizes.len() >= 3, "{sizes:?}");
    for r in &fig4 {
        let v: f64 = r["pos_rms_mm_mean"].parse().unwrap();
        let three = comparison::method(&r["method"]).unwrap().observes == Observes::ThreeReflectors;
        assert!(v > 0.0 && (v < 0.1 || !three), "{r:?}");
    }
    // Fig. 4's verification error falls as configurations are added (geometric-only data): the
    // largest set's is below the smallest set's.
    let ver = |n: &usize| -> f64 {
        fig4.iter()
            .filter(|r| {
                r["n_configs"] == n.to_string() && r["method"] == "minimax" && r["split"] == "ver"
            })
            .map(|r| r["pos_rms_mm_mean"].parse::<f64>().unwrap())
            .fold(0.0, f64::max)
    };
    let (first, last) = (sizes.first().unwrap(), sizes.last().unwrap());
    assert!(
        ver(last) < ver(first),
        "{first}: {} {last}: {}",
        ver(first),
        ver(last)
    );

    for f in ["histograms.csv", "boxplots.csv", "runs.csv"] {
        let (_, rows) = read_csv(&dir.join(f));
        assert!(!rows.is_empty(), "{f}");
    }
    let (_, boxes) = read_csv(&dir.join("boxplots.csv"));
    for b in &boxes {
        let v: Vec<f64> = [
            "min",
            "whisker_lo",
            "q1",
            "median",
            "q3",
            "whisker_hi",
            "max",
        ]
        .iter()
        .map(|k| b[*k].parse().unwrap())
        .collect();
        assert!(v.windows(2).all(|w| w[0] <= w[1]), "{b:?}");
    }
    for svg in [
        "fig4_configurations.svg",
        "fig6_relative_right.svg",
        "fig6_relative_left.svg",
        "fig7_base_methods.svg",
        "fig8_collaborative.svg",
    ] {
        let text = std::fs::read_to_string(dir.join(svg)).unwrap();
        assert!(
            text.starts_with("<svg") && text.trim_end().ends_with("</svg>"),
            "{svg}"
        );
        assert!(text.contains("minimax"), "{svg} names the methods");
    }
    let report = std::fs::read_to_string(dir.join("report.md")).unwrap();
    assert!(report.contains("Table 5 analogue") && report.contains("| | paper |"));
}

#[test]
fn quick_study_holds_the_papers_orderings_on_geometric_data() {
    let dir = quick_study();
    let (_, t5) = read_csv(&dir.join("table5_relative_accuracy.csv"));
    let (_, t8) = read_csv(&dir.join("table8_collaborative_accuracy.csv"));
    let (_, t6) = read_csv(&dir.join("table6_base_methods.csv"));
    // (table, rows of a position and an orientation RMS, methods in it)
    let arm_rows = [
        "right.pos_rms",
        "right.ori_rms",
        "left.pos_rms",
        "left.ori_rms",
    ];
    let collab_rows = ["collab.pos_rms", "collab.ori_rms"];
    type Rows = [HashMap<String, String>];
    let checks: [(&str, &Rows, &[&str], bool); 3] = [
        ("table5", &t5, &arm_rows, false),
        ("table8", &t8, &collab_rows, false),
        ("table6", &t6, &collab_rows, true),
    ];
    for (name, rows, row_ids, base) in checks {
        for m in METHODS.iter().filter(|m| {
            if base {
                m.role.compares_base()
            } else {
                m.role.compares_arms()
            }
        }) {
            for row in row_ids {
                let v = table_mean(rows, row, m.key);
                let nominal = table_mean(rows, row, "nominal");
                let truth = table_mean(rows, row, "truth");
                assert!(
                    v < nominal,
                    "{name} {row}: {} {v} not below nominal {nominal}",
                    m.key
                );
                if m.observes == Observes::ThreeReflectors {
                    assert!(
                        v <= 1.10 * truth,
                        "{name} {row}: {} {v} more than 10% above the true parameters' {truth}",
                        m.key
                    );
                }
            }
        }
    }
    // Minimax is the paper's method in both comparisons.
    assert_eq!(comparison::method("minimax").unwrap().role, Role::Both);

    // A method that sees one reflector (ref. [26]) reaches the noise floor on that reflector's
    // distances and cannot see the flange's orientation: its verification orientation RMS is at least
    // twice minimax's, as in the paper's Tables 5 and 8.
    let (_, runs) = read_csv(&dir.join("runs.csv"));
    let run = |model: &str, pairs: &str| {
        runs.iter()
            .find(|r| r["model"] == model && r["split"] == "ver" && r["pairs"] == pairs)
            .unwrap_or_else(|| panic!("runs.csv: no {model} {pairs}"))
    };
    for m in METHODS
        .iter()
        .filter(|m| m.observes == Observes::OneReflector)
    {
        for pairs in ["relative_left", "relative_right"] {
            let own = &run(m.key, pairs)["reflector_used"];
            let column = match own.as_str() {
                "a" => "pos_rms_a_mm",
                "b" => "pos_rms_b_mm",
                "c" => "pos_rms_c_mm",
                other => panic!("{} {pairs}: reflector_used `{other}`", m.key),
            };
            let v: f64 = run(m.key, pairs)[column].parse().unwrap();
            let truth: f64 = run("truth", pairs)[column].parse().unwrap();
            assert!(
                v <= 1.10 * truth,
                "{} {pairs}: its reflector {own}: {v} mm, true parameters {truth} mm",
                m.key
            );
        }
        for (rows, row) in [
            (&t5, "right.ori_rms"),
            (&t5, "left.ori_rms"),
            (&t8, "collab.ori_rms"),
        ] {
            let v = table_mean(rows, row, m.key);
            let minimax = table_mean(rows, row, "minimax");
            assert!(
                v >= 2.0 * minimax,
                "{row}: {} {v} rad, not twice minimax's {minimax}",
                m.key
            );
        }
    }
}

#[test]
fn refuses_to_overwrite_and_explains_its_options() {
    let dir = quick_study();
    let err = fails(&[
        "reproduce",
        "paper",
        "--quick",
        "--out",
        dir.to_str().unwrap(),
    ]);
    assert!(
        err.contains("already exists") && err.contains("--force"),
        "{err}"
    );
    let err = fails(&["reproduce", "paper", "--quick"]);
    assert!(err.contains("--out"), "{err}");
    let tmp = tempfile::tempdir().unwrap();
    let out = tmp.path().join("x");
    let err = fails(&[
        "reproduce",
        "paper",
        "--methods",
        "minimax,nosuch",
        "--out",
        out.to_str().unwrap(),
    ]);
    assert!(err.contains("nosuch") && err.contains("lsq"), "{err}");
    let err = fails(&["reproduce", "qp", "--out", out.to_str().unwrap()]);
    assert!(err.contains("reproduce paper"), "{err}");
    let err = fails(&[
        "reproduce",
        "paper",
        "--sizes",
        "500",
        "--out",
        out.to_str().unwrap(),
    ]);
    assert!(err.contains("500"), "{err}");
    assert!(!out.exists(), "nothing written by refused runs");
}

#[test]
fn runs_on_a_dataset_of_the_users_and_replaces_with_force() {
    let tmp = tempfile::tempdir().unwrap();
    let data = tmp.path().join("sim");
    ok(&[
        "simulate",
        "--out",
        data.to_str().unwrap(),
        "--seed",
        "5",
        "--configs",
        "40",
        "--cal",
        "25",
    ]);
    let out = tmp.path().join("cmp");
    let args = [
        "reproduce",
        "paper",
        "--dataset",
        data.to_str().unwrap(),
        "--methods",
        "minimax",
        "--sizes",
        "20",
        "--out",
        out.to_str().unwrap(),
    ];
    ok(&args);
    let (_, t5) = read_csv(&out.join("table5_relative_accuracy.csv"));
    let columns: Vec<&str> = t5.iter().map(|r| r["column"].as_str()).collect();
    assert!(columns.contains(&"minimax") && !columns.contains(&"truth"));
    assert!(
        table_mean(&t5, "left.pos_rms", "minimax") < table_mean(&t5, "left.pos_rms", "nominal")
    );
    // An earlier run's outputs are kept unless --force.
    std::fs::write(out.join("report.md"), "stale").unwrap();
    let err = fails(&args);
    assert!(err.contains("report.md"), "{err}");
    assert_eq!(
        std::fs::read_to_string(out.join("report.md")).unwrap(),
        "stale"
    );
    let mut forced = args.to_vec();
    forced.push("--force");
    ok(&forced);
    let report = std::fs::read_to_string(out.join("report.md")).unwrap();
    assert!(report.contains("Table 5 analogue"), "{report}");
}

/// The engine's comparison: every method of the table runs on the same data; a method that cannot
/// run is recorded with its reason while the others go on; a cancelled comparison stops.
#[test]
fn engine_comparison_records_failures_and_cancels() {
    let sim = simulate::simulate_with_robot(
        &simulate::paper_options(11, 50, 30),
        &dualcal::robot::RobotDescription::builtin_irb14000(),
    )
    .unwrap();
    let never = Arc::new(AtomicBool::new(false));
    let mut events = Vec::new();
    let c = comparison::compare(
        &comparison::CompareInput {
            dataset: &sim.dataset,
            nominal: &sim.nominal,
            truth: Some(&sim.truth),
            body_from_left_base: nalgebra::Isometry3::identity(),
        },
        &METHODS,
        &CalibrationSettings::default(),
        &never,
        &mut |e| events.push(e),
    )
    .unwrap();
    assert_eq!(c.methods.len(), METHODS.len());
    assert_eq!(events.len(), 2 * METHODS.len());
    assert!(!c.cancelled);
    let nominal = c
        .nominal
        .report(Split::Ver)
        .unwrap()
        .relative_left
        .unwrap()
        .pos_rms_mm;
    for m in &c.methods {
        let run = m
            .run()
            .unwrap_or_else(|| panic!("{}: {:?}", m.entry.key, m.outcome));
        let ver = run.figures.report(Split::Ver).unwrap();
        let bound = match m.entry.observes {
            Observes::ThreeReflectors => 0.1 * nominal,
            Observes::OneReflector => nominal,
        };
        assert!(
            ver.relative_left.unwrap().pos_rms_mm < bound,
            "{}",
            m.entry.key
        );
    }

    // Three calibration configurations per arm: the methods cannot run, the nominal figures can.
    let tiny = sim.dataset.with_cal_subset(3);
    let c = comparison::compare(
        &comparison::CompareInput {
            dataset: &tiny,
            nominal: &sim.nominal,
            truth: None,
            body_from_left_base: nalgebra::Isometry3::identity(),
        },
        &METHODS,
        &CalibrationSettings::default(),
        &never,
        &mut |_| {},
    )
    .unwrap();
    assert!(c.nominal.report(Split::Ver).is_some());
    for m in &c.methods {
        let e = m.outcome.as_ref().expect_err("too few configurations");
        assert!(
            matches!(e, comparison::MethodError::Calibration(_))
                && e.to_string().contains("configurations"),
            "{}: {e}",
            m.entry.key
        );
    }

    let cancelled = Arc::new(AtomicBool::new(true));
    let c = comparison::compare(
        &comparison::CompareInput {
            dataset: &sim.dataset,
            nominal: &sim.nominal,
            truth: None,
            body_from_left_base: nalgebra::Isometry3::identity(),
        },
        &METHODS,
        &CalibrationSettings::default(),
        &cancelled,
        &mut |_| {},
    )
    .unwrap();
    assert!(c.cancelled && c.methods.is_empty());
}

/// A comparison with configurations left out computes every model's figures without them — the
/// configurations each method was calibrated on — so a method's figures are those its calibration
/// shows.
#[test]
fn comparison_figures_leave_out_the_excluded_configurations() {
    let sim = simulate::simulate_with_robot(
        &simulate::paper_options(12, 50, 30),
        &dualcal::robot::RobotDescription::builtin_irb14000(),
    )
    .unwrap();
    let exclude: Vec<dualcal::side::ConfigId> = (0..3)
        .map(|i| dualcal::side::ConfigId::new(dualcal::side::Side::Left, i))
        .collect();
    let common = CalibrationSettings {
        exclude: exclude.clone(),
        ..CalibrationSettings::default()
    };
    let minimax = [*comparison::method("minimax").unwrap()];
    let c = comparison::compare(
        &comparison::CompareInput {
            dataset: &sim.dataset,
            nominal: &sim.nominal,
            truth: Some(&sim.truth),
            body_from_left_base: nalgebra::Isometry3::identity(),
        },
        &minimax,
        &common,
        &Arc::new(AtomicBool::new(false)),
        &mut |_| {},
    )
    .unwrap();
    let run = c.methods[0].run().expect("minimax runs");
    assert_eq!(run.result.settings.exclude, exclude);
    let kept = sim.dataset.excluding(&exclude);
    for figures in [&c.nominal, c.truth.as_ref().unwrap(), &run.figures] {
        assert_eq!(figures.excluded, exclude);
        for split in [Split::Cal, Split::Ver] {
            let want = dualcal::metrics::evaluate(&kept, &figures.model, split).unwrap();
            let got = figures.report(split).unwrap();
            assert_eq!(
                got.relative_left.unwrap().n_configs,
                want.relative_left.unwrap().n_configs
            );
            assert_eq!(
                got.collaborative.unwrap().n_pairs,
                want.collaborative.unwrap().n_pairs
            );
            let (a, b) = (
                got.relative_left.unwrap().pos_rms_mm,
                want.relative_left.unwrap().pos_rms_mm,
            );
            assert!((a - b).abs() <= 1e-12 * b, "{split:?}: {a} vs {b}");
        }
    }
    // The excluded rows are still listed, marked.
    let rows = &run.figures.configs;
    assert!(rows.iter().filter(|r| r.excluded).count() == exclude.len());
}
