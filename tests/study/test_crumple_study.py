"""How the crumple study saves its stages and prices its cases.

A stage run for some cases keeps the cases saved before it: stages are re-run for a few cases
at a time and run side by side (a long reference level beside a short one), each writing
crumple.json when it ends. Catches a save that replaces a stage's whole entry with what one run
computed: the other run's cases would vanish.
"""
import contextlib
import io
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



class ConvergenceRule(unittest.TestCase):
    """The rule that ends a converge case: every mean moves by less than its seed spread; with a
    move floor (N = 256), each compared statistic by less than its spread or the floor. Catches a
    floor that leaks into the strict cases, one that also admits moves above it, and the
    uncompared final kinetic energy blocking a floored case."""

    @staticmethod
    def level(**moves):
        out = {s: {"mean": 100.0 * (1 + moves.get(s, 0.0)), "sd": 0.1} for s in crumple_study.STATS}
        return out

    def test_strict_rule_wants_moves_below_the_spread(self):
        a = self.level()
        self.assertTrue(crumple_study.moved_within_spread(a, self.level(splits=0.0005)))
        self.assertFalse(crumple_study.moved_within_spread(a, self.level(splits=0.005)))
        self.assertFalse(crumple_study.moved_within_spread(a, self.level(kinetic_end=0.005)))

    def test_floor_admits_small_moves_of_the_compared_statistics_only(self):
        a = self.level()
        self.assertTrue(crumple_study.moved_within_spread(a, self.level(splits=0.005, vertices=-0.009), 0.01))
        self.assertFalse(crumple_study.moved_within_spread(a, self.level(vertices=0.012), 0.01))
        self.assertTrue(crumple_study.moved_within_spread(a, self.level(kinetic_end=0.1), 0.01))


class ConvergencePhrase(unittest.TestCase):
    """Tables and charts name the level the errors are measured against. Catches a case that has
    not converged printed as "converged at S = None", or its reference named by the first level
    (levels sort as strings: "64" < "8") instead of the finest one run."""

    def test_unconverged_case_names_its_finest_level(self):
        case = {"converged_at": None, "levels": {"1": {}, "8": {}, "64": {}, "16": {}}}
        for short in (False, True):
            phrase = crumple_study.convergence_phrase(case, short)
            self.assertIn("not converged", phrase)
            self.assertTrue(phrase.endswith("S = 64"), phrase)

    def test_converged_case_names_where(self):
        case = {"converged_at": 256, "levels": {"128": {}, "256": {}, "512": {}}}
        self.assertEqual(crumple_study.convergence_phrase(case), "converged at S = 256")


class ParetoMethods(unittest.TestCase):
    """pareto --methods runs only the named methods and keeps every other method whose runs are
    all cached (recomputed against the current reference). Catches a filter that runs the others
    anyway (hours of runs at N = 256) or that drops their cached rows from the case."""

    class FakeRunner:
        def __init__(self, cached_methods):
            self.cached_methods, self.ran = cached_methods, []

        @staticmethod
        def method_of(lines):
            return " ".join(str(a) for a in lines[0])

        def cached(self, lines):
            return any(m in self.method_of(lines) for m in self.cached_methods)

        def run(self, lines):
            if not self.cached(lines):
                self.ran.append(self.method_of(lines))
            return [{"exit": 0, **{s: 1.0 + 0.01 * k for s in crumple_study.STATS}} for k in range(len(lines))]

    def test_only_named_methods_run_and_cached_ones_stay(self):
        ref = {s: {"mean": 1.0, "sd": 0.01} for s in crumple_study.STATS}
        runner = self.FakeRunner(cached_methods=["--integrator approx --grid"])  # the paper's step
        with mock.patch.object(crumple_study, "reference_level", return_value=(64, ref)):
            result = crumple_study.stage_pareto(runner, False, ["N64_k1e4"], methods=["xpbd"])
        rows = result["N64_k1e4"]["methods"]
        self.assertTrue(runner.ran)
        self.assertTrue(all("--integrator xpbd" in r for r in runner.ran), runner.ran)
        self.assertEqual({r["method"] for r in rows.values()}, {"xpbd", "paper"})
        self.assertAlmostEqual(rows["paper/S1"]["error"]["max"], 0.035)


class SeriesChart(unittest.TestCase):
    """The report's kinetic-energy and facet chart reads the cache only: a configuration whose
    seeds are not all cached is left out, never run (the report stage must not start hour-long
    crumples). Catches a chart that runs what is missing, or that finds none of the stages' runs
    (its command lines differing from the ones the pareto and converge stages cache)."""

    def test_cached_configurations_only(self):
        ref = {s: {"mean": 1.0, "sd": 0.01} for s in crumple_study.STATS}
        stage_keys = set()

        class Recorder:  # what the stages run for N64_k1e4: the cache of the fake runner below
            def cached(self, lines):
                return False  # so that pareto runs only the named methods

            def run(self, lines):
                stage_keys.update(" ".join(str(a) for a in args) for args in lines)
                return [{"exit": 0, **{s: 1.0 for s in crumple_study.STATS}} for _ in lines]

        with mock.patch.object(crumple_study, "reference_level", return_value=(256, ref)), \
                contextlib.redirect_stdout(io.StringIO()):
            crumple_study.stage_pareto(Recorder(), False, ["N64_k1e4"], methods=["paper", "default"])
        with mock.patch.object(crumple_study, "CONVERGE_CASES",
                               [("N64_k1e4", ["--grid", 64], 1e4, [256], 256, 0.0)]), \
                contextlib.redirect_stdout(io.StringIO()):
            crumple_study.stage_converge(Recorder(), False, ["N64_k1e4"])

        runner = ParetoMethods.FakeRunner(cached_methods=[])
        runner.cached = lambda lines: all(" ".join(str(a) for a in args) in stage_keys for args in lines)
        charted = {}
        with mock.patch.object(crumple_study, "reference_level", return_value=(256, ref)), \
                mock.patch("crumple_series.chart", side_effect=lambda groups, *_: charted.update(groups)):
            crumple_study.chart_series(runner, "N64_k1e4", "unused.png")
        self.assertEqual(runner.ran, [])
        self.assertEqual(set(charted), {"paper's step (S = 1)", "default", "converged (S = 256)"})


if __name__ == "__main__":
    unittest.main()
