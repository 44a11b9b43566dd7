#!/usr/bin/python3
"""Stability map (issue 5): for each method, over stiffness kappa 1e2..1e7 and step h
1/1000..1/30 s, does a 2 s run stay bounded (crumple exit 0) or not (exit 3)?

    /usr/bin/python3 scripts/stability_map.py [--quick] [--jobs 2]

Scenes (16 x 16 grid, fracture ON in both):
  free    the free relax from a squeeze of 0.8 (default fracture and restoration)
  sphere  the sphere crumple (defaults: R 1.0 -> 0.3 of the reach in 2 s)
Methods: symplectic Euler, the approximate implicit method with the paper's explicit predictor
(K = 1) and with the bounded predictor (K = 1, 4), Baraff-Witkin + CG (tolerance 1e-3, 1e-8).
Backends: fast (1 thread) for the first four, reference for Baraff-Witkin. Not timed, so two runs
go at once.

The explicit limit of theory is drawn on the charts: h_crit = 2 / omega_max with omega_max^2 the
largest eigenvalue of M^-1 K for the uniform 16 x 16 grid at rest (K assembled here with numpy
from [Eq 5], eigenvalues by scipy): omega_max = c sqrt(kappa). Fracture adds light vertices and
lowers the limit (tests/model/test_stability.cpp measures by how much).

Writes results/accuracy/stability.json and stability_<scene>.png.
"""
import argparse
import os
import shutil
import sys
from concurrent.futures import ThreadPoolExecutor

import numpy as np

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import accuracy_common as ac  # noqa: E402
from accuracy_reference import kname  # noqa: E402

KAPPAS = [1e2, 1e3, 1e4, 1e5, 1e6, 1e7]
STEPS = ac.STEPS
SECONDS = 2.0
SCENES = {
    "free": ["--scene", "free", "--squeeze", "0.8"],
    "sphere": ["--scene", "sphere"],
}
METHODS = {
    "explicit": (["--integrator", "explicit", "--backend", "fast"], "symplectic Euler"),
    "approx-K1-paper": (["--integrator", "approx", "--predictor", "explicit", "--backend", "fast"],
                        "approx. implicit K=1, paper's explicit predictor"),
    "approx-K1": (["--integrator", "approx", "--sweeps", "1", "--backend", "fast"], "approx. implicit K=1 (bounded)"),
    "approx-K4": (["--integrator", "approx", "--sweeps", "4", "--backend", "fast"], "approx. implicit K=4 (bounded)"),
    "implicit-1e-3": (["--integrator", "implicit", "--cg-tolerance", "1e-3"], "Baraff-Witkin, CG tol 1e-3"),
    "implicit-1e-8": (["--integrator", "implicit", "--cg-tolerance", "1e-8"], "Baraff-Witkin, CG tol 1e-8"),
}


def omega_coefficient(grid=ac.GRID):
    """omega_max / sqrt(kappa) of the uniform grid at rest: K = sum over edges of
    kappa (m_a + m_b) u u^T blocks (flat sheet at rest: only the axial term), M = masses."""
    from scipy.linalg import eigh
    X, F, E, m, l0 = ac.rest_mesh(grid)
    n = len(X)
    K = np.zeros((3 * n, 3 * n))
    for (a, b), l in zip(E, l0):
        u = (X[a] - X[b]) / l
        B = (m[a] + m[b]) * np.outer(u, u)
        for i, j, s in ((a, a, 1), (b, b, 1), (a, b, -1), (b, a, -1)):
            K[3 * i:3 * i + 3, 3 * j:3 * j + 3] += s * B
    Minv_sqrt = np.repeat(1 / np.sqrt(m), 3)
    A = Minv_sqrt[:, None] * K * Minv_sqrt[None, :]
    lam = eigh(A, eigvals_only=True, subset_by_index=[3 * n - 1, 3 * n - 1])[0]
    return float(np.sqrt(lam))


def one(scene, method, kappa, n, work):
    d = os.path.join(work, "stab", f"{scene}_{method}_k{kname(kappa)}_n{n}")
    shutil.rmtree(d, ignore_errors=True)
    f = ac.frames_for(n, SECONDS)
    args = (["--grid", ac.GRID] + SCENES[scene] + METHODS[method][0] + ["--kappa", kappa]
            + ["--frame-dt", repr(f["frame_dt"]), "--frames", f["frames"], "--substeps", f["substeps"]])
    rc, wall, err = ac.crumple(args, d)
    r = {"scene": scene, "method": method, "kappa": kappa, "steps_per_s": n, "exit": rc,
         "bounded": rc == 0, "wall_s": round(wall, 2)}
    st_path = os.path.join(d, "stats.csv")
    if os.path.exists(st_path):
        st = ac.read_stats(st_path)
        if len(st["time"]):
            r["time_reached"] = float(st["time"][-1])
            r["vertices_end"] = int(st["vertices"][-1])
            r["splits"] = int(st["splits"].sum())
    if rc != 0:
        r["why"] = err.replace("crumple: error: ", "")
    shutil.rmtree(d, ignore_errors=True)
    return r


def explicit_limit(c):
    """The explicit method's limit of theory on the uniform grid, h = 2 / (c sqrt kappa), as a
    curve in the map's cell coordinates (x: cell of log h, y: cell of log kappa), half a cell
    beyond the tested ends."""
    xs_h = np.log(1.0 / np.array(STEPS, dtype=float))  # increasing
    # cell centres at log h of each step; extrapolated linearly half a cell beyond the ends
    cx = np.arange(len(STEPS)) + 0.5
    xs_ext = np.concatenate([[xs_h[0] - 0.5 * (xs_h[1] - xs_h[0])], xs_h, [xs_h[-1] + 0.5 * (xs_h[-1] - xs_h[-2])]])
    cx_ext = np.concatenate([[0.0], cx, [len(STEPS)]])
    ks_ext = np.logspace(np.log10(KAPPAS[0]) - 0.5, np.log10(KAPPAS[-1]) + 0.5, 300)
    hs = 2 / (c * np.sqrt(ks_ext))
    xi = np.interp(np.log(hs), xs_ext, cx_ext, left=np.nan, right=np.nan)
    ky = np.log10(np.array(KAPPAS, dtype=float))
    yj = (np.log10(ks_ext) - ky[0]) / (ky[1] - ky[0]) + 0.5
    return xi, yj


def method_map(ax, m, cells, limit):
    """One method's panel: a cell per (step, kappa), green bounded, red failed (labelled with
    the time it reached), and the explicit limit dashed."""
    from matplotlib.patches import Rectangle
    for i, n in enumerate(STEPS):              # x: h grows to the right (STEPS: 1/h falling)
        for j, k in enumerate(KAPPAS):         # y: kappa grows upwards
            r = cells.get((m, k, n))
            if r is None:
                continue
            col = "#7fc97f" if r["bounded"] else "#f0027f"
            ax.add_patch(Rectangle((i, j), 1, 1, facecolor=col, edgecolor="white", lw=2))
            if not r["bounded"]:
                t = r.get("time_reached")
                ax.text(i + 0.5, j + 0.5, f"{t:.2f} s" if t is not None else "x", ha="center", va="center",
                        fontsize=7.5, color="white")
    ax.plot(*limit, color="k", lw=1.5, ls="--", label="explicit limit 2/omega_max (uniform grid)")
    ax.set_xlim(0, len(STEPS))
    ax.set_ylim(0, len(KAPPAS))
    ax.set_xticks(np.arange(len(STEPS)) + 0.5)
    ax.set_xticklabels([f"1/{n}" for n in STEPS], fontsize=8)
    ax.set_yticks(np.arange(len(KAPPAS)) + 0.5)
    ax.set_yticklabels([kname(k) for k in KAPPAS], fontsize=8)
    ax.set_xlabel("step h (s)")
    ax.set_ylabel("kappa")
    nb = sum(1 for k in KAPPAS for n in STEPS if cells.get((m, k, n), {}).get("bounded"))
    ax.set_title(f"{m}: {METHODS[m][1]}\n{nb} of {len(KAPPAS) * len(STEPS)} bounded", fontsize=9.5)
    ax.set_aspect("equal")


def plot(data, scene, path):
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    from matplotlib.patches import Rectangle
    methods = list(METHODS)
    ncol = 3
    nrow = (len(methods) + ncol - 1) // ncol
    fig, axes = plt.subplots(nrow, ncol, figsize=(5.2 * ncol, 4.6 * nrow), squeeze=False)
    cells = {(r["method"], r["kappa"], r["steps_per_s"]): r for r in data["runs"] if r["scene"] == scene}
    limit = explicit_limit(data["omega_coefficient"])
    for ax, m in zip(axes.flat, methods):
        method_map(ax, m, cells, limit)
    for ax in list(axes.flat)[len(methods):]:
        ax.axis("off")
    handles = [Rectangle((0, 0), 1, 1, facecolor="#7fc97f"), Rectangle((0, 0), 1, 1, facecolor="#f0027f"),
               plt.Line2D([], [], color="k", ls="--")]
    fig.legend(handles, ["bounded over 2 s (exit 0)", "failed (exit 3); label: simulated time reached",
                         "explicit limit 2/omega_max of the uniform 16 x 16 grid"],
               loc="lower center", ncol=3, fontsize=9)
    what = ("free relax from a squeeze of 0.8" if scene == "free" else "sphere crumple (R 1.0 -> 0.3 in 2 s)")
    fig.suptitle(f"Stability map, {what}, fracture on, 16 x 16 grid, 2 s", fontsize=12)
    fig.tight_layout(rect=(0, 0.05, 1, 0.96))
    fig.savefig(path, dpi=100)
    plt.close(fig)


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--quick", action="store_true", help="kappa 1e2, 1e4, 1e6; h 1/480, 1/120, 1/30")
    ap.add_argument("--jobs", type=int, default=2)
    ap.add_argument("--plots-only", action="store_true")
    ap.add_argument("--work", default=os.path.join(ac.ROOT, "build-acc", "acc_runs"))
    a = ap.parse_args()
    global KAPPAS, STEPS
    if a.plots_only:
        data = ac.load_json(os.path.join(ac.OUT, "stability.json"))
        KAPPAS, STEPS = data["kappas"], data["steps_per_s"]
    else:
        if a.quick:
            KAPPAS, STEPS = [1e2, 1e4, 1e6], [480, 120, 30]
        todo = [(s, m, k, n) for s in SCENES for m in METHODS for k in KAPPAS for n in STEPS]
        # the slow ones (implicit, small h) first, so the two workers finish together
        todo.sort(key=lambda t: (not t[1].startswith("implicit"), -t[3]))
        done = []

        def job(t):
            r = one(*t, a.work)
            done.append(r)
            if len(done) % 25 == 0:
                print(f"  {len(done)}/{len(todo)}", flush=True)
            return r
        with ThreadPoolExecutor(a.jobs) as ex:
            runs = list(ex.map(job, todo))
        c = omega_coefficient()
        data = {"what": "stability map: exit code of a 2 s run per method, kappa, h",
                "grid": ac.GRID, "seconds": SECONDS, "kappas": KAPPAS, "steps_per_s": STEPS,
                "scenes": {s: SCENES[s] for s in SCENES},
                "methods": {m: {"args": METHODS[m][0], "text": METHODS[m][1]} for m in METHODS},
                "omega_coefficient": c,
                "explicit_h_crit": {kname(k): 2 / (c * np.sqrt(k)) for k in KAPPAS},
                "runs": runs}
        ac.save_json(os.path.join(ac.OUT, "stability.json"), data)
    for s in SCENES:
        plot(data, s, os.path.join(ac.OUT, f"stability_{s}.png"))
        for m in METHODS:
            bad = [(kname(r["kappa"]), f"1/{r['steps_per_s']}") for r in data["runs"]
                   if r["scene"] == s and r["method"] == m and not r["bounded"]]
            print(f"{s} {m}: {len(bad)} failed: {bad}")


if __name__ == "__main__":
    main()
