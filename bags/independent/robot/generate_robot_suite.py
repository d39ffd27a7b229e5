#!/usr/bin/env python3
"""Write the independent robot suite (issue 27): a tracked mobile manipulator with a telescoping
column and a 6R arm, its prism read by a total station from several setups, on seven grounds —
made by numpy from mechanics and from how the instruments work, never by metrocell.

    .venv/bin/python bags/independent/robot/generate_robot_suite.py --out DIR --seeds 1 2 [--sample]
        [--no-reference-calibration] [--floor-reps 40]

Writes per seed DIR/seed_S/{robot.urdf, model.yaml, model_gravity.yaml} and per ground
DIR/seed_S/<condition>/{export.csv, mapping.yaml}; the answer key DIR/answers.json (the truth,
the numpy baselines, the noise floor) is for the scorer only. Deterministic per seed. `--sample`:
two grounds (flat floor, seesaw) and a smaller program (5 groups, ~240 waypoints).
"""

import argparse
import datetime as dt
import json
import os
import sys
import time

import numpy as np

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))

from baselines import noise_floor, oracle, rigid_per_group  # noqa: E402
from column_bending import effective_compliance  # noqa: E402
from conditions import CALIBRATION, CONDITIONS, SAMPLE  # noqa: E402
from effect_sizes import sizes  # noqa: E402
from export_files import columns, model_text, write_csv, write_mapping  # noqa: E402
from hidden_truth import draw_robot_truth  # noqa: E402
from recording import build_recording  # noqa: E402
from reference_calibration import calibrate, recovered, restation_and_check, tilt_from_accelerometer  # noqa: E402
from robot_description import ARM_JOINTS, urdf_text  # noqa: E402
from stationing_program import make_program  # noqa: E402
from urdf_chain import Urdf  # noqa: E402


def epoch_start(seed, index):
    """Each ground recorded on its own day, from 07:30 UTC."""
    d = dt.datetime(2025, 9, 1, 7, 30, tzinfo=dt.timezone.utc) + dt.timedelta(days=index + 40 * seed)
    return d.timestamp()


def accelerometer_truth(rec, robot):
    """The tilt each accelerometer's mean reading implies, less the true tilt of the link it is on
    (what an alignment term must absorb): (roll, pitch) offsets [rad] in the convention of
    reference_calibration.tilt_from_accelerometer."""
    out = {}
    for sensor, link in (("base", "base_imu"), ("tip", "column_tip_imu")):
        implied = tilt_from_accelerometer(rec["accel"][sensor].mean(axis=0), (0.0, 0.0))
        out[sensor] = {**robot["accelerometers"][sensor], "implied_tilt_rad": list(implied)}
    out["base"]["tilt_offset_rad"] = [out["base"]["implied_tilt_rad"][0] - rec["tilt"][0],
                                      out["base"]["implied_tilt_rad"][1] - rec["tilt"][1]]
    return out


def robot_answer(robot, program, urdf, rec_flat):
    torques = rec_flat["state"]["torques"]
    eff = effective_compliance(np.array(program["levels_m"]), robot["column"])
    return {**robot,
            "column_effective": {"column_lower_m": program["levels_m"],
                                 **{k: np.asarray(v).tolist() for k, v in eff.items()},
                                 "note": "a pure moment at the top plate on level ground: plate tilt and shift per N·m (column_bending.py)"},
            "gravity_torque_range_Nm_flat": {j: [float(torques[j].min()), float(torques[j].max())] for j in ARM_JOINTS},
            "equations": {
                "joint_compliance": "dtheta_j = k_j * tau_j, tau_j = a_j . sum_i (c_i - o_j) x m_i g_B (links outboard of j, undeflected pose)",
                "joint_backlash": "dtheta_j = (b_j / 2) * sign(tau_j); the commanded angle is the middle of the play",
                "column_bending": "foot phi = c_foot M(foot); overlap i phi = 2 M / (k_pad_i o_i(e)^2), o1 = 0.80 - e, o2 = 0.90 - e, "
                                  "about the overlap's middle; beam: tilt = M_top L/EI + F L^2/(2EI), shift = M_top L^2/(2EI) + F L^3/(3EI), "
                                  "L = 0.95 + 2e from the column_outer frame; phi = c M (the moment vector)",
                "prism_offset": "true prism origin = URDF prism_mount xyz + prism_offset_error_m, flange frame",
                "thermal": "every joint origin xyz * (1 + alpha_parent (T - 20 C)); prismatic travel * (1 + alpha_steel (T - 20 C)); "
                           "arm and flange aluminium, chassis and column steel",
                "accelerometer": "reading = (R_link R_mis)^T (-g_B) + bias + noise",
                "tilt": "R_WB = Rx(roll) Ry(pitch), g_B = R_WB^T (0, 0, -9.81)"}}


def one_seed(seed, out_dir, a, answers):
    sd = os.path.join(out_dir, f"seed_{seed}")
    os.makedirs(sd, exist_ok=True)
    urdf_path = os.path.join(sd, "robot.urdf")
    with open(urdf_path, "w") as f:
        f.write(urdf_text())
    with open(os.path.join(sd, "model.yaml"), "w") as f:
        f.write(model_text())
    with open(os.path.join(sd, "model_gravity.yaml"), "w") as f:
        f.write(model_text(gravity_terms=True))
    urdf = Urdf(urdf_path)
    program = make_program(np.random.default_rng([seed, 101]), urdf, target_waypoints=240 if a.sample else 450,
                           n_groups=5 if a.sample else None)
    robot = draw_robot_truth(np.random.default_rng([seed, 202]))
    conditions = [c for c in CONDITIONS if not a.sample or c.key in SAMPLE]
    recs = {}
    entry = {"program": {"levels_m": program["levels_m"], "groups": program["groups"],
                         "setup_of_group": [f"S{s + 1}" for s in program["setup_of_group"]],
                         "waypoints": int(len(program["role"])), "fit": int((program["role"] == "fit").sum()),
                         "check": int((program["role"] == "check").sum())},
             "conditions": {}}
    for i, c in enumerate(CONDITIONS):
        if c not in conditions:
            continue
        rec = build_recording(urdf, program, robot, c, np.random.default_rng([seed, 303, i]))
        recs[c.key] = rec
        d = os.path.join(sd, c.key)
        os.makedirs(d, exist_ok=True)
        cols = columns(rec, epoch_start(seed, i))
        write_csv(os.path.join(d, "export.csv"), cols)
        write_mapping(os.path.join(d, "mapping.yaml"), cols)
        floor = noise_floor(rec, np.random.default_rng([seed, 404, i]), reps=a.floor_reps)
        fl = floor["per_setup_levelled"]["overall"]
        entry["conditions"][c.key] = {
            "description": c.description, "tilt_rad": {"roll": rec["tilt"][0], "pitch": rec["tilt"][1],
                                                       "magnitude": float(np.hypot(*rec["tilt"]))},
            "ambient_c_mean": float(rec["temperature_true_c"].mean()), "outdoors": c.outdoors,
            "setups": [s.truth() for s in rec["setups"]], "accelerometers": accelerometer_truth(rec, robot),
            "rows": int(len(rec["role"])), "effect_sizes": sizes(urdf, rec, robot),
            "rigid_6dof_per_group": rigid_per_group(rec, "6dof"), "rigid_levelled_per_group": rigid_per_group(rec, "levelled"),
            "noise_floor": floor, "oracle_true_robot_per_setup": oracle(rec),
            "target_p95_xy_m": 1.5 * fl["p95_xy_m"], "target_p95_z_m": 1.5 * fl["p95_z_m"]}
    entry["robot"] = robot_answer(robot, program, urdf, recs[CALIBRATION])
    if not a.no_reference_calibration:
        t0 = time.time()
        theta, sigma, _ = calibrate(urdf, recs[CALIBRATION])
        entry["reference_calibration"] = {"recovered": recovered(theta, sigma), "seconds": time.time() - t0,
                                          "what": "reference_calibration.py: the generator's own model structure fitted on the flat floor's fit points"}
        for key, rec in recs.items():
            entry["conditions"][key]["reference_calibration_check"] = restation_and_check(urdf, rec, theta)
    answers["seeds"][str(seed)] = entry
    return entry


def print_table(seed, entry):
    mm = lambda v: f"{v * 1e3:6.2f}" if v is not None else "     -"
    print(f"\nseed {seed}: {entry['program']['waypoints']} waypoints ({entry['program']['fit']} fit, {entry['program']['check']} check), "
          f"{len(entry['program']['groups'])} groups, column levels {entry['program']['levels_m']} m")
    print(f"{'condition':18s} {'tilt mrad':>9s} {'T °C':>5s} | {'rigid 6dof':>10s} {'rigid lev':>9s} | {'floor xy':>8s} {'floor z':>7s} "
          f"{'target':>6s} | {'oracle':>6s} {'ref.cal':>7s}   (p95 xy in mm unless said)")
    for key, c in entry["conditions"].items():
        rc = c.get("reference_calibration_check", {}).get("overall", {}).get("p95_xy_m")
        print(f"{key:18s} {c['tilt_rad']['magnitude'] * 1e3:9.2f} {c['ambient_c_mean']:5.1f} | "
              f"{mm(c['rigid_6dof_per_group']['overall']['p95_xy_m']):>10s} {mm(c['rigid_levelled_per_group']['overall']['p95_xy_m']):>9s} | "
              f"{mm(c['noise_floor']['per_setup_levelled']['overall']['p95_xy_m']):>8s} {mm(c['noise_floor']['per_setup_levelled']['overall']['p95_z_m']):>7s} "
              f"{mm(c['target_p95_xy_m']):>6s} | {mm(c['oracle_true_robot_per_setup']['overall']['p95_xy_m']):>6s} {mm(rc):>7s}")


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--out", required=True)
    ap.add_argument("--seeds", type=int, nargs="+", default=[1, 2])
    ap.add_argument("--sample", action="store_true", help="two grounds, a smaller program")
    ap.add_argument("--floor-reps", type=int, default=40, help="noise-only repetitions for the floor")
    ap.add_argument("--no-reference-calibration", action="store_true", help="skip the numpy reference calibration (~10 s per seed)")
    a = ap.parse_args()
    os.makedirs(a.out, exist_ok=True)
    answers = {"generator": "bags/independent/robot/generate_robot_suite.py", "seeds": {}, "sample": a.sample,
               "calibration_condition": CALIBRATION,
               "conventions": {
                   "frames": "site level frame W: z up, origin on the ground under base_link; base frame p_W = R_WB p_B; "
                             "instrument: p_W = Rz(yaw) Rx(tilt0) Ry(tilt1) p_I + origin",
                   "check_statistics": "check_statistics.py: errors predicted - measured in the instrument frame; rms_m of the 3-D norm",
                   "noise_floor": "baselines.noise_floor: perfectly known robot, levelled pose (yaw, translation, tilt prior 5e-5) "
                                  "per setup from its fit points, pooled over reps",
                   "target": "1.5 x the floor's p95 (xy and z)"}}
    t0 = time.time()
    for seed in a.seeds:
        entry = one_seed(seed, a.out, a, answers)
        print_table(seed, entry)
    with open(os.path.join(a.out, "answers.json"), "w") as f:
        json.dump(answers, f, indent=1, default=float)
    print(f"\nwrote {len(a.seeds)} seed(s) to {a.out} in {time.time() - t0:.0f} s (answer key: {os.path.join(a.out, 'answers.json')})")


if __name__ == "__main__":
    main()
