#!/usr/bin/python3
"""Charts and REPORT.md from a crumple_bench Google Benchmark JSON (scripts/bench.sh runs it).

Usage: bench_report.py FRAME_JSON [--run RUN_JSON] [--out DIR] [--headline PNG]

Reads every repetition of every benchmark (run_type "iteration"; the aggregates Google Benchmark
adds are recomputed here from the repetitions), and writes to DIR (default: the JSON's folder):
  frame_time.png  median frame time against live vertex count, log-log, one line per
                  backend/threads, with the 60 fps (16.7 ms) and 30 fps (33.3 ms) budgets
  speedup.png     speed-up of each step reference -> <backend> 1 thread -> 2 threads ... per N
                  (drawn when at least two crumple configurations exist)
  passes.png      per-pass breakdown, only when BM_Pass/<pass>/<backend>/<threads>/<N> exist
  roofline.png    each pass's achieved GB/s (bytes counted from the layout over its time)
                  against BM_Stream's measured bandwidth, when both exist
  REPORT.md       machine, how it was run, table, largest sheet within 60/30 fps, the fast
                  backend against its performance targets (scripts/bench_targets.py), the charts
--headline also copies frame_time.png there (results/frame_time.png, shown by the README).
"""
import argparse
import json
import math
import os
import re
import shutil
import statistics
import sys

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402

import bench_targets  # noqa: E402  (beside this script)
import machine_info  # noqa: E402

FRAME = re.compile(r"^BM_Frame/(?P<backend>[^/]+)/(?P<threads>\d+)/(?P<n>\d+)(?:/[a-z_]+)?$")
FROZEN = re.compile(r"^BM_Frozen/(?P<backend>[^/]+)/(?P<threads>\d+)/(?P<n>\d+)(?:/[a-z_]+)?$")
FROZEN_FRESH = re.compile(r"^BM_FrozenFresh/(?P<backend>[^/]+)/(?P<threads>\d+)/(?P<n>\d+)(?:/[a-z_]+)?$")
STEPS = re.compile(r"^BM_Steps/(?P<backend>[^/]+)/(?P<threads>\d+)/(?P<n>\d+)(?:/[a-z_]+)?$")
PASS = re.compile(r"^BM_Pass/(?P<pass>[^/]+)/(?P<backend>[^/]+)/(?P<threads>\d+)/(?P<n>\d+)(?:/iterations:\d+)?(?:/[a-z_]+)?$")
STREAM = re.compile(r"^BM_Stream/(?P<kernel>[a-z]+)/(?P<threads>\d+)/(?P<mib>\d+)(?:/[a-z_]+)?$")
FIRST_TOUCH = re.compile(r"^BM_FirstTouch/(?P<pages>[a-z]+)/(?P<mib>\d+)(?:/(?P<threads>\d+))?"
                         r"(?:/iterations:\d+)?(?:/[a-z_]+)?$")
CORE_TO_CORE = re.compile(r"^BM_CoreToCore/(?P<threads>\d+)/(?P<bytes>\d+)(?:/[a-z_]+)?$")
DEFAULT = re.compile(r"^BM_Default/(?P<backend>[^/]+)/(?P<threads>\d+)/(?P<n>\d+)(?:/[a-z_]+)?$")
PAIR = re.compile(r"^BM_Pair/(?P<backend>[^/]+)/(?P<threads>\d+)/(?P<n>\d+)(?:/[a-z_]+)?$")
EVENTS = re.compile(r"^BM_Events/(?P<backend>[^/]+)/(?P<threads>\d+)/(?P<n>\d+)(?:/iterations:\d+)?(?:/[a-z_]+)?$")
TO_MS = {"ns": 1e-6, "us": 1e-3, "ms": 1.0, "s": 1e3}
BUDGETS = [(60, 1000.0 / 60), (30, 1000.0 / 30)]
PEERS = {"bullet"}  # different methods: charted, never part of the speed-up chain


class Bench:
    """Every repetition of one benchmark."""

    def __init__(self, name):
        self.name = name
        self.times = []     # ms per frame, one per repetition
        self.counters = {}  # counter -> values, one per repetition
        self.errors = []

    def median(self):
        return statistics.median(self.times)

    def quartiles(self):
        if len(self.times) < 2:
            return self.times[0], self.times[0]
        q = statistics.quantiles(self.times, n=4, method="inclusive")
        return q[0], q[2]

    def cv(self):
        """Coefficient of variation in per cent (sample standard deviation / mean)."""
        if len(self.times) < 2:
            return float("nan")
        return 100.0 * statistics.stdev(self.times) / statistics.mean(self.times)

    def values(self, key):
        """The counter's finite values, one per repetition."""
        return [v for v in self.counters.get(key, []) if isinstance(v, (int, float)) and math.isfinite(v)]

    def counter(self, key):
        vals = self.values(key)
        return statistics.median(vals) if vals else float("nan")


def load(path):
    with open(path) as f:
        data = json.load(f)
    benches = {}
    for b in data.get("benchmarks", []):
        if b.get("run_type", "iteration") != "iteration":
            continue
        name = b.get("run_name", b["name"])
        bench = benches.setdefault(name, Bench(name))
        if b.get("error_occurred") or b.get("skipped"):
            bench.errors.append(b.get("error_message") or b.get("skip_message") or "skipped")
            continue
        bench.times.append(b["real_time"] * TO_MS.get(b.get("time_unit", "ns"), 1e-6))
        for k, v in b.items():
            if k not in ("real_time", "cpu_time", "iterations", "repetitions", "repetition_index",
                         "threads", "family_index", "per_family_instance_index") and isinstance(v, (int, float)):
                bench.counters.setdefault(k, []).append(v)
    return data.get("context", {}), benches


def config_key(backend, threads):
    return (backend, int(threads))


def config_label(backend, threads, context):
    t = "thread" if threads == 1 else "threads"
    if backend == "bullet":
        pit = context.get("bullet_piterations", "?")
        return f"Bullet soft body (PBD, piterations={pit}), {threads} {t}"
    return f"{backend}, {threads} {t}"


def order_configs(keys):
    """The speed-up chain's order: reference, then builds without SIMD (labels containing
    "nosimd", e.g. fast-nosimd from a -DCRUMPLE_DISABLE_SIMD=ON build), then the other crumple
    backends by name, peers (Bullet) last; thread counts ascending within a backend."""
    def rank(k):
        backend, threads = k
        group = 3 if backend in PEERS else 0 if backend == "reference" else 1 if "nosimd" in backend else 2
        return (group, backend, threads)
    return sorted(keys, key=rank)


def frame_series(benches, pattern=FRAME):
    """{(backend, threads): {n: Bench}} for the BM_Frame (or other pattern's) benchmarks that
    produced times."""
    series = {}
    for name, b in benches.items():
        m = pattern.match(name)
        if m and b.times:
            series.setdefault(config_key(m["backend"], m["threads"]), {})[int(m["n"])] = b
    return series


def fmt_ms(ms):
    return f"{ms:.3g}" if ms < 100 else f"{ms:.0f}"


def chart_frame_time(series, context, machine, path):
    fig, ax = plt.subplots(figsize=(9, 6))
    styles = {}
    markers = "osD^v<>p*h"
    annotated = None
    for i, key in enumerate(order_configs(series)):
        backend, threads = key
        pts = sorted(series[key].items())
        xs = [b.counter("vertices") if math.isfinite(b.counter("vertices")) else n * n for n, b in pts]
        ys = [b.median() for _, b in pts]
        lo = [y - b.quartiles()[0] for (_, b), y in zip(pts, ys)]
        hi = [b.quartiles()[1] - y for (_, b), y in zip(pts, ys)]
        peer = backend in PEERS
        line = ax.errorbar(xs, ys, yerr=[lo, hi], marker=markers[i % len(markers)], markersize=5,
                           capsize=3, linestyle="--" if peer else "-", linewidth=1.6,
                           label=config_label(backend, threads, context))
        styles[key] = line
        if annotated is None or len(pts) > len(series[annotated]):
            annotated = key
    if annotated is not None:  # mark the sizes once, at the configuration with most points
        for n, b in sorted(series[annotated].items()):
            v = b.counter("vertices")
            ax.annotate(f"N={n}", (v if math.isfinite(v) else n * n, 0.015), xycoords=("data", "axes fraction"),
                        ha="center", fontsize=7, color="0.35")
            ax.axvline(v if math.isfinite(v) else n * n, color="0.85", linewidth=0.8, zorder=0)
    for (fps, ms), style in zip(BUDGETS, [":", "-."]):
        ax.axhline(ms, color="0.3", linestyle=style, linewidth=1.2, label=f"{fps} fps budget ({ms:.1f} ms)")
    ax.set_xscale("log")
    ax.set_yscale("log")
    ax.set_xlabel("live vertices at the timed frames (crumple: N x N grid plus split vertices; Bullet: N x N)")
    ax.set_ylabel("time per 1/60 s frame [ms]  (median; bars: quartiles)")
    ax.set_title(f"crumple: one frame of the sphere crumple\n{machine}", fontsize=11)
    ax.grid(True, which="major", alpha=0.35)
    ax.grid(True, which="minor", alpha=0.12)
    ax.legend(fontsize=8, loc="upper left")
    fig.tight_layout()
    fig.savefig(path, dpi=130)
    plt.close(fig)


def speedup_chain(series):
    """reference/1, then each other crumple backend's thread counts ascending."""
    keys = [k for k in order_configs(series) if k[0] not in PEERS]
    return keys if len(keys) >= 2 else []


def speedup_steps(series):
    chain = speedup_chain(series)
    steps = list(zip(chain, chain[1:]))
    if len(chain) > 2:
        steps.append((chain[0], chain[-1]))  # the whole way
    sizes = sorted(set().union(*(series[k].keys() for k in chain))) if chain else []
    table = []  # (step, n, speed-up)
    for a, b in steps:
        for n in sizes:
            if n in series[a] and n in series[b]:
                table.append(((a, b), n, series[a][n].median() / series[b][n].median()))
    return chain, steps, sizes, table


def short(key):
    backend, threads = key
    return f"{backend} {threads}t"


def chart_speedup(series, machine, path):
    chain, steps, sizes, table = speedup_steps(series)
    if not table:
        return False
    fig, ax = plt.subplots(figsize=(9, 5))
    width = 0.8 / len(steps)
    for i, step in enumerate(steps):
        vals = {n: s for (st, n, s) in table if st == step}
        xs = [j + (i - (len(steps) - 1) / 2) * width for j, n in enumerate(sizes) if n in vals]
        ys = [vals[n] for n in sizes if n in vals]
        whole = len(chain) > 2 and i == len(steps) - 1
        bars = ax.bar(xs, ys, width * 0.95, label=f"{short(step[0])} -> {short(step[1])}" + (" (whole way)" if whole else ""),
                      hatch="//" if whole else None, alpha=0.85)
        for bar, y in zip(bars, ys):
            ax.text(bar.get_x() + bar.get_width() / 2, y, f"{y:.2f}x" if y < 10 else f"{y:.0f}x",
                    ha="center", va="bottom", fontsize=7)
    ax.axhline(1.0, color="0.2", linewidth=1)
    ax.set_xticks(range(len(sizes)))
    ax.set_xticklabels([f"N={n}" for n in sizes])
    ax.set_ylabel("speed-up (median frame time before / after)")
    ax.set_title(f"crumple: speed-up of each step, per sheet size\n{machine}", fontsize=11)
    ax.grid(True, axis="y", alpha=0.3)
    ax.legend(fontsize=8)
    fig.tight_layout()
    fig.savefig(path, dpi=130)
    plt.close(fig)
    return True


def pass_series(benches):
    """{(backend, threads): {n: {pass: median ms}}} for BM_Pass benchmarks."""
    out = {}
    for name, b in benches.items():
        m = PASS.match(name)
        if m and b.times:
            out.setdefault(config_key(m["backend"], m["threads"]), {}).setdefault(int(m["n"]), {})[m["pass"]] = b.median()
    return out


def chart_passes(passes, machine, path):
    if not passes:
        return False
    keys = order_configs(passes)
    names = sorted({p for cfg in passes.values() for per_n in cfg.values() for p in per_n})
    fig, axes = plt.subplots(1, len(keys), figsize=(max(6, 4.5 * len(keys)), 5), squeeze=False, sharey=True)
    colors = plt.rcParams["axes.prop_cycle"].by_key()["color"]
    for ax, key in zip(axes[0], keys):
        sizes = sorted(passes[key])
        bottom = [0.0] * len(sizes)
        for i, p in enumerate(names):
            totals = [sum(passes[key][n].values()) for n in sizes]
            share = [100.0 * passes[key][n].get(p, 0.0) / t if t > 0 else 0 for n, t in zip(sizes, totals)]
            ax.bar(range(len(sizes)), share, bottom=bottom, color=colors[i % len(colors)], label=p)
            bottom = [b + s for b, s in zip(bottom, share)]
        for j, n in enumerate(sizes):
            ax.text(j, 101, f"{fmt_ms(sum(passes[key][n].values()))} ms", ha="center", fontsize=7)
        ax.set_xticks(range(len(sizes)))
        ax.set_xticklabels([f"N={n}" for n in sizes], fontsize=8)
        ax.set_title(short(key), fontsize=10)
        ax.set_ylim(0, 108)
    axes[0][0].set_ylabel("share of the summed pass times [%] (total on top)")
    axes[0][-1].legend(fontsize=8, loc="center left", bbox_to_anchor=(1.0, 0.5))
    fig.suptitle(f"crumple: time per pass\n{machine}", fontsize=11)
    fig.tight_layout()
    fig.savefig(path, dpi=130)
    plt.close(fig)
    return True


def stream_bandwidth(benches, spread=False):
    """{threads: {kernel: median GB/s}} from BM_Stream's bytes_per_second; with spread, the
    lowest and highest repetition's instead: {threads: {kernel: (lowest, highest)}}."""
    out = {}
    for name, b in benches.items():
        m = STREAM.match(name)
        vals = b.values("bytes_per_second") if m and b.times else []
        if vals:
            value = (min(vals) / 1e9, max(vals) / 1e9) if spread else statistics.median(vals) / 1e9
            out.setdefault(int(m["threads"]), {})[m["kernel"]] = value
    return out


def stream_table(benches, stream):
    """The STREAM table: each kernel's median GB/s and, where it has several repetitions, their
    range. A machine whose bandwidth changes during the run (a VM's host: docs/PERFORMANCE.md)
    shows it there, and the roof, a median, may then come from its faster minutes."""
    spread = stream_bandwidth(benches, spread=True)
    kernels = sorted({k for per_t in stream.values() for k in per_t})
    lines = ["| threads | " + " | ".join(f"{k} GB/s" for k in kernels) + " |", "|---:|" + "---:|" * len(kernels)]
    ranged = False
    for threads in sorted(stream):
        cells = []
        for k in kernels:
            median = stream[threads].get(k, float("nan"))
            lo, hi = (f"{x:.1f}" for x in spread.get(threads, {}).get(k, (median, median)))
            ranged |= lo != hi
            cells.append(f"{median:.1f}" + (f" ({lo}-{hi})" if lo != hi else ""))
        lines.append(f"| {threads} | " + " | ".join(cells) + " |")
    return lines + [""] + (["In brackets: the lowest and highest repetition.", ""] if ranged else [])


# BM_FirstTouch's kinds of page, in the report's order, and how the report names each.
FIRST_TOUCH_PAGES = [("small", "4 KiB pages"), ("huge", "huge pages"),
                     ("idle", "huge pages of memory left free for 3 s first")]


def first_touch(benches):
    """{(pages, threads): median us a 4 KiB of first touch} from BM_FirstTouch's us_per_4kib
    (a name without a threads part ran on 1 thread)."""
    out = {}
    for name, b in benches.items():
        m = FIRST_TOUCH.match(name)
        if m and b.times:
            out[(m["pages"], int(m["threads"] or 1))] = b.counter("us_per_4kib")
    return out


# Repetitions of BM_CoreToCore further apart than this ratio measured two placements of the CPUs.
PLACEMENT_SPREAD = 1.5


def core_to_core_lines(benches):
    """The report's sentence on how long the two CPUs take to hand a cache line to each other."""
    found = [b for name, b in benches.items() if CORE_TO_CORE.match(name) and b.times]
    if not found:
        return []
    trips = found[0].values("ns_per_round_trip")
    spread = ""
    if trips and min(trips) > 0 and max(trips) > PLACEMENT_SPREAD * min(trips):
        spread = (f" (the median of repetitions from {min(trips):.0f} to {max(trips):.0f} ns: the two CPUs' "
                  "distance changed during the run, as when a VM's host moves its vCPUs between chips)")
    return [f"Two CPUs hand a 64-byte line back and forth in {found[0].counter('ns_per_round_trip'):.0f} ns a "
            f"round trip{spread} (`BM_CoreToCore`, "
            "a counter each of two pinned threads waits for in turn): what a line written by one thread and "
            "read next by the other costs, as the parallel passes do at their blocks' borders and in their "
            "reductions. Cores sharing a last-level cache answer faster than cores on separate ones, whose "
            "caches each hold only their own thread's part of the state.", ""]


def first_touch_lines(benches, stream):
    """The report's sentence on what a first touch of memory costs, against streaming 4 KiB."""
    touch = first_touch(benches)
    if not touch:
        return []
    def cost(pages, label):
        two = f" ({touch[(pages, 2)]:.2f} us on 2 threads)" if (pages, 2) in touch else ""
        return f"{touch[(pages, 1)]:.2f} us a 4 KiB on {label}{two}"

    costs = ", ".join(cost(pages, label) for pages, label in FIRST_TOUCH_PAGES if (pages, 1) in touch)
    copy = 4096 / (roof(stream, 1) * 1e9) * 1e6  # nan without BM_Stream on 1 thread
    against = f" (the best STREAM kernel moves 4 KiB in {copy:.2f} us on 1 thread)" if math.isfinite(copy) else ""
    return [f"First touch of fresh memory (`BM_FirstTouch`, 1 thread unless said, a write a 4 KiB page; the "
            f"kernel maps and zeroes each page on the core that touches it): {costs}{against}. Growth into "
            "memory not used before pays this once a page, which is why the fast backend faults its reserved "
            "room in ahead, on all its threads (docs/DECISIONS.md D16). "
            "Memory that has sat free a while may cost more: a virtual machine's kernel may report free memory "
            "to its host, which discards it, and the next touch faults on the host a 4 KiB at a time.", ""]


# BM_Stream's kernel that reads whole lines at random: the rate of scattered misses, no STREAM kernel.
GATHER = "gather"


def roof(stream, threads):
    """The bandwidth a pass on `threads` threads is set against: the best streaming kernel there."""
    kernels = [gbs for k, gbs in stream.get(threads, {}).items() if k != GATHER]
    return max(kernels) if kernels else float("nan")


def line_rate(stream, threads):
    """GB/s of lines read at random on `threads` threads (BM_Stream/gather), or nan."""
    return stream.get(threads, {}).get(GATHER, float("nan"))


PASS_ORDER = ["normals", "edge_forces", "gather", "integrate", "adapt_test", "topology_apply", "layout"]


def pass_rank(name):
    """A step's order for the fast passes, others after them by name."""
    return (PASS_ORDER.index(name), "") if name in PASS_ORDER else (len(PASS_ORDER), name)


def pass_bytes_rows(benches):
    """(key, n, pass, median ms, bytes) for BM_Pass benchmarks that count their bytes."""
    rows = []
    for name, b in benches.items():
        m = PASS.match(name)
        if m and b.times and math.isfinite(b.counter("bytes")):
            rows.append((config_key(m["backend"], m["threads"]), int(m["n"]), m["pass"], b.median(), b.counter("bytes")))
    keys = order_configs({r[0] for r in rows})
    return sorted(rows, key=lambda r: (keys.index(r[0]), r[1], pass_rank(r[2])))


def chart_roofline(rows, stream, machine, path):
    if not rows or not stream:
        return False
    sizes = sorted({r[1] for r in rows})
    keys = order_configs({r[0] for r in rows})
    passes = sorted({r[2] for r in rows}, key=pass_rank)
    fig, axes = plt.subplots(1, len(sizes), figsize=(max(6, 5.5 * len(sizes)), 5), squeeze=False, sharey=True)
    width = 0.8 / len(keys)
    for ax, n in zip(axes[0], sizes):
        for i, key in enumerate(keys):
            gbs = {p: b / (ms * 1e-3) / 1e9 for k, nn, p, ms, b in rows if k == key and nn == n}
            xs = [j + (i - (len(keys) - 1) / 2) * width for j, p in enumerate(passes) if p in gbs]
            ax.bar(xs, [gbs[p] for p in passes if p in gbs], width * 0.95, label=short(key))
        for threads, style in zip(sorted(stream), ["--", ":", "-."]):
            ax.axhline(roof(stream, threads), color="0.25", linestyle=style, linewidth=1.2,
                       label=f"STREAM best, {threads}t ({roof(stream, threads):.1f} GB/s)")
            if math.isfinite(line_rate(stream, threads)):
                ax.axhline(line_rate(stream, threads), color="tab:red", linestyle=style, linewidth=1.0,
                           label=f"lines at random, {threads}t ({line_rate(stream, threads):.1f} GB/s)")
        ax.set_xticks(range(len(passes)))
        ax.set_xticklabels(passes, rotation=30, ha="right", fontsize=8)
        ax.set_title(f"N={n}", fontsize=10)
        ax.grid(True, axis="y", alpha=0.3)
    axes[0][0].set_ylabel("achieved GB/s (counted bytes / median time)")
    axes[0][-1].legend(fontsize=8)
    fig.suptitle(f"crumple: each pass against the measured memory bandwidth\n{machine}", fontsize=11)
    fig.tight_layout()
    fig.savefig(path, dpi=130)
    plt.close(fig)
    return True


def roofline_section(benches, charts):
    stream = stream_bandwidth(benches)
    rows = pass_bytes_rows(benches)
    frozen = [(k, n, b) for k, per_n in frame_series(benches, FROZEN).items() for n, b in per_n.items()
              if math.isfinite(b.counter("bytes"))]
    if not stream and not rows and not frozen:
        return []
    lines = ["## Roofline: the passes against the memory bandwidth", "",
             "`BM_Stream/<kernel>/<threads>/<MiB>` runs a kernel over arrays of doubles of <MiB> each, four times "
             "the L3 the machine reports rounded up to a multiple of 128 MiB (128 MiB where none is reported; the "
             "three arrays within a quarter of the memory): read "
             "(a sum), copy, triad (a = b + q c), with bytes as STREAM counts them (no write-allocate read), and "
             "gather (one double from each line, the lines in random order: whole lines counted). Each fast pass's "
             "bytes are counted from the layout (`bench/bytes_moved.cpp`: every array it reads or writes, element "
             "count times element size, data read through indices once per distinct element, adjacency rows at "
             "their full stride; topology_apply adds 64 bytes per line of the rows each event touches), so "
             "bytes / time is the bandwidth the pass achieves. It is set against the best STREAM kernel on the "
             "same thread count: a pass near it is memory-bound at its layout's traffic, one far below it is bound "
             "by something else (latency of scattered reads, compute, serial work).", ""]
    if stream:
        lines += stream_table(benches, stream)
    lines += first_touch_lines(benches, stream)
    lines += core_to_core_lines(benches)
    if "roofline.png" in charts:
        lines += ["![each pass against the measured bandwidth](roofline.png)", ""]
    if rows:
        lines += ["| configuration | N | pass | MB moved | median ms | GB/s | of STREAM |", "|---|---:|---|---:|---:|---:|---:|"]
        for key, n, p, ms, b in rows:
            gbs = b / (ms * 1e-3) / 1e9
            share = 100.0 * gbs / roof(stream, key[1])
            lines.append(f"| {short(key)} | {n} | {p} | {b / 1e6:.1f} | {fmt_ms(ms)} | {gbs:.1f} | "
                         f"{f'{share:.0f} %' if math.isfinite(share) else '-'} |")
        lines.append("")
    if frozen:
        lines += frozen_floor_table(frozen, frame_series(benches, FROZEN_FRESH), stream)
    return lines


# The size whose frozen step sets the in-cache rate the larger sizes' are read against.
CACHED_N = 128


def frozen_floor_ms(b, stream, threads):
    """The time a frozen benchmark's counted bytes take at the best streaming kernel on its
    thread count (nan without BM_Stream there)."""
    return b.counter("bytes") / (roof(stream, threads) * 1e9) * 1e3


def frozen_floor_table(frozen, fresh, stream):
    """The frozen step against its bandwidth floor, as prepared and (BM_FrozenFresh, where
    measured) just after a relayout."""
    with_fresh = any(fresh.values())
    lines = ["The frozen step (`BM_Frozen`: normals, edge_forces, gather, integrate on the prepared mesh) against "
             "its bandwidth floor, the time its counted bytes take at the best STREAM bandwidth on its thread count" +
             (("; `BM_FrozenFresh` times the same frames after one relayout of the prepared state, whose vertices "
               "are a fifth new since its last relayout and stored at the arrays' ends: the two bracket the step as "
               "the layout ages between relayouts") if with_fresh else "") + ". `x N = " + str(CACHED_N) + "`: the ns "
             "per vertex against the same configuration's at N = " + str(CACHED_N) + ", the smallest sheet here, whose "
             "state (~10 MB) a server core's L3 can hold: a step that costs about as much a vertex at every size "
             "is bound by its kernels' work and latency chains, not by the memory, however far above its floor:", "",
             "| configuration | N | vertices | frozen ms | MB moved | floor ms | frozen / floor | GB/s | ns per vertex | "
             "x N = " + str(CACHED_N) + " |" + (" fresh layout ms | fresh / floor |" if with_fresh else ""),
             "|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|" + ("---:|---:|" if with_fresh else "")]
    keys = order_configs({r[0] for r in frozen})
    ns_cached = {key: b.median() * 1e6 / b.counter("vertices") for key, n, b in frozen if n == CACHED_N}
    for key, n, b in sorted(frozen, key=lambda r: (keys.index(r[0]), r[1])):
        ms, by, v = b.median(), b.counter("bytes"), b.counter("vertices")
        floor = frozen_floor_ms(b, stream, key[1])
        bound = (f"{floor:.3g} | {ms / floor:.1f}x") if math.isfinite(floor) else "- | -"
        ns = ms * 1e6 / v
        cached = f"{ns / ns_cached[key]:.2f}x" if key in ns_cached else "-"
        row = (f"| {short(key)} | {n} | {v:,.0f} | {fmt_ms(ms)} | {by / 1e6:.1f} | {bound} | "
               f"{by / (ms * 1e-3) / 1e9:.1f} | {ns:.0f} | {cached} |")
        if with_fresh:
            f = fresh.get(key, {}).get(n)
            if f is None:
                row += " - | - |"
            else:
                row += f" {fmt_ms(f.median())} | " + (f"{f.median() / floor:.1f}x |" if math.isfinite(floor) else "- |")
        lines.append(row)
    lines.append("")
    return lines


def default_section(series, paper):
    """BM_Default beside BM_Frame: what the converging default (D28) costs against the paper's step."""
    if not series:
        return []
    lines = ["## The default configuration against the paper's", "",
             "`BM_Default/<backend>/<threads>/<N>` times one `Sheet::step` frame of the command's default "
             "configuration (docs/DECISIONS.md D28: symplectic Euler with the viscosity, substeps chosen per frame, "
             "fracture and restoration every 1/240 s of simulated time) from its own prepared state, as `BM_Frame` does for the paper's. Medians; "
             "events per frame from the counters.", "",
             "| configuration | N | default ms/frame | splits / restores per frame | paper ms/frame | "
             "splits / restores per frame | default / paper |", "|---|---:|---:|---:|---:|---:|---:|"]
    for key in order_configs(series):
        for n, b in sorted(series[key].items()):
            p = paper.get(key, {}).get(n)
            pt = (f"{fmt_ms(p.median())} | {p.counter('splits'):,.0f} / {p.counter('restores'):,.0f} | "
                  f"{b.median() / p.median():.1f}x") if p and p.times else "- | - | -"
            lines.append(f"| {short(key)} | {n} | {fmt_ms(b.median())} | {b.counter('splits'):,.0f} / "
                         f"{b.counter('restores'):,.0f} | {pt} |")
    lines.append("")
    return lines


def event_floor_us(b, stream, threads):
    """The time an event's modelled lines (counter event_bytes) take at the random-line rate."""
    return b.counter("event_bytes") / (line_rate(stream, threads) * 1e9) * 1e6


def events_section(benches):
    rows = []
    for name, b in benches.items():
        m = EVENTS.match(name)
        if m and b.times:
            rows.append((config_key(m["backend"], m["threads"]), int(m["n"]), b))
    if not rows:
        return []
    stream = stream_bandwidth(benches)
    lines = ["## Events applied as a batch", "",
             "`BM_Events/<backend>/<threads>/<N>` applies the splits and restores of one recorded step of the "
             "prepared state (the adapt pass minus its test alone on a twin of the same state, bench/bench_events.cpp), "
             "per event; no relayout. Median over repetitions of the per-iteration time, and the ratio of the summed "
             "times (`us_per_event`). Where the layout is modelled (the fast backend), the lines one event touches "
             "(`bench/bytes_moved.cpp`, every line of the rows of its five vertices, five edges, four triangles "
             "and record) set against the rate at which the machine serves lines at random on the same thread "
             "count (`BM_Stream/gather`) give the event's floor: the time its lines take if each one misses.", "",
             "| configuration | N | splits | restores | us per event (median) | us per event (sums) | lines | "
             "floor us | event / floor |",
             "|---|---:|---:|---:|---:|---:|---:|---:|---:|"]
    keys = order_configs({r[0] for r in rows})
    for key, n, b in sorted(rows, key=lambda r: (keys.index(r[0]), r[1])):
        other = " (**iterations applied another batch**)" if any(v > 0 for v in b.counters.get("mismatch", [])) else ""
        floor = event_floor_us(b, stream, key[1])
        bound = (f"{b.counter('event_bytes') / 64:.0f} | {floor:.2f} | {b.counter('us_per_event') / floor:.1f}x"
                 if math.isfinite(floor) else "- | - | -")
        lines.append(f"| {short(key)} | {n} | {b.counter('splits'):,.0f} | {b.counter('restores'):,.0f} | "
                     f"{1000.0 * b.median():.2f} | {b.counter('us_per_event'):.2f}{other} | {bound} |")
    lines.append("")
    return lines


def pair_group(b, reps):
    """(1-thread ms, 2-thread ms, speed-up, lowest, highest, repetitions) over the repetitions
    `reps` (indices) of one BM_Pair benchmark, or None when none of them has a speed-up."""
    c = b.counters  # BM_Pair sets ms_1t, ms_2t and speedup in every repetition
    reps = [i for i in reps if math.isfinite(c["speedup"][i]) and c["speedup"][i] > 0]
    if not reps:
        return None
    ratios = [c["speedup"][i] for i in reps]
    return (statistics.median(c["ms_1t"][i] for i in reps), statistics.median(c["ms_2t"][i] for i in reps),
            statistics.median(ratios), min(ratios), max(ratios), len(reps))


def pair_placements(b):
    """[(placement, repetition indices, median round trip ns)] of one BM_Pair benchmark: one
    group of every repetition, named "near" or "far" when all share a placement, "all" followed
    by a group per placement when they do not; [(None, all, nan)] for a run without the
    placement counters (BM_Pair before they existed, or CPUs that could not be pinned)."""
    near = b.counters.get("near_placement", [])
    trips = b.counters.get("round_trip_ns", [])
    every = list(range(len(b.counters.get("speedup", []))))
    if not every:
        return []
    if len(near) != len(every) or len(trips) != len(every):
        return [(None, every, float("nan"))]
    groups = {name: [i for i in every if (near[i] == 1) == (name == "near")] for name in ("near", "far")}
    trip = lambda reps: statistics.median(trips[i] for i in reps)
    if not groups["far"] or not groups["near"]:
        name = "far" if groups["far"] else "near"
        return [(name, every, trip(every))]
    return [("all", every, trip(every))] + [(name, reps, trip(reps)) for name, reps in groups.items()]


def pair_rows(benches):
    """(backend, N, placement, 1-thread ms, 2-thread ms, speed-up, lowest, highest, repetitions,
    round trip ns) per BM_Pair benchmark and placement of its two CPUs (pair_placements). The
    speed-up is the median over repetitions of each repetition's own ratio (its pairs' summed
    1-thread time over their summed 2-thread time: both halves of a pair ran on the machine in
    the same state), not the ratio of the two sides' medians; the times are medians of each
    side's mean frame."""
    rows = []
    for name, b in benches.items():
        m = PAIR.match(name)
        if not m or not b.times:
            continue
        for placement, reps, trip in pair_placements(b):
            group = pair_group(b, reps)
            if group:
                rows.append((m["backend"], int(m["n"]), placement) + group + (trip,))
    order = {None: 0, "all": 0, "near": 1, "far": 2}
    return sorted(rows, key=lambda r: (r[0], r[1], order[r[2]]))


def pair_section(benches, context):
    rows = pair_rows(benches)
    if not rows:
        return []
    placed = any(r[2] is not None for r in rows)
    lines = ["## Two threads against one, in pairs", "",
             "`BM_Pair/<backend>/2/<N>` runs `BM_Frame`'s frames on 1 thread and on 2 back to back in every "
             "iteration (which side goes first alternates), so that the two halves of a pair meet the same "
             "neighbours on a shared machine; each repetition's speed-up is its pairs' summed 1-thread time over "
             "their summed 2-thread time, and the table gives the median over repetitions with the lowest and "
             "highest (the speed-up table above divides medians of separately interleaved benchmarks instead). "
             "Times: medians of each side's mean frame."]
    head = "| configuration | N | 1 thread ms | 2 threads ms | speed-up (median) | lowest | highest | reps |"
    rule = "|---|---:|---:|---:|---:|---:|---:|---:|"
    if placed:
        near_ns = context.get("crumple_near_round_trip_ns", "?")  # bench/core_to_core.h, kNearRoundTripNs
        lines[-1] += (" Before each pair the first two CPUs' round trip is sampled (as `BM_CoreToCore` does); a "
                      f"repetition whose median is below {near_ns} ns ran with the two CPUs near "
                      "each other (sharing a last-level cache), above it far apart. When a run saw both, the "
                      "rows after \"all\" give each placement's repetitions.")
        head = head.replace("| N |", "| N | placement | round trip ns |")
        rule = rule.replace("|---:|", "|---:|---|---:|", 1)
    lines += ["", head, rule]
    for backend, n, placement, ms1, ms2, med, lo, hi, reps, trip in rows:
        where = f" {placement} | {trip:.0f} |" if placed else ""
        lines.append(f"| {backend} 2t against 1t | {n} |{where} {fmt_ms(ms1)} | {fmt_ms(ms2)} | {med:.2f}x | "
                     f"{lo:.2f}x | {hi:.2f}x | {reps} |")
    lines.append("")
    return lines


def largest_within(series_for_config, budget_ms):
    fits = [(n, b) for n, b in series_for_config.items() if b.median() <= budget_ms]
    if not fits:
        return None
    return max(fits, key=lambda nb: nb[0])


def event_cost_series(benches, series):
    """The frames the frozen ones are subtracted from: BM_Steps (bare steps), or BM_Frame in runs
    from before BM_Steps existed."""
    return frame_series(benches, STEPS) or series


def event_cost_rows(series, frozen):
    """(key, n, frame ms, frozen ms, events per frame, frozen run had events) where both were
    measured."""
    rows = []
    for key in order_configs(frozen):
        for n, fz in sorted(frozen[key].items()):
            fr = series.get(key, {}).get(n)
            if fr is None:
                continue
            events = fr.counter("splits") + fr.counter("restores")
            thawed = any(v > 0 for v in fz.counters.get("mismatch", []))  # in any repetition
            rows.append((key, n, fr.median(), fz.median(), events, thawed))
    return rows


def event_cost_section(series, frozen):
    rows = event_cost_rows(series, frozen)
    if not rows:
        return []
    lines = ["## What the events cost", "",
             "`BM_Frozen/<backend>/<threads>/<N>` times the frames of `BM_Steps` (those of `BM_Frame` as the backend's "
             "bare steps, without the API's render buffers and totals; runs from before `BM_Steps` existed compare "
             "`BM_Frame`, which then timed bare steps) from the same prepared state with "
             "fracture and restoration switched off: the physics alone on a frozen topology. The difference is what "
             "the events cost per frame (fracture and restoration tests, splits, restores and, in the fast backend, "
             "the relayouts they trigger), and per event once divided by the splits + restores of a frame. Medians of "
             "each; the difference of two noisy medians is itself noisy. The frozen frames keep the prepared mesh, which "
             "the adaptive frames grow (at N = 256 by ~1,300 vertices a frame, ~1 %), so the difference also charges the "
             "events with the physics of the elements they add (a few per cent of it).", "",
             "| configuration | N | frame ms | frozen ms | events share | events/frame | us per event |",
             "|---|---:|---:|---:|---:|---:|---:|"]
    for key, n, frame, frz, events, thawed in rows:
        cost = frame - frz
        per = f"{1000.0 * cost / events:.2f}" if math.isfinite(events) and events > 0 else "-"
        if thawed:  # the frozen run had events: set_adaptivity did not hold, the row means nothing
            per += " (**the frozen run had events**)"
        lines.append(f"| {key[0]} {key[1]}t | {n} | {fmt_ms(frame)} | {fmt_ms(frz)} | {100.0 * cost / frame:.0f} % | "
                     f"{events:,.0f} | {per} |")
    lines.append("")
    return lines


def fmt_load(values):
    """A load-average triple as the report prints it ('?' when unknown)."""
    return ", ".join(f"{x:.2f}" for x in values) or "?"


def cpu_line(m, context):
    """The CPU as run.json's machine records it: model (with its core generation and family
    where recorded: a VM may name CPUs of two generations alike), CPUs, caches, clock."""
    model = m.get("model", "unknown CPU")
    if m.get("microarchitecture"):
        arch = machine_info.GENERATION_NAMES.get(m["microarchitecture"], m["microarchitecture"])
        model += f" ({arch}, family {m.get('family')} model {m.get('model_number')})"
    hv = f", {m['hypervisor']} guest" if m.get("hypervisor") else ""
    caches = (f"L2 {m.get('l2') or '?'}, L3 {m.get('l3') or '?'}" if m.get("l2") or m.get("l3")
              else "caches not reported by lscpu")
    return (f"{model}{hv}; {m.get('cpus', context.get('num_cpus', '?'))} CPUs "
            f"({m.get('cores_per_socket', '?')} cores per socket, {m.get('threads_per_core', '?')} thread(s) per core); "
            f"{caches}; {context.get('mhz_per_cpu', '?')} MHz")


# A sample of the CPUs' time before the build says the machine is busy above this busy share
# (on 2 CPUs, half a core's worth of other work), and names the hypervisor's steal above this.
BUSY_SHARE, STEAL_SHARE = 0.25, 0.05


def load_lines(run, context, cpus):
    """The machine's load before the run, and the verdict whether other work competed with it.
    The load at the benchmark's start includes bench.sh's own build just before it; the load
    average before that build (run.json's load_before_build) still carries work that ended up to
    a minute before; the CPUs' busy share sampled over a few seconds after it
    (cpu_use_before_build, from /proc/stat) tells what competes now, and decides where present."""
    lines = []
    before = run.get("load_before_build", [])
    load = before or context.get("load_avg", [])
    use = run.get("cpu_use_before_build") or {}
    if before:
        lines.append(f"- Load average before bench.sh built the harness {fmt_load(before)} "
                     "(the one at start above includes that build)")
    why = ""
    if "busy" in use:
        lines.append(f"- CPU time before the build, over {use.get('seconds', 0):g} s (/proc/stat): "
                     f"{100 * use['busy']:.1f} % of all CPUs' time busy, {100 * use.get('steal', 0):.1f} % "
                     "stolen by the hypervisor")
        if use["busy"] > BUSY_SHARE:
            why = f"{100 * use['busy']:.1f} % of the {cpus} CPUs' time was busy just before the run's build"
    elif load and load[0] > 0.5 * cpus:
        when = "before the run's build" if before else "when the run started"
        why = f"load average {load[0]:.2f} on {cpus} CPUs {when}"
    if why:
        lines.append(f"- **The machine was busy**: {why}, "
                     "so other work competed for the cores and the timings are noisier (see CV) and slower than on an idle machine")
    if use.get("steal", 0) > STEAL_SHARE:
        lines.append(f"- **The hypervisor took {100 * use['steal']:.1f} % of the CPUs' time** before the run "
                     "(steal): the host's other guests competed for the cores")
    return lines


def machine_section(run, context):
    """The report's machine section: CPU, SIMD, compiler, load, caveats."""
    m = run.get("machine", {})
    lines = []
    lines.append("## Machine")
    lines.append("")
    lines.append(f"- CPU: {cpu_line(m, context)}")
    lines.append(f"- SIMD: **{m.get('simd', '?')}** (flags: {', '.join(m.get('flags', [])) or '?'})")
    lines.append(f"- Compiler: {m.get('compiler', '?')} (binary: {context.get('crumple_compiler', '?')}); "
                 f"build {context.get('crumple_build_type', '?')}, flags `{context.get('crumple_cxx_flags', '?')}`")
    lines.append(f"- Backends built: {context.get('crumple_backends', '?')}; kernel {m.get('kernel', '?')}; "
                 f"load average at start {fmt_load(context.get('load_avg', []))}")
    lines += load_lines(run, context, context.get("num_cpus") or m.get("cpus") or 1)
    if run.get("mode") == "quick":
        lines.append("- **Quick mode** (`--quick`): N <= 256 and few, short repetitions; a smoke test of the harness, "
                     "not numbers to publish")
    if context.get("library_build_type") == "debug":
        lines.append("- Google Benchmark library: Debian's libbenchmark 1.7.1 reports itself as a debug build; "
                     "that concerns the harness's own bookkeeping, not the measured code, which is timed by "
                     "`steady_clock` around the frames (manual time)")
    lines.append("")
    return lines


def how_run_section(run, context):
    """What ran: the command, repetitions, and what BM_Frame and Bullet's frame time."""
    lines = ["## How it was run", ""]
    lines.append(f"- `{run.get('command', 'scripts/bench.sh')}`, which ran:")
    lines.append(f"  `{run.get('benchmark_command', '?')}`")
    lines.append(f"- {run.get('repetitions', '?')} repetitions per benchmark, randomly interleaved across benchmarks, "
                 f"at least {run.get('min_time', '?')} s of timed frames per repetition; "
                 f"{run.get('seconds', '?')} s in all. Medians and CV (sample standard deviation / mean) are over the repetitions.")
    prep = context.get("crumple_prep_fraction_of_sphere_time")
    prep_txt = f"{float(prep):g} x sphere_time" if prep else "the prepared point"
    lines.append(f"- `BM_Frame/<backend>/<threads>/<N>`: one 1/60 s frame of the paper's sphere crumple "
                 f"(`crumple::Params` defaults, `paper_params()`; the command's default configuration is `BM_Default`'s) on an N x N grid as an engine's frame loop runs it: one `Sheet::step` "
                 "call of the embedding API, i.e. the frame's steps plus packing the render buffers and the totals "
                 "pass of the instability check (docs/PERFORMANCE.md gives their share); timed from a state prepared by simulating to "
                 f"{prep_txt}, where edges split and restore every frame. Each iteration clones the prepared state "
                 "and runs one warm-up frame (both untimed), then times a fixed batch of frames "
                 f"({context.get('crumple_frames_per_iteration', '?')}, as N: frames) with `steady_clock` "
                 "(manual time) and reports their mean: every iteration simulates the same frames. "
                 "vertices/edges: live counts at the timed frames; splits/restores: per timed frame.")
    lines.append(f"- `BM_Frame/bullet/1/<N>`: Bullet {context.get('bullet_version', '')} `btSoftBody` patch over the same grid "
                 "(CreatePatch with gendiags: the structural links plus one diagonal per quad), hanging from two pinned corners "
                 f"under gravity, `stepSimulation(1/60., 1, 1/60.)`, piterations = {context.get('bullet_piterations', '?')}. "
                 "**A different method**: position-based constraint projection, fixed topology, no fracture, no sphere; "
                 "it shows what a common soft-body library costs per frame at the same size, not the same physics.")
    lines.append("")
    return lines


def frame_time_section(series, charts):
    """Every frame benchmark's median, spread, sizes and events."""
    lines = ["## Frame time", ""]
    if "frame_time.png" in charts:
        lines.append("![frame time against vertex count](frame_time.png)")
        lines.append("")
    lines.append("| benchmark | N | median ms | CV % | reps | vertices | edges | splits/frame | restores/frame | fps |")
    lines.append("|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|")
    for key in order_configs(series):
        for n, b in sorted(series[key].items()):
            v, e = b.counter("vertices"), b.counter("edges")
            sp, rs = b.counter("splits"), b.counter("restores")
            med = b.median()
            lines.append(f"| `{key[0]}/{key[1]}/{n}` | {n} | {fmt_ms(med)} | {b.cv():.1f} | {len(b.times)} | "
                         f"{v:,.0f} | {e:,.0f} | {sp:.1f} | {rs:.1f} | {1000.0 / med:,.1f} |")
    lines.append("")
    return lines


def budget_section(series, context):
    """The largest N of each configuration within 60 and 30 fps."""
    lines = ["## Largest sheet within the frame budget", ""]
    lines.append("Largest measured N whose median frame time fits the budget (a real-time loop also needs time to draw).")
    lines.append("")
    lines.append("| configuration | 60 fps (<= 16.7 ms) | 30 fps (<= 33.3 ms) |")
    lines.append("|---|---|---|")
    for key in order_configs(series):
        cells = []
        biggest = max(series[key])
        for fps, ms in BUDGETS:
            best = largest_within(series[key], ms)
            if best is None:
                cells.append(f"none (N={min(series[key])} takes {fmt_ms(series[key][min(series[key])].median())} ms)")
            else:
                n, b = best
                more = " (largest measured)" if n == biggest else ""
                cells.append(f"N={n}{more}: {b.counter('vertices'):,.0f} vertices, {fmt_ms(b.median())} ms")
        lines.append(f"| {config_label(key[0], key[1], context)} | {cells[0]} | {cells[1]} |")
    lines += longest_budget_lines(series, context)
    lines.append("")
    return lines


def longest_budget_lines(series, context):
    """The budget table again by each benchmark's `longest_ms` (the longest single frame of a
    batch), for the configurations that report it; nothing for runs from before the counter."""
    longest = {key: {n: b for n, b in by_n.items() if b.values("longest_ms")} for key, by_n in series.items()}
    longest = {key: by_n for key, by_n in longest.items() if by_n}
    if not longest:
        return []
    lines = ["", "By the longest frame instead: `longest_ms` is the longest single frame of a timed batch (median "
             "over repetitions; in the fast backend the frame that relays its arrays out, when the batch holds one). A "
             "loop that must never miss its budget has to fit this frame, not the median.", "",
             "| configuration | 60 fps (<= 16.7 ms) | 30 fps (<= 33.3 ms) |", "|---|---|---|"]
    for key in order_configs(longest):
        cells = []
        for fps, ms in BUDGETS:
            fits = [n for n, b in longest[key].items() if b.counter("longest_ms") <= ms]
            if not fits:
                n = min(longest[key])
                cells.append(f"none (N={n}: longest {fmt_ms(longest[key][n].counter('longest_ms'))} ms)")
            else:
                b = longest[key][max(fits)]
                cells.append(f"N={max(fits)}: longest {fmt_ms(b.counter('longest_ms'))} ms, median {fmt_ms(b.median())} ms")
        lines.append(f"| {config_label(key[0], key[1], context)} | {cells[0]} | {cells[1]} |")
    return lines


LINEAR_BASE = 128  # the N whose cost per vertex the others are set against (issue 13's target 3)


def per_vertex_rows(series):
    """[(config, [(n, ns per vertex, ratio to N = LINEAR_BASE or None)])] for every configuration
    with a vertex count: the median frame over the median live vertices."""
    rows = []
    for key in order_configs(series):
        cells = []
        for n, b in sorted(series[key].items()):
            v = b.counter("vertices")
            if v > 0:
                cells.append((n, b.median() * 1e6 / v))
        base = dict(cells).get(LINEAR_BASE)
        rows.append((key, [(n, ns, ns / base if base else None) for n, ns in cells]))
    return [(k, c) for k, c in rows if c]


def per_vertex_section(series, context):
    """Cost per vertex against N: constant if a frame's cost were linear in the sheet's size."""
    rows = per_vertex_rows(series)
    if not rows:
        return []
    sizes = sorted({n for _, cells in rows for n, _, _ in cells})
    lines = ["## Cost per vertex", ""]
    lines.append(f"Median frame time over the frame's live vertices, in ns, and in brackets against N = {LINEAR_BASE} "
                 "of the same configuration: a cost linear in the sheet's size keeps the bracket at 1; a larger sheet's "
                 "working set leaves the caches.")
    lines.append("")
    lines.append("| configuration | " + " | ".join(f"N={n}" for n in sizes) + " |")
    lines.append("|---|" + "---:|" * len(sizes))
    for key, cells in rows:
        by_n = {n: (ns, ratio) for n, ns, ratio in cells}
        lines.append(f"| {config_label(key[0], key[1], context)} | " + " | ".join(
            "-" if n not in by_n else f"{by_n[n][0]:,.0f}" + (f" ({by_n[n][1]:.2f}x)" if by_n[n][1] else "")
            for n in sizes) + " |")
    lines.append("")
    return lines


def targets_section(benches, series):
    """The performance targets' section (scripts/bench_targets.py) from this report's numbers."""
    stream, nan = stream_bandwidth(benches), float("nan")
    frozen_series = frame_series(benches, FROZEN)
    frozen = {key: {n: (b.median(), b.counter("vertices"), frozen_floor_ms(b, stream, key[1])) for n, b in by_n.items()}
              for key, by_n in frozen_series.items()}
    events = {key: {n: (b.counter("us_per_event"), event_floor_us(b, stream, key[1])) for n, b in by_n.items()}
              for key, by_n in frame_series(benches, EVENTS).items()}
    minus = {}
    for key, n, frame, frz, count, thawed in event_cost_rows(event_cost_series(benches, series), frozen_series):
        if count > 0 and not thawed:
            minus.setdefault(key, {})[n] = 1000.0 * (frame - frz) / count
    per_vertex = {key: {n: ratio for n, _, ratio in cells if ratio} for key, cells in per_vertex_rows(series)}
    pairs = {}
    for backend, n, _placement, _ms1, _ms2, speedup, *_ in pair_rows(benches):
        if backend == bench_targets.BACKEND:
            pairs.setdefault(n, speedup)  # a benchmark's first row is over all its repetitions
    frames = {}
    for key, by_n in series.items():
        for n, b in by_n.items():
            steps_floor = frozen.get(key, {}).get(n, (nan, nan, nan))[2]
            event_floor = events.get(key, {}).get(n, (nan, nan))[1]
            count = b.counter("splits") + b.counter("restores")
            frames.setdefault(key, {})[n] = (b.median(), steps_floor + count * event_floor * 1e-3)
    return bench_targets.section(frozen, events, minus, per_vertex, pairs, frames)


def speedup_section(series, charts):
    """Each step of the chain reference -> no SIMD -> SIMD -> two threads, per N."""
    chain, steps, sizes, table = speedup_steps(series)
    lines = ["## Speed-up", ""]
    if table:
        if "speedup.png" in charts:
            lines.append("![speed-up per step](speedup.png)")
            lines.append("")
        lines.append("| step | " + " | ".join(f"N={n}" for n in sizes) + " |")
        lines.append("|---|" + "---:|" * len(sizes))
        for step in steps:
            vals = {n: s for (st, n, s) in table if st == step}
            lines.append(f"| {short(step[0])} -> {short(step[1])} | " +
                         " | ".join(f"{vals[n]:.2f}x" if n in vals else "-" for n in sizes) + " |")
    else:
        lines.append("Only one crumple configuration was measured; no speed-up to show.")
    lines.append("")
    return lines


def problems_section(benches):
    """Benchmarks whose iterations did different work, and benchmarks that reported an error."""
    lines = []
    uneven = [name for name, b in benches.items() if FRAME.match(name) and b.counter("mismatch") > 0]
    if uneven:
        lines.append("## Iterations that did different work")
        lines.append("")
        lines.append("These benchmarks had iterations whose splits/restores differed from the dry run of the same frames "
                     "(counter `mismatch`): the backend is not deterministic there, so their iterations are not exactly comparable.")
        lines.append("")
        for name in sorted(uneven):
            lines.append(f"- `{name}`: median {benches[name].counter('mismatch'):.0f} iterations per repetition")
        lines.append("")
    errors = {name: b.errors for name, b in benches.items() if b.errors}
    if errors:
        lines.append("## Benchmarks that reported an error (no time)")
        lines.append("")
        for name, errs in sorted(errors.items()):
            lines.append(f"- `{name}`: {errs[0]} ({len(errs)} of {len(errs) + len(benches[name].times)} repetitions)")
        lines.append("")
    return lines


def report(json_path, run, context, benches, out_dir, charts):
    series = frame_series(benches)
    m = run.get("machine", {})
    title_tag = m.get("tag", os.path.basename(os.path.abspath(out_dir)))
    lines = [f"# crumple benchmark: {m.get('model', 'unknown CPU')} ({title_tag})", ""]
    lines.append(f"Written by `scripts/bench_report.py` from `{os.path.basename(json_path)}` "
                 f"({run.get('mode', '?')} mode, {run.get('date', context.get('date', '?'))}, "
                 f"git `{run.get('git', '?')}`).")
    lines.append("")
    lines += machine_section(run, context)
    lines += how_run_section(run, context)
    lines += frame_time_section(series, charts)
    lines += budget_section(series, context)
    lines += targets_section(benches, series)
    lines += per_vertex_section(series, context)
    lines += speedup_section(series, charts)
    lines += pair_section(benches, context)
    lines += event_cost_section(event_cost_series(benches, series), frame_series(benches, FROZEN))
    lines += events_section(benches)
    lines += default_section(frame_series(benches, DEFAULT), series)
    lines += roofline_section(benches, charts)
    if "passes.png" in charts:
        lines += ["## Time per pass", "", "![per-pass breakdown](passes.png)", ""]
    lines += problems_section(benches)
    return "\n".join(lines)


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("json")
    ap.add_argument("--run", help="run.json written by scripts/bench.sh")
    ap.add_argument("--out", help="output folder (default: the JSON's folder)")
    ap.add_argument("--headline", help="also copy frame_time.png to this path")
    args = ap.parse_args()
    out = args.out or os.path.dirname(os.path.abspath(args.json))
    os.makedirs(out, exist_ok=True)
    run = {}
    if args.run and os.path.exists(args.run):
        with open(args.run) as f:
            run = json.load(f)
    context, benches = load(args.json)
    series = frame_series(benches)
    if not series:
        print(f"bench_report: no BM_Frame benchmark with times in {args.json}", file=sys.stderr)
        return 1
    m = run.get("machine", {})
    machine = f"{m.get('model', context.get('host_name', '?'))}, {m.get('simd', '?')}, {m.get('cpus', context.get('num_cpus', '?'))} cores, {m.get('compiler', context.get('crumple_compiler', ''))}"
    charts = []
    chart_frame_time(series, context, machine, os.path.join(out, "frame_time.png"))
    charts.append("frame_time.png")
    if chart_speedup(series, machine, os.path.join(out, "speedup.png")):
        charts.append("speedup.png")
    if chart_passes(pass_series(benches), machine, os.path.join(out, "passes.png")):
        charts.append("passes.png")
    if chart_roofline(pass_bytes_rows(benches), stream_bandwidth(benches), machine, os.path.join(out, "roofline.png")):
        charts.append("roofline.png")
    text = report(args.json, run, context, benches, out, charts)
    with open(os.path.join(out, "REPORT.md"), "w") as f:
        f.write(text + "\n")
    print(text)
    print(f"\nbench_report: wrote {', '.join(charts + ['REPORT.md'])} to {out}")
    if args.headline:
        os.makedirs(os.path.dirname(os.path.abspath(args.headline)), exist_ok=True)
        shutil.copyfile(os.path.join(out, "frame_time.png"), args.headline)
        print(f"bench_report: copied frame_time.png to {args.headline}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
