"""Checks of the generator's physics against independent statements of it (run:
`.venv/bin/python -m unittest discover -s bags/independent/robot -p 'test_*.py'`)."""

import os
import sys
import tempfile
import unittest

import numpy as np

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))

from accelerometer import readings  # noqa: E402
from column_bending import column_deflection, effective_compliance  # noqa: E402
from gravity import G, gravity_in_base, joint_gravity_torque  # noqa: E402
from hidden_truth import draw_robot_truth  # noqa: E402
from pose_fit import levelled_pose, levelled_prediction  # noqa: E402
from robot_description import ARM_JOINTS, COLUMN, urdf_text  # noqa: E402
from rotations import rot_z, tilt_matrix  # noqa: E402
from total_station import Setup, polar_to_local  # noqa: E402
from true_robot import nominal_prism, true_state  # noqa: E402
from urdf_chain import Urdf  # noqa: E402


def robot():
    d = tempfile.mkdtemp()
    path = os.path.join(d, "robot.urdf")
    with open(path, "w") as f:
        f.write(urdf_text())
    return Urdf(path)


def poses(rng, n):
    q = {"column_lower": rng.uniform(0, 0.6, n)}
    for j in ARM_JOINTS:
        q[j] = rng.uniform(-np.pi, np.pi, n)
    return q


def potential(urdf, q, g_base, delta=None):
    """V = −Σ m_i g·c_i over every link."""
    frames, _ = urdf.forward(urdf.full_joint_values(q), joint_delta=delta)
    c = urdf.centres_of_mass(frames, list(urdf.links))
    return -sum(urdf.links[l]["mass"] * (c[l] @ g_base) for l in urdf.links)


class Physics(unittest.TestCase):
    @classmethod
    def setUpClass(cls):
        cls.urdf = robot()
        cls.rng = np.random.default_rng(7)

    def test_mimic_column_grows_twice_the_joint(self):
        q = poses(self.rng, 5)
        frames, _ = self.urdf.forward(self.urdf.full_joint_values(q))
        foot = frames["column_outer"][:, 2, 3]
        top = frames["column_top"][:, 2, 3]
        np.testing.assert_allclose(top - foot, COLUMN["inner_to_top_m"] + 2 * q["column_lower"], atol=1e-12)

    def test_gravity_torque_is_minus_dV_dq(self):
        q = poses(self.rng, 6)
        g = gravity_in_base(0.01, -0.012)
        frames, jf = self.urdf.forward(self.urdf.full_joint_values(q))
        for j in ARM_JOINTS:
            tau = joint_gravity_torque(self.urdf, frames, jf, j, g)
            h = 1e-6
            dV = (potential(self.urdf, q, g, {j: h}) - potential(self.urdf, q, g, {j: -h})) / (2 * h)
            np.testing.assert_allclose(tau, -dV, atol=1e-5, err_msg=j)

    def test_deflections_lower_the_potential_energy(self):
        """Gravity does positive work on every yield: the deflected robot's V is lower."""
        rng = np.random.default_rng(3)
        truth = draw_robot_truth(rng)
        q = poses(rng, 50)
        g = gravity_in_base(0.0, 0.0)
        for effect in ("joint_compliance", "column_bending"):
            s = true_state(self.urdf, q, np.full(50, 20.0), (0.0, 0.0), truth, effects={effect})
            c = self.urdf.centres_of_mass(s["frames"], list(self.urdf.links))
            V1 = -sum(self.urdf.links[l]["mass"] * (c[l] @ g) for l in self.urdf.links)
            V0 = potential(self.urdf, q, g)
            self.assertTrue(np.all(V1 < V0 + 1e-9), effect)

    def test_column_bends_toward_the_reach(self):
        """The arm stretched along +x: the column top tilts about +y and shifts toward +x (and a
        little about −x: the wrist stands 0.16 m off to +y)."""
        q = {"column_lower": np.array([0.3])}
        for j in ARM_JOINTS:
            q[j] = np.zeros(1)
        truth = draw_robot_truth(np.random.default_rng(1))
        frames, _ = self.urdf.forward(self.urdf.full_joint_values(q))
        D, info = column_deflection(self.urdf, frames, q["column_lower"], gravity_in_base(0, 0), truth["column"])
        self.assertGreater(info["tilt_rad"][0, 1], 0.0)
        self.assertGreater(info["shift_m"][0, 0], 0.0)
        self.assertLess(info["tilt_rad"][0, 0], 0.0)
        self.assertLess(abs(info["tilt_rad"][0, 0]), 0.4 * info["tilt_rad"][0, 1])

    def test_column_compliance_grows_with_extension(self):
        truth = draw_robot_truth(np.random.default_rng(1))
        c = effective_compliance(np.array([0.0, 0.3, 0.6]), truth["column"])
        self.assertTrue(np.all(np.diff(c["tilt_rad_per_Nm"]) > 0))
        self.assertGreater(c["overlap1_rad_per_Nm"][2] / c["overlap1_rad_per_Nm"][0], 15.0)

    def test_level_accelerometer_reads_plus_g_up(self):
        truth = {"misalignment_rotvec_rad": [0, 0, 0], "bias_m_per_s2": [0, 0, 0], "noise_m_per_s2": 0.0}
        r = readings(np.eye(3)[None], gravity_in_base(0, 0), truth, None)
        np.testing.assert_allclose(r[0], [0, 0, G], atol=1e-12)
        # nose down (pitch > 0): gravity has a +x part in the base, the specific force a −x part
        r = readings(np.eye(3)[None], gravity_in_base(0, 0.01), truth, None)
        self.assertLess(r[0, 0], -0.09)

    def test_tip_accelerometer_turned_90_degrees(self):
        """The tip sensor is mounted turned +90° about z: its x reads the base's y."""
        q = poses(self.rng, 3)
        truth = {"misalignment_rotvec_rad": [0, 0, 0], "bias_m_per_s2": [0, 0, 0], "noise_m_per_s2": 0.0}
        robot_truth = draw_robot_truth(np.random.default_rng(2))
        s = true_state(self.urdf, q, np.full(3, 20.0), (0.004, 0.01), robot_truth, effects=set())
        r = readings(s["frames"]["column_tip_imu"][:, :3, :3], s["g_base"], truth, None)
        f_base = -s["g_base"]
        np.testing.assert_allclose(r[:, 0], f_base[1], atol=1e-9)
        np.testing.assert_allclose(r[:, 1], -f_base[0], atol=1e-9)

    def test_total_station_coordinates(self):
        s = Setup("S", [5.0, 1.0, 1.5], 0.7, [3e-5, -2e-5])
        p = np.array([[0.3, 0.2, 1.8], [-0.5, 0.9, 0.4]])
        obs = s.observe(p, None, noiseless=True)
        np.testing.assert_allclose(obs["xyz"], s.to_instrument(p), atol=1e-12)
        np.testing.assert_allclose(polar_to_local(obs["hz"], obs["v"], obs["sd"]), obs["xyz"], atol=1e-12)
        self.assertTrue(np.all((obs["u"] > 6e-4) & (obs["u"] < 9e-4)))

    def test_levelled_pose_recovers_the_setup(self):
        rng = np.random.default_rng(5)
        s = Setup("S", [4.0, -3.0, 1.6], 2.5, [0.0, 0.0])      # the prior holds a tilt at 0
        p = rng.uniform(-1, 1, (20, 3)) + [0, 0, 1.5]
        obs = s.observe(p, None, noiseless=True)
        x = levelled_pose(p, obs["xyz"], np.full((20, 3), 7e-4))
        np.testing.assert_allclose(levelled_prediction(x, p), obs["xyz"], atol=1e-6)
        self.assertAlmostEqual(x[0] % (2 * np.pi), 2.5, places=5)

    def test_tilt_convention(self):
        """R_WB = Rx(roll)·Ry(pitch) and g_B = R_WBᵀ·(0, 0, −g)."""
        g = gravity_in_base(0.02, -0.03)
        np.testing.assert_allclose(tilt_matrix(0.02, -0.03) @ g, [0, 0, -G], atol=1e-12)
        np.testing.assert_allclose(rot_z(0.3) @ rot_z(-0.3), np.eye(3), atol=1e-15)

    def test_rigid_urdf_is_the_truth_without_effects(self):
        q = poses(self.rng, 8)
        truth = draw_robot_truth(np.random.default_rng(2))
        s = true_state(self.urdf, q, np.full(8, 20.0), (0.01, 0.0), truth, effects=set())
        np.testing.assert_allclose(s["prism"], nominal_prism(self.urdf, q), atol=1e-12)


if __name__ == "__main__":
    unittest.main()
