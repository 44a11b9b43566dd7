"""scripts/machine_info.py's results-folder tag. Wrong code this catches: two core generations
behind one generic VM model name ("AMD EPYC") given one tag, so that a run on one overwrites the
other's results; AMD family 19h's Zen 3 and Zen 4 model ranges confused; a generation appended
to a name that has a model number (the folder of a named CPU would change for nothing); an Intel
model number read without its family 6, or a client core (model 151, Alder Lake) taken for a
server one; a clock in the name ("@ 2.20GHz") taken for a model number. Class CpuUse names its
own, as does class Folder."""
import json
import os
import subprocess
import sys
import tempfile
import unittest

sys.path.insert(0, os.path.join(os.path.dirname(__file__), "..", "..", "scripts"))
import machine_info  # noqa: E402

AVX512 = {"Flags": "fpu avx2 avx512f"}


def tag(model, cpu, flags=AVX512):
    return machine_info.tag(dict(flags, **{"Model name": model}), cpu)


class Tag(unittest.TestCase):
    def test_generations_behind_one_generic_name_differ(self):
        self.assertEqual(tag("AMD EPYC", ("AuthenticAMD", 26, 2)), "amd-epyc-zen5_avx512")
        self.assertEqual(tag("AMD EPYC", ("AuthenticAMD", 25, 0x11)), "amd-epyc-zen4_avx512")
        self.assertEqual(tag("AMD EPYC", ("AuthenticAMD", 25, 0x01)), "amd-epyc-zen3_avx512")
        self.assertEqual(tag("AMD EPYC", ("AuthenticAMD", 25, 0xA0)), "amd-epyc-zen4_avx512")
        self.assertEqual(tag("AMD EPYC", ("AuthenticAMD", 23, 0x31), {"Flags": "avx2"}), "amd-epyc-zen2_avx2")

    def test_a_model_number_needs_no_generation(self):
        self.assertEqual(tag("AMD EPYC 9654 96-Core Processor", ("AuthenticAMD", 25, 0x11)), "amd-epyc-9654_avx512")

    def test_intel_generations_behind_one_generic_name_differ(self):
        xeon = "Intel(R) Xeon(R) Processor"
        self.assertEqual(tag(xeon, ("GenuineIntel", 6, 207)), "intel-xeon-emr_avx512")
        self.assertEqual(tag(xeon, ("GenuineIntel", 6, 143)), "intel-xeon-spr_avx512")
        self.assertEqual(tag(xeon, ("GenuineIntel", 6, 85)), "intel-xeon-skx_avx512")
        self.assertEqual(tag("Intel(R) Xeon(R) CPU @ 2.20GHz", ("GenuineIntel", 6, 85)), "intel-xeon-skx_avx512")
        self.assertEqual(tag("Intel(R) Xeon(R) Gold 6430", ("GenuineIntel", 6, 143)), "intel-xeon-gold-6430_avx512")

    def test_unknown_generations_keep_the_plain_name(self):
        self.assertEqual(tag("Intel(R) Xeon(R) Processor", ("GenuineIntel", 6, 151)), "intel-xeon_avx512")
        self.assertEqual(tag("Intel(R) Xeon(R) Processor", ("GenuineIntel", 15, 207)), "intel-xeon_avx512")
        self.assertEqual(tag("AMD EPYC", ("", -1, -1)), "amd-epyc_avx512")


class CpuUse(unittest.TestCase):
    """The CPUs' busy and stolen shares between two /proc/stat readings. Wrong code this catches:
    a per-CPU line read instead of the aggregate one, iowait counted as busy, guest time counted
    twice (it is inside user already), steal left out of the total, the shares of the totals
    since boot instead of the difference."""

    BEFORE = "cpu  1000 0 500 8000 400 10 10 80 300 0\ncpu0 1 1 1 1 1 1 1 1 1 1\nintr 9\n"
    AFTER = "cpu  1100 0 550 8300 420 10 20 100 350 0\ncpu0 2 2 2 2 2 2 2 2 2 2\nintr 10\n"

    def test_shares_of_the_difference(self):
        before, after = machine_info.cpu_times(self.BEFORE), machine_info.cpu_times(self.AFTER)
        self.assertEqual(before, (1520, 8400, 80))
        # Busy 160 (user 100, system 50, softirq 10), idle 320 (idle 300, iowait 20), steal 20.
        self.assertEqual(machine_info.cpu_use(before, after, 3), {"seconds": 3, "busy": 0.32, "steal": 0.04})

    def test_a_kernel_without_steal_and_no_reading(self):
        self.assertEqual(machine_info.cpu_times("cpu 1 2 3 4\n"), (6, 4, 0))
        self.assertEqual(machine_info.cpu_use(None, (1, 2, 3), 3), {})
        self.assertEqual(machine_info.cpu_use((1, 2, 3), (1, 2, 3), 0), {})  # no time between: no shares
        self.assertIsNone(machine_info.cpu_times("intr 5\n"))


class Folder(unittest.TestCase):
    """scripts/bench.sh's guard against writing one machine's run into another's results folder.
    Wrong code this catches: the tags compared the wrong way (a folder of this machine refused, or
    another's accepted), a folder without run.json refused (a new --out folder could never be
    used), an unreadable run.json taken as free (a crash or an overwrite), a refusal that exits 0
    or prints more than one line."""

    SCRIPT = os.path.join(os.path.dirname(__file__), "..", "..", "scripts", "machine_info.py")

    def setUp(self):
        self.dir = tempfile.TemporaryDirectory()
        self.folder = self.dir.name

    def tearDown(self):
        self.dir.cleanup()

    def write_run(self, text):
        with open(os.path.join(self.folder, "run.json"), "w") as f:
            f.write(text)

    def test_a_folder_without_a_run_is_free(self):
        self.assertIsNone(machine_info.folder_conflict(self.folder, "intel-xeon-icx_avx512"))

    def test_only_this_machines_tag_may_write(self):
        self.write_run(json.dumps({"machine": {"tag": "amd-epyc-zen5_avx512"}}))
        self.assertIsNone(machine_info.folder_conflict(self.folder, "amd-epyc-zen5_avx512"))
        problem = machine_info.folder_conflict(self.folder, "intel-xeon-icx_avx512")
        self.assertIn("amd-epyc-zen5_avx512", problem)
        self.assertIn("results/intel-xeon-icx_avx512", problem)

    def test_an_unreadable_run_is_refused(self):
        for text in ("{not json", json.dumps({"mode": "full"}), json.dumps([1])):
            self.write_run(text)
            self.assertIn("cannot be read", machine_info.folder_conflict(self.folder, "x_avx2"))

    def test_the_command_exits_2_with_one_line(self):
        self.write_run(json.dumps({"machine": {"tag": "no-such-machine_sse"}}))
        bad = subprocess.run([sys.executable, self.SCRIPT, "--check-folder", self.folder],
                             capture_output=True, text=True)
        self.assertEqual(bad.returncode, 2)
        self.assertEqual(len(bad.stderr.strip().splitlines()), 1, bad.stderr)
        self.assertIn("no-such-machine_sse", bad.stderr)
        os.remove(os.path.join(self.folder, "run.json"))
        free = subprocess.run([sys.executable, self.SCRIPT, "--check-folder", self.folder],
                              capture_output=True, text=True)
        self.assertEqual((free.returncode, free.stderr), (0, ""))


if __name__ == "__main__":
    unittest.main()
