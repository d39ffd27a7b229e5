"""One recording: the program run on one ground, the prism measured from the recording's setups,
the accelerometers and the thermometer logged at every waypoint.

Everything a recording is made of is returned (the truth next to what was measured), for the
export, the answer key and the baselines.
"""

import numpy as np

from accelerometer import readings
from conditions import tilt_of
from robot_description import IMU_LINKS
from rotations import tilt_matrix
from stationing_program import timing
from total_station import place_setups
from true_robot import nominal_prism, true_state


def ambient_temperature(rng, condition, t):
    """The air (and the links, which stood in it for hours) over the recording: the condition's
    mean, a slow drift of up to ±0.6 K over the recording, logged with σ 0.05 K."""
    drift = rng.uniform(-0.6, 0.6) * (t - t.min()) / max(t.max() - t.min(), 1.0)
    true = condition.ambient_c + rng.uniform(-0.3, 0.3) + drift
    return true, np.round(true + rng.normal(0.0, 0.05, len(t)), 2)


def build_recording(urdf, program, robot, condition, rng):
    tilt = tilt_of(condition, rng)
    n_setups = int(program["setup_of_group"].max()) + 1
    azimuths = program["setup_azimuths_rad"] + rng.uniform(-0.25, 0.25, n_setups)
    setups = place_setups(rng, n_setups, azimuths)
    setup_idx = program["setup_of_group"][program["group"]]
    t = timing(rng, program, program["setup_of_group"])
    temp_true, temp_logged = ambient_temperature(rng, condition, t)
    q = program["q"]
    state = true_state(urdf, q, temp_true, tilt, robot)
    R_wb = tilt_matrix(*tilt)
    p_site = state["prism"] @ R_wb.T                      # base → the site's level frame
    n = len(t)
    measured, sigma = np.zeros((n, 3)), np.zeros((n, 3))
    raw = {"hz": np.zeros(n), "v": np.zeros(n), "sd": np.zeros(n)}
    for s, setup in enumerate(setups):
        sel = setup_idx == s
        obs = setup.observe(p_site[sel], rng)
        measured[sel], sigma[sel] = obs["xyz"], obs["u"]
        for k in raw:
            raw[k][sel] = obs[k]
    accel = {}
    for name, link in IMU_LINKS.items():
        accel[name] = readings(state["frames"][link][:, :3, :3], state["g_base"], robot["accelerometers"][name], rng)
    return {"condition": condition, "tilt": tilt, "setups": setups, "setup_index": setup_idx, "time_s": t,
            "temperature_true_c": temp_true, "temperature_logged_c": temp_logged, "q": q, "state": state,
            "prism_site": p_site, "measured": measured, "sigma": sigma, "raw": raw, "accel": accel,
            "nominal_base": nominal_prism(urdf, q), "role": program["role"], "group": program["group"]}
