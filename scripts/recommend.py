#!/usr/bin/python3
"""Which integrator and step to use for a scene and an error budget, from the saved accuracy
study (results/accuracy/sweep.json, written by scripts/accuracy_sweep.py).

    /usr/bin/python3 scripts/recommend.py --scene hang --kappa 1e5 --error 1e-2
    /usr/bin/python3 scripts/recommend.py --scene free --kappa 1e3 --error 1e-3 --json

Prints the cheapest (method, step) whose measured error after 1 s (RMS vertex distance to the
reference / sheet diagonal) is within the budget, its cost (ms per simulated second on the
study's 16 x 16 grid; fast backend 2 threads, Baraff-Witkin on the reference backend) and the
crumple options to get it, then the next-best alternatives. A kappa that was not studied for the
scene takes the nearest studied one (in log kappa) and says so. Exit status 0 with a
recommendation, 1 when no tested method meets the budget, 2 for bad arguments.

    /usr/bin/python3 scripts/recommend.py --scene crumple --grid 128 --kappa 1e4 --error 0.1

The crumple scene (the sphere crumple of 3 s) answers from results/accuracy/crumple/crumple.json
(scripts/crumple_study.py): the cheapest timed configuration whose statistics' seed means are all
within the budget (relative error) of the converged crumple at that grid size and kappa, its
ms per frame, and the options to get it.
"""
import argparse
import json
import math
import os
import sys

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
from accuracy_common import frames_for  # noqa: E402
import crumple_study  # noqa: E402


def crumple_main(a):
    """The crumple scene: a case of the crumple study, by grid size and kappa."""
    data = crumple_study.load_result() if a.table is None else json.load(open(a.table))
    label = f"N{a.grid}_k1e{round(math.log10(a.kappa))}"
    if label not in data.get("pareto", {}):
        studied = ", ".join(sorted(data.get("pareto", {}))) or "none"
        print(f"recommend: the crumple study has no case {label} (grid {a.grid}, kappa {a.kappa:g}); "
              f"studied: {studied}", file=sys.stderr)
        return 2
    points = crumple_study.pareto_points(data, label)
    if not points:
        print(f"recommend: case {label} has no timed configuration (run the study's timing stage)", file=sys.stderr)
        return 2
    ok = sorted((p for p in points if p[4] <= a.error), key=lambda p: p[3])
    args = {k: row for k, row in data["timing"][crumple_study.timing_key(label)].items()}
    machines, commits = crumple_study.timed_on(data, label)

    def describe(p):
        full = args[p[0]]["args"]  # the timed command line, less its seed, on the study's --paper base
        opts = ["--paper"] + [o for i, o in enumerate(full) if o != "--seed" and not (i > 0 and full[i - 1] == "--seed")]
        return {"configuration": p[0], "ms_per_frame": p[3], "error": p[4], "fits_60fps": p[3] <= 1000 / 60,
                "crumple_options": " ".join(opts)}

    case = data.get("converge", {}).get("cases", {}).get(label)
    reference = {"substeps": data["pareto"][label]["reference_substeps"],
                 "converged": bool(case and case.get("converged_at") is not None)}
    out = {"scene": "crumple", "case": label, "error_budget": a.error, "reference": reference,
           "recommendation": describe(ok[0]) if ok else None,
           "alternatives": [describe(p) for p in ok[1:1 + a.alternatives]],
           "machine": " and ".join(machines), "commit": " and ".join(commits)}
    if a.json:
        print(json.dumps(out, indent=1))
        return 0 if ok else 1
    print(f"crumple {label}, error budget {a.error:g} (largest relative error of a statistic's seed mean)")
    print(f"  errors against the S = {reference['substeps']} level: " + (
        "converged by the study's rule" if reference["converged"] else
        "the finest run so far, not converged by the study's rule (results/accuracy/crumple/tables.md)"))
    if not ok:
        best = min(points, key=lambda p: p[4])
        print(f"  none of the timed configurations meets it; the most accurate: {best[0]}, error {best[4]:.1%}, "
              f"{best[3]:.1f} ms/frame")
        return 1
    r = out["recommendation"]
    print(f"  cheapest: {r['configuration']}, error {r['error']:.1%}, {r['ms_per_frame']:.1f} ms per frame "
          f"({'fits' if r['fits_60fps'] else 'does not fit'} 60 fps)")
    print(f"    crumple run {r['crumple_options']}")
    for alt in out["alternatives"]:
        print(f"  then: {alt['configuration']}: error {alt['error']:.1%}, {alt['ms_per_frame']:.1f} ms/frame")
    print(f"  (timed on {out['machine']}, crumple {out['commit']})")
    return 0


def parse_args(argv):
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--scene", required=True, help="hang or free (the scenes of the trajectory study), or crumple")
    ap.add_argument("--grid", type=int, default=128, help="crumple: grid size N of the case")
    ap.add_argument("--kappa", type=float, required=True, help="stiffness per unit mass")
    ap.add_argument("--error", type=float, required=True, help="error budget (fraction of the sheet diagonal)")
    ap.add_argument("--table", default=None, help="the saved study (default: results/accuracy/sweep.json, "
                    "for crumple results/accuracy/crumple/crumple.json)")
    ap.add_argument("--alternatives", type=int, default=3)
    ap.add_argument("--json", action="store_true", help="print one JSON object")
    a = ap.parse_args(argv)
    if not (a.kappa > 0 and a.error > 0):
        ap.error("--kappa and --error must be positive")
    return a


def trajectory_case(a):
    """The saved study and its case nearest a's scene and kappa, with notes on how near: or an
    error message when the study cannot be read or did not study the scene."""
    a.table = a.table or os.path.join(ROOT, "results", "accuracy", "sweep.json")
    try:
        with open(a.table) as f:
            data = json.load(f)
    except OSError as e:
        return f"cannot read {a.table}: {e.strerror} (run scripts/accuracy.sh first)"
    cases = [c for c in data["cases"] if c["scene"] == a.scene]
    if not cases:
        scenes = sorted({c["scene"] for c in data["cases"]})
        return f"scene '{a.scene}' was not studied; studied: {', '.join(scenes)}"
    case = min(cases, key=lambda c: abs(math.log10(c["kappa"]) - math.log10(a.kappa)))
    notes = []
    if abs(math.log10(case["kappa"]) - math.log10(a.kappa)) > 1e-9:
        studied = ", ".join(f"{c['kappa']:g}" for c in cases)
        notes.append(f"kappa {a.kappa:g} was not studied for the {a.scene} scene; using the nearest, "
                     f"kappa {case['kappa']:g} (studied: {studied})")
    ref_unc = case.get("reference_change")
    if ref_unc and a.error < 3 * ref_unc:
        notes.append(f"the budget is within 3x of the reference's own uncertainty ({ref_unc:.2g}): "
                     "errors that small are not resolved by this study")
    return data, case, notes


def describe(r, methods):
    """A study row as a recommendation: the method, its step and the crumple options for it."""
    m = methods[r["method"]]
    n = r["steps_per_s"]
    opts = m["args"] + ["--backend", m["backend"]] + (["--threads", str(m["threads"])] if m["backend"] == "fast" else [])
    # h = 1/n: n/60 substeps of the default 1/60 s frame when 60 divides n, else frames as
    # close to 1/60 s as the step allows (then --frames counts those frames)
    if n % 60 == 0:
        step = ["--substeps", str(n // 60)]
    else:
        f = frames_for(n)
        step = ["--frame-dt", f"{f['frame_dt']:.9g}", "--substeps", str(f["substeps"])]
    return {"method": r["method"], "text": m["text"], "step": f"1/{n}", "h": 1.0 / n,
            "ms_per_simulated_s": r["ms_per_s"], "error": r["error"],
            "crumple_options": " ".join(str(o) for o in opts + step)}


def print_trajectory(a, case, out, data):
    """The text answer for a trajectory scene; returns the exit status."""
    print(f"scene {a.scene}, kappa {case['kappa']:g}, error budget {a.error:g} (after 1 s, fraction of the sheet diagonal)")
    for n in out["notes"]:
        print(f"  note: {n}")
    r = out["recommendation"]
    if not r:
        best = min((r for r in case["rows"] if not r["failed"] and r.get("error") is not None),
                   key=lambda r: r["error"], default=None)
        print("  none of the tested methods and steps (h >= 1/1000 s) meets this budget")
        if best:
            print(f"  the most accurate tested: {best['method']} at h = 1/{best['steps_per_s']}, error {best['error']:.2g}")
        return 1
    print(f"  cheapest: {r['method']} ({r['text']}) at h = {r['step']} s")
    print(f"    error {r['error']:.2g}, cost {r['ms_per_simulated_s']:.3g} ms per simulated second (16 x 16 grid)")
    print(f"    crumple run {r['crumple_options']}")
    for alt in out["alternatives"]:
        print(f"  then: {alt['method']} at h = {alt['step']}: error {alt['error']:.2g}, "
              f"{alt['ms_per_simulated_s']:.3g} ms/s")
    if data.get("timing_note"):
        print(f"  ({data['timing_note']})")
    return 0


def main(argv=None):
    a = parse_args(argv)
    if a.scene == "crumple":
        return crumple_main(a)
    found = trajectory_case(a)
    if isinstance(found, str):
        print(f"recommend: {found}", file=sys.stderr)
        return 2
    data, case, notes = found
    ok = [r for r in case["rows"] if not r["failed"] and r.get("error") is not None
          and r.get("ms_per_s") and r["error"] <= a.error]
    ok.sort(key=lambda r: r["ms_per_s"])
    methods = data["methods"]
    out = {"scene": a.scene, "kappa_asked": a.kappa, "kappa_used": case["kappa"], "error_budget": a.error,
           "notes": notes, "recommendation": describe(ok[0], methods) if ok else None,
           "alternatives": [describe(r, methods) for r in ok[1:1 + a.alternatives]],
           "source": os.path.relpath(a.table, ROOT), "timing_note": data.get("timing_note")}
    if a.json:
        print(json.dumps(out, indent=1))
        return 0 if ok else 1
    return print_trajectory(a, case, out, data)

if __name__ == "__main__":
    sys.exit(main())
