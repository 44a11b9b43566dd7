#!/usr/bin/python3
"""Model no more than a scene needs (issue 5): adaptive against uniform, and the refinement floor
and restoration threshold as cost controls.

    /usr/bin/python3 scripts/accuracy_adaptive.py [--quick]

1. Adaptive against uniform, sphere crumple (defaults: R 1.0 -> 0.3 of the reach in 2 s, dome
   0.03), 3 s, fast backend, 2 threads:
     adaptive   grid 24, fracture on (floor 0.5: an edge breaks only while its rest length is at
                least half the input's mean edge length), seeds 1, 2, 3
     uniform    grid 47, fracture and restoration off: the coarse sheet uniformly refined to
                half its edge length (the length most refined edges reach with floor 0.5)
     coarse     grid 24, fracture and restoration off (what adaptivity adds to the same mesh)
   Frame cost = mean step_ms over the run (median over the seeds / repetitions, interleaved);
   what the eye sees = scripts/crease.py's crease length (edges with a dihedral angle above
   30 degrees, per sqrt(sheet area)) and compaction radius (RMS distance from the centroid),
   both on final.obj; renders side by side with scripts/render.py.
2. Cost controls: grid 24, 600 frames (10 s) with --sphere-time 8, --floor 0.25 / 0.5 / 1.0 by
   --epsilon 0.1 / 0.5 / 0.9: vertex count and frame time over time.

Writes results/accuracy/adaptive.json, adaptive_vs_uniform.png, adaptive_vs_uniform_renders.png,
cost_controls.json, cost_controls.png, and final OBJs under results/accuracy/adaptive/.
"""
import argparse
import os
import shutil
import subprocess
import sys

import numpy as np

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import accuracy_common as ac  # noqa: E402
import crease  # noqa: E402

FAST = ["--backend", "fast", "--threads", "2"]
CASES = {
    "adaptive": ["--grid", 24],
    "uniform": ["--grid", 47, "--no-fracture", "--no-restoration"],
    "coarse": ["--grid", 24, "--no-fracture", "--no-restoration"],
}
CASE_TEXT = {
    "adaptive": "adaptive: grid 24, fracture on, floor 0.5",
    "uniform": "uniform: grid 47 (half the edge length), fracture off",
    "coarse": "coarse: grid 24, fracture off",
}
CASE_COLOR = {"adaptive": "#d62728", "uniform": "#1f77b4", "coarse": "#7f7f7f"}


def smooth(t, y, k):
    """Running mean over k frames (only where the window is full)."""
    y = np.convolve(np.asarray(y, float), np.ones(k) / k, mode="valid")
    return np.asarray(t)[k // 2: k // 2 + len(y)], y


def run(args, d):
    shutil.rmtree(d, ignore_errors=True)
    rc, wall, err = ac.crumple(args, d)
    if rc != 0:
        raise RuntimeError(f"crumple {' '.join(map(str, args))}: {err}")
    return ac.read_stats(os.path.join(d, "stats.csv"))


def sheet_measures(path):
    """crease.py's measures on final.obj (unit-square sheet: A0 = 1), plus the crease length at
    60 degrees and the creased share of all interior edge length (how much of the mesh is folded)."""
    m = crease.measure(path, ref_area=1.0)
    m60 = crease.measure(path, deg=60.0, ref_area=1.0)
    V, F, _ = ac.read_obj(path)
    normals, _ = crease.face_normals(V, F)
    E, _ = crease.dihedral_angles(V, F, normals)
    total = float(np.linalg.norm(V[E[:, 0]] - V[E[:, 1]], axis=1).sum())
    return {"crease_norm": m["crease_norm"], "crease_norm_60": m60["crease_norm"],
            "crease_share": m["crease_length"] / total, "crease_edges": m["crease_edges"],
            "rms_radius": m["rms_radius"], "rms_radius_area": m["rms_radius_area"],
            "max_dihedral_deg": m["max_dihedral_deg"], "mean_dihedral_deg": m["mean_dihedral_deg"]}


def adaptive_vs_uniform(a):
    frames = 180
    # Seed 1 three times (timing: medians, per frame too), then seeds 2 and 3 once (the spread
    # of the crease measures of the stochastic adaptive run); interleaved over the cases.
    schedule = [(0, 1), (1, 1), (2, 1), (0, 2), (0, 3)] if not a.quick else [(0, 1)]
    res = {c: {"runs": []} for c in CASES}
    keep = os.path.join(ac.OUT, "adaptive")
    os.makedirs(keep, exist_ok=True)
    for rep, seed in schedule:
        for c, args in CASES.items():
            d = os.path.join(a.work, "adaptive", f"{c}_{seed}_{rep}")
            st = run(args + FAST + ["--frames", frames, "--seed", seed], d)
            r = {"seed": seed, "rep": rep, "ms_per_frame": float(st["step_ms"].mean()),
                 "vertices_end": int(st["vertices"][-1]), "triangles_end": int(st["triangles"][-1]),
                 "splits": int(st["splits"].sum()), "restores": int(st["restores"].sum()),
                 "time": st["time"].tolist(), "vertices": st["vertices"].astype(int).tolist(),
                 "step_ms": st["step_ms"].tolist()}
            if rep == 0:
                r.update(sheet_measures(os.path.join(d, "final.obj")))
            if rep == 0 and seed == 1:
                shutil.copy(os.path.join(d, "final.obj"), os.path.join(keep, f"{c}.obj"))
            res[c]["runs"].append(r)
            shutil.rmtree(d, ignore_errors=True)
    for c in CASES:
        runs = res[c]["runs"]
        res[c]["text"] = CASE_TEXT[c]
        res[c]["args"] = CASES[c] + ["--frames", frames]
        timed = [r for r in runs if r["seed"] == 1]
        seeds = [r for r in runs if r["rep"] == 0]
        res[c]["step_ms_median_per_frame"] = np.median(np.array([r["step_ms"] for r in timed]), axis=0).tolist()
        res[c]["time"] = timed[0]["time"]
        res[c]["vertices"] = timed[0]["vertices"]
        for k, src in (("ms_per_frame", timed), ("vertices_end", seeds), ("splits", seeds), ("crease_norm", seeds),
                       ("crease_norm_60", seeds), ("crease_share", seeds), ("rms_radius", seeds),
                       ("rms_radius_area", seeds), ("mean_dihedral_deg", seeds)):
            vals = [r[k] for r in src]
            res[c][k] = {"median": float(np.median(vals)), "min": float(min(vals)), "max": float(max(vals)),
                         "n": len(vals)}
        for r in runs:  # keep the JSON small: per-frame series only in the aggregate
            r.pop("time"), r.pop("vertices"), r.pop("step_ms")
    out = {"what": "adaptive (grid 24, fracture) against uniform (grid 47, no fracture), sphere crumple 3 s",
           "timing_note": ac.timing_note(), "backend": "fast, 2 threads", "frames": frames,
           "schedule": "seed 1 x3 (timing), seeds 2 and 3 (crease spread)", "cases": res}
    ac.save_json(os.path.join(ac.OUT, "adaptive.json"), out)
    plot_adaptive(out)
    renders(a)
    return out


def plot_adaptive(data):
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    fig, axes = plt.subplots(1, 4, figsize=(20, 4.8))
    cases = data["cases"]
    for c, r in cases.items():
        axes[0].plot(r["time"], r["vertices"], color=CASE_COLOR[c], label=r["text"])
        axes[1].plot(*smooth(r["time"], r["step_ms_median_per_frame"], 9), color=CASE_COLOR[c], label=r["text"])
    axes[0].set_xlabel("time (s)")
    axes[0].set_ylabel("vertices")
    axes[0].set_title("vertex count (seed 1)")
    axes[1].set_xlabel("time (s)")
    axes[1].set_ylabel("ms per frame (running mean of 9 frames)")
    axes[1].set_title("frame cost (seed 1, median of 3 runs per frame; fast, 2 threads)", fontsize=10)
    axes[0].legend(fontsize=8)
    names = list(cases)
    x = np.arange(len(names))
    for ax, key, lab in ((axes[2], "ms_per_frame", "mean ms per frame (3 s run)"),
                         (axes[3], "crease_norm", "crease length / sqrt(area)")):
        med = [cases[c][key]["median"] for c in names]
        lo = [cases[c][key]["median"] - cases[c][key]["min"] for c in names]
        hi = [cases[c][key]["max"] - cases[c][key]["median"] for c in names]
        ax.bar(x, med, yerr=[lo, hi], color=[CASE_COLOR[c] for c in names], capsize=5)
        ax.set_xticks(x)
        ax.set_xticklabels(names)
        ax.set_ylabel(lab)
        for i, v in enumerate(med):
            ax.text(i, v, f"{v:.3g}", ha="center", va="bottom", fontsize=9)
    axes[2].set_title("frame cost (median of 3 runs; bars: min-max)", fontsize=9.5)
    axes[3].set_title("crease length (dihedral > 30 deg; seeds 1-3, bars: min-max);\n"
                      "r: compaction radius (RMS distance from the centroid)", fontsize=9.5)
    for i, c in enumerate(names):
        axes[3].text(i, 0.02 * max(cases[n]["crease_norm"]["median"] for n in names) + 0.0,
                     f"r = {cases[c]['rms_radius']['median']:.3f}", ha="center", va="bottom", fontsize=8.5,
                     color="white", fontweight="bold")
    fig.text(0.01, 0.01, data["timing_note"], fontsize=8, color="#444")
    fig.tight_layout(rect=(0, 0.03, 1, 1))
    fig.savefig(os.path.join(ac.OUT, "adaptive_vs_uniform.png"), dpi=100)
    plt.close(fig)


def renders(a):
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    import matplotlib.image as mpimg
    keep = os.path.join(ac.OUT, "adaptive")
    pngs = []
    for c in CASES:
        png = os.path.join(a.work, f"render_{c}.png")
        subprocess.run(["/usr/bin/python3", os.path.join(ac.ROOT, "scripts", "render.py"),
                        os.path.join(keep, f"{c}.obj"), png, "--size", "5", "--dpi", "110", "--title", CASE_TEXT[c]],
                       check=True, capture_output=True)
        pngs.append(png)
    fig, axes = plt.subplots(1, len(pngs), figsize=(6 * len(pngs), 6))
    for ax, p in zip(axes, pngs):
        ax.imshow(mpimg.imread(p))
        ax.axis("off")
    fig.suptitle("Sphere crumple after 3 s (seed 1): adaptive coarse mesh with fracture, uniform fine mesh, "
                 "uniform coarse mesh", fontsize=12)
    fig.tight_layout()
    fig.savefig(os.path.join(ac.OUT, "adaptive_vs_uniform_renders.png"), dpi=90)
    plt.close(fig)


def cost_controls(a):
    floors = [0.25, 0.5, 1.0]
    eps = [0.1, 0.5, 0.9]
    frames = 600 if not a.quick else 240
    sphere_time = 8 if not a.quick else 3
    runs = []
    reps = 1 if a.quick else 3
    stats = {}
    for rep in range(reps):  # interleaved repetitions; the topology is the same each time (seed 1)
        for f in floors:
            for e in eps:
                d = os.path.join(a.work, "cost", f"f{f}_e{e}")
                stats.setdefault((f, e), []).append(
                    run(["--grid", 24, "--frames", frames, "--sphere-time", sphere_time, "--floor", f, "--epsilon", e]
                        + FAST, d))
                shutil.rmtree(d, ignore_errors=True)
    for f in floors:
        for e in eps:
            st = dict(stats[(f, e)][0])
            st["step_ms"] = np.median(np.array([x["step_ms"] for x in stats[(f, e)]]), axis=0)
            t = st["time"]
            hold = t > sphere_time
            runs.append({"floor": f, "epsilon": e, "time": t.tolist(), "vertices": st["vertices"].astype(int).tolist(),
                         "step_ms": st["step_ms"].tolist(), "splits": int(st["splits"].sum()),
                         "restores": int(st["restores"].sum()),
                         "vertices_start": int(st["vertices"][0]), "vertices_max": int(st["vertices"].max()),
                         "vertices_at_sphere_end": int(st["vertices"][np.searchsorted(t, sphere_time - 1e-9)]),
                         "vertices_end": int(st["vertices"][-1]),
                         "ms_per_frame_mean": float(st["step_ms"].mean()),
                         "ms_per_frame_hold": float(st["step_ms"][hold].mean()) if hold.any() else None,
                         "ms_per_frame_first_second": float(st["step_ms"][:60].mean())})
    # Longer: does the count settle once the sphere holds? 60 s per floor at epsilon 0.5.
    long_runs = []
    long_frames = 3600 if not a.quick else 0
    for f in floors if long_frames else []:
        d = os.path.join(a.work, "cost", f"long_f{f}")
        st = run(["--grid", 24, "--frames", long_frames, "--sphere-time", sphere_time, "--floor", f] + FAST, d)
        t, v = st["time"], st["vertices"]
        at = {f"{x:g}": int(v[np.searchsorted(t, x - 1e-9)]) for x in (sphere_time, 10, 20, 30, 40, 50, 60)}
        long_runs.append({"floor": f, "epsilon": 0.5, "time": t[::10].tolist(), "vertices": v[::10].astype(int).tolist(),
                          "vertices_at": at, "ms_per_frame_last_10s": float(st["step_ms"][-600:].mean()),
                          "growth_per_10s_at_end": float(v[-1] / v[-601] - 1)})
        shutil.rmtree(d, ignore_errors=True)
    out = {"what": "vertex count and frame time over a long crumple per --floor and --epsilon",
           "grid": 24, "frames": frames, "sphere_time": sphere_time, "backend": "fast, 2 threads",
           "timing_note": ac.timing_note(), "reps": reps, "runs": runs, "long_frames": long_frames, "long_runs": long_runs}
    ac.save_json(os.path.join(ac.OUT, "cost_controls.json"), out)
    plot_cost(out)
    return out


def plot_cost(data):
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    fig, axes = plt.subplots(1, 3 if data["long_runs"] else 2, figsize=(22 if data["long_runs"] else 16, 5.8))
    fcol = {0.25: "#d62728", 0.5: "#1f77b4", 1.0: "#2ca02c"}
    els = {0.1: ":", 0.5: "-", 0.9: "--"}
    for r in data["runs"]:
        lab = f"floor {r['floor']}, epsilon {r['epsilon']}"
        axes[0].plot(r["time"], r["vertices"], color=fcol[r["floor"]], ls=els[r["epsilon"]], label=lab)
        axes[1].plot(*smooth(r["time"], r["step_ms"], 15), color=fcol[r["floor"]], ls=els[r["epsilon"]], label=lab)
    for r in data["long_runs"]:
        axes[2].plot(r["time"], r["vertices"], color=fcol[r["floor"]], label=f"floor {r['floor']}, epsilon 0.5")
    if data["long_runs"]:
        axes[2].set_ylabel("vertices")
        axes[2].set_yscale("log")
        axes[2].set_title(f"the same over {data['long_frames'] // 60} s: growth slows, does not stop", fontsize=10)
        axes[2].legend(fontsize=8)
    for ax in axes:
        ax.axvline(data["sphere_time"], color="k", lw=0.8, ls=":")
        ax.set_xlabel("time (s)")
        ax.grid(True, alpha=0.3)
    axes[0].text(data["sphere_time"], axes[0].get_ylim()[1] * 0.97, " sphere stops shrinking", fontsize=8, va="top")
    axes[0].set_ylabel("vertices")
    axes[0].set_yscale("log")
    axes[0].set_title(f"vertex count (grid 24 = 576 vertices at start)", fontsize=10)
    axes[1].set_ylabel("ms per frame (running mean of 15 frames)")
    axes[1].set_title("frame cost, fast backend, 2 threads", fontsize=10)
    axes[0].legend(fontsize=8, ncol=3, loc="lower right")
    fig.suptitle(f"Cost controls: refinement floor (colour) and restoration threshold epsilon (line style), "
                 f"sphere crumple over {data['sphere_time']} s then held", fontsize=11)
    fig.text(0.01, 0.01, f"seed 1; frame times: per-frame median of {data['reps']} interleaved runs; timings come from a shared 2-core machine ("
             + ac.cpu_model() + "), noisy: ~10-20 % within a session, up to 2x between sessions", fontsize=8, color="#444")
    fig.tight_layout(rect=(0, 0.03, 1, 0.96))
    fig.savefig(os.path.join(ac.OUT, "cost_controls.png"), dpi=100)
    plt.close(fig)


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--quick", action="store_true")
    ap.add_argument("--work", default=os.path.join(ac.ROOT, "build-acc", "acc_runs"))
    a = ap.parse_args()
    av = adaptive_vs_uniform(a)
    for c, r in av["cases"].items():
        print(f"{c}: {r['ms_per_frame']['median']:.3f} ms/frame, {r['vertices_end']['median']:.0f} vertices, "
              f"crease {r['crease_norm']['median']:.3f}, radius {r['rms_radius']['median']:.3f}")
    cc = cost_controls(a)
    for r in cc["runs"]:
        print(f"floor {r['floor']} eps {r['epsilon']}: vertices {r['vertices_start']} -> max {r['vertices_max']}, "
              f"at sphere end {r['vertices_at_sphere_end']}, end {r['vertices_end']}; "
              f"{r['ms_per_frame_mean']:.2f} ms/frame")


if __name__ == "__main__":
    main()
