//! Import tracker exports and joint logs into a dataset through the crate's front door, then
//! calibrate it. The files are made here from the bundled example, as a tracker's software and a
//! controller would write them: per arm a SpatialAnalyzer point list (`L001_a x y z`, mm) and a
//! joint log (`id,q1..q7,split`, degrees); one shot of `L003`'s reflector `a` is left out, so the
//! report says what did not match.
//!
//! `cargo run --release --example import -- [OUT_DIR]`
//! (default: `target/example-import/`: the input files, and the imported dataset in `dataset/`).

use dualcal::import::MatchRule;
use dualcal::{Calibration, Dataset, Import, Robot, Side};
use std::path::{Path, PathBuf};

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let out =
        PathBuf::from(std::env::args().nth(1).unwrap_or_else(|| {
            concat!(env!("CARGO_MANIFEST_DIR"), "/target/example-import").into()
        }));
    std::fs::create_dir_all(&out)?;
    let example = Dataset::load(concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/assets/datasets/example"
    ))?;
    for side in Side::BOTH {
        write_exports(&example, side, &out)?;
    }
    let imported = Import::new(&Robot::builtin_irb14000())
        .arm(
            Side::Left,
            out.join("left.txt"),
            Some(out.join("left-joints.csv")),
        )
        .arm(
            Side::Right,
            out.join("right.txt"),
            Some(out.join("right-joints.csv")),
        )
        .matching(MatchRule::Name)
        .angle_unit(dualcal::dataset::AngleUnit::Deg)
        .run()?;
    print!("{}", imported.report_text());
    imported.save(out.join("dataset"), true)?;
    let result = Calibration::new(imported.dataset()).run()?;
    if let Some(ver) = result.accuracy()?.verification
        && let (Some(before), Some(after)) =
            (ver.nominal.collaborative, ver.calibrated.collaborative)
    {
        println!(
            "verification collaborative: {:.3} → {:.3} mm RMS",
            before.pos_rms_mm, after.pos_rms_mm
        );
    }
    println!(
        "imported dataset written to {}",
        out.join("dataset").display()
    );
    Ok(())
}

/// One arm's point list and joint log as a tracker and a controller write them.
fn write_exports(ds: &Dataset, side: Side, out: &Path) -> std::io::Result<()> {
    let mut points = String::from("// SpatialAnalyzer ASCII export\n// Units: Millimeters\n");
    let mut joints = String::from("id,q1,q2,q3,q4,q5,q6,q7,split\n");
    for m in &ds.data().arm(side).measurements {
        for (name, p) in ds.reflector_names().iter().zip(&m.tracker_points_mm) {
            if m.id == "L003" && name == "a" {
                continue; // a shot the operator missed
            }
            points += &format!("{}_{name} {:?} {:?} {:?}\n", m.id, p.x, p.y, p.z);
        }
        let q: Vec<String> = m
            .q_rad
            .iter()
            .map(|q| format!("{:?}", q.to_degrees()))
            .collect();
        joints += &format!("{},{},{}\n", m.id, q.join(","), m.split.name());
    }
    std::fs::write(out.join(format!("{side}.txt")), points)?;
    std::fs::write(out.join(format!("{side}-joints.csv")), joints)
}
