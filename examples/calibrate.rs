//! Calibrate a dataset through the crate's front door and write what goes back on the robot: the
//! parameter file, the calibrated URDF and the ABB base frames.
//!
//! `cargo run --release --example calibrate -- [DATASET_DIR] [OUT_DIR]`
//! (default: the bundled example, written into `target/example-calibrate/`).

use dualcal::{Calibration, Dataset, Method, Side};

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let mut args = std::env::args().skip(1);
    let dataset = args
        .next()
        .unwrap_or_else(|| concat!(env!("CARGO_MANIFEST_DIR"), "/assets/datasets/example").into());
    let out = std::path::PathBuf::from(args.next().unwrap_or_else(|| {
        concat!(env!("CARGO_MANIFEST_DIR"), "/target/example-calibrate").into()
    }));
    let ds = Dataset::load(&dataset)?;
    let result = Calibration::new(&ds)
        .method(Method::Minimax)
        .on_event(|_event| {}) // progress: stage started, each iteration, stage finished
        .run()?;
    for stage in result.stages() {
        println!(
            "{}: {} after {} iterations",
            stage.stage, stage.termination, stage.iterations
        );
    }
    if let Some(ver) = result.accuracy()?.verification {
        for (name, before, after) in [
            (
                "left",
                ver.nominal.relative_left,
                ver.calibrated.relative_left,
            ),
            (
                "right",
                ver.nominal.relative_right,
                ver.calibrated.relative_right,
            ),
            (
                "collaborative",
                ver.nominal.collaborative,
                ver.calibrated.collaborative,
            ),
        ] {
            if let (Some(b), Some(a)) = (before, after) {
                println!(
                    "verification {name}: {:.3} → {:.3} mm RMS",
                    b.pos_rms_mm, a.pos_rms_mm
                );
            }
        }
    }
    for p in result
        .parameters(Side::Left)
        .iter()
        .filter(|p| p.identified)
        .take(5)
    {
        let sigma = p.sigma.map_or("–".to_string(), |s| format!("{s:.4}"));
        println!(
            "left {}: {:.4} → {:.4} {} (1σ {sigma})",
            p.name, p.nominal, p.calibrated, p.unit
        );
    }
    std::fs::create_dir_all(&out)?;
    result.save_params(out.join("params.json"))?;
    result.save_urdf(out.join("calibrated.urdf"))?;
    std::fs::write(out.join("MOC_base_frames.cfg"), result.abb_base_frames())?;
    println!("written to {}", out.display());
    Ok(())
}
