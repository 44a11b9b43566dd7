"""scripts/bench_report.py on synthetic benchmarks: the rooflines (class Rooflines: the STREAM
roof leaves out the random-line kernel, BM_Stream/gather, and an event's floor is its modelled
bytes at that kernel's rate on the event's thread count), BM_Pair's speed-up (class Pairs), the
busy-machine verdict (class MachineLoad), the cost per vertex against N = 128 (class
PerVertex), the frozen step on a fresh layout beside the prepared one (class FrozenFresh), the
first touch of memory against streaming (class FirstTouch), the STREAM table's ranges (class
StreamSpread), the CPU line (class CpuLine), the
CPUs' cache-line round trip (class CoreToCore), BM_Pair by placement (class PairPlacements) and
the frame budget by the longest frame (class LongestFrame).
Wrong code the rooflines catch: the gather kernel taken as the roof (it is the lowest, so every
pass would look closer to memory-bound), the floor computed from the streaming rate or from the
other thread count's line rate, bytes read as lines; each class names its own."""
import os
import sys
import unittest

sys.path.insert(0, os.path.join(os.path.dirname(__file__), "..", "..", "scripts"))
import bench_report  # noqa: E402


def bench(name, ms, **counters):
    b = bench_report.Bench(name)
    b.times = [ms]
    b.counters = {k: [v] for k, v in counters.items()}
    return b


def benches():
    out = {}
    for kernel, threads, gbs in [("read", 1, 9e9), ("triad", 1, 14e9), ("gather", 1, 16e9),
                                 ("read", 2, 15e9), ("triad", 2, 19e9), ("gather", 2, 8e9)]:
        name = f"BM_Stream/{kernel}/{threads}/128"
        out[name] = bench(name, 10.0, bytes_per_second=gbs)
    # 128 lines of 64 bytes an event; 4 us per event on 1 thread, 2 on 2.
    for threads, us in [(1, 4.0), (2, 2.0)]:
        name = f"BM_Events/fast/{threads}/256/iterations:8/manual_time"
        out[name] = bench(name, us / 1000.0, us_per_event=us, event_bytes=128 * 64.0, splits=10, restores=5,
                          mismatch=0)
    return out


class Rooflines(unittest.TestCase):
    def test_roof_is_the_best_streaming_kernel(self):
        # On 1 thread the synthetic line rate (16) beats every streaming kernel: still no roof.
        stream = bench_report.stream_bandwidth(benches())
        self.assertEqual(bench_report.roof(stream, 1), 14.0)
        self.assertEqual(bench_report.roof(stream, 2), 19.0)
        self.assertEqual(bench_report.line_rate(stream, 1), 16.0)
        self.assertEqual(bench_report.line_rate(stream, 2), 8.0)

    def test_event_floor_is_its_lines_at_the_random_line_rate(self):
        rows = [line for line in bench_report.events_section(benches()) if line.startswith("| fast")]
        self.assertEqual(len(rows), 2)
        # 8192 bytes at 16 GB/s: 0.512 us, the event 4 us: 7.8x; on 2 threads 8 GB/s: 1.024 us, 2.0x.
        self.assertTrue(rows[0].endswith("| 128 | 0.51 | 7.8x |"), rows[0])
        self.assertTrue(rows[1].endswith("| 128 | 1.02 | 2.0x |"), rows[1])

    def test_no_line_rate_no_floor(self):
        b = {k: v for k, v in benches().items() if "gather" not in k}
        rows = [line for line in bench_report.events_section(b) if line.startswith("| fast")]
        self.assertTrue(all(r.endswith("| - | - | - |") for r in rows), rows)


class StreamSpread(unittest.TestCase):
    """The STREAM table gives each kernel's median and the range of its repetitions, which shows a
    machine whose bandwidth changed during the run. Wrong code this catches: the range taken from
    another kernel or thread count, the times' range instead of the bandwidth's, the median of
    the range's ends instead of the repetitions', a range printed for a single repetition."""

    def test_median_and_range_of_each_kernel(self):
        b = {k: v for k, v in benches().items() if k.startswith("BM_Stream")}
        spread = b["BM_Stream/read/2/128"]
        spread.times = [10.0, 12.0, 9.0, 20.0, 11.0]
        spread.counters["bytes_per_second"] = [53e9, 35e9, 60e9, 34e9, 31e9]  # in the run's order
        lines = bench_report.stream_table(b, bench_report.stream_bandwidth(b))
        rows = {line.split("|")[1].strip(): line for line in lines if line.startswith("| 1 ") or line.startswith("| 2 ")}
        self.assertEqual(lines[0], "| threads | gather GB/s | read GB/s | triad GB/s |")
        self.assertEqual(rows["1"], "| 1 | 16.0 | 9.0 | 14.0 |")
        self.assertEqual(rows["2"], "| 2 | 8.0 | 35.0 (31.0-60.0) | 19.0 |")
        self.assertIn("In brackets: the lowest and highest repetition.", lines)

    def test_no_range_no_note(self):
        b = {k: v for k, v in benches().items() if k.startswith("BM_Stream")}
        lines = bench_report.stream_table(b, bench_report.stream_bandwidth(b))
        self.assertFalse(any("(" in line or "brackets" in line for line in lines), lines)


class MachineLoad(unittest.TestCase):
    """The busy verdict reads the CPUs' busy share sampled before bench.sh's build when run.json
    has it, else the load before that build, else the load at the start. Wrong code this
    catches: the verdict taken from the load at the benchmark's start (which the build just
    before inflates) although an earlier reading exists; from the load average (which still
    carries work that ended before the run) although the CPU sample exists; a busy machine not
    flagged; the steal share not named, or named when small."""

    context = {"num_cpus": 2, "load_avg": [1.68, 0.67, 0.25]}

    def busy(self, run):
        return [line for line in bench_report.machine_section(run, self.context) if "was busy" in line]

    def test_a_build_before_the_run_does_not_make_it_busy(self):
        self.assertEqual(self.busy({"load_before_build": [0.07, 0.02, 0.0]}), [])

    def test_neighbours_before_the_build_make_it_busy(self):
        busy = self.busy({"load_before_build": [1.9, 1.5, 1.2]})
        self.assertEqual(len(busy), 1)
        self.assertIn("1.90 on 2 CPUs before the run's build", busy[0])

    def test_without_the_earlier_reading_the_start_load_decides(self):
        self.assertEqual(len(self.busy({})), 1)

    def test_the_cpu_sample_decides_over_the_load_average(self):
        # Work that ended seconds before the build: the load average is high, the CPUs idle.
        run = {"load_before_build": [1.15, 1.08, 0.65], "cpu_use_before_build": {"seconds": 3, "busy": 0.02, "steal": 0.0}}
        self.assertEqual(self.busy(run), [])
        lines = bench_report.machine_section(run, self.context)
        self.assertIn("- CPU time before the build, over 3 s (/proc/stat): 2.0 % of all CPUs' time busy, "
                      "0.0 % stolen by the hypervisor", lines)
        self.assertFalse(any("hypervisor took" in line for line in lines), lines)

    def test_a_busy_cpu_sample_makes_it_busy(self):
        run = {"load_before_build": [0.1, 0.1, 0.1], "cpu_use_before_build": {"seconds": 3, "busy": 0.4, "steal": 0.12}}
        busy = self.busy(run)
        self.assertEqual(len(busy), 1)
        self.assertIn("40.0 % of the 2 CPUs' time was busy just before the run's build", busy[0])
        lines = bench_report.machine_section(run, self.context)
        self.assertEqual(len([line for line in lines if "The hypervisor took 12.0 %" in line]), 1, lines)

    def test_the_thresholds(self):
        def verdicts(busy, steal):
            run = {"cpu_use_before_build": {"seconds": 3, "busy": busy, "steal": steal}}
            lines = bench_report.machine_section(run, self.context)
            return any("was busy" in line for line in lines), any("hypervisor took" in line for line in lines)
        self.assertEqual(verdicts(0.2, 0.03), (False, False))
        self.assertEqual(verdicts(0.3, 0.07), (True, True))

    def test_an_unread_sample_leaves_the_load_average_to_decide(self):
        run = {"load_before_build": [1.9, 1.5, 1.2], "cpu_use_before_build": {}}
        self.assertEqual(len(self.busy(run)), 1)
        self.assertFalse(any("CPU time before" in line for line in bench_report.machine_section(run, self.context)))


class CoreToCore(unittest.TestCase):
    """BM_CoreToCore's round trip is quoted from its counter, with the repetitions' range when
    they measured two placements of the CPUs. Wrong code this catches: the iteration time (ms for
    100,000 round trips) printed instead of ns_per_round_trip, a sentence without the benchmark
    in the run, the range left out of a bimodal run (the median alone then reads as the machine's
    one distance) or printed for an ordinary spread."""

    NAME = "BM_CoreToCore/2/64/manual_time"

    def test_round_trip_from_the_counter(self):
        b = {self.NAME: bench(self.NAME, 50.8, ns_per_round_trip=507.5)}
        lines = bench_report.core_to_core_lines(b)
        self.assertIn("in 508 ns a round trip (`BM_CoreToCore`", lines[0])

    def repetitions(self, trips):
        b = bench(self.NAME, 10.0)
        b.times = [t / 10.0 for t in trips]
        b.counters = {"ns_per_round_trip": trips}
        return bench_report.core_to_core_lines({self.NAME: b})[0]

    def test_two_placements_give_the_range(self):
        line = self.repetitions([101.0, 446.0, 103.0, 480.0, 435.0])
        self.assertIn("in 435 ns a round trip (the median of repetitions from 101 to 480 ns", line)

    def test_an_ordinary_spread_gives_no_range(self):
        line = self.repetitions([479.0, 440.0, 445.0, 493.0, 451.0])
        self.assertIn("in 451 ns a round trip (`BM_CoreToCore`", line)

    def test_no_benchmark_no_sentence(self):
        self.assertEqual(bench_report.core_to_core_lines(benches()), [])


class CpuLine(unittest.TestCase):
    """The report's CPU line names the core generation where run.json records it and says when
    lscpu gave no cache sizes. Wrong code this catches: the generation dropped (two VM kinds
    named "AMD EPYC" would read alike), empty cache fields printed as "L2 , L3 "."""

    def test_generation_and_family_are_named(self):
        line = bench_report.cpu_line({"model": "AMD EPYC", "microarchitecture": "zen5", "family": 26,
                                      "model_number": 2, "l2": "2 MiB", "l3": "32 MiB"}, {})
        self.assertTrue(line.startswith("AMD EPYC (Zen 5, family 26 model 2);"), line)
        self.assertIn("L2 2 MiB, L3 32 MiB", line)

    def test_an_intel_generation_is_named_in_words(self):
        line = bench_report.cpu_line({"model": "Intel(R) Xeon(R) Processor", "microarchitecture": "emr",
                                      "family": 6, "model_number": 207}, {})
        self.assertTrue(line.startswith("Intel(R) Xeon(R) Processor (Emerald Rapids, family 6 model 207);"), line)

    def test_missing_caches_are_said_missing(self):
        line = bench_report.cpu_line({"model": "AMD EPYC", "l2": "", "l3": ""}, {})
        self.assertIn("caches not reported by lscpu", line)
        self.assertNotIn("L2 ,", line)

    def test_an_older_run_json_reads_as_before(self):
        line = bench_report.cpu_line({"model": "AMD EPYC", "hypervisor": "KVM", "l2": "1 MiB"}, {"mhz_per_cpu": 2596})
        self.assertTrue(line.startswith("AMD EPYC, KVM guest;"), line)
        self.assertTrue(line.endswith("2596 MHz"), line)


class PerVertex(unittest.TestCase):
    """Cost per vertex is the median frame over the median live vertices, set against N = 128 of
    the same configuration. Wrong code this catches: the ratio against the smallest N measured
    (here 64) or against another configuration's N = 128, ms left unconverted, a ratio printed
    where the configuration has no N = 128."""

    def frames(self, threads, times):
        out = {}
        for n, (ms, vertices) in times.items():
            name = f"BM_Frame/fast/{threads}/{n}/manual_time"
            b = bench_report.Bench(name)
            b.times = [ms, ms * 1.5, ms * 0.5]
            b.counters = {"vertices": [vertices] * 3}
            out[name] = b
        return out

    def test_ratio_is_against_n128_of_the_same_configuration(self):
        benches = self.frames(1, {64: (1.0, 8000), 128: (4.0, 20000), 512: (60.0, 200000)})
        benches.update(self.frames(2, {256: (10.0, 100000)}))
        rows = dict(bench_report.per_vertex_rows(bench_report.frame_series(benches)))
        self.assertEqual(rows[("fast", 1)], [(64, 125.0, 0.625), (128, 200.0, 1.0), (512, 300.0, 1.5)])
        self.assertEqual(rows[("fast", 2)], [(256, 100.0, None)])
        lines = bench_report.per_vertex_section(bench_report.frame_series(benches), {})
        self.assertIn("| fast, 2 threads | - | - | 100 | - |", lines)


class Pairs(unittest.TestCase):
    """BM_Pair's speed-up is the median of each repetition's own ratio. Wrong code this catches:
    the ratio of the two sides' medians (here 95 / 50 = 1.90 against the repetitions' 1.70),
    the ratio inverted, a row for a benchmark without the counter."""

    def test_speedup_is_the_median_of_the_repetitions_ratios(self):
        name = "BM_Pair/fast/2/512/manual_time"
        b = bench_report.Bench(name)
        b.times = [50.0, 60.0, 45.0]
        b.counters = {"ms_1t": [100.0, 80.0, 95.0], "ms_2t": [50.0, 60.0, 45.0], "speedup": [1.5, 1.9, 1.7]}
        empty = bench_report.Bench("BM_Pair/fast/2/256/manual_time")
        empty.times = [10.0]
        rows = bench_report.pair_rows({name: b, empty.name: empty})
        self.assertEqual(len(rows), 1)
        self.assertEqual(rows[0][:9], ("fast", 512, None, 95.0, 50.0, 1.7, 1.5, 1.9, 3))
        table = [line for line in bench_report.pair_section({name: b}, {}) if line.startswith("| fast")]
        self.assertEqual(table, ["| fast 2t against 1t | 512 | 95 | 50 | 1.70x | 1.50x | 1.90x | 3 |"])


class PairPlacements(unittest.TestCase):
    """BM_Pair's repetitions grouped by where the VM placed the two CPUs (near_placement, the
    median round trip). Wrong code this catches: a repetition counted under the other placement
    (the flag inverted or read from another repetition: the near group's 1.85x and 125 ns would
    move), a placement's group left out when the run saw both, a lone placement given an "all"
    row and a copy of itself, the threshold not named."""

    def pair(self, near, trips, speedup):
        b = bench_report.Bench("BM_Pair/fast/2/256/manual_time")
        b.times = [30.0] * len(near)
        b.counters = {"ms_1t": [60.0 + i for i in range(len(near))], "ms_2t": b.times[:], "speedup": speedup,
                      "near_placement": near, "round_trip_ns": trips}
        return {b.name: b}

    def test_two_placements_give_a_row_each_after_all(self):
        benches = self.pair([1, 0, 0, 1, 0], [120.0, 480.0, 500.0, 130.0, 450.0], [1.9, 1.4, 1.5, 1.8, 1.3])
        rows = bench_report.pair_rows(benches)
        self.assertEqual([r[2] for r in rows], ["all", "near", "far"])
        self.assertEqual(rows[0][5:], (1.5, 1.3, 1.9, 5, 450.0))
        self.assertEqual(rows[1][3:], (61.5, 30.0, 1.85, 1.8, 1.9, 2, 125.0))
        self.assertEqual(rows[2][3:], (62.0, 30.0, 1.4, 1.3, 1.5, 3, 480.0))
        lines = bench_report.pair_section(benches, {"crumple_near_round_trip_ns": "250"})
        self.assertTrue(any("below 250 ns" in line for line in lines))
        table = [line for line in lines if line.startswith("| fast")]
        self.assertEqual(table[1], "| fast 2t against 1t | 256 | near | 125 | 61.5 | 30 | 1.85x | 1.80x | 1.90x | 2 |")

    def test_one_placement_gives_one_row_named_after_it(self):
        rows = bench_report.pair_rows(self.pair([0, 0, 0], [480.0, 500.0, 450.0], [1.4, 1.5, 1.3]))
        self.assertEqual([(r[2], r[8], r[9]) for r in rows], [("far", 3, 480.0)])


class FrozenFresh(unittest.TestCase):
    """BM_FrozenFresh sits beside BM_Frozen of the same configuration and N, against the same
    floor. Wrong code this catches: a fresh time paired by N alone (here the 1-thread row would
    take the 2-thread fresh time) or by configuration alone (the 512 one), BM_FrozenFresh read as
    a frozen row of its own, its ratio against another thread count's roof."""

    def test_fresh_layout_beside_the_prepared_one(self):
        b = {k: v for k, v in benches().items() if k.startswith("BM_Stream")}  # roofs 14 (1t) and 19 (2t)
        for name, ms in [("BM_Frozen/fast/2/256/manual_time", 10.0), ("BM_Frozen/fast/1/256/manual_time", 20.0),
                         ("BM_FrozenFresh/fast/2/256/manual_time", 7.0), ("BM_FrozenFresh/fast/2/512/manual_time", 30.0)]:
            b[name] = bench(name, ms, bytes=95e6, vertices=100000)
        lines = bench_report.roofline_section(b, {})
        rows = [line for line in lines if line.startswith("| fast")]
        self.assertEqual(len(rows), 2, rows)
        # 95 MB at 19 GB/s: 5 ms (2.0x, fresh 1.4x); at 14 GB/s: 6.79 ms (2.9x), no fresh run.
        self.assertTrue(rows[0].startswith("| fast 1t | 256 |") and rows[0].endswith("| 6.79 | 2.9x | 4.8 | 200 | - | - | - |"), rows[0])
        self.assertTrue(rows[1].startswith("| fast 2t | 256 |") and rows[1].endswith("| 5 | 2.0x | 9.5 | 100 | - | 7 | 1.4x |"), rows[1])


class FrozenAgainstCached(unittest.TestCase):
    """Each frozen row's ns per vertex against its own configuration's at N = 128. Wrong code this
    catches: a ratio of frame times instead of per-vertex costs (the sizes' vertex counts differ),
    a 128 row of another thread count or configuration as the divisor (here 1t's 128 row costs
    twice 2t's), a row without a 128 row of its own given a ratio rather than '-'."""

    def test_each_size_against_its_own_configurations_128(self):
        b = {k: v for k, v in benches().items() if k.startswith("BM_Stream")}
        for name, ms, vertices in [("BM_Frozen/fast/2/128/manual_time", 2.0, 25000),    # 80 ns
                                   ("BM_Frozen/fast/2/512/manual_time", 45.0, 450000),  # 100 ns
                                   ("BM_Frozen/fast/1/128/manual_time", 4.0, 25000),    # 160 ns
                                   ("BM_Frozen/fast/1/512/manual_time", 90.0, 450000),  # 200 ns
                                   ("BM_Frozen/fast-nosimd/1/512/manual_time", 90.0, 450000)]:
            b[name] = bench(name, ms, bytes=95e6, vertices=vertices)
        rows = {" | ".join(line.split(" | ")[:2]): line.split(" | ")[9].strip(" |")
                for line in bench_report.roofline_section(b, {}) if line.startswith("| fast")}
        self.assertEqual(rows, {"| fast 2t | 128": "1.00x", "| fast 2t | 512": "1.25x", "| fast 1t | 128": "1.00x",
                                "| fast 1t | 512": "1.25x", "| fast-nosimd 1t | 512": "-"})


class FirstTouch(unittest.TestCase):
    """BM_FirstTouch's cost a 4 KiB per kind of page and thread count, set against the 1-thread
    STREAM roof. Wrong code this catches: the iteration time read instead of the us_per_4kib
    counter, the kinds of page swapped or mislabelled (idle among them, whose name has an
    iterations part), a 2-thread row taken for the 1-thread one or dropped (its name has a
    threads part before the iterations part), the 2-thread roof (0.22 us) instead of 1 thread's."""

    def test_cost_per_page_kind_against_streaming(self):
        b = {k: v for k, v in benches().items() if k.startswith("BM_Stream")}  # roof 14 GB/s on 1 thread
        for pages, threads, us in [("idle", 2, 6.0), ("idle", 1, 11.0), ("huge", 2, 2.5), ("huge", 1, 5.0),
                                   ("small", 1, 12.0)]:
            name = f"BM_FirstTouch/{pages}/64" + (f"/{threads}" if threads > 1 else "")
            if pages == "idle":
                name += "/iterations:2"
            b[name + "/manual_time"] = bench(name + "/manual_time", 99.0, us_per_4kib=us)
        text = " ".join(bench_report.roofline_section(b, {}))
        self.assertIn("12.00 us a 4 KiB on 4 KiB pages, 5.00 us a 4 KiB on huge pages (2.50 us on 2 threads), "
                      "11.00 us a 4 KiB on huge pages of memory left free for 3 s first (6.00 us on 2 threads)", text)
        self.assertIn("moves 4 KiB in 0.29 us on 1 thread", text)  # 4096 B at 14 GB/s

    def test_no_first_touch_run_no_sentence(self):
        self.assertNotIn("First touch", " ".join(bench_report.roofline_section(benches(), {})))


class LongestFrame(unittest.TestCase):
    """The budget table by `longest_ms`. Wrong code this catches: the budget judged by the
    median again (N = 256's 20 ms median fits 30 fps, its 36 ms longest frame does not), the
    largest N taken regardless of the budget, a row for a configuration without the counter
    (Bullet here), the table printed for a run from before the counter."""

    def test_the_longest_frame_decides(self):
        b = {}
        for n, ms, longest in [(128, 5.0, 8.0), (256, 20.0, 36.0), (512, 100.0, 160.0)]:
            name = f"BM_Frame/fast/2/{n}/manual_time"
            b[name] = bench(name, ms, longest_ms=longest, vertices=n * n)
        b["BM_Frame/bullet/1/128/manual_time"] = bench("BM_Frame/bullet/1/128/manual_time", 7.0, vertices=16384)
        lines = bench_report.budget_section(bench_report.frame_series(b), {})
        longest = lines[lines.index("| configuration | 60 fps (<= 16.7 ms) | 30 fps (<= 33.3 ms) |", 5):]
        rows = [line for line in longest if line.startswith("| fast") or line.startswith("| Bullet")]
        self.assertEqual(rows, ["| fast, 2 threads | N=128: longest 8 ms, median 5 ms | N=128: longest 8 ms, median 5 ms |"])
        # The median table above it still says N = 256 fits 30 fps.
        self.assertTrue(any(line.startswith("| fast, 2 threads |") and "N=256" in line for line in lines[:8]), lines)

    def test_no_table_without_the_counter(self):
        b = {"BM_Frame/fast/2/128/manual_time": bench("BM_Frame/fast/2/128/manual_time", 5.0, vertices=16384)}
        lines = bench_report.budget_section(bench_report.frame_series(b), {})
        self.assertFalse(any("longest" in line for line in lines))


if __name__ == "__main__":
    unittest.main()
