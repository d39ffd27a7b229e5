"""What a case conceals: one recipe per physical effect, drawn at a size factor f.

f = 1 is the effect's usual size and sign, f = −1 the same size with the sign reversed (the
physically meaningful opposite: an over-compensated backlash, a spindle growing toward the
table, a tracker stamping early, ...), f = 3 three times the usual range, f ≈ 0.4 a
half-magnitude case (1–3× the noise). Each recipe returns a `Concealed`: machine effects,
changes to the tracker, a latency, and the truth in physical/ISO terms for the answer key.
"""

import numpy as np

from .air import STANDARD_AIR
from .effects_out_of_catalog import CyclingDrift, LocalBump
from .geometric_errors import PeriodicScrewError, PositioningError, SquarenessError, StraightnessError
from .reversal import ReversalError
from .thermal import ScaleExpansion, StructureGrowth
from .tracker import PoseDrift, Refraction, Warmup

UM = 1e-6


class Concealed:
    def __init__(self, effect_id, machine=(), warmup=None, refraction=None, drift=None, latency_s=0.0,
                 power_on_s=None, station_bias_k=0.0, truth=None, needs=()):
        self.effect_id = effect_id            # our own name of the physical effect
        self.machine = list(machine)
        self.warmup, self.refraction, self.drift = warmup, refraction, drift
        self.latency_s, self.power_on_s, self.station_bias_k = latency_s, power_on_s, station_bias_k
        self.truth = truth or {}
        self.needs = set(needs)               # program/signal needs: "shift", "fly", "nests"


def _sgn(rng):
    return 1.0 if rng.random() < 0.5 else -1.0


# -- ISO 230-1 / 230-2 geometry ------------------------------------------------------------------

def reversal(axis):
    def make(rng, setting, f):
        # lost motion of 36–52 µm: a worn ball-screw drive without backlash compensation: B < 0 (reversal.py)
        e = ReversalError(axis, -f * rng.uniform(36, 52) * UM)
        return Concealed(f"reversal_{axis}", [e], truth=e.truth())
    return make


def positioning(axis, shape="progressive"):
    def make(rng, setting, f):
        travel = setting.travel["xyz".index(axis)]
        if shape == "progressive":     # a lead/scale error plus a little bow
            e = PositioningError(axis, travel, progressive_per_m=f * rng.uniform(70, 100) * UM,
                                 bow_m=f * _sgn(rng) * rng.uniform(6, 10) * UM)
        else:                          # non-linear: bow and S-wave dominate
            e = PositioningError(axis, travel, progressive_per_m=f * _sgn(rng) * rng.uniform(10, 20) * UM,
                                 bow_m=f * rng.uniform(28, 38) * UM, wave_m=f * _sgn(rng) * rng.uniform(15, 22) * UM)
        return Concealed(f"positioning_{axis}_{shape}", [e], truth=e.truth())
    return make


def straightness(axis, direction):
    def make(rng, setting, f):
        travel = setting.travel["xyz".index(axis)]
        e = StraightnessError(axis, direction, travel, bow_m=f * rng.uniform(26, 36) * UM,
                              wave_m=f * _sgn(rng) * rng.uniform(6, 10) * UM)
        return Concealed(f"straightness_{axis}_{direction}", [e], truth=e.truth())
    return make


def squareness(name):
    def make(rng, setting, f):
        e = SquarenessError(name, f * rng.uniform(80, 120) * UM)        # 16–25 arcsec
        return Concealed(f"squareness_{name}", [e], truth=e.truth())
    return make


def screw_periodic(axis):
    def make(rng, setting, f):
        lead = float(rng.choice([5, 10, 12, 16, 20])) * 1e-3           # ISO 3408-2 preferred leads
        amp = abs(f) * rng.uniform(14, 20) * UM
        phase = rng.uniform(0, 2 * np.pi) + (np.pi if f < 0 else 0.0)   # reversed: the same screw turned half a revolution
        e = PeriodicScrewError(axis, lead, amp, phase)
        return Concealed(f"periodic_{axis}", [e], truth=e.truth())
    return make


# -- ISO 230-3 thermal ---------------------------------------------------------------------------

def scale_expansion(axis="x"):
    def make(rng, setting, f):
        if f >= 3:
            alpha = 3 * 11.5e-6 * rng.uniform(0.95, 1.05)  # 3×: beyond any metal scale (aluminium is 23e-6): the range test
        elif f < 0:
            alpha = -rng.uniform(7, 10) * 1e-6             # the controller's thermal compensation set too high
        else:
            alpha = f * 11.5e-6 * rng.uniform(0.9, 1.1)    # steel; f < 1: partly compensated
        e = ScaleExpansion(axis, alpha, "x_scale")
        return Concealed(f"scale_expansion_{axis}", [e], truth=e.truth(), needs={"shift"})
    return make


def column_growth():
    def make(rng, setting, f):
        # the column (~1.2 m of cast iron, 10.5e-6/K) lifts the head as it warms (+z) by
        # 10–15 µm/K; reversed: the spindle's own growth toward the table dominates (−z)
        g = abs(f) * rng.uniform(10, 15) * UM
        direction = [0.0, 0.0, 1.0 if f > 0 else -1.0]
        e = StructureGrowth("column", direction, g, rng.uniform(15, 40) * 60)
        return Concealed("column_growth", [e], truth=e.truth(), needs={"shift"})
    return make


# -- the tracker ---------------------------------------------------------------------------------

def tracker_warmup():
    def make(rng, setting, f):
        w = Warmup(0.0, f * rng.uniform(25, 40) * UM, rng.uniform(20, 45) * 60, -rng.uniform(3, 12) * 60)
        return Concealed("tracker_warmup", warmup=w, power_on_s=w.t_on, truth=w.truth(), needs={"shift"})
    return make


def refraction_standard_air():
    """The tracker computed its index for 20 °C, 1013.25 hPa, 50 %RH instead of the station's
    readings. The plant's altitude and hall temperature set the size: ~550 m (950 hPa), 21–23 °C
    usually; a plant at ~1800 m (815 hPa, 24 °C) for 3×; ~250 m (985 hPa) for half; a cold store
    at sea level (1030 hPa, 12 °C) reverses the sign."""
    def make(rng, setting, f):
        if f < 0:
            setting.plant_pressure(rng.uniform(102600, 103400))
            setting.hall_temperature(rng.uniform(11.5, 13.0))
        elif f >= 3:
            setting.plant_pressure(rng.uniform(80800, 82000))
            setting.hall_temperature(rng.uniform(23.5, 25.0))
        elif f < 1:
            setting.plant_pressure(rng.uniform(98200, 98800))
        air = setting.air
        r = Refraction(air.beam, lambda t: {k: np.full(np.shape(t), v) for k, v in STANDARD_AIR.items()},
                       "tracker used standard air (20 C, 1013.25 hPa, 50 %RH) instead of the station's readings")
        return Concealed("refraction_standard_air", refraction=r, truth={"used_air": STANDARD_AIR}, needs={"station_truth"})
    return make


def refraction_station_bias():
    """The station sits near a warm cabinet (or in a draught): it reads the air 3–5 K off the
    beam's; the tracker used the station's reading."""
    def make(rng, setting, f):
        bias = f * rng.uniform(3.0, 5.0)                   # station − beam, K
        setting.air.station_bias = bias
        air = setting.air
        r = Refraction(air.beam, air.station_reading, f"station reads {bias:+.2f} K off the beam's air")
        return Concealed("refraction_station_bias", refraction=r, station_bias_k=bias,
                         truth={"station_minus_beam_k": bias}, needs={"station_truth"})
    return make


def latency():
    def make(rng, setting, f):
        L = f * rng.uniform(0.25, 0.4) * 1e-3
        return Concealed("latency", latency_s=L, needs={"fly"},
                         truth={"latency_s": L, "meaning": "tracker stamps are L later than the instant it measured; d = -L*v"})
    return make


def stand_sinking(rate_um_per_h=(8.0, 14.0), column_warming_linearly=False):
    """The tracker's stand settling: its origin sinks (−z of the table) at a constant rate;
    reversed, it rises (its legs warming). With `column_warming_linearly` the column's
    thermocouple meanwhile warms steadily all shift (the confounder: a column growth along +z
    would look the same in the tool points; the reference nests tell them apart)."""
    def make(rng, setting, f):
        if column_warming_linearly:
            from .temperatures import History
            base = setting.histories["column"].base
            setting.histories["column"] = History(base, rng.uniform(0.7, 1.0)).ripple(0.03, 2400.0, rng.uniform(0, 6.28))
        rate = f * rng.uniform(*rate_um_per_h) * UM / 3600.0          # m/s, + = sinking
        d = PoseDrift(translation=lambda t, r=rate: np.outer(np.asarray(t, float), [0.0, 0.0, -r]),
                      description="tracker stand sinking linearly" if f > 0 else "tracker stand rising linearly (legs warming)")
        return Concealed("tracker_stand_sinking", drift=d, needs={"shift", "nests"},
                         truth={"sink_rate_m_per_s": rate, "description": d.description})
    return make


def tracker_turning():
    def make(rng, setting, f):
        rate = f * rng.uniform(12, 20) * UM / 3600.0                  # rad/s about its standing axis
        t_half = rng.uniform(1.0, 2.0) * 3600.0
        # a smooth turn that slows down (the base's grease settling): rate·T·(1 − e^(−t/T))
        d = PoseDrift(yaw=lambda t, r=rate, T=t_half: r * T * (1.0 - np.exp(-np.asarray(t, float) / T)),
                      description="tracker head base turning slowly about its standing axis")
        return Concealed("tracker_turning", drift=d, needs={"shift", "nests"},
                         truth={"initial_yaw_rate_rad_per_s": rate, "time_constant_s": t_half, "description": d.description})
    return make


# -- out of catalog ----------------------------------------------------------------------------

def cycling_drift():
    def make(rng, setting, f):
        e = CyclingDrift(rng.uniform(22, 30) * UM, rng.uniform(35, 55) * 60, rng.uniform(0, 2 * np.pi))
        return Concealed("cycling_drift", [e], truth=e.truth(), needs={"shift", "nests", "steady"})
    return make


def local_bump():
    def make(rng, setting, f):
        tr = setting.travel
        centre = [rng.uniform(0.3, 0.7) * tr[0][1], rng.uniform(0.3, 0.7) * tr[1][1], rng.uniform(0.3, 0.7) * tr[2][1]]
        direction = [0.0, 1.0, 0.0] if rng.random() < 0.5 else [1.0, 0.0, 0.0]
        e = LocalBump(centre, rng.uniform(0.08, 0.11), rng.uniform(30, 40) * UM, direction)
        return Concealed("local_bump", [e], truth=e.truth())
    return make
