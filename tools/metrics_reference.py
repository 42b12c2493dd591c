#!/usr/bin/env python3
"""Independent reference implementation of dualcal's accuracy metrics (paper eqs. 5-8).

Written from the definitions of the paper (eqs. 5–8, docs/solver.md), sharing no code with the Rust crate: its own file readers, its own
standard-DH forward kinematics (4x4 homogeneous matrices), its own Kabsch fit (numpy SVD) and its own
rotation angle (arccos of the trace). Prints the same JSON as `dualcal evaluate --json`:

    {"relative_left": {...}, "relative_right": {...}, "collaborative": {...}}

Usage:
    metrics_reference.py DATASET (--params FILE | --nominal [--base-translation X Y Z]
                                  [--base-rotation R11 R12 ... R33]) [--split cal|ver|all]

DATASET is a `dualcal-dataset/1` directory (or its dataset.toml). `--nominal` uses the paper's Table 3 for
both arms, the dataset's nominal reflectors and the right-arm base in the left-arm base given on the
command line (mm; default: the public YuMi body layout).
"""

import argparse
import csv
import io
import json
import math
import os
import sys
import tomllib

try:
    import numpy as np
except ImportError:  # pragma: no cover - reported to the caller
    sys.stderr.write("metrics_reference.py: numpy is required (pip install numpy / apt install python3-numpy)\n")
    sys.exit(3)

DATASET_FORMAT = "dualcal-dataset/1"
PARAMS_FORMAT = "dualcal-params/1"

# Paper Table 3: a (mm), d (mm), theta (rad), alpha (rad), chain order.
HALF_PI = math.pi / 2
TABLE3 = [
    (-30.0, 166.0, 0.0, -HALF_PI),
    (30.0, 0.0, 0.0, HALF_PI),
    (40.5, 251.5, 0.0, -HALF_PI),
    (40.5, 0.0, -HALF_PI, -HALF_PI),
    (-27.0, 265.0, 0.0, HALF_PI),
    (27.0, 0.0, 0.0, -HALF_PI),
    (0.0, 36.0, 0.0, 0.0),
]
NOMINAL_BASE_ROTATION = [
    [0.2352, -0.8755, 0.4220],
    [0.8746, 0.0012, -0.4849],
    [0.4241, 0.4831, 0.7660],
]
NOMINAL_BASE_TRANSLATION_MM = [61.61, -70.77, -34.14]

POS_THRESHOLDS_MM = (0.3, 0.6)
ORI_THRESHOLDS_RAD = (0.005, 0.01)


class InputError(Exception):
    pass


def length_scale(unit, where):
    if unit == "mm":
        return 1.0
    if unit == "m":
        return 1000.0
    raise InputError(f"{where}: unknown length unit {unit!r} (expected mm or m)")


def angle_scale(unit, where):
    if unit == "rad":
        return 1.0
    if unit == "deg":
        return math.pi / 180.0
    raise InputError(f"{where}: unknown angle unit {unit!r} (expected deg or rad)")


# ---------------------------------------------------------------------------------------------------------
# Reading files


def read_arm_csv(path, mm_per_unit, rad_per_unit):
    with open(path, encoding="utf-8") as f:
        lines = [ln for ln in f.read().splitlines() if ln.strip() and not ln.lstrip().startswith("#")]
    reader = csv.DictReader(io.StringIO("\n".join(lines)))
    reader.fieldnames = [h.strip() for h in (reader.fieldnames or [])]
    needed = ["id"] + [f"q{i}" for i in range(1, 8)] + [f"{r}{c}" for r in "abc" for c in "xyz"]
    missing = [h for h in needed if h not in reader.fieldnames]
    if missing:
        raise InputError(f"{path}: missing column(s) {missing}")
    rows = []
    for row in reader:
        q = [float(row[f"q{i}"]) * rad_per_unit for i in range(1, 8)]
        pts = [[float(row[f"{r}{c}"]) * mm_per_unit for c in "xyz"] for r in "abc"]
        split = (row.get("split") or "cal").strip() or "cal"
        if split not in ("cal", "ver"):
            raise InputError(f"{path}: configuration {row['id']}: split {split!r}")
        rows.append({"id": row["id"].strip(), "q": q, "points": pts, "split": split})
    return rows


def read_dataset(path):
    manifest = os.path.join(path, "dataset.toml") if os.path.isdir(path) else path
    base_dir = os.path.dirname(os.path.abspath(manifest))
    with open(manifest, "rb") as f:
        doc = tomllib.load(f)
    if doc.get("format") != DATASET_FORMAT:
        raise InputError(f"{manifest}: format is {doc.get('format')!r}, expected {DATASET_FORMAT!r}")
    units = doc.get("units", {})
    mm = length_scale(units.get("length", "mm"), manifest)
    rad = angle_scale(units.get("angle", "deg"), manifest)
    refl = doc["reflectors"]
    reflectors = np.array([[float(x) * mm for x in refl[k]] for k in "abc"])
    arms = {}
    for arm in doc["arms"]:
        name = arm["name"]
        if name not in ("left", "right"):
            raise InputError(f"{manifest}: unknown arm {name!r}")
        arms[name] = read_arm_csv(os.path.join(base_dir, arm["file"]), mm, rad)
    for name in ("left", "right"):
        if name not in arms:
            raise InputError(f"{manifest}: no {name} arm")
    return {"reflectors_mm": reflectors, "arms": arms}


def read_params(path):
    with open(path, encoding="utf-8") as f:
        doc = json.load(f)
    if doc.get("format") != PARAMS_FORMAT:
        raise InputError(f"{path}: format is {doc.get('format')!r}, expected {PARAMS_FORMAT!r}")
    units = doc.get("units", {})
    mm = length_scale(units.get("length", "mm"), path)
    rad = angle_scale(units.get("angle", "rad"), path)
    model = {}
    for name in ("left", "right"):
        arm = doc["arms"][name]
        if len(arm["dh"]) != 7:
            raise InputError(f"{path}: arms.{name}.dh has {len(arm['dh'])} rows, expected 7")
        dh = [(r["a"] * mm, r["d"] * mm, r["theta"] * rad, r["alpha"] * rad) for r in arm["dh"]]
        refl = np.array([[float(x) * mm for x in arm["reflectors"][k]] for k in "abc"])
        model[name] = {"dh": dh, "reflectors_mm": refl}
    base = doc["right_base_in_left"]
    model["base"] = homogeneous(np.array(base["rotation"], dtype=float), np.array(base["translation"]) * mm)
    return model


def nearest_rotation(m):
    u, _, vt = np.linalg.svd(m)
    r = u @ vt
    if np.linalg.det(r) < 0:
        u[:, -1] *= -1
        r = u @ vt
    return r


def homogeneous(r, t):
    h = np.eye(4)
    h[:3, :3] = r
    h[:3, 3] = t
    return h


# ---------------------------------------------------------------------------------------------------------
# Kinematics


def dh_matrix(a, d, theta, alpha):
    ct, st = math.cos(theta), math.sin(theta)
    ca, sa = math.cos(alpha), math.sin(alpha)
    return np.array(
        [
            [ct, -st * ca, st * sa, a * ct],
            [st, ct * ca, -ct * sa, a * st],
            [0.0, sa, ca, d],
            [0.0, 0.0, 0.0, 1.0],
        ]
    )


def flange_pose(dh, q):
    t = np.eye(4)
    for (a, d, theta, alpha), qi in zip(dh, q):
        t = t @ dh_matrix(a, d, qi + theta, alpha)
    return t


def kabsch(model_pts, measured_pts):
    """Proper rotation R minimising sum |measured - (R model + t)|^2."""
    p = model_pts - model_pts.mean(axis=0)
    q = measured_pts - measured_pts.mean(axis=0)
    h = p.T @ q
    u, _, vt = np.linalg.svd(h)
    d = np.sign(np.linalg.det(vt.T @ u.T))
    return vt.T @ np.diag([1.0, 1.0, d]) @ u.T


def arm_arrays(rows, arm_model, world_from_base):
    """Measured points/rotations and model points/rotations (in the `world_from_base` frame)."""
    n = len(rows)
    meas_pts = np.zeros((n, 3, 3))
    meas_rot = np.zeros((n, 3, 3))
    model_pts = np.zeros((n, 3, 3))
    model_rot = np.zeros((n, 3, 3))
    refl_h = np.hstack([arm_model["reflectors_mm"], np.ones((3, 1))])
    for i, row in enumerate(rows):
        pts = np.array(row["points"])
        meas_pts[i] = pts
        meas_rot[i] = kabsch(arm_model["reflectors_mm"], pts)
        pose = world_from_base @ flange_pose(arm_model["dh"], row["q"])
        model_pts[i] = (pose @ refl_h.T).T[:, :3]
        model_rot[i] = pose[:3, :3]
    return meas_pts, meas_rot, model_pts, model_rot


def angle_of(r):
    """Rotation angle of each 3x3 matrix in a stack, from the trace."""
    c = (np.trace(r, axis1=-2, axis2=-1) - 1.0) / 2.0
    return np.arccos(np.clip(c, -1.0, 1.0))


def pair_errors(a, ia, b, ib):
    """Delta d (npairs x 3) and Delta o (npairs) for pairs (a[ia[k]], b[ib[k]])."""
    ma, ra, oa, qa = a
    mb, rb, ob, qb = b
    dm = np.linalg.norm(ma[ia] - mb[ib], axis=-1)
    do = np.linalg.norm(oa[ia] - ob[ib], axis=-1)
    dd = dm - do
    tr = lambda x: np.swapaxes(x, -1, -2)  # noqa: E731
    rel_m = tr(ra[ia]) @ rb[ib]
    rel_o = tr(qa[ia]) @ qb[ib]
    return dd, angle_of(tr(rel_m) @ rel_o)


def stats(dd, do, n_configs):
    n = len(do)
    rms_k = np.sqrt(np.mean(dd**2, axis=0))
    worst = np.max(np.abs(dd), axis=1)
    return {
        "pos_rms_mm": float(np.max(rms_k)),
        "pos_rms_per_reflector_mm": [float(x) for x in rms_k],
        "pos_max_mm": float(np.max(worst)),
        "ori_rms_rad": float(np.sqrt(np.mean(do**2))),
        "ori_max_rad": float(np.max(do)),
        "pos_within_0_3mm_frac": float(np.count_nonzero(worst <= POS_THRESHOLDS_MM[0]) / n),
        "pos_within_0_6mm_frac": float(np.count_nonzero(worst <= POS_THRESHOLDS_MM[1]) / n),
        "ori_within_0_005rad_frac": float(np.count_nonzero(do <= ORI_THRESHOLDS_RAD[0]) / n),
        "ori_within_0_01rad_frac": float(np.count_nonzero(do <= ORI_THRESHOLDS_RAD[1]) / n),
        "n_configs": n_configs,
        "n_pairs": n,
    }


def evaluate(dataset, model, split):
    sel = {}
    for name in ("left", "right"):
        rows = [r for r in dataset["arms"][name] if split == "all" or r["split"] == split]
        if len(rows) < 2:
            raise InputError(f"{name} arm: {len(rows)} configuration(s) in split {split!r}, need at least 2")
        sel[name] = rows
    left = arm_arrays(sel["left"], model["left"], np.eye(4))
    right_own = arm_arrays(sel["right"], model["right"], np.eye(4))
    right_in_left = arm_arrays(sel["right"], model["right"], model["base"])
    out = {}
    for name, arrays in (("left", left), ("right", right_own)):
        n = len(sel[name])
        i, j = np.triu_indices(n, k=1)
        dd, do = pair_errors(arrays, i, arrays, j)
        out[f"relative_{name}"] = stats(dd, do, n)
    nl, nr = len(sel["left"]), len(sel["right"])
    il, ir = np.meshgrid(np.arange(nl), np.arange(nr), indexing="ij")
    dd, do = pair_errors(left, il.ravel(), right_in_left, ir.ravel())
    out["collaborative"] = stats(dd, do, nl + nr)
    return out


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("dataset")
    g = ap.add_mutually_exclusive_group(required=True)
    g.add_argument("--params", help="dualcal-params/1 JSON file")
    g.add_argument("--nominal", action="store_true", help="Table 3 + dataset reflectors + base below")
    ap.add_argument("--base-translation", nargs=3, type=float, metavar=("X", "Y", "Z"))
    ap.add_argument("--base-rotation", nargs=9, type=float, metavar="R")
    ap.add_argument("--split", choices=["cal", "ver", "all"], default="all")
    args = ap.parse_args(argv)
    try:
        dataset = read_dataset(args.dataset)
        if args.params:
            model = read_params(args.params)
        else:
            rot = np.array(args.base_rotation or sum(NOMINAL_BASE_ROTATION, []), dtype=float).reshape(3, 3)
            trans = np.array(args.base_translation or NOMINAL_BASE_TRANSLATION_MM, dtype=float)
            arm = {"dh": TABLE3, "reflectors_mm": dataset["reflectors_mm"]}
            model = {"left": arm, "right": arm, "base": homogeneous(nearest_rotation(rot), trans)}
        report = evaluate(dataset, model, args.split)
    except (InputError, OSError, KeyError, ValueError, TypeError, tomllib.TOMLDecodeError) as e:
        sys.stderr.write(f"metrics_reference.py: {type(e).__name__}: {e}\n")
        return 2
    json.dump(report, sys.stdout, indent=2)
    sys.stdout.write("\n")
    return 0


if __name__ == "__main__":
    sys.exit(main())
