"""Tests of the regression gate's decision (scripts/gate.py) on synthetic benchmark data.

The compare-style input is made the way the gate makes it: synthetic Google Benchmark JSON per
side (repetitions of a benchmark's real time), merged with gate.merge_runs, and compared by
Google Benchmark's own compare.py code (gbench.report.get_difference_report, the function behind
`compare.py --dump_to_json`), so the tests see compare.py's real output format.
"""
import json
import os
import random
import subprocess
import sys
import tempfile
import unittest
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]
sys.path.insert(0, str(ROOT / "scripts"))
import gate  # noqa: E402

GBENCH = "/usr/share/benchmark"
COMPARE = os.path.join(GBENCH, "compare.py")
sys.path.insert(0, GBENCH)
try:
    from gbench import report as gbench_report  # noqa: E402
except ImportError:  # libbenchmark-tools missing: the compare.py-based tests skip
    gbench_report = None

NAME = "BM_Frame/fast/1/128/manual_time"


def run_json(name, times_ms, errors=()):
    """One crumple_bench run's JSON with one benchmark's repetitions."""
    rows = [{"name": name, "run_name": name, "run_type": "iteration", "repetitions": len(times_ms),
             "repetition_index": i, "threads": 1, "iterations": 100, "real_time": t,
             "cpu_time": t * 1.5, "time_unit": "ms", "vertices": 18000.0}
            for i, t in enumerate(times_ms)]
    for msg in errors:
        rows.append({"name": name, "run_name": name, "run_type": "iteration", "error_occurred": True,
                     "error_message": msg, "iterations": 0, "real_time": 0.0, "cpu_time": 0.0,
                     "time_unit": "ms"})
    return {"context": {"num_cpus": 2}, "benchmarks": rows}


def samples(mean, cv, n, seed):
    rng = random.Random(seed)
    return [mean * (1.0 + rng.gauss(0.0, cv)) for _ in range(n)]


def alternated(times, rounds=3):
    """Split one side's repetitions over `rounds` runs, as gate.sh does, and merge them back."""
    per = (len(times) + rounds - 1) // rounds
    return gate.merge_runs([run_json(NAME, times[i:i + per]) for i in range(0, len(times), per)])


@unittest.skipIf(gbench_report is None, "Google Benchmark's compare.py (libbenchmark-tools) not found")
class GateDecision(unittest.TestCase):
    def verdict(self, base_times, head_times, **kw):
        report = gbench_report.get_difference_report(alternated(base_times), alternated(head_times), utest=True)
        verdicts = gate.evaluate(json.loads(json.dumps(report)), **kw)  # through JSON, like --dump_to_json
        self.assertEqual([v.name for v in verdicts], [NAME])
        return verdicts[0], verdicts

    def test_clear_regression_fails(self):
        v, all_v = self.verdict(samples(10.0, 0.01, 9, 1), samples(12.0, 0.01, 9, 2))
        self.assertAlmostEqual(v.change_pct, 20.0, delta=2.0)
        self.assertLess(v.pvalue, 0.05)
        self.assertEqual(v.source, "compare.py")
        self.assertEqual(v.status, "REGRESSION")
        self.assertTrue(gate.gate_failed(all_v))

    def test_two_percent_noise_passes(self):
        v, all_v = self.verdict(samples(10.0, 0.02, 9, 3), samples(10.0, 0.02, 9, 4))
        self.assertLess(abs(v.change_pct), 5.0)
        self.assertFalse(gate.gate_failed(all_v))

    def test_significant_two_percent_slowdown_passes(self):
        # Clearly slower (p < 0.05) but under the 5 % threshold.
        v, all_v = self.verdict(samples(10.0, 0.002, 9, 5), samples(10.2, 0.002, 9, 6))
        self.assertLess(v.pvalue, 0.05)
        self.assertAlmostEqual(v.change_pct, 2.0, delta=0.5)
        self.assertFalse(gate.gate_failed(all_v))

    def test_noisy_ten_percent_slowdown_passes(self):
        # Few, noisy repetitions: the medians differ by ~10 % but the U test cannot tell.
        base = [10.0, 14.0, 7.0, 12.0]      # median 11
        head = [12.5, 8.0, 16.0, 11.7]      # median 12.1: +10 %
        v, all_v = self.verdict(base, head)
        self.assertAlmostEqual(v.change_pct, 10.0, delta=1.0)
        self.assertGreater(v.pvalue, 0.05)
        self.assertEqual(v.status, "slower, not significant")
        self.assertFalse(gate.gate_failed(all_v))

    def test_improvement_passes(self):
        v, all_v = self.verdict(samples(10.0, 0.01, 9, 7), samples(7.0, 0.01, 9, 8))
        self.assertLess(v.change_pct, -25.0)
        self.assertLess(v.pvalue, 0.05)
        self.assertEqual(v.status, "faster")
        self.assertFalse(gate.gate_failed(all_v))

    def test_threshold_is_a_parameter(self):
        v, all_v = self.verdict(samples(10.0, 0.002, 9, 5), samples(10.2, 0.002, 9, 6), threshold_pct=1.0)
        self.assertEqual(v.status, "REGRESSION")
        self.assertTrue(gate.gate_failed(all_v))


class GateWithoutCompareNumbers(unittest.TestCase):
    def test_missing_utest_and_median_rows_are_computed_here(self):
        # A compare-style report with no U test and no median row: gate.py falls back to scipy.
        base = samples(10.0, 0.01, 9, 11)
        head = samples(12.0, 0.01, 9, 12)
        report = [{"name": NAME, "label": "", "time_unit": "ms", "run_type": "iteration",
                   "aggregate_name": "", "utest": {},
                   "measurements": [{"real_time": a, "cpu_time": a, "real_time_other": b,
                                     "cpu_time_other": b, "time": (b - a) / a, "cpu": (b - a) / a}
                                    for a, b in zip(base, head)]}]
        (v,) = gate.evaluate(report)
        self.assertEqual(v.source, "gate.py")
        self.assertLess(v.pvalue, 0.05)
        self.assertEqual(v.status, "REGRESSION")


class GateErrorsAndMerge(unittest.TestCase):
    def test_merge_pools_repetitions_and_adds_median(self):
        merged = gate.merge_runs([run_json(NAME, [1.0, 2.0, 3.0]), run_json(NAME, [4.0, 5.0, 6.0]),
                                  run_json(NAME, [7.0, 8.0, 9.0])])
        it = [b for b in merged["benchmarks"] if b["run_type"] == "iteration"]
        agg = [b for b in merged["benchmarks"] if b["run_type"] == "aggregate"]
        self.assertEqual(len(it), 9)
        self.assertEqual([b["repetition_index"] for b in it], list(range(9)))
        self.assertEqual(len(agg), 1)
        self.assertEqual(agg[0]["name"], NAME + "_median")
        self.assertEqual(agg[0]["real_time"], 5.0)

    def test_error_only_in_head_fails(self):
        base = gate.merge_runs([run_json(NAME, [1.0, 1.1, 0.9])])
        head = gate.merge_runs([run_json(NAME, [], errors=["unstable while preparing"])])
        verdicts = gate.error_verdicts(base, head)
        self.assertEqual([v.status for v in verdicts], ["ERROR"])
        self.assertIn("unstable", verdicts[0].message)
        self.assertTrue(gate.gate_failed(verdicts))

    def test_error_in_both_is_not_a_regression(self):
        base = gate.merge_runs([run_json(NAME, [], errors=["unbounded"])])
        head = gate.merge_runs([run_json(NAME, [], errors=["unbounded"])])
        self.assertEqual(gate.error_verdicts(base, head), [])


@unittest.skipIf(not os.path.exists(COMPARE), "compare.py not found")
class GateCommandLine(unittest.TestCase):
    """gate.py merge + compare.py --dump_to_json + gate.py check, as gate.sh runs them."""

    def run_gate(self, base_times, head_times):
        with tempfile.TemporaryDirectory() as d:
            for side, times in (("base", base_times), ("head", head_times)):
                runs = []
                for r in range(3):
                    p = os.path.join(d, f"{side}-{r}.json")
                    with open(p, "w") as f:
                        json.dump(run_json(NAME, times[r::3]), f)
                    runs.append(p)
                subprocess.run([sys.executable, str(ROOT / "scripts/gate.py"), "merge",
                                os.path.join(d, f"{side}.json")] + runs, check=True)
            subprocess.run([sys.executable, COMPARE, "--no-color", "--dump_to_json", os.path.join(d, "c.json"),
                            "benchmarks", os.path.join(d, "base.json"), os.path.join(d, "head.json")],
                           check=True, capture_output=True)
            done = subprocess.run([sys.executable, str(ROOT / "scripts/gate.py"), "check", os.path.join(d, "c.json"),
                                   "--base", os.path.join(d, "base.json"), "--head", os.path.join(d, "head.json")],
                                  capture_output=True, text=True)
            return done.returncode, done.stdout

    def test_regression_exits_1(self):
        code, out = self.run_gate(samples(10.0, 0.01, 9, 21), samples(12.0, 0.01, 9, 22))
        self.assertEqual(code, 1, out)
        self.assertIn("REGRESSION", out)

    def test_noise_exits_0(self):
        code, out = self.run_gate(samples(10.0, 0.02, 9, 23), samples(10.0, 0.02, 9, 24))
        self.assertEqual(code, 0, out)
        self.assertIn("PASS", out)


if __name__ == "__main__":
    unittest.main()
