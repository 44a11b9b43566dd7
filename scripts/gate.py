#!/usr/bin/python3
"""The performance regression gate's data handling and decision (scripts/gate.sh drives it).

  gate.py merge OUT.json RUN.json...
      Merges several crumple_bench runs of ONE revision (the alternated runs of gate.sh) into one
      Google Benchmark JSON: every repetition of every run (run_type "iteration") under its name,
      plus one "<name>_median" aggregate per benchmark recomputed over all of them (so
      compare.py shows the change of the medians), and "crumple_errors": {name: message} for
      benchmarks that reported an error (SkipWithError) in any run.

  gate.py check COMPARE.json [--base BASE.json --head HEAD.json] [--threshold 5] [--alpha 0.05]
      Reads the --dump_to_json output of Google Benchmark's compare.py (which never fails by
      itself), prints one row per benchmark and exits 1 when the gate fails: some benchmark's
      median frame time is slower by more than --threshold per cent AND the two-sided
      Mann-Whitney U test over the repetitions gives p < --alpha. With --base/--head (merged
      files), a benchmark that ran in the base but reported an error in the head also fails it.

Numbers used: the median change is compare.py's, from the "<name>_median" aggregate rows
(measurements[0].time, i.e. (head - base) / base of the real-time medians); the p-value is
compare.py's utest.time_pvalue (scipy.stats.mannwhitneyu, two-sided, on every repetition's
real time). Only where compare.py gives none (fewer than 2 repetitions on a side, no aggregate
row) does gate.py compute the same quantities itself from the repetitions in the report.
"""
import argparse
import json
import math
import statistics
import sys
from dataclasses import dataclass

AGG_SUFFIXES = ("_mean", "_median", "_stddev", "_cv")


@dataclass
class Verdict:
    name: str
    base_ms: float          # median real time, base (in the benchmark's time unit)
    head_ms: float          # median real time, head
    change_pct: float       # (head - base) / base * 100; positive: head is slower
    pvalue: float           # two-sided U test over the repetitions (nan: not computable)
    reps: tuple             # (base repetitions, head repetitions)
    source: str             # where change/p came from: "compare.py" or "gate.py"
    status: str             # REGRESSION | slower, not significant | faster[, not significant] | same | ERROR
    unit: str = "ms"
    message: str = ""       # ERROR: the head's error message

    @property
    def failed(self):
        return self.status in ("REGRESSION", "ERROR")


# ---------------------------------------------------------------------------------------------
# merge


def merge_runs(runs):
    """One benchmark JSON (dict) from several runs (dicts) of the same binary."""
    merged = {"context": dict(runs[0].get("context", {})) if runs else {}, "benchmarks": []}
    order, reps, errors = [], {}, {}
    for run in runs:
        for b in run.get("benchmarks", []):
            if b.get("run_type", "iteration") != "iteration":
                continue
            name = b["name"]
            if b.get("error_occurred") or b.get("skipped"):
                errors.setdefault(name, b.get("error_message") or b.get("skip_message") or "skipped")
                continue
            if name not in reps:
                order.append(name)
                reps[name] = []
            reps[name].append(b)
    for name in order:
        rows = reps[name]
        for i, b in enumerate(rows):
            b = dict(b)
            b["repetition_index"] = i
            b["repetitions"] = len(rows)
            merged["benchmarks"].append(b)
    for name in order:  # aggregates after every repetition, as Google Benchmark writes them
        rows = reps[name]
        agg = {k: v for k, v in rows[0].items() if k not in ("repetition_index",)}
        agg.update({
            "name": name + "_median", "run_name": rows[0].get("run_name", name), "run_type": "aggregate",
            "aggregate_name": "median", "aggregate_unit": "time", "repetitions": len(rows),
            "iterations": len(rows),
            "real_time": statistics.median(r["real_time"] for r in rows),
            "cpu_time": statistics.median(r["cpu_time"] for r in rows),
        })
        merged["benchmarks"].append(agg)
    merged["crumple_errors"] = errors
    merged["context"]["crumple_merged_runs"] = len(runs)
    return merged


# ---------------------------------------------------------------------------------------------
# decision


def _u_test(a, b):
    """Two-sided Mann-Whitney U p-value (scipy), nan when it cannot be computed."""
    if len(a) < 2 or len(b) < 2:
        return float("nan")
    from scipy.stats import mannwhitneyu
    return float(mannwhitneyu(a, b, alternative="two-sided").pvalue)


def evaluate(diff_report, threshold_pct=5.0, alpha=0.05):
    """Verdicts, one per benchmark, from compare.py's --dump_to_json report (a list).

    A benchmark is a REGRESSION when its median is slower by more than threshold_pct per cent
    and the U test says the difference is significant (p < alpha); slower but not significant,
    or within the threshold, passes. Improvements always pass."""
    iters, medians = {}, {}
    for row in diff_report:
        name = row.get("name", "")
        if name == "OVERALL_GEOMEAN":
            continue
        if row.get("run_type") == "aggregate":
            if row.get("aggregate_name") == "median":
                medians[name[: -len("_median")] if name.endswith("_median") else name] = row
            continue
        if name.endswith(AGG_SUFFIXES) and row.get("run_type") is None:
            continue  # an aggregate row of an old report without run_type
        iters[name] = row

    verdicts = []
    for name, row in iters.items():
        ms = row.get("measurements", [])
        base = [m["real_time"] for m in ms]
        head = [m["real_time_other"] for m in ms]
        source = "compare.py"
        med = medians.get(name)
        if med and med.get("measurements"):
            m0 = med["measurements"][0]
            base_med, head_med = m0["real_time"], m0["real_time_other"]
            change = 100.0 * m0["time"]
        else:
            if not base:
                continue
            base_med, head_med = statistics.median(base), statistics.median(head)
            change = 100.0 * (head_med - base_med) / abs(base_med) if base_med else float("nan")
            source = "gate.py"
        ut = row.get("utest") or {}
        p = ut.get("time_pvalue")
        if p is None:
            p = _u_test(base, head)
            source = "gate.py"
        reps = (ut.get("nr_of_repetitions", len(base)), ut.get("nr_of_repetitions_other", len(head)))
        significant = isinstance(p, float) and math.isfinite(p) and p < alpha
        if change > threshold_pct and significant:
            status = "REGRESSION"
        elif change > threshold_pct:
            status = "slower, not significant"
        elif change < -threshold_pct:
            status = "faster" if significant else "faster, not significant"
        else:
            status = "same"
        verdicts.append(Verdict(name, base_med, head_med, change, p, reps, source, status,
                                row.get("time_unit", "ms")))
    return verdicts


def error_verdicts(base_merged, head_merged):
    """Benchmarks that produced times in the base but only errors in the head."""
    base_ok = {b["name"] for b in base_merged.get("benchmarks", []) if b.get("run_type") == "iteration"}
    head_ok = {b["name"] for b in head_merged.get("benchmarks", []) if b.get("run_type") == "iteration"}
    out = []
    for name, msg in sorted(head_merged.get("crumple_errors", {}).items()):
        if name in base_ok and name not in head_ok:
            out.append(Verdict(name, float("nan"), float("nan"), float("nan"), float("nan"), (0, 0),
                               "gate.py", "ERROR", "ms", msg))
    return out


def gate_failed(verdicts):
    return any(v.failed for v in verdicts)


def format_table(verdicts, threshold_pct, alpha):
    w = max([len(v.name) for v in verdicts] + [9])
    lines = [f"{'benchmark':<{w}}  {'base':>10}  {'head':>10}  {'change':>8}  {'p (U)':>7}  {'reps':>7}  verdict",
             "-" * (w + 62)]
    for v in verdicts:
        if v.status == "ERROR":
            lines.append(f"{v.name:<{w}}  {'':>10}  {'':>10}  {'':>8}  {'':>7}  {'':>7}  ERROR in head: "
                         f"{v.message}")
            continue
        p = f"{v.pvalue:.4f}" if math.isfinite(v.pvalue) else "n/a"
        lines.append(f"{v.name:<{w}}  {v.base_ms:>8.4g}{v.unit:>2}  {v.head_ms:>8.4g}{v.unit:>2}  "
                     f"{v.change_pct:>+7.1f}%  {p:>7}  {v.reps[0]:>3}/{v.reps[1]:<3}  {v.status}")
    lines.append("")
    lines.append(f"gate: a benchmark fails when its median is more than {threshold_pct:g}% slower and the "
                 f"Mann-Whitney U test gives p < {alpha:g} (medians and p from "
                 f"{', '.join(sorted({v.source for v in verdicts if v.status != 'ERROR'})) or 'n/a'}).")
    return "\n".join(lines)


# ---------------------------------------------------------------------------------------------


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    sub = ap.add_subparsers(dest="cmd", required=True)
    m = sub.add_parser("merge", help="merge runs of one revision")
    m.add_argument("out")
    m.add_argument("runs", nargs="+")
    c = sub.add_parser("check", help="decide from compare.py's JSON")
    c.add_argument("compare_json")
    c.add_argument("--base")
    c.add_argument("--head")
    c.add_argument("--threshold", type=float, default=5.0, help="per cent (default 5)")
    c.add_argument("--alpha", type=float, default=0.05, help="U-test significance (default 0.05)")
    args = ap.parse_args(argv)

    if args.cmd == "merge":
        runs = []
        for path in args.runs:
            with open(path) as f:
                runs.append(json.load(f))
        with open(args.out, "w") as f:
            json.dump(merge_runs(runs), f, indent=1)
        return 0

    with open(args.compare_json) as f:
        report = json.load(f)
    verdicts = evaluate(report, args.threshold, args.alpha)
    if args.base and args.head:
        with open(args.base) as f:
            base = json.load(f)
        with open(args.head) as f:
            head = json.load(f)
        verdicts += error_verdicts(base, head)
    if not verdicts:
        print("gate: no benchmark in common between base and head: nothing compared", file=sys.stderr)
        return 2
    print(format_table(verdicts, args.threshold, args.alpha))
    failed = [v.name for v in verdicts if v.failed]
    if failed:
        print(f"gate: FAIL: {len(failed)} benchmark(s) regressed: {', '.join(failed)}")
        return 1
    print(f"gate: PASS ({len(verdicts)} benchmarks)")
    return 0


if __name__ == "__main__":
    sys.exit(main())
