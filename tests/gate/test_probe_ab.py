"""Tests of scripts/probe_ab.sh (two crumple_layout_probe builds in continuous runs) with fake probes.

Each fake probe is a small script that prints the probe's summary (its header and one row) with
its call's values taken from a list it is given, and logs each call; the tests read the table.
Wrong code this catches: runs not in A B B A cycles (the log's order), a cycle's ratio taken from
another cycle's runs or as B's over A's median instead of per cycle, a column's medians or range
wrong, the probe's arguments not passed on, and a probe that fails or prints no summary accepted
silently.
"""
import os
import subprocess
import textwrap
import unittest
from pathlib import Path

from fake_tools import FakeToolsCase

ROOT = Path(__file__).resolve().parents[2]
PROBE_AB = ROOT / "scripts" / "probe_ab.sh"

FAKE = textwrap.dedent("""\
    #!/usr/bin/python3
    import sys
    frames, log, mode = {frames!r}, {log!r}, {mode!r}
    with open(log, "a") as f:
        f.write({side!r} + " " + " ".join(sys.argv[1:]) + "\\n")
    calls = [l.split()[0] for l in open(log)].count({side!r})
    if mode == "crash":
        sys.exit(3)
    print("N = 256, 2 thread(s), 107055 vertices at frame 72; 24 timed frames a run")
    if mode == "nosummary":
        sys.exit(0)
    print("\\nmedians over 1 rounds (ms a frame)")
    print("fraction     frame  longest    warm")
    v = frames[calls - 1]
    print(f"0.25      {{v:8.2f}} {{2 * v:8.2f}} {{v / 10:7.2f}}")
""")


class ProbeAbScript(FakeToolsCase):
    def fake(self, side, frames, mode="ok"):
        return self.write_fake(side, FAKE.format(frames=list(frames), log=self.log, side=side, mode=mode))

    def run_script(self, *args):
        return subprocess.run(["bash", str(PROBE_AB), *args], capture_output=True, text=True, timeout=60)

    def row(self, stdout, name):
        line = next(l for l in stdout.splitlines() if l.startswith(f"| {name} "))
        return [c.strip() for c in line.strip("|").split("|")]

    def test_cycles_medians_and_ratios(self):
        # A's four runs 10, 12, 20, 30; B's 9, 9, 10, 30: cycle 1 is A 10, B 9, B 9, A 12.
        a = self.fake("A", [10, 12, 20, 30])
        b = self.fake("B", [9, 9, 10, 30])
        r = self.run_script(a, b, "256", "2", "24", "2", "0")
        self.assertEqual(r.returncode, 0, r.stderr)
        calls = [l.split() for l in Path(self.log).read_text().splitlines()]
        self.assertEqual([c[0] for c in calls], ["A", "B", "B", "A", "A", "B", "B", "A"])
        self.assertEqual(calls[0][1:], ["256", "2", "24", "1", "0.25"])
        frame = self.row(r.stdout, "frame")
        self.assertEqual(frame[1], "16.00 (10.00-30.00)")
        self.assertEqual(frame[2], "9.50 (9.00-30.00)")
        self.assertEqual(frame[3], "0.82 0.80")  # (9 + 9) / (10 + 12), (10 + 30) / (20 + 30)
        self.assertEqual(self.row(r.stdout, "longest")[3], "0.82 0.80")
        self.assertEqual(self.row(r.stdout, "warm")[1], "1.60 (1.00-3.00)")

    def test_a_failing_probe_fails_the_script(self):
        for mode in ("crash", "nosummary"):
            with self.subTest(mode=mode):
                Path(self.log).write_text("")
                a = self.fake("A", [10, 10])
                b = self.fake("B", [10, 10], mode=mode)
                r = self.run_script(a, b, "256", "2", "24", "1", "0")
                self.assertNotEqual(r.returncode, 0)
                self.assertIn("failed or printed no summary", r.stderr)
                self.assertNotIn("| frame ", r.stdout)

    def test_bad_arguments(self):
        a = self.fake("A", [10])
        for args in ([a, "/nonexistent", "256", "2"], [a, a, "256"], [a, a, "256", "2", "24", "0"],
                     [a, a, "x", "2"], [a, a, "256", "2", "24", "1", "-1"]):
            with self.subTest(args=args):
                r = self.run_script(*args)
                self.assertEqual(r.returncode, 2)
                self.assertTrue(r.stderr.strip())


if __name__ == "__main__":
    unittest.main()
