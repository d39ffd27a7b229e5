"""The answer key's truth next to what metrocell's calibrate reports, by the planned catalog ids
(issue 27) and the joint/axis names in a parameter's JSON path — the parameter names are not
fixed yet, so a parameter is matched when its path names the term and one joint or axis.

Judged (|value − truth| ≤ 3σ): joint_compliance per joint [rad/(N·m)], joint_backlash per joint
[rad, the full play b], tool_offset per axis [m, flange frame]. Shown, not judged (their
parameterisation is metrocell's): column_bending (the truth's effective compliance per column
level is printed beside it), accelerometer_alignment, link_thermal_expansion.
"""

import re

from robot_description import ARM_JOINTS

AXES = {"x": 0, "y": 1, "z": 2}


def _joint_in(path):
    """The one arm joint the parameter's own name (else its whole path) names, or None."""
    for text in (path.rsplit("/", 1)[-1], path):
        hits = [j for j in ARM_JOINTS if re.search(rf"(^|[^a-z0-9]|_){re.escape(j)}($|[^a-z0-9]|_)", text)]
        if len(hits) == 1:
            return hits[0]
    return None


def _axis_in(path):
    # the parameter's own name: the last word of a JSON path (`/parameters[tool_offset.dx]` → `dx`)
    leaf = [w for w in re.split(r"[/.\[\]]+", path) if w][-1].lower()
    m = re.fullmatch(r"(d|delta_|offset_|tool_offset_)?([xyz])(_m)?", leaf)
    return AXES[m.group(2)] if m else None


def match(entries, robot):
    """entries: metrocell_contract.parameter_entries of calibrate's JSON → rows
    {term, name, path, value, sigma, truth, z, judged, ok}."""
    rows = []
    for path, value, sigma in entries:
        low = path.lower()
        row = {"path": path, "value": value, "sigma": sigma, "truth": None, "judged": False}
        if "joint_compliance" in low and (j := _joint_in(low)):
            row.update(term="joint_compliance", name=j, truth=robot["joint_compliance_rad_per_Nm"][j], judged=True)
        elif "joint_backlash" in low and (j := _joint_in(low)):
            row.update(term="joint_backlash", name=j, truth=robot["joint_backlash_rad"].get(j, 0.0), judged=True)
        elif "tool_offset" in low and (a := _axis_in(low)) is not None:
            row.update(term="tool_offset", name="xyz"[a], truth=robot["prism_offset_error_m"][a], judged=True)
        elif "column_bending" in low:
            row.update(term="column_bending", name=path.rsplit("/", 1)[-1])
        elif "accelerometer_alignment" in low:
            row.update(term="accelerometer_alignment", name=path.rsplit("/", 1)[-1])
        elif "link_thermal_expansion" in low:
            row.update(term="link_thermal_expansion", name=path.rsplit("/", 1)[-1],
                       truth=robot["alpha_per_K"]["aluminium"])
        else:
            continue
        if row["judged"]:
            s = row["sigma"]
            row["z"] = (value - row["truth"]) / s if s else None
            row["ok"] = bool(s) and abs(value - row["truth"]) <= 3.0 * s
        rows.append(row)
    return rows
