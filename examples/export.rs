//! Everything a calibration gives back to the robot, through the crate's front door: the parameter
//! file and its accuracy evaluated again (`dualcal evaluate`), the calibrated URDF and its overlay,
//! the ABB base frames, and joint targets compensated for the controller's nominal model.
//!
//! `cargo run --release --example export -- [DATASET_DIR] [OUT_DIR]`
//! (default: the bundled example, written into `target/example-export/`).

use dualcal::controller::compensate::{CompensationSettings, Target};
use dualcal::{Calibration, Dataset, Side, evaluate};

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let mut args = std::env::args().skip(1);
    let dataset = args
        .next()
        .unwrap_or_else(|| concat!(env!("CARGO_MANIFEST_DIR"), "/assets/datasets/example").into());
    let out =
        std::path::PathBuf::from(args.next().unwrap_or_else(|| {
            concat!(env!("CARGO_MANIFEST_DIR"), "/target/example-export").into()
        }));
    std::fs::create_dir_all(&out)?;
    let ds = Dataset::load(&dataset)?;
    let result = Calibration::new(&ds).run()?;

    // The parameter file, and its accuracy on the dataset read back (what `dualcal evaluate` prints).
    let params = out.join("params.json");
    result.save_params(&params)?;
    let figures = evaluate(&ds, &params)?;
    if let Some(ver) = figures.verification.and_then(|r| r.collaborative) {
        println!(
            "params.json on the verification split: {:.4} mm RMS (collaborative)",
            ver.pos_rms_mm
        );
    }

    // The calibrated URDF (the description with only the arm joints' origins changed), the same
    // changes as an overlay, and the base frames for the ABB controller.
    result.save_urdf(out.join("calibrated.urdf"))?;
    std::fs::write(out.join("overlay.yaml"), result.overlay(false)?)?;
    std::fs::write(out.join("MOC_base_frames.cfg"), result.abb_base_frames())?;

    // Joint targets of the robot program, compensated: the calibrated robot then reaches the poses
    // the controller's nominal model meant.
    let targets: Vec<Target> = ds.data().arm(Side::Left).measurements[..5]
        .iter()
        .map(|m| Target::Joints(m.q_rad.clone()))
        .collect();
    for (target, compensated) in targets.iter().zip(result.compensate(
        Side::Left,
        &targets,
        &CompensationSettings::default(),
    )) {
        match compensated {
            Ok(c) => println!(
                "compensated: largest joint change {:.4} mrad, remaining error {:.1e} mm",
                1e3 * c.largest_change,
                c.residual_mm
            ),
            Err(why) => println!("refused ({:?}): {why}", target.start()),
        }
    }
    println!("written to {}", out.display());
    Ok(())
}
