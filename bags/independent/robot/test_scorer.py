"""The scorer's logic on a fake metrocell (fake_metrocell.py) and on JSON written here (run:
`.venv/bin/python -m unittest discover -s bags/independent/robot -p 'test_*.py'`)."""

import json
import os
import subprocess
import sys
import tempfile
import unittest

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, HERE)

from metrocell_contract import ContractError, parameter_entries, read_check  # noqa: E402
from score_robot_suite import diagnose_verdict  # noqa: E402
from truth_matching import match  # noqa: E402

STATS = {"n": 40, "rms_m": 1e-3, "p50_xy_m": 1e-3, "p95_xy_m": 2e-3, "p95_z_m": 1.5e-3, "max_m": 3e-3}


class Contract(unittest.TestCase):
    def test_check_section_read_in_every_accepted_spelling(self):
        j = {"check": {"rigid": {"all": STATS, "per_setup": [{"setup": "S1", **STATS}]},
                       "fitted": {"overall": STATS, "setups": {"S1": STATS, "S2": STATS}}}}
        c = read_check(j, "test")
        self.assertEqual(c["declared"]["setups"]["S1"]["p95_xy_m"], 2e-3)
        self.assertEqual(sorted(c["fitted"]["setups"]), ["S1", "S2"])

    def test_missing_check_names_the_path(self):
        with self.assertRaisesRegex(ContractError, r"no top-level `check` section.*top-level keys: fit"):
            read_check({"fit": {}}, "test")
        with self.assertRaisesRegex(ContractError, r"check has no `fitted` section"):
            read_check({"check": {"declared": {"overall": STATS}}}, "test")
        bad = dict(STATS)
        del bad["p95_xy_m"]
        with self.assertRaisesRegex(ContractError, r"check.fitted.overall: missing p95_xy_m"):
            read_check({"check": {"declared": {"overall": STATS}, "fitted": {"overall": bad}}}, "test")

    def test_parameters_matched_to_truth(self):
        robot = {"joint_compliance_rad_per_Nm": {"shoulder_lift": 2e-5, "elbow": 1.5e-5},
                 "joint_backlash_rad": {"elbow": 3e-4}, "prism_offset_error_m": [3e-3, -2e-3, 4e-3],
                 "alpha_per_K": {"aluminium": 23e-6}}
        fit = {"terms": [{"label": "joint_compliance[shoulder_pan,shoulder_lift,elbow]",
                          "parameters": {"shoulder_lift": {"value": 2.1e-5, "sigma": 1e-6},
                                         "elbow": {"value": 1.0e-5, "sigma": 1e-6}}},
                         {"label": "tool_offset", "parameters": {"dy": {"value": -2.1e-3, "sigma": 1e-4}}},
                         {"label": "joint_backlash", "parameters": {"b_elbow": {"value": 2.5e-4, "sigma": 1e-4}}}]}
        rows = {(r["term"], r["name"]): r for r in match(parameter_entries(fit), robot)}
        self.assertTrue(rows[("joint_compliance", "shoulder_lift")]["ok"])
        self.assertFalse(rows[("joint_compliance", "elbow")]["ok"])          # 5σ off
        self.assertAlmostEqual(rows[("joint_compliance", "elbow")]["z"], -5.0)
        self.assertTrue(rows[("tool_offset", "y")]["ok"])
        self.assertTrue(rows[("joint_backlash", "elbow")]["ok"])

    def test_diagnose_verdict(self):
        sizes = {"joint_compliance": {"after_pose_rms_in_sigma": 1.3}, "column_bending": {"after_pose_rms_in_sigma": 4.0},
                 "prism_offset": {"after_pose_rms_in_sigma": 5.0}, "joint_backlash": {"after_pose_rms_in_sigma": 0.1},
                 "thermal": {"after_pose_rms_in_sigma": 0.04}}
        v = diagnose_verdict(["column_bending", "accelerometer_alignment", "joint_offset"], sizes)
        self.assertEqual(v["missing"], ["joint_compliance", "tool_offset"])
        self.assertEqual(v["false_claims"], ["joint_offset"])
        self.assertEqual(v["optional"], ["joint_backlash", "link_thermal_expansion"])


class WithFakeMetrocell(unittest.TestCase):
    @classmethod
    def setUpClass(cls):
        cls.suite = tempfile.mkdtemp(prefix="robot_suite_test_")
        subprocess.run([sys.executable, os.path.join(HERE, "generate_robot_suite.py"), "--out", cls.suite, "--seeds", "1",
                        "--sample", "--no-reference-calibration", "--floor-reps", "4"], check=True, capture_output=True)

    def score(self, mode):
        env = dict(os.environ, FAKE_METROCELL=mode, FAKE_ANSWERS=os.path.join(self.suite, "answers.json"))
        out = os.path.join(self.suite, f"results_{mode}.json")
        p = subprocess.run([sys.executable, os.path.join(HERE, "score_robot_suite.py"), "--metrocell",
                            os.path.join(HERE, "fake_metrocell.py"), "--suite", self.suite, "--out", out],
                           capture_output=True, text=True, env=env)
        return p, out

    def test_complete_workflow_passes(self):
        p, out = self.score("complete")
        self.assertEqual(p.returncode, 0, p.stdout + p.stderr)
        self.assertIn("every target met", p.stdout)
        self.assertIn("seesaw_forward", p.stdout)
        with open(out) as f:
            r = json.load(f)
        rows = r["results"]["1"]["rows"]
        self.assertEqual([x["condition"] for x in rows], ["flat_floor", "seesaw_forward"])
        self.assertTrue(all(x["ok"] for x in rows))
        judged = [x for x in r["results"]["1"]["parameters"] if x["judged"]]
        self.assertEqual(len(judged), 9)              # six compliances, three offsets
        self.assertTrue(all(x["ok"] for x in judged))

    def test_missed_target_exits_1(self):
        p, _ = self.score("miss")
        self.assertEqual(p.returncode, 1)
        self.assertIn("FAIL", p.stdout)
        self.assertIn("TARGETS MISSED", p.stdout)

    def test_false_claim_exits_1(self):
        p, _ = self.score("false_claim")
        self.assertEqual(p.returncode, 1)
        self.assertIn("FALSE CLAIMS ['joint_offset']", p.stdout)

    def test_missing_option_exits_2_naming_it(self):
        p, _ = self.score("no_refit")
        self.assertEqual(p.returncode, 2)
        self.assertIn("--refit", p.stderr)
        self.assertIn("issue 27", p.stderr)

    def test_missing_check_section_exits_2_naming_the_path(self):
        p, _ = self.score("no_check")
        self.assertEqual(p.returncode, 2)
        self.assertIn("no top-level `check` section", p.stderr)

    def test_import_refused_exits_2(self):
        p, _ = self.score("bad_import")
        self.assertEqual(p.returncode, 2)
        self.assertIn("imu_frames", p.stderr)

    def test_missing_binary_exits_2(self):
        p = subprocess.run([sys.executable, os.path.join(HERE, "score_robot_suite.py"), "--metrocell", "/nonexistent/metrocell",
                            "--suite", self.suite], capture_output=True, text=True)
        self.assertEqual(p.returncode, 2)
        self.assertIn("not found or not executable", p.stderr)


if __name__ == "__main__":
    unittest.main()
