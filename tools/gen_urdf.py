#!/usr/bin/env python3
"""Generate assets/irb14000.urdf: dualcal's own description of the ABB IRB 14000 (YuMi).

Written from public facts only (no meshes): the nominal DH table of the paper's Table 3, the public
YuMi joint-1 placement on the body, the joint limits, and primitive geometry (boxes, cylinders,
spheres) of roughly YuMi size for drawing and collision checks.

Frame conventions (mirrored by src/robot.rs):
  * DH: T_i = Rz(q_i + theta_i) Tz(d_i) Tx(a_i) Rx(alpha_i), chain order = ABB axes 1, 2, 7, 3, 4, 5, 6.
  * DH base frame (frame 0) = body_from_joint1_origin * Tz(-66 mm) * Rz(pi).
  * link_1 = joint-1 frame rotated by q1; the chain-position-2 joint origin in link_1 is
    Rz(pi + theta_1) Tz(d_1 - 66) Tx(a_1) Rx(alpha_1).
  * link_i (i >= 2) = DH frame i-1 rotated by q_i; the joint at chain position i+1 has origin
    Rz(theta_i) Tz(d_i) Tx(a_i) Rx(alpha_i) in link_i; the fixed flange joint in link_7 is row 7.
  * URDF rpy: R = Rz(yaw) Ry(pitch) Rx(roll). Lengths in metres in the file.

Usage: python3 tools/gen_urdf.py > assets/irb14000.urdf   (python3 standard library only)
"""

import math
import sys

PI = math.pi
HALF_PI = math.pi / 2.0

# Nominal DH table (paper Table 3), chain order; (a_mm, d_mm, theta_rad, alpha_rad).
# Must equal IRB14000_NOMINAL_DH in src/kinematics.rs (tests/urdf_model.rs checks the FK).
DH = [
    (-30.0, 166.0, 0.0, -HALF_PI),
    (30.0, 0.0, 0.0, HALF_PI),
    (40.5, 251.5, 0.0, -HALF_PI),
    (40.5, 0.0, -HALF_PI, -HALF_PI),
    (-27.0, 265.0, 0.0, HALF_PI),
    (27.0, 0.0, 0.0, -HALF_PI),
    (0.0, 36.0, 0.0, 0.0),
]

# DH frame 0 lies on the joint-1 axis this far below link_1's origin.
DH_BASE_BELOW_LINK1_MM = 66.0

# Public YuMi layout: joint-1 origin in the body frame (m, rad).
JOINT1 = {
    "l": ((0.05355, 0.07250, 0.41492), (0.9781, -0.5716, 2.3180)),
    "r": ((0.05355, -0.0725, 0.41492), (-0.9795, -0.5682, -2.3155)),
}

# Chain order of the joint names: chain position 3 is ABB axis 7.
JOINT_NUMBERS = [1, 2, 7, 3, 4, 5, 6]
LIMITS_DEG = [
    (-168.5, 168.5),
    (-143.5, 43.5),
    (-168.5, 168.5),
    (-123.5, 80.0),
    (-290.0, 290.0),
    (-88.0, 138.0),
    (-229.0, 229.0),
]
# Maximum axis speeds (deg/s, ABB data sheet) and a nominal effort (N m) for completeness.
VELOCITY_DEG_S = [180.0, 180.0, 180.0, 180.0, 400.0, 400.0, 400.0]
EFFORT_NM = 30.0

MATERIALS = {
    "dualcal_body_white": (0.92, 0.92, 0.90, 1.0),
    "dualcal_shell_grey": (0.78, 0.79, 0.80, 1.0),
    "dualcal_joint_dark": (0.30, 0.32, 0.35, 1.0),
    "dualcal_flange_metal": (0.62, 0.63, 0.66, 1.0),
    "dualcal_base_dark": (0.22, 0.23, 0.25, 1.0),
}


# ---------------------------------------------------------------- small rigid-transform algebra
def mat_mul(a, b):
    return [[sum(a[i][k] * b[k][j] for k in range(3)) for j in range(3)] for i in range(3)]


def mat_vec(a, v):
    return [sum(a[i][k] * v[k] for k in range(3)) for i in range(3)]


def rot_x(t):
    c, s = math.cos(t), math.sin(t)
    return [[1.0, 0.0, 0.0], [0.0, c, -s], [0.0, s, c]]


def rot_y(t):
    c, s = math.cos(t), math.sin(t)
    return [[c, 0.0, s], [0.0, 1.0, 0.0], [-s, 0.0, c]]


def rot_z(t):
    c, s = math.cos(t), math.sin(t)
    return [[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]]


def identity():
    return [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]]


def transpose(a):
    return [[a[j][i] for j in range(3)] for i in range(3)]


def rpy_from_matrix(r):
    """(roll, pitch, yaw) with R = Rz(yaw) Ry(pitch) Rx(roll).

    Yaw and pitch come from the first column; roll is then read off Ry(p)^T Rz(y)^T R, which stays
    accurate near gimbal lock (any error in yaw is absorbed by roll)."""
    yaw = math.atan2(r[1][0], r[0][0]) if abs(r[1][0]) + abs(r[0][0]) > 1e-300 else 0.0
    pitch = math.atan2(-r[2][0], math.hypot(r[0][0], r[1][0]))
    m = mat_mul(transpose(mat_mul(rot_z(yaw), rot_y(pitch))), r)
    roll = math.atan2(m[2][1] - m[1][2], m[1][1] + m[2][2])
    return (roll, pitch, yaw)


def dh_origin(a_mm, d_mm, phi_rad, alpha_rad):
    """Rz(phi) Tz(d) Tx(a) Rx(alpha) as (rotation, translation_mm)."""
    r = mat_mul(rot_z(phi_rad), rot_x(alpha_rad))
    t = [a_mm * math.cos(phi_rad), a_mm * math.sin(phi_rad), d_mm]
    return r, t


def clean(v):
    """Exact zeros instead of round-off residues such as 1.8e-15 (far below any tolerance)."""
    return 0.0 if abs(v) < 1e-14 else v


def fmt(v):
    return repr(clean(v)) if clean(v) != 0.0 else "0"


def fmt3(vs):
    return " ".join(fmt(v) for v in vs)


# ---------------------------------------------------------------- geometry helpers (mm in, m out)
def rotation_z_to(u):
    """A rotation whose z axis is the unit vector u."""
    ux, uy, uz = u
    # pick a helper axis not parallel to u
    h = [1.0, 0.0, 0.0] if abs(ux) < 0.9 else [0.0, 1.0, 0.0]
    x = [h[1] * uz - h[2] * uy, h[2] * ux - h[0] * uz, h[0] * uy - h[1] * ux]
    n = math.sqrt(sum(c * c for c in x))
    x = [c / n for c in x]
    y = [uy * x[2] - uz * x[1], uz * x[0] - ux * x[2], ux * x[1] - uy * x[0]]
    return [[x[0], y[0], ux], [x[1], y[1], uy], [x[2], y[2], uz]]


def cylinder_between(p0, p1, radius_mm, material):
    d = [p1[i] - p0[i] for i in range(3)]
    length = math.sqrt(sum(c * c for c in d))
    u = [c / length for c in d]
    centre = [(p0[i] + p1[i]) / 2.0 for i in range(3)]
    return {
        "kind": "cylinder",
        "radius": radius_mm,
        "length": length,
        "xyz": centre,
        "rot": rotation_z_to(u),
        "material": material,
    }


def hub(centre, axis, radius_mm, length_mm, material):
    return {
        "kind": "cylinder",
        "radius": radius_mm,
        "length": length_mm,
        "xyz": list(centre),
        "rot": rotation_z_to(axis),
        "material": material,
    }


def box(centre, size_mm, material):
    return {"kind": "box", "size": size_mm, "xyz": list(centre), "rot": identity(), "material": material}


def sphere(centre, radius_mm, material):
    return {"kind": "sphere", "radius": radius_mm, "xyz": list(centre), "rot": identity(), "material": material}


def geometry_xml(shape):
    k = shape["kind"]
    if k == "cylinder":
        return f'<cylinder radius="{fmt(shape["radius"] / 1000)}" length="{fmt(shape["length"] / 1000)}"/>'
    if k == "box":
        return f'<box size="{fmt3([s / 1000 for s in shape["size"]])}"/>'
    return f'<sphere radius="{fmt(shape["radius"] / 1000)}"/>'


def shape_xml(shape, indent):
    origin = (
        f'<origin xyz="{fmt3([c / 1000 for c in shape["xyz"]])}" '
        f'rpy="{fmt3(rpy_from_matrix(shape["rot"]))}"/>'
    )
    g = geometry_xml(shape)
    pad = " " * indent
    visual = (
        f"{pad}<visual>\n{pad}  {origin}\n{pad}  <geometry>{g}</geometry>\n"
        f'{pad}  <material name="{shape["material"]}"/>\n{pad}</visual>\n'
    )
    if shape.get("visual_only"):
        return visual
    return visual + f"{pad}<collision>\n{pad}  {origin}\n{pad}  <geometry>{g}</geometry>\n{pad}</collision>\n"


# ---------------------------------------------------------------- the robot
# The offset links (2, 4, 6) carry the motor housings ("hubs") of both of their joints; the long
# links (1, 3, 5) are tubes between the housings, and link 7 is the wrist with the flange. A hub is
# coaxial with its joint, so it looks the same whichever side of the joint owns it; giving both hubs
# of a short offset to one link keeps links i and i+2 apart except when the arm really folds.
# Sizes in mm: about 90 mm across at the shoulder, 50 mm at the wrist.
HUB = {2: (42.0, 84.0), 3: (38.0, 76.0), 4: (35.0, 70.0), 5: (32.0, 64.0), 6: (29.0, 58.0)}  # joint: (r, len)
TUBE_R = {1: 44.0, 3: 35.0, 5: 30.0}
OFFSET_R = {2: 36.0, 4: 31.0, 6: 26.0}
WRIST_R = 23.0
WRIST_BACK = 8.0
FLANGE_R = 18.0
TUBE_END_GAP = {1: 0.0, 3: 0.0, 5: 24.0}
NECK_R = 17.0
FLANGE_THICKNESS = 6.0


def arm_origins():
    """Origin of the joint following each link, in that link's frame: list of (rotation, t_mm)."""
    out = []
    for i, (a, d, theta, alpha) in enumerate(DH):
        if i == 0:
            out.append(dh_origin(a, d - DH_BASE_BELOW_LINK1_MM, PI + theta, alpha))
        else:
            out.append(dh_origin(a, d, theta, alpha))
    return out


def link_shapes(k, origin):
    """Primitive shapes of link k (1-based chain position) in its own frame, mm.

    Link k's frame has its z axis on joint k; `origin` places joint k+1 (or the flange)."""
    rot, t = origin
    next_axis = mat_vec(rot, [0.0, 0.0, 1.0])
    shell, dark, metal = "dualcal_shell_grey", "dualcal_joint_dark", "dualcal_flange_metal"
    z = [0.0, 0.0, 0.0]
    if k in (1, 3, 5):
        # tube along the joint axis, from beyond this joint's hub to the next joint's hub
        z0 = 0.0 if k == 1 else HUB[k][1] / 2.0
        z1 = t[2] - HUB[k + 1][0] - TUBE_END_GAP[k]
        shapes = [cylinder_between([0.0, 0.0, z0], [0.0, 0.0, z1], TUBE_R[k], shell)]
        if TUBE_END_GAP[k] > 0.0:
            # a slim neck up to the next hub, drawn only: the collision tube stops short so that the
            # wrist can fold back over it (axis 5 down to -88 deg)
            neck = cylinder_between([0.0, 0.0, z1], [t[0], t[1], t[2]], NECK_R, shell)
            neck["visual_only"] = True
            shapes.append(neck)
        return shapes
    if k in (2, 4, 6):
        shapes = [hub(z, [0.0, 0.0, 1.0], HUB[k][0], HUB[k][1], dark)]
        shapes.append(cylinder_between(z, t, OFFSET_R[k], shell))
        if k + 1 in HUB:
            shapes.append(hub(t, next_axis, HUB[k + 1][0], HUB[k + 1][1], dark))
        return shapes
    # link 7: wrist housing (reaching a little back over link 6's end) and the flange disc
    top = t[2] - FLANGE_THICKNESS
    return [
        cylinder_between([0.0, 0.0, -WRIST_BACK], [0.0, 0.0, top], WRIST_R, shell),
        cylinder_between([0.0, 0.0, top], [0.0, 0.0, t[2]], FLANGE_R, metal),
    ]


def body_shapes():
    """The body in its own frame (origin on the floor under the robot, x forward, z up), mm."""
    return [
        box([-20.0, 0.0, 50.0], [400.0, 496.0, 100.0], "dualcal_base_dark"),
        box([-60.0, 0.0, 290.0], [180.0, 210.0, 380.0], "dualcal_body_white"),
        box([-80.0, 0.0, 520.0], [140.0, 180.0, 80.0], "dualcal_body_white"),
    ]


def main():
    out = []
    w = out.append
    w('<?xml version="1.0"?>\n')
    w("<!-- GENERATED FILE: written by tools/gen_urdf.py (dualcal); do not edit by hand.\n")
    w("     ABB IRB 14000 (YuMi) described from public facts: nominal DH table (Table 3 of the\n")
    w("     calibration paper, a3 = 40.5 mm), public joint-1 placement, joint limits, primitive\n")
    w("     geometry of roughly YuMi size. No meshes. Lengths in metres, angles in radians.\n")
    w("     DH base frame (frame 0) of each arm = joint-1 origin * Tz(-0.066) * Rz(pi). -->\n")
    w('<robot name="abb_irb14000">\n')
    for name, rgba in MATERIALS.items():
        w(f'  <material name="{name}">\n    <color rgba="{fmt3(rgba[:3])} {fmt(rgba[3])}"/>\n  </material>\n')

    w('  <link name="yumi_body">\n')
    for s in body_shapes():
        w(shape_xml(s, 4))
    w("  </link>\n")

    origins = arm_origins()
    for side in ("l", "r"):
        side_name = "left" if side == "l" else "right"
        w(f"\n  <!-- {side_name} arm -->\n")
        for i in range(len(DH)):
            w(f'  <link name="yumi_link_{i + 1}_{side}">\n')
            for s in link_shapes(i + 1, origins[i]):
                w(shape_xml(s, 4))
            w("  </link>\n")
        w(f'  <link name="yumi_flange_{side}"/>\n')

        parent = "yumi_body"
        for i in range(len(DH)):
            child = f"yumi_link_{i + 1}_{side}"
            if i == 0:
                xyz, rpy = JOINT1[side]
            else:
                rot, t = origins[i - 1]
                xyz = [c / 1000.0 for c in t]
                rpy = rpy_from_matrix(rot)
            lo, hi = LIMITS_DEG[i]
            w(f'  <joint name="yumi_joint_{JOINT_NUMBERS[i]}_{side}" type="revolute">\n')
            w(f'    <parent link="{parent}"/>\n    <child link="{child}"/>\n')
            w(f'    <origin xyz="{fmt3(xyz)}" rpy="{fmt3(rpy)}"/>\n')
            w('    <axis xyz="0 0 1"/>\n')
            w(
                f'    <limit lower="{fmt(math.radians(lo))}" upper="{fmt(math.radians(hi))}" '
                f'effort="{fmt(EFFORT_NM)}" velocity="{fmt(math.radians(VELOCITY_DEG_S[i]))}"/>\n'
            )
            w("  </joint>\n")
            parent = child
        rot, t = origins[-1]
        w(f'  <joint name="yumi_flange_joint_{side}" type="fixed">\n')
        w(f'    <parent link="{parent}"/>\n    <child link="yumi_flange_{side}"/>\n')
        w(f'    <origin xyz="{fmt3([c / 1000.0 for c in t])}" rpy="{fmt3(rpy_from_matrix(rot))}"/>\n')
        w("  </joint>\n")
    w("</robot>\n")
    sys.stdout.write("".join(out))


if __name__ == "__main__":
    main()
