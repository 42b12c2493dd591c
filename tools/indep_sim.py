#!/usr/bin/env python3
"""An independent simulator of a laser-tracker calibration, written apart from dualcal's models (issue 44).

The true robot is the URDF itself with errors drawn into it — all six components of every joint
origin on both arm chains (the flange's fixed joint included), a zero offset per joint (folded into
its origin, a rotation about the joint's axis) — the reflectors shifted by up to ±0.5 mm per axis on
each hand, and the tracker station drawn around the nominal one (its position within ±`--station-mm`
per axis, its frame turned at random). Its forward kinematics is tools/urdf_fk.py's (its own XML
reading and transforms, numpy); nothing of dualcal computes the measured points.

The tracker's noise depends on the distance L (m) to the point: along the line of sight σ = half the
MPE (`mpe_um + mpe_um_per_m · L`, µm), across it σ = half of `mpe_um + 2.5 · mpe_um_per_m · L` (the
angle encoders' share grows with the distance), per axis.

    indep_sim.py measure --urdf ROBOT.urdf --configs PLANDIR --seed S --tracker X,Y,Z --out DIR
                         [--nver 100] [--left BASE:TIP --right BASE:TIP] [--builtin]

PLANDIR holds `left.csv` and `right.csv` as `dualcal plan` writes them (`id,q1..qN,split`, degrees):
planned, or random (`dualcal plan --candidates N --n N`: the first N collision-free, tracker-facing
draws). Writes DIR/data (the calibration rows and `--nver` verification rows per arm, random
configurations within 80 % of the joint limits; the dataset `dualcal calibrate` reads; the robot the
built-in IRB 14000 with `--builtin`, else the URDF) and DIR/truth (the same measurements with the true
robot's URDF and reflectors: `dualcal evaluate DIR/truth --nominal --split ver` gives the noise floor).
The same seed draws the same true robot, station, noise and verification configurations whatever the
configurations are, so planned and random sets are measured on equal terms.

    indep_sim.py ratio --bin DUALCAL DIR [--method NAME]

calibrates DIR/data (`dualcal calibrate`), evaluates the result and the truth on the verification
split, prints the mean of both arms' relative positioning RMS over the truth's (1.00 = the noise floor).
"""

import argparse
import json
import math
import os
import subprocess
import sys
import tempfile
import xml.etree.ElementTree as ET

import numpy as np

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import urdf_fk  # noqa: E402  (the project's independent forward kinematics)

MOVING = ("revolute", "continuous", "prismatic")
REFLECTORS_MM = {"a": (45.0, 0.0, 40.0), "b": (-25.0, 40.0, 40.0), "c": (-25.0, -40.0, 40.0)}
# The true robot's errors (1σ): joint-origin translation per axis, rotation per axis, zero offset.
ORIGIN_MM, ORIGIN_RAD, ZERO_RAD, REFLECTOR_MM = 0.3, 0.001, 0.001, 0.5


def rpy_of(r):
    """URDF rpy of a rotation matrix (R = Rz(y) Ry(p) Rx(r))."""
    pitch = math.asin(max(-1.0, min(1.0, -r[2, 0])))
    if abs(math.cos(pitch)) < 1e-9:
        return [math.atan2(-r[1, 2], r[1, 1]), pitch, 0.0]
    return [math.atan2(r[2, 1], r[2, 2]), pitch, math.atan2(r[1, 0], r[0, 0])]


def chain_of(robot, base, tip):
    by_child = {j.find("child").get("link"): j for j in robot.findall("joint")}
    out, link = [], tip
    while link != base:
        j = by_child[link]
        if j.find("mimic") is not None:
            raise SystemExit("indep_sim.py: mimic joints are not simulated (%s)" % j.get("name"))
        out.append(j)
        link = j.find("parent").get("link")
    return list(reversed(out))


def axis_of(j):
    a = j.find("axis")
    k = np.array(urdf_fk.floats(a.get("xyz") if a is not None else None, (1, 0, 0)), dtype=float)
    return k / np.linalg.norm(k)


def perturb(robot, chains, rng):
    """Draw the errors into the joints of `chains` (each joint once)."""
    seen = set()
    for chain in chains:
        for j in chain:
            if j.get("name") in seen:
                continue
            seen.add(j.get("name"))
            t = urdf_fk.origin_of(j)
            dr = urdf_fk.axis_angle(rng.normal(size=3), ORIGIN_RAD * np.linalg.norm(rng.normal(size=3)))
            r = t[:3, :3] @ dr
            if j.get("type") == "revolute" or j.get("type") == "continuous":
                r = r @ urdf_fk.axis_angle(axis_of(j), rng.normal(0.0, ZERO_RAD))
            xyz = (t[:3, 3] + rng.normal(0.0, ORIGIN_MM, 3)) / 1000.0
            o = j.find("origin")
            if o is None:
                o = ET.SubElement(j, "origin")
            o.set("xyz", " ".join(repr(float(v)) for v in xyz))
            o.set("rpy", " ".join(repr(float(v)) for v in rpy_of(r)))


def fk(chain, q):
    t = np.eye(4)
    i = 0
    for j in chain:
        t = t @ urdf_fk.origin_of(j)
        if j.get("type") in MOVING:
            if j.get("type") == "prismatic":
                t = t @ urdf_fk.homogeneous(np.eye(3), q[i] * axis_of(j))
            else:
                t = t @ urdf_fk.homogeneous(urdf_fk.axis_angle(axis_of(j), q[i]), (0, 0, 0))
            i += 1
    return t


def limits(chain):
    out = []
    for j in chain:
        if j.get("type") not in MOVING:
            continue
        lim = j.find("limit")
        if j.get("type") == "continuous" or lim is None:
            out.append((-math.pi, math.pi))
        else:
            out.append((float(lim.get("lower")), float(lim.get("upper"))))
    return out


def read_configs(path, chain):
    """A `dualcal plan` CSV: ids and joint values (degrees; mm for a prismatic joint) -> rad / mm."""
    kinds = [j.get("type") for j in chain if j.get("type") in MOVING]
    rows = []
    with open(path) as f:
        header = None
        for line in f:
            line = line.strip()
            if not line or line.startswith("#"):
                continue
            cells = [c.strip() for c in line.split(",")]
            if header is None:
                header = cells
                continue
            qs = [float(c) for c in cells[1 : 1 + len(kinds)]]
            q = [v if k == "prismatic" else math.radians(v) for v, k in zip(qs, kinds)]
            rows.append((cells[0], q))
    return rows


def random_station(rng, tracker_mm, station_mm):
    """tracker_from_root: the station drawn around `tracker_mm`, its frame turned at random."""
    r = urdf_fk.axis_angle(rng.normal(size=3), rng.uniform(0.0, math.pi))
    at = np.asarray(tracker_mm, dtype=float) + rng.uniform(-station_mm, station_mm, 3)
    root_from_tracker = urdf_fk.homogeneous(r, at)
    return np.linalg.inv(root_from_tracker)


def noisy(p_tracker, rng, mpe_um, mpe_um_per_m):
    l_m = np.linalg.norm(p_tracker) / 1000.0
    u = p_tracker / np.linalg.norm(p_tracker)
    radial = 0.5e-3 * (mpe_um + mpe_um_per_m * l_m)
    across = 0.5e-3 * (mpe_um + 2.5 * mpe_um_per_m * l_m)
    n = rng.normal(size=3)
    along = np.dot(n, u) * u
    return p_tracker + radial * along + across * (n - along)


def write_dataset(out, csvs, robot_key, arms_extra, reflectors):
    os.makedirs(out, exist_ok=True)
    lines = ['format = "dualcal-dataset/1"']
    if robot_key:
        lines.append('robot = "%s"' % robot_key)
    lines += ['description = "indep_sim.py"', "", "[units]", 'length = "mm"', 'angle = "rad"', ""]
    lines += ["[tracker]", "mpe_um = 16.0", "mpe_um_per_m = 0.8", "", "[reflectors]"]
    lines += ["%s = [%r, %r, %r]" % (k, *v) for k, v in reflectors.items()]
    for side in ("left", "right"):
        lines += ["", "[[arms]]", 'name = "%s"' % side, 'file = "%s.csv"' % side]
        lines += arms_extra.get(side, [])
        with open(os.path.join(out, side + ".csv"), "w") as f:
            f.write(csvs[side])
    with open(os.path.join(out, "dataset.toml"), "w") as f:
        f.write("\n".join(lines) + "\n")


def measure(a):
    rng = np.random.default_rng(a.seed)
    nominal_tree = ET.parse(a.urdf)
    truth_tree = ET.parse(a.urdf)
    links = {"left": a.left.split(":"), "right": a.right.split(":")}
    nominal = {s: chain_of(nominal_tree.getroot(), *links[s]) for s in links}
    truth = {s: chain_of(truth_tree.getroot(), *links[s]) for s in links}
    perturb(truth_tree.getroot(), [truth["left"], truth["right"]], rng)
    refl = {s: {k: np.array(v) + rng.uniform(-REFLECTOR_MM, REFLECTOR_MM, 3) for k, v in REFLECTORS_MM.items()} for s in links}
    tracker_from_root = random_station(rng, [float(v) for v in a.tracker.split(",")], a.station_mm)
    ver = {}
    for s in ("left", "right"):
        lim = limits(nominal[s])
        ver[s] = [
            ("V%03d" % (i + 1), [0.5 * (lo + hi) + 0.8 * 0.5 * (hi - lo) * rng.uniform(-1, 1) for lo, hi in lim])
            for i in range(a.nver)
        ]
    noise_rng = np.random.default_rng(a.seed + 7_000_000)
    csvs = {}
    for s in ("left", "right"):
        cal = read_configs(os.path.join(a.configs, s + ".csv"), nominal[s])
        n_q = len(limits(nominal[s]))
        head = "id," + ",".join("q%d" % (i + 1) for i in range(n_q))
        head += "," + ",".join(k + c for k in REFLECTORS_MM for c in "xyz") + ",split\n"
        body = []
        for rows, split in ((cal, "cal"), (ver[s], "ver")):
            for ident, q in rows:
                t = tracker_from_root @ fk(truth[s], q)
                pts = []
                for k in REFLECTORS_MM:
                    p = (t @ np.append(refl[s][k], 1.0))[:3]
                    pts += list(p if a.noise_scale == 0 else noisy(p, noise_rng, 16.0 * a.noise_scale, 0.8 * a.noise_scale))
                body.append(",".join([ident] + ["%.9f" % v for v in q] + ["%.6f" % v for v in pts] + [split]))
        csvs[s] = head + "\n".join(body) + "\n"
    extra = {s: ['base_link = "%s"' % links[s][0], 'tip_link = "%s"' % links[s][1]] for s in links}
    robot = None if a.builtin else os.path.abspath(a.urdf)
    write_dataset(os.path.join(a.out, "data"), csvs, robot, {} if a.builtin else extra, REFLECTORS_MM)
    os.makedirs(os.path.join(a.out, "truth"), exist_ok=True)
    truth_tree.write(os.path.join(a.out, "truth", "truth.urdf"))
    for s in links:
        extra[s].append("reflectors = { %s }" % ", ".join("%s = [%r, %r, %r]" % (k, *map(float, v)) for k, v in refl[s].items()))
    write_dataset(os.path.join(a.out, "truth"), csvs, "truth.urdf", extra, REFLECTORS_MM)


def relative_rms(bin_, dataset, model_args):
    out = subprocess.run([bin_, "evaluate", dataset, "--split", "ver", "--json"] + model_args, check=True, capture_output=True, text=True).stdout
    r = json.loads(out)
    return 0.5 * (r["relative_left"]["pos_rms_mm"] + r["relative_right"]["pos_rms_mm"])


def ratio(bin_, sim_dir, method=None):
    """The calibrated model's verification RMS over the true robot's (both arms' mean)."""
    with tempfile.TemporaryDirectory() as tmp:
        params = os.path.join(tmp, "p.json")
        cmd = [bin_, "calibrate", os.path.join(sim_dir, "data"), "--out", params, "--quiet"]
        if method:
            cmd += ["--method", method]
        subprocess.run(cmd, check=True, capture_output=True, text=True)
        calibrated = relative_rms(bin_, os.path.join(sim_dir, "data"), ["--params", params])
    floor = relative_rms(bin_, os.path.join(sim_dir, "truth"), ["--nominal"])
    return calibrated / floor


def main(argv):
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    sub = ap.add_subparsers(dest="cmd", required=True)
    m = sub.add_parser("measure")
    m.add_argument("--urdf", required=True)
    m.add_argument("--configs", required=True)
    m.add_argument("--seed", type=int, required=True)
    m.add_argument("--tracker", default="2000,0,500")
    m.add_argument("--station-mm", type=float, default=250.0)
    m.add_argument("--nver", type=int, default=100)
    m.add_argument("--noise-scale", type=float, default=1.0, help="0: no noise (checks the models agree)")
    m.add_argument("--left", default="yumi_body:yumi_flange_l")
    m.add_argument("--right", default="yumi_body:yumi_flange_r")
    m.add_argument("--builtin", action="store_true", help="the data's robot is the built-in IRB 14000")
    m.add_argument("--out", required=True)
    r = sub.add_parser("ratio")
    r.add_argument("--bin", required=True)
    r.add_argument("--method")
    r.add_argument("dir")
    a = ap.parse_args(argv[1:])
    if a.cmd == "measure":
        measure(a)
    else:
        print("%.4f" % ratio(a.bin, a.dir, a.method))
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv))
