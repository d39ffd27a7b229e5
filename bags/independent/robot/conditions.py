"""The seven grounds the robot was recorded on.

Tilt of the chassis relative to the level (roll about base x, pitch about base y), and the air:
indoors 21 °C, outdoors 9 °C (the links 12 K colder). Per seed each tilt gets ±10 % and, where
the direction is not set by how the chassis stands (flat, pallet, outdoors), a random direction.
"""

from dataclasses import dataclass

import numpy as np


@dataclass
class Condition:
    key: str
    description: str
    tilt_mrad: float               # magnitude
    direction_deg: float = None    # of the down-slope in the base frame; None: random per seed
    ambient_c: float = 21.0
    outdoors: bool = False


CONDITIONS = [
    Condition("flat_floor", "flat shop floor (the calibration recording)", 0.2),
    Condition("pallet", "chassis standing on a wooden pallet", 3.0),
    Condition("slabs_one_track", "concrete slabs under the left track only: a roll", 8.0, 270.0),
    Condition("seesaw_forward", "on a seesaw tilted nose down", 15.0, 0.0),
    Condition("seesaw_backward", "on a seesaw tilted nose up", 15.0, 180.0),
    Condition("outdoors_cold", "outdoors on asphalt at 9 °C (21 °C indoors)", 1.0, None, 9.0, True),
    Condition("ramp_diagonal", "on a loading ramp, turned across it: roll and pitch", 11.0, 150.0),
]
SAMPLE = ("flat_floor", "seesaw_forward")
CALIBRATION = "flat_floor"


def tilt_of(condition, rng):
    """(roll, pitch) [rad]: the chassis tilted so its down-slope points along the direction
    θ in the base's xy plane. A base whose +x points down-slope has gravity's horizontal part
    along +x in the base frame: g_B ≈ g·(sin(pitch)·…) — with R_WB = Rx(roll)·Ry(pitch),
    g_B = R_WBᵀ(0, 0, −g) ≈ g·(pitch, −roll, −1), so pitch = t·cos θ, roll = −t·sin θ."""
    t = condition.tilt_mrad * 1e-3 * rng.uniform(0.9, 1.1)
    theta = np.radians(condition.direction_deg) if condition.direction_deg is not None else rng.uniform(0, 2 * np.pi)
    return float(-t * np.sin(theta)), float(t * np.cos(theta))
