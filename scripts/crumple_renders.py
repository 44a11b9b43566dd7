#!/usr/bin/python3
"""Issue 12's renders side by side: the same 3 s sphere crumple of an N x N sheet (seed 1) in the
paper's configuration, the default, the converged damped model and the undamped model.

    CRUMPLE_EXE=build/app/crumple /usr/bin/python3 scripts/crumple_renders.py [--grid 64]
        [--seed 1] [--out results/accuracy/crumple] [--reuse]

Writes crumple_renders_N<grid>.png there, each panel titled with its configuration and its run's
splits, restores and vertices at the end (from stats.csv), and keeps every run's final.obj and
stats.csv under <out>/renders_N<grid>/<name>/ (not committed: 4 MB at N = 64; --reuse draws
from them instead of running again). Every run is the fast backend on two threads:
- paper      `--paper` (one approximate implicit step a frame, fracture every step);
- default    no options (D28: symplectic Euler with c = kappa h_ref, steps of at most 1/3840 s,
             the fracture/restoration pass every 1/240 s);
- converged  the paper's model with the same viscosity and 256 steps a frame, the pass after every
             step: the converge stage's reference level at N = 64 (crumple_study.py), on the fast
             backend;
- undamped   the paper's model with symplectic Euler, 64 steps a frame and no viscosity.
"""
import argparse
import os
import subprocess
import sys

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, HERE)
from crumple_study import C, OUT  # noqa: E402
from crumple_stats import EXE  # noqa: E402
from render import load_obj, render_mesh  # noqa: E402

CONFIGS = [
    ("paper", "the paper's (--paper)", ["--paper"]),
    ("default", "the default", []),
    ("converged", "converged (c = %s, 256 steps)" % C,
     ["--paper", "--integrator", "explicit", "--viscosity", C, "--substeps", "256"]),
    ("undamped", "undamped (64 steps, c = 0)", ["--paper", "--integrator", "explicit", "--substeps", "64"]),
]


def totals(stats_csv):
    """Total splits and restores over the frames, and the vertices at the end."""
    with open(stats_csv) as fh:
        head = fh.readline().strip().split(",")
        rows = [dict(zip(head, line.strip().split(","))) for line in fh if line.strip()]
    if not rows:
        raise RuntimeError(f"{stats_csv} has no frames")
    return (sum(int(float(r["splits"])) for r in rows), sum(int(float(r["restores"])) for r in rows),
            int(float(rows[-1]["vertices"])))


def run(name, options, grid, seed, out, reuse):
    folder = os.path.join(out, name)
    obj, stats = os.path.join(folder, "final.obj"), os.path.join(folder, "stats.csv")
    if reuse and os.path.exists(obj) and os.path.exists(stats):
        return obj, totals(stats)
    os.makedirs(folder, exist_ok=True)
    cmd = [EXE, "run"] + options + ["--grid", str(grid), "--seed", str(seed), "--backend", "fast",
                                    "--threads", "2", "--quiet", "--force", "--out", folder]
    print("crumple_renders:", " ".join(cmd), flush=True)
    p = subprocess.run(cmd, capture_output=True, text=True)
    if p.returncode != 0:
        sys.exit(f"crumple_renders: {name} failed (exit {p.returncode}): {p.stderr.strip()}")
    return obj, totals(stats)


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--grid", type=int, default=64)
    ap.add_argument("--seed", type=int, default=1)
    ap.add_argument("--out", default=OUT)
    ap.add_argument("--reuse", action="store_true", help="draw from the kept runs where both files exist")
    a = ap.parse_args(argv)
    if not os.path.exists(EXE):
        sys.exit(f"crumple_renders: no crumple at {EXE} (set CRUMPLE_EXE)")
    runs = os.path.join(a.out, f"renders_N{a.grid}")
    fig = plt.figure(figsize=(4 * len(CONFIGS), 4.6))
    for k, (name, title, options) in enumerate(CONFIGS):
        obj, (splits, restores, vertices) = run(name, options, a.grid, a.seed, runs, a.reuse)
        V, F, L = load_obj(obj)
        ax = fig.add_subplot(1, len(CONFIGS), k + 1, projection="3d", proj_type="ortho")
        render_mesh(V, F, L, ax=ax, elev=35, azim=-60, fill=0.9)
        ax.set_title(f"{title}\n{splits:,} splits, {restores:,} restores, {vertices:,} vertices", fontsize=9)
    fig.suptitle(f"The same 3 s sphere crumple, N = {a.grid}, seed {a.seed} (fast backend)", fontsize=11)
    fig.tight_layout(rect=(0, 0, 1, 0.93))  # room for the suptitle above the panel titles
    path = os.path.join(a.out, f"crumple_renders_N{a.grid}.png")
    fig.savefig(path, dpi=110)
    print("crumple_renders: wrote", path)


if __name__ == "__main__":
    main()
