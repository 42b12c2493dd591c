//! Plan a measurement through the crate's front door: which configurations of the built-in IRB 14000
//! to measure for a tracker 2 m in front of it, the predicted accuracy, and the files to fill in
//! (the dataset CSVs, the visiting path, RAPID modules).
//!
//! `cargo run --release --example plan -- [N] [OUT_DIR]`
//! (default: 20 configurations per arm, written into `target/example-plan/`).

use dualcal::{Plan, Robot, Side};

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let mut args = std::env::args().skip(1);
    let n: usize = args.next().map_or(Ok(20), |s| s.parse())?;
    let out = args
        .next()
        .unwrap_or_else(|| concat!(env!("CARGO_MANIFEST_DIR"), "/target/example-plan").into());
    let robot = Robot::builtin_irb14000();
    let planned = Plan::new(&robot, [2000.0, 0.0, 300.0])
        .configurations(n)
        .keep_out([1800.0, -300.0, -1000.0], [2200.0, 300.0, 200.0]) // the tracker's stand
        .run()?;
    print!("{}", planned.summary());
    for side in Side::BOTH {
        let first = &planned.configurations(side)[0];
        let deg: Vec<String> = first
            .iter()
            .map(|q| format!("{:.1}", q.to_degrees()))
            .collect();
        println!("{side} arm, first configuration: [{}] deg", deg.join(", "));
        if let Some(p) = planned.predicted(side) {
            let largest = p.uncertainty.largest("mm").map_or(f64::NAN, |s| s.sigma);
            println!(
                "{side} arm: predicted largest 1σ {largest:.4} mm with {:.4} mm of tracker noise{}",
                p.point_sigma_mm,
                p.verification_ratio
                    .map(|r| format!("; verification {r:.3}× the noise floor"))
                    .unwrap_or_default()
            );
        }
    }
    planned.save(&out, true)?;
    println!("wrote {out}");
    Ok(())
}
