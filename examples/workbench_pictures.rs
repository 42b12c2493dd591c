//! The workbench's pictures and its frame-time study, driven headlessly with egui_kittest on wgpu
//! (Mesa lavapipe, no window, no GPU), as `tests/gui.rs` drives it: not tests (they assert nothing
//! but that the workbench got there), so they are commands, run by hand.
//!
//! ```sh
//! cargo run --release --example workbench_pictures -- workbench        # README: docs/workbench-yumi.png
//! cargo run --release --example workbench_pictures -- layout           # README: docs/screenshot-1280x800.png
//! cargo run --release --example workbench_pictures -- meshes           # docs/performance.md: yumi-*.png
//! cargo run --release --example workbench_pictures -- compare          # README: docs/compare-methods.png
//! cargo run --release --example workbench_pictures -- beyond-geometry  # docs/solver.md
//! cargo run --release --example workbench_pictures -- frame-time       # docs/performance.md
//! ```
//!
//! - `workbench`: the workbench on a dataset of your own (`DUALCAL_SCREENSHOT_DATASET=DIR`, e.g. one
//!   simulated with the public YuMi description, see docs/performance.md), after Auto-exclude, the
//!   most severe flagged configuration selected (its row struck through in the table, its flag
//!   beside it). Window size `DUALCAL_SCREENSHOT_SIZE` (default 1280x800).
//! - `layout`: the workbench on the bundled example after a calibration, the convergence plots of
//!   its last step and the status line saying how it ended (window size `DUALCAL_SCREENSHOT_SIZE`,
//!   default 1280x800; 1920x1080 for docs/screenshot-1920x1080.png).
//! - `meshes`: the robot's meshes as the viewport draws them, the viewport alone (no panels), only
//!   the robot and the grid, with the mesh detail `DUALCAL_MESH_DETAIL` chooses
//!   (`DUALCAL_SCREENSHOT_DATASET=DIR`; size `DUALCAL_SCREENSHOT_SIZE`, default 640x480).
//! - `compare`: the comparison view at 1280 × 800 on the bundled example, every method of the
//!   comparison table run.
//! - `beyond-geometry`: the workbench after a calibration beyond geometry — the Accuracy tab with
//!   nominal, the geometric calibration and the full model side by side, the robot section's
//!   compliances (1280 × 800).
//! - `frame-time`: not a benchmark with a threshold: prints the time to build and render a 1400×900
//!   frame with all 2 × 220 configurations' triangles and error vectors, the camera orbiting so the
//!   viewport re-renders every frame; with `DUALCAL_FRAME_TIME_DATASET=DIR` on another dataset (e.g.
//!   one of the public YuMi, with its meshes).
//!
//! The pictures are written to `DUALCAL_SCREENSHOT_OUT` (default `target/<name>.png`). Set
//! `XDG_RUNTIME_DIR` to a mode-700 directory to silence a harmless warning.

use dualcal::app::{AppLaunch, Command, LaunchOptions, WorkbenchApp};
use egui_kittest::Harness;
use egui_kittest::kittest::Queryable;
use std::path::PathBuf;

/// Frame caps: they only stop a hung run.
const MAX_LOAD_FRAMES: usize = 20_000;
const MAX_RUN_FRAMES: usize = 200_000;

fn main() -> anyhow::Result<()> {
    let what = std::env::args().nth(1).unwrap_or_default();
    match what.as_str() {
        "workbench" => workbench(),
        "layout" => layout(),
        "meshes" => meshes(),
        "compare" => compare(),
        "beyond-geometry" => beyond_geometry(),
        "frame-time" => frame_time(),
        _ => anyhow::bail!(
            "usage: workbench_pictures workbench|layout|meshes|compare|beyond-geometry|frame-time"
        ),
    }
}

/// The workbench in a window of `size`, opening `dataset` (`None`: the bundled example); `msaa` as
/// `dualcal gui` draws (off: as the tests' snapshots).
fn harness(size: [f32; 2], dataset: Option<PathBuf>, msaa: bool) -> Harness<'static, WorkbenchApp> {
    let launch = AppLaunch {
        dataset,
        urdf: None,
    };
    // The options `dualcal gui` reads from this environment (DUALCAL_MESH_DETAIL, DUALCAL_MSAA, …);
    // without `msaa`, one sample unless DUALCAL_MSAA forces a count (as the tests' snapshots).
    let mut options = LaunchOptions::from_vars(|name| std::env::var_os(name));
    if !msaa {
        options.msaa_samples = options.msaa_samples.or(Some(1));
    }
    Harness::builder()
        .with_size(eframe::egui::Vec2::new(size[0], size[1]))
        .wgpu()
        .build_eframe(move |cc| WorkbenchApp::with_options(cc, launch, options))
}

/// Step frames until `done` holds (or the cap is hit).
fn step_until(
    harness: &mut Harness<'_, WorkbenchApp>,
    max_frames: usize,
    what: &str,
    done: impl Fn(&WorkbenchApp) -> bool,
) -> anyhow::Result<()> {
    for _ in 0..max_frames {
        if done(harness.state()) {
            // One more frame so the UI shows the new state.
            harness.step();
            return Ok(());
        }
        harness.step();
        std::thread::sleep(std::time::Duration::from_millis(2));
    }
    anyhow::bail!("{what}: not reached within {max_frames} frames")
}

/// Loaded, without errors (and its meshes too).
fn loaded(harness: &mut Harness<'_, WorkbenchApp>) -> anyhow::Result<()> {
    step_until(harness, MAX_LOAD_FRAMES, "loading", |app| !app.is_loading())?;
    step_until(harness, MAX_LOAD_FRAMES, "loading the meshes", |app| {
        !app.is_loading_meshes()
    })?;
    no_errors(harness)
}

fn no_errors(harness: &Harness<'_, WorkbenchApp>) -> anyhow::Result<()> {
    let errors = harness.state().errors();
    anyhow::ensure!(errors.is_empty(), "{errors:?}");
    anyhow::ensure!(harness.state().session().is_some(), "nothing loaded");
    Ok(())
}

fn dataset_from_env() -> anyhow::Result<PathBuf> {
    std::env::var_os("DUALCAL_SCREENSHOT_DATASET")
        .map(PathBuf::from)
        .ok_or_else(|| anyhow::anyhow!("set DUALCAL_SCREENSHOT_DATASET to a dataset directory"))
}

/// `DUALCAL_SCREENSHOT_SIZE` as `WxH`, else `default`.
fn size_from_env(default: [f32; 2]) -> anyhow::Result<[f32; 2]> {
    let Ok(size) = std::env::var("DUALCAL_SCREENSHOT_SIZE") else {
        return Ok(default);
    };
    size.split_once('x')
        .and_then(|(w, h)| Some([w.parse().ok()?, h.parse().ok()?]))
        .ok_or_else(|| anyhow::anyhow!("DUALCAL_SCREENSHOT_SIZE as WxH, not {size:?}"))
}

/// Render the window into `DUALCAL_SCREENSHOT_OUT` (default `target/<name>.png`).
fn save(harness: &mut Harness<'_, WorkbenchApp>, name: &str) -> anyhow::Result<PathBuf> {
    let out = std::env::var_os("DUALCAL_SCREENSHOT_OUT")
        .map_or_else(|| format!("target/{name}.png").into(), PathBuf::from);
    harness.run_steps(4);
    let image = harness
        .render()
        .map_err(|e| anyhow::anyhow!("render: {e}"))?;
    image.save(&out)?;
    println!(
        "wrote {} ({}x{})",
        out.display(),
        image.width(),
        image.height()
    );
    Ok(out)
}

/// Change the 3D view's display options and camera as its View section and the mouse would.
fn edit_view(
    harness: &mut Harness<'_, WorkbenchApp>,
    edit: impl FnOnce(
        &mut dualcal::app::viewport::scene::SceneOptions,
        &mut dualcal::app::viewport::camera::OrbitCamera,
    ),
) {
    let view = harness.state().viewport();
    let (mut options, mut camera) = (view.options.clone(), view.camera);
    edit(&mut options, &mut camera);
    let app = harness.state_mut();
    app.apply(Command::SetViewOptions(Box::new(options)));
    app.apply(Command::SetCamera(Box::new(camera)));
}

fn workbench() -> anyhow::Result<()> {
    let size = size_from_env([1280.0, 800.0])?;
    let mut harness = harness(size, Some(dataset_from_env()?), true);
    loaded(&mut harness)?;
    harness.get_by_label("Auto-exclude").click();
    harness.step();
    step_until(&mut harness, MAX_RUN_FRAMES, "auto-exclude", |app| {
        !app.is_calibrating()
    })?;
    no_errors(&harness)?;
    let worst = harness
        .state()
        .session()
        .and_then(|s| {
            s.screening
                .worst_per_config()
                .into_iter()
                .max_by(|a, b| a.severity().total_cmp(&b.severity()))
        })
        .map(|f| f.config);
    harness.state_mut().apply(Command::Select {
        config: worst,
        reveal_in_table: true,
    });
    // Closer to the robot, the verification configurations hidden: the robot and the flagged
    // triangles stay readable at 1280 × 800.
    edit_view(&mut harness, |options, camera| {
        camera.distance_mm *= 0.7;
        options.show_ver = false;
    });
    save(&mut harness, "workbench")?;
    Ok(())
}

fn layout() -> anyhow::Result<()> {
    let size = size_from_env([1280.0, 800.0])?;
    let mut harness = harness(size, None, true);
    loaded(&mut harness)?;
    harness.get_by_label("Calibrate").click();
    harness.step();
    step_until(&mut harness, MAX_RUN_FRAMES, "calibration", |app| {
        !app.is_calibrating()
    })?;
    no_errors(&harness)?;
    let name = format!("screenshot-{}x{}", size[0], size[1]);
    save(&mut harness, &name)?;
    Ok(())
}

fn meshes() -> anyhow::Result<()> {
    let size = size_from_env([640.0, 480.0])?;
    let mut harness = harness(size, Some(dataset_from_env()?), false);
    loaded(&mut harness)?;
    // Both arms at home, as the View section's "home" buttons put them.
    for k in 0..2 {
        let Some(home) = harness.get_all_by_label("home").nth(k) else {
            break;
        };
        home.scroll_to_me();
        harness.run_steps(2);
        if let Some(home) = harness.get_all_by_label("home").nth(k) {
            home.click();
        }
        harness.run_steps(2);
    }
    harness.state_mut().set_panels_visible(false);
    edit_view(&mut harness, |options, camera| {
        options.show_measured = false;
        options.show_model = false;
        options.show_vectors = false;
        options.show_grid = false;
        camera.distance_mm *= 0.4;
    });
    save(&mut harness, "meshes")?;
    println!(
        "meshes drawn: {}",
        if harness.state().viewport().draws_simplified_meshes() {
            "simplified"
        } else {
            "full"
        }
    );
    Ok(())
}

fn compare() -> anyhow::Result<()> {
    let mut harness = harness([1280.0, 800.0], None, true);
    loaded(&mut harness)?;
    harness.get_by_label("Compare methods…").click();
    harness.run_steps(2);
    harness.get_by_label("all").click();
    harness.run_steps(2);
    harness.get_by_label("Run comparison").click();
    harness.step();
    step_until(&mut harness, MAX_RUN_FRAMES, "comparison", |app| {
        !app.is_comparing()
    })?;
    no_errors(&harness)?;
    save(&mut harness, "compare-methods")?;
    Ok(())
}

/// A paper-size simulated dataset of the built-in robot with the robustness study's joint errors
/// (gear harmonics and compliance: what only a model beyond geometry explains), as
/// `tests/gui.rs`'s Model picker test calibrates it.
fn beyond_geometry() -> anyhow::Result<()> {
    let robot = dualcal::robot::RobotDescription::builtin_irb14000();
    let opts = dualcal::simulate::SimOptions {
        joint_error: Some(dualcal::simulate::unmodelled_joint_errors()),
        ..dualcal::simulate::paper_options(5, 220, 120)
    };
    let sim = dualcal::simulate::simulate_with_robot(&opts, &robot)?;
    let dir = tempfile::tempdir()?;
    dualcal::dataset::save(&sim.dataset, dir.path(), dualcal::dataset::Units::MM_DEG)?;
    let mut harness = harness([1280.0, 800.0], Some(dir.path().to_path_buf()), true);
    loaded(&mut harness)?;
    let mut settings = harness.state().settings().clone();
    settings.model =
        dualcal::kinematics::ErrorTerms::from_name("full").map_err(anyhow::Error::msg)?;
    harness
        .state_mut()
        .apply(Command::SetSettings(Box::new(settings)));
    harness.get_by_label("Calibrate").click();
    harness.step();
    step_until(&mut harness, MAX_RUN_FRAMES, "calibration", |app| {
        !app.is_calibrating()
    })?;
    no_errors(&harness)?;
    harness.get_by_label("Accuracy").click();
    save(&mut harness, "workbench-full-model")?;
    Ok(())
}

fn frame_time() -> anyhow::Result<()> {
    let dataset = std::env::var_os("DUALCAL_FRAME_TIME_DATASET").map(PathBuf::from);
    let mut harness = harness([1400.0, 900.0], dataset, false);
    loaded(&mut harness)?;
    if let Some(dualcal::app::session::RobotMeshes::Loaded(m)) =
        harness.state().session().map(|s| &s.meshes)
    {
        println!(
            "robot meshes: {} files, {} triangles as loaded; packed {} meshes, {} vertices, {} triangles, in {:.3} s (simplified copy included)",
            m.visual_files,
            m.visual_triangles,
            m.packed.mesh_count(),
            m.packed.vertices.len(),
            m.packed.indices.len() / 3,
            m.elapsed_secs
        );
        if let Some(s) = &m.simplified {
            println!(
                "simplified copy: {} vertices, {} triangles",
                s.vertices.len(),
                s.indices.len() / 3
            );
        }
        println!(
            "meshes drawn: {} (DUALCAL_MESH_DETAIL={:?})",
            if harness.state().viewport().draws_simplified_meshes() {
                "simplified"
            } else {
                "full"
            },
            std::env::var("DUALCAL_MESH_DETAIL").ok()
        );
    }
    type Setup = fn(&mut dualcal::app::viewport::scene::SceneOptions);
    let variants: [(&str, bool, Setup); 4] = [
        ("whole window", true, |_| {}),
        ("viewport only", false, |_| {}),
        ("viewport only, robot only", false, |o| {
            o.show_measured = false;
            o.show_model = false;
            o.show_vectors = false;
        }),
        ("viewport only, nothing drawn", false, |o| {
            o.show_robot = false;
            o.show_grid = false;
            o.show_measured = false;
            o.show_model = false;
            o.show_vectors = false;
        }),
    ];
    for (label, panels, setup) in variants {
        harness.state_mut().set_panels_visible(panels);
        edit_view(&mut harness, |options, _| setup(options));
        harness.run_steps(2);
        let _ = harness.render();
        let mut samples = Vec::new();
        for _ in 0..40 {
            edit_view(&mut harness, |_, camera| camera.orbit(5.0, 0.0));
            let t = std::time::Instant::now();
            harness.step();
            harness
                .render()
                .map_err(|e| anyhow::anyhow!("render: {e}"))?;
            samples.push(t.elapsed().as_secs_f64() * 1e3);
        }
        samples.sort_by(f64::total_cmp);
        let mean = samples.iter().sum::<f64>() / samples.len() as f64;
        println!(
            "{label}: mean {mean:.1} ms, median {:.1} ms, max {:.1} ms per frame (build + render + readback)",
            samples[samples.len() / 2],
            samples[samples.len() - 1]
        );
    }
    Ok(())
}
