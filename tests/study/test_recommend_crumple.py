"""recommend.py's crumple scene and the crumple study's Pareto helpers on a synthetic study.

The synthetic crumple.json has, for case N64_k1e4, configurations whose costs and errors are
chosen so that each wrong rule picks a different one: the most accurate (not the cheapest within
the budget), the cheapest overall (not within the budget), one without a timing, and a failed one.
"""
import json
import subprocess
import sys
import tempfile
import unittest
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]
sys.path.insert(0, str(ROOT / "scripts"))
import crumple_study  # noqa: E402

RECOMMEND = [sys.executable, str(ROOT / "scripts" / "recommend.py")]


def row(method, s, err):
    return {"method": method, "backend": "fast", "substeps": s, "summary": {},
            **({"error": {"max": err, "per_stat": {}, "noise": {}}} if err is not None else {})}


def timed(ms, args):
    return {"ms_frame": ms, "rounds": [ms], "args": args}


STUDY = {
    "pareto": {"N64_k1e4": {"reference_substeps": 256,
                            "reference": {s: {"mean": 1.0, "sd": 0.02} for s in crumple_study.ERROR_STATS},
                            "methods": {
                                "paper/S1": row("paper", 1, 1.40),           # cheapest overall, far off
                                "explicit-F/S32": row("explicit-F", 32, 0.09),  # cheapest within 10 %
                                "explicit/S64": row("explicit", 64, 0.03),   # most accurate, dearer
                                "explicit-F/S16": row("explicit-F", 16, 0.11),  # just outside 10 %
                                "xpbd/S4": row("xpbd", 4, 0.05),             # within, but never timed
                                "approx-K1/S4": row("approx-K1", 4, None),   # failed
                            }}},
    "timing": {"machine": "test machine", "commit": "abc",
               "N64": {"paper/S1": timed(2.0, ["--grid", "64", "--seed", "1", "--integrator", "approx"]),
                       "explicit-F/S32": timed(30.0, ["--grid", "64", "--seed", "1", "--substeps", "32"]),
                       "explicit/S64": timed(90.0, ["--grid", "64", "--seed", "1", "--substeps", "64"]),
                       "explicit-F/S16": timed(15.0, ["--grid", "64", "--seed", "1", "--substeps", "16"]),
                       "approx-K1/S4": timed(10.0, ["--grid", "64", "--seed", "1"])}},
}


class Helpers(unittest.TestCase):
    def test_front_and_cheapest(self):
        points = crumple_study.pareto_points(STUDY, "N64_k1e4")
        self.assertEqual([p[0] for p in points], ["paper/S1", "explicit-F/S16", "explicit-F/S32", "explicit/S64"])
        self.assertEqual([p[0] for p in crumple_study.pareto_front(points)],
                         ["paper/S1", "explicit-F/S16", "explicit-F/S32", "explicit/S64"])
        self.assertEqual(crumple_study.cheapest_within(points)[0], "explicit-F/S32")
        self.assertEqual(crumple_study.cheapest_within(points, 0.05)[0], "explicit/S64")
        self.assertIsNone(crumple_study.cheapest_within(points, 0.01))

    def test_front_drops_dominated(self):
        points = [("a", "m", 1, 1.0, 0.5), ("b", "m", 2, 2.0, 0.6), ("c", "m", 4, 3.0, 0.1)]
        self.assertEqual([p[0] for p in crumple_study.pareto_front(points)], ["a", "c"])


class Command(unittest.TestCase):
    def run_recommend(self, *args):
        with tempfile.TemporaryDirectory() as d:
            path = Path(d) / "crumple.json"
            path.write_text(json.dumps(STUDY))
            return subprocess.run(RECOMMEND + ["--scene", "crumple", "--table", str(path)] + list(args),
                                  capture_output=True, text=True)

    def test_cheapest_within_budget(self):
        p = self.run_recommend("--grid", "64", "--kappa", "1e4", "--error", "0.1", "--json")
        self.assertEqual(p.returncode, 0, p.stderr)
        out = json.loads(p.stdout)
        self.assertEqual(out["recommendation"]["configuration"], "explicit-F/S32")
        # the study runs every command line from the --paper base (crumple_stats)
        self.assertEqual(out["recommendation"]["crumple_options"], "--paper --grid 64 --substeps 32")
        self.assertFalse(out["recommendation"]["fits_60fps"])
        self.assertEqual([a["configuration"] for a in out["alternatives"]], ["explicit/S64"])

    def test_no_configuration_meets_budget(self):
        p = self.run_recommend("--grid", "64", "--kappa", "1e4", "--error", "0.01")
        self.assertEqual(p.returncode, 1)
        self.assertIn("most accurate: explicit/S64", p.stdout)

    def test_says_whether_the_reference_converged(self):
        # Catches a recommendation that presents errors against an unconverged level (the
        # provisional N = 256 reference) as errors against the converged crumple.
        p = self.run_recommend("--grid", "64", "--kappa", "1e4", "--error", "0.1")
        self.assertIn("against the S = 256 level: the finest run so far, not converged", p.stdout)
        STUDY["converge"] = {"cases": {"N64_k1e4": {"converged_at": 256, "levels": {"256": {}}}}}
        try:
            p = self.run_recommend("--grid", "64", "--kappa", "1e4", "--error", "0.1", "--json")
        finally:
            del STUDY["converge"]
        self.assertEqual(json.loads(p.stdout)["reference"], {"substeps": 256, "converged": True})

    def test_unstudied_case_is_an_error(self):
        p = self.run_recommend("--grid", "512", "--kappa", "1e4", "--error", "0.1")
        self.assertEqual(p.returncode, 2)
        self.assertIn("no case N512_k1e4", p.stderr)
        self.assertEqual(p.stderr.count("\n"), 1)


if __name__ == "__main__":
    unittest.main()
