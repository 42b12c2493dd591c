//! Load the meshes of a robot description and report what was loaded, how long it took, and every
//! warning (a missing or unreadable file):
//!
//! ```sh
//! cargo run --release --example load_meshes -- ROBOT.urdf [visual|collision] [PACKAGE=DIR …]
//! ```
use dualcal::meshes::{GeometryKind, MeshResolver, PackageMap, load_robot_meshes};
use std::path::{Path, PathBuf};
use std::time::Instant;

fn main() -> anyhow::Result<()> {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let Some(file) = args.first() else {
        anyhow::bail!("usage: load_meshes ROBOT.urdf [visual|collision] [PACKAGE=DIR …]");
    };
    let kind = match args.get(1).map(String::as_str) {
        Some("collision") => GeometryKind::Collision,
        _ => GeometryKind::Visual,
    };
    let packages: PackageMap = args
        .iter()
        .skip(2)
        .filter_map(|a| a.split_once('='))
        .map(|(k, v)| (k.to_string(), PathBuf::from(v)))
        .collect();
    let robot = urdf_rs::read_file(file)?;
    let resolver = MeshResolver::new(Some(Path::new(file)), packages);
    let start = Instant::now();
    let set = load_robot_meshes(&robot, &resolver, kind);
    let secs = start.elapsed().as_secs_f64();
    let bytes: u64 = set
        .meshes
        .keys()
        .filter_map(|(name, _)| resolver.resolve(name).ok())
        .filter_map(|p| std::fs::metadata(p).ok())
        .map(|m| m.len())
        .sum();
    println!(
        "{kind:?} meshes of {file}: {} files, {:.2} MB, {} triangles, loaded in {secs:.3} s; {} warnings",
        set.meshes.len(),
        bytes as f64 / 1e6,
        set.triangle_count(),
        set.warnings.len()
    );
    for w in &set.warnings {
        println!("  warning: {w}");
    }
    Ok(())
}
