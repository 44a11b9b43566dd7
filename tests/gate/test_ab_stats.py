"""Tests of scripts/ab_stats.sh (the crumple statistics of two crumple binaries) with two fake
crumple binaries that write a known stats.csv for each seed.

Wrong code this catches: the per-frame split and restore counts taken from the last frame (or
the vertex count summed) instead of totals and the final count; the seed not passed (every run
alike); a failing or missing binary accepted silently.
"""
import os
import subprocess
import textwrap
import unittest
from pathlib import Path

from fake_tools import FakeToolsCase

ROOT = Path(__file__).resolve().parents[2]
AB_STATS = ROOT / "scripts" / "ab_stats.sh"

# Seed s writes two frames: splits 10 s and 5 (+ shift), restores 2 and 1, vertices 1 then 100 s.
FAKE = textwrap.dedent("""\
    #!/usr/bin/python3
    import os, sys
    shift, fail = {shift!r}, {fail!r}
    if fail:
        print("crumple: error: broken", file=sys.stderr)
        sys.exit(2)
    seed = int(sys.argv[sys.argv.index("--seed") + 1])
    out = sys.argv[sys.argv.index("--out") + 1]
    os.makedirs(out)
    with open(os.path.join(out, "stats.csv"), "w") as f:
        f.write("frame,vertices,splits,restores\\n")
        f.write(f"1,1,{{10 * seed}},2\\n")
        f.write(f"2,{{100 * seed}},{{5 + shift}},1\\n")
""")


class AbStatsScript(FakeToolsCase):
    def fake(self, name, shift=0, fail=False):
        return self.write_fake(name, FAKE.format(shift=shift, fail=fail))

    def run_script(self, a, b, seeds="4"):
        return subprocess.run(["bash", str(AB_STATS), a, b, seeds, "--", "--grid", "8"], capture_output=True,
                              text=True)

    def test_totals_final_count_and_standard_errors(self):
        r = self.run_script(self.fake("A"), self.fake("B", shift=1))
        self.assertEqual(r.returncode, 0, r.stderr)
        rows = {line.split("|")[1].strip(): line for line in r.stdout.splitlines() if line.startswith("| ")}
        # splits: 15, 25, 35, 45 (mean 30, sd 12.9) against 16 ... 46; se = 12.9 * sqrt(2 / 4)
        self.assertEqual(rows["splits"], "| splits | 30.0 +- 12.9 | 31.0 +- 12.9 | +3.33 % | +0.11 |")
        self.assertEqual(rows["restores"], "| restores | 3.0 +- 0.0 | 3.0 +- 0.0 | +0.00 % | +0.00 |")
        self.assertEqual(rows["vertices"], "| vertices | 250.0 +- 129.1 | 250.0 +- 129.1 | +0.00 % | +0.00 |")

    def test_a_failing_or_missing_binary_is_an_error(self):
        r = self.run_script(self.fake("A"), self.fake("B", fail=True))
        self.assertNotEqual(r.returncode, 0)
        self.assertIn("failed on seed 1", r.stderr)
        r = self.run_script(os.path.join(self.dir.name, "missing"), self.fake("B"))
        self.assertEqual(r.returncode, 2)
        self.assertIn("is not an executable", r.stderr)
        r = self.run_script(self.fake("A"), self.fake("B"), seeds="1")
        self.assertEqual(r.returncode, 2)


if __name__ == "__main__":
    unittest.main()
