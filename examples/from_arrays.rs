//! Measurements held in memory (joint values and tracker points from another program) calibrated
//! without writing files: one arm of the bundled example, read here as plain numbers.
//!
//! `cargo run --release --example from_arrays`

use dualcal::{ArmArrays, Arrays, Calibration, Dataset, Method, Robot, Split};

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let csv = std::fs::read_to_string(concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/assets/datasets/example/left.csv"
    ))?;
    let mut arm = ArmArrays::default();
    // id, q1..q7 (deg), ax..cz (mm), split
    for line in csv.lines().skip(2).filter(|l| !l.trim().is_empty()) {
        let cells: Vec<&str> = line.split(',').collect();
        let numbers: Vec<f64> = cells[1..17]
            .iter()
            .map(|c| c.parse())
            .collect::<Result<_, _>>()?;
        arm.ids.push(cells[0].to_string());
        arm.joints
            .push(numbers[..7].iter().map(|d| d.to_radians()).collect());
        arm.points_mm
            .push(numbers[7..].chunks(3).map(|p| [p[0], p[1], p[2]]).collect());
        arm.split.push(if cells[17] == "ver" {
            Split::Ver
        } else {
            Split::Cal
        });
    }
    let ds = Dataset::from_arrays(
        &Robot::builtin_irb14000(),
        Arrays {
            reflector_names: vec!["a".into(), "b".into(), "c".into()],
            nominal_reflectors_mm: vec![
                [45.0, 0.0, 40.0],
                [-25.0, 40.0, 40.0],
                [-25.0, -40.0, 40.0],
            ],
            left: Some(arm),
            right: None,
            tracker: Default::default(),
            measured_together: false,
        },
    )?;
    let result = Calibration::new(&ds).method(Method::LeastSquares).run()?;
    let ver = result
        .accuracy()?
        .verification
        .ok_or("no verification rows")?;
    let (b, a) = (
        ver.nominal.relative_left.unwrap(),
        ver.calibrated.relative_left.unwrap(),
    );
    println!(
        "left arm alone, verification: {:.3} → {:.3} mm RMS",
        b.pos_rms_mm, a.pos_rms_mm
    );
    Ok(())
}
