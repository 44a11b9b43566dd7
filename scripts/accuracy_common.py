#!/usr/bin/python3
"""Shared helpers of the accuracy / stability study (issue 5): running `crumple run`, reading its
outputs, the scenes, the methods, energies.

Used by scripts/accuracy_reference.py, accuracy_sweep.py, stability_map.py,
accuracy_adaptive.py and recommend.py. Not a command.
"""
import csv
import json
import math
import os
import subprocess
import tempfile
import time

import numpy as np

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
OUT = os.environ.get("CRUMPLE_ACC_OUT", os.path.join(ROOT, "results", "accuracy"))
EXE = os.environ.get("CRUMPLE_EXE", os.path.join(ROOT, "build-acc", "app", "crumple"))

UNSTABLE = 3

# --- scenes of the accuracy study -------------------------------------------------------------
# hang: the two top corners pinned, gravity. The hang scene keeps the manipulation sphere of the
# sphere scene (core/sim/scene.cpp gives every non-free scene a sphere that shrinks to 0.3 of the
# reach in 2 s), which would squeeze the hanging sheet; a sphere of 100 reaches never touches it.
# --perturb 0.01: a small deterministic dome, so the buckling branch is well defined (an exactly
# flat, symmetric start lets float and double runs pick different branches).
GRID = 16
SCENES = {
    "hang": ["--scene", "hang", "--gravity", "9.81", "--no-fracture", "--no-restoration",
             "--sphere-start", "100", "--sphere-end", "100", "--perturb", "0.01"],
    "free": ["--scene", "free", "--squeeze", "0.8", "--no-fracture", "--no-restoration",
             "--perturb", "0.01"],
}
SCENE_TEXT = {
    "hang": "16 x 16 sheet hanging from its two top corners, gravity 9.81, fracture and "
            "restoration off, dome 0.01",
    "free": "16 x 16 sheet released from a squeeze of 0.8, fracture and restoration off, dome 0.01",
}
SHEET_SIZE = math.sqrt(2.0)  # the unit square's diagonal: errors are divided by it

# --- methods --------------------------------------------------------------------------------------
# name -> (crumple options, backend used for cost and error, threads)
METHODS = {
    "explicit": (["--integrator", "explicit"], "fast", 2),
    "approx-K1": (["--integrator", "approx", "--sweeps", "1"], "fast", 2),
    "approx-K2": (["--integrator", "approx", "--sweeps", "2"], "fast", 2),
    "approx-K4": (["--integrator", "approx", "--sweeps", "4"], "fast", 2),
    "approx-K8": (["--integrator", "approx", "--sweeps", "8"], "fast", 2),
    "approx-K1-paper": (["--integrator", "approx", "--sweeps", "1", "--predictor", "explicit"], "fast", 2),
    "implicit-1e-3": (["--integrator", "implicit", "--cg-tolerance", "1e-3"], "reference", 1),
    "implicit-1e-8": (["--integrator", "implicit", "--cg-tolerance", "1e-8"], "reference", 1),
}
METHOD_TEXT = {
    "explicit": "symplectic Euler",
    "approx-K1": "approx. implicit, K=1 (paper), bounded predictor",
    "approx-K2": "approx. implicit, K=2",
    "approx-K4": "approx. implicit, K=4",
    "approx-K8": "approx. implicit, K=8",
    "approx-K1-paper": "approx. implicit, K=1, paper's explicit predictor",
    "implicit-1e-3": "Baraff-Witkin + CG, tol 1e-3",
    "implicit-1e-8": "Baraff-Witkin + CG, tol 1e-8",
}
COLORS = {
    "explicit": "#444444", "approx-K1": "#1f77b4", "approx-K2": "#2ca02c", "approx-K4": "#17becf",
    "approx-K8": "#9467bd", "approx-K1-paper": "#d62728", "implicit-1e-3": "#ff7f0e",
    "implicit-1e-8": "#8c564b", "reference": "#000000",
}
MARKERS = {
    "explicit": "o", "approx-K1": "s", "approx-K2": "D", "approx-K4": "^", "approx-K8": "v",
    "approx-K1-paper": "x", "implicit-1e-3": "P", "implicit-1e-8": "*",
}
STEPS = [1000, 480, 240, 120, 60, 30]  # steps per second: h = 1/n (the range)
# The accuracy sweep adds smaller steps so that the tighter error budgets get an answer: 1/2000
# and 1/4000 for every method, 1/8000 and 1/16000 for symplectic Euler (cheap).
EXTRA_STEPS = {m: [4000, 2000] for m in METHODS}
EXTRA_STEPS["explicit"] = [16000, 8000, 4000, 2000]


def sweep_steps(method):
    return EXTRA_STEPS.get(method, []) + STEPS


def timing_note():
    return ("timings come from a shared 2-core machine (" + cpu_model() + "); medians of "
            "interleaved repetitions; noisy: ~10-20 % within a session, up to 2x between sessions")


def cpu_model():
    try:
        out = subprocess.run(["lscpu"], capture_output=True, text=True,
                             env=dict(os.environ, LC_ALL="C")).stdout
    except OSError:
        return "unknown"
    model, cpus, flags = "unknown", "?", set()
    for line in out.splitlines():
        k, _, v = line.partition(":")
        if k.strip() == "Model name":
            model = v.strip()
        if k.strip() == "CPU(s)":
            cpus = v.strip()
        if k.strip() == "Flags":
            flags = set(v.split())
    # Two VMs that lscpu names alike ("AMD EPYC") differ in their widest SIMD and in speed.
    simd = next((name for flag, name in (("avx512f", "AVX-512"), ("avx2", "AVX2")) if flag in flags), None)
    return f"{model}, {cpus} CPUs" + (f", {simd}" if simd else "")


def frames_for(steps_per_second, seconds=1.0):
    """--frame-dt, --frames, --substeps for h = 1/steps_per_second over `seconds`: frames of
    1/60 s (or an integer fraction of it) when 60 divides the step count per second, else
    frames as close to 1/60 s as the step allows. Frame boundaries land exactly on the step grid;
    crumple allows at most 10000 substeps per frame."""
    n = steps_per_second
    total = int(round(n * seconds))
    divisors = [s for s in range(1, min(n, 10000) + 1) if n % s == 0]
    sixty = [s for s in divisors if (n // s) % 60 == 0]
    if sixty:
        best = max(sixty)
    else:
        want = max(1.0, n / 60.0)
        best = min(divisors, key=lambda s: abs(math.log(s / want)))
    return {"frame_dt": best / n, "frames": total // best, "substeps": best}


def pinned_base(args):
    """`crumple run` options that keep a study's command lines meaning what they meant when it
    was run: the paper's configuration as the base its options change (--paper), and the
    reference backend where none is named (the command's defaults before D28)."""
    args = [str(a) for a in args]
    return ["--paper"] + ([] if "--backend" in args else ["--backend", "reference"]) + args


def crumple(args, out=None, timeout=3600):
    """Runs `crumple run --paper ARGS [--out OUT] --quiet` (pinned_base); returns (exit code,
    wall seconds, stderr)."""
    cmd = [EXE, "run"] + pinned_base(args) + ["--quiet"]
    if out:
        cmd += ["--out", out]
    t0 = time.perf_counter()
    p = subprocess.run(cmd, capture_output=True, text=True, timeout=timeout)
    return p.returncode, time.perf_counter() - t0, p.stderr.strip()


def step_args(steps_per_second, seconds=1.0):
    f = frames_for(steps_per_second, seconds)
    return ["--frame-dt", repr(f["frame_dt"]), "--frames", f["frames"], "--substeps", f["substeps"]]


def read_stats(path):
    with open(path) as f:
        rows = list(csv.DictReader(f))
    out = {}
    for key in rows[0].keys() if rows else []:
        out[key] = np.array([float(r[key]) for r in rows])
    return out


def read_obj(path):
    V, F, L = [], [], []
    with open(path) as f:
        for line in f:
            if line.startswith("v "):
                V.append([float(t) for t in line.split()[1:4]])
            elif line.startswith("f "):
                F.append([int(t.split("/")[0]) - 1 for t in line.split()[1:4]])
            elif line.startswith("l "):
                L.append([int(t) - 1 for t in line.split()[1:3]])
    return np.array(V), np.array(F, dtype=np.int64), np.array(L, dtype=np.int64).reshape(-1, 2)


def rms_error(x, ref):
    """RMS vertex distance divided by the sheet size (the unit square's diagonal)."""
    return float(np.sqrt(((x - ref) ** 2).sum(axis=1).mean()) / SHEET_SIZE)


# --- energy ---------------------------------------------------------------------------------------
_rest_cache = {}


def rest_mesh(grid=GRID):
    """Rest positions, triangles, edges, vertex masses (total 1, by area) of the N x N grid, read
    from a run with every force off (one frame, nothing moves)."""
    if grid in _rest_cache:
        return _rest_cache[grid]
    with tempfile.TemporaryDirectory() as d:
        rc, _, err = crumple(["--grid", grid, "--scene", "free", "--squeeze", "1", "--perturb", "0",
                              "--kappa", "0", "--bend", "0", "--frames", "1", "--no-fracture"], d)
        assert rc == 0, err
        X, F, _ = read_obj(os.path.join(d, "final.obj"))
    E = np.concatenate([F[:, [0, 1]], F[:, [1, 2]], F[:, [2, 0]]])
    E = np.unique(np.sort(E, axis=1), axis=0)
    area = 0.5 * np.linalg.norm(np.cross(X[F[:, 1]] - X[F[:, 0]], X[F[:, 2]] - X[F[:, 0]]), axis=1)
    m = np.zeros(len(X))
    for k in range(3):
        np.add.at(m, F[:, k], area / 3)
    m /= area.sum()
    l0 = np.linalg.norm(X[E[:, 0]] - X[E[:, 1]], axis=1)
    _rest_cache[grid] = (X, F, E, m, l0)
    return _rest_cache[grid]


def potential(x, kappa, gravity, grid=GRID):
    """(spring potential, gravitational potential) of positions x on the rest grid (no fracture:
    the topology is the input's). Bending [Eq 9] has no potential and is left out."""
    X, F, E, m, l0 = rest_mesh(grid)
    lt = np.linalg.norm(x[E[:, 0]] - x[E[:, 1]], axis=1)
    ke = kappa * (m[E[:, 0]] + m[E[:, 1]])
    spring = float(0.5 * (ke * (lt - l0) ** 2).sum())
    grav = float(gravity * (m * x[:, 2]).sum())
    return spring, grav


def energy_from_dir(scene, kappa, n, d):
    """Energy per 1/60 s of a finished run in d (written with --every 1/60 s): kinetic
    (stats.csv), spring potential and gravitational potential (from the frame OBJs). Bending
    [Eq 9] has no potential: it is not in the total."""
    f = frames_for(n)
    per = max(1, int(round((1.0 / 60) / f["frame_dt"])))
    st = read_stats(os.path.join(d, "stats.csv"))
    gravity = 9.81 if scene == "hang" else 0.0
    out = {"time": [0.0], "kinetic": [0.0], "spring": [], "gravity": []}
    sp, gp = potential(initial_positions(scene), kappa, gravity)  # t = 0: at rest
    out["spring"].append(sp)
    out["gravity"].append(gp)
    for i in range(len(st["frame"])):
        fr = int(st["frame"][i])
        p = os.path.join(d, f"frame_{fr:05d}.obj")
        if fr % per or not os.path.exists(p):
            continue
        sp, gp = potential(read_obj(p)[0], kappa, gravity)
        out["time"].append(float(st["time"][i]))
        out["kinetic"].append(float(st["kinetic"][i]))
        out["spring"].append(sp)
        out["gravity"].append(gp)
    return out


_init = {}


def without(args, option):
    """args with `option VALUE` removed."""
    out, skip = [], False
    for a in args:
        if skip:
            skip = False
            continue
        if a == option:
            skip = True
            continue
        out.append(a)
    return out


def initial_positions(scene):
    """The scene's state at t = 0 (a run of 1 frame with every force off writes it unchanged)."""
    if scene in _init:
        return _init[scene]
    with tempfile.TemporaryDirectory() as d:
        args = ["--grid", GRID] + without(SCENES[scene], "--gravity") + [
            "--kappa", 0, "--bend", 0, "--frames", 1, "--integrator", "explicit"]
        rc, _, err = crumple(args, d)
        assert rc == 0, err
        _init[scene] = read_obj(os.path.join(d, "final.obj"))[0]
    return _init[scene]


def save_json(path, data):
    os.makedirs(os.path.dirname(path), exist_ok=True)
    tmp = path + ".tmp"
    with open(tmp, "w") as f:
        json.dump(data, f, indent=1, sort_keys=False)
    os.replace(tmp, path)


def load_json(path):
    with open(path) as f:
        return json.load(f)


def fmt_h(n):
    return f"1/{n}"
