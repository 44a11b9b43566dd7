#!/usr/bin/python3
"""Speed against accuracy (issue 5): every method at every step on the studied scenes, error
against the reference after 1 s and cost per simulated second; Pareto charts, the budget table,
energy over time at h = 1/60.

    /usr/bin/python3 scripts/accuracy_sweep.py [--quick] [--reps 3]

Needs results/accuracy/reference.json and reference/*.obj (scripts/accuracy_reference.py).

Per case (scene, kappa) and method (accuracy_common.METHODS) and step h = 1/n (n in
accuracy_common.sweep_steps(method): 1/30 .. 1/1000 s, and 1/2000, 1/4000 for every method,
1/8000, 1/16000 for symplectic Euler, so that tight budgets get an answer):
  * cost: ms per simulated second = sum of stats.csv's step_ms over 1 s of simulated time, on
    the backend the method would run on (approx and explicit: fast, 2 threads; Baraff-Witkin:
    reference, its only backend); the median of `reps` repetitions, interleaved (every
    configuration once, then again, ...), so slow phases of the shared machine hit all alike;
  * error: RMS vertex distance to the reference after 1 s / sqrt 2, measured on that same
    backend (the fast backend is float); for approx and explicit also on the reference backend
    (double), to show float's share;
  * a run that exits 3 (unstable) is "failed": no error, no cost, not on a chart;
  * energy at h = 1/60: kinetic (stats.csv) + spring + gravitational potential (frame OBJs).

Writes results/accuracy/sweep.json, pareto_k<kappa>.png, pareto.md, energy_<scene>_k<kappa>.png.
"""
import argparse
import math
import os
import shutil
import sys

import numpy as np

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import accuracy_common as ac  # noqa: E402
from accuracy_reference import kname  # noqa: E402

BUDGETS = [1e-1, 1e-2, 1e-3, 1e-4]


def method_args(method, backend=None):
    opts, be, threads = ac.METHODS[method]
    be = backend or be
    return opts + ["--backend", be, "--threads", threads if be == "fast" else 1]


def one_run(case, method, n, work, backend=None, energy=False):
    scene, kappa = case["scene"], case["kappa"]
    be = backend or ac.METHODS[method][1]
    d = os.path.join(work, "sweep", f"{case['name']}_{method}_{be}_n{n}")
    shutil.rmtree(d, ignore_errors=True)
    args = ["--grid", ac.GRID] + ac.SCENES[scene] + ["--kappa", kappa] + method_args(method, backend) + ac.step_args(n)
    if energy:
        args += ["--every", 1]
    rc, wall, err = ac.crumple(args, d)
    out = {"exit": rc, "wall_s": wall}
    stats_path = os.path.join(d, "stats.csv")
    if os.path.exists(stats_path):
        st = ac.read_stats(stats_path)
        out["ms_per_s"] = float(st["step_ms"].sum() / max(st["time"][-1], 1e-12)) if len(st["time"]) else None
        out["frames_done"] = int(len(st["time"]))
        out["time_reached"] = float(st["time"][-1]) if len(st["time"]) else 0.0
    if rc == 0:
        x = ac.read_obj(os.path.join(d, "final.obj"))[0]
        out["error"] = ac.rms_error(x, case["ref_x"])
    else:
        out["why"] = err.replace("crumple: error: ", "")
    if energy and os.path.exists(stats_path):
        out["energy"] = ac.energy_from_dir(scene, kappa, n, d)  # up to the failure, if it failed
    shutil.rmtree(d, ignore_errors=True)
    return out


def pareto(points):
    """Indices of the Pareto-optimal points of [(cost, error)]: no other is cheaper and more exact."""
    order = sorted(range(len(points)), key=lambda i: (points[i][0], points[i][1]))
    front, best = [], math.inf
    for i in order:
        if points[i][1] < best:
            front.append(i)
            best = points[i][1]
    return front


def cheapest(rows, budget):
    ok = [r for r in rows if r.get("error") is not None and r["error"] <= budget and r.get("ms_per_s")]
    return min(ok, key=lambda r: r["ms_per_s"]) if ok else None


def load_cases():
    """The reference's studied cases (no demos), each with its final positions as ref_x."""
    ref = ac.load_json(os.path.join(ac.OUT, "reference.json"))
    cases = [c for c in ref["cases"] if not c["demo"] and "reference_steps_per_s" in c]
    for c in cases:
        c["ref_x"] = ac.read_obj(os.path.join(ac.OUT, "reference", c["name"] + ".obj"))[0]
    return cases


def measure(a, cases, configs):
    """{(case index, method, n): the first repetition's result with every repetition's cost in
    reps_ms}, configurations interleaved in a new order each repetition; then the float
    methods' error on the double (reference) backend."""
    results = {(ci, m, n): {"reps_ms": []} for ci, m, n in configs}
    rng = np.random.default_rng(5)
    for rep in range(a.reps):
        order = list(range(len(configs)))
        rng.shuffle(order)  # interleaved and in a different order each repetition
        for k, idx in enumerate(order):
            ci, m, n = configs[idx]
            r = one_run(cases[ci], m, n, a.work, energy=(rep == 0 and n == 60))
            res = results[(ci, m, n)]
            if rep == 0:
                res.update({key: v for key, v in r.items() if key not in ("wall_s",)})
                res.pop("ms_per_s", None)
            if r["exit"] == 0 and r.get("ms_per_s") is not None:
                res["reps_ms"].append(r["ms_per_s"])
            if k % 40 == 0:
                print(f"  rep {rep + 1}/{a.reps}: {k}/{len(configs)}", flush=True)
    for ci, m, n in configs:
        if ac.METHODS[m][1] == "fast":
            r = one_run(cases[ci], m, n, a.work, backend="reference")
            results[(ci, m, n)]["error_double"] = r.get("error")
            results[(ci, m, n)]["exit_double"] = r["exit"]
    return results


def result_row(m, n, res):
    """sweep.json's row of one method at step 1/n from its measured result."""
    row = {"method": m, "steps_per_s": n, "h": 1.0 / n, "backend": ac.METHODS[m][1],
           "threads": ac.METHODS[m][2], "exit": res["exit"], "failed": res["exit"] != 0,
           "error": res.get("error"), "error_double": res.get("error_double"),
           "exit_double": res.get("exit_double"),
           "ms_per_s": float(np.median(res["reps_ms"])) if res["reps_ms"] and res["exit"] == 0 else None,
           "reps_ms": res["reps_ms"]}
    if res["exit"] != 0:
        row["why"] = res.get("why")
        row["time_reached"] = res.get("time_reached")
    if "energy" in res:
        row["energy"] = res["energy"]
    return row


def case_summary(c, rows):
    """sweep.json's case: its rows with the Pareto-optimal ones marked, and the cheapest run
    within each error budget."""
    front = pareto([(r["ms_per_s"], r["error"]) for r in rows if not r["failed"]])
    ok = [r for r in rows if not r["failed"]]
    for i in front:
        ok[i]["pareto"] = True
    return {"scene": c["scene"], "kappa": c["kappa"], "name": c["name"],
            "reference_steps_per_s": c["reference_steps_per_s"],
            "reference_change": c.get("reference_change"),
            "reference_energy": c.get("energy"), "rows": rows,
            "budgets": {f"{b:g}": (lambda r: None if r is None else
                                   {"method": r["method"], "steps_per_s": r["steps_per_s"],
                                    "ms_per_s": r["ms_per_s"], "error": r["error"]})(cheapest(rows, b))
                        for b in BUDGETS}}


def run_all(a):
    cases = load_cases()
    methods = list(ac.METHODS)
    configs = [(ci, m, n) for ci in range(len(cases)) for m in methods for n in ac.sweep_steps(m)]
    results = measure(a, cases, configs)
    out_cases = [case_summary(c, [result_row(m, n, results[(ci, m, n)]) for m in methods for n in ac.sweep_steps(m)])
                 for ci, c in enumerate(cases)]
    data = {"what": "speed against accuracy: error after 1 s vs cost per simulated second",
            "grid": ac.GRID, "sheet_size": ac.SHEET_SIZE, "reps": a.reps, "quick": a.quick,
            "machine": ac.cpu_model(), "timing_note": ac.timing_note(),
            "methods": {m: {"text": ac.METHOD_TEXT[m], "args": ac.METHODS[m][0], "backend": ac.METHODS[m][1],
                            "threads": ac.METHODS[m][2]} for m in methods},
            "scenes": {s: {"args": ac.SCENES[s], "text": ac.SCENE_TEXT[s]} for s in ac.SCENES},
            "cases": out_cases}
    ac.save_json(os.path.join(ac.OUT, "sweep.json"), data)
    return data


# --- charts and tables ---------------------------------------------------------------------------
def pareto_methods(ax, data, rows):
    """Each method's runs as a line through its steps, the explicit method's double error
    dashed; returns the double points (their errors widen the axis)."""
    for m in data["methods"]:
        pts = [(r["ms_per_s"], r["error"], r["steps_per_s"]) for r in rows
               if r["method"] == m and not r["failed"] and r["ms_per_s"]]
        nfail = sum(1 for r in rows if r["method"] == m and r["failed"])
        nrun = sum(1 for r in rows if r["method"] == m)
        label = f"{m}" + (f"  ({nfail} of {nrun} steps failed)" if nfail else "")
        if pts:
            pts.sort(key=lambda p: -p[2])
            ax.plot([p[0] for p in pts], [p[1] for p in pts], marker=ac.MARKERS[m], color=ac.COLORS[m],
                    lw=1, ms=7, label=label, alpha=0.9)
            for p in pts:
                ax.annotate(f"1/{p[2]}", (p[0], p[1]), textcoords="offset points", xytext=(4, 3),
                            fontsize=6.5, color=ac.COLORS[m])
        else:
            ax.plot([], [], marker=ac.MARKERS[m], color=ac.COLORS[m], lw=0, label=label + " (all failed)")
    dbl = sorted([(r["ms_per_s"], r["error_double"]) for r in rows if r["method"] == "explicit"
                  and not r["failed"] and r.get("error_double") and r["ms_per_s"]])
    if dbl:
        ax.plot([p[0] for p in dbl], [p[1] for p in dbl], ls="--", lw=0.8, color=ac.COLORS["explicit"],
                marker="o", mfc="none", ms=6, alpha=0.6,
                label="explicit, error in double (reference backend) at the same cost")
    return dbl


def pareto_front(ax, ok):
    """The Pareto front as a staircase through its circled runs."""
    front = sorted([r for r in ok if r.get("pareto")], key=lambda r: r["ms_per_s"])
    if not front:
        return
    xs, ys = [], []
    for i, r in enumerate(front):
        xs.append(r["ms_per_s"])
        ys.append(r["error"])
        if i + 1 < len(front):
            xs.append(front[i + 1]["ms_per_s"])
            ys.append(r["error"])
    ax.plot(xs, ys, color="k", lw=2.2, alpha=0.35, zorder=0, label="Pareto front")
    ax.scatter([r["ms_per_s"] for r in front], [r["error"] for r in front], s=160,
               facecolors="none", edgecolors="k", lw=1.4, zorder=5)


def pareto_axes(ax, c, errs):
    """Budgets, the reference's uncertainty band, log axes, labels and legend of one case."""
    for b in BUDGETS:
        ax.axhline(b, color="grey", lw=0.6, ls=":")
    if c.get("reference_change"):
        ax.axhspan(1e-9, c["reference_change"], color="grey", alpha=0.12, lw=0)
        ax.text(0.99, c["reference_change"] * 0.8, "below the reference's own uncertainty",
                transform=ax.get_yaxis_transform(), ha="right", va="top", fontsize=8, color="grey")
    ax.set_xscale("log")
    ax.set_yscale("log")
    if errs:
        ax.set_ylim(min(min(errs), c.get("reference_change") or 1) / 3, max(errs) * 3)
    ax.set_xlabel("cost: ms of wall time per simulated second (fast backend, 2 threads; "
                  "implicit: reference)", fontsize=9)
    ax.set_ylabel("error after 1 s: RMS vertex distance / sheet diagonal")
    ax.set_title(f"{c['scene']} scene, kappa {kname(c['kappa'])}: error against cost "
                 f"(labels: step h)", fontsize=11)
    ax.grid(True, which="both", alpha=0.25)
    ax.legend(fontsize=8, loc="upper left", bbox_to_anchor=(1.01, 1.0), framealpha=0.9)


def plot_pareto(data):
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    by_kappa = {}
    for c in data["cases"]:
        by_kappa.setdefault(c["kappa"], []).append(c)
    paths = []
    for kappa, cases in sorted(by_kappa.items()):
        fig, axes = plt.subplots(1, len(cases), figsize=(13.5 * len(cases), 7), squeeze=False)
        for ax, c in zip(axes[0], cases):
            dbl = pareto_methods(ax, data, c["rows"])
            ok = [r for r in c["rows"] if not r["failed"] and r["ms_per_s"]]
            pareto_front(ax, ok)
            pareto_axes(ax, c, [r["error"] for r in ok] + [p[1] for p in dbl])
        fig.text(0.01, 0.005, "16 x 16 grid; circled: Pareto-optimal; failed runs (exit 3) are not plotted.\n"
                 + data["timing_note"] + ".", fontsize=7.5, color="#444")
        fig.tight_layout(rect=(0, 0.04, 1, 1))
        p = os.path.join(ac.OUT, f"pareto_k{kname(kappa)}.png")
        fig.savefig(p, dpi=100)
        plt.close(fig)
        paths.append(p)
    return paths


def plot_energy(data):
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    paths = []
    for c in data["cases"]:
        fig, axes = plt.subplots(1, 2, figsize=(15, 5.5))
        ref = c["reference_energy"]

        def total(e):
            return np.array(e["kinetic"]) + np.array(e["spring"]) + np.array(e["gravity"])
        e0 = total(ref)[0]
        for ax, what in zip(axes, ["total", "kinetic"]):
            if ref:
                y = total(ref) - e0 if what == "total" else np.array(ref["kinetic"])
                ax.plot(ref["time"], y, color="k", lw=2.5, alpha=0.5, label=f"reference (h = 1/{c['reference_steps_per_s']})")
            for r in c["rows"]:
                if r["steps_per_s"] != 60 or "energy" not in r:
                    continue
                e = r["energy"]
                y = total(e) - e0 if what == "total" else np.array(e["kinetic"])
                lab = r["method"] + (" (failed)" if r["failed"] else "")
                ax.plot(e["time"], y, color=ac.COLORS[r["method"]], marker=ac.MARKERS[r["method"]], ms=3,
                        lw=1, label=lab)
            ax.set_xlabel("time (s)")
            if what == "total":
                ax.set_ylabel("E(t) - E(0) (J): kinetic + spring + gravity")
                ax.set_title("total energy change (bending has no potential: not included)", fontsize=10)
                vals = [total(r["energy"]) - e0 for r in c["rows"] if r["steps_per_s"] == 60 and "energy" in r
                        and not r["failed"]] + ([total(ref) - e0] if ref else [])
                if vals:
                    lo = min(v.min() for v in vals)
                    hi = max(v.max() for v in vals)
                    scale = max(abs(e0), max(np.abs(np.array(ref["kinetic"]))) if ref else 0, 1e-6)
                    # symmetric log: the small drifts (implicit damping, bending's work) and the
                    # large ones (approx stretching) on one axis
                    ax.set_yscale("symlog", linthresh=0.01 * scale)
                    ax.set_ylim(min(lo * 1.5, -0.02 * scale), max(hi * 1.5, 0.02 * scale))
                    ax.axhline(0, color="k", lw=0.6)
                    ax.text(0.01, 0.01, f"symmetric log scale, linear within +-{0.01 * scale:.2g} J; E(0) = {e0:.3g} J",
                            transform=ax.transAxes, fontsize=8, color="#444")
            else:
                ax.set_ylabel("kinetic energy (J)")
                ax.set_title("kinetic energy", fontsize=10)
                vals = [np.array(r["energy"]["kinetic"]) for r in c["rows"] if r["steps_per_s"] == 60
                        and "energy" in r and not r["failed"]] + ([np.array(ref["kinetic"])] if ref else [])
                if vals:
                    ax.set_ylim(0, 1.1 * max(v.max() for v in vals))
            ax.grid(True, alpha=0.3)
        axes[0].legend(fontsize=8, loc="best")
        fig.suptitle(f"{c['scene']} scene, kappa {kname(c['kappa'])}: energy at h = 1/60 s per method "
                     f"(failed runs stop where they blew up; off-scale values clipped)", fontsize=11)
        fig.tight_layout()
        p = os.path.join(ac.OUT, f"energy_{c['name']}.png")
        fig.savefig(p, dpi=100)
        plt.close(fig)
        paths.append(p)
    return paths


def fmt(x, digits=3):
    return "-" if x is None else f"{x:.{digits}g}"


def write_tables(data):
    L = ["# Speed against accuracy: the cheapest method per error budget", "",
         "Error: RMS vertex distance to the reference after 1 s, divided by the sheet diagonal "
         "sqrt 2. Cost: milliseconds of wall time per simulated second (sum of step_ms), "
         "fast backend with 2 threads for symplectic Euler and the approximate implicit method, "
         "the reference backend (1 thread) for Baraff-Witkin. 16 x 16 grid. " + data["timing_note"] + ".", ""]
    for c in data["cases"]:
        L += case_table(c)
    L += float_double_section(data)
    with open(os.path.join(ac.OUT, "pareto.md"), "w") as f:
        f.write("\n".join(L) + "\n")


def case_table(c):
    """pareto.md's section of one case: the cheapest run per budget, then every run."""
    L = [f"## {c['scene']}, kappa {kname(c['kappa'])}", "",
         f"Reference: symplectic Euler at h = 1/{c['reference_steps_per_s']}; its own uncertainty "
         f"(change when h was last halved) {fmt(c['reference_change'], 2)}.", "",
         "| error budget | cheapest method | step h | cost (ms / simulated s) | error |",
         "|---|---|---|---|---|"]
    for b in BUDGETS:
        r = c["budgets"][f"{b:g}"]
        if r is None:
            L.append(f"| {b:g} | none of the tested methods and steps | | | |")
        else:
            note = " (below the reference's uncertainty)" if c["reference_change"] and r["error"] < c["reference_change"] else ""
            L.append(f"| {b:g} | {r['method']} | 1/{r['steps_per_s']} | {fmt(r['ms_per_s'])} | "
                     f"{fmt(r['error'], 2)}{note} |")
    anyr = cheapest(c["rows"], math.inf)
    if anyr:
        L.append(f"| any (bounded) | {anyr['method']} | 1/{anyr['steps_per_s']} | {fmt(anyr['ms_per_s'])} | "
                 f"{fmt(anyr['error'], 2)} |")
    L += ["", "<details><summary>every run</summary>", "",
          "| method | h | error (costed backend) | error (double) | ms / simulated s | Pareto |",
          "|---|---|---|---|---|---|"]
    for r in c["rows"]:
        err = f"failed (exit 3 at {r.get('time_reached') or 0:.2f} s)" if r["failed"] else fmt(r["error"], 2)
        ed = "-" if r.get("exit_double") is None else ("failed" if r["exit_double"] else fmt(r["error_double"], 2))
        L.append(f"| {r['method']} | 1/{r['steps_per_s']} | {err} | {ed} | {fmt(r['ms_per_s'])} | "
                 f"{'yes' if r.get('pareto') else ''} |")
    return L + ["", "</details>", ""]


def float_double_section(data):
    """pareto.md's float (fast backend) against double (reference backend) for the same method
    and step; nothing when no run finished on both."""
    pairs = [(c["name"], r) for c in data["cases"] for r in c["rows"]
             if r.get("error") is not None and r.get("error_double") is not None]
    if not pairs:
        return []
    ratio = [r["error"] / r["error_double"] for _, r in pairs]
    same = sum(1 for q in ratio if abs(q - 1) < 0.1)
    worse = [(n, r) for (n, r), q in zip(pairs, ratio) if q > 2]
    both_fail = sum(1 for c in data["cases"] for r in c["rows"] if r["failed"] and r.get("exit_double"))
    one_fail = sum(1 for c in data["cases"] for r in c["rows"] if r.get("exit_double") is not None
                   and bool(r["failed"]) != bool(r["exit_double"]))
    L = ["## Float against double", "",
         f"Every symplectic Euler and approximate implicit run was repeated on the reference backend "
         f"(double). Of {len(pairs)} runs that finished on both, the float error is within 10 % of the "
         f"double one in {same}; it is more than twice the double one in {len(worse)}"
         + (": " + ", ".join(f"{n} {r['method']} 1/{r['steps_per_s']} ({r['error']:.2g} vs {r['error_double']:.2g})"
                             for n, r in worse) if worse else "")
         + f". {both_fail} runs failed on both backends, {one_fail} on one only.", "",
         "Symplectic Euler, error on each backend:", "",
         "| case | " + " | ".join(f"1/{n}" for n in ac.sweep_steps("explicit")) + " |",
         "|---|" + "---|" * len(ac.sweep_steps("explicit"))]
    for c in data["cases"]:
        cells = []
        for n in ac.sweep_steps("explicit"):
            r = next((r for r in c["rows"] if r["method"] == "explicit" and r["steps_per_s"] == n), None)
            if r is None or r["failed"]:
                cells.append("failed")
            else:
                cells.append(f"{fmt(r['error'], 2)} / {fmt(r['error_double'], 2)}")
        L.append(f"| {c['name']} (float / double) | " + " | ".join(cells) + " |")
    return L + [""]


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--quick", action="store_true", help="one repetition")
    ap.add_argument("--reps", type=int, default=None)
    ap.add_argument("--plots-only", action="store_true", help="redraw from sweep.json")
    ap.add_argument("--work", default=os.path.join(ac.ROOT, "build-acc", "acc_runs"))
    a = ap.parse_args()
    a.reps = a.reps or (1 if a.quick else 5)
    data = ac.load_json(os.path.join(ac.OUT, "sweep.json")) if a.plots_only else run_all(a)
    plot_pareto(data)
    plot_energy(data)
    write_tables(data)
    for c in data["cases"]:
        print(c["name"], {k: (v and (v["method"], f"1/{v['steps_per_s']}", round(v["ms_per_s"], 2))) for k, v in c["budgets"].items()})


if __name__ == "__main__":
    main()
