"""One recording of the XFYZ machine: the shop (shop.py), a program chosen by what the concealed
effects need to be seen at all (a shift for thermal and instrument drifts, on-the-fly sweeps for
a latency, else a half-hour geometric job), the simulation (xfyz_cell.py) and the export
columns (export.py).

The program families are the same whatever is concealed within a family, so the program does
not give the answer away; what a family offers (bidirectional lines, random points, a body
diagonal, sweeps, reference nests) is what a metrologist would do for that kind of check.
"""

import numpy as np

from . import programs, shop
from .export import Column, fixed, mm, utc_stamp
from .magnitude import effect_in_noise_units
from .tracker import LaserTracker
from .xfyz_cell import XFYZCell


class Setting:
    """Everything about the shop a case's recipes may read or adjust."""

    def __init__(self, rng, family, steady=False):
        self.family = family
        self.travel, self.tool_offset = shop.machine_size(rng)
        self.tracker_R, self.tracker_T = shop.tracker_on_table(rng, self.travel, self.tool_offset)
        if family == "shift":
            self.duration_s = rng.uniform(2.5, 4.5) * 3600.0
            self.histories = shop.short_job_histories(rng) if steady else shop.shift_histories(rng, self.duration_s)
        else:
            self.duration_s = None
            self.histories = shop.short_job_histories(rng)
        self.air = shop.PlantAir(rng, self.histories["air"])
        self.power_on_s = -rng.uniform(2.0, 4.0) * 3600.0     # the tracker was switched on long before
        self.nests = shop.reference_nests(self.travel, self.tool_offset)

    def plant_pressure(self, pressure_pa):
        self.air.p0 = pressure_pa

    def hall_temperature(self, temperature_c):
        shift = temperature_c - self.histories["air"].base
        for h in self.histories.values():
            h.base += shift


def _program(setting, rng, with_nests, many_x):
    travel = setting.travel
    home = np.array([0.0, 0.0, travel[2][1]])
    planner = programs.Planner(home, rng, feed_m_s=rng.uniform(0.06, 0.12))
    if setting.family == "fly":
        # stationary anchors, then sweeps along X and Y in both directions at various feeds
        for i, p in enumerate(programs.random_points(travel, 16, rng)):
            planner.move_to(p)
            planner.read_here(f"S{i + 1:02d}")
        for k in range(4):
            y, z = rng.uniform(0.05, 0.95) * travel[1][1], rng.uniform(0.1, 0.9) * travel[2][1]
            a, b = [0.01, y, z], [travel[0][1] - 0.01, y, z]
            for d, (p0, p1) in enumerate([(a, b), (b, a)]):
                planner.sweep(p0, p1, rng.uniform(0.04, 0.12), rng.uniform(0.18, 0.3), f"SX{k + 1}{'FB'[d]}")
        for k in range(3):
            x, z = rng.uniform(0.05, 0.95) * travel[0][1], rng.uniform(0.1, 0.9) * travel[2][1]
            a, b = [x, 0.01, z], [x, travel[1][1] - 0.01, z]
            for d, (p0, p1) in enumerate([(a, b), (b, a)]):
                planner.sweep(p0, p1, rng.uniform(0.04, 0.12), rng.uniform(0.18, 0.3), f"SY{k + 1}{'FB'[d]}")
        return planner.readings()
    if setting.family == "shift":
        n = 44 if many_x else 26
        pts = np.vstack([programs.random_points(travel, n, rng),
                         programs.body_diagonal_points(travel, 6, rng, [0, 0, 0], [1, 1, 1])])
        nests = setting.nests if with_nests else None
        next_nest = [0.0]

        def one_round(pl):
            programs.random_rounds(pl, pts, 1, rng, round_gap_s=(0, 1), nests=None)
            if nests is not None and pl.t >= next_nest[0]:
                for nid, npos in nests:
                    pl.read_nest(nid, npos)
                next_nest[0] = pl.t + 1800.0 * rng.uniform(0.85, 1.15)

        if nests is not None:
            for nid, npos in nests:
                planner.read_nest(nid, npos)
            next_nest[0] = planner.t + 1800.0 * rng.uniform(0.85, 1.15)
        programs.shift_schedule(one_round, planner, setting.duration_s, rng, gap_s=(4 * 60, 12 * 60))
        return planner.readings()
    # geometry: ISO 230-2 bidirectional lines along each axis, random points, a body diagonal
    xmax, ymax, zmax = travel[0][1], travel[1][1], travel[2][1]
    lines_x = [[0, rng.uniform(0.15, 0.4) * ymax, rng.uniform(0.2, 0.5) * zmax],
               [0, rng.uniform(0.6, 0.85) * ymax, rng.uniform(0.5, 0.8) * zmax]]
    programs.bidirectional_lines(planner, travel, "x", lines_x, int(rng.integers(19, 24)), 1, rng)
    lines_y = [[rng.uniform(0.15, 0.4) * xmax, 0, rng.uniform(0.5, 0.8) * zmax],
               [rng.uniform(0.6, 0.85) * xmax, 0, rng.uniform(0.2, 0.5) * zmax]]
    programs.bidirectional_lines(planner, travel, "y", lines_y, int(rng.integers(11, 14)), 1, rng)
    lines_z = [[rng.uniform(0.3, 0.7) * xmax, rng.uniform(0.3, 0.7) * ymax, 0]]
    programs.bidirectional_lines(planner, travel, "z", lines_z, int(rng.integers(8, 10)), 1, rng)
    pts = np.vstack([programs.random_points(travel, 30, rng),
                     programs.body_diagonal_points(travel, 10, rng, [0, 1, 0], [1, 0, 1])])
    programs.random_rounds(planner, pts, 1, rng, round_gap_s=(0, 1), id_prefix="R")
    return planner.readings()


def simulate(setting, concealed, rng, noise="gaussian"):
    """Readings, the simulated export columns and the size of what is concealed."""
    machine_effects, latency = [], 0.0
    warmup = refraction = drift = None
    for c in concealed:
        machine_effects += c.machine
        latency += c.latency_s
        warmup = c.warmup or warmup
        refraction = c.refraction or refraction
        drift = c.drift or drift
        if c.power_on_s is not None:
            setting.power_on_s = c.power_on_s
    needs = set().union(*[c.needs for c in concealed]) if concealed else set()
    readings = _program(setting, rng, with_nests="nests" in needs, many_x=any(c.effect_id.startswith("periodic") for c in concealed))
    tracker = LaserTracker(setting.tracker_R, setting.tracker_T, noise=noise, warmup=warmup, refraction=refraction, drift=drift)
    cell = XFYZCell(setting.travel, setting.tool_offset, tracker, setting.histories, shop.SENSOR_NOISE_K, machine_effects, latency)
    sim = cell.simulate(readings, rng)
    # the size of the concealed effects as a pose-fitting model sees them
    clean = cell.simulate(readings, None, noiseless=True)["measured"]
    bare = cell.without_errors().simulate(readings, None, noiseless=True)["measured"]
    fit_rows = ~sim["is_nest"]
    size = effect_in_noise_units(clean[fit_rows], bare[fit_rows], sim["u95"][fit_rows])
    return readings, sim, size, tracker


def columns(setting, readings, sim, rng, epoch_start_s):
    """The export's columns, in the tracker software's habits (mm, U95, °C, hPa, %RH, +1/−1)."""
    t = readings["t"]
    n = len(t)
    station = setting.air.logged(t, rng)
    q = readings["q"]
    cols = [
        Column("Point", readings["point_id"], str, "point_id"),
        Column("Role", list(readings["role"]), str, "role"),
        Column("Time (UTC)", epoch_start_s + t, utc_stamp, "timestamp"),
        Column("X nominal [mm]", sim["nominal"][:, 0], mm, "nominal_x", 0.001),
        Column("Y nominal [mm]", sim["nominal"][:, 1], mm, "nominal_y", 0.001),
        Column("Z nominal [mm]", sim["nominal"][:, 2], mm, "nominal_z", 0.001),
        Column("X [mm]", sim["measured"][:, 0], mm, "measured_x", 0.001),
        Column("Y [mm]", sim["measured"][:, 1], mm, "measured_y", 0.001),
        Column("Z [mm]", sim["measured"][:, 2], mm, "measured_z", 0.001),
        Column("U95 [mm]", sim["u95"], lambda v: f"{v * 1000:.4f}", "u95", 0.001),
        Column("X axis [mm]", q[:, 0], mm, "joint.x", 0.001),
        Column("Y axis [mm]", q[:, 1], mm, "joint.y", 0.001),
        Column("Z axis [mm]", q[:, 2], mm, "joint.z", 0.001),
    ]
    if "tool_offset" in readings:
        # the target on the spindle, as the controller's active tool offset
        for k, a in enumerate("XYZ"):
            cols.append(Column(f"Tool {a} [mm]", readings["tool_offset"][:, k], mm, f"tool_offset.{a.lower()}", 0.001))
    if setting.family == "fly":
        v = readings["v"]
        for k, a in enumerate("XYZ"):
            cols.append(Column(f"{a} feed [mm/s]", v[:, k], lambda x: f"{x * 1000:.3f}", f"velocity.{a.lower()}", 0.001))
    for k, a in enumerate("XYZ"):
        cols.append(Column(f"{a} dir", [f"{int(s):+d}" for s in readings["approach"][:, k]], str, f"approach.{a.lower()}"))
    temps = sim["temperatures"]
    cols += [Column("T X-scale [C]", temps["x_scale"], fixed(2), "temperature.x_scale"),
             Column("T column [C]", temps["column"], fixed(2), "temperature.column"),
             Column("T hall [C]", temps["air"], fixed(2), "temperature.air"),
             Column("Station T [C]", station["temperature_c"], fixed(2), "temperature.station"),
             Column("Station P [hPa]", station["pressure_hpa"], fixed(1), "pressure", 100.0),
             Column("Station RH [%]", station["humidity_pct"], fixed(1), "humidity", 0.01),
             Column("Tracker on (UTC)", np.full(n, epoch_start_s + setting.power_on_s), utc_stamp, "instrument_on_time")]
    return cols, station
