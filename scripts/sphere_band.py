#!/usr/bin/python3
"""The default sphere crumple over seeds: the band that Runs.SphereCrumpleDefaults asserts.

    /usr/bin/python3 scripts/sphere_band.py [build-dir] [seeds]
        -> results/sphere_band/stats.csv (one row a run) and results/sphere_band/band.json

Runs `crumple run --paper --grid 16 --frames 150 --seed S --backend B` with every other option
at the paper's configuration (the run the test makes: make_grid(16), Params{}, 150 steps of one
frame each) for seeds
1..seeds (default 16) on both backends, and records each run's splits and restores (summed over
stats.csv) and its live vertices at the end. band.json holds, per quantity over all runs of both
backends (they agree in distribution, tests/model/test_agreement.cpp), the mean, the sample
standard deviation and the band mean +- 4 sd, rounded outward to integers.
"""
import csv
import json
import math
import os
import subprocess
import sys
import tempfile

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
OUT = os.path.join(ROOT, "results", "sphere_band")
QUANTITIES = ("splits", "restores", "vertices")


def run(exe, backend, seed, work):
    out = os.path.join(work, f"{backend}_{seed}")
    cmd = [exe, "run", "--paper", "--grid", "16", "--frames", "150", "--seed", str(seed), "--backend", backend,
           "--out", out, "--quiet"]
    subprocess.run(cmd, check=True)
    with open(os.path.join(out, "stats.csv")) as f:
        rows = list(csv.DictReader(f))
    return {"backend": backend, "seed": seed, "splits": sum(int(r["splits"]) for r in rows),
            "restores": sum(int(r["restores"]) for r in rows), "vertices": int(rows[-1]["vertices"])}


def band(values):
    mean = sum(values) / len(values)
    sd = math.sqrt(sum((v - mean) ** 2 for v in values) / (len(values) - 1))
    return {"mean": round(mean, 2), "sd": round(sd, 2), "low": math.floor(mean - 4 * sd),
            "high": math.ceil(mean + 4 * sd)}


def main():
    build = sys.argv[1] if len(sys.argv) > 1 else os.path.join(ROOT, "build")
    seeds = int(sys.argv[2]) if len(sys.argv) > 2 else 16
    exe = os.path.join(build, "app", "crumple")
    with tempfile.TemporaryDirectory() as work:
        runs = [run(exe, b, s, work) for b in ("reference", "fast") for s in range(1, seeds + 1)]
    os.makedirs(OUT, exist_ok=True)
    with open(os.path.join(OUT, "stats.csv"), "w", newline="") as f:
        w = csv.DictWriter(f, fieldnames=["backend", "seed", *QUANTITIES])
        w.writeheader()
        w.writerows(runs)
    result = {"command": "crumple run --paper --grid 16 --frames 150 --seed S --backend B", "seeds": seeds,
              "runs": len(runs), **{q: band([r[q] for r in runs]) for q in QUANTITIES}}
    with open(os.path.join(OUT, "band.json"), "w") as f:
        json.dump(result, f, indent=2)
        f.write("\n")
    print(json.dumps(result, indent=2))


if __name__ == "__main__":
    main()
