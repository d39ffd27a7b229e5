"""Refractive index of air, as a laser tracker's software computes it from a weather reading.

The modified Edlén equation of Birch & Downs (Metrologia 30 (1993) 155, corrected in
Metrologia 31 (1994) 315). Written here from the published equations, not from metrocell.

A tracker's range comes from an optical path: the ADM (or interferometer) measures n·D, and the
software divides by the index n_used it computed from the air it was given. The geometric
distance D therefore comes out as D·n_true/n_used: the range error is D·(n_true/n_used − 1).
"""

import numpy as np

#: Vacuum wavelength of a HeNe tracker interferometer [µm]; an ADM's ~800 nm changes the
#: ratios used here by < 0.5 %.
WAVELENGTH_UM = 0.633

#: The "standard air" many trackers default to when no station reading is entered.
STANDARD_AIR = {"temperature_c": 20.0, "pressure_pa": 101325.0, "humidity_rh": 0.5}


def saturation_vapour_pressure_pa(temperature_c):
    """Saturation vapour pressure over water [Pa] (Magnus form, Sonntag 1990 constants):
    accurate to ~0.1 % at 10–30 °C, far below what matters to the index (water shifts n by
    ~0.4 ppm per kPa of vapour)."""
    t = np.asarray(temperature_c, dtype=float)
    return 611.2 * np.exp(17.62 * t / (243.12 + t))


def refractive_index(temperature_c, pressure_pa, humidity_rh, wavelength_um=WAVELENGTH_UM):
    """Phase refractive index of moist air (Birch & Downs 1993/1994).

    temperature_c [°C], pressure_pa [Pa], humidity_rh relative humidity 0..1.
    """
    t = np.asarray(temperature_c, dtype=float)
    p = np.asarray(pressure_pa, dtype=float)
    s2 = (1.0 / wavelength_um) ** 2                       # σ², σ the vacuum wavenumber [µm⁻¹]
    # dispersion of standard air (15 °C, 101 325 Pa, dry, 450 ppm CO2): (n − 1)_s × 1e8
    ns_minus_1 = (8342.54 + 2406147.0 / (130.0 - s2) + 15998.0 / (38.9 - s2)) * 1e-8
    # density of dry air at t, p (B&D 1993 eq. 2)
    ntp_minus_1 = p * ns_minus_1 / 96095.43 * (1.0 + 1e-8 * (0.601 - 0.00972 * t) * p) / (1.0 + 0.003661 * t)
    # water vapour lowers the index (B&D 1994 correction, f = partial pressure of water [Pa])
    f = np.asarray(humidity_rh, dtype=float) * saturation_vapour_pressure_pa(t)
    return 1.0 + ntp_minus_1 - f * (3.7345 - 0.0401 * s2) * 1e-10


def range_scale_error(true_air, used_air):
    """n_true/n_used − 1: the relative range error of a tracker that computed its index from
    `used_air` while the beam travelled through `true_air` (dicts of temperature_c,
    pressure_pa, humidity_rh; arrays broadcast)."""
    n_true = refractive_index(true_air["temperature_c"], true_air["pressure_pa"], true_air["humidity_rh"])
    n_used = refractive_index(used_air["temperature_c"], used_air["pressure_pa"], used_air["humidity_rh"])
    return n_true / n_used - 1.0
