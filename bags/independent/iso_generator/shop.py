"""The shop around an XFYZ machine: its size, where the tracker stands on the table, the
temperature histories of a shift, the plant's air and the reference nests.

Every case draws these from its own seed, the same way whatever it conceals, so nothing in a
recording's shape tells which effect it holds.
"""

import numpy as np

from .temperatures import History
from .tracker import rotation_xyz

#: a plant ~550 m above sea level: the barometric formula gives ~950 hPa on an average day
PLANT_PRESSURE_PA = 95000.0


def machine_size(rng):
    """Travel of X, Y, Z (m) near 800 × 500 × 400 mm and the SMR's offset below the spindle
    gauge line (the tool point is q + offset)."""
    travel = [(0.0, round(rng.uniform(0.76, 0.84), 2)), (0.0, round(rng.uniform(0.47, 0.53), 2)),
              (0.0, round(rng.uniform(0.37, 0.43), 2))]
    tool_offset = np.array([0.0, 0.0, -round(rng.uniform(0.10, 0.18), 3)])
    return travel, tool_offset


def table_height(tool_offset):
    """The table's top in the machine frame: 60 mm below the lowest tool point."""
    return tool_offset[2] - 0.06


def tracker_on_table(rng, travel, tool_offset):
    """The tracker on its low stand on the table, outside the work zone at one of its corners,
    0.4–1.6 m from the points; yawed arbitrarily, levelled to better than 0.1°."""
    zt = table_height(tool_offset)
    x = -rng.uniform(0.25, 0.40) if rng.random() < 0.5 else travel[0][1] + rng.uniform(0.25, 0.40)
    y = -rng.uniform(0.15, 0.30) if rng.random() < 0.5 else travel[1][1] + rng.uniform(0.15, 0.30)
    z = zt + rng.uniform(0.25, 0.40)
    tilt = np.radians(0.1)
    R = rotation_xyz(rng.uniform(-tilt, tilt), rng.uniform(-tilt, tilt), rng.uniform(-np.pi, np.pi))
    return R, np.array([x, y, z])


def reference_nests(travel, tool_offset):
    """Three nests glued to the table's corners (they move with the workpiece, as the tracker
    does: a drift of the tracker moves them, a drift of the machine does not)."""
    zt = table_height(tool_offset) + 0.02
    x1, y1 = travel[0][1], travel[1][1]
    return [("NEST1", np.array([-0.05, -0.05, zt])), ("NEST2", np.array([x1 + 0.05, -0.05, zt])),
            ("NEST3", np.array([0.4 * x1, y1 + 0.05, zt]))]


def shift_histories(rng, duration_s, scale_rise=1.0):
    """A shift's temperatures (°C): the hall air drifting with the air conditioning's ripple;
    the X scale warming as the X drive works (first-order, τ ≈ 1 h); the column warming in an
    S-curve as spindle and drives heat it. The machine stood still overnight before t = 0."""
    air0 = rng.uniform(20.4, 22.4)
    air = History(air0, rng.uniform(0.1, 0.35)).ripple(rng.uniform(0.06, 0.18), rng.uniform(20, 50) * 60, rng.uniform(0, 2 * np.pi))
    x_scale = (History(air0 + rng.uniform(-0.2, 0.3))
               .rise(scale_rise * rng.uniform(2.5, 4.0), rng.uniform(45, 80) * 60, rng.uniform(3, 15) * 60)
               .ripple(rng.uniform(0.03, 0.08), rng.uniform(20, 50) * 60, rng.uniform(0, 2 * np.pi)))
    column = (History(air0 + rng.uniform(-0.3, 0.2))
              .logistic(rng.uniform(2.5, 4.0), rng.uniform(0.3, 0.5) * duration_s, rng.uniform(15, 30) * 60)
              .ripple(rng.uniform(0.03, 0.1), rng.uniform(25, 55) * 60, rng.uniform(0, 2 * np.pi)))
    return {"x_scale": x_scale, "column": column, "air": air}


def short_job_histories(rng):
    """A half-hour job: temperatures nearly steady (a slight drift and ripple)."""
    air0 = rng.uniform(20.4, 22.4)
    return {"x_scale": History(air0 + rng.uniform(-0.2, 0.3), rng.uniform(-0.2, 0.3)).ripple(0.03, 1800.0, rng.uniform(0, 6.28)),
            "column": History(air0 + rng.uniform(-0.3, 0.2), rng.uniform(-0.2, 0.3)).ripple(0.04, 2400.0, rng.uniform(0, 6.28)),
            "air": History(air0, rng.uniform(-0.2, 0.3)).ripple(rng.uniform(0.05, 0.15), rng.uniform(15, 40) * 60, rng.uniform(0, 6.28))}


SENSOR_NOISE_K = {"x_scale": 0.02, "column": 0.02, "air": 0.03}


class PlantAir:
    """The air on the beam (the hall's air temperature history, the plant's pressure and
    humidity drifting with the weather) and what the station reads of it (+ a bias)."""

    def __init__(self, rng, beam_temperature, pressure0_pa=PLANT_PRESSURE_PA, station_bias_k=0.0):
        self.beam_temperature = beam_temperature
        self.p0 = pressure0_pa + rng.uniform(-600, 600)
        self.p_rate = rng.uniform(-80, 80) / 3600.0                 # Pa/s: weather, ≤ 0.8 hPa/h
        self.rh0, self.rh_rate = rng.uniform(0.35, 0.55), rng.uniform(-0.02, 0.02) / 3600.0
        self.station_bias = station_bias_k

    def beam(self, t):
        t = np.asarray(t, dtype=float)
        return {"temperature_c": self.beam_temperature(t), "pressure_pa": self.p0 + self.p_rate * t,
                "humidity_rh": self.rh0 + self.rh_rate * t}

    def station_reading(self, t):
        b = self.beam(t)
        return {**b, "temperature_c": b["temperature_c"] + self.station_bias}

    def logged(self, t, rng):
        """The station's log: 0.05 K, 10 Pa, 1 %RH noise; resolution 0.01 K, 0.1 hPa, 0.1 %RH."""
        s = self.station_reading(t)
        n = np.shape(t)
        return {"temperature_c": np.round(s["temperature_c"] + rng.normal(0, 0.05, n), 2),
                "pressure_hpa": np.round((s["pressure_pa"] + rng.normal(0, 10.0, n)) / 100.0, 1),
                "humidity_pct": np.round(100 * s["humidity_rh"] + rng.normal(0, 1.0, n), 1)}
