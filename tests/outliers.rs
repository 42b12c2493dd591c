//! The screening API the command line and the workbench use: gross errors injected by the simulator
//! are flagged with the right kind and reflector, `auto_exclude` leaves them out and the fit is as good
//! as without them, clean data raise no flag, and whole-file problems are findings.

use dualcal::dataset::Split;
use dualcal::exclusion;
use dualcal::kinematics::DualArmModel;
use dualcal::metrics;
use dualcal::quality::{self, FlagKind, QualityRecord, ScreenSettings, Severity};
use dualcal::robot::RobotDescription;
use dualcal::side::{ConfigId, Side};
use dualcal::simulate::{self, GrossError, GrossErrorModel, SimOptions, SimOutput};
use dualcal::solver::{CalibrationSettings, Calibrator};
use nalgebra::Vector3;
use std::collections::BTreeSet;

fn sim(seed: u64, gross: Option<GrossErrorModel>) -> SimOutput {
    let robot = RobotDescription::builtin_irb14000();
    let nominal = robot.nominal_model(SimOptions::default_reflectors());
    let opts = SimOptions {
        gross_errors: gross,
        ..simulate::paper_options(seed, 100, 60)
    };
    simulate::simulate(&opts, &nominal, &|_, _| false).expect("simulation")
}

fn heavy() -> GrossErrorModel {
    GrossErrorModel {
        misread_fraction: 0.05,
        misread_mm: (0.5, 5.0),
        swapped_labels_fraction: 0.02,
        other_arm_fraction: 0.02,
    }
}

#[test]
fn clean_data_raise_no_flag() {
    for seed in [1, 2] {
        let s = sim(seed, None);
        let before = quality::screen(&s.dataset, &s.nominal, &ScreenSettings::default());
        assert!(before.flags.is_empty(), "{:#?}", before.flags);
        assert!(before.findings.is_empty(), "{:#?}", before.findings);
        let result = Calibrator::new(&s.dataset, &s.nominal).run().unwrap();
        let after = exclusion::screen_result(&s.dataset, &result, &ScreenSettings::default());
        assert!(after.flags.is_empty(), "{:#?}", after.flags);
        assert!(after.findings.is_empty(), "{:#?}", after.findings);
    }
}

#[test]
fn gross_errors_are_flagged_and_auto_excluded() {
    let s = sim(3, Some(heavy()));
    let clean = sim(3, None);
    let injected: BTreeSet<ConfigId> = s.gross_errors.iter().map(|r| r.config).collect();
    assert_eq!(injected.len(), 2 * 9);
    let auto = exclusion::auto_exclude(
        &s.dataset,
        &s.nominal,
        None,
        &CalibrationSettings::default(),
        &ScreenSettings::default(),
    )
    .unwrap();
    let excluded: BTreeSet<ConfigId> = auto.excluded.iter().map(|f| f.config).collect();
    assert_eq!(excluded, injected, "{:#?}", auto.excluded);
    assert!(auto.stopped.is_none());
    // Each flag says what it was. Every misread of this dataset moves its reflector by 0.5–3.7 mm,
    // which changes the two triangle sides that meet at it by far more than the triangle check's
    // threshold (~0.08 mm): the model-free check catches each and names the reflector. A row of the
    // other arm is told as one (by its triangle or its distances), swapped labels as such.
    for r in &s.gross_errors {
        let f = auto.excluded.iter().find(|f| f.config == r.config).unwrap();
        match &r.error {
            GrossError::Misread {
                reflector,
                displacement_mm,
            } => {
                assert_eq!(f.kind, FlagKind::Triangle, "{f:?} for {r:?}");
                assert_eq!(f.reflector, Some(*reflector), "{f:?} for {r:?}");
                assert!(f.size_mm <= displacement_mm.norm() * 1.05 + 0.05, "{f:?}");
            }
            GrossError::SwappedLabels { .. } => {
                assert_eq!(f.kind, FlagKind::LabelsSwapped, "{f:?}")
            }
            GrossError::OtherArm { .. } => {
                assert_eq!(f.kind, FlagKind::OtherArm, "{f:?} for {r:?}")
            }
        }
    }
    // The fit without them is as good as the fit of the data without gross errors.
    let reference = Calibrator::new(&clean.dataset, &clean.nominal)
        .run()
        .unwrap();
    let ver = |m: &DualArmModel| {
        metrics::evaluate(&clean.dataset, m, Split::Ver)
            .unwrap()
            .collaborative
            .unwrap()
            .pos_rms_mm
    };
    let (with, without) = (ver(&auto.result.calibrated), ver(&reference.calibrated));
    // Within 5% of the fit of the outlier-free data, as the README and docs/reliability.md say.
    assert!(with <= 1.05 * without, "{with} vs {without}");
    // Without exclusion the minimax fit is far worse.
    let raw = Calibrator::new(&s.dataset, &s.nominal).run().unwrap();
    assert!(ver(&raw.calibrated) > 5.0 * without);
    // The parameter file's record names them.
    let record = QualityRecord::new(&s.dataset, &auto.screening, &auto.result.settings.exclude);
    assert_eq!(record.excluded.len(), injected.len());
    assert!(
        record
            .excluded
            .iter()
            .all(|e| e.reason != "excluded by the user")
    );
}

#[test]
fn explanations_of_single_mistakes() {
    let s = sim(4, None);
    let settings = ScreenSettings::default();
    let check = |ds: &dualcal::dataset::Dataset, config: ConfigId, kind: FlagKind, words: &str| {
        let screening = quality::screen(ds, &s.nominal, &settings);
        let by = screening.by_config();
        let flags = by
            .get(&config)
            .unwrap_or_else(|| panic!("{config:?} not flagged"));
        assert!(
            flags
                .iter()
                .any(|f| f.kind == kind && f.reason.contains(words)),
            "{flags:#?}"
        );
        assert_eq!(screening.suspects(), vec![config]);
    };
    // Joint columns q2 and q4 swapped in one row (within either joint's limits).
    let mut ds = s.dataset.clone();
    let i = (0..100)
        .find(|&i| {
            let q = &ds.arms.left.measurements[i].q_rad;
            (q[1] - q[3]).abs() > 0.5 && q[1] > -2.1 && q[1] < 0.75 && q[3] > -2.1 && q[3] < 0.75
        })
        .unwrap();
    ds.arms.left.measurements[i].q_rad.swap(1, 3);
    check(
        &ds,
        ConfigId::new(Side::Left, i),
        FlagKind::JointsSwapped,
        "q2 and q4",
    );
    // Labels a and b swapped.
    let mut ds = s.dataset.clone();
    ds.arms.right.measurements[7].tracker_points_mm.swap(0, 1);
    check(
        &ds,
        ConfigId::new(Side::Right, 7),
        FlagKind::LabelsSwapped,
        "a↔b",
    );
    // Reflector c misread by 1 mm along the triangle's normal (invisible to the side lengths).
    let mut ds = s.dataset.clone();
    let p = ds.arms.left.measurements[20].tracker_points_mm.clone();
    let normal = (p[1] - p[0]).cross(&(p[2] - p[0])).normalize();
    ds.arms.left.measurements[20].tracker_points_mm[2] += normal;
    let result = Calibrator::new(&ds, &s.nominal).run().unwrap();
    let after = exclusion::screen_result(&ds, &result, &settings);
    let f = after.worst_per_config();
    assert_eq!(f.len(), 1, "{f:#?}");
    assert_eq!(
        (f[0].config, f[0].kind, f[0].reflector),
        (ConfigId::new(Side::Left, 20), FlagKind::Residual, Some(2))
    );
    assert!((f[0].size_mm - 1.0).abs() < 0.2, "{:?}", f[0]);
}

#[test]
fn whole_file_findings() {
    let s = sim(5, None);
    let settings = ScreenSettings::default();
    // The right arm measured from a tracker 200 mm away from where the left arm was.
    let mut ds = s.dataset.clone();
    for m in &mut ds.arms.right.measurements {
        for p in &mut m.tracker_points_mm {
            *p += Vector3::new(0.0, 200.0, 0.0);
        }
    }
    let before = quality::screen(&ds, &s.nominal, &settings);
    assert!(
        before
            .findings
            .iter()
            .any(|f| f.severity == Severity::Warning && f.message.contains("one tracker position")),
        "{:#?}",
        before.findings
    );
    let result = Calibrator::new(&ds, &s.nominal).run().unwrap();
    let after = exclusion::screen_result(&ds, &result, &settings);
    assert!(
        after
            .findings
            .iter()
            .any(|f| f.message.contains("right-arm base is 2")),
        "{:#?}",
        after.findings
    );
    // The tracker moved after the 40th left configuration.
    let mut ds = s.dataset.clone();
    for m in ds.arms.left.measurements.iter_mut().skip(40) {
        for p in &mut m.tracker_points_mm {
            *p += Vector3::new(0.5, 0.0, -0.3);
        }
    }
    let result = Calibrator::new(&ds, &s.nominal).run().unwrap();
    let after = exclusion::screen_result(&ds, &result, &settings);
    assert!(
        after
            .findings
            .iter()
            .any(|f| f.side == Some(Side::Left) && f.message.contains("L040` and `L041")),
        "{:#?}",
        after.findings
    );
    // Joint values in ABB axis order: the nominal model is far off, an error with the cause.
    let mut ds = s.dataset.clone();
    for m in &mut ds.arms.left.measurements {
        let q = m.q_rad.clone();
        m.q_rad = vec![q[0], q[1], q[3], q[4], q[5], q[6], q[2]];
    }
    let before = quality::screen(&ds, &s.nominal, &settings);
    assert!(before.has_errors());
    assert!(
        before.findings[0].message.contains("ABB axis order"),
        "{:#?}",
        before.findings
    );
}
