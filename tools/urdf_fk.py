#!/usr/bin/env python3
"""Independent forward kinematics of a URDF file, for checking dualcal's calibrated URDF export.

Shares no code with the Rust crate: its own XML reading (the standard library's ElementTree), its own
joint transforms (4x4 homogeneous matrices from xyz/rpy and axis-angle rotations, numpy). For every
configuration of the input it prints the pose of the chain's tip and the positions of named links, all
in the chain's base link frame, in millimetres:

    urdf_fk.py ROBOT.urdf BASE TIP CONFIGS.json [LINK ...]

CONFIGS.json is a list of joint-value lists in the chain order of the movable joints from BASE to TIP
that have their own value (URDF units: radians, metres for a prismatic joint); a joint with a
<mimic joint multiplier offset> gets multiplier * leader + offset instead, and a leader off the chain
(a column's virtual joint on a side branch) takes a value of its own where its first follower stands.
Each LINK is a link fixed below TIP (through fixed joints). Prints JSON:

    {"joints": [names...], "configs": [{"tip": [[4x4]], "links": {"name": [x, y, z]}}, ...]}
"""

import json
import math
import sys
import xml.etree.ElementTree as ET

try:
    import numpy as np
except ImportError:  # pragma: no cover - reported to the caller
    sys.stderr.write("urdf_fk.py: numpy is required (pip install numpy / apt install python3-numpy)\n")
    sys.exit(3)


def floats(text, default):
    if text is None:
        return list(default)
    return [float(v) for v in text.split()]


def rot_x(a):
    c, s = math.cos(a), math.sin(a)
    return np.array([[1, 0, 0], [0, c, -s], [0, s, c]], dtype=float)


def rot_y(a):
    c, s = math.cos(a), math.sin(a)
    return np.array([[c, 0, s], [0, 1, 0], [-s, 0, c]], dtype=float)


def rot_z(a):
    c, s = math.cos(a), math.sin(a)
    return np.array([[c, -s, 0], [s, c, 0], [0, 0, 1]], dtype=float)


def axis_angle(axis, angle):
    """Rodrigues' formula."""
    k = np.asarray(axis, dtype=float)
    k = k / np.linalg.norm(k)
    kx = np.array([[0, -k[2], k[1]], [k[2], 0, -k[0]], [-k[1], k[0], 0]])
    return np.eye(3) + math.sin(angle) * kx + (1 - math.cos(angle)) * kx @ kx


def homogeneous(r, t):
    m = np.eye(4)
    m[:3, :3] = r
    m[:3, 3] = t
    return m


def origin_of(joint):
    o = joint.find("origin")
    xyz = floats(o.get("xyz") if o is not None else None, (0, 0, 0))
    rpy = floats(o.get("rpy") if o is not None else None, (0, 0, 0))
    # URDF: R = Rz(yaw) Ry(pitch) Rx(roll); metres -> millimetres.
    r = rot_z(rpy[2]) @ rot_y(rpy[1]) @ rot_x(rpy[0])
    return homogeneous(r, [1000.0 * v for v in xyz])


def main(argv):
    if len(argv) < 5:
        sys.stderr.write(__doc__)
        return 2
    robot = ET.parse(argv[1]).getroot()
    base, tip = argv[2], argv[3]
    with open(argv[4]) as f:
        configs = json.load(f)
    links = argv[5:]
    by_child = {}
    for j in robot.findall("joint"):
        by_child[j.find("child").get("link")] = j

    def path(from_link, to_link):
        out = []
        link = to_link
        while link != from_link:
            j = by_child[link]
            out.append(j)
            link = j.find("parent").get("link")
        return list(reversed(out))

    chain = path(base, tip)
    moving = ("revolute", "continuous", "prismatic")
    by_name = {j.get("name"): j for j in robot.findall("joint")}
    def root(name, depth=0):
        m = by_name[name].find("mimic")
        if m is None or depth > len(by_name):
            return name
        return root(m.get("joint"), depth + 1)

    # The joints with their own value, in chain order; a leader off the chain that a chain joint
    # mimics stands where its first follower stands.
    on_chain = {j.get("name") for j in chain}
    movable = []
    for j in chain:
        if j.get("type") not in moving:
            continue
        name = root(j.get("name"))
        if (name == j.get("name") or name not in on_chain) and name not in movable:
            movable.append(name)
    out = {"joints": movable, "configs": []}

    def value(values, name, depth=0):
        if name in values:
            return values[name]
        m = by_name[name].find("mimic")
        if m is None or depth > len(by_name):
            raise SystemExit("urdf_fk.py: joint %s has no value" % name)
        leader = value(values, m.get("joint"), depth + 1)
        return float(m.get("multiplier", "1")) * leader + float(m.get("offset", "0"))

    for q in configs:
        values = dict(zip(movable, q))
        t = np.eye(4)
        for j in chain:
            t = t @ origin_of(j)
            if j.get("type") in moving:
                axis = floats(j.find("axis").get("xyz") if j.find("axis") is not None else None, (1, 0, 0))
                v = value(values, j.get("name"))
                if j.get("type") == "prismatic":
                    k = np.asarray(axis, dtype=float)
                    t = t @ homogeneous(np.eye(3), 1000.0 * v * k / np.linalg.norm(k))
                else:
                    t = t @ homogeneous(axis_angle(axis, v), (0, 0, 0))
        entry = {"tip": t.tolist(), "links": {}}
        for name in links:
            u = t.copy()
            for j in path(tip, name):
                u = u @ origin_of(j)
            entry["links"][name] = u[:3, 3].tolist()
        out["configs"].append(entry)
    json.dump(out, sys.stdout)
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv))
