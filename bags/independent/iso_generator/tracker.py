"""A laser tracker as it measures: a head turning in azimuth and elevation and a range from its
absolute distance meter (ADM), converted by its software to Cartesian coordinates in the
tracker's own frame (z along its standing axis, x its azimuth zero) and exported in mm with a
U95 per point.

What goes wrong with it, modelled from how the instrument works:
* warm-up: the ADM's zero drifts as the head warms after power-on, Δρ = A + B·(1 − e^(−t/τ)),
  t the time since power-on (manufacturers specify 1–3 h warm-up; B of 10–80 µm);
* refraction: the range is an optical path divided by the index the software computed from the
  air it was given (air.py). With standard air entered instead of the station's readings at a
  plant ~550 m up, n_true/n_used − 1 ≈ −20 ppm; with a station reading a few K off the beam's
  air, ≈ 1 ppm/K;
* pose drift: the tracker's stand settles (sinks) or its head base turns slowly: its pose in the
  table frame changes in time, all points move together about the tracker;
* noise: isotropic, σ = U95/2 per coordinate with U95 = a + b·ρ (a few µm plus a few µm per metre,
  the form of a manufacturer's MPE statement), Gaussian or Student t.
"""

import numpy as np

from .air import range_scale_error


def rotation_xyz(rx, ry, rz):
    """R = Rz(rz)·Ry(ry)·Rx(rx): a tracker yawed by rz after being tilted by rx, ry."""
    cx, sx, cy, sy, cz, sz = np.cos(rx), np.sin(rx), np.cos(ry), np.sin(ry), np.cos(rz), np.sin(rz)
    Rx = np.array([[1, 0, 0], [0, cx, -sx], [0, sx, cx]])
    Ry = np.array([[cy, 0, sy], [0, 1, 0], [-sy, 0, cy]])
    Rz = np.array([[cz, -sz, 0], [sz, cz, 0], [0, 0, 1]])
    return Rz @ Ry @ Rx


class Warmup:
    """ADM zero drift after power-on: Δρ(t) = A + B·(1 − exp(−(t − t_on)/τ))."""

    def __init__(self, offset_m, amplitude_m, time_constant_s, power_on_s):
        self.A, self.B, self.tau, self.t_on = offset_m, amplitude_m, time_constant_s, power_on_s

    def range_error(self, t):
        return self.A + self.B * (1.0 - np.exp(-(t - self.t_on) / self.tau))

    def truth(self):
        return {"A_m": self.A, "B_m": self.B, "tau_s": self.tau, "power_on_s": self.t_on,
                "equation": "drho = A + B*(1 - exp(-(t - t_on)/tau))"}


class Refraction:
    """Range scale n_true/n_used − 1 from the air on the beam (true) and the air the tracker
    software used; both are functions of time returning dicts for air.range_scale_error."""

    def __init__(self, true_air, used_air, description):
        self.true_air, self.used_air, self.description = true_air, used_air, description

    def scale(self, t):
        return range_scale_error(self.true_air(t), self.used_air(t))

    def truth(self, t):
        k = self.scale(t)
        return {"description": self.description, "scale_mean_ppm": float(np.mean(k) * 1e6),
                "scale_min_ppm": float(np.min(k) * 1e6), "scale_max_ppm": float(np.max(k) * 1e6)}


class PoseDrift:
    """The tracker's pose changing in time: its origin moves by translation(t) [m, table frame]
    (a stand sinking: −z) and its head base turns about its own standing axis by yaw(t) [rad]."""

    def __init__(self, translation=None, yaw=None, description=""):
        self.translation = translation or (lambda t: np.zeros((np.size(t), 3)))
        self.yaw = yaw or (lambda t: np.zeros(np.size(t)))
        self.description = description


class LaserTracker:
    def __init__(self, rotation, origin_m, u95_constant_m=8e-6, u95_per_m=4e-6, noise="gaussian", dof=4.0,
                 warmup=None, refraction=None, drift=None):
        self.R0, self.T0 = np.asarray(rotation), np.asarray(origin_m, dtype=float)
        self.u95_a, self.u95_b = u95_constant_m, u95_per_m
        self.noise, self.dof = noise, dof
        self.warmup, self.refraction, self.drift = warmup, refraction, drift

    def pose_at(self, t):
        """(R (N,3,3), T (N,3)): p_table = R·p_tracker + T at each instant."""
        n = np.size(t)
        R = np.repeat(self.R0[None], n, axis=0)
        T = np.repeat(self.T0[None], n, axis=0)
        if self.drift is not None:
            yaw = np.asarray(self.drift.yaw(t), dtype=float)
            c, s = np.cos(yaw), np.sin(yaw)
            Rz = np.zeros((n, 3, 3))
            Rz[:, 0, 0], Rz[:, 0, 1], Rz[:, 1, 0], Rz[:, 1, 1], Rz[:, 2, 2] = c, -s, s, c, 1.0
            R = R @ Rz                                      # turning about its own standing axis
            T = T + self.drift.translation(t)
        return R, T

    def measure(self, p_table, t, rng, noiseless=False):
        """Reported Cartesian coordinates in the tracker frame [m] and U95 [m] of the points
        p_table (N,3) of the table frame at times t (s since the job's start)."""
        R, T = self.pose_at(t)
        p = np.einsum("nji,nj->ni", R, p_table - T)      # Rᵀ·(p − T)
        rho = np.linalg.norm(p, axis=1)
        azimuth = np.arctan2(p[:, 1], p[:, 0])
        elevation = np.arctan2(p[:, 2], np.hypot(p[:, 0], p[:, 1]))
        reported_rho = rho.copy()
        if self.refraction is not None:
            reported_rho = reported_rho * (1.0 + self.refraction.scale(t))
        if self.warmup is not None:
            reported_rho = reported_rho + self.warmup.range_error(t)
        direction = np.stack([np.cos(elevation) * np.cos(azimuth), np.cos(elevation) * np.sin(azimuth), np.sin(elevation)], axis=1)
        u95 = self.u95_a + self.u95_b * rho
        sigma = u95 / 2.0
        if noiseless:
            z = np.zeros(p.shape)
        elif self.noise == "student_t":
            # unit-variance Student t: heavy tails at the stated σ
            z = rng.standard_t(self.dof, size=p.shape) / np.sqrt(self.dof / (self.dof - 2.0))
        else:
            z = rng.normal(size=p.shape)
        reported = direction * reported_rho[:, None] + z * sigma[:, None]
        return reported, u95, rho

    def without_errors(self):
        """The same tracker, standing still, with a perfect range: the reference for how big
        an effect is."""
        return LaserTracker(self.R0, self.T0, self.u95_a, self.u95_b, self.noise, self.dof)

    def truth(self):
        rx, ry, rz = _euler_of(self.R0)
        return {"origin_in_table_m": self.T0.tolist(), "rotation_xyz_rad": [rx, ry, rz],
                "convention": "p_table = R p_tracker + T, R = Rz Ry Rx",
                "noise": {"u95_constant_m": self.u95_a, "u95_per_m": self.u95_b, "distribution": self.noise,
                          "dof": self.dof if self.noise == "student_t" else None,
                          "sigma_per_coordinate": "U95/2, isotropic"}}


def _euler_of(R):
    ry = -np.arcsin(R[2, 0])
    rx = np.arctan2(R[2, 1], R[2, 2])
    rz = np.arctan2(R[1, 0], R[0, 0])
    return float(rx), float(ry), float(rz)
