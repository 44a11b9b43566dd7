#!/usr/bin/python3
"""Runs the stability tests (tests/model/test_stability.cpp, GoogleTest) and saves what they
measured (their RecordProperty values: omega_max, h_crit, the observed explicit limit, ...).

    /usr/bin/python3 scripts/stability_tests.py [--build build-acc]

Writes results/accuracy/stability_tests.json. Exit status: the test binary's.
"""
import argparse
import os
import subprocess
import sys
import tempfile
import xml.etree.ElementTree as ET

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import accuracy_common as ac  # noqa: E402


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--build", default=os.path.join(ac.ROOT, "build-acc"))
    a = ap.parse_args()
    exe = os.path.join(a.build, "tests", "test_model")
    with tempfile.TemporaryDirectory() as d:
        xml = os.path.join(d, "out.xml")
        p = subprocess.run([exe, "--gtest_filter=*Stability*", f"--gtest_output=xml:{xml}"],
                           capture_output=True, text=True)
        root = ET.parse(xml).getroot()
    tests = []
    for tc in root.iter("testcase"):
        props = {pr.get("name"): pr.get("value") for pr in tc.iter("property")}
        failures = [f.get("message") for f in tc.iter("failure")]
        tests.append({"name": tc.get("name"), "time_s": float(tc.get("time", 0)), "passed": not failures,
                      "failures": failures, "properties": props})
    out = {"what": "tests/model/test_stability.cpp: measured values", "exit": p.returncode,
           "total_time_s": round(sum(t["time_s"] for t in tests), 3), "tests": tests}
    ac.save_json(os.path.join(ac.OUT, "stability_tests.json"), out)
    for t in tests:
        print(f"{'ok  ' if t['passed'] else 'FAIL'} {t['name']} ({t['time_s']:.2f} s) {t['properties']}")
    return p.returncode


if __name__ == "__main__":
    sys.exit(main())
