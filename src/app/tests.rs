//! The workbench driven inside the crate, for what needs test-only hooks: a calibration worker that
//! panics (the fault injection is compiled into tests only). The rest of the workbench's tests drive
//! it from outside, as a user does (`tests/gui.rs`).

use super::task::Execution;
use super::{AppLaunch, WorkbenchApp};
use egui_kittest::Harness;
use egui_kittest::kittest::Queryable;

/// A frame cap: generous, so a slow machine passes; it only stops a hung test.
const MAX_FRAMES: usize = 200_000;

fn step_until(
    harness: &mut Harness<'_, WorkbenchApp>,
    what: &str,
    done: impl Fn(&WorkbenchApp) -> bool,
) {
    for _ in 0..MAX_FRAMES {
        if done(harness.state()) {
            // One more frame so the UI shows the new state.
            harness.step();
            return;
        }
        harness.step();
        std::thread::sleep(std::time::Duration::from_millis(2));
    }
    panic!("{what}: not reached within {MAX_FRAMES} frames");
}

/// A panic inside the calibration worker is caught and shown; the window stays usable and the next
/// calibration runs. `execution`: on a thread, or stepped in frames (a browser).
fn a_panicking_worker_is_shown(execution: Execution) {
    let mut harness = Harness::builder()
        .with_size(eframe::egui::Vec2::new(1400.0, 900.0))
        .wgpu()
        .build_eframe(|cc| {
            WorkbenchApp::with_options(
                cc,
                AppLaunch::default(),
                crate::app::LaunchOptions {
                    msaa_samples: Some(1),
                    ..Default::default()
                },
            )
        });
    step_until(&mut harness, "loading the example", |app| !app.is_loading());
    assert!(
        harness.state().session().is_some(),
        "{:?}",
        harness.state().errors()
    );
    harness.state_mut().set_execution(execution);
    harness.state_mut().inject_panic_in_next_calibration();
    harness.get_by_label("Calibrate").click();
    harness.step();
    step_until(&mut harness, "the worker's end", |app| {
        !app.is_calibrating()
    });
    let errors = harness.state().errors().to_vec();
    assert_eq!(errors.len(), 1, "{errors:?}");
    assert!(
        errors[0].contains("stopped unexpectedly")
            && errors[0].contains("fault injected into the calibration worker"),
        "{errors:?}"
    );
    harness.get_by_label_contains("calibration worker stopped unexpectedly");
    harness.get_by_label_contains("Calibration failed; the nominal model is shown again");
    // Still usable: the next calibration runs to its result.
    harness.get_by_label("Calibrate").click();
    harness.step();
    step_until(&mut harness, "calibration", |app| !app.is_calibrating());
    assert!(harness.state().session().unwrap().calibrated.is_some());
}

#[test]
fn a_panic_in_the_calibration_thread_is_shown() {
    a_panicking_worker_is_shown(Execution::Thread);
}

#[test]
fn a_panic_in_calibration_work_stepped_in_frames_is_shown() {
    a_panicking_worker_is_shown(Execution::InFrames);
}
