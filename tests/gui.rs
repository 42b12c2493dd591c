//! The workbench driven headlessly with egui_kittest on wgpu (Mesa lavapipe, no window, no GPU):
//! start on the bundled example, calibrate, cancel, open a broken dataset, snapshot the viewport;
//! the quality flags, excluding a configuration by a click or a key (re-solved at once), Auto-exclude;
//! a robot description of the user's own dropped on the window (its arms, joints,
//! meshes and warnings in the Robot section).
//! The tests drive the workbench as a user does (clicks and keys by label) or through its
//! [`Command`]s, and read its state. (A panicking worker is tested inside the crate, `src/app/tests.rs`:
//! its fault injection is compiled into tests only. The screenshot makers and the frame-time study are
//! `examples/workbench_pictures.rs`.)
//! (Set `XDG_RUNTIME_DIR` to a mode-700 directory to silence a harmless warning; `.ci/run` does.)
#![cfg(feature = "gui")]

use dualcal::app::{AppLaunch, Command, LaunchOptions, WorkbenchApp};
use dualcal::side::{ConfigId, PerSide};
use egui_kittest::Harness;
use egui_kittest::kittest::Queryable;

#[path = "fixtures/robots.rs"]
mod robots;

/// Frame caps: generous, so a slow machine passes; they only stop a hung test.
const MAX_LOAD_FRAMES: usize = 20_000;
const MAX_RUN_FRAMES: usize = 200_000;

fn harness(size: [f32; 2], launch: AppLaunch) -> Harness<'static, WorkbenchApp> {
    Harness::builder()
        .with_size(eframe::egui::Vec2::new(size[0], size[1]))
        .wgpu()
        .build_eframe(move |cc| WorkbenchApp::with_options(cc, launch, test_options()))
}

/// The launch options `dualcal gui` reads from this environment (the tools below take
/// `DUALCAL_MESH_DETAIL`), one sample (no MSAA) unless `DUALCAL_MSAA` forces a count: pixel-stable
/// snapshots.
fn test_options() -> LaunchOptions {
    let env = env_options();
    LaunchOptions {
        msaa_samples: env.msaa_samples.or(Some(1)),
        ..env
    }
}

/// The launch options `dualcal gui` reads from this environment.
fn env_options() -> LaunchOptions {
    LaunchOptions::from_vars(|name| std::env::var_os(name))
}

/// Step frames until `done` holds (or the cap is hit, which fails the test).
fn step_until(
    harness: &mut Harness<'_, WorkbenchApp>,
    max_frames: usize,
    what: &str,
    done: impl Fn(&WorkbenchApp) -> bool,
) {
    for _ in 0..max_frames {
        if done(harness.state()) {
            // One more frame so the UI shows the new state.
            harness.step();
            return;
        }
        harness.step();
        std::thread::sleep(std::time::Duration::from_millis(2));
    }
    panic!("{what}: not reached within {max_frames} frames");
}

fn loaded(harness: &mut Harness<'_, WorkbenchApp>) {
    step_until(harness, MAX_LOAD_FRAMES, "loading the example", |app| {
        !app.is_loading()
    });
    assert!(
        harness.state().session().is_some(),
        "example not loaded: {:?}",
        harness.state().errors()
    );
}

/// Change the calibration settings as the settings panel would.
fn edit_settings(
    harness: &mut Harness<'_, WorkbenchApp>,
    edit: impl FnOnce(&mut dualcal::solver::CalibrationSettings),
) {
    let mut settings = harness.state().settings().clone();
    edit(&mut settings);
    harness
        .state_mut()
        .apply(Command::SetSettings(Box::new(settings)));
}

/// Change the 3D view's display options as its View section would.
fn edit_view_options(
    harness: &mut Harness<'_, WorkbenchApp>,
    edit: impl FnOnce(&mut dualcal::app::viewport::scene::SceneOptions),
) {
    let mut options = harness.state().viewport().options.clone();
    edit(&mut options);
    harness
        .state_mut()
        .apply(Command::SetViewOptions(Box::new(options)));
}

/// Pick exactly these methods in the comparison view.
fn pick_methods(harness: &mut Harness<'_, WorkbenchApp>, keys: &[&str]) {
    let keys = keys.iter().map(|k| k.to_string()).collect();
    harness
        .state_mut()
        .apply(Command::PickComparedMethods(keys));
}

#[test]
fn calibrate_shows_calibrated_figures() {
    let mut harness = harness([1400.0, 900.0], AppLaunch::default());
    loaded(&mut harness);
    harness.get_by_label("errors of the nominal model");
    harness.get_by_label("Accuracy").click();
    harness.step();
    harness.get_by_label("Calibrate to see the calibrated figures.");

    harness.get_by_label("Calibrate").click();
    harness.step();
    assert!(harness.state().is_calibrating());
    step_until(&mut harness, MAX_RUN_FRAMES, "calibration result", |app| {
        !app.is_calibrating()
    });
    let app = harness.state();
    let (ver, worst_before, worst_after) = {
        assert!(app.errors().is_empty(), "{:?}", app.errors());
        let session = app.session().unwrap();
        let calibrated = session.calibrated.as_ref().expect("a calibrated result");
        assert!(!app.history().is_empty(), "no convergence history");
        // One owner: once the run ended, the history shown is the calibration result's own.
        assert!(
            std::ptr::eq(app.history(), calibrated.result.history.as_slice()),
            "the history shown is not the calibration's"
        );

        // The table now lists the calibrated model's errors, and the accuracy panel shows both columns.
        harness.get_by_label("errors of the calibrated model");
        assert!(
            harness
                .query_by_label("Calibrate to see the calibrated figures.")
                .is_none()
        );
        // The calibrated relative figures on the verification split are shown with 3 decimals; they
        // must be among the labels.
        let ver = calibrated
            .analysis
            .ver
            .report
            .as_ref()
            .expect("verification report");
        let rms = format!("{:.3}", ver.relative_left.unwrap().pos_rms_mm);
        assert!(
            harness.query_all_by_label(&rms).count() >= 1,
            "{rms} mm not shown"
        );
        let worst = |a: &dualcal::analysis::Analysis| {
            a.configs
                .iter()
                .map(|r| r.worst_pos_mm)
                .fold(0.0f64, f64::max)
        };
        (*ver, worst(&session.nominal), worst(&calibrated.analysis))
    };
    // The summary table (Tables 4–8 style) lists the collaborative figures of both models.
    harness.get_by_label("Summary").click();
    harness.step();
    harness.get_by_label("collaborative");
    let collab = format!("{:.3}", ver.collaborative.unwrap().pos_rms_mm);
    assert!(
        harness.query_all_by_label(&collab).count() >= 1,
        "{collab} mm not shown"
    );
    // Calibration must have lowered the worst configuration error it shows in the table.
    assert!(
        worst_after < worst_before,
        "{worst_after} >= {worst_before} mm"
    );
    // The robot section gives the identified parameters' 1σ (issue 22).
    let u = harness
        .state()
        .session()
        .unwrap()
        .calibrated
        .as_ref()
        .unwrap()
        .uncertainty
        .left
        .clone();
    let u = u.expect("the left arm's uncertainty");
    harness.get_by_label("left joints and parameters").click();
    harness.run_steps(2);
    let header = format!(
        "1σ of the identified parameters (point noise {:.4} mm, condition {:.1})",
        u.point_sigma_mm, u.condition
    );
    harness.get_by_label(&header).click();
    harness.run_steps(2);
    for p in &u.parameters {
        let text = format!("{:.4} {}", p.sigma, p.unit);
        assert!(harness.query_all_by_label(&text).count() >= 1, "{text}");
    }
    // The parameters distances never see are listed once (not again under the calibration's).
    let why = "joint 1 d: a translation along the first axis";
    let listed = harness
        .query_all(egui_kittest::kittest::by().label_contains(why))
        .count();
    assert_eq!(listed, 1, "{why} listed {listed} times");
}

#[test]
fn cancel_stops_the_run_and_keeps_the_previous_state() {
    let mut harness = harness([1400.0, 900.0], AppLaunch::default());
    loaded(&mut harness);
    // The paper's subgradient QP with a huge iteration budget: a run far longer than the test.
    edit_settings(&mut harness, |settings| {
        settings.qp = dualcal::solver::QpMethod::Paper;
        settings.max_qp_iterations = 100_000_000;
    });
    // Let the settings panel lay out the new row before clicking by position.
    harness.run_steps(2);
    harness.get_by_label("Calibrate").click();
    harness.step();
    assert!(
        harness.state().is_calibrating(),
        "{:?}",
        harness.state().errors()
    );
    harness.get_by_label("Cancel").click();
    step_until(&mut harness, MAX_RUN_FRAMES, "cancellation", |app| {
        !app.is_calibrating()
    });
    let app = harness.state();
    assert!(
        app.session().unwrap().calibrated.is_none(),
        "a cancelled run must not replace the current result"
    );
    // Its iterations went with its job: the history shown is the last finished calibration's (none).
    assert!(
        app.history().is_empty(),
        "{} iterations",
        app.history().len()
    );
    assert!(app.errors().is_empty(), "{:?}", app.errors());
    // The status says what is shown: the last finished calibration, here none (the nominal model).
    harness.get_by_label_contains("cancelled");
    harness.get_by_label_contains("the nominal model is shown again");
    harness.get_by_label("errors of the nominal model");
}

#[test]
fn a_broken_dataset_shows_its_error_and_keeps_the_last_good_one() {
    let mut harness = harness([1400.0, 900.0], AppLaunch::default());
    loaded(&mut harness);
    let before = harness.state().session().unwrap().dataset.dir.clone();

    let dir = tempfile::tempdir().unwrap();
    std::fs::write(
        dir.path().join("dataset.toml"),
        "format = \"dualcal-dataset/1\"\n[units]\nlength = \"furlong\"\nangle = \"deg\"\n",
    )
    .unwrap();
    harness
        .state_mut()
        .apply(Command::OpenDataset(dir.path().to_path_buf()));
    step_until(
        &mut harness,
        MAX_LOAD_FRAMES,
        "loading the broken dataset",
        |app| !app.is_loading(),
    );
    let app = harness.state();
    assert_eq!(app.errors().len(), 1, "{:?}", app.errors());
    assert!(
        app.errors()[0].contains("dataset.toml"),
        "{:?}",
        app.errors()
    );
    assert_eq!(app.session().unwrap().dataset.dir, before);
    harness.get_by_label_contains("cannot open dataset");
    harness.get_by_label_contains("previous dataset stays");

    // Idle, the UI settles (no endless repaints) and every widget has an accessible name.
    harness.run();

    // The error can be dismissed.
    harness.get_by_label("×").click();
    harness.step();
    assert!(harness.state().errors().is_empty());
}

#[test]
fn viewport_snapshot() {
    let mut harness = harness([400.0, 280.0], AppLaunch::default());
    loaded(&mut harness);
    {
        let app = harness.state_mut();
        app.set_panels_visible(false);
        app.apply(Command::SetCamera(Box::default()));
        app.apply(Command::SetAutoScale(false));
    }
    edit_view_options(&mut harness, |options| {
        // One arm's calibration configurations keep the picture readable.
        options.show_arm = PerSide::new(true, false);
        options.show_ver = false;
        options.exaggeration = 5.0;
        options.color_max_mm = 10.0;
    });
    harness.run_steps(3);
    harness.snapshot("viewport");
}

#[test]
fn selecting_in_the_table_and_in_the_viewport() {
    let mut harness = harness([1400.0, 900.0], AppLaunch::default());
    loaded(&mut harness);

    // "Select worst" picks the row with the largest |Δd| and poses that arm in it (the button above
    // the table: the view options' one is below the fold of the settings panel at this size).
    harness
        .get_all_by_label("Select worst")
        .last()
        .unwrap()
        .click();
    harness.step();
    let ConfigId { side, index } = harness.state().selection().expect("worst selected");
    let session = harness.state().session().unwrap();
    let worst = session
        .nominal
        .configs
        .iter()
        .map(|r| r.worst_pos_mm)
        .fold(0.0f64, f64::max);
    let row = session
        .nominal
        .configs
        .iter()
        .find(|r| r.config.side == side && r.config.index == index)
        .unwrap();
    assert_eq!(row.worst_pos_mm, worst);
    assert_eq!(harness.state().viewport_pose(side), Some(index));

    // Clicking another row's id selects it.
    // The table is sorted by |Δd| descending: the second row is on screen.
    let flags = session.screening.by_config();
    let order = dualcal::app::table::sorted_rows(
        &session.nominal,
        &flags,
        dualcal::app::table::TableState::default(),
    );
    let other = &session.nominal.configs[order[1]];
    assert_ne!((other.config.side, other.config.index), (side, index));
    let (other_id, other_sel) = (other.id.clone(), other.config);
    harness.get_by_label(&other_id).click();
    harness.step();
    assert_eq!(harness.state().selection(), Some(other_sel));

    // Clicking a configuration in the viewport selects it (viewport alone fills the window).
    harness.state_mut().set_panels_visible(false);
    harness.step();
    // The target: the configuration whose anchor lies farthest, on screen, from every other one's (at
    // least 20 points), so that the nearest configuration to a click on it is it alone.
    let (target, at) = {
        let app = harness.state();
        let camera = app.viewport().camera;
        let rows = &app.session().unwrap().nominal.configs;
        let screen: Vec<_> = rows
            .iter()
            .map(|r| {
                let anchor = dualcal::app::viewport::scene::pick_anchor(r);
                camera
                    .project(&anchor, 1400.0, 900.0)
                    .filter(|[x, y]| (20.0..1380.0).contains(x) && (20.0..880.0).contains(y))
                    .map(|[x, y]| eframe::egui::pos2(x, y))
            })
            .collect();
        let isolation = |i: usize| {
            let p = screen[i]?;
            let nearest = screen
                .iter()
                .enumerate()
                .filter(|&(j, q)| j != i && q.is_some())
                .map(|(_, q)| (q.unwrap() - p).length())
                .fold(f32::INFINITY, f32::min);
            Some(nearest)
        };
        let (best, gap) = (0..rows.len())
            .filter(|&i| rows[i].config != other_sel)
            .filter_map(|i| isolation(i).map(|g| (i, g)))
            .max_by(|a, b| a.1.total_cmp(&b.1))
            .expect("configurations on screen");
        assert!(
            gap >= 20.0,
            "no isolated configuration on screen (best gap {gap} points)"
        );
        (rows[best].config, screen[best].unwrap())
    };
    click_at(&mut harness, at);
    assert_eq!(
        harness.state().selection(),
        Some(target),
        "a click on an isolated configuration's anchor picks it"
    );
}

fn click_at(harness: &mut Harness<'_, WorkbenchApp>, pos: eframe::egui::Pos2) {
    use eframe::egui::{Event, Modifiers, PointerButton};
    harness.event(Event::PointerMoved(pos));
    harness.event(Event::PointerButton {
        pos,
        button: PointerButton::Primary,
        pressed: true,
        modifiers: Modifiers::NONE,
    });
    harness.step();
    harness.event(Event::PointerButton {
        pos,
        button: PointerButton::Primary,
        pressed: false,
        modifiers: Modifiers::NONE,
    });
    harness.step();
    harness.step();
}

/// A file dropped on the window, as the windowing layer would hand it over.
#[derive(Debug)]
struct Dropped(std::path::PathBuf);

impl eframe::egui::DroppedFile for Dropped {
    fn path(&self) -> &std::path::Path {
        &self.0
    }

    fn bytes(&self) -> Result<Vec<u8>, String> {
        std::fs::read(&self.0).map_err(|e| e.to_string())
    }
}

#[test]
fn dropping_a_dataset_opens_it() {
    let mut harness = harness([1400.0, 900.0], AppLaunch::default());
    loaded(&mut harness);
    // A copy of the example with only its first 10 configurations per arm.
    let example = dualcal::app::bundled_example_path();
    let dir = tempfile::tempdir().unwrap();
    std::fs::copy(
        example.join("dataset.toml"),
        dir.path().join("dataset.toml"),
    )
    .unwrap();
    for arm in ["left.csv", "right.csv"] {
        let text = std::fs::read_to_string(example.join(arm)).unwrap();
        let mut rows = 0;
        let kept: Vec<&str> = text
            .lines()
            .filter(|line| {
                let data = !line.starts_with('#') && !line.starts_with("id,");
                if data {
                    rows += 1;
                }
                !data || rows <= 10
            })
            .collect();
        std::fs::write(dir.path().join(arm), kept.join("\n") + "\n").unwrap();
    }
    harness
        .input_mut()
        .dropped_files
        .push(std::sync::Arc::new(Dropped(
            dir.path().join("dataset.toml"),
        )));
    harness.step();
    step_until(
        &mut harness,
        MAX_LOAD_FRAMES,
        "loading the dropped dataset",
        |app| !app.is_loading(),
    );
    let app = harness.state();
    assert!(app.errors().is_empty(), "{:?}", app.errors());
    let session = app.session().unwrap();
    assert_eq!(session.dataset.arms.left.measurements.len(), 10);
    assert_eq!(session.dataset.arms.right.measurements.len(), 10);
    harness.get_by_label_contains("10 left + 10 right configurations");
}

/// The "Model:" toggle shows what is drawn: before any calibration the nominal model (the calibrated
/// choice is disabled and not selected); once a calibration exists, the calibrated one.
#[test]
fn the_model_toggle_shows_the_drawn_model() {
    use egui_kittest::kittest::NodeT;
    let toggled = |harness: &Harness<'_, WorkbenchApp>, label: &str| {
        format!(
            "{:?}",
            harness.get_by_label(label).accesskit_node().toggled()
        )
    };
    let mut harness = harness([1400.0, 900.0], AppLaunch::default());
    loaded(&mut harness);
    assert_eq!(toggled(&harness, "nominal"), "Some(True)");
    assert_eq!(toggled(&harness, "calibrated"), "Some(False)");

    harness.get_by_label("Calibrate").click();
    harness.step();
    step_until(&mut harness, MAX_RUN_FRAMES, "calibration result", |app| {
        !app.is_calibrating()
    });
    assert_eq!(toggled(&harness, "nominal"), "Some(False)");
    assert_eq!(toggled(&harness, "calibrated"), "Some(True)");

    harness.get_by_label("nominal").click();
    // The click is handled while that frame is drawn; the next one shows it.
    harness.step();
    harness.step();
    assert_eq!(toggled(&harness, "nominal"), "Some(True)");
    assert_eq!(toggled(&harness, "calibrated"), "Some(False)");
}

/// The example is compiled into the binary: unpacked into a cache directory it is the same dataset
/// as the source tree's, and a second unpack reuses the directory.
#[test]
fn the_compiled_in_example_unpacks_to_the_same_dataset() {
    let cache = tempfile::tempdir().expect("temp dir");
    let unpacked = dualcal::app::unpack_example(cache.path()).expect("unpack");
    assert!(unpacked.starts_with(cache.path()));
    let source = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("assets/datasets/example");
    let a = dualcal::dataset::load(&source).expect("source example");
    let b = dualcal::dataset::load(&unpacked).expect("unpacked example");
    for (x, y) in [(&a.arms.left, &b.arms.left), (&a.arms.right, &b.arms.right)] {
        assert_eq!(x.measurements, y.measurements);
    }
    assert_eq!(a.nominal_reflectors_mm, b.nominal_reflectors_mm);
    assert_eq!(a.tracker, b.tracker);
    assert_eq!(
        dualcal::app::unpack_example(cache.path()).expect("again"),
        unpacked
    );
}

/// The Accuracy tab's RMS row: the label "RMS (mm)" and the nominal and the after cells beside it.
fn accuracy_rms_cells(harness: &Harness<'_, WorkbenchApp>) -> [String; 2] {
    use egui_kittest::kittest::NodeT;
    let rms = harness.get_by_label("RMS (mm)");
    let grid = rms.parent().expect("the numbers grid");
    // A label's text is its accessibility value.
    let labels: Vec<String> = grid
        .children()
        .filter_map(|n| n.accesskit_node().value())
        .collect();
    let at = labels
        .iter()
        .position(|l| l == "RMS (mm)")
        .expect("RMS row");
    [labels[at + 1].clone(), labels[at + 2].clone()]
}

/// What the Accuracy tab shows while a calibration runs is the figure of the model the run has
/// reached: on a 2 × 400 simulated dataset, the "after" column of the collaborative Δd changes from
/// frame to frame during the run (every stage changes it), every value it shows is the figure of one
/// of the run's iterates (checked against a run of the same calibration next to the app), and differs
/// from both the nominal and the final figure; the figures are marked live until the run ends.
/// `execution` is where the app runs the calibration.
fn accuracy_follows_a_running_calibration(execution: Option<dualcal::app::task::Execution>) {
    use dualcal::dataset::Split;
    use dualcal::solver::{CalibrationRun, Calibrator, IterationRecord, Observer, StageSummary};

    let robot = dualcal::robot::RobotDescription::builtin_irb14000();
    let sim = dualcal::simulate::simulate_with_robot(
        &dualcal::simulate::paper_options(3, 400, 300),
        &robot,
    )
    .expect("simulation");
    let dir = tempfile::tempdir().unwrap();
    dualcal::dataset::save(&sim.dataset, dir.path(), dualcal::dataset::Units::MM_DEG).unwrap();
    let mut harness = harness(
        [1280.0, 800.0],
        AppLaunch {
            dataset: Some(dir.path().to_path_buf()),
            urdf: None,
        },
    );
    loaded(&mut harness);
    if let Some(execution) = execution {
        harness.state_mut().set_execution(execution);
    }

    // The figure shown (collaborative Δd RMS on the verification split) of every iterate of the same
    // calibration, run here.
    struct Iterates<'a> {
        dataset: &'a dualcal::dataset::Dataset,
        rms_mm: Vec<f64>,
    }
    impl Iterates<'_> {
        fn record(&mut self, run: &CalibrationRun) {
            let report =
                dualcal::metrics::evaluate(self.dataset, &run.current_model(), Split::Ver).unwrap();
            self.rms_mm.push(report.collaborative.unwrap().pos_rms_mm);
        }
    }
    impl Observer for Iterates<'_> {
        fn iteration(&mut self, _: &IterationRecord, run: &CalibrationRun) {
            self.record(run);
        }
        fn stage_finished(&mut self, _: &StageSummary, run: &CalibrationRun) {
            self.record(run);
        }
    }
    let session = harness.state().session().unwrap();
    let mut iterates = Iterates {
        dataset: &session.dataset,
        rms_mm: Vec::new(),
    };
    Calibrator::new(&session.dataset, &session.nominal.model)
        .observer(&mut iterates)
        .run()
        .expect("reference calibration");
    let iterate_rms = iterates.rms_mm;

    harness.get_by_label("Accuracy").click();
    harness.step();
    harness
        .get_by_role_and_label(eframe::egui::accesskit::Role::ComboBox, "Figure:")
        .click();
    harness.run_steps(2);
    harness.get_by_label("collaborative Δd (mm)").click();
    harness.run_steps(2);
    harness.get_by_label("collaborative Δd (mm) — verification split");
    let [nominal, before] = accuracy_rms_cells(&harness);
    assert_eq!(before, "—", "no calibration yet");
    harness.get_by_label("Calibrate").click();
    harness.step();
    assert!(harness.state().is_calibrating());
    let mut shown = Vec::new();
    let mut marked_live = false;
    for _ in 0..MAX_RUN_FRAMES {
        if !harness.state().is_calibrating() {
            break;
        }
        harness.step();
        if harness.state().is_calibrating() {
            shown.push(accuracy_rms_cells(&harness)[1].clone());
            marked_live |= harness.query_by_label_contains("live: ").is_some();
        }
    }
    harness.step();
    assert!(!harness.state().is_calibrating(), "the run did not end");
    let app = harness.state();
    assert!(app.errors().is_empty(), "{:?}", app.errors());
    let calibrated = app.session().unwrap().calibrated.as_ref().expect("result");
    let final_rms = calibrated
        .analysis
        .ver
        .report
        .unwrap()
        .collaborative
        .unwrap()
        .pos_rms_mm;
    let [_, after] = accuracy_rms_cells(&harness);
    assert_eq!(after, format!("{final_rms:.3}"));
    assert!(harness.query_by_label_contains("live: ").is_none());

    let mid: Vec<&String> = shown
        .iter()
        .filter(|v| **v != nominal && **v != after && v.as_str() != "—")
        .collect();
    assert!(
        !mid.is_empty(),
        "during the run the Accuracy tab showed only the previous figures: {shown:?} \
         (nominal {nominal}, final {after})"
    );
    let mut distinct = mid.clone();
    distinct.dedup();
    println!("shown during the run: {distinct:?} (nominal {nominal}, final {after})");
    assert!(
        distinct.len() >= 2,
        "the figures did not change between frames of the run: {shown:?}"
    );
    for v in &mid {
        let v: f64 = v.parse().expect("a number");
        assert!(
            iterate_rms.iter().any(|x| (x - v).abs() <= 0.0006),
            "{v} mm is no iterate's figure ({iterate_rms:?})"
        );
    }
    assert!(marked_live, "the live figures were not marked as such");
}

#[test]
fn the_accuracy_tab_follows_a_running_calibration() {
    accuracy_follows_a_running_calibration(None);
}

/// The same where there are no threads (a browser): the calibration stepped within the frames.
#[test]
fn the_accuracy_tab_follows_a_calibration_stepped_in_frames() {
    accuracy_follows_a_running_calibration(Some(dualcal::app::task::Execution::InFrames));
}

/// A simulated dataset (built-in robot, `n` configurations per arm, `n_cal` for calibration) with a
/// reflector misread by 3–5 mm in 2% of each arm's configurations, saved to `dir`; returns the
/// injected configurations.
fn dataset_with_misreads(dir: &std::path::Path, n: usize, n_cal: usize) -> Vec<(ConfigId, String)> {
    let robot = dualcal::robot::RobotDescription::builtin_irb14000();
    let mut opts = dualcal::simulate::paper_options(11, n, n_cal);
    opts.gross_errors = Some(dualcal::simulate::GrossErrorModel {
        misread_fraction: 0.02,
        misread_mm: (3.0, 5.0),
        swapped_labels_fraction: 0.0,
        other_arm_fraction: 0.0,
    });
    let sim = dualcal::simulate::simulate_with_robot(&opts, &robot).expect("simulation");
    dualcal::dataset::save(&sim.dataset, dir, dualcal::dataset::Units::MM_DEG).unwrap();
    assert!(!sim.gross_errors.is_empty());
    sim.gross_errors
        .iter()
        .map(|g| (g.config, g.id.clone()))
        .collect()
}

fn open_at(dir: &std::path::Path) -> Harness<'static, WorkbenchApp> {
    let mut harness = harness(
        [1400.0, 900.0],
        AppLaunch {
            dataset: Some(dir.to_path_buf()),
            urdf: None,
        },
    );
    loaded(&mut harness);
    harness
}

fn calibrated_ver_collab_rms(app: &WorkbenchApp) -> f64 {
    let calibrated = app
        .session()
        .unwrap()
        .calibrated
        .as_ref()
        .expect("a result");
    calibrated
        .analysis
        .ver
        .report
        .unwrap()
        .collaborative
        .unwrap()
        .pos_rms_mm
}

/// The screening's flags are in the table (reason and size) and colour the 3D view; unticking a
/// flagged row's box leaves it out and re-solves at once (the run starts in that frame, the nominal
/// and calibrated figures then leave it out and change); X on the selection takes it back in.
#[test]
fn excluding_a_flagged_configuration_resolves_at_once_and_changes_the_figures() {
    let dir = tempfile::tempdir().unwrap();
    let injected = dataset_with_misreads(dir.path(), 150, 90);
    let mut harness = open_at(dir.path());
    let (flagged, flagged_id, flagged_reason) = {
        let session = harness.state().session().unwrap();
        let worst = session.screening.worst_per_config();
        // The misreads are caught before fitting (the triangle test).
        for (config, id) in &injected {
            assert!(
                worst.iter().any(|f| f.config == *config),
                "injected misread {id} not flagged: {worst:?}"
            );
        }
        let f = worst
            .iter()
            .max_by(|a, b| a.severity().total_cmp(&b.severity()))
            .unwrap();
        (
            f.config,
            f.id.clone(),
            format!("{} {:.2}", f.kind.label(), f.size_mm),
        )
    };
    // The count, and the flag column sorted most severe first.
    harness.get_by_label_contains("flagged (nominal model), 0 excluded");
    harness.get_by_label("flag (mm)").click();
    harness.run_steps(2);
    assert!(
        harness.query_all_by_label_contains(&flagged_reason).count() >= 1,
        "no {flagged_reason} flag shown"
    );
    // The 3D view draws the flagged configurations in their flag colour, outlined.
    let flag_lines = |app: &WorkbenchApp| {
        let session = app.session().unwrap();
        let n = session.screening.suspects().len();
        let scene = app.viewport().scene();
        (n, scene.lines.len())
    };
    let (n_flagged, lines_with) = flag_lines(harness.state());
    edit_view_options(&mut harness, |options| options.show_flags = false);
    harness.run_steps(2);
    let (_, lines_without) = flag_lines(harness.state());
    assert_eq!(
        lines_with - lines_without,
        6 * n_flagged,
        "an outline per flagged triangle"
    );
    edit_view_options(&mut harness, |options| options.show_flags = true);
    harness.run_steps(2);

    harness.get_by_label("Calibrate").click();
    harness.step();
    step_until(&mut harness, MAX_RUN_FRAMES, "calibration", |app| {
        !app.is_calibrating()
    });
    assert!(
        harness.state().errors().is_empty(),
        "{:?}",
        harness.state().errors()
    );
    let with_outlier = calibrated_ver_collab_rms(harness.state());
    // The figures of the split the flagged configuration is in.
    let split_rms = |analysis: &dualcal::analysis::Analysis, config: ConfigId| {
        let row = analysis
            .configs
            .iter()
            .find(|r| r.config == config)
            .unwrap();
        let figures = analysis.figures(row.split).unwrap();
        figures.report.unwrap().collaborative.unwrap().pos_rms_mm
    };
    let nominal_with = split_rms(&harness.state().session().unwrap().nominal, flagged);

    // Untick the row's "use" box: the configuration is excluded and a calibration starts at once.
    harness.get_by_label(&format!("use {flagged_id}")).click();
    harness.step();
    {
        let app = harness.state();
        assert!(app.is_calibrating(), "no re-solve started");
        assert_eq!(app.session().unwrap().exclude, vec![flagged]);
    }
    step_until(&mut harness, MAX_RUN_FRAMES, "the re-solve", |app| {
        !app.is_calibrating()
    });
    let app = harness.state();
    assert!(app.errors().is_empty(), "{:?}", app.errors());
    let session = app.session().unwrap();
    let calibrated = session.calibrated.as_ref().unwrap();
    assert_eq!(calibrated.result.settings.exclude, vec![flagged]);
    assert_eq!(session.nominal.excluded, vec![flagged]);
    assert!(
        session
            .nominal
            .configs
            .iter()
            .any(|r| r.config == flagged && r.excluded),
        "the row is still listed, marked excluded"
    );
    let without_outlier = calibrated_ver_collab_rms(app);
    assert_ne!(without_outlier, with_outlier, "the figures did not change");
    assert_ne!(
        split_rms(&session.nominal, flagged),
        nominal_with,
        "the nominal figures still include the excluded configuration"
    );
    harness.get_by_label_contains("1 excluded");
    harness.get_by_label_contains("1 configuration(s) left out");

    // Select the row (click its id) and press X: it is used again, and calibrated again at once.
    harness.get_by_label(&flagged_id).click();
    harness.step();
    assert_eq!(harness.state().selection(), Some(flagged));
    harness.key_press(eframe::egui::Key::X);
    harness.step();
    assert!(harness.state().is_calibrating(), "X did not re-solve");
    assert!(harness.state().session().unwrap().exclude.is_empty());
    step_until(&mut harness, MAX_RUN_FRAMES, "the re-solve", |app| {
        !app.is_calibrating()
    });
    let again = calibrated_ver_collab_rms(harness.state());
    assert!(
        (again - with_outlier).abs() < 1e-9,
        "{again} vs {with_outlier}: the same data must give the same result"
    );
}

/// Auto-exclude applies `exclusion::auto_exclude` and lists what it removed.
#[test]
fn auto_exclude_removes_the_misreads_and_lists_them() {
    let dir = tempfile::tempdir().unwrap();
    let injected = dataset_with_misreads(dir.path(), 150, 90);
    let mut harness = open_at(dir.path());
    harness.get_by_label("Auto-exclude").click();
    harness.step();
    assert!(harness.state().is_calibrating());
    step_until(&mut harness, MAX_RUN_FRAMES, "auto-exclude", |app| {
        !app.is_calibrating()
    });
    let app = harness.state();
    assert!(app.errors().is_empty(), "{:?}", app.errors());
    let session = app.session().unwrap();
    let auto = session.auto_exclusion.as_ref().expect("a summary");
    for (config, id) in &injected {
        assert!(session.exclude.contains(config), "{id} not excluded");
        assert!(auto.excluded.iter().any(|f| f.config == *config));
    }
    assert_eq!(
        session.calibrated.as_ref().unwrap().result.settings.exclude,
        session.exclude
    );
    harness.get_by_label_contains(&format!(
        "Auto-exclude removed {} configuration",
        auto.excluded.len()
    ));
    for f in &auto.excluded {
        harness.get_by_label_contains(&format!("{} {}:", f.config.side.name(), f.id));
    }
}

/// A URDF dropped on the window (the path a file dialog's choice takes too: `Command::OpenUrdf`)
/// replaces the robot: the Robot section lists its arms (base → tip, joints), the missing mesh as a
/// warning, and the 3D view draws its meshes; a broken URDF dropped next is an error and the robot
/// stays.
#[test]
fn a_dropped_urdf_replaces_the_robot_and_the_robot_section_lists_its_arms() {
    let mut harness = harness([1400.0, 900.0], AppLaunch::default());
    loaded(&mut harness);
    harness.get_by_label("built-in IRB 14000");
    let dir = tempfile::tempdir().unwrap();
    let urdf = robots::write_yumi_like(dir.path());
    // One visual mesh missing: a warning and a stand-in, not a refused robot.
    let pkg = dir.path().join("yumi_description");
    std::fs::remove_file(pkg.join("meshes/link_3.stl")).unwrap();
    harness
        .input_mut()
        .dropped_files
        .push(std::sync::Arc::new(Dropped(urdf.clone())));
    harness.step();
    step_until(
        &mut harness,
        MAX_LOAD_FRAMES,
        "loading with the URDF",
        |app| !app.is_loading() && !app.is_loading_meshes(),
    );
    let app = harness.state();
    assert!(app.errors().is_empty(), "{:?}", app.errors());
    let session = app.session().unwrap();
    assert_eq!(session.robot_source.as_deref(), Some(urdf.as_path()));
    let dualcal::app::session::RobotMeshes::Loaded(meshes) = &session.meshes else {
        panic!("meshes not loaded");
    };
    assert!(
        meshes.visual_files >= 8,
        "{} mesh files",
        meshes.visual_files
    );
    assert_eq!(meshes.visual_missing, 1);
    let drawn_meshes = app
        .viewport()
        .scene()
        .instances
        .iter()
        .filter(|i| matches!(i.geometry, dualcal::app::viewport::scene::Geometry::Mesh(_)))
        .count();
    assert!(drawn_meshes >= 8, "{drawn_meshes} mesh instances drawn");
    // On this software adapter (lavapipe) "auto" draws the simplified copy; "full" the meshes as
    // loaded, which stay the session's for everything else.
    let simplified = meshes.simplified.clone().expect("a simplified copy");
    let full = meshes.packed.clone();
    assert_eq!(simplified.mesh_count(), full.mesh_count());
    assert!(app.viewport().draws_simplified_meshes());
    let drawn_pack = |h: &Harness<'_, WorkbenchApp>| h.state().viewport().scene().meshes.clone();
    assert!(std::sync::Arc::ptr_eq(
        &drawn_pack(&harness).unwrap(),
        &simplified
    ));
    // The view options are below the fold of the left panel: scrolled to first.
    harness.get_by_label("full").scroll_to_me();
    harness.run_steps(4);
    harness.get_by_label("full").click();
    harness.run_steps(2);
    assert!(std::sync::Arc::ptr_eq(
        &drawn_pack(&harness).unwrap(),
        &full
    ));
    // The view options are below the fold of the left panel: scrolled to first.
    harness.get_by_label("simplified").scroll_to_me();
    harness.run_steps(4);
    harness.get_by_label("simplified").click();
    harness.run_steps(2);
    assert!(std::sync::Arc::ptr_eq(
        &drawn_pack(&harness).unwrap(),
        &simplified
    ));
    harness.get_by_label("yumi.urdf");
    harness.get_by_label("yumi_body → yumi_link_7_l (7 joints)");
    harness.get_by_label("yumi_body → yumi_link_7_r (7 joints)");
    harness.get_by_label_contains("nominal model: the URDF's joint origins");
    harness.get_by_label_contains("1 missing");
    // The warnings name the missing file; the joints list opens with their limits.
    let n_warnings = {
        let session = harness.state().session().unwrap();
        session.robot.warnings.len() + meshes_warnings(session)
    };
    harness
        .get_by_label(&format!(
            "{n_warnings} warning{}",
            if n_warnings == 1 { "" } else { "s" }
        ))
        .click();
    harness.run_steps(2);
    assert!(harness.query_all_by_label_contains("link_3.stl").count() >= 1);
    harness.get_by_label("left joints and parameters").click();
    harness.run_steps(2);
    harness.get_by_label("yumi_joint_7_l");
    harness.get_by_label_contains("parameters,");

    // A broken description: the error names it, the robot stays.
    let broken = dir.path().join("broken.urdf");
    std::fs::write(&broken, "<robot name=\"x\"><link name=\"a\"/>").unwrap();
    harness
        .input_mut()
        .dropped_files
        .push(std::sync::Arc::new(Dropped(broken)));
    harness.step();
    step_until(
        &mut harness,
        MAX_LOAD_FRAMES,
        "loading the broken URDF",
        |app| !app.is_loading(),
    );
    let app = harness.state();
    assert_eq!(app.errors().len(), 1, "{:?}", app.errors());
    assert!(
        app.errors()[0].contains("broken.urdf"),
        "{:?}",
        app.errors()
    );
    assert_eq!(
        app.session().unwrap().robot_source.as_deref(),
        Some(urdf.as_path())
    );
    harness.get_by_label_contains("previous dataset stays, with its robot");
}

fn meshes_warnings(session: &dualcal::app::session::Session) -> usize {
    match &session.meshes {
        dualcal::app::session::RobotMeshes::Loaded(m) => m.warnings.len(),
        _ => 0,
    }
}

/// Some label contains `text` (the status line and the settings panel may both say it).
fn shown(harness: &Harness<'_, WorkbenchApp>, text: &str) {
    assert!(
        harness.query_all_by_label_contains(text).count() >= 1,
        "{text:?} is not shown"
    );
}

/// Pick `choice` in the settings combo labelled `label`.
fn pick_in_combo(harness: &mut Harness<'_, WorkbenchApp>, label: &str, choice: &str) {
    harness
        .get_by_role_and_label(eframe::egui::accesskit::Role::ComboBox, label)
        .click();
    harness.run_steps(2);
    harness.get_by_label(choice).click();
    harness.run_steps(2);
}

fn calibrate(harness: &mut Harness<'_, WorkbenchApp>) {
    harness.get_by_label("Calibrate").click();
    harness.step();
    step_until(harness, MAX_RUN_FRAMES, "calibration result", |app| {
        !app.is_calibrating()
    });
}

/// The verification split's collaborative RMS* of the last calibration.
fn calibrated_ver_collab(app: &WorkbenchApp) -> f64 {
    let c = app
        .session()
        .unwrap()
        .calibrated
        .as_ref()
        .expect("calibrated");
    c.analysis
        .ver
        .report
        .unwrap()
        .collaborative
        .unwrap()
        .pos_rms_mm
}

/// Press "Run comparison" and wait for it to end, without errors.
fn run_comparison(harness: &mut Harness<'_, WorkbenchApp>) {
    harness.get_by_label("Run comparison").click();
    harness.step();
    assert!(harness.state().is_comparing());
    step_until(harness, MAX_RUN_FRAMES, "comparison", |app| {
        !app.is_comparing()
    });
    let app = harness.state();
    assert!(app.errors().is_empty(), "{:?}", app.errors());
}

/// The `method` record of the parameter file the workbench exports.
fn exported_method(app: &WorkbenchApp) -> serde_json::Value {
    let bytes = dualcal::app::export::Export::Params
        .contents(app.session().unwrap())
        .expect("a calibration to export")
        .expect("the parameter file");
    let file: serde_json::Value = serde_json::from_slice(&bytes).unwrap();
    file["method"].clone()
}

#[test]
fn the_method_picker_changes_the_method_used() {
    use dualcal::solver::{Method, Reflector};
    let mut harness = harness([1400.0, 900.0], AppLaunch::default());
    loaded(&mut harness);
    calibrate(&mut harness);
    assert!(
        harness.state().errors().is_empty(),
        "{:?}",
        harness.state().errors()
    );
    let minimax = calibrated_ver_collab(harness.state());
    shown(&harness, "method minimax, base minimax");

    pick_in_combo(&mut harness, "Method", "least squares");
    calibrate(&mut harness);
    let app = harness.state();
    assert!(app.errors().is_empty(), "{:?}", app.errors());
    let result = &app.session().unwrap().calibrated.as_ref().unwrap().result;
    assert_eq!(result.settings.method, Method::LeastSquares);
    let lsq = calibrated_ver_collab(app);
    assert!(
        (lsq - minimax).abs() > 1e-6,
        "least squares and minimax gave the same figures ({lsq} mm)"
    );
    shown(&harness, "method lsq, base minimax");
    assert_eq!(
        exported_method(harness.state())["objective"],
        "LeastSquares"
    );

    // distance-single takes a reflector; any other method drops it (the solver refuses one).
    assert!(harness.query_by_label("Reflector").is_none());
    pick_in_combo(&mut harness, "Method", "distance, one reflector [26]");
    pick_in_combo(&mut harness, "Reflector", "b");
    assert_eq!(harness.state().settings().reflector, Some(Reflector::B));
    calibrate(&mut harness);
    let app = harness.state();
    // The method ran: the result and the status say which reflector it used.
    assert!(app.errors().is_empty(), "{:?}", app.errors());
    let r = &app.session().unwrap().calibrated.as_ref().unwrap().result;
    assert_eq!(r.settings.method, Method::DistanceSingle);
    assert_eq!(r.reflector_used.left, Some(Reflector::B));
    assert_eq!(r.reflector_used.right, Some(Reflector::B));
    shown(
        &harness,
        "method distance-single (reflector left b, right b)",
    );
    pick_in_combo(&mut harness, "Method", "minimax (paper, Algorithm I)");
    assert_eq!(harness.state().settings().reflector, None);
    assert!(harness.query_by_label("Reflector").is_none());
}

/// The comparison view: the picked methods run in the background, one row each after the nominal
/// one, with their own figures; adopting one makes it the calibration the exports write.
#[test]
fn the_comparison_lists_each_method_and_adopting_one_changes_the_export() {
    use dualcal::solver::Method;
    let mut harness = harness([1400.0, 900.0], AppLaunch::default());
    loaded(&mut harness);
    calibrate(&mut harness);
    assert_eq!(exported_method(harness.state())["objective"], "Minimax");

    harness.get_by_label("Compare methods…").click();
    harness.run_steps(2);
    harness.get_by_label("Pick methods and press Run comparison.");
    pick_methods(&mut harness, &["minimax"]);
    harness.run_steps(2);
    // The picker adds least squares.
    harness.get_by_label("least squares").click();
    harness.run_steps(2);
    run_comparison(&mut harness);
    let app = harness.state();
    let comparison = app
        .compare_view()
        .comparison
        .as_ref()
        .expect("a comparison");
    let keys: Vec<&str> = comparison.methods.iter().map(|m| m.entry.key).collect();
    assert_eq!(keys, ["minimax", "lsq"]);
    let ver_collab = |key: &str| {
        comparison
            .method(key)
            .and_then(|m| m.figures())
            .and_then(|f| f.report(dualcal::dataset::Split::Ver))
            .expect("verification figures")
            .collaborative
            .unwrap()
            .pos_rms_mm
    };
    let (minimax, lsq) = (ver_collab("minimax"), ver_collab("lsq"));
    assert!((minimax - lsq).abs() > 1e-6, "same figures {minimax} mm");
    let nominal = comparison
        .nominal
        .report(dualcal::dataset::Split::Ver)
        .unwrap()
        .collaborative
        .unwrap()
        .pos_rms_mm;
    assert!(nominal > 10.0 * minimax.max(lsq), "nominal {nominal} mm");
    // One row per method plus the nominal one, each with its figures shown.
    harness.get_by_role_and_label(eframe::egui::accesskit::Role::Label, "nominal");
    for key in ["minimax", "lsq"] {
        let title = dualcal::comparison::method(key).unwrap().title();
        harness.get_by_role_and_label(eframe::egui::accesskit::Role::Label, &title);
    }
    for v in [nominal, minimax, lsq] {
        let text = format!("{v:.3}");
        assert!(
            harness.query_all_by_label(&text).count() >= 1,
            "{text} not shown"
        );
    }
    assert_eq!(
        harness.query_all_by_label_contains("converged (").count(),
        2
    );
    harness.get_by_label_contains("Comparison done");

    // Move the pointer off Run comparison first: its tooltip covers the table's rows.
    harness.get_by_label("Adopt lsq").hover();
    harness.run_steps(2);
    harness.get_by_label("Adopt lsq").click();
    harness.step();
    assert_eq!(harness.state().compare_view().adopted, Some("lsq"));
    step_until(&mut harness, MAX_RUN_FRAMES, "adopting", |app| {
        !app.is_calibrating()
    });
    let app = harness.state();
    assert!(app.errors().is_empty(), "{:?}", app.errors());
    let adopted = &app.session().unwrap().calibrated.as_ref().unwrap().result;
    assert_eq!(adopted.settings.method, Method::LeastSquares);
    assert!((calibrated_ver_collab(app) - lsq).abs() < 1e-9);
    assert_eq!(exported_method(app)["objective"], "LeastSquares");
    shown(&harness, "Adopted the compared result (method lsq");
}

/// Stepped in frames (a browser build): a method that stops at the iteration limit says so in its
/// row. Cancelling stops the running method (its row says so) and skips the rest.
#[test]
fn a_comparison_stepped_in_frames_shows_terminations_and_cancels() {
    let mut harness = harness([1400.0, 900.0], AppLaunch::default());
    loaded(&mut harness);
    harness
        .state_mut()
        .set_execution(dualcal::app::task::Execution::InFrames);
    edit_settings(&mut harness, |s| s.max_iterations = 1);
    pick_methods(&mut harness, &["minimax"]);
    harness.state_mut().apply(Command::StartComparison);
    step_until(&mut harness, MAX_RUN_FRAMES, "comparison", |app| {
        !app.is_comparing()
    });
    assert!(harness.state().errors().is_empty());
    harness.get_by_label_contains("iteration limit reached");
    harness.get_by_label("Adopt minimax");

    // The paper's subgradient QP with a huge budget: far longer than the test, until cancelled (on a
    // thread: stepped in frames, one outer iteration of it would hold the frame).
    harness
        .state_mut()
        .set_execution(dualcal::app::task::Execution::Thread);
    edit_settings(&mut harness, |s| {
        s.max_iterations = 100;
        s.qp = dualcal::solver::QpMethod::Paper;
        s.max_qp_iterations = 100_000_000;
    });
    pick_methods(&mut harness, &["minimax", "lsq"]);
    harness.state_mut().apply(Command::StartComparison);
    step_until(&mut harness, MAX_RUN_FRAMES, "the first method", |app| {
        app.compare_view().progress.is_some()
    });
    assert!(harness.state().is_comparing());
    harness.get_by_label("Cancel comparison").click();
    step_until(&mut harness, MAX_RUN_FRAMES, "cancellation", |app| {
        !app.is_comparing()
    });
    let app = harness.state();
    let comparison = app.compare_view().comparison.as_ref().unwrap();
    assert!(comparison.cancelled);
    assert_eq!(comparison.methods.len(), 1, "the rest is skipped");
    shown(&harness, "Comparison cancelled");
    shown(&harness, "(left arm): cancelled");
}

/// At 1280 × 800 with a URDF robot (its Robot section lists arms, meshes and joints), the left panel's
/// last row ("Model: nominal / calibrated") can be brought into view above the status bar: the panel
/// scrolls (or fits).
#[test]
fn the_left_panel_reaches_its_last_row_at_1280x800_with_a_urdf_robot() {
    let mut harness = harness([1280.0, 800.0], AppLaunch::default());
    loaded(&mut harness);
    let dir = tempfile::tempdir().unwrap();
    let urdf = robots::write_yumi_like(dir.path());
    harness
        .input_mut()
        .dropped_files
        .push(std::sync::Arc::new(Dropped(urdf)));
    harness.step();
    step_until(
        &mut harness,
        MAX_LOAD_FRAMES,
        "loading with the URDF",
        |app| !app.is_loading() && !app.is_loading_meshes(),
    );
    harness.get_by_label("yumi.urdf");
    harness.get_by_label("Model:").scroll_to_me();
    for _ in 0..5 {
        harness.step();
    }
    let row = harness.get_by_label("Model:").rect();
    // The status bar is at least one text line (~24 points) at the window's bottom.
    assert!(
        row.min.y >= 0.0 && row.max.y <= 800.0 - 24.0,
        "the Model row is at {row:?}, not within the panel above the status bar"
    );
}

/// A robot with a prismatic lift and a coupled (`<mimic>`) joint on each arm: the robot section
/// lists the lift with its travel in mm and the coupled joint as a mimic without a column.
#[test]
fn the_robot_section_lists_prismatic_and_mimic_joints() {
    let dir = tempfile::tempdir().unwrap();
    let urdf = robots::write_file(
        dir.path(),
        "lift_mimic.urdf",
        robots::lift_mimic_urdf().as_bytes(),
    );
    let options = dualcal::robot::LoadOptions {
        arms: PerSide::new(
            Some(dualcal::robot::ArmLinks::new(
                robots::LIFT_MIMIC_ARMS[0].0,
                robots::LIFT_MIMIC_ARMS[0].1,
            )),
            Some(dualcal::robot::ArmLinks::new(
                robots::LIFT_MIMIC_ARMS[1].0,
                robots::LIFT_MIMIC_ARMS[1].1,
            )),
        ),
        ..Default::default()
    };
    let robot = dualcal::robot::RobotDescription::load(urdf.as_path(), &options).unwrap();
    let sim = dualcal::simulate::simulate_with_robot(
        &dualcal::simulate::paper_options(4, 40, 20),
        &robot,
    )
    .unwrap();
    let mut ds = sim.dataset.clone();
    ds.robot = Some(urdf.clone());
    for (side, a) in ds.arms.iter_mut() {
        a.links = robot.arm(side).links.clone().into();
    }
    let data = dir.path().join("data");
    dualcal::dataset::save(&ds, &data, dualcal::dataset::Units::MM_DEG).unwrap();
    let mut harness = open_at(&data);
    assert!(
        harness.state().errors().is_empty(),
        "{:?}",
        harness.state().errors()
    );
    harness.get_by_label("left_base_link → left_flange (6 joints)");
    harness.get_by_label("left joints and parameters").click();
    harness.run_steps(2);
    harness.get_by_label("left_lift_joint");
    harness.get_by_label("0.0 … 300.0 mm");
    harness.get_by_label("left_coupled_joint");
    harness.get_by_label("mimic");
    // Six columns q1 … q6 for seven movable joints.
    harness.get_by_label("q6");
    assert_eq!(harness.query_all_by_label("q7").count(), 0);
}

/// In a window narrower than the status line saying how a run ended, the line keeps to its one line
/// left of the registration RMS (elided, the whole on hover), and the bottom of the window moves
/// nothing either (the plots' tabs, the RMS; `a_finished_run_moves_no_control` checks the left panel).
#[test]
fn a_long_status_line_keeps_to_its_line_left_of_the_registration_rms() {
    let mut harness = harness([1024.0, 768.0], AppLaunch::default());
    loaded(&mut harness);
    let places = |harness: &Harness<'_, WorkbenchApp>| {
        [
            harness.get_by_label("Calibrate").rect(),
            harness.get_by_label("Convergence").rect(),
            harness.get_by_label_contains("registration RMS").rect(),
        ]
    };
    let before = places(&harness);
    harness.get_by_label("Calibrate").click();
    harness.step();
    step_until(&mut harness, MAX_RUN_FRAMES, "calibration", |app| {
        !app.is_calibrating()
    });
    harness.run_steps(2);
    assert_eq!(places(&harness), before, "Calibrate, the tabs, the RMS");
    let status = harness.get_by_label_contains("Calibration done").rect();
    let rms = before[2];
    assert!(
        status.max.x <= rms.min.x,
        "the status {status:?} reaches the registration RMS {rms:?}"
    );
    assert!(
        status.height() < 1.5 * rms.height(),
        "the status {status:?} is one line, as the RMS {rms:?}"
    );
}

/// A one-arm dataset of a lifting column whose measured joint is a leader off the chain (the
/// column's two stages on the chain mimic it, tests/column_mimic.rs): the robot section lists the
/// leader as the arm's first column, under its own name and with its limits, before its followers.
#[test]
fn the_robot_section_lists_a_mimic_leader_off_the_chain_as_a_column() {
    let dir = tempfile::tempdir().unwrap();
    let urdf = robots::write_file(
        dir.path(),
        "column.urdf",
        robots::column_mimic_urdf().as_bytes(),
    );
    let (base, tip) = robots::COLUMN_MIMIC_ARM;
    let links = dualcal::robot::ArmLinks::new(base, tip);
    let options = dualcal::robot::LoadOptions {
        arms: PerSide::new(Some(links.clone()), Some(links.clone())),
        ..Default::default()
    };
    let robot = dualcal::robot::RobotDescription::load(urdf.as_path(), &options).unwrap();
    let sim = dualcal::simulate::simulate_with_robot(
        &dualcal::simulate::paper_options(4, 40, 20),
        &robot,
    )
    .unwrap();
    let mut ds = sim.dataset.clone();
    ds.robot = Some(urdf.clone());
    ds.arms.left.links = Some(links);
    ds.arms.right = dualcal::dataset::ArmData::not_measured(dualcal::side::Side::Right);
    let data = dir.path().join("data");
    dualcal::dataset::save(&ds, &data, dualcal::dataset::Units::MM_DEG).unwrap();
    let mut harness = open_at(&data);
    assert!(
        harness.state().errors().is_empty(),
        "{:?}",
        harness.state().errors()
    );
    let leader = robot.arm(dualcal::side::Side::Left).chain.variables()[0].clone();
    assert!(
        leader.is_off_chain(),
        "the fixture's first column is its leader"
    );
    harness.get_by_label("left joints and parameters").click();
    harness.run_steps(2);
    let row = harness.get_by_label(&leader.name).rect();
    let (lo, hi) = leader.range();
    harness.get_by_label(&format!("{lo:.1} … {hi:.1} mm"));
    // Its row is the first column's, above the stages that follow it.
    let q1 = harness.get_by_label("q1").rect();
    assert!(
        (q1.center().y - row.center().y).abs() < 1.0,
        "{q1:?} {row:?}"
    );
    let mimic = harness.get_all_by_label("mimic").next().unwrap().rect();
    assert!(mimic.min.y > row.max.y, "{mimic:?} below {row:?}");
}

/// The example's measurements as a tracker would export them (SpatialAnalyzer-style points
/// `<id>_<reflector> x y z` under a `//` header) and a controller's joint log, per arm.
fn tracker_files(dir: &std::path::Path) -> PerSide<(std::path::PathBuf, std::path::PathBuf)> {
    let example = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("assets/datasets/example");
    PerSide::from_fn(|side| {
        let text = std::fs::read_to_string(example.join(format!("{side}.csv"))).unwrap();
        let mut points = String::from("// exported for the test\n// units: mm\n");
        let mut joints = String::from("id,q1,q2,q3,q4,q5,q6,q7\n");
        for line in text.lines().filter(|l| !l.starts_with('#')).skip(1) {
            let f: Vec<&str> = line.split(',').collect();
            joints += &format!("{}\n", f[..8].join(","));
            for (k, r) in ["a", "b", "c"].iter().enumerate() {
                let xyz = &f[8 + 3 * k..11 + 3 * k];
                points += &format!("{}_{r} {} {} {}\n", f[0], xyz[0], xyz[1], xyz[2]);
            }
        }
        let p = dir.join(format!("{side}-points.txt"));
        let j = dir.join(format!("{side}-joints.csv"));
        std::fs::write(&p, points).unwrap();
        std::fs::write(&j, joints).unwrap();
        (p, j)
    })
}

#[test]
fn the_import_window_previews_the_files_then_writes_and_opens_the_dataset() {
    let dir = tempfile::tempdir().unwrap();
    let files = tracker_files(dir.path());
    let mut harness = harness([1280.0, 800.0], AppLaunch::default());
    loaded(&mut harness);
    harness.get_by_label("Import…").click();
    harness.run_steps(2);
    assert!(harness.state().import_view().open);
    harness.get_by_label(
        "Choose a point file: one arm's for a dataset of that arm alone, or both arms'.",
    );
    let mut inputs = harness.state().import_view().inputs.clone();
    for side in dualcal::side::Side::BOTH {
        inputs.points[side] = files[side].0.display().to_string();
        inputs.joints[side] = files[side].1.display().to_string();
    }
    // A joint order that does not parse: named in the preview, nothing to write.
    inputs.joint_order = "1,2,9".into();
    harness
        .state_mut()
        .apply(Command::SetImportInputs(Box::new(inputs.clone())));
    harness
        .state_mut()
        .apply(Command::SetImportFolder(dir.path().join("imported")));
    harness.run_steps(3);
    let err = harness
        .state()
        .import_view()
        .preview()
        .unwrap()
        .result
        .as_ref()
        .err()
        .cloned()
        .expect("the joint order is refused");
    assert!(err.contains("joint order"), "{err}");
    harness.get_by_label(&err);
    inputs.joint_order.clear();
    harness
        .state_mut()
        .apply(Command::SetImportInputs(Box::new(inputs)));
    harness.run_steps(3);
    // The preview: every configuration of both arms matched, nothing left over.
    for side in ["left", "right"] {
        let line =
            format!("{side}: 220 configurations (SpatialAnalyzer export, mm; 660 points read)");
        harness.get_by_label(&line);
    }
    // `DUALCAL_SCREENSHOT_OUT=docs/import-window.png` saves the window with its preview (1280×800).
    if let Some(out) = std::env::var_os("DUALCAL_SCREENSHOT_OUT") {
        harness.get_by_label("Report").click();
        harness.run_steps(3);
        harness.render().unwrap().save(out).unwrap();
        harness.get_by_label("Report").click();
        harness.run_steps(2);
    }
    harness.get_by_label("Write dataset and open").click();
    harness.run_steps(2);
    step_until(&mut harness, MAX_LOAD_FRAMES, "loading the import", |app| {
        !app.is_loading()
    });
    let app = harness.state();
    assert!(app.errors().is_empty(), "{:?}", app.errors());
    assert!(!app.import_view().open);
    let session = app.session().unwrap();
    assert_eq!(session.dataset.dir, dir.path().join("imported"));
    // The same measurements as the example (the import writes mm and rad at full precision).
    let example = dualcal::dataset::load(
        &std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("assets/datasets/example"),
    )
    .unwrap();
    for side in dualcal::side::Side::BOTH {
        let (a, b) = (
            &example.arms[side].measurements,
            &session.dataset.arms[side].measurements,
        );
        assert_eq!(a.len(), b.len());
        for (x, y) in a.iter().zip(b) {
            assert_eq!(x.id, y.id);
            for (p, q) in x.tracker_points_mm.iter().zip(&y.tracker_points_mm) {
                assert!((p - q).norm() < 1e-9);
            }
        }
    }
    // Written once: a second import into the same folder is refused, the view says why.
    harness.state_mut().apply(Command::ShowImport(true));
    harness.run_steps(3);
    harness.get_by_label("Write dataset and open").click();
    harness.run_steps(2);
    let err = harness.state().import_view().write_error.clone().unwrap();
    assert!(err.contains("imported"), "{err}");
}

/// The planning window: plan both arms of the loaded robot in the background for a target accuracy
/// (the fewest configurations whose predicted accuracy over the workspace reaches it, and the curve
/// N → predicted accuracy, as `dualcal plan --target`), the plan drawn in 3D (the tracker, its lines
/// of sight, the planned reflectors) with the arm in the chosen planned pose; closing the window
/// draws the dataset again. `DUALCAL_SCREENSHOT_OUT=docs/planning-view.png` also saves the window's
/// picture (1280×800).
#[test]
fn the_planning_window_plans_for_a_target_and_draws_the_plan_with_the_tracker() {
    let mut harness = harness([1280.0, 800.0], AppLaunch::default());
    loaded(&mut harness);
    harness.get_by_label("Plan measurements…").click();
    harness.run_steps(2);
    assert!(harness.state().plan_view().open);
    let mut inputs = harness.state().plan_view().inputs.clone();
    inputs.target = Some(1.3);
    inputs.candidates = 60;
    harness
        .state_mut()
        .apply(Command::SetPlanInputs(Box::new(inputs)));
    harness.get_by_label("Plan").click();
    harness.run_steps(2);
    step_until(&mut harness, MAX_RUN_FRAMES, "planning", |app| {
        app.plan_view()
            .result
            .as_ref()
            .is_some_and(|r| r.plans().is_some())
            || app.plan_view().error.is_some()
    });
    let app = harness.state();
    assert!(
        app.plan_view().error.is_none(),
        "{:?}",
        app.plan_view().error
    );
    let plans = app.plan_view().result.as_ref().unwrap().plans().unwrap();
    // Each arm: the number of configurations the target search settled on, its prediction at or
    // under the target, the designs tried on the way (N = 6 and 8 at least, predicting worse) — and
    // the window says so.
    for (side, plan) in [("left", &plans.left), ("right", &plans.right)] {
        let n = plan.configs.len();
        let predicted = plan
            .prediction
            .as_ref()
            .expect("a prediction")
            .default_method
            .mean;
        assert!(
            predicted <= 1.3,
            "{side}: {n} configurations predict {predicted}"
        );
        assert!(plan.curve.len() >= 3, "{side}: {:?}", plan.curve);
        assert!(plan.curve.iter().any(|(m, _)| *m == n));
        let first = plan.curve[0].1.as_ref().unwrap().default_method.mean;
        assert!(
            first > 1.3,
            "{side}: the smallest design tried predicts {first}"
        );
        let said = format!("target 1.300×: {n} configurations reach it");
        assert!(
            harness
                .query_all(egui_kittest::kittest::by().label_contains(&said))
                .count()
                >= 1,
            "{said}"
        );
    }
    assert!(
        harness
            .query_all(egui_kittest::kittest::by().label_contains("predicted over the region"))
            .count()
            == 2
    );
    let n_left = plans.left.configs.len();
    let n_right = plans.right.configs.len();
    assert!(n_left >= 8 && n_right >= 8, "{n_left} {n_right}");
    // Drawn: the first planned pose of each arm, the tracker where it was put, every planned
    // configuration's reflectors.
    let overlay = app.viewport().plan.clone().expect("the plan is drawn");
    assert_eq!(overlay.q_rad.left.as_ref(), Some(&plans.left.configs[0]));
    assert_eq!(
        overlay.tracker_mm,
        nalgebra::Vector3::new(2000.0, 0.0, 300.0)
    );
    assert_eq!(overlay.points_mm.right.len(), n_right);
    // Another planned pose of the right arm.
    harness.get_by_label("R003").scroll_to_me();
    harness.run_steps(4);
    harness.get_by_label("R003").click();
    harness.run_steps(3);
    let overlay = harness.state().viewport().plan.clone().unwrap();
    assert_eq!(overlay.q_rad.right.as_ref(), Some(&plans.right.configs[2]));
    if let Some(out) = std::env::var_os("DUALCAL_SCREENSHOT_OUT") {
        harness.run_steps(3);
        harness.render().unwrap().save(out).unwrap();
    }
    // Closed: the dataset is drawn again.
    harness.state_mut().apply(Command::ShowPlan(false));
    harness.run_steps(3);
    assert!(harness.state().viewport().plan.is_none());
}

/// A simulated dataset of the built-in robot (`seed`, configurations, calibration ones), changed by
/// `edit`, saved in `dir`.
fn save_simulated(
    dir: &std::path::Path,
    (seed, n, n_cal): (u64, usize, usize),
    edit: impl FnOnce(&mut dualcal::dataset::Dataset),
) {
    let robot = dualcal::robot::RobotDescription::builtin_irb14000();
    let opts = dualcal::simulate::paper_options(seed, n, n_cal);
    let mut ds = dualcal::simulate::simulate_with_robot(&opts, &robot)
        .unwrap()
        .dataset;
    edit(&mut ds);
    dualcal::dataset::save(&ds, dir, dualcal::dataset::Units::MM_DEG).unwrap();
}

/// One arm alone (a dataset with one `[[arms]]` entry): the dataset section says the other arm was
/// not measured, the convergence tabs list only its stage, the calibration, the accuracy and summary
/// tabs, the comparison and the exports work, and the figures of the other arm and the collaborative
/// pairs are absent, never zero.
#[test]
fn one_arm_alone_calibrates_compares_and_exports() {
    use dualcal::dataset::Split;
    use dualcal::side::Side;
    let dir = tempfile::tempdir().unwrap();
    save_simulated(dir.path(), (12, 120, 80), |ds| {
        ds.arms.right = dualcal::dataset::ArmData::not_measured(Side::Right);
    });
    let mut harness = open_at(dir.path());
    shown(&harness, "right: not measured");
    shown(&harness, "one arm alone (left)");
    harness.get_by_label("step 1 (left arm)");
    assert_eq!(
        harness.query_all_by_label("step 1 (right arm)").count(),
        0,
        "the right arm has no stage"
    );
    calibrate(&mut harness);
    let app = harness.state();
    assert!(app.errors().is_empty(), "{:?}", app.errors());
    let c = app
        .session()
        .unwrap()
        .calibrated
        .as_ref()
        .expect("a result");
    assert!(c.result.is_converged(), "{:?}", c.result.warnings());
    let ver = c.analysis.ver.report.expect("verification figures");
    assert!(ver.relative_left.unwrap().pos_rms_mm < 0.05);
    assert!(ver.relative_right.is_none() && ver.collaborative.is_none());
    for tab in ["Accuracy", "Summary", "Convergence"] {
        harness.get_by_label(tab).click();
        harness.run_steps(3);
    }
    let params = dualcal::app::export::Export::Params
        .contents(harness.state().session().unwrap())
        .unwrap()
        .unwrap();
    let params: serde_json::Value = serde_json::from_slice(&params).unwrap();
    assert!(
        params["statistics"]["ver"]["relative_right"].is_null(),
        "{params}"
    );
    // The comparison view: each method on the one arm.
    harness.get_by_label("Compare methods…").click();
    harness.run_steps(2);
    pick_methods(&mut harness, &["minimax", "lsq"]);
    harness.run_steps(2);
    run_comparison(&mut harness);
    let app = harness.state();
    let comparison = app
        .compare_view()
        .comparison
        .as_ref()
        .expect("a comparison");
    for key in ["minimax", "lsq"] {
        let report = comparison
            .method(key)
            .and_then(|m| m.figures())
            .and_then(|f| f.report(Split::Ver))
            .unwrap_or_else(|| panic!("{key}: no figures"));
        assert!(report.relative_left.unwrap().pos_rms_mm < 0.05, "{key}");
        assert!(report.relative_right.is_none(), "{key}");
    }
    harness.run_steps(3);
}

/// The step-1 method follows the data until the user picks one: the absolute positions for one
/// marker per hand measured together in one frame (as `dualcal calibrate`'s default), said under the
/// settings; the paper's minimax for the example.
#[test]
fn the_method_follows_the_data_until_picked() {
    use dualcal::side::Side;
    use dualcal::solver::Method;
    let dir = tempfile::tempdir().unwrap();
    save_simulated(dir.path(), (13, 60, 40), |ds| {
        ds.nominal_reflectors_mm.truncate(1);
        ds.reflector_names = ds.reflector_names[..1].to_vec().into();
        for side in Side::BOTH {
            for (i, m) in ds.arms[side].measurements.iter_mut().enumerate() {
                m.tracker_points_mm.truncate(1);
                m.id = format!("P{i:03}");
            }
        }
        ds.measured_together = true;
    });
    let mut harness = harness([1400.0, 900.0], AppLaunch::default());
    loaded(&mut harness);
    assert_eq!(harness.state().settings().method, Method::Minimax);
    harness
        .state_mut()
        .apply(Command::OpenDataset(dir.path().to_path_buf()));
    step_until(&mut harness, MAX_LOAD_FRAMES, "loading", |app| {
        !app.is_loading()
    });
    assert_eq!(harness.state().settings().method, Method::Position);
    shown(&harness, "position: the default for this data");
    // Picked by the user: kept for the next dataset.
    pick_in_combo(&mut harness, "Method", "minimax (paper, Algorithm I)");
    harness
        .state_mut()
        .apply(Command::OpenDataset(dir.path().to_path_buf()));
    step_until(&mut harness, MAX_LOAD_FRAMES, "loading", |app| {
        !app.is_loading()
    });
    assert_eq!(harness.state().settings().method, Method::Minimax);
}

/// A paper-size simulated dataset of the built-in robot with the robustness study's joint errors (gear
/// harmonics and compliance: what only a model beyond geometry explains), written to a temporary
/// directory.
fn joint_error_dataset() -> tempfile::TempDir {
    let robot = dualcal::robot::RobotDescription::builtin_irb14000();
    let opts = dualcal::simulate::SimOptions {
        joint_error: Some(dualcal::simulate::unmodelled_joint_errors()),
        ..dualcal::simulate::paper_options(5, 220, 120)
    };
    let sim = dualcal::simulate::simulate_with_robot(&opts, &robot).expect("simulation");
    let dir = tempfile::tempdir().unwrap();
    dualcal::dataset::save(&sim.dataset, dir.path(), dualcal::dataset::Units::MM_DEG).unwrap();
    dir
}

/// Issue 21 in the workbench: the Model picker calibrates beyond geometry; the Accuracy tab shows the
/// geometric calibration of the same data between nominal and the full model; the identified
/// compliances and harmonics are listed with their σ; the exported parameter file carries them.
#[test]
fn the_model_picker_calibrates_beyond_geometry_beside_the_geometric_fit() {
    use dualcal::dataset::Split;
    use dualcal::kinematics::ErrorTerms;
    let dir = joint_error_dataset();
    let mut harness = open_at(dir.path());
    pick_in_combo(&mut harness, "Model", "full model");
    assert_eq!(
        harness.state().settings().model,
        ErrorTerms::from_name("full").unwrap()
    );
    calibrate(&mut harness);
    let app = harness.state();
    assert!(app.errors().is_empty(), "{:?}", app.errors());
    let session = app.session().unwrap();
    let c = session.calibrated.as_ref().expect("calibrated");
    assert_eq!(c.result.calibrated.error_terms().name(), "full");
    // The geometric reference is the geometric calibration of the same data: far above the full
    // model on this data (unmodelled joint errors for it).
    let geometric = session.geometric.as_ref().expect("the geometric reference");
    let rms = |a: &dualcal::analysis::Analysis| {
        a.figures(Split::Ver)
            .and_then(|f| f.report.as_ref())
            .map(|r| r.relative_left.unwrap().pos_rms_mm)
            .unwrap()
    };
    let (g, f) = (rms(geometric), rms(&c.analysis));
    eprintln!("workbench, relative left RMS on verification: geometric {g:.4} mm, full {f:.4} mm");
    assert!(g > 10.0 * f, "geometric {g} vs full {f}");
    harness.get_by_label("Accuracy").click();
    harness.run_steps(3);
    shown(&harness, "geometric");
    // The robot section lists the identified compliances and harmonics with their σ.
    harness.get_by_label("left joints and parameters").click();
    harness.run_steps(2);
    harness
        .get_by_label("beyond geometry: the `full` model's compliances and harmonics")
        .click();
    harness.run_steps(2);
    let c = harness
        .state()
        .session()
        .unwrap()
        .calibrated
        .as_ref()
        .unwrap();
    let u = c
        .uncertainty
        .left
        .as_ref()
        .expect("the left arm's uncertainty");
    let sigma = u
        .parameters
        .iter()
        .find(|p| p.name == "j2.k_axis")
        .expect("j2's compliance identified");
    assert_eq!(sigma.unit, "mrad/(N·m)");
    shown(&harness, &format!("± {:.4} mrad/(N·m)", sigma.sigma));
    shown(&harness, "j2.h2_cos");
    let bytes = dualcal::app::export::Export::Params
        .contents(harness.state().session().unwrap())
        .expect("a calibration to export")
        .expect("the parameter file");
    let file: serde_json::Value = serde_json::from_slice(&bytes).unwrap();
    assert_eq!(file["arms"]["left"]["errors"]["model"], "full");
    assert!(file["arms"]["left"]["errors"]["parameters"]["j2.k_axis"].is_number());
    // Back to the geometric model: no reference column, no errors in the result.
    harness.get_by_label("left joints and parameters").click();
    harness.run_steps(2);
    edit_settings(&mut harness, |s| s.model = ErrorTerms::GEOMETRIC);
    calibrate(&mut harness);
    let session = harness.state().session().unwrap();
    assert!(session.geometric.is_none());
    assert!(
        session
            .calibrated
            .as_ref()
            .unwrap()
            .result
            .calibrated
            .error_terms()
            .is_geometric()
    );
}

/// At 1280 × 800 no control moves when a calibration ends: the left panel's line naming the current
/// calibration is there before one too, one line high, so Calibrate, Cancel, the exports and the view
/// options below it stay where they were.
#[test]
fn a_finished_run_moves_no_control() {
    let mut harness = harness([1280.0, 800.0], AppLaunch::default());
    loaded(&mut harness);
    let controls = ["Calibrate", "Cancel", "Parameters (JSON)…", "Reset view"];
    let rects = |harness: &Harness<'_, WorkbenchApp>| {
        controls.map(|label| harness.get_by_label(label).rect())
    };
    let before = rects(&harness);
    harness.get_by_label("Calibrate").click();
    harness.step();
    step_until(&mut harness, MAX_RUN_FRAMES, "calibration result", |app| {
        !app.is_calibrating()
    });
    harness.run_steps(2);
    assert!(
        harness.state().session().unwrap().calibrated.is_some(),
        "{:?}",
        harness.state().errors()
    );
    shown(&harness, "current: method");
    let after = rects(&harness);
    for ((label, b), a) in controls.iter().zip(before).zip(after) {
        assert_eq!(b, a, "{label} moved when the run ended");
    }
}
