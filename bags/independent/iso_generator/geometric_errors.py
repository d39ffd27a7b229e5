"""ISO 230-1 geometric errors of the linear axes of a 3-axis machine, as displacements of the
tool relative to the workpiece.

Every error here is what ISO 230-1 (2012) calls an error motion or a location error of a linear
axis, evaluated at the commanded axis positions q = (x, y, z) [m] and returned as the
displacement d (N×3, m) of the functional point (the tool-side target) relative to the
workpiece, "actual minus commanded" (ISO 230-1 3.4: the deviation of the actual from the
nominal relative position). That is the quantity a tracker standing on the table sees, so it
does not matter that the X axis moves the table and Y, Z move the tool: the relative
displacement is the same.

Coordinates u = (q − q_min)/(q_max − q_min) ∈ [0, 1] are used only to state shapes.
"""

import numpy as np

AXES = "xyz"


def _unit(u):
    return np.clip(u, 0.0, 1.0)


def bow_shape(u):
    """Symmetric bow, 0 at both ends and 1 at mid-travel."""
    return 4.0 * u * (1.0 - u)


def s_shape(u):
    """Antisymmetric cubic wave, 0 at both ends and mid-travel, peak ±1 at u ≈ 0.21 / 0.79."""
    peak = (3 - np.sqrt(3)) / 6
    return u * (1.0 - u) * (1.0 - 2.0 * u) / (peak * (1 - peak) * (1 - 2 * peak))


class PositioningError:
    """E_XX, E_YY, E_ZZ (ISO 230-1 3.4.4 / ISO 230-2): the error of the axis along its own
    direction, a smooth function of the position. `progressive` is the scale-like part
    (µm/m × q, e.g. a screw-lead or scale error), `bow` a symmetric non-linear part (peak at
    mid-travel), `wave` an antisymmetric cubic one (e.g. a worn screw)."""

    kind = "positioning"

    def __init__(self, axis, travel, progressive_per_m=0.0, bow_m=0.0, wave_m=0.0):
        self.axis, self.k = axis, AXES.index(axis)
        self.travel = tuple(travel)
        self.progressive_per_m, self.bow_m, self.wave_m = progressive_per_m, bow_m, wave_m

    def along_axis(self, q_axis):
        u = _unit((q_axis - self.travel[0]) / (self.travel[1] - self.travel[0]))
        return self.progressive_per_m * (q_axis - self.travel[0]) + self.bow_m * bow_shape(u) + self.wave_m * s_shape(u)

    def displacement(self, ctx):
        d = np.zeros_like(ctx.q)
        d[:, self.k] = self.along_axis(ctx.q[:, self.k])
        return d

    def truth(self):
        return {"iso": f"E_{self.axis.upper()}{self.axis.upper()}", "axis": self.axis, "travel_m": list(self.travel),
                "progressive_m_per_m": self.progressive_per_m, "bow_m": self.bow_m, "wave_m": self.wave_m,
                "shape": "E(q) = progressive*(q - q0) + bow*4u(1-u) + wave*s(u), u = (q - q0)/(q1 - q0)"}


class StraightnessError:
    """E_YX, E_ZX, ... (ISO 230-1 3.4.8): the deviation of the moving axis' trajectory in a
    perpendicular direction, measured from the least-squares reference straight line (ISO
    230-1 3.4.10), so its mean and its slope over the travel are zero by definition (a slope is
    a squareness/orientation, not a straightness)."""

    kind = "straightness"

    def __init__(self, axis, direction, travel, bow_m=0.0, wave_m=0.0):
        self.axis, self.direction = axis, direction
        self.k, self.j = AXES.index(axis), AXES.index(direction)
        self.travel = tuple(travel)
        self.bow_m, self.wave_m = bow_m, wave_m
        # the least-squares reference line of the raw shape over the travel (ISO 230-1 3.4.10)
        u = np.linspace(0.0, 1.0, 2001)
        raw = self._raw(u)
        self._line = np.polyfit(u, raw, 1)

    def _raw(self, u):
        return self.bow_m * bow_shape(u) + self.wave_m * s_shape(u)

    def across(self, q_axis):
        u = _unit((q_axis - self.travel[0]) / (self.travel[1] - self.travel[0]))
        return self._raw(u) - np.polyval(self._line, u)

    def displacement(self, ctx):
        d = np.zeros_like(ctx.q)
        d[:, self.j] = self.across(ctx.q[:, self.k])
        return d

    def truth(self):
        return {"iso": f"E_{self.direction.upper()}{self.axis.upper()}", "axis": self.axis, "direction": self.direction,
                "travel_m": list(self.travel), "bow_m": self.bow_m, "wave_m": self.wave_m,
                "shape": "bow*4u(1-u) + wave*s(u) minus its least-squares line over the travel"}


class SquarenessError:
    """Squareness as an ISO 230-1 location error (3.5.2): the orientation of an axis' average
    line, a rotation by a small angle about a coordinate axis, positive by the right-hand rule.

    The reference is the Z axis first and then Y (this standard allows choosing the reference;
    we state ours):
      EC0X  X's average line turned about +Z: moving x adds (0, +ε·x, 0)
      EB0X  X's average line turned about +Y: moving x adds (0, 0, −ε·x)
      EA0Y  Y's average line turned about +X: moving y adds (0, 0, +ε·y)
    i.e. the direction of the turned axis is R(ε)·e_axis, and d = (R(ε) − I)·e_axis·q.
    """

    kind = "squareness"
    _SPEC = {"EC0X": ("x", 2), "EB0X": ("x", 1), "EA0Y": ("y", 0)}

    def __init__(self, name, angle_rad):
        self.name, self.angle = name, angle_rad
        self.axis, self.about = self._SPEC[name]

    def displacement(self, ctx):
        k = AXES.index(self.axis)
        e_axis = np.zeros(3)
        e_axis[k] = 1.0
        omega = np.zeros(3)
        omega[self.about] = self.angle
        turned = np.cross(omega, e_axis)          # first order: (R(ε) − I)·e = ε × e
        return ctx.q[:, [k]] * turned[None, :]

    def truth(self):
        return {"iso": self.name, "angle_rad": self.angle, "axis": self.axis, "about": AXES[self.about],
                "convention": "rotation of the axis' average line about the named axis, right-hand positive; reference Z then Y"}


class PeriodicScrewError:
    """The periodic part of E_XX of a ball-screw axis (ISO 230-2 Annex / ISO 3408-3 "v_2π"):
    the error repeats every screw revolution, i.e. every lead P of travel, from the screw's
    eccentricity and lead wobble. d_axis = A·sin(2π·q/P + φ) (+ an optional second harmonic)."""

    kind = "pitch_cyclic"

    def __init__(self, axis, lead_m, amplitude_m, phase_rad, second_harmonic_m=0.0, second_phase_rad=0.0):
        self.axis, self.k = axis, AXES.index(axis)
        self.lead, self.amplitude, self.phase = lead_m, amplitude_m, phase_rad
        self.second, self.second_phase = second_harmonic_m, second_phase_rad

    def along_axis(self, q_axis):
        w = 2.0 * np.pi * q_axis / self.lead
        return self.amplitude * np.sin(w + self.phase) + self.second * np.sin(2 * w + self.second_phase)

    def displacement(self, ctx):
        d = np.zeros_like(ctx.q)
        d[:, self.k] = self.along_axis(ctx.q[:, self.k])
        return d

    def truth(self):
        return {"iso": f"E_{self.axis.upper()}{self.axis.upper()} periodic", "axis": self.axis, "lead_m": self.lead,
                "amplitude_m": self.amplitude, "phase_rad": self.phase, "second_harmonic_m": self.second,
                "shape": "A*sin(2*pi*q/P + phi)"}


class AngularError:
    """E_AX, E_BX, E_CX, E_AY, … (ISO 230-1 3.4.5–3.4.7: roll, pitch and yaw error motions of a
    linear axis): the small rotation ε(q) of the moving component about the named coordinate axis,
    right-hand positive, a smooth function of its position — here a linear trend plus a symmetric
    bow over the travel. ISO 230-1 3.4.9 (Abbe): the rotation displaces the functional point by
    ε × r, r the vector from the point the component's motion is referred to (its reference
    point) to the functional point. So an angular error is seen through an arm that depends on
    what the component carries and where its reference point sits:

    * `side = "workpiece"`: the component carries the workpiece (XFYZ's X table). The table turns
      under the tool, so the tool relative to the workpiece moves by −ε × (p − c): p the tool
      point in workpiece coordinates (q + tool offset), c the table's reference point in them.
    * `side = "tool"`: the component carries the tool (the column's Y carriage, the Z ram): the
      tool point moves by ε × (p_tool − c), both measured on the tool side from the machine
      zero — for Y the ram's extension (z) and the tool offset are in the arm, for Z only the
      tool offset. `carried` lists the axes whose position lengthens the arm.

    The reference points are where a machine builder would put them (the table's centre, the Y
    carriage's guideway behind the spindle, the ram's guide above the gauge line) — not where a
    model would like them: a reference point elsewhere changes ε × r by ε(q) × constant, which an
    honest model must take up in the axis' straightness and positioning errors.
    """

    kind = "angular"

    def __init__(self, axis, about, travel, side, carried, reference_m, trend_rad=0.0, bow_rad=0.0):
        self.axis, self.about = axis, about
        self.k, self.a = AXES.index(axis), AXES.index(about)
        self.travel = tuple(travel)
        self.side, self.carried = side, list(carried)
        self.reference = np.asarray(reference_m, dtype=float)
        self.trend, self.bow = trend_rad, bow_rad

    def angle(self, q_axis):
        u = _unit((q_axis - self.travel[0]) / (self.travel[1] - self.travel[0]))
        # a trend through the middle of the travel (zero mean: a constant angle is a set-up) and a bow
        return self.trend * (u - 0.5) + self.bow * (bow_shape(u) - 2.0 / 3.0)

    def displacement(self, ctx):
        eps = np.zeros_like(ctx.q)
        eps[:, self.a] = self.angle(ctx.q[:, self.k])
        # the tool offset: one for every reading, or each reading's (a reflector moved between rounds)
        arm = np.broadcast_to(ctx.tool_offset - self.reference, ctx.q.shape).copy()
        for c in self.carried:
            j = AXES.index(c)
            arm[:, j] += ctx.q[:, j]
        d = np.cross(eps, arm)
        return -d if self.side == "workpiece" else d

    def truth(self):
        return {"iso": f"E_{'ABC'[self.a]}{self.axis.upper()}", "axis": self.axis, "about": self.about,
                "side": self.side, "carried": self.carried, "reference_m": self.reference.tolist(),
                "trend_rad": self.trend, "bow_rad": self.bow,
                "shape": "trend*(u - 1/2) + bow*(4u(1-u) - 2/3), u = (q - q0)/(q1 - q0)"}
