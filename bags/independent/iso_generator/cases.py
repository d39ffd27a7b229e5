"""The case table: what each recording conceals, how big, which sign.

Categories (the scorer's table): single (usual size and sign), sign_reversed, range_3x,
half_magnitude (1–3× the noise), pair, null, out_of_catalog, confounder, and below_noise: a
weather station reading a few K off the beam's air changes ranges by ~1 ppm/K, under 0.5× the
noise at 0.5–1.5 m — physics the data cannot show; judged only for claiming nothing wrong. `kind` is what the
answer key says (single, pair, null, out_of_catalog, confounder).

`SAMPLE` is the small representative subset `generate_suite.py --sample` writes.
"""

from . import recipes as r


class CaseSpec:
    def __init__(self, key, kind, category, parts, family=None, noise="gaussian", note=""):
        self.key, self.kind, self.category = key, kind, category
        self.parts = parts                 # [(recipe, f)]; for arm/delta: [("arm"|"delta", f)]
        self.family, self.noise, self.note = family, noise, note


def _single(key, recipe, f, category, note=""):
    return CaseSpec(key, "single", category, [(recipe, f)], note=note)


CASES = [
    # -- single effects at their usual size and sign ---------------------------------------------
    _single("reversal_y", r.reversal("y"), 1, "single", "lost motion on Y, ISO 230-2 B < 0"),
    _single("positioning_y_progressive", r.positioning("y", "progressive"), 1, "single"),
    _single("positioning_x_nonlinear", r.positioning("x", "nonlinear"), 1, "single"),
    _single("straightness_x_in_z", r.straightness("x", "z"), 1, "single", "E_ZX bow"),
    _single("squareness_EC0X", r.squareness("EC0X"), 1, "single"),
    _single("squareness_EB0X", r.squareness("EB0X"), 1, "single"),
    _single("squareness_EA0Y", r.squareness("EA0Y"), 1, "single"),
    _single("periodic_x", r.screw_periodic("x"), 1, "single"),
    _single("scale_expansion_x", r.scale_expansion("x"), 1, "single"),
    _single("column_growth", r.column_growth(), 1, "single", "column lifts the head (+z)"),
    _single("tracker_warmup", r.tracker_warmup(), 1, "single"),
    _single("refraction_standard_air", r.refraction_standard_air(), 1, "single", "plant at ~550 m"),
    _single("latency", r.latency(), 1, "single", "tracker stamps late"),
    _single("stand_sinking", r.stand_sinking(), 1, "single"),
    _single("tracker_turning", r.tracker_turning(), 1, "single"),
    CaseSpec("arm_tool_offset", "single", "single", [("arm", 1)]),
    CaseSpec("delta_rod_length", "single", "single", [("delta", 1)]),
    # -- the same effects with the sign reversed ------------------------------------------------------
    _single("reversal_y_overcompensated", r.reversal("y"), -1, "sign_reversed", "controller backlash setting too large, B > 0"),
    _single("positioning_y_negative", r.positioning("y", "progressive"), -1, "sign_reversed"),
    _single("straightness_x_in_z_negative", r.straightness("x", "z"), -1, "sign_reversed"),
    _single("squareness_EC0X_negative", r.squareness("EC0X"), -1, "sign_reversed"),
    _single("periodic_x_opposite_phase", r.screw_periodic("x"), -1, "sign_reversed"),
    _single("scale_expansion_x_overcompensated", r.scale_expansion("x"), -1, "sign_reversed", "alpha_net < 0"),
    _single("spindle_growth_down", r.column_growth(), -1, "sign_reversed", "growth toward the table (-z)"),
    _single("tracker_warmup_negative", r.tracker_warmup(), -1, "sign_reversed"),
    _single("refraction_cold_store", r.refraction_standard_air(), -1, "sign_reversed", "sea level, 12 C: n_true > n_standard"),
    _single("latency_early", r.latency(), -1, "sign_reversed", "tracker stamps early"),
    _single("stand_rising", r.stand_sinking(), -1, "sign_reversed"),
    _single("refraction_station_cold", r.refraction_station_bias(), -1, "below_noise", "station reads 3-5 K below the beam's air"),
    # -- three times the usual range ---------------------------------------------------------------
    _single("reversal_y_3x", r.reversal("y"), 3, "range_3x"),
    _single("positioning_y_3x", r.positioning("y", "progressive"), 3, "range_3x"),
    _single("squareness_EC0X_3x", r.squareness("EC0X"), 3, "range_3x"),
    _single("periodic_x_3x", r.screw_periodic("x"), 3, "range_3x"),
    _single("scale_expansion_x_3x", r.scale_expansion("x"), 3, "range_3x", "3x steel: beyond the usual range"),
    _single("column_growth_3x", r.column_growth(), 3, "range_3x"),
    _single("tracker_warmup_3x", r.tracker_warmup(), 3, "range_3x"),
    _single("refraction_high_plant", r.refraction_standard_air(), 3, "range_3x", "plant at ~1800 m"),
    _single("latency_3x", r.latency(), 3, "range_3x"),
    # -- half magnitude: 1–3× the noise ----------------------------------------------------------------
    _single("reversal_y_small", r.reversal("y"), 0.4, "half_magnitude"),
    _single("positioning_y_small", r.positioning("y", "progressive"), 0.4, "half_magnitude"),
    _single("straightness_x_in_z_small", r.straightness("x", "z"), 0.45, "half_magnitude"),
    _single("squareness_EC0X_small", r.squareness("EC0X"), 0.4, "half_magnitude"),
    _single("periodic_x_small", r.screw_periodic("x"), 0.45, "half_magnitude"),
    _single("scale_expansion_x_small", r.scale_expansion("x"), 0.45, "half_magnitude"),
    _single("column_growth_small", r.column_growth(), 0.45, "half_magnitude"),
    _single("tracker_warmup_small", r.tracker_warmup(), 0.4, "half_magnitude"),
    _single("latency_small", r.latency(), 0.4, "half_magnitude"),
    _single("refraction_station_warm", r.refraction_station_bias(), 1, "below_noise", "station reads 3-5 K above the beam's air"),
    # -- pairs -------------------------------------------------------------------------------------
    CaseSpec("pair_reversal_y_column_growth", "pair", "pair", [(r.reversal("y"), 1), (r.column_growth(), 1)]),
    CaseSpec("pair_periodic_x_scale_x", "pair", "pair", [(r.screw_periodic("x"), 1), (r.scale_expansion("x"), 1)], note="same axis"),
    CaseSpec("pair_squareness_xy_positioning_y", "pair", "pair", [(r.squareness("EC0X"), 1), (r.positioning("y", "progressive"), 1)]),
    CaseSpec("pair_positioning_x_reversal_x", "pair", "pair", [(r.positioning("x", "nonlinear"), 1), (r.reversal("x"), 1)], note="same axis"),
    CaseSpec("pair_warmup_scale_x", "pair", "pair", [(r.tracker_warmup(), 1), (r.scale_expansion("x"), 1)]),
    CaseSpec("pair_straightness_squareness_yz", "pair", "pair", [(r.straightness("x", "z"), 1), (r.squareness("EA0Y"), 1)]),
    # -- nulls -------------------------------------------------------------------------------------
    CaseSpec("null", "null", "null", []),
    CaseSpec("null_heavy_tailed", "null", "null", [], noise="student_t", note="Student t, 4 dof"),
    CaseSpec("null_thermal_shift", "null", "null", [], family="shift", note="temperatures change ~3 K, the machine does not"),
    # -- out of catalog ----------------------------------------------------------------------------
    CaseSpec("cycling_drift", "out_of_catalog", "out_of_catalog", [(r.cycling_drift(), 1)]),
    CaseSpec("local_bump", "out_of_catalog", "out_of_catalog", [(r.local_bump(), 1)]),
    # -- confounder: the stand sinks while the column thermocouple warms monotonically -------------------
    CaseSpec("confounder_sinking_vs_column", "confounder", "confounder", [(r.stand_sinking((12.0, 16.0), column_warming_linearly=True), 1)],
             note="no column growth; the column's thermocouple warms monotonically all shift"),
]

SAMPLE = ["reversal_y", "reversal_y_overcompensated", "squareness_EC0X_3x", "periodic_x", "column_growth",
          "tracker_warmup_negative", "latency", "scale_expansion_x_small", "refraction_standard_air", "stand_sinking",
          "pair_reversal_y_column_growth", "null", "local_bump", "confounder_sinking_vs_column"]
