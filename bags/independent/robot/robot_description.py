"""The nominal robot as its builder's CAD describes it, and the URDF file written from it.

A tracked mobile manipulator:
* `base_link` — the tracked chassis (origin on the ground between the tracks, x forward, z up),
  two track links and the base accelerometer's frame `base_imu` as fixed children;
* a lifting column of three nested tubes: `column_outer` fixed on the chassis, `column_middle`
  sliding out of it (joint `column_lower`, 0…0.6 m) and `column_inner` sliding out of the
  middle one (joint `column_upper`, written `<mimic joint="column_lower" multiplier="1"
  offset="0"/>`: one motor drives both through a belt, so the column grows by 2e); `column_top`
  is the plate on the inner tube carrying the arm and the tip accelerometer `column_tip_imu`
  (mounted turned 90° about z, as the sensor board happened to fit);
* a 6R arm of UR10-like proportions (upper arm 612 mm, forearm 572.3 mm, the published UR10
  offsets d1 127.3, d4 163.9, d5 115.7, d6 92.2 mm; masses close to the published UR10 link
  masses), zero pose stretched horizontally along +x, positive shoulder_lift and elbow turning
  the arm down (axes +y);
* `flange` (z along wrist_3's axis) and the `prism` (a 360° reflector on a bracket, 110 mm off
  the flange axis and 65 mm out from the flange face).

Every link has an `<inertial>` (mass, centre of mass; the inertia tensor is a solid box/cylinder
estimate, present because URDF requires it, unused by the physics here).

The column's inner geometry (tube lengths and overlaps) is not in the URDF — a URDF has no place
for it — it is in COLUMN below and used only by the true robot's bending (column_bending.py).
"""

import math
from dataclasses import dataclass, field

ROOT_LINK, TIP_LINK = "base_link", "prism"
COLUMN_JOINTS = ("column_lower", "column_upper")
ARM_JOINTS = ("shoulder_pan", "shoulder_lift", "elbow", "wrist_1", "wrist_2", "wrist_3")
INDEPENDENT_JOINTS = ("column_lower",) + ARM_JOINTS
COLUMN_LINKS = ("column_outer", "column_middle", "column_inner", "column_top")
ARM_LINKS = ("arm_base_link", "shoulder_link", "upper_arm_link", "forearm_link", "wrist_1_link",
             "wrist_2_link", "wrist_3_link", "flange", "prism")
IMU_LINKS = {"base": "base_imu", "tip": "column_tip_imu"}

# Materials' linear expansion coefficients [1/K] (handbook values, e.g. Kaye & Laby): the arm's
# castings and tubes are aluminium alloy, the column's tubes and screw are steel, the chassis steel.
ALPHA = {"aluminium": 23.0e-6, "steel": 11.5e-6}


@dataclass
class Link:
    name: str
    mass: float                  # kg
    com: tuple                   # centre of mass in the link frame, m
    size: tuple = (0.1, 0.1, 0.1)  # box used only for the inertia estimate, m
    material: str = "aluminium"


@dataclass
class Joint:
    name: str
    kind: str                    # fixed, revolute, prismatic
    parent: str
    child: str
    xyz: tuple = (0.0, 0.0, 0.0)
    rpy: tuple = (0.0, 0.0, 0.0)
    axis: tuple = (0.0, 0.0, 1.0)
    limit: tuple = None          # (lower, upper, effort N or N·m, velocity)
    mimic: dict = field(default_factory=dict)


# The column (steel tubes), heights in the column_outer frame (its foot on the chassis):
# the middle tube's bottom is at z = e (its frame origin), the outer tube ends at OUTER_TOP; the
# inner tube's bottom is at z = e in the middle tube's frame (2e in the outer's), the middle tube
# ends at MIDDLE_LENGTH in its frame; the inner tube carries the plate INNER_TO_TOP above its bottom.
COLUMN = {
    "outer_top_m": 0.80,        # outer tube length above the foot
    "middle_length_m": 0.90,    # middle tube length
    "inner_to_top_m": 0.95,     # inner tube bottom to the top plate
    "stroke_m": 0.60,           # per segment (column_lower's limit)
}
# overlaps: o1(e) = outer_top − e (middle in outer), o2(e) = middle_length − e (inner in middle)

LINKS = [
    Link("base_link", 185.0, (-0.05, 0.0, 0.24), (0.9, 0.6, 0.35), "steel"),
    Link("left_track", 24.0, (0.0, 0.0, 0.0), (1.0, 0.16, 0.24), "steel"),
    Link("right_track", 24.0, (0.0, 0.0, 0.0), (1.0, 0.16, 0.24), "steel"),
    Link("base_imu", 0.02, (0.0, 0.0, 0.0), (0.03, 0.03, 0.01), "steel"),
    Link("column_outer", 16.0, (0.0, 0.0, 0.40), (0.16, 0.16, 0.80), "steel"),
    Link("column_middle", 10.5, (0.0, 0.0, 0.45), (0.14, 0.14, 0.90), "steel"),
    Link("column_inner", 8.0, (0.0, 0.0, 0.48), (0.12, 0.12, 0.95), "steel"),
    Link("column_top", 3.5, (0.0, 0.0, 0.01), (0.25, 0.25, 0.02), "steel"),
    Link("column_tip_imu", 0.02, (0.0, 0.0, 0.0), (0.03, 0.03, 0.01), "steel"),
    Link("arm_base_link", 4.0, (0.0, 0.0, 0.05), (0.19, 0.19, 0.1)),
    Link("shoulder_link", 7.78, (0.0, 0.0, 0.0), (0.15, 0.15, 0.2)),
    Link("upper_arm_link", 12.93, (0.306, 0.0, 0.0), (0.7, 0.12, 0.12)),
    Link("forearm_link", 3.87, (0.286, 0.0, 0.0), (0.6, 0.09, 0.09)),
    Link("wrist_1_link", 1.96, (0.0, 0.06, 0.0), (0.09, 0.12, 0.09)),
    Link("wrist_2_link", 1.96, (0.0, 0.0, -0.06), (0.09, 0.09, 0.12)),
    Link("wrist_3_link", 0.202, (0.0, 0.07, 0.0), (0.08, 0.03, 0.08)),
    Link("flange", 2.6, (0.02, 0.0, 0.05), (0.12, 0.12, 0.10)),      # tool changer, tool and the prism bracket
    Link("prism", 0.30, (0.0, 0.0, 0.0), (0.07, 0.07, 0.07)),        # 360° prism
]

TWO_PI = 2.0 * math.pi
JOINTS = [
    Joint("left_track_mount", "fixed", "base_link", "left_track", (0.0, 0.30, 0.12)),
    Joint("right_track_mount", "fixed", "base_link", "right_track", (0.0, -0.30, 0.12)),
    Joint("base_imu_mount", "fixed", "base_link", "base_imu", (-0.25, 0.10, 0.32)),
    Joint("column_mount", "fixed", "base_link", "column_outer", (0.20, 0.0, 0.40)),
    Joint("column_lower", "prismatic", "column_outer", "column_middle", (0.0, 0.0, 0.0), axis=(0.0, 0.0, 1.0),
          limit=(0.0, COLUMN["stroke_m"], 4000.0, 0.05)),
    Joint("column_upper", "prismatic", "column_middle", "column_inner", (0.0, 0.0, 0.0), axis=(0.0, 0.0, 1.0),
          limit=(0.0, COLUMN["stroke_m"], 4000.0, 0.05), mimic={"joint": "column_lower", "multiplier": 1.0, "offset": 0.0}),
    Joint("column_cap", "fixed", "column_inner", "column_top", (0.0, 0.0, COLUMN["inner_to_top_m"])),
    Joint("column_tip_imu_mount", "fixed", "column_top", "column_tip_imu", (0.08, -0.06, -0.03), (0.0, 0.0, math.pi / 2)),
    Joint("arm_mount", "fixed", "column_top", "arm_base_link", (0.0, 0.0, 0.02)),
    Joint("shoulder_pan", "revolute", "arm_base_link", "shoulder_link", (0.0, 0.0, 0.1273), axis=(0.0, 0.0, 1.0),
          limit=(-TWO_PI, TWO_PI, 330.0, 2.09)),
    Joint("shoulder_lift", "revolute", "shoulder_link", "upper_arm_link", (0.0, 0.176, 0.0), axis=(0.0, 1.0, 0.0),
          limit=(-TWO_PI, TWO_PI, 330.0, 2.09)),
    Joint("elbow", "revolute", "upper_arm_link", "forearm_link", (0.612, -0.128, 0.0), axis=(0.0, 1.0, 0.0),
          limit=(-math.pi, math.pi, 150.0, 3.14)),
    Joint("wrist_1", "revolute", "forearm_link", "wrist_1_link", (0.5723, 0.0, 0.0), axis=(0.0, 1.0, 0.0),
          limit=(-TWO_PI, TWO_PI, 56.0, 3.14)),
    Joint("wrist_2", "revolute", "wrist_1_link", "wrist_2_link", (0.0, 0.1159, 0.0), axis=(0.0, 0.0, -1.0),
          limit=(-TWO_PI, TWO_PI, 56.0, 3.14)),
    Joint("wrist_3", "revolute", "wrist_2_link", "wrist_3_link", (0.0, 0.0, -0.1157), axis=(0.0, 1.0, 0.0),
          limit=(-TWO_PI, TWO_PI, 56.0, 3.14)),
    Joint("flange_mount", "fixed", "wrist_3_link", "flange", (0.0, 0.0922, 0.0), (-math.pi / 2, 0.0, 0.0)),
    # the prism: 110 mm off the flange axis (along flange x), 65 mm out from the face (flange z)
    Joint("prism_mount", "fixed", "flange", "prism", (0.110, 0.0, 0.065)),
]


def box_inertia(mass, size):
    a, b, c = size
    return (mass * (b * b + c * c) / 12.0, mass * (a * a + c * c) / 12.0, mass * (a * a + b * b) / 12.0)


def _fmt(v):
    return " ".join(f"{x:.12g}" if abs(x) > 1e-12 else "0" for x in v)


def urdf_text(name="tracked_mobile_manipulator"):
    """The URDF (XML) of the nominal robot."""
    out = ['<?xml version="1.0"?>',
           "<!-- A tracked mobile manipulator as its builder's CAD gives it: chassis, a lifting column of",
           "     two telescoping segments driven by one motor (column_upper mimics column_lower), a 6R arm",
           "     of UR10-like proportions, a 360-degree prism on a bracket at the flange. Lengths at 20 degC.",
           "     Written by bags/independent/robot/robot_description.py. -->",
           f'<robot name="{name}">']
    for link in LINKS:
        ixx, iyy, izz = box_inertia(link.mass, link.size)
        out += [f'  <link name="{link.name}">',
                "    <inertial>",
                f'      <origin xyz="{_fmt(link.com)}" rpy="0 0 0"/>',
                f'      <mass value="{link.mass:.6g}"/>',
                f'      <inertia ixx="{ixx:.6g}" ixy="0" ixz="0" iyy="{iyy:.6g}" iyz="0" izz="{izz:.6g}"/>',
                "    </inertial>",
                "  </link>"]
    for j in JOINTS:
        out += [f'  <joint name="{j.name}" type="{j.kind}">',
                f'    <parent link="{j.parent}"/>',
                f'    <child link="{j.child}"/>',
                f'    <origin xyz="{_fmt(j.xyz)}" rpy="{_fmt(j.rpy)}"/>']
        if j.kind != "fixed":
            out.append(f'    <axis xyz="{_fmt(j.axis)}"/>')
        if j.limit is not None:
            lo, hi, effort, vel = j.limit
            out.append(f'    <limit lower="{lo:.6g}" upper="{hi:.6g}" effort="{effort:.6g}" velocity="{vel:.6g}"/>')
        if j.mimic:
            m = j.mimic
            out.append(f'    <mimic joint="{m["joint"]}" multiplier="{m["multiplier"]:.6g}" offset="{m["offset"]:.6g}"/>')
        out.append("  </joint>")
    out.append("</robot>")
    return "\n".join(out) + "\n"


def link_material(name):
    return next(link.material for link in LINKS if link.name == name)
