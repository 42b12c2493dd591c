//! The front door's whole calibration of the bundled example (2 × 120 calibration configurations):
//! both steps, the screening of the result, each arm's uncertainty and the parameter file's records —
//! what `dualcal.calibrate(ds)` runs in Python (`python python/examples/bench.py` times that call;
//! docs/performance.md compares the two).
//!
//! `cargo bench --no-default-features --bench front_door`

use criterion::{Criterion, criterion_group, criterion_main};
use std::hint::black_box;

fn bench(c: &mut Criterion) {
    let ds = dualcal::Dataset::load(concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/assets/datasets/example"
    ))
    .expect("the bundled example");
    let mut group = c.benchmark_group("front_door");
    group.sample_size(20);
    group.bench_function("calibrate_example", |b| {
        b.iter(|| {
            let r = dualcal::Calibration::new(black_box(&ds))
                .run()
                .expect("calibration");
            assert!(r.is_converged());
            black_box(r)
        })
    });
    group.finish();
}

criterion_group!(benches, bench);
criterion_main!(benches);
