"""Temperature and station-air histories over a shift (time t in s since the job started).

Each history is the true temperature of one place (the X scale, the column surface, the air on
the beam, ...); a sensor logs it with its own noise and 0.01 K resolution (`log`). Shapes are
those of a shop: a machine warming up after it starts (a first-order rise, or a logistic when
the heat sources ramp up), the air conditioning cycling (a ripple of 0.05–0.3 K with a period
of 15–60 min), a slow drift of the hall over the day.
"""

import numpy as np


class History:
    """T(t) = base + drift·t + Σ rises + Σ ripples. Before t_start of a rise nothing rises."""

    def __init__(self, base_c, drift_k_per_h=0.0):
        self.base, self.drift = base_c, drift_k_per_h / 3600.0
        self.rises, self.logistics, self.ripples = [], [], []

    def rise(self, amount_k, time_constant_s, start_s=0.0):
        """First-order warm-up after heat is switched on at start_s (ISO 230-3: the
        structure approaches a new equilibrium exponentially)."""
        self.rises.append((amount_k, time_constant_s, start_s))
        return self

    def logistic(self, amount_k, midpoint_s, width_s):
        """An S-shaped change (heat sources ramping up over a shift)."""
        self.logistics.append((amount_k, midpoint_s, width_s))
        return self

    def ripple(self, amplitude_k, period_s, phase_rad=0.0):
        """Air-conditioning cycling (ISO 230-3: environmental temperature variation)."""
        self.ripples.append((amplitude_k, period_s, phase_rad))
        return self

    def __call__(self, t_s):
        t = np.asarray(t_s, dtype=float)
        v = self.base + self.drift * t
        for amount, tau, start in self.rises:
            v = v + amount * np.where(t > start, 1.0 - np.exp(-np.clip(t - start, 0, None) / tau), 0.0)
        for amount, mid, width in self.logistics:
            v = v + amount / (1.0 + np.exp(-(t - mid) / width))
        for amp, period, phase in self.ripples:
            v = v + amp * np.sin(2 * np.pi * t / period + phase)
        return v


def first_order_lag(history, t_s, time_constant_s, t_from_s=-4 * 3600.0, step_s=5.0):
    """The temperature of a body following `history` through a first-order lag,
    τ·dT_f/dt = T − T_f (ISO 230-3: a structure's mean temperature lags its surface), at the
    times t_s. Integrated exactly for a piecewise-linear input on a fine grid from t_from_s,
    where the machine stood at equilibrium for hours (T_f = T)."""
    t_end = float(np.max(t_s)) + step_s
    grid = np.arange(t_from_s, t_end + step_s, step_s)
    u = history(grid)
    a = np.exp(-step_s / time_constant_s)
    # exact response to a linear ramp over each step: T_f' = a T_f + (1 − a) u_k + (u_{k+1} − u_k)(1 − (1 − a) τ/h)
    b = 1.0 - (1.0 - a) * time_constant_s / step_s
    out = np.empty_like(u)
    out[0] = u[0]
    for k in range(len(u) - 1):
        out[k + 1] = a * out[k] + (1.0 - a) * u[k] + (u[k + 1] - u[k]) * b
    return np.interp(t_s, grid, out)


def log(history_values, rng, noise_k=0.02, resolution_k=0.01):
    """What a thermocouple/RTD logger writes: the truth plus Gaussian noise, rounded."""
    v = history_values + rng.normal(0.0, noise_k, np.shape(history_values))
    return np.round(v / resolution_k) * resolution_k
