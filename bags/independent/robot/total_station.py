"""A total station as it measures a prism, from one setup (one placement on its tripod).

How the instrument works (e.g. Leica/Trimble/Topcon manuals; Uren & Price, *Surveying for
Engineers*): after levelling, its dual-axis compensator corrects the angles for what remains of
the standing axis's tilt, so its frame's z is along gravity up to the compensator's residual
(σ ≈ 5e-5 rad here); it reads the horizontal direction Hz (clockwise from its own zero, which
the user never oriented: the setup's yaw is unknown), the zenith angle V and the slope distance
SD of its EDM (the meteorological correction from the air it was given — the right air here:
no refraction error), and exports local coordinates in its own frame, origin at the trunnion
axis:   E = SD·sin V·sin Hz,   N = SD·sin V·cos Hz,   H = SD·cos V   (x, y, z; mm).

Noise (per measurement, Gaussian): the EDM σ_SD = 0.3 mm + 1.5 ppm·SD, the angles σ = 1"
(ATR on a prism), and the 360° prism's centring/pointing error, σ_c = 0.7 mm isotropic (a
360° prism's centre wanders with its orientation by up to ~2 mm peak; taken as random here) —
about 0.75 mm per axis at 3–8 m. The exported standard uncertainties per axis are the diagonal
of the propagated covariance J·diag(σ_SD², σ_Hz², σ_V²)·Jᵀ + σ_c²·I (the layout has no
off-diagonal terms).

Frames: the site's level frame W (z up, origin on the ground under the robot's base_link);
the instrument frame I of setup s: p_W = R_s·p_I + T_s, R_s = Rz(ψ_s)·Rx(ε_x)·Ry(ε_y).
"""

import numpy as np

from rotations import rot_z, tilt_matrix

ARCSEC = np.pi / (180.0 * 3600.0)
GON = np.pi / 200.0


class Setup:
    def __init__(self, name, origin_w, yaw, residual_tilt, edm_const_m=0.3e-3, edm_ppm=1.5, angle_sigma_rad=1.0 * ARCSEC,
                 centring_sigma_m=0.7e-3):
        self.name = name
        self.T = np.asarray(origin_w, dtype=float)
        self.yaw, self.tilt = float(yaw), np.asarray(residual_tilt, dtype=float)
        self.R = rot_z(self.yaw) @ tilt_matrix(*self.tilt)
        self.edm_const, self.edm_ppm = edm_const_m, edm_ppm
        self.angle_sigma, self.centring_sigma = angle_sigma_rad, centring_sigma_m

    def to_instrument(self, p_w):
        return (p_w - self.T) @ self.R          # Rᵀ·(p − T), row-wise

    def observe(self, p_w, rng, noiseless=False):
        """Measured (Hz, V, SD) [rad, rad, m] of true prism centres p_w (N,3) and the exported
        coordinates (N,3) [m] and standard uncertainties (N,3) [m]."""
        p = self.to_instrument(p_w)
        n = len(p)
        if not noiseless:
            p = p + rng.normal(0.0, self.centring_sigma, (n, 3))
        sd = np.linalg.norm(p, axis=1)
        hz = np.mod(np.arctan2(p[:, 0], p[:, 1]), 2 * np.pi)
        v = np.arctan2(np.hypot(p[:, 0], p[:, 1]), p[:, 2])
        sigma_sd = self.edm_const + self.edm_ppm * 1e-6 * sd
        if not noiseless:
            sd = sd + rng.normal(0.0, 1.0, n) * sigma_sd
            hz = np.mod(hz + rng.normal(0.0, self.angle_sigma, n), 2 * np.pi)
            v = v + rng.normal(0.0, self.angle_sigma, n)
        xyz = polar_to_local(hz, v, sd)
        return {"hz": hz, "v": v, "sd": sd, "xyz": xyz, "u": self.uncertainty(hz, v, sd)}

    def uncertainty(self, hz, v, sd):
        sigma_sd = self.edm_const + self.edm_ppm * 1e-6 * sd
        sh, ch, sv, cv = np.sin(hz), np.cos(hz), np.sin(v), np.cos(v)
        # ∂(E, N, H)/∂(SD, Hz, V)
        J = np.stack([np.stack([sv * sh, sd * sv * ch, sd * cv * sh], -1),
                      np.stack([sv * ch, -sd * sv * sh, sd * cv * ch], -1),
                      np.stack([cv, np.zeros_like(sd), -sd * sv], -1)], -2)
        S = np.zeros((len(sd), 3, 3))
        S[:, 0, 0], S[:, 1, 1], S[:, 2, 2] = sigma_sd ** 2, self.angle_sigma ** 2, self.angle_sigma ** 2
        C = J @ S @ np.transpose(J, (0, 2, 1)) + self.centring_sigma ** 2 * np.eye(3)
        return np.sqrt(np.einsum("nii->ni", C))

    def truth(self):
        return {"name": self.name, "origin_in_site_level_frame_m": self.T.tolist(), "yaw_rad": self.yaw,
                "residual_tilt_rad": self.tilt.tolist(),
                "convention": "p_site = Rz(yaw)·Rx(tilt[0])·Ry(tilt[1])·p_instrument + origin; the site frame is level, "
                              "origin on the ground under base_link; the robot's base frame is p_site = R_tilt(ground)·p_base",
                "noise": {"edm_sigma_m": f"{self.edm_const} + {self.edm_ppm} ppm", "angle_sigma_rad": self.angle_sigma,
                          "centring_sigma_m": self.centring_sigma}}


def polar_to_local(hz, v, sd):
    return np.stack([sd * np.sin(v) * np.sin(hz), sd * np.sin(v) * np.cos(hz), sd * np.cos(v)], axis=1)


def place_setups(rng, n, azimuths, tilt_sigma=5e-5):
    """n setups at 3.5–8 m from the robot in the given directions [rad] from base_link, the
    instrument 1.35–1.75 m above the ground (± 0.1 m of ground relief), yaw anywhere."""
    out = []
    for s in range(n):
        d = rng.uniform(3.5, 8.0)
        a = azimuths[s]
        origin = np.array([d * np.cos(a), d * np.sin(a), rng.uniform(1.35, 1.75) + rng.uniform(-0.1, 0.1)])
        out.append(Setup(f"S{s + 1}", origin, rng.uniform(0, 2 * np.pi), rng.normal(0.0, tilt_sigma, 2)))
    return out
