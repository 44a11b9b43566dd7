"""REPORT.md's performance targets (scripts/bench_targets.py, wired by scripts/bench_report.py's
targets_section) on synthetic numbers. Wrong code this catches: a goal compared the wrong way
(BM_Pair's speed-up must reach its goal, the times stay under theirs), the one- and two-thread
event goals swapped, a goal called out of reach whose floor is below it (or one whose bandwidth
floor is above it only "not met"), a modelled floor (events, the frame) taken for a bound, a
value printed equal to its goal while the verdict says it misses it, the frame's floor without
its events, the floors taken from another thread count's bandwidth, the events' cost taken from
the API's frames instead of the bare steps, BM_Pair's times read as its speed-up."""
import os
import sys
import unittest

sys.path.insert(0, os.path.join(os.path.dirname(__file__), "..", "..", "scripts"))
import bench_report  # noqa: E402
import bench_targets  # noqa: E402

NAN = float("nan")


def rows_of(lines):
    """{measure: (this run, goal, floor, verdict)} of the section's table."""
    out = {}
    for line in lines:
        cells = [c.strip() for c in line.strip("|").split("|")]
        if len(cells) == 6 and cells[0].isdigit():
            out[cells[1]] = tuple(cells[2:])
    return out


class Verdicts(unittest.TestCase):
    def test_the_frozen_step_against_its_goal_and_its_floor(self):
        frozen = {("fast", 2): {256: (10.0, 100000, 5.0),   # 100 ns, floor 50 ns: out of reach; 2.00x: met
                                512: (16.0, 400000, 4.0)}}  # 40 ns, floor 10 ns: not met; 4.00x: not met
        rows = rows_of(bench_targets.section(frozen, {}, {}, {}, {}, {}))
        self.assertEqual(rows["frozen step, 2t, N = 256: ns a vertex"],
                         ("100.0", "<= 30", "50.0", "out of reach here (floor above the goal)"))
        self.assertEqual(rows["frozen step, 2t, N = 256: its floor's multiple"], ("2.00x", "<= 2x", "-", "met"))
        self.assertEqual(rows["frozen step, 2t, N = 512: ns a vertex"], ("40.0", "<= 30", "10.0", "not met"))
        self.assertEqual(rows["frozen step, 2t, N = 512: its floor's multiple"][3], "not met")
        self.assertEqual(rows_of(bench_targets.section({("fast", 2): {512: (10.0, 400000, 4.0)}}, {}, {}, {}, {}, {}))
                         ["frozen step, 2t, N = 512: ns a vertex"][3], "met")  # 25 ns

    def test_each_thread_count_has_its_event_goal(self):
        events = {("fast", 2): {256: (1.2, 0.5)}, ("fast", 1): {256: (1.2, 0.9), 512: (2.0, 1.6)}}
        rows = rows_of(bench_targets.section({}, events, {("fast", 2): {512: 0.9}}, {}, {}, {}))
        self.assertEqual(rows["`BM_Events`, 2t, N = 256: us an event"], ("1.20", "<= 1", "0.50 (model)", "not met"))
        self.assertEqual(rows["`BM_Events`, 1t, N = 256: us an event"], ("1.20", "<= 1.5", "0.90 (model)", "met"))
        # An event's floor is a model that cached lines beat: never "out of reach".
        self.assertEqual(rows["`BM_Events`, 1t, N = 512: us an event"][3], "not met")
        self.assertEqual(rows["frame minus frozen over events, 2t, N = 512: us an event"], ("0.90", "<= 1", "-", "met"))

    def test_digits_enough_to_tell_a_value_from_its_goal(self):
        self.assertEqual(bench_targets.shown(30.04, 30.0, digits=1), "30.04")
        self.assertEqual(bench_targets.shown(30.0, 30.0, digits=1), "30.0")
        self.assertEqual(bench_targets.shown(1.3000000001, 1.3, "x"), "1.3000000001x")  # past six decimals

    def test_a_miss_by_less_than_the_last_digit_shows_one_more(self):
        rows = rows_of(bench_targets.section({}, {}, {}, {("fast", 2): {512: 1.304, 1024: 1.3}, ("fast", 1): {512: 1.5}},
                                             {}, {}))
        self.assertEqual(rows["frame ns a vertex, 2t, N = 512 against 128"], ("1.304x", "<= 1.3x", "-", "not met"))
        self.assertEqual(rows["frame ns a vertex, 2t, N = 1024 against 128"], ("1.30x", "<= 1.3x", "-", "met"))
        self.assertEqual(rows["frame ns a vertex, 1t, N = 512 against 128"][3], "not met")

    def test_two_threads_must_reach_the_speed_up(self):
        rows = rows_of(bench_targets.section({}, {}, {}, {}, {128: 1.2, 256: 1.8, 512: 1.7996}, {}))
        self.assertNotIn("`BM_Pair` 2t against 1t, N = 128", rows)  # below the target's sizes
        self.assertEqual(rows["`BM_Pair` 2t against 1t, N = 256"], ("1.80x", ">= 1.8x", "-", "met"))
        self.assertEqual(rows["`BM_Pair` 2t against 1t, N = 512"], ("1.7996x", ">= 1.8x", "-", "not met"))

    def test_the_paper_frame_and_the_moonshot(self):
        frame = lambda ms, floor: rows_of(bench_targets.section({}, {}, {}, {}, {}, {("fast", 2): {512: (ms, floor)}}))[
            "paper's frame, 2t, N = 512: ms"]
        self.assertEqual(frame(30.0, 20.0), ("30.0", "<= 33 (moonshot 16.7)", "20.0 (model)", "met"))
        self.assertEqual(frame(16.0, NAN)[2:], ("-", "met; the 60 fps moonshot met"))
        self.assertEqual(frame(50.0, 40.0)[3], "not met")  # its floor is a model: no "out of reach"
        self.assertEqual(frame(33.04, 20.0)[0], "33.04")  # one digit more where 33.0 would read as the goal

    def test_other_backends_and_no_numbers_give_no_section(self):
        self.assertEqual(bench_targets.section({("reference", 2): {256: (10.0, 1000, 1.0)}}, {}, {}, {}, {},
                                               {("fast-nosimd", 2): {512: (10.0, 1.0)}}), [])


class FromTheBenchmarks(unittest.TestCase):
    """bench_report's wiring: the floors from the best streaming kernel and the random-line rate of
    the row's own thread count, the frame's floor as its frozen steps' plus its events' at the
    BM_Events floor."""

    def test_floors_from_the_run(self):
        b = {}
        for kernel, threads, gbs in [("triad", 1, 14e9), ("gather", 1, 16e9), ("triad", 2, 19e9), ("gather", 2, 8e9)]:
            name = f"BM_Stream/{kernel}/{threads}/128"
            b[name] = bench_report.Bench(name)
            b[name].times, b[name].counters = [10.0], {"bytes_per_second": [gbs]}

        def add(name, ms, **counters):
            b[name] = bench_report.Bench(name)
            b[name].times, b[name].counters = [ms], {k: [v] for k, v in counters.items()}
        add("BM_Frozen/fast/2/512/manual_time", 10.0, bytes=95e6, vertices=100000)  # floor 5 ms at 19 GB/s
        add("BM_Events/fast/2/512/iterations:8/manual_time", 0.002, us_per_event=2.0, event_bytes=8192.0)  # 1.024 us
        add("BM_Frame/fast/2/512/manual_time", 60.0, splits=1000.0, restores=500.0, vertices=100000)
        add("BM_Steps/fast/2/512/manual_time", 50.0, splits=1000.0, restores=500.0)
        add("BM_Pair/fast/2/512/manual_time", 150.0, ms_1t=100.0, ms_2t=52.6, speedup=1.9)
        rows = rows_of(bench_report.targets_section(b, bench_report.frame_series(b)))
        # The bare steps less the frozen ones, not the API's frame: (50 - 10) ms over 1,500 events.
        self.assertEqual(rows["frame minus frozen over events, 2t, N = 512: us an event"][0], "26.67")
        self.assertEqual(rows["`BM_Pair` 2t against 1t, N = 512"][:2], ("1.90x", ">= 1.8x"))
        self.assertEqual(rows["frozen step, 2t, N = 512: ns a vertex"][:3], ("100.0", "<= 30", "50.0"))
        self.assertEqual(rows["frozen step, 2t, N = 512: its floor's multiple"][0], "2.00x")
        self.assertEqual(rows["`BM_Events`, 2t, N = 512: us an event"][:3], ("2.00", "<= 1", "1.02 (model)"))
        # 5 ms + 1,500 events x 1.024 us = 6.536 ms.
        self.assertEqual(rows["paper's frame, 2t, N = 512: ms"][:3], ("60.0", "<= 33 (moonshot 16.7)", "6.5 (model)"))


if __name__ == "__main__":
    unittest.main()
