//! Speed of loading a robot description's meshes (engine side: read, parse, normals, in parallel):
//! a synthetic 3 MB set of binary STL files, ten links of 6 000 triangles each, written by the bench.
//!
//! `cargo bench --bench meshes`
use criterion::{Criterion, criterion_group, criterion_main};
use dualcal::meshes::{GeometryKind, MeshResolver, PackageMap, load_robot_meshes};
use std::hint::black_box;

/// A binary STL of `n` triangles on a sphere-ish strip (zero normals: the loader computes them).
fn stl(n: usize, seed: f32) -> Vec<u8> {
    let mut b = vec![0u8; 80];
    b.extend((n as u32).to_le_bytes());
    for i in 0..n {
        let t = i as f32 * 0.01 + seed;
        b.extend([0u8; 12]);
        for k in 0..3 {
            let a = t + k as f32 * 0.003;
            for c in [a.cos() * 0.05, a.sin() * 0.05, (a * 0.1).sin() * 0.1] {
                b.extend(c.to_le_bytes());
            }
        }
        b.extend([0u8; 2]);
    }
    b
}

fn bench(c: &mut Criterion) {
    let dir = tempfile::tempdir().expect("temp dir");
    let mut links = String::new();
    let mut bytes = 0;
    for k in 0..10 {
        let data = stl(6000, k as f32);
        bytes += data.len();
        std::fs::write(dir.path().join(format!("link_{k}.stl")), data).expect("write");
        links += &format!(
            "<link name=\"l{k}\"><visual><geometry><mesh filename=\"link_{k}.stl\"/></geometry></visual></link>"
        );
    }
    let urdf_path = dir.path().join("robot.urdf");
    let robot =
        urdf_rs::read_from_string(&format!("<robot name=\"r\">{links}</robot>")).expect("urdf");
    let resolver = MeshResolver::new(Some(&urdf_path), PackageMap::new());
    let mut group = c.benchmark_group("meshes");
    group.sample_size(10);
    group.bench_function(
        format!("load_{:.1}_MB_of_binary_stl", bytes as f64 / 1e6),
        |b| {
            b.iter(|| {
                let set = load_robot_meshes(black_box(&robot), &resolver, GeometryKind::Visual);
                assert!(set.warnings.is_empty());
                black_box(set.triangle_count())
            })
        },
    );
    group.finish();
}

criterion_group!(benches, bench);
criterion_main!(benches);
