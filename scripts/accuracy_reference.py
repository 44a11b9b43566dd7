#!/usr/bin/python3
"""Reference solutions of the accuracy study (issue 5): symplectic Euler, reference backend
(double), at steps h = 1/(60 S), S = 250, 500, 1000, ... halved until halving changes the state
after 1 s by less than 1e-6 of the sheet size (RMS vertex distance / sqrt 2), or a cap is reached.

    /usr/bin/python3 scripts/accuracy_reference.py [--quick] [--jobs 2]

Writes results/accuracy/reference.json (per case: every level's step, the change from the
previous level, wall time; the energy of the finest level per 1/60 s frame),
results/accuracy/reference/<scene>_k<kappa>.obj (the finest level's state after 1 s, what the
sweep measures errors against) and results/accuracy/reference_convergence.png.

Cases: the hang scene at kappa 1e4 and 1e5, the free relax at kappa 1e2 and 1e3 (studied), and
demonstration cases that have no well-defined reference: the free relax at kappa 1e4 and 1e5
(chaotic: the state after 1 s does not converge as h -> 0) and the hang scene at kappa 1e3 (the
sheet itself stretches past crumple's instability test, RMS strain > 1).
"""
import argparse
import os
import shutil
import sys
from concurrent.futures import ThreadPoolExecutor

import numpy as np

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import accuracy_common as ac  # noqa: E402

CASES = [("hang", 1e4), ("hang", 1e5), ("free", 1e2), ("free", 1e3)]
DEMOS = [("free", 1e4), ("free", 1e5), ("hang", 1e3)]
TARGET = 1e-6


def kname(k):
    return f"{k:.0e}".replace("e+0", "e").replace("e+", "e")


def case_name(scene, kappa):
    return f"{scene}_k{kname(kappa)}"


def run_case(scene, kappa, cap_s, work, demo=False):
    name = case_name(scene, kappa)
    levels = []
    prev = None
    s = 250
    status = "capped"
    while s <= cap_s:
        n = 60 * s
        d = os.path.join(work, "ref", f"{name}_n{n}")
        shutil.rmtree(d, ignore_errors=True)
        args = ["--grid", ac.GRID] + ac.SCENES[scene] + ["--kappa", kappa, "--integrator", "explicit",
                                                          "--backend", "reference"] + ac.step_args(n)
        if not demo:  # an OBJ every 1/60 s: the finest level's give the energy
            args += ["--every", max(1, int(round((1.0 / 60) / ac.frames_for(n)["frame_dt"])))]
        rc, wall, err = ac.crumple(args, d)
        lev = {"steps_per_s": n, "h": 1.0 / n, "exit": rc, "wall_s": round(wall, 2)}
        if rc != 0:
            lev["error"] = err
            levels.append(lev)
            status = "unstable"
            print(f"  {name} n={n}: exit {rc}: {err}", flush=True)
            break
        x = ac.read_obj(os.path.join(d, "final.obj"))[0]
        if prev is not None:
            lev["change"] = ac.rms_error(x, prev[1])
        levels.append(lev)
        print(f"  {name} n={n}: change {lev.get('change', float('nan')):.3g} ({wall:.1f} s)", flush=True)
        if prev is not None:
            shutil.rmtree(prev[0], ignore_errors=True)
        prev = (d, x)
        if "change" in lev and lev["change"] < TARGET:
            status = "converged"
            break
        if demo and len(levels) >= 4:
            break
        s *= 2
    res = {"scene": scene, "kappa": kappa, "name": name, "levels": levels, "status": status,
           "target": TARGET, "demo": demo, "scene_args": ac.SCENES[scene], "grid": ac.GRID}
    if prev is not None and not demo:
        # the finest level is the reference (its frame OBJs give the energy)
        n = levels[-1]["steps_per_s"]
        res["reference_steps_per_s"] = n
        res["reference_change"] = levels[-1].get("change")
        os.makedirs(os.path.join(ac.OUT, "reference"), exist_ok=True)
        shutil.copy(os.path.join(prev[0], "final.obj"), os.path.join(ac.OUT, "reference", name + ".obj"))
        res["energy"] = ac.energy_from_dir(scene, kappa, n, prev[0])
    if prev is not None:
        shutil.rmtree(prev[0], ignore_errors=True)
    return res


def plot(data, path):
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    fig, ax = plt.subplots(figsize=(9.5, 5.8))
    styles = {"hang_k1e4": ("#1f77b4", "o"), "hang_k1e5": ("#d62728", "s"), "free_k1e2": ("#2ca02c", "^"),
              "free_k1e3": ("#9467bd", "D"), "free_k1e4": ("#ff7f0e", "x"), "free_k1e5": ("#8c564b", "+"),
              "hang_k1e3": ("#7f7f7f", "v")}
    for c in data["cases"]:
        hs = [lv["h"] for lv in c["levels"] if "change" in lv]
        ch = [lv["change"] for lv in c["levels"] if "change" in lv]
        if not hs:
            continue
        col, mk = styles.get(c["name"], ("k", "o"))
        label = f"{c['scene']}, kappa {kname(c['kappa'])}"
        if c["demo"]:
            label += " (chaotic: no reference)" if c["status"] != "unstable" else " (unstable)"
        ax.loglog(hs, ch, marker=mk, color=col, ls="--" if c["demo"] else "-", label=label)
    h = np.array([1e-6, 3e-5])
    ax.loglog(h, 2e-5 * h / 3e-5, color="grey", lw=1, ls="-.", label="slope 1 (first order)")
    ax.axhline(TARGET, color="k", lw=0.8, ls=":")
    ax.text(ax.get_xlim()[0] * 1.1 if ax.get_xlim()[0] > 0 else 1e-6, TARGET * 1.3, "target 1e-6", fontsize=9)
    ax.set_xlabel("step h of the finer run (s)")
    ax.set_ylabel("change of the state after 1 s when h is halved\n(RMS vertex distance / sheet diagonal)")
    ax.set_title("Reference convergence: symplectic Euler, reference backend (double), 16 x 16 grid", fontsize=11)
    ax.grid(True, which="both", alpha=0.3)
    for c in data["cases"]:
        if c["status"] == "unstable":
            lv = c["levels"][-1]
            ax.plot([], [], " ", label=f"{c['scene']}, kappa {kname(c['kappa'])}: exit 3 at h = 1/{lv['steps_per_s']} "
                                        "(the sheet over-stretches)")
    ax.legend(fontsize=8, loc="upper left")
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)


def table(data):
    lines = ["| case | h (s) | change when halved | wall (s) |", "|---|---|---|---|"]
    for c in data["cases"]:
        for lv in c["levels"]:
            ch = f"{lv['change']:.2e}" if "change" in lv else ("exit 3 (unstable)" if lv["exit"] else "-")
            lines.append(f"| {c['scene']} k={kname(c['kappa'])}{' (demo)' if c['demo'] else ''} | "
                         f"1/{lv['steps_per_s']} | {ch} | {lv['wall_s']} |")
    return "\n".join(lines)


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--quick", action="store_true", help="cap at S = 2000 (h = 1/120000) instead of 64000 (h = 1/3840000)")
    ap.add_argument("--jobs", type=int, default=2)
    ap.add_argument("--work", default=os.path.join(ac.ROOT, "build-acc", "acc_runs"))
    a = ap.parse_args()
    cap = 2000 if a.quick else 64000
    todo = [(s, k, cap, False) for s, k in CASES] + [(s, k, 2000 if a.quick else 4000, True) for s, k in DEMOS]
    with ThreadPoolExecutor(a.jobs) as ex:
        results = list(ex.map(lambda t: run_case(t[0], t[1], t[2], a.work, t[3]), todo))
    data = {"what": "reference solutions: symplectic Euler, reference backend, h halved until the "
                    "state after 1 s changes by < 1e-6 of the sheet diagonal",
            "sheet_size": ac.SHEET_SIZE, "quick": a.quick, "cap_S": cap, "cases": results}
    ac.save_json(os.path.join(ac.OUT, "reference.json"), data)
    with open(os.path.join(ac.OUT, "reference_convergence.md"), "w") as f:
        f.write("# Reference convergence\n\nSymplectic Euler, reference backend, 16 x 16 grid; change = RMS "
                "vertex distance after 1 s between h and 2h, divided by the sheet diagonal sqrt 2.\n\n")
        f.write(table(data) + "\n")
    plot(data, os.path.join(ac.OUT, "reference_convergence.png"))
    for c in results:
        print(f"{c['name']}: {c['status']}, finest h = 1/{c['levels'][-1]['steps_per_s']}, "
              f"last change {c['levels'][-1].get('change', float('nan')):.3g}")


if __name__ == "__main__":
    main()
