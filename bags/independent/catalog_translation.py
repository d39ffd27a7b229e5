"""The truth of each concealed effect, translated into the parameters metrocell's catalog
documents (crates/physics/README.md) — the only place in bags/independent/ that knows the
catalog's conventions. The generator's physics never imports this; the answer key and the
scorer do.

Translations (documented catalog equation ← our ISO/physical definition):
  positioning[k]   d = δ_k(q_k)·e_k, δ a Legendre series over the travel: the least-squares
                   Legendre coefficients c0..c3 of our E_KK(q) over the model's travel,
                   u = 2(q − q_min)/(q_max − q_min) − 1. c0 (an offset) is not identifiable with
                   an unknown tracker pose.
  straightness[k:j] d = δ_j(q_k)·e_j: the same projection of our E_JK (c0 not identifiable).
  squareness[xy|xz|yz]  xy: d = (−y·s, 0, 0); xz: d = (−z·s, 0, 0); yz: d = (0, −z·s, 0).
                   Our EC0X (ε, X turned about Z: d = (0, εx, 0)) equals a rigid rotation by ε
                   about Z plus (εy, 0, 0): s_xy = −ε. EB0X (d = (0, 0, −εx)) = rotation by ε about
                   Y + (−εz, 0, 0): s_xz = +ε. EA0Y (d = (0, 0, εy)) = rotation by ε about X +
                   (0, εz, 0): s_yz = −ε. (The rotation is absorbed by the tracker pose.)
  pitch_cyclic[k]  d = e_k·[a1 cos(2πq/P) + b1 sin(2πq/P)]: A·sin(2πq/P + φ) gives a1 = A sin φ,
                   b1 = A cos φ.
  backlash[k]      d = −(β/2)·s_k·e_k: our ISO 230-2 B gives d = (B/2)·s, so β = −B.
  thermal_scale[k] d = e_k·α·q_k·(T − 20 °C): α as is.
  thermal_growth[sensor]  d = n̂·g·(T_f − 20 °C): g along our direction; given here as the value
                   along +z (coefficient_along_z), the scorer turns it to the finding's direction.
  tracker_warmup   Δρ = A + B(1 − e^(−t/τ)): as is (t since power-on).
  refraction       Δρ = ρ·(n(t+ΔT, p+Δp, h+Δh)/n(t, p, h) − 1), (t, p, h) the station's readings,
                   n "shop-floor Edlén": only the scale n_beam/n_used − 1 is identifiable (ΔT and Δp
                   act alike); we give the ΔT alone and the Δp alone that reproduce our mean scale
                   (computed with Birch & Downs in the generator) at the station's mean readings,
                   solved with the shop-floor Edlén equation as NIST publishes it (the README names
                   the formula, not its constants: at the tens of kelvin a standard-air error needs,
                   the ΔT depends on the formula's water term, ~15 % between B&D and shop-floor).
  instrument_drift pose(t) = pose + Σ_j P_j(u)·(dx_j, dy_j, dz_j, rx_j, ry_j, rz_j),
                   u = 2(t − t_start)/(t_end − t_start) − 1 over the recording: the Legendre
                   coefficients (j ≥ 1) of our pose drift; a stand sinking at r gives
                   dz1 = −r·(t_end − t_start)/2; a head turning about its own standing axis by δ(t)
                   gives rz_j (taken as the increment of the pose's last Euler angle, a turn about
                   the tracker's own z — the README does not say which axes r turns about).
  time_offset      d = −Δt·v: Δt = our latency L (tracker stamps later than the instant).
  tool_offset      d = (dx, dy, dz): our error of the SMR offset in the flange frame (assumed
                   to be the catalog's frame for an arm; the README does not say).
  delta_rod_length rod length per tower L + ΔL_T: as is.
"""

import numpy as np

from iso_generator.geometric_errors import PositioningError, StraightnessError


def _param(value, unit, identifiable=True, note=None, aliases=()):
    out = {"value": float(value), "unit": unit, "identifiable": bool(identifiable), "aliases": list(aliases)}
    if note:
        out["note"] = note
    return out


def legendre_coefficients(fn, travel, order=3):
    """Least-squares Legendre coefficients of fn(q) over the travel (dense uniform grid)."""
    q = np.linspace(travel[0], travel[1], 4001)
    u = 2.0 * (q - travel[0]) / (travel[1] - travel[0]) - 1.0
    V = np.polynomial.legendre.legvander(u, order)
    c, *_ = np.linalg.lstsq(V, fn(q), rcond=None)
    return c


def _series(fn, travel):
    c = legendre_coefficients(fn, travel)
    return {f"c{i}": _param(c[i], "m", identifiable=(i > 0), note="an offset: absorbed by the tracker pose" if i == 0 else None)
            for i in range(4)}


def shop_floor_index(temperature_c, pressure_pa, humidity_rh):
    """The shop-floor Edlén equation (NIST Engineering Metrology Toolbox):
    n = 1 + 7.86e-4·p/(273 + t) − 1.5e-11·RH·(t² + 160), p in kPa, RH in %."""
    t = np.asarray(temperature_c, dtype=float)
    return 1.0 + 7.86e-4 * (pressure_pa / 1000.0) / (273.0 + t) - 1.5e-11 * (100.0 * humidity_rh) * (t * t + 160.0)


def _refraction_equivalents(k_mean, station):
    """ΔT alone and Δp alone giving the scale k at the station's mean readings (shop-floor Edlén)."""
    t, p, h = station["temperature_c"], station["pressure_pa"], station["humidity_rh"]
    n0 = shop_floor_index(t, p, h)

    def solve(f, lo, hi):
        for _ in range(80):
            mid = 0.5 * (lo + hi)
            if (f(mid) - k_mean) * (f(lo) - k_mean) > 0:
                lo = mid
            else:
                hi = mid
        return 0.5 * (lo + hi)

    dT = solve(lambda d: shop_floor_index(t + d, p, h) / n0 - 1.0, -200.0, 200.0)
    dp = solve(lambda d: shop_floor_index(t, p + d, h) / n0 - 1.0, -60000.0, 60000.0)
    return dT, dp


def translate(effect_id, truth, context):
    """Expected finding(s) for one concealed effect: [{term, label, parameters}], or [] for a
    structure no catalog term models. `context`: model travel, station means, refraction scale."""
    travel = context["travel"]
    if effect_id.startswith("reversal"):
        a = truth["axis"]
        return [{"term": "backlash", "label": f"backlash[{a}]",
                 "parameters": {"reversal": _param(-truth["B_m"], "m")}}]
    if effect_id.startswith("positioning"):
        a = truth["axis"]
        e = PositioningError(a, truth["travel_m"], truth["progressive_m_per_m"], truth["bow_m"], truth["wave_m"])
        return [{"term": "positioning", "label": f"positioning[{a}]",
                 "parameters": _series(e.along_axis, travel["xyz".index(a)])}]
    if effect_id.startswith("straightness"):
        a, d = truth["axis"], truth["direction"]
        e = StraightnessError(a, d, truth["travel_m"], truth["bow_m"], truth["wave_m"])
        return [{"term": "straightness", "label": f"straightness[{a}:{d}]",
                 "parameters": _series(e.across, travel["xyz".index(a)])}]
    if effect_id.startswith("squareness"):
        name, eps = truth["iso"], truth["angle_rad"]
        pair, s = {"EC0X": ("xy", -eps), "EB0X": ("xz", eps), "EA0Y": ("yz", -eps)}[name]
        return [{"term": "squareness", "label": f"squareness[{pair}]", "parameters": {"s": _param(s, "rad")}}]
    if effect_id.startswith("periodic"):
        a, A, phi = truth["axis"], truth["amplitude_m"], truth["phase_rad"]
        return [{"term": "pitch_cyclic", "label": f"pitch_cyclic[{a}]", "lead_m": truth["lead_m"],
                 "parameters": {"a1": _param(A * np.sin(phi), "m"), "b1": _param(A * np.cos(phi), "m")}}]
    if effect_id.startswith("scale_expansion"):
        return [{"term": "thermal_scale", "label": f"thermal_scale[{truth['axis']}]",
                 "parameters": {"alpha": _param(truth["alpha_per_k"], "1/K")}}]
    if effect_id == "column_growth":
        g_z = truth["coefficient_m_per_k"] * truth["direction"][2]
        return [{"term": "thermal_growth", "label": f"thermal_growth[{truth['sensor']}]",
                 "parameters": {"coefficient": _param(g_z, "m/K", note="along +z; flips with a -z direction"),
                                "time_constant": _param(truth["time_constant_s"], "s", aliases=["tau"])},
                 "direction": [0.0, 0.0, 1.0]}]
    if effect_id == "tracker_warmup":
        return [{"term": "tracker_warmup", "label": "tracker_warmup",
                 "parameters": {"offset": _param(truth["A_m"], "m", aliases=["A", "a"]),
                                "amplitude": _param(truth["B_m"], "m", aliases=["B", "b"]),
                                "time_constant": _param(truth["tau_s"], "s", aliases=["tau"])}}]
    if effect_id.startswith("refraction"):
        k = context["refraction_scale_mean"]
        dT, dp = _refraction_equivalents(k, context["station_mean"])
        if effect_id == "refraction_station_bias":
            dT, dp = -truth["station_minus_beam_k"], None
        params = {"delta_t": _param(dT, "K", aliases=["path_temperature_offset", "temperature_offset", "dt", "delta_temperature"],
                                    note="identifiable only as the range scale together with delta_p")}
        if dp is not None:
            params["delta_p"] = _param(dp, "Pa", aliases=["path_pressure_offset", "pressure_offset", "dp", "delta_pressure"],
                                       note="alternative to delta_t: the same range scale")
        else:
            params["delta_p"] = _param(0.0, "Pa", aliases=["path_pressure_offset", "pressure_offset", "dp", "delta_pressure"])
        return [{"term": "refraction", "label": "refraction", "range_scale_ppm": k * 1e6, "parameters": params,
                 "degenerate": ["delta_t", "delta_p"]}]
    if effect_id == "latency":
        return [{"term": "time_offset", "label": "time_offset",
                 "parameters": {"dt": _param(truth["latency_s"], "s", aliases=["delta_t", "offset", "time_offset", "latency"])}}]
    if effect_id in ("tracker_stand_sinking", "tracker_turning"):
        t0, t1 = context["time_span_s"]
        params = {}
        if effect_id == "tracker_stand_sinking":
            drift = {"dz": lambda t: -truth["sink_rate_m_per_s"] * t}
        else:
            rate, tc = truth["initial_yaw_rate_rad_per_s"], truth["time_constant_s"]
            drift = {"rz": lambda t: rate * tc * (1.0 - np.exp(-t / tc))}
        for comp in ("dx", "dy", "dz", "rx", "ry", "rz"):
            fn = drift.get(comp, lambda t: 0.0 * t)
            c = legendre_coefficients(fn, (t0, t1))
            for j in (1, 2, 3):
                params[f"{comp}{j}"] = _param(c[j], "rad" if comp[0] == "r" else "m")
        return [{"term": "instrument_drift", "label": "instrument_drift", "parameters": params,
                 "physical": truth, "time_span_s": [t0, t1], "unexplained_is_correct": True}]
    if effect_id == "arm_tool_offset":
        e = truth["error_flange_m"]
        return [{"term": "tool_offset", "label": "tool_offset",
                 "parameters": {"dx": _param(e[0], "m"), "dy": _param(e[1], "m"), "dz": _param(e[2], "m")},
                 "note": "flange frame assumed"}]
    if effect_id == "delta_rod_length":
        e = truth["rod_length_error_m"]
        return [{"term": "delta_rod_length", "label": "delta_rod_length",
                 "parameters": {f"rod_length_{t}": _param(e[t], "m") for t in "abc"}}]
    return []           # out of catalog
