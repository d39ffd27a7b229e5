"""Where the true robot puts its prism, and how its links sit, at commanded joint values.

The true robot is the URDF plus what the URDF leaves out (each in its own file):
  thermal_expansion.py — links at the ambient temperature instead of 20 °C;
  the prism's true offset from the flange (the bracket as built, a few mm off the drawing);
  column_bending.py    — the column's foot, overlaps and tubes yielding under the arm's moment;
  joint_compliance.py  — the joints' elastic yield and backlash under the gravity torques;
all under the gravity of the ground's tilt (gravity.py). Order: the thermally scaled chain with
the true prism offset is the undeflected robot; its weights give the column's deflection and the
joints' torques; the deflected chain is the undeflected one with the joint deflections added and
the column top moved by the column's deflection.
"""

import numpy as np

from column_bending import column_deflection
from gravity import gravity_in_base
from joint_compliance import gravity_torques, joint_deflections
from robot_description import ARM_JOINTS, TIP_LINK
from thermal_expansion import expansion_hooks

ALL_EFFECTS = frozenset({"thermal", "prism_offset", "column_bending", "joint_compliance", "joint_backlash"})


def nominal_prism(urdf, q):
    """The rigid URDF's prism position in the base frame (N,3) — what the user's model says."""
    frames, _ = urdf.forward(urdf.full_joint_values(q))
    return frames[TIP_LINK][:, :3, 3]


def true_state(urdf, q, temperature_c, tilt, truth, effects=ALL_EFFECTS):
    """The true robot at commanded joints q {independent joint: (N,)}.

    tilt: (roll, pitch) of the ground [rad]; truth: hidden_truth.py's robot truth; effects: which
    of ALL_EFFECTS are on (for the size of each in the answer key). Returns {prism (N,3),
    frames {link: (N,4,4)}, column_rotation (N,3,3), torques, deflections, column_info, g_base}."""
    g_base = gravity_in_base(*tilt)
    full = urdf.full_joint_values(q)
    n = len(next(iter(q.values())))
    origin_scale = motion_scale = None
    if "thermal" in effects:
        alpha = {"aluminium": truth["alpha_per_K"]["aluminium"], "steel": truth["alpha_per_K"]["steel"]}
        origin_scale, motion_scale = expansion_hooks(urdf, temperature_c, alpha)
    origin_offset = {"prism_mount": np.array(truth["prism_offset_error_m"])} if "prism_offset" in effects else None
    frames0, jf0 = urdf.forward(full, origin_scale=origin_scale, motion_scale=motion_scale, origin_offset=origin_offset)
    premultiply, column_info = None, None
    column_rotation = np.repeat(np.eye(3)[None], n, axis=0)
    if "column_bending" in effects:
        D, column_info = column_deflection(urdf, frames0, np.asarray(q["column_lower"]), g_base, truth["column"])
        premultiply = {"column_top": D}
        column_rotation = D[:, :3, :3]
    torques = gravity_torques(urdf, frames0, jf0, ARM_JOINTS, g_base)
    compliance = truth["joint_compliance_rad_per_Nm"] if "joint_compliance" in effects else {}
    backlash = truth["joint_backlash_rad"] if "joint_backlash" in effects else {}
    deflections = joint_deflections(torques, compliance, backlash)
    frames, _ = urdf.forward(full, joint_delta=deflections, origin_scale=origin_scale, motion_scale=motion_scale,
                             origin_offset=origin_offset, link_premultiply=premultiply)
    return {"prism": frames[TIP_LINK][:, :3, 3], "frames": frames, "column_rotation": column_rotation,
            "torques": torques, "deflections": deflections, "column_info": column_info, "g_base": g_base}
