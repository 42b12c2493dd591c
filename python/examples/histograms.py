"""Calibrate the bundled example from Python and plot the accuracy histograms (the paper's Figs. 6–8:
per pair of verification configurations, the worst reflector's distance error), nominal against
calibrated.

    pip install ./python matplotlib
    python python/examples/histograms.py [DATASET_DIR] [OUT.png]
"""

import pathlib
import sys

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

import dualcal  # noqa: E402

root = pathlib.Path(__file__).resolve().parents[2]
dataset = sys.argv[1] if len(sys.argv) > 1 else root / "assets" / "datasets" / "example"
out = sys.argv[2] if len(sys.argv) > 2 else "histograms.png"

ds = dualcal.Dataset.load(dataset)
result = dualcal.calibrate(ds)
print(result, "stages:", [(s["stage"], s["iterations"]) for s in result.stages])

panels = [
    ("left_position_mm", "relative Δd, left arm (mm)"),
    ("right_position_mm", "relative Δd, right arm (mm)"),
    ("collaborative_position_mm", "collaborative Δd (mm)"),
]
nominal = result.pair_errors("ver", "nominal")
calibrated = result.pair_errors("ver", "calibrated")
fig, axes = plt.subplots(2, len(panels), figsize=(12, 6), constrained_layout=True)
for column, (key, label) in enumerate(panels):
    for row, (name, samples) in enumerate((("nominal", nominal), ("calibrated", calibrated))):
        ax = axes[row, column]
        values = samples[key]
        ax.hist(values, bins=41, color="#888" if row == 0 else "#2a7")
        rms = float(np.sqrt(np.mean(values**2)))
        ax.set_title(f"{name}: worst reflector per pair, RMS {rms:.3f} mm", fontsize=9)
        ax.set_xlabel(label)
        ax.set_ylabel("pairs")
fig.suptitle(f"{pathlib.Path(dataset).name}: verification pairs, nominal vs calibrated")
fig.savefig(out, dpi=100)
print("written", out)
