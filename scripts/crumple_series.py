#!/usr/bin/python3
"""The crumple over time and its facets (issue 12, section 2): kinetic energy against time (seed
mean, with the seed spread as a band) and the histogram of final mesh-edge lengths, a few
configurations of one case side by side. Reads the runs that scripts/crumple_stats.py measured
(their `kinetic` series and `edge_hist`); scripts/crumple_study.py's report stage calls it with
runs from its cache (no run of its own).
"""
import numpy as np

import crumple_stats


def chart(groups, path, title, frame_dt=1.0 / 60):
    """groups: label -> the runs of one configuration (one per seed). False where none has a run
    that finished."""
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    groups = {k: [r for r in runs if r.get("exit") == 0] for k, runs in groups.items()}
    groups = {k: runs for k, runs in groups.items() if runs}
    if not groups:
        return False
    fig, (energy, facets) = plt.subplots(1, 2, figsize=(11.5, 4.4))
    edges = crumple_stats.EDGE_BINS
    centers = (edges[:-1] + edges[1:]) / 2
    for label, runs in groups.items():
        series = np.array([r["kinetic"] for r in runs], float)
        t = (np.arange(series.shape[1]) + 1) * crumple_stats.KE_EVERY * frame_dt
        mean, spread = series.mean(0), series.std(0, ddof=1) if len(runs) > 1 else np.zeros(series.shape[1])
        line, = energy.plot(t, mean, label=f"{label} ({len(runs)} seeds)")
        energy.fill_between(t, np.maximum(mean - spread, mean * 1e-3), mean + spread, color=line.get_color(),
                            alpha=0.2, lw=0)
        hist = np.array([r["edge_hist"] for r in runs], float)
        share = hist / hist.sum(1, keepdims=True)
        facets.step(centers, share.mean(0), where="mid", color=line.get_color(), label=label)
    energy.set_yscale("log")
    energy.set_xlabel("simulated time (s)")
    energy.set_ylabel("kinetic energy (seed mean; band: seed spread)")
    energy.legend(fontsize=7)
    facets.set_xlabel("final mesh-edge length / the input's mean edge length (last bin: longer)")
    facets.set_ylabel("share of the mesh edges (seed mean)")
    facets.legend(fontsize=7)
    fig.suptitle(title, fontsize=9)
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)
    return True
