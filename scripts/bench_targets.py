"""REPORT.md's section on the fast backend's performance targets (issue 13, docs/PERFORMANCE.md):
each target's numbers in this run, the goal, the floor the roofline sets where it sets one, and
whether the run meets it. scripts/bench_report.py computes the inputs (medians, floors, pair
speed-ups) and calls section(); this module only reads them against the goals, so a report's
verdicts follow from the same numbers its other tables print.

Floors come in two kinds. The frozen step's is a bound: its counted bytes at the best STREAM
bandwidth; where that floor is above the goal, the goal is out of reach on that machine and the
verdict says so rather than "not met". An event's floor is a model (the lines it touches, each
a miss at the random-line rate), which a run with its lines in cache can beat, and the frame's
adds those to its frozen steps' floor: both are shown for scale and never decide a verdict.
"""
import math

BACKEND = "fast"
# Target 1: the frozen step on two threads, at most this many ns a vertex and within this
# multiple of its bandwidth floor, at these N.
FROZEN_NS, FROZEN_X_FLOOR, FROZEN_SIZES, FROZEN_THREADS = 30.0, 2.0, (256, 512), 2
# Target 2: us an event at most, by thread count, at these N.
EVENT_US, EVENT_SIZES = {2: 1.0, 1: 1.5}, (256, 512)
# Target 3: a frame's ns a vertex at these N within this multiple of N = 128's.
LINEAR_X, LINEAR_SIZES = 1.3, (512, 1024)
# Target 4: two threads at least this much faster than one for whole frames from this N on.
PAIR_X, PAIR_MIN_N = 1.8, 256
# Target 5: the paper's frame at this N on two threads, in ms (30 fps; 60 fps the moonshot).
FRAME_N, FRAME_THREADS, FRAME_MS, MOONSHOT_MS = 512, 2, 33.0, 1000.0 / 60


def verdict(met, floor_above_goal=False):
    if met:
        return "met"
    return "out of reach here (floor above the goal)" if floor_above_goal else "not met"


def shown(x, goal, unit="", digits=2):
    """x with `digits` decimals, more where those would print it equal to a goal it misses or
    meets by less (1.304 against 1.3), so that the number and the verdict never seem to disagree;
    repr's shortest exact form past six."""
    for d in range(digits, 7):
        text = f"{x:.{d}f}"
        if x == goal or text != f"{goal:.{d}f}":
            return text + unit
    return repr(x) + unit


def frozen_rows(frozen):
    """frozen: {(backend, threads): {n: (ms, vertices, floor ms or nan)}}: per N the step's ns a
    vertex against the goal (out of reach where the floor itself is above it), then its multiple
    of the floor."""
    rows = []
    for n in FROZEN_SIZES:
        cell = frozen.get((BACKEND, FROZEN_THREADS), {}).get(n)
        if cell is None:
            continue
        ms, vertices, floor_ms = cell
        ns, where = ms * 1e6 / vertices, f"frozen step, {FROZEN_THREADS}t, N = {n}"
        bounded = math.isfinite(floor_ms)
        floor_ns = floor_ms * 1e6 / vertices if bounded else float("nan")
        rows.append(("1", where + ": ns a vertex", shown(ns, FROZEN_NS, digits=1), f"<= {FROZEN_NS:g}",
                     shown(floor_ns, FROZEN_NS, digits=1) if bounded else "-",
                     verdict(ns <= FROZEN_NS, bounded and floor_ns > FROZEN_NS)))
        if bounded:
            x = ms / floor_ms
            rows.append(("1", where + ": its floor's multiple", shown(x, FROZEN_X_FLOOR, "x"),
                         f"<= {FROZEN_X_FLOOR:g}x", "-", verdict(x <= FROZEN_X_FLOOR)))
    return rows


def event_rows(events, frame_minus_frozen):
    """events: {(backend, threads): {n: (us an event, floor us or nan)}} from BM_Events;
    frame_minus_frozen: {(backend, threads): {n: us an event}}."""
    rows = []
    for threads, goal in sorted(EVENT_US.items(), reverse=True):
        for n in EVENT_SIZES:
            cell = events.get((BACKEND, threads), {}).get(n)
            if cell is not None:
                us, floor = cell
                finite = math.isfinite(floor)  # a model, not a bound (the module's comment)
                rows.append(("2", f"`BM_Events`, {threads}t, N = {n}: us an event", shown(us, goal),
                             f"<= {goal:g}", f"{floor:.2f} (model)" if finite else "-", verdict(us <= goal)))
            diff = frame_minus_frozen.get((BACKEND, threads), {}).get(n)
            if diff is not None:
                rows.append(("2", f"frame minus frozen over events, {threads}t, N = {n}: us an event",
                             shown(diff, goal), f"<= {goal:g}", "-", verdict(diff <= goal)))
    return rows


def linear_rows(per_vertex):
    """per_vertex: {(backend, threads): {n: ratio of ns a vertex to N = 128's}}."""
    rows = []
    for threads in (2, 1):
        for n in LINEAR_SIZES:
            ratio = per_vertex.get((BACKEND, threads), {}).get(n)
            if ratio is not None:
                rows.append(("3", f"frame ns a vertex, {threads}t, N = {n} against 128", shown(ratio, LINEAR_X, "x"),
                             f"<= {LINEAR_X:g}x", "-", verdict(ratio <= LINEAR_X)))
    return rows


def pair_rows(pairs):
    """pairs: {n: median speed-up of BM_Pair's two threads over one} for the fast backend."""
    return [("4", f"`BM_Pair` 2t against 1t, N = {n}", shown(x, PAIR_X, "x"), f">= {PAIR_X:g}x", "-",
             verdict(x >= PAIR_X))
            for n, x in sorted(pairs.items()) if n >= PAIR_MIN_N]


def frame_rows(frames):
    """frames: {(backend, threads): {n: (median ms, floor ms or nan)}} from BM_Frame, the floor
    being the frame's frozen steps and its events at their floors (the fracture and restoration
    test and the API's passes left out; a model through the events' floor, so no verdict)."""
    cell = frames.get((BACKEND, FRAME_THREADS), {}).get(FRAME_N)
    if cell is None:
        return []
    ms, floor = cell
    note = "; the 60 fps moonshot met" if ms <= MOONSHOT_MS else ""
    return [("5", f"paper's frame, {FRAME_THREADS}t, N = {FRAME_N}: ms", shown(ms, FRAME_MS, digits=1),
             f"<= {FRAME_MS:g} (moonshot {MOONSHOT_MS:.1f})", f"{floor:.1f} (model)" if math.isfinite(floor) else "-",
             verdict(ms <= FRAME_MS) + note)]


def section(frozen, events, frame_minus_frozen, per_vertex, pairs, frames):
    """The section's lines (none when the run measured none of the targets)."""
    rows = (frozen_rows(frozen) + event_rows(events, frame_minus_frozen) + linear_rows(per_vertex) +
            pair_rows(pairs) + frame_rows(frames))
    if not rows:
        return []
    lines = ["## The performance targets", "",
             f"The `{BACKEND}` backend against the targets of issue 13 (docs/PERFORMANCE.md), from this run (medians; "
             "`BM_Events` as its summed times' ratio, `BM_Pair` as its paired ratios' median; the tables below give "
             "each number's context). The frozen step's floor is a bound, its counted bytes at the best STREAM "
             "bandwidth: above its goal, it puts the goal out of this machine's reach. An event's floor is a model "
             "(its modelled lines, each a miss at the random-line rate), which events whose lines are cached can "
             "beat, and the frame's is its frozen steps and events at those floors without its test and the API's "
             "passes: both are for scale and decide no verdict.", "",
             "| target | measure | this run | goal | floor | verdict |", "|---|---|---:|---|---:|---|"]
    lines += [f"| {t} | {what} | {value} | {goal} | {floor} | {v} |" for t, what, value, goal, floor, v in rows]
    lines.append("")
    return lines
