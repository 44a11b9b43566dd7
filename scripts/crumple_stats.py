#!/usr/bin/python3
"""Statistics of one crumple (issue 12): runs `crumple run --paper ARGS` once and measures what a
crumple is. (--paper: every command line of the study names its configuration as changes to the
paper's, so that its meaning does not follow the command's default; docs/DECISIONS.md D28.)

    /usr/bin/python3 scripts/crumple_stats.py -- --grid 64 --seed 3 [crumple run options]
        -> prints one JSON object

Measures (each a number per run; a crumple is compared by seed means against seed spread):
- splits, restores: totals over the run (stats.csv);
- vertices: live vertices at the end;
- crease_norm: length of the mesh edges whose dihedral angle exceeds 30 degrees, divided by
  sqrt of the initial sheet area (scripts/crease.py);
- radius_norm: compaction radius, the RMS distance of the vertices from their centroid,
  divided by sqrt(A0) (a flat unit square: 0.408);
- kinetic_end: kinetic energy at the last frame; kinetic: the series, every `--ke-every` frames;
- edge_hist: histogram of the final mesh-edge lengths divided by the input's mean edge length
  (bins of EDGE_BINS); edge_mean: the mean of that ratio (a facet-size measure);
- ms_frame, ms_frame_mean: median and mean wall time of a frame (stats.csv step_ms), exit: crumple's
  exit code.

Python API: measure(args, work_dir) -> dict. Used by scripts/crumple_study.py.
"""
import json
import os
import subprocess
import sys
import tempfile

import numpy as np

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from crease import crease_stats  # noqa: E402
from render import load_obj  # noqa: E402

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
EXE = os.environ.get("CRUMPLE_EXE", os.path.join(ROOT, "build-acc", "app", "crumple"))
EDGE_BINS = np.linspace(0.0, 1.6, 33)
KE_EVERY = 6  # frames between the kinetic series' samples (0.1 s at 60 Hz)


def read_stats(path):
    rows = np.genfromtxt(path, delimiter=",", names=True)
    return np.atleast_1d(rows)


def mesh_edges(F):
    e = np.concatenate([F[:, [0, 1]], F[:, [1, 2]], F[:, [2, 0]]])
    e.sort(axis=1)
    return np.unique(e, axis=0)


def input_mean_edge(args):
    """Mean edge length of the input: the N x N unit grid (alternating diagonals) or an OBJ."""
    if "--mesh" in args:
        V, F, _ = load_obj(args[args.index("--mesh") + 1])
    else:
        n = int(args[args.index("--grid") + 1]) if "--grid" in args else 32
        V, F, _ = grid_mesh(n)
    E = mesh_edges(np.asarray(F))
    V = np.asarray(V)
    return float(np.linalg.norm(V[E[:, 0]] - V[E[:, 1]], axis=1).mean()), V, F


def grid_mesh(n):
    """The unit N x N grid's vertices and triangles (edge lengths only: diagonals do not matter)."""
    xs = np.linspace(0.0, 1.0, n)
    V = np.array([[x, y, 0.0] for y in xs for x in xs])
    F = []
    for j in range(n - 1):
        for i in range(n - 1):
            a, b, c, d = j * n + i, j * n + i + 1, (j + 1) * n + i + 1, (j + 1) * n + i
            F += [[a, b, c], [a, c, d]]
    return V, np.array(F), None


def area(V, F):
    V = np.asarray(V, float)
    F = np.asarray(F)
    return float(0.5 * np.linalg.norm(np.cross(V[F[:, 1]] - V[F[:, 0]], V[F[:, 2]] - V[F[:, 0]]), axis=1).sum())


def measure(args, work, ke_every=KE_EVERY, timeout=7200):
    """Runs `crumple run ARGS --out WORK --quiet` and returns its statistics (see the module doc)."""
    args = [str(a) for a in args]
    # The paper's configuration is the base every command line of the study changes (D28).
    p = subprocess.run([EXE, "run", "--paper"] + args + ["--out", work, "--quiet"], capture_output=True, text=True,
                       timeout=timeout)
    out = {"args": args, "exit": p.returncode}
    if p.returncode != 0:
        out["error"] = p.stderr.strip()
        return out
    st = read_stats(os.path.join(work, "stats.csv"))
    V, F, L = load_obj(os.path.join(work, "final.obj"))
    l_mean, V0, F0 = input_mean_edge(args)
    c = crease_stats(V, F, L, ref_area=area(V0, F0))
    E = mesh_edges(np.asarray(F))
    V = np.asarray(V)
    ratio = np.linalg.norm(V[E[:, 0]] - V[E[:, 1]], axis=1) / l_mean
    hist, _ = np.histogram(np.clip(ratio, EDGE_BINS[0], EDGE_BINS[-1] - 1e-9), bins=EDGE_BINS)
    out.update({
        "splits": int(st["splits"].sum()),
        "restores": int(st["restores"].sum()),
        "vertices": int(st["vertices"][-1]),
        "crease_norm": c["crease_norm"],
        "radius_norm": c["rms_radius_norm"],
        "kinetic_end": float(st["kinetic"][-1]),
        "kinetic": [float(k) for k in st["kinetic"][ke_every - 1::ke_every]],
        "edge_hist": [int(h) for h in hist],
        "edge_mean": float(ratio.mean()),
        "ms_frame": float(np.median(st["step_ms"])),
        "ms_frame_mean": float(np.mean(st["step_ms"])),
        "frames": int(len(st)),
    })
    return out


def main(argv=None):
    argv = sys.argv[1:] if argv is None else argv
    if argv and argv[0] == "--":
        argv = argv[1:]
    with tempfile.TemporaryDirectory() as d:
        r = measure(argv, d)
    print(json.dumps(r, indent=2))
    return 0 if r["exit"] == 0 else 1


if __name__ == "__main__":
    sys.exit(main())
