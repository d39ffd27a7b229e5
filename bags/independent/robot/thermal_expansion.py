"""Links growing and shrinking with their temperature.

A length between two features of one part at temperature T is L(T) = L₂₀·(1 + α·(T − 20 °C))
(linear expansion; ISO 1 sets 20 °C as the reference at which the URDF's CAD lengths hold).
So each joint origin's offset, which is a length of its parent link, scales by
1 + α_parent·ΔT, and the column's travel by 1 + α_steel·ΔT (its screw and tubes are steel).
The links are taken at the ambient temperature (the robot stood for hours before measuring;
the motors' own heat is left out). Outdoors at 9 °C against 21 °C indoors the arm's 1.2 m
shrinks by 23e-6 · 12 K · 1.2 m ≈ 0.33 mm.
"""

import numpy as np

from robot_description import ALPHA, link_material

REFERENCE_C = 20.0


def expansion_hooks(urdf, temperature_c, alpha_by_material=None):
    """(origin_scale {joint: (N,)}, motion_scale {joint: (N,)}) for link temperatures (N,) °C."""
    alpha = alpha_by_material or ALPHA
    dT = np.asarray(temperature_c, dtype=float) - REFERENCE_C
    origin_scale, motion_scale = {}, {}
    for name, j in urdf.joints.items():
        origin_scale[name] = 1.0 + alpha[link_material(j["parent"])] * dT
        if j["type"] == "prismatic":
            motion_scale[name] = 1.0 + alpha[link_material(j["child"])] * dT
    return origin_scale, motion_scale
