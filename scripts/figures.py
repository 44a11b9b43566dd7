#!/usr/bin/python3
"""Reproduce the paper's parameter figures with `crumple run` and write them to results/figures.

    /usr/bin/python3 scripts/figures.py --bin build-fig/app/crumple [--out results/figures]
        [--quick] [--seeds 5] [--grid 32] [--frames 180] [--jobs 2]
        [--sim-args "--substeps 2 ..."]   extra crumple options for every sweep run
        [--only fig10,fig11,fig12,fig6,diag,woody,hero] [--perturb A]

Figures (the sphere-crumple scene, an N x N grid, default model parameters except the swept
one; the same seed list for every setting; the picture shows seed 1, the numbers under it are
mean +- s.d. over all seeds):
  fig10_phi.png      phi = 0, 0.5, 0.75, 1 (psi = 0.25)   claim: smaller phi breaks more
  fig11_psi.png      psi = 0, 0.25, 0.5, 1 (phi = 0.25)   claim: smaller psi -> re-breaks
  fig12_epsilon.png  epsilon = 0.1, 0.9                    claim: small epsilon restores easily
  fig6_varphi.png    m_n of [Eq 3] for varphi = 1..5 (computed) + one sweep per varphi
  diag_substeps.png, diag_flat.png   not paper claims: time-step dependence, and a flat
                     sheet vs one with a small smooth out-of-plane bump (3 seeds)
  woody_strip.png, woody.gif   crumpling tests/data/woody.obj
  hero.png           a crumpled sheet for the README
and claims.json (every number, per seed) and README.md (verdict per claim, generated from
the numbers of this run).

Measures (see crease.py): splits / restores are the totals of the per-frame counts in
stats.csv; vertices is the final count; crease = total length of mesh edges with a dihedral
angle > 30 deg divided by sqrt(initial area); rms = RMS vertex distance from the centroid.
Re-breaks (the psi claim): an edge created by a split always has the split's new vertex as an
endpoint, and original vertices are never removed and keep the first N0 slots (so the first
N0 `v` lines of the OBJ), so an auxiliary spring (a broken edge still held, `l` line) with an
endpoint >= N0 is a *second-generation* break: an edge made by an earlier split that broke
again. rebreak_frac = such springs / all held springs at the end. Restored breaks are not
counted (they left no spring). Also late_rate: mean splits per frame over the last third of
the run, after the first crumple.
A run that stops early ("simulation became unstable") is marked; its numbers cover the frames
it ran, its picture is its last written frame, and the means use completed runs only when
there are any.
"""
import argparse
import json
import math
import os
import shlex
import subprocess
import sys
import time
from concurrent.futures import ThreadPoolExecutor

import numpy as np
import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
from matplotlib.gridspec import GridSpec, GridSpecFromSubplotSpec  # noqa: E402

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, HERE)
import accuracy_common as ac  # noqa: E402
from render import load_obj, render_mesh, face_normals  # noqa: E402
from crease import crease_stats  # noqa: E402

ROOT = os.path.dirname(HERE)
ELEV, AZIM = 50.0, -60.0   # the sweeps: from above, the pancake-like results show their tops


# ----------------------------------------------------------------------------- running
def read_stats(path):
    with open(path) as fh:
        head = fh.readline().strip().split(",")
        rows = [list(map(float, l.split(","))) for l in fh if l.strip()]
    a = np.array(rows) if rows else np.zeros((0, len(head)))
    return {h: a[:, i] for i, h in enumerate(head)}


def frame_files(d):
    return sorted(f for f in os.listdir(d) if f.startswith("frame_") and f.endswith(".obj"))


def run_sim(binary, outdir, args, every, ref_area, force=False):
    """Run crumple once (cached by command line) and measure it. Returns a dict."""
    os.makedirs(outdir, exist_ok=True)
    # The paper's configuration on the reference backend, as the figures were made (D28).
    cmd = [binary, "run", "--quiet", "--out", outdir, "--every", str(every)] + ac.pinned_base(args)
    meta = os.path.join(outdir, "run.json")
    if not force and os.path.exists(meta):
        with open(meta) as fh:
            old = json.load(fh)
        if old.get("cmd") == cmd and old.get("binary_mtime") == os.path.getmtime(binary):
            return old
    for f in os.listdir(outdir):
        os.remove(os.path.join(outdir, f))
    t0 = time.time()
    p = subprocess.run(cmd, capture_output=True, text=True)
    wall = time.time() - t0
    st = read_stats(os.path.join(outdir, "stats.csv")) if os.path.exists(
        os.path.join(outdir, "stats.csv")) else None
    final = os.path.join(outdir, "final.obj")
    ok = p.returncode == 0 and os.path.exists(final)
    if not os.path.exists(final):
        fr = frame_files(outdir)
        final = os.path.join(outdir, fr[-1]) if fr else None
    r = {"cmd": cmd, "binary_mtime": os.path.getmtime(binary), "rc": p.returncode, "ok": ok,
         "error": p.stderr.strip()[-300:], "wall_s": wall, "obj": final}
    if st is None or len(st["frame"]) == 0:
        r["frames_run"] = 0
        with open(meta, "w") as fh:
            json.dump(r, fh)
        return r
    r.update(series_measures(st))
    if final:
        r.update(shape_measures(final, ref_area, r["vertices0"]))
    with open(meta, "w") as fh:
        json.dump(r, fh)
    return r


def series_measures(st):
    """run_sim's numbers from stats.csv: totals, first and final counts, late split rate,
    cumulative series."""
    n = len(st["frame"])
    n0 = int(st["vertices"][0] - st["splits"][0] + st["restores"][0])
    late = st["splits"][2 * n // 3:]
    return {
        "frames_run": int(st["frame"][-1]),
        "splits": int(st["splits"].sum()),
        "restores": int(st["restores"].sum()),
        "vertices": int(st["vertices"][-1]),
        "vertices0": n0,
        "late_rate": float(late.mean()) if len(late) else 0.0,
        "max_strain": float(st["max_strain"].max()),
        "step_ms_mean": float(st["step_ms"].mean()),
        "series": {"time": st["time"].round(5).tolist(),
                   "splits": np.cumsum(st["splits"]).astype(int).tolist(),
                   "restores": np.cumsum(st["restores"]).astype(int).tolist(),
                   "vertices": st["vertices"].astype(int).tolist()},
    }


def shape_measures(final, ref_area, n0):
    """run_sim's numbers from the last mesh: aspect, crease, RMS radius, held and re-broken
    springs (an endpoint >= n0, the original vertex count, marks a second-generation break)."""
    V, F, L = load_obj(final)
    c = crease_stats(V, F, L, ref_area=ref_area)
    held = len(L)
    reb = int(np.any(L >= n0, axis=1).sum()) if held else 0
    used = V[np.unique(F)] if len(F) else V
    ev = np.linalg.eigvalsh(np.cov((used - used.mean(0)).T))
    return {"aspect": float(np.sqrt(max(ev[0], 0) / ev[-1])) if ev[-1] > 0 else 0.0,
            "crease": c["crease_norm"], "crease_length": c["crease_length"],
            "rms": c["rms_radius_norm"], "mean_dihedral": c["mean_dihedral_deg"],
            "held": held, "rebreaks": reb,
            "rebreak_frac": reb / held if held else 0.0,
            "obj_frame": os.path.basename(final)}


def run_many(binary, jobs, specs):
    """specs: list of (outdir, args, every, ref_area). Returns results in order."""
    with ThreadPoolExecutor(max_workers=jobs) as ex:
        futs = [ex.submit(run_sim, binary, *s) for s in specs]
        return [f.result() for f in futs]


def perturbed_grid(path, n, amp, seed=3):
    """Write the n x n unit-square grid of `crumple run --grid n` (alternating diagonals) as an
    OBJ with a smooth out-of-plane perturbation: a sum of the 9 lowest sine modes with random
    phases, scaled so max |z| = amp (in sheet widths). The sheet is then slightly curved *at
    rest*; the perturbation only breaks the flat sheet's symmetry so the sphere can buckle
    it out of plane (see README: a perfectly flat sheet stays a flat disk)."""
    rng = np.random.default_rng(seed)
    xs = np.linspace(0.0, 1.0, n)
    X, Y = np.meshgrid(xs, xs)
    Z = np.zeros_like(X)
    for kx in range(1, 4):
        for ky in range(1, 4):
            Z += (rng.normal() / (kx * kx + ky * ky)
                  * np.sin(np.pi * kx * X + rng.uniform(0, 2 * np.pi))
                  * np.sin(np.pi * ky * Y + rng.uniform(0, 2 * np.pi)))
    Z *= amp / max(np.abs(Z).max(), 1e-12)
    with open(path, "w") as f:
        f.write(f"# {n}x{n} unit grid, smooth out-of-plane perturbation max |z| = {amp}\n")
        for x, y, z in zip(X.ravel(), Y.ravel(), Z.ravel()):
            f.write(f"v {x:.9g} {y:.9g} {z:.9g}\n")
        for iy in range(n - 1):
            for ix in range(n - 1):
                a = iy * n + ix + 1
                b, d = a + 1, a + n
                c = b + n
                if (ix + iy) % 2 == 1:
                    f.write(f"f {a} {b} {d}\nf {b} {c} {d}\n")
                else:
                    f.write(f"f {a} {b} {c}\nf {a} {c} {d}\n")
    return path


def sheet_args(work, n, amp):
    """crumple options for an n x n sheet: --grid n, or a perturbed grid OBJ when amp > 0."""
    if amp <= 0:
        return ["--grid", str(n)]
    p = os.path.join(work, f"grid{n}_perturb{amp:g}.obj")
    if not os.path.exists(p):
        perturbed_grid(p, n, amp)
    return ["--mesh", p]


# ----------------------------------------------------------------------------- numbers
METRICS = ["splits", "restores", "vertices", "crease", "rms", "aspect", "held", "rebreaks",
           "rebreak_frac", "late_rate", "mean_dihedral", "wall_s"]


def summarize(runs):
    ok = [r for r in runs if r.get("ok")]
    use = ok if ok else [r for r in runs if r.get("frames_run", 0) > 0]
    s = {"n": len(runs), "n_ok": len(ok), "truncated": not ok,
         "failed_at": [r.get("frames_run") for r in runs if not r.get("ok")]}
    for m in METRICS:
        v = np.array([r[m] for r in use if m in r], float)
        if len(v):
            s[m] = {"mean": float(v.mean()), "sd": float(v.std(ddof=1)) if len(v) > 1 else 0.0,
                    "min": float(v.min()), "max": float(v.max()),
                    "values": [float(x) for x in v]}
    return s


def fmt(s, m, nd=0):
    if m not in s:
        return "n/a"
    d = s[m]
    if nd == 0:
        return f"{d['mean']:.0f} ± {d['sd']:.0f}"
    return f"{d['mean']:.{nd}f} ± {d['sd']:.{nd}f}"


def trend(xs, means, decreasing=True):
    """'monotonic', 'ends' (first vs last only) or 'no'."""
    d = np.diff(means)
    mono = np.all(d <= 0) if decreasing else np.all(d >= 0)
    ends = means[-1] < means[0] if decreasing else means[-1] > means[0]
    return "monotonic" if mono else ("ends" if ends else "no")


def separated(a, b):
    """Are the seed ranges of two settings disjoint (a clear difference for few seeds)?"""
    return a["max"] < b["min"] or b["max"] < a["min"]


# ----------------------------------------------------------------------------- drawing
def panel_view(objs, elev=ELEV):
    """Shared radius for a row: each panel centred, common scale."""
    rad = 0.0
    from render import camera_frame
    eye, up, right = camera_frame(elev, AZIM)
    for o in objs:
        if not o:
            continue
        V, F, _ = load_obj(o)
        P = V - 0.5 * (V.min(0) + V.max(0))
        sx, sy = P @ right, P @ up
        rad = max(rad, 0.5 * (sx.max() - sx.min()), 0.5 * (sy.max() - sy.min()))
    return rad if rad > 0 else None


def sweep_figure(path, title, pname, values, labels, summaries, runs_by_col, claim_metric,
                 claim_label, extra_lines, elev=None, xticklabels=None):
    """One row of renders (first seed), numbers under them, then time series and the
    claim's metric per seed."""
    seed1 = [runs[0] for runs in runs_by_col]
    ncol = len(values)
    w = max(3.4 * ncol, 10.0)
    cw = w * 0.93 / ncol   # column width in inches: the render row is as tall
    H = cw + 5.2
    fig = plt.figure(figsize=(w, H), facecolor="white")
    gs = GridSpec(3, ncol, figure=fig, height_ratios=[cw, 1.35, 2.5], hspace=0.12,
                  left=0.06, right=0.98, top=1 - 0.75 / H, bottom=0.8 / H)
    fig.suptitle(title, fontsize=13, y=1 - 0.12 / H, va="top")
    elev = ELEV if elev is None else elev
    radius = panel_view([r.get("obj") for r in seed1], elev)
    for k, (lab, s, r1) in enumerate(zip(labels, summaries, seed1)):
        sweep_column(fig, gs, k, lab, s, r1, extra_lines, elev, radius)
    sub = GridSpecFromSubplotSpec(1, 3, subplot_spec=gs[2, :], wspace=0.3)
    cmap = plt.get_cmap("viridis")
    cols = [cmap(i / max(1, ncol - 1) * 0.85) for i in range(ncol)]
    sweep_series(fig, sub, labels, cols, runs_by_col)
    ax = fig.add_subplot(sub[0, 2])
    for x, s, c in zip(values, summaries, cols):
        if claim_metric in s:
            v = s[claim_metric]["values"]
            ax.plot([x] * len(v), v, "o", color=c, ms=4, alpha=0.8)
    xs = [x for x, s in zip(values, summaries) if claim_metric in s]
    ms = [s[claim_metric]["mean"] for s in summaries if claim_metric in s]
    ax.plot(xs, ms, "-", color="0.3", lw=1.2)
    ax.set_xlabel(pname)
    if xticklabels:
        ax.set_xticks(values)
        ax.set_xticklabels(xticklabels, fontsize=7)
    ax.set_ylabel(claim_label)
    ax.grid(alpha=0.3)
    fig.text(0.5, 0.005, "crease: length of edges with dihedral > 30° / sqrt(sheet area); "
             "rms: RMS vertex distance from the centroid / sqrt(area) (flat: 0.408); "
             "curves: every seed", ha="center", va="bottom", fontsize=8, color="0.3")
    fig.savefig(path, dpi=95, facecolor="white")
    plt.close(fig)


def sweep_column(fig, gs, k, lab, s, r1, extra_lines, elev, radius):
    """Column k of a sweep figure: seed 1's render and the setting's numbers under it (red when
    some seeds went unstable)."""
    ax = fig.add_subplot(gs[0, k], projection="3d", proj_type="ortho")
    if r1.get("obj"):
        V, F, L = load_obj(r1["obj"])
        render_mesh(V, F, L, ax=ax, elev=elev, azim=AZIM, radius=radius, fill=0.95)
    ax.set_title(lab, fontsize=11, pad=0)
    tax = fig.add_subplot(gs[1, k])
    tax.axis("off")
    lines = [f"splits    {fmt(s, 'splits')}",
             f"restores  {fmt(s, 'restores')}",
             f"vertices  {fmt(s, 'vertices')}",
             f"crease    {fmt(s, 'crease', 1)}"]
    for key, name, nd in extra_lines:
        lines.append(f"{name:<9} {fmt(s, key, nd)}")
    note = f"{s['n']} seeds"
    if s["n_ok"] < s["n"]:
        note += f", {s['n'] - s['n_ok']} UNSTABLE (frames {s['failed_at']})"
    if not r1.get("ok"):
        note = f"seed 1 unstable at frame {r1.get('frames_run')} (last frame shown); " + note
    lines.append(note)
    tax.text(0.5, 1.0, "\n".join(lines), ha="center", va="top", family="monospace",
             multialignment="left",
             fontsize=8.6, color="black" if s["n_ok"] == s["n"] else "firebrick",
             transform=tax.transAxes)


def sweep_series(fig, sub, labels, cols, runs_by_col):
    """Cumulative splits and restores of every seed, coloured by setting."""
    for j, key in enumerate(["splits", "restores"]):
        ax = fig.add_subplot(sub[0, j])
        for lab, c, runs in zip(labels, cols, runs_by_col):
            for r in runs:
                if "series" in r:
                    ax.plot(r["series"]["time"], r["series"][key], color=c, lw=0.8,
                            alpha=0.7, label=lab if r is runs[0] else None)
        ax.set_xlabel("time (s)")
        ax.set_ylabel(f"cumulative {key}")
        ax.grid(alpha=0.3)
        if j == 0:
            ax.legend(fontsize=7, frameon=False)


# ----------------------------------------------------------------------------- Fig 6
def mn_formula(varphi, d, m=None):
    """[Eq 3]: new-vertex mass for neighbour distances d (rest) and masses m."""
    d = np.asarray(d, float)
    m = np.ones_like(d) if m is None else np.asarray(m, float)
    delta = d / d.sum()
    mk = 0.5 * (delta ** (1.0 / varphi) + 1.0) * m
    return float((m - mk).sum())


def fig6(path, summaries, varphis):
    vf = np.linspace(1, 6, 200)
    sq = [mn_formula(v, [1, 1, 1, 1]) for v in vf]
    # a 32x32 grid edge of length h with its two wings (alternating diagonals):
    # axis edge: ends at h/2, wings at sqrt(h^2 + (h/2)^2); diagonal: ends at h/sqrt2, wings h/sqrt2
    ax_e = [mn_formula(v, [0.5, 0.5, math.sqrt(1.25), math.sqrt(1.25)]) for v in vf]
    bnd = [mn_formula(v, [0.5, 0.5, math.sqrt(1.25)]) for v in vf]
    fig = plt.figure(figsize=(13, 4.6), facecolor="white")
    gs = GridSpec(1, 3, figure=fig, width_ratios=[1.2, 1.25, 1.0], wspace=0.38,
                  left=0.06, right=0.98, top=0.86, bottom=0.13)
    fig.suptitle("Fig 6: mass a new vertex takes, [Eq 3] "
                 "m_n = sum_k m_k (1 - (delta_k^(1/varphi) + 1)/2)", fontsize=12)
    ax = fig.add_subplot(gs[0])
    ax.plot(vf, sq, label="unit square diagonal, unit masses (paper's Fig 6)")
    ax.plot(vf, ax_e, "--", label="grid axis edge + 2 wings (interior)")
    ax.plot(vf, bnd, ":", label="grid boundary edge + 1 wing")
    for v in range(1, 6):
        y = mn_formula(v, [1, 1, 1, 1])
        ax.plot(v, y, "o", color="C0")
        ax.annotate(f"{y:.4f}", (v, y), textcoords="offset points", xytext=(4, 5), fontsize=8)
    ax.set_xlabel("varphi")
    ax.set_ylabel("m_n (unit masses)")
    ax.legend(fontsize=7.5, frameon=False)
    ax.grid(alpha=0.3)
    ax2 = fig.add_subplot(gs[1])
    ax2.axis("off")
    rows = [["varphi", "m_n sq.", "splits", "vertices", "crease"]]
    for v, s in zip(varphis, summaries):
        rows.append([f"{v:g}", f"{mn_formula(v, [1, 1, 1, 1]):.4f}", fmt(s, "splits"),
                     fmt(s, "vertices"), fmt(s, "crease", 1)])
    t = ax2.table(cellText=rows[1:], colLabels=rows[0], loc="center", cellLoc="center",
                  colWidths=[0.13, 0.17, 0.25, 0.25, 0.22])
    t.auto_set_font_size(False)
    t.set_fontsize(8)
    t.scale(1.1, 1.6)
    ax2.set_title("sphere crumple per varphi (mean ± s.d.)", fontsize=9)
    ax3 = fig.add_subplot(gs[2])
    for key, c in [("splits", "C0"), ("restores", "C1"), ("vertices", "C2")]:
        m = [s[key]["mean"] if key in s else np.nan for s in summaries]
        e = [s[key]["sd"] if key in s else np.nan for s in summaries]
        ax3.errorbar(varphis, m, yerr=e, fmt="o-", color=c, label=key, capsize=3, ms=4)
    ax3.set_xlabel("varphi")
    ax3.set_ylabel("count")
    ax3.legend(fontsize=8, frameon=False)
    ax3.grid(alpha=0.3)
    ax3.set_title("the mean new-vertex mass is not in crumple's output\n"
                  "(OBJ and stats.csv carry no per-vertex mass)", fontsize=8)
    fig.savefig(path, dpi=100, facecolor="white")
    plt.close(fig)


# ----------------------------------------------------------------------------- woody
def woody(binary, work, out, frames, mesh, extra, every, quick):
    d = os.path.join(work, "woody")
    Vi, Fi, _ = load_obj(mesh)
    area0 = float(face_normals(Vi, Fi)[1].sum())
    r = run_sim(binary, d, ["--mesh", mesh, "--frames", str(frames), "--seed", "1"] + extra,
                every, area0)
    fr = frame_files(d)
    objs = [(0, mesh)] + [(int(f[6:11]), os.path.join(d, f)) for f in fr]
    if r.get("ok"):
        objs.append((r["frames_run"], os.path.join(d, "final.obj")))
    objs = sorted(dict(objs).items())
    from render import camera_frame
    view = {"elev": 55.0, "azim": -75.0}
    eye, up, right = camera_frame(view["elev"], view["azim"])
    view["center"] = 0.5 * (Vi.min(0) + Vi.max(0))
    P = Vi - view["center"]
    view["radius"] = 1.02 * max(np.abs(P @ right).max(), np.abs(P @ up).max())
    st = read_stats(os.path.join(d, "stats.csv"))
    c = woody_strip(os.path.join(out, "woody_strip.png"), objs, st, view, (Vi, Fi, area0), r)
    gif = os.path.join(out, "woody.gif")
    try:
        from PIL import Image  # noqa: F401
    except ImportError:
        print("figures: python3-pil missing, no GIF", file=sys.stderr)
        return r, c
    woody_gif(gif, objs[::2 if quick else 1], view, int(1000 * every * (2 if quick else 1) / 60 * 2))
    return r, c


def woody_strip(path, objs, st, view, input_mesh, r):
    """Six frames evenly over the run, each with its time and counts; returns the last one's
    crease statistics."""
    Vi, Fi, area0 = input_mesh
    cums = np.cumsum(st["splits"])
    cumr = np.cumsum(st["restores"])

    def label(fn):
        if fn == 0:
            return "t = 0 s (input)"
        i = min(fn, len(cums)) - 1
        return (f"t = {fn / 60:.1f} s\nsplits {int(cums[i])}, restores {int(cumr[i])}\n"
                f"vertices {int(st['vertices'][i])}")

    want = np.linspace(0, objs[-1][0], 6)
    pick = []
    for w in want:
        k = min(range(len(objs)), key=lambda i: abs(objs[i][0] - w))
        if objs[k] not in pick:
            pick.append(objs[k])
    fig = plt.figure(figsize=(3.0 * len(pick), 3.9), facecolor="white")
    for k, (fn, o) in enumerate(pick):
        ax = fig.add_axes([k / len(pick), 0.16, 1 / len(pick), 0.78], projection="3d",
                          proj_type="ortho")
        V, F, L = load_obj(o)
        render_mesh(V, F, L, ax=ax, fill=0.97, **view)
        fig.text((k + 0.5) / len(pick), 0.15, label(fn), ha="center", va="top", fontsize=8.5)
    c = crease_stats(*load_obj(pick[-1][1]), ref_area=area0)
    fig.suptitle(f"woody.obj ({len(Fi)} triangles, ~{np.ptp(Vi[:, 0]):.0f} units wide) in the "
                 f"shrinking sphere; final crease {c['crease_norm']:.1f} sheet-widths, "
                 f"RMS radius {c['rms_radius_norm']:.3f} sqrt(A0)"
                 + ("" if r.get("ok") else f" — UNSTABLE at frame {r.get('frames_run')}"),
                 fontsize=10)
    fig.savefig(path, dpi=100, facecolor="white")
    plt.close(fig)
    return c


def woody_gif(path, objs, view, duration_ms):
    """Every given frame rendered small, assembled with Pillow (duration_ms a frame)."""
    from PIL import Image
    imgs = []
    for fn, o in objs:
        fig = plt.figure(figsize=(4.0, 4.0), facecolor="white")
        ax = fig.add_axes([0, 0, 1, 1], projection="3d", proj_type="ortho")
        V, F, L = load_obj(o)
        render_mesh(V, F, L, ax=ax, fill=0.97, **view)
        fig.text(0.03, 0.03, f"t = {fn / 60:.2f} s", fontsize=9)
        fig.canvas.draw()
        im = Image.fromarray(np.asarray(fig.canvas.buffer_rgba())[:, :, :3].copy())
        plt.close(fig)
        imgs.append(im.quantize(colors=64, method=Image.Quantize.MEDIANCUT))
    imgs[0].save(path, save_all=True, append_images=imgs[1:], duration=duration_ms, loop=0,
                 optimize=True)


# ----------------------------------------------------------------------------- hero
def hero(binary, work, out, grid, frames, extra, frame_pick, perturb):
    d = os.path.join(work, f"hero{grid}")
    r = run_sim(binary, d, sheet_args(work, grid, perturb)
                + ["--frames", str(frames), "--seed", "1"] + extra, max(1, frames // 6), 1.0)
    o = r.get("obj")
    if frame_pick:
        cand = os.path.join(d, f"frame_{frame_pick:05d}.obj")
        if os.path.exists(cand):
            o = cand
    fig = plt.figure(figsize=(8, 6), facecolor="white")
    ax = fig.add_axes([0, 0, 1, 1], projection="3d", proj_type="ortho")
    V, F, L = load_obj(o)
    render_mesh(V, F, L, ax=ax, elev=28, azim=-52, fill=0.9, crease_width=0.3,
                crease_deg=40)
    fig.savefig(os.path.join(out, "hero.png"), dpi=130, facecolor="white")
    plt.close(fig)
    return r, o


# ----------------------------------------------------------------------------- main
ALL_FIGURES = ("fig10", "fig11", "fig12", "fig6", "diag", "woody", "hero")


def parse_args(argv):
    p = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    p.add_argument("--bin", default=os.path.join(ROOT, "build-fig", "app", "crumple"))
    p.add_argument("--out", default=None, help="default results/figures; with --quick "
                   "<work>/quick-figures, so a quick pass does not overwrite the real figures")
    p.add_argument("--work", default=os.path.join(ROOT, "build-fig", "figwork"))
    p.add_argument("--quick", action="store_true", help="2 seeds, 120 frames, hero on a 32 grid")
    p.add_argument("--seeds", type=int, default=5)
    p.add_argument("--grid", type=int, default=32)
    p.add_argument("--frames", type=int, default=180)
    p.add_argument("--jobs", type=int, default=os.cpu_count() or 2)
    p.add_argument("--sim-args", default="", help="extra crumple options for every sweep")
    p.add_argument("--woody-args", default=None, help="crumple options for woody "
                   "(default: --sim-args)")
    p.add_argument("--perturb", type=float, default=0.0,
                   help="sweeps: start from a grid with a smooth out-of-plane bump of this "
                        "amplitude (sheet widths; 0 = the flat --grid sheet)")
    p.add_argument("--hero-args", default="--substeps 4",
                   help="crumple options for the hero (default: '--substeps 4')")
    p.add_argument("--hero-perturb", type=float, default=0.03,
                   help="hero: out-of-plane perturbation amplitude (0 = flat grid)")
    p.add_argument("--hero-grid", type=int, default=64)
    p.add_argument("--hero-frame", type=int, default=0, help="frame to show (0: last)")
    p.add_argument("--only", default=",".join(ALL_FIGURES))
    a = p.parse_args(argv)
    if a.quick:
        a.seeds, a.frames = 2, 120
    if a.out is None:
        a.out = (os.path.join(a.work, "quick-figures") if a.quick
                 else os.path.join(ROOT, "results", "figures"))
    return a


class Run:
    """One run of this script: its options, the seed list and crumple arguments every sweep
    shares, and the claims (every number, per seed) recorded so far."""

    def __init__(self, a):
        self.a = a
        self.seeds = list(range(1, a.seeds + 1))
        self.extra = shlex.split(a.sim_args)
        self.common = ["--frames", str(a.frames)] + self.extra
        self.every = max(1, a.frames // 6)
        self.t_start = time.time()
        self.claims = {"config": {"binary": os.path.abspath(a.bin), "grid": a.grid,
                                  "frames": a.frames, "seeds": self.seeds,
                                  "sim_args": self.extra, "perturb": a.perturb,
                                  "git": git_describe(), "date": time.strftime("%Y-%m-%d %H:%M")}}

    def sweep(self, name, settings, seed_list=None):
        """settings: list of (label, [args]) or (label, [args], perturbation amplitude).
        Returns list of (summary, runs)."""
        a = self.a
        specs, idx = [], []
        for k, st in enumerate(settings):
            args = st[1]
            sheet = sheet_args(a.work, a.grid, st[2] if len(st) > 2 else a.perturb)
            for s in seed_list or self.seeds:
                tag = "_".join(x.lstrip("-") for x in args) or "default"
                tag = "".join(ch if ch.isalnum() or ch in "._=-" else "_" for ch in tag)[:60]
                specs.append((os.path.join(a.work, name, f"{k}_{tag}_s{s}"),
                              sheet + self.common + args + ["--seed", str(s)], self.every, 1.0))
                idx.append(k)
        res = run_many(a.bin, a.jobs, specs)
        return [(summarize(runs), runs)
                for runs in ([r for r, i in zip(res, idx) if i == k] for k in range(len(settings)))]

    def record(self, name, pname, values, settings, res, verdict):
        self.claims[name] = {"parameter": pname, "settings": [
            {"value": v, "args": args, "summary": s,
             "runs": [{k: r.get(k) for k in ["rc", "ok", "frames_run", "error", "wall_s"]
                       + METRICS if k in r} for r in runs]}
            for v, (lab, args, *_), (s, runs) in zip(values, settings, res)],
            "verdict": verdict}

    def draw(self, png, title, pname, values, settings, res, metric, metric_label, extras, **kw):
        """sweep_figure of one sweep: labels, summaries and runs come from settings and res."""
        sweep_figure(os.path.join(self.a.out, png), title, pname, values,
                     [lab for lab, *_ in settings], [s for s, _ in res], [runs for _, runs in res],
                     metric, metric_label, extras, **kw)

    def caption(self):
        """The parameter sweeps' shared title tail: the scene, and what picture and numbers show."""
        return (f"grid {self.a.grid}, {self.a.frames} frames, seed 1 shown, numbers mean ± s.d. "
                f"over {len(self.seeds)} seeds")

    def done(self, what):
        print(f"{what} done ({time.time() - self.t_start:.0f} s)", file=sys.stderr)


def fig10_phi(run):
    vals = [0.0, 0.5, 0.75, 1.0]
    st = [(f"phi = {v:g}", ["--phi", f"{v:g}", "--psi", "0.25"]) for v in vals]
    res = run.sweep("fig10", st)
    sm = [s for s, _ in res]
    means = np.array([s["splits"]["mean"] for s in sm])
    tr = trend(vals, means, decreasing=True)
    verdict = {"claim": "smaller phi breaks more edges", "metric": "total splits",
               "means": means.tolist(), "trend": tr,
               "held": tr == "monotonic",
               "phi0_vs_phi1_separated": separated(sm[0]["splits"], sm[-1]["splits"])}
    run.record("fig10", "phi", vals, st, res, verdict)
    run.draw("fig10_phi.png", f"Fig 10: phi sweep (psi = 0.25), {run.caption()}",
             "phi", vals, st, res, "splits", "total splits", [("rms", "rms", 3)])
    run.done("fig10")


def fig11_psi(run):
    vals = [0.0, 0.25, 0.5, 1.0]
    st = [(f"psi = {v:g}", ["--psi", f"{v:g}", "--phi", "0.25"]) for v in vals]
    res = run.sweep("fig11", st)
    sm = [s for s, _ in res]
    fr, rb, lr, spl = (np.array([s[m]["mean"] for s in sm])
                       for m in ("rebreak_frac", "rebreaks", "late_rate", "splits"))
    verdict = {"claim": "smaller psi makes broken edges break again more readily",
               "metric": "rebreak_frac: share of the held auxiliary springs whose edge was "
                         "made by an earlier split (second-generation breaks)",
               "rebreak_frac_means": fr.tolist(), "rebreaks_means": rb.tolist(),
               "late_rate_means": lr.tolist(), "splits_means": spl.tolist(),
               "trend_rebreak_frac": trend(vals, fr), "trend_rebreaks": trend(vals, rb),
               "trend_late_rate": trend(vals, lr), "trend_splits": trend(vals, spl),
               "held": trend(vals, fr) == "monotonic",
               "psi0_vs_psi1_separated": separated(sm[0]["rebreak_frac"],
                                                   sm[-1]["rebreak_frac"])}
    run.record("fig11", "psi", vals, st, res, verdict)
    run.draw("fig11_psi.png", f"Fig 11: psi sweep (phi = 0.25), {run.caption()}",
             "psi", vals, st, res, "rebreak_frac", "re-broken share of held springs",
             [("rebreaks", "re-breaks", 0), ("rebreak_frac", "re-brk %", 3),
              ("late_rate", "late/frm", 1)])
    run.done("fig11")


def fig12_epsilon(run):
    vals = [0.1, 0.9]
    st = [(f"epsilon = {v:g}", ["--epsilon", f"{v:g}"]) for v in vals]
    res = run.sweep("fig12", st)
    sm = [s for s, _ in res]
    rs, hd, cr = ([s[m]["mean"] for s in sm] for m in ("restores", "held", "crease"))
    verdict = {"claim": "small epsilon restores creases easily, large epsilon keeps them",
               "metric": "total restores; held auxiliary springs and crease at the end",
               "restores_means": rs, "held_means": hd, "crease_means": cr,
               "restores_higher_at_small_eps": rs[0] > rs[1],
               "restores_separated": separated(sm[0]["restores"], sm[1]["restores"]),
               "more_held_at_large_eps": hd[1] > hd[0],
               "more_crease_at_large_eps": cr[1] > cr[0],
               "held": rs[0] > rs[1] and hd[1] > hd[0]}
    run.record("fig12", "epsilon", vals, st, res, verdict)
    run.draw("fig12_epsilon.png",
             f"Fig 12: epsilon (restoration threshold), grid {run.a.grid}, {run.a.frames} "
             f"frames, seed 1 shown, mean ± s.d. over {len(run.seeds)} seeds",
             "epsilon", vals, st, res, "restores", "total restores", [("held", "held", 0)])
    run.done("fig12")


def fig6_varphi(run):
    vals = [1.0, 2.0, 3.0, 4.0, 5.0]
    st = [(f"varphi = {v:g}", ["--varphi", f"{v:g}"]) for v in vals]
    res = run.sweep("fig6", st)
    verdict = {"check": "[Eq 3] unit-square diagonal, unit masses, varphi = 4",
               "m_n": mn_formula(4, [1, 1, 1, 1]), "expected": 2 - math.sqrt(2),
               "m_n_by_varphi": {f"{v:g}": mn_formula(v, [1, 1, 1, 1]) for v in vals},
               "held": abs(mn_formula(4, [1, 1, 1, 1]) - (2 - math.sqrt(2))) < 1e-12,
               "mean_new_vertex_mass_from_sim": None,
               "note": "crumple's outputs carry no per-vertex mass, so the simulated mean "
                       "new-vertex mass is not measured"}
    run.record("fig6", "varphi", vals, st, res, verdict)
    fig6(os.path.join(run.a.out, "fig6_varphi.png"), [s for s, _ in res], vals)
    run.done("fig6")


def diagnostics(run):
    """Not paper claims: what the pictures depend on besides the model's parameters."""
    dseeds = run.seeds[:3]
    st = [(f"substeps {k}", [] if k == 1 else ["--substeps", str(k)]) for k in (1, 2, 4, 8)]
    res = run.sweep("diag_substeps", st, dseeds)
    sm = [s for s, _ in res]
    run.record("diag_substeps", "substeps", [1, 2, 4, 8], st, res,
               {"question": "are the fracture counts converged in the time step?",
                "splits_means": [s["splits"]["mean"] for s in sm],
                "aspect_means": [s["aspect"]["mean"] for s in sm]})
    run.draw("diag_substeps.png",
             f"Diagnostic: time step (h = 1/60 s / substeps), model defaults, grid "
             f"{run.a.grid}, {run.a.frames} frames, {len(dseeds)} seeds",
             "substeps", [1, 2, 4, 8], st, res, "splits", "total splits",
             [("aspect", "aspect", 2), ("wall_s", "wall s", 1)])
    st = [("flat grid", [], 0.0), ("bump 0.01", [], 0.01), ("bump 0.03", [], 0.03),
          ("bump 0.03, substeps 4", ["--substeps", "4"], 0.03)]
    res = run.sweep("diag_flat", st, dseeds)
    sm = [s for s, _ in res]
    run.record("diag_flat", "initial out-of-plane perturbation", [l for l, *_ in st], st,
               res, {"question": "does a flat sheet stay a flat disk in the sphere?",
                     "aspect_means": [s["aspect"]["mean"] for s in sm],
                     "splits_means": [s["splits"]["mean"] for s in sm]})
    run.draw("diag_flat.png",
             f"Diagnostic: flat sheet vs a smooth out-of-plane bump (max |z| in sheet "
             f"widths), model defaults, grid {run.a.grid}, {len(dseeds)} seeds, side view",
             "", [0, 1, 2, 3], st, res, "aspect", "aspect (thickness / width)",
             [("aspect", "aspect", 2), ("rms", "rms", 3)], elev=10.0,
             xticklabels=["flat", "0.01", "0.03", "0.03\nsubst. 4"])
    run.done("diagnostics")


def woody_figure(run):
    a = run.a
    wargs = run.extra if a.woody_args is None else shlex.split(a.woody_args)
    mesh = os.path.join(ROOT, "tests", "data", "woody.obj")
    r, c = woody(a.bin, a.work, a.out, a.frames, mesh, wargs, 5, a.quick)
    run.claims["woody"] = {"args": wargs, "ok": r.get("ok"), "frames_run": r.get("frames_run"),
                           "splits": r.get("splits"), "restores": r.get("restores"),
                           "vertices": r.get("vertices"), "crease": c["crease_norm"],
                           "rms": c["rms_radius_norm"], "error": r.get("error")}
    run.done("woody")


def hero_figure(run):
    a = run.a
    hargs = shlex.split(a.hero_args)
    grid = 32 if a.quick else a.hero_grid
    r, o = hero(a.bin, a.work, a.out, grid, a.frames, hargs, a.hero_frame, a.hero_perturb)
    run.claims["hero"] = {"args": hargs, "grid": grid, "perturb": a.hero_perturb,
                          "ok": r.get("ok"), "frames_run": r.get("frames_run"),
                          "shown": os.path.basename(o), "splits": r.get("splits"),
                          "vertices": r.get("vertices"), "error": r.get("error")}
    run.done("hero")


FIGURES = {"fig10": fig10_phi, "fig11": fig11_psi, "fig12": fig12_epsilon, "fig6": fig6_varphi,
           "diag": diagnostics, "woody": woody_figure, "hero": hero_figure}


def save_claims(run, only):
    """claims.json (merged into the existing one when only some figures ran) and README.md."""
    claims = run.claims
    claims["config"]["runtime_s"] = round(time.time() - run.t_start, 1)
    path = os.path.join(run.a.out, "claims.json")
    if os.path.exists(path) and only != set(ALL_FIGURES):
        with open(path) as fh:
            old = json.load(fh)
        old.update(claims)
        claims = old
    with open(path, "w") as fh:
        json.dump(claims, fh, indent=1)
    write_readme(os.path.join(run.a.out, "README.md"), claims)


def main(argv=None):
    a = parse_args(argv)
    only = set(a.only.split(","))
    os.makedirs(a.out, exist_ok=True)
    os.makedirs(a.work, exist_ok=True)
    run = Run(a)
    for name in ALL_FIGURES:
        if name in only:
            FIGURES[name](run)
    save_claims(run, only)
    print(f"figures: done in {time.time() - run.t_start:.0f} s -> {a.out}", file=sys.stderr)


def git_describe():
    try:
        h = subprocess.run(["git", "-C", ROOT, "rev-parse", "--short", "HEAD"],
                           capture_output=True, text=True).stdout.strip()
        dirty = subprocess.run(["git", "-C", ROOT, "status", "--porcelain", "core", "app"],
                               capture_output=True, text=True).stdout.strip()
        return h + ("+uncommitted core/app changes" if dirty else "")
    except OSError:
        return "unknown"


def _row(s, keys):
    return " | ".join(fmt(s, k, 3 if k in ("rebreak_frac", "rms") else
                          (2 if k == "aspect" else
                           (1 if k in ("crease", "late_rate", "wall_s") else 0))) for k in keys)


def _table(c, name, pname, keys, heads):
    """One sweep's settings as a markdown table: mean ± s.d. of each key, runs stopped early."""
    t = [f"| {pname} | " + " | ".join(heads) + " | stopped early |",
         "|---" * (len(heads) + 2) + "|"]
    for st in c[name]["settings"]:
        s = st["summary"]
        val = st["value"] if isinstance(st["value"], str) else f"{st['value']:g}"
        t.append(f"| {val} | {_row(s, keys)} | "
                 f"{s['n'] - s['n_ok']}/{s['n']}"
                 + (f" (frames {s['failed_at']})" if s['failed_at'] else "") + " |")
    return t


def _held(b):
    return "**held**" if b else "**did not hold**"


def _readme_header(c):
    cfg = c["config"]
    return ["# Figures: the paper's parameter claims, measured", "",
            "Generated by `scripts/figures.sh` (which runs `scripts/figures.py`); every number "
            "below comes from `claims.json` of the same run, so rerun rather than edit.", "",
            "Reproduce: `scripts/figures.sh` (builds `build-fig`, then about 35 s on 2 cores; "
            "`--quick` is a 2-seed, 120-frame pass written to `build-fig/figwork/quick-figures/`; "
            "`--sim-args \"...\"` adds crumple options to every sweep run; "
            "`/usr/bin/python3 scripts/figures.py --help` lists the rest).", "",
            f"- binary: `{os.path.relpath(cfg['binary'], ROOT) if cfg['binary'].startswith(ROOT) else cfg['binary']}` "
            f"at git {cfg['git']}, {cfg['date']}",
            f"- scene: sphere crumple of a {cfg['grid']}x{cfg['grid']} grid"
            + (f" perturbed out of plane by max |z| = {cfg['perturb']:g}" if cfg.get("perturb") else "")
            + f", {cfg['frames']} frames "
            f"of 1/60 s, seeds {cfg['seeds']}, extra options: `{' '.join(cfg['sim_args']) or '(none: defaults)'}`",
            f"- runtime: {cfg.get('runtime_s', '?')} s",
            "- numbers: mean ± s.d. over the seeds; a run that stopped early (unstable) is "
            "excluded from the means when any run of the setting completed.",
            "- crease = total length of edges with dihedral angle > 30° divided by sqrt(initial "
            "area) (sheet-widths of crease; `scripts/crease.py` says why); rms = RMS vertex "
            "distance from the centroid / sqrt(initial area) (flat unit square: 0.408).", ""]


def _readme_fig10(c):
    v = c["fig10"]["verdict"]
    return (["## Fig 10 — smaller phi breaks more (`fig10_phi.png`, psi = 0.25)", ""]
            + _table(c, "fig10", "phi", ["splits", "restores", "vertices", "crease", "rms", "aspect"],
                     ["splits", "restores", "vertices", "crease", "rms", "aspect"])
            + ["", f"Verdict: {_held(v['held'])}. Total splits by phi: "
               + ", ".join(f"{m:.0f}" for m in v["means"])
               + f" (trend: {v['trend']}; phi = 0 vs 1 seed ranges "
               + ("disjoint" if v["phi0_vs_phi1_separated"] else "overlap") + ").", ""])


def _readme_fig11(c):
    v = c["fig11"]["verdict"]
    L = ["## Fig 11 — smaller psi makes broken edges break again (`fig11_psi.png`, "
         "phi = 0.25)", "",
         "Measured: *re-breaks*, the held auxiliary springs (broken edges, `l` lines of the "
         "final OBJ) whose edge was itself made by an earlier split (it has an endpoint "
         "created by a split: index >= the initial vertex count), and their share of all "
         "held springs (re-brk %); also *late/frm*, splits per frame over the last third "
         "of the run (after the first crumple), and total splits.", ""]
    L += _table(c, "fig11", "psi", ["splits", "restores", "rebreaks", "rebreak_frac",
                                    "late_rate", "crease"],
                ["splits", "restores", "re-breaks", "re-brk share", "late/frame", "crease"])
    L += ["", f"Verdict: {_held(v['held'])} on the re-broken share (trend "
          f"{v['trend_rebreak_frac']}: "
          + ", ".join(f"{m:.3f}" for m in v["rebreak_frac_means"])
          + "; psi = 0 vs 1 seed ranges "
          + ("disjoint" if v["psi0_vs_psi1_separated"] else "overlap")
          + f"). Re-break count trend {v['trend_rebreaks']}, late split rate trend "
          f"{v['trend_late_rate']}, total splits trend {v['trend_splits']} "
          "('monotonic' = decreasing as psi grows, as the claim predicts; 'ends' = "
          "psi = 0 above psi = 1 but not monotonic).", ""]
    return L


def _readme_fig12(c):
    v = c["fig12"]["verdict"]
    return (["## Fig 12 — small epsilon restores easily (`fig12_epsilon.png`)", ""]
            + _table(c, "fig12", "epsilon", ["splits", "restores", "held", "vertices", "crease"],
                     ["splits", "restores", "held springs", "vertices", "crease"])
            + ["", f"Verdict: {_held(v['held'])}. Restores at epsilon 0.1 vs 0.9: "
               f"{v['restores_means'][0]:.0f} vs {v['restores_means'][1]:.0f} ("
               + ("seed ranges disjoint" if v["restores_separated"] else "seed ranges overlap")
               + f"); broken edges still held at the end: {v['held_means'][0]:.0f} vs "
               f"{v['held_means'][1]:.0f}; crease {v['crease_means'][0]:.1f} vs "
               f"{v['crease_means'][1]:.1f}.", ""])


def _readme_fig6(c):
    v = c["fig6"]["verdict"]
    return (["## Fig 6 — mass of a new vertex (`fig6_varphi.png`)", "",
             "Computed from [Eq 3] for the diagonal of a unit square of four unit masses "
             "(all delta = 1/4): " + ", ".join(f"varphi {k}: {m:.4f}"
                                                for k, m in v["m_n_by_varphi"].items())
             + f". varphi = 4 gives {v['m_n']:.5f} = 2 - sqrt 2: {_held(v['held'])}. "
             "The simulated mean new-vertex mass is not reported: crumple's outputs carry "
             "no per-vertex mass. The sweep per varphi:", ""]
            + _table(c, "fig6", "varphi", ["splits", "restores", "vertices", "crease"],
                     ["splits", "restores", "vertices", "crease"])
            + [""])


def _readme_diagnostics(c):
    L = ["## Diagnostics, not paper claims (`diag_substeps.png`, `diag_flat.png`)", "",
         "aspect = sqrt(smallest / largest eigenvalue of the vertex covariance): 0 for a "
         "flat sheet, ~0.1-0.3 for a flat disk, ~0.6-1 for a ball.", "",
         "Time step (model defaults):", ""]
    L += _table(c, "diag_substeps", "substeps", ["splits", "restores", "vertices", "crease",
                                                 "aspect", "wall_s"],
                ["splits", "restores", "vertices", "crease", "aspect", "wall s"])
    sp = c["diag_substeps"]["verdict"]["splits_means"]
    L += ["", f"Total splits fall from {sp[0]:.0f} (substeps 1) to {sp[-1]:.0f} "
          f"(substeps 8), {sp[-1] / sp[0]:.2f}x: the fracture counts are "
          + ("not converged in the time step, although P is converted per step with "
             "h / h_ref (MODEL.md section 4); the sweeps above use substeps 1, so their "
             "counts belong to h = 1/60 s." if sp[-1] < 0.8 * sp[0] else
             "roughly converged in the time step.") , "",
          "Flat sheet vs a smooth bump (writes a perturbed grid OBJ and runs --mesh):", ""]
    L += _table(c, "diag_flat", "sheet", ["splits", "restores", "vertices", "crease",
                                          "aspect", "rms"],
                ["splits", "restores", "vertices", "crease", "aspect", "rms"])
    asp = c["diag_flat"]["verdict"]["aspect_means"]
    L += ["", "bump A: max |z| = A sheet widths (a sum of the 9 lowest sine modes, "
          "`perturbed_grid` in figures.py). Final aspect "
          + ", ".join(f"{x:.2f}" for x in asp) + ". "
          + ("A perfectly flat sheet ends as a flat disk (the sphere squeezes it in plane "
             "and fracture absorbs the compression at the scale of single edges; nothing "
             "breaks the symmetry at the sheet's scale); a small bump lets it buckle out "
             "of plane into a ball." if asp[0] < 0.5 * max(asp[1:]) else
             "The flat sheet and the bumped ones end with similar shapes."), ""]
    return L


def _readme_caveats(c):
    src = c["diag_substeps"] if "diag_substeps" in c else c["fig10"]
    s0 = src["settings"][0]["summary"]
    dih = s0.get("mean_dihedral", {}).get("mean", float("nan"))
    return ["## Caveats", "",
            f"- The crease measure counts a rough surface, not only distinct crease lines: at "
            f"the default time step the mean dihedral angle over all interior edges is "
            f"{dih:.0f}° (first row of "
            + ("the time-step diagnostic" if "diag_substeps" in c else "Fig 10")
            + "), so a large share of all edges exceed 30°. Compare settings with it, do not "
            "read it as a count of folds.",
            "- The psi measure is a snapshot of the final OBJ: breaks that were restored left "
            "no spring and are not counted; the effect it shows is modest (see the numbers).",
            "- All sweeps start from a perfectly flat sheet, which the sphere squeezes into a "
            "flat disk (see the aspect column and the diagnostics), not a three-dimensional wad "
            "like real crumpled paper. The claims concern counts, which the pictures only "
            "illustrate.", ""]


def _readme_woody(c):
    w = c["woody"]
    return ["## Woody (`woody_strip.png`, `woody.gif`)", "",
            f"tests/data/woody.obj crumpled in the sphere scene, seed 1, options "
            f"`{' '.join(w['args']) or '(defaults)'}`: "
            + ("completed" if w["ok"] else f"UNSTABLE at frame {w['frames_run']}")
            + f"; {w['splits']} splits, {w['restores']} restores, {w['vertices']} vertices, "
            f"crease {w['crease']:.1f} sheet-widths, rms {w['rms']:.3f}.", ""]


def _readme_hero(c):
    h = c["hero"]
    return ["## Hero (`hero.png`)", "",
            f"{h['grid']}x{h['grid']} grid"
            + (f" with a smooth out-of-plane perturbation of max |z| = {h['perturb']:g} "
               "sheet widths (see Diagnostics: a perfectly flat sheet crumples into a flat disk)"
               if h.get("perturb") else "")
            + f", seed 1, options `{' '.join(h['args']) or '(defaults)'}`, "
            f"showing {h['shown']}; {h['splits']} splits, {h['vertices']} vertices"
            + ("" if h["ok"] else f"; UNSTABLE at frame {h['frames_run']}") + ".", ""]


def write_readme(path, c):
    """README.md of a run, every number from its claims c; a section per figure that ran."""
    L = _readme_header(c)
    for present, section in ((("fig10",), _readme_fig10), (("fig11",), _readme_fig11),
                             (("fig12",), _readme_fig12), (("fig6",), _readme_fig6),
                             (("diag_substeps", "diag_flat"), _readme_diagnostics)):
        if all(k in c for k in present):
            L += section(c)
    if "fig10" in c or "diag_substeps" in c:
        L += _readme_caveats(c)
    for key, section in (("woody", _readme_woody), ("hero", _readme_hero)):
        if key in c:
            L += section(c)
    with open(path, "w") as fh:
        fh.write("\n".join(L) + "\n")

if __name__ == "__main__":
    main()
