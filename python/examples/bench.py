"""Time `dualcal.calibrate` on the bundled example (2 × 120 calibration configurations): the median
of N calls, to set beside `cargo bench --no-default-features --bench front_door`, which times the same
calibration from Rust (docs/performance.md).

    python python/examples/bench.py [N]
"""

import pathlib
import statistics
import sys
import time

import dualcal

root = pathlib.Path(__file__).resolve().parents[2]
n = int(sys.argv[1]) if len(sys.argv) > 1 else 30
ds = dualcal.Dataset.load(root / "assets" / "datasets" / "example")
dualcal.calibrate(ds)  # warm-up
times = []
for _ in range(n):
    t0 = time.perf_counter()
    result = dualcal.calibrate(ds)
    times.append(time.perf_counter() - t0)
    assert result.converged
print(
    f"dualcal.calibrate(example): median {statistics.median(times) * 1e3:.2f} ms, "
    f"min {min(times) * 1e3:.2f} ms, max {max(times) * 1e3:.2f} ms over {n} calls"
)
