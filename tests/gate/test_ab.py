"""Tests of scripts/ab.sh (A/B of two benchmark binaries) with two fake crumple_bench binaries.

Each fake binary is a small script that writes Google Benchmark's JSON (a median aggregate per
benchmark) to --benchmark_out, taking its round's value from a list it is given, and logs each
call; the tests read ab.sh's table. Wrong code this catches: rounds not alternated A, B, A, B;
the ratio taken of the medians instead of per round; the counter ignored, or one of several
counters' tables missing or taken from the other's values; a filter that matched
nothing, or a missing binary, accepted silently; with CRUMPLE_AB_PLACEMENT=1, the round trips
printed out of round order, measured when not asked for, or a missing one passed over.
"""
import os
import subprocess
import textwrap
import unittest
from pathlib import Path

from fake_tools import FakeToolsCase

ROOT = Path(__file__).resolve().parents[2]
AB = ROOT / "scripts" / "ab.sh"

FAKE = textwrap.dedent("""\
    #!/usr/bin/python3
    import json, sys
    values, log, names, mode, trips = {values!r}, {log!r}, {names!r}, {mode!r}, {trips!r}
    out = next(a.split("=", 1)[1] for a in sys.argv if a.startswith("--benchmark_out="))
    if "CoreToCore" in next(a for a in sys.argv if a.startswith("--benchmark_filter=")):
        with open(log, "a") as f:  # logged apart from the rounds' runs
            f.write({side!r} + "T\\n")
        k = open(log).read().split().count({side!r} + "T")
        rows = [{{"name": "BM_CoreToCore/2/64/manual_time", "run_type": "iteration",
                  "ns_per_round_trip": trips[k - 1]}}] if trips else []
        json.dump({{"benchmarks": rows}}, open(out, "w"))
        sys.exit(0)
    with open(log, "a") as f:
        f.write({side!r} + "\\n")
    calls = open(log).read().split().count({side!r})
    if not names:  # like crumple_bench when the filter matches nothing: an empty file, status 0
        open(out, "w").close()
        sys.exit(0)
    if mode == "crash":
        sys.exit(3)
    if mode == "drop_first" and calls == 1:  # the first benchmark missing from the first run
        names = names[1:]
    v = values[calls - 1]
    if mode == "error":  # SkipWithError: an iteration row with the error, no aggregate
        rows = [{{"name": n, "run_name": n, "run_type": "iteration", "error_occurred": True,
                  "error_message": "state mismatch", "real_time": 0.0}} for n in names]
    elif mode == "single":  # one repetition: its iteration row, no aggregates
        rows = [{{"name": n, "run_name": n, "run_type": "iteration", "real_time": v}} for n in names]
    else:
        rows = [{{"name": n + "_median", "run_name": n, "run_type": "aggregate", "aggregate_name": "median",
                  "real_time": v, "time_unit": "ms", "us_per_event": v / 10}} for n in names]
    json.dump({{"benchmarks": rows}}, open(out, "w"))
""")


class AbScript(FakeToolsCase):
    def fake(self, side, values, names=("BM_Events/fast/1/128",), mode="median", trips=()):
        return self.write_fake(side, FAKE.format(values=list(values), log=self.log, names=list(names), side=side,
                                                 mode=mode, trips=list(trips)))

    def run_ab(self, *args, placement=False):
        env = dict(os.environ, CRUMPLE_AB_PLACEMENT="1" if placement else "0")
        return subprocess.run(["bash", str(AB), *args], capture_output=True, text=True, timeout=60, env=env)

    def row(self, stdout, name):
        line = next(l for l in stdout.splitlines() if l.startswith(f"| {name} "))
        return [c.strip() for c in line.strip("|").split("|")]

    def test_medians_and_paired_ratio(self):
        # Round ratios 0.5, 0.8, 0.9: their median 0.8 differs from the ratio of the medians (9/10).
        a = self.fake("A", [10, 20, 5])
        b = self.fake("B", [5, 16, 4.5])
        r = self.run_ab(a, b, "BM_Events", "3", "2")
        self.assertEqual(r.returncode, 0, r.stderr)
        cells = self.row(r.stdout, "BM_Events/fast/1/128")
        self.assertEqual(cells[1:], ["10 20 5", "5 16 4.5", "10", "5", "0.800"])
        # Alternated, and neither side always first: A B, B A, A B.
        self.assertEqual(Path(self.log).read_text().split(), ["A", "B", "B", "A", "A", "B"])

    def test_rounds_pair_by_round(self):
        # A misses the benchmark in round 1: round 2's runs pair, not A's round 2 with B's round 1.
        a = self.fake("A", [10, 20, 40], names=("BM_X", "BM_Y"), mode="drop_first")
        b = self.fake("B", [30, 10, 10], names=("BM_X", "BM_Y"))
        r = self.run_ab(a, b, "BM", "3", "1")
        self.assertEqual(r.returncode, 0, r.stderr)
        # BM_X pairs rounds 2 and 3 only: A 20, 40 against B 10, 10.
        self.assertEqual(self.row(r.stdout, "BM_X")[1:], ["20 40", "10 10", "30", "10", "0.375"])

    def test_one_repetition_uses_its_run(self):
        r = self.run_ab(self.fake("A", [4, 8], mode="single"), self.fake("B", [2, 8], mode="single"), "BM", "2", "1")
        self.assertEqual(r.returncode, 0, r.stderr)
        self.assertEqual(self.row(r.stdout, "BM_Events/fast/1/128")[1:], ["4 8", "2 8", "6", "5", "0.750"])

    def test_a_benchmark_that_did_not_run_fails(self):
        r = self.run_ab(self.fake("A", [1]), self.fake("B", [1], mode="error"), "BM", "1", "1")
        self.assertNotEqual(r.returncode, 0)
        self.assertIn("did not run on B in round 1: state mismatch", r.stderr)
        self.assertNotIn("Traceback", r.stderr)

    def test_a_failing_binary_fails(self):
        r = self.run_ab(self.fake("A", [1], mode="crash"), self.fake("B", [1]), "BM", "1", "1")
        self.assertEqual(r.returncode, 1)
        self.assertIn("failed in round 1", r.stderr)

    def test_counter_is_compared(self):
        a = self.fake("A", [10, 20])
        b = self.fake("B", [30, 20])
        r = self.run_ab(a, b, "BM_Events", "2", "1", "us_per_event")
        self.assertEqual(r.returncode, 0, r.stderr)
        self.assertIn("us_per_event", r.stdout)
        self.assertEqual(self.row(r.stdout, "BM_Events/fast/1/128")[1:], ["1 2", "3 2", "1.5", "2.5", "2.000"])

    def test_several_counters_give_a_table_each(self):
        a = self.fake("A", [10, 20])
        b = self.fake("B", [30, 20])
        r = self.run_ab(a, b, "BM_Events", "2", "1", "real_time,us_per_event")
        self.assertEqual(r.returncode, 0, r.stderr)
        time, events = r.stdout.split("\n\n")
        self.assertIn("A (real time)", time)
        self.assertEqual(self.row(time, "BM_Events/fast/1/128")[1:], ["10 20", "30 20", "15", "25", "2.000"])
        self.assertIn("A (us_per_event)", events)
        self.assertEqual(self.row(events, "BM_Events/fast/1/128")[1:], ["1 2", "3 2", "1.5", "2.5", "2.000"])

    def test_unknown_counter_fails(self):
        r = self.run_ab(self.fake("A", [1]), self.fake("B", [1]), "BM_Events", "1", "1", "no_such")
        self.assertNotEqual(r.returncode, 0)
        self.assertIn("no counter no_such", r.stderr)

    def test_filter_matching_nothing_fails(self):
        r = self.run_ab(self.fake("A", [1], names=()), self.fake("B", [1], names=()), "NOPE", "1", "1")
        self.assertNotEqual(r.returncode, 0)
        self.assertIn("matched no benchmark", r.stderr)

    def test_placement_before_each_round(self):
        a = self.fake("A", [10, 20, 5], trips=[100, 480, 120])
        b = self.fake("B", [5, 16, 4.5])
        r = self.run_ab(a, b, "BM_Events", "3", "2", placement=True)
        self.assertEqual(r.returncode, 0, r.stderr)
        self.assertIn("before each round (BM_CoreToCore, ns): 100 480 120\n", r.stdout)
        self.assertEqual(Path(self.log).read_text().split(), ["AT", "A", "B", "AT", "B", "A", "AT", "A", "B"])
        self.assertEqual(self.row(r.stdout, "BM_Events/fast/1/128")[-1], "0.800")

    def test_no_placement_unless_asked(self):
        r = self.run_ab(self.fake("A", [1, 2], trips=[100, 100]), self.fake("B", [1, 2]), "BM_Events", "2", "1")
        self.assertEqual(r.returncode, 0, r.stderr)
        self.assertNotIn("round trip", r.stdout)
        self.assertNotIn("AT", Path(self.log).read_text().split())

    def test_a_missing_round_trip_fails(self):
        r = self.run_ab(self.fake("A", [1]), self.fake("B", [1]), "BM_Events", "1", "1", placement=True)
        self.assertNotEqual(r.returncode, 0)
        self.assertIn("gave no round trip before round 1", r.stderr)
        self.assertNotIn("Traceback", r.stderr)

    def test_bad_arguments_fail(self):
        a = self.fake("A", [1])
        for args in ([a], [a, os.path.join(self.dir.name, "missing"), "x"], [a, a, "x", "0"], [a, a, "x", "2", "y"]):
            r = self.run_ab(*args)
            self.assertEqual(r.returncode, 2, args)
            self.assertEqual(len(r.stderr.strip().splitlines()), 1, r.stderr)


if __name__ == "__main__":
    unittest.main()
