#!/usr/bin/env python3
"""A real-like, ill-conditioned one-arm dataset, simulated apart from dualcal's model: a 6-joint
UR-like industrial arm (this script's own URDF), its joint origins perturbed in the URDF itself
(xyz ±0.3 mm, rpy ±2 mrad σ), one reflector near the flange, forward kinematics by tools/urdf_fk.py
(its own XML reading and transforms, no dualcal code), configurations whose flange orientation varies
by at most ~10° (the three parallel pitch joints moved together, base and wrist nearly still), and
0.04 mm of tracker noise per axis: what a Leica-measured industrial arm looks like (issue 47).

    tools/ill_conditioned_data.py OUT_DIR [--seed N] [--cal 150] [--ver 60] [--spread-deg 4]

Writes OUT_DIR/robot.urdf (nominal), OUT_DIR/truth.urdf, OUT_DIR/dataset.toml, OUT_DIR/left.csv;
prints the flange's largest orientation change across the configurations. `--harmonic-mrad A` adds
errors no geometric model explains (each joint turns a little more or less as it rotates).
"""

import argparse
import json
import math
import os
import subprocess
import sys
import tempfile

import numpy as np

HERE = os.path.dirname(os.path.abspath(__file__))

# (name, parent, child, xyz m, rpy rad, axis) of a UR5-like arm on a 0.5 m stand.
JOINTS = [
    ("shoulder_pan", "base_link", "shoulder_link", (0, 0, 0.089159), (0, 0, 0), (0, 0, 1)),
    ("shoulder_lift", "shoulder_link", "upper_arm_link", (0, 0.13585, 0), (0, math.pi / 2, 0), (0, 1, 0)),
    ("elbow", "upper_arm_link", "forearm_link", (0, -0.1197, 0.425), (0, 0, 0), (0, 1, 0)),
    ("wrist_1", "forearm_link", "wrist_1_link", (0, 0, 0.39225), (0, math.pi / 2, 0), (0, 1, 0)),
    ("wrist_2", "wrist_1_link", "wrist_2_link", (0, 0.093, 0), (0, 0, 0), (0, 0, 1)),
    ("wrist_3", "wrist_2_link", "wrist_3_link", (0, 0, 0.09465), (0, 0, 0), (0, 1, 0)),
]
FLANGE = ("flange", "wrist_3_link", "tool0", (0, 0.0823, 0), (-math.pi / 2, 0, 0))


def urdf(joints):
    links = {"world", "base_link"} | {j[1] for j in joints} | {j[2] for j in joints} | {"tool0"}
    out = ['<?xml version="1.0"?>', '<robot name="industrial_6r">']
    out += [f'  <link name="{l}"/>' for l in sorted(links)]
    out.append('  <joint name="stand" type="fixed"><parent link="world"/><child link="base_link"/>'
               '<origin xyz="0 0 0.5" rpy="0 0 0"/></joint>')
    for name, parent, child, xyz, rpy, axis in joints:
        out.append(
            f'  <joint name="{name}" type="revolute"><parent link="{parent}"/><child link="{child}"/>'
            f'<origin xyz="{xyz[0]:.9f} {xyz[1]:.9f} {xyz[2]:.9f}" rpy="{rpy[0]:.9f} {rpy[1]:.9f} {rpy[2]:.9f}"/>'
            f'<axis xyz="{axis[0]} {axis[1]} {axis[2]}"/>'
            '<limit lower="-6.2832" upper="6.2832" effort="150" velocity="3.15"/></joint>'
        )
    name, parent, child, xyz, rpy = FLANGE
    out.append(f'  <joint name="{name}" type="fixed"><parent link="{parent}"/><child link="{child}"/>'
               f'<origin xyz="{xyz[0]} {xyz[1]} {xyz[2]}" rpy="{rpy[0]} {rpy[1]} {rpy[2]}"/></joint>')
    out.append("</robot>")
    return "\n".join(out) + "\n"


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("out")
    ap.add_argument("--seed", type=int, default=1)
    ap.add_argument("--cal", type=int, default=150)
    ap.add_argument("--ver", type=int, default=60)
    ap.add_argument("--harmonic-mrad", type=float, default=0.0,
                    help="unmodelled joint errors: each joint turns A·sin(q + φ) + A/2·sin(2q + ψ) further, mrad")
    ap.add_argument("--spread-deg", type=float, default=4.0,
                    help="half-range of the base, wrist and pitch-sum joints' motion, deg")
    a = ap.parse_args()
    rng = np.random.default_rng(a.seed)
    os.makedirs(a.out, exist_ok=True)
    truth = []
    for name, parent, child, xyz, rpy, axis in JOINTS:
        dx = rng.normal(0, 0.0003, 3)
        dr = rng.normal(0, 0.002, 3)
        truth.append((name, parent, child, tuple(np.add(xyz, dx)), tuple(np.add(rpy, dr)), axis))
    with open(os.path.join(a.out, "robot.urdf"), "w") as f:
        f.write(urdf(JOINTS))
    with open(os.path.join(a.out, "truth.urdf"), "w") as f:
        f.write(urdf(truth))
    d, s = math.radians(1), a.spread_deg
    n = a.cal + a.ver
    configs = []
    for _ in range(n):
        q2 = rng.uniform(-100, -40) * d
        q3 = rng.uniform(40, 110) * d
        configs.append([
            rng.uniform(-s, s) * d, q2, q3,
            -(q2 + q3) - 90 * d + rng.uniform(-s / 2, s / 2) * d,
            90 * d + rng.uniform(-s / 2, s / 2) * d,
            rng.uniform(-s / 2, s / 2) * d,
        ])
    phases = rng.uniform(0, 2 * math.pi, (6, 2))
    amp = a.harmonic_mrad * 1e-3
    true_q = [[v + amp * math.sin(v + phases[j][0]) + amp / 2 * math.sin(2 * v + phases[j][1])
               for j, v in enumerate(q)] for q in configs]
    with tempfile.NamedTemporaryFile("w", suffix=".json", delete=False) as f:
        json.dump(true_q, f)
        path = f.name
    fk = json.loads(subprocess.run(
        [sys.executable, os.path.join(HERE, "urdf_fk.py"), os.path.join(a.out, "truth.urdf"),
         "base_link", "tool0", path], check=True, capture_output=True, text=True).stdout)
    os.unlink(path)
    reflector_nominal = np.array([0.0, 0.0, 40.0])
    reflector_true = reflector_nominal + rng.normal(0, 0.5, 3)
    rows, r0, spread = [], None, 0.0
    for i, (q, c) in enumerate(zip(configs, fk["configs"])):
        t = np.array(c["tip"])
        r = t[:3, :3]
        if r0 is None:
            r0 = r
        cos = (np.trace(r0.T @ r) - 1) / 2
        spread = max(spread, math.degrees(math.acos(max(-1.0, min(1.0, cos)))))
        p = t[:3, :3] @ reflector_true + t[:3, 3] + rng.normal(0, 0.04, 3)
        split = "cal" if i < a.cal else "ver"
        rows.append([f"P{i + 1:03d}"] + [f"{math.degrees(v):.9f}" for v in q]
                    + [f"{v:.6f}" for v in p] + [split])
    with open(os.path.join(a.out, "left.csv"), "w") as f:
        f.write("id,q1,q2,q3,q4,q5,q6,ax,ay,az,split\n")
        for row in rows:
            f.write(",".join(row) + "\n")
    with open(os.path.join(a.out, "dataset.toml"), "w") as f:
        f.write('format = "dualcal-dataset/1"\nrobot = "robot.urdf"\n\n[units]\nlength = "mm"\n'
                'angle = "deg"\n\n[tracker]\nmpe_um = 15.0\nmpe_um_per_m = 6.0\n\n[reflectors]\n'
                'a = [0.0, 0.0, 40.0]\n\n[[arms]]\nname = "left"\nfile = "left.csv"\n'
                'base_link = "base_link"\ntip_link = "tool0"\n')
    print(f"flange orientation spread {spread:.1f} deg over {n} configurations; true reflector "
          f"{reflector_true.round(3).tolist()} mm (nominal {reflector_nominal.tolist()})")


if __name__ == "__main__":
    main()
