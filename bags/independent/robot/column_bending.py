"""The telescoping column yielding under the moment of what it carries.

Three places give, each turning everything above it (small rotations, first order in the
deflection; the moments are taken at the undeflected pose):

1. the foot — the column's flange bolted on the chassis: a rotational spring,
       φ_foot = c_foot · M(foot)                                   [rad = rad/(N·m) · N·m]
2. each sliding overlap — a tube held in the one around it by two guide pads at the overlap's
   ends, o apart, each a spring of stiffness k [N/m]: a moment M is a couple ±M/o on the pads,
   each yields M/(o·k), so the inner tube turns by
       φ_i = 2·M / (k_i · o_i(e)²),   o_1(e) = outer_top − e,  o_2(e) = middle_length − e,
   about the overlap's middle; the overlap shrinks as the column extends, so this grows
   steeply with the extension e (from 0.8 m to 0.2 m of overlap: 16×);
3. the tubes' own flexure — a cantilever of the extended length L(e) (foot to top plate) and
   flexural rigidity EI [N·m²] under the end moment M_top and the end force F⊥ of what the
   plate carries (Euler–Bernoulli; e.g. Gere & Timoshenko, *Mechanics of Materials*, tables of
   cantilever deflections):
       tip tilt  = M_top·L/EI + F⊥·L²/(2EI),   tip shift = M_top·L²/(2EI) + F⊥·L³/(3EI).

Vector form (ẑ the column's axis): a moment vector M turns the structure about M itself,
φ = c·M (a weight at +x under −z gravity: M along +y, and a rotation about +y lowers +x); a
rotation φ at the point s moves the plate by φ × (p_top − s); the beam's end moment moves the
tip along M × ẑ, its end force F⊥ along F⊥ and tilts it about ẑ × F⊥.

The plate's deflection is returned as one rigid transform in the base frame, D = T(p_top + δ)·
R(φ)·T(−p_top), which the URDF chain applies to `column_top` and so to the arm; the tip
accelerometer on the plate turns with R(φ).
"""

import numpy as np

from gravity import bending_part, weight_moment
from robot_description import COLUMN
from rotations import rotvec_matrix


def overlaps(e):
    """Overlap lengths o_1, o_2 [m] at the column_lower extension e [m]."""
    return COLUMN["outer_top_m"] - e, COLUMN["middle_length_m"] - e


def overlap_compliance(k_pad, overlap):
    """2/(k·o²) [rad/(N·m)]."""
    return 2.0 / (k_pad * overlap ** 2)


def column_deflection(urdf, frames, e, g_base, params):
    """(D (N,4,4), info) for the column_lower extension e (N,) — frames: the undeflected chain.

    params: {foot_compliance_rad_per_Nm, overlap_pad_stiffness_N_per_m: [k1, k2],
             flexural_rigidity_Nm2}."""
    foot = frames["column_outer"][:, :3, 3]
    axis = frames["column_outer"][0, :3, 2]
    top = frames["column_top"][:, :3, 3]
    all_links = [l for l in urdf.subtree_links("column_mount")]
    above_overlap1 = urdf.subtree_links("column_lower")
    above_overlap2 = urdf.subtree_links("column_upper")
    above_plate = urdf.subtree_links("column_cap")
    centres = urdf.centres_of_mass(frames, all_links)
    mass = {l: urdf.links[l]["mass"] for l in all_links}

    def moment_at(point, links):
        return bending_part(weight_moment({l: mass[l] for l in links}, centres, point, g_base), axis)

    o1, o2 = overlaps(e)
    s1 = foot + np.outer((e + COLUMN["outer_top_m"]) / 2.0, axis)            # middle of overlap 1
    s2 = foot + np.outer((3.0 * e + COLUMN["middle_length_m"]) / 2.0, axis)  # middle of overlap 2
    k1, k2 = params["overlap_pad_stiffness_N_per_m"]
    hinges = [(foot, params["foot_compliance_rad_per_Nm"] * moment_at(foot, all_links)),
              (s1, overlap_compliance(k1, o1)[:, None] * moment_at(s1, above_overlap1)),
              (s2, overlap_compliance(k2, o2)[:, None] * moment_at(s2, above_overlap2))]
    phi = np.zeros_like(top)
    shift = np.zeros_like(top)
    for point, rot in hinges:
        phi += rot
        shift += np.cross(rot, top - point)
    # the tubes' flexure under what the plate carries
    EI = params["flexural_rigidity_Nm2"]
    L = (top - foot) @ axis
    M_top = moment_at(top, above_plate)
    weight = sum(mass[l] for l in above_plate) * g_base
    F = weight - (weight @ axis) * axis
    F = np.repeat(F[None, :], len(e), axis=0)
    beam_tilt = (L / EI)[:, None] * M_top + (L ** 2 / (2 * EI))[:, None] * np.cross(axis[None, :], F)
    beam_shift = (L ** 2 / (2 * EI))[:, None] * np.cross(M_top, axis[None, :]) + (L ** 3 / (3 * EI))[:, None] * F
    phi += beam_tilt
    shift += beam_shift
    R = rotvec_matrix(phi)
    D = np.repeat(np.eye(4)[None], len(e), axis=0)
    D[:, :3, :3] = R
    D[:, :3, 3] = top + shift - np.einsum("nij,nj->ni", R, top)
    info = {"tilt_rad": phi, "shift_m": shift, "moment_foot_Nm": hinges[0][1] / params["foot_compliance_rad_per_Nm"],
            "moment_top_Nm": M_top, "length_m": L}
    return D, info


def effective_compliance(e, params, lever_m=0.0):
    """The column's compliance at the extension e for a pure moment applied at its top plate
    (level ground, no shear): tilt of the plate per N·m [rad/(N·m)] and shift of the plate per
    N·m [m/(N·m)] — a summary that does not depend on how a model parameterises the column."""
    o1, o2 = overlaps(np.asarray(e, dtype=float))
    k1, k2 = params["overlap_pad_stiffness_N_per_m"]
    EI = params["flexural_rigidity_Nm2"]
    top = COLUMN["inner_to_top_m"] + 2.0 * np.asarray(e)
    h1 = (e + COLUMN["outer_top_m"]) / 2.0
    h2 = (3.0 * e + COLUMN["middle_length_m"]) / 2.0
    c0, c1, c2 = params["foot_compliance_rad_per_Nm"], overlap_compliance(k1, o1), overlap_compliance(k2, o2)
    tilt = c0 + c1 + c2 + top / EI
    shift = c0 * top + c1 * (top - h1) + c2 * (top - h2) + top ** 2 / (2.0 * EI)
    return {"tilt_rad_per_Nm": tilt, "shift_m_per_Nm": shift, "foot_rad_per_Nm": c0 * np.ones_like(tilt),
            "overlap1_rad_per_Nm": c1, "overlap2_rad_per_Nm": c2, "beam_rad_per_Nm": top / EI, "length_m": top}
