"""How the crumple study saves its stages and prices its cases.

A stage run for some cases keeps the cases saved before it: stages are re-run for a few cases
at a time and run side by side (a long reference level beside a short one), each writing
crumple.json when it ends. Catches a save that replaces a stage's whole entry with what one run
computed: the other run's cases would vanish.
"""
import sys
import tempfile
import unittest
from pathlib import Path
from unittest import mock

ROOT = Path(__file__).resolve().parents[2]
sys.path.insert(0, str(ROOT / "scripts"))
import crumple_study  # noqa: E402


class MergeResult(unittest.TestCase):
    def saved(self, *stages):
        with tempfile.TemporaryDirectory() as d, mock.patch.object(crumple_study, "OUT", d):
            for stage, result in stages:
                crumple_study.merge_result(stage, result)
            return crumple_study.load_result()

    def test_nested_cases_are_merged(self):
        data = self.saved(("converge", {"seeds": 8, "cases": {"N32": {"levels": {"1": 1}}}}),
                          ("converge", {"seeds": 8, "cases": {"N256": {"levels": {"2": 2}}}}),
                          ("converge", {"seeds": 8, "cases": {"N32": {"levels": {"4": 4}}}}))
        self.assertEqual(data["converge"]["cases"], {"N32": {"levels": {"4": 4}}, "N256": {"levels": {"2": 2}}})
        self.assertEqual(data["converge"]["seeds"], 8)

    def test_top_level_cases_are_merged_and_other_stages_kept(self):
        data = self.saved(("pareto", {"N64_k1e4": 1}), ("timing", {"N64": {"paper/S1": 2.0}}),
                          ("pareto", {"N128_k1e4": 2}), ("pareto", {"N64_k1e4": 3}))
        self.assertEqual(data["pareto"], {"N64_k1e4": 3, "N128_k1e4": 2})
        self.assertEqual(data["timing"], {"N64": {"paper/S1": 2.0}})


class TimingOfACase(unittest.TestCase):
    """A case's cost comes from the timing of its own grid size and stiffness: at kappa 1e5 the
    default takes more substeps and the crumple other events. Catches costs looked up by grid
    size alone (kappa 1e5 points priced at kappa 1e4)."""

    def test_each_stiffness_has_its_own_timing(self):
        row = {"method": "default", "substeps": 64, "error": {"max": 0.05}}
        data = {"pareto": {label: {"methods": {"default/S64": row}} for label in ("N64_k1e4", "N64_k1e5")},
                "timing": {"N64": {"default/S64": {"ms_frame": 60.0}}, "N64_k1e5": {"default/S64": {"ms_frame": 150.0}}}}
        self.assertEqual(crumple_study.pareto_points(data, "N64_k1e4")[0][3], 60.0)
        self.assertEqual(crumple_study.pareto_points(data, "N64_k1e5")[0][3], 150.0)


if __name__ == "__main__":
    unittest.main()
