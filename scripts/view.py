#!/usr/bin/python3
"""A live view of a crumple run (matplotlib's 3D axes in a Tk window): drag to rotate, right-drag
or scroll to zoom; the title shows the frame, its simulated time, its wall time and the counts.

  scripts/view.py DIR                          replay the frames in DIR (from `crumple run
                                               --out DIR --every K`), then keep the last one
  scripts/view.py --live DIR -- [run options]  start `crumple run --out DIR --every K [options]`
                                               and show each frame as the run writes it
  scripts/view.py DIR --frame N --screenshot P draw frame N (default: the last) in the window,
                                               save the window's image to P and exit

The frame time comes from DIR/stats.csv (step_ms), written when the run ends; a live view shows
the wall time between the frames it received until then.
"""
import argparse
import csv
import glob
import os
import re
import subprocess
import sys
import time

import matplotlib

from accuracy_common import read_obj  # vertices, triangles, auxiliary springs of a crumple OBJ

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
PAPER = (0.93, 0.90, 0.80)  # the sheet's colour, lit by its normal (test_view.py looks for it)


def frame_files(folder):
    """{frame number: path} of the frame_NNNNN.obj files in folder (final.obj as the last frame)."""
    frames = {}
    for p in glob.glob(os.path.join(folder, "frame_*.obj")):
        m = re.search(r"frame_(\d+)\.obj$", p)
        if m:
            frames[int(m.group(1))] = p
    return frames


def read_stats(folder):
    """{frame: row} of folder/stats.csv, or {} while the run has not finished it."""
    path = os.path.join(folder, "stats.csv")
    if not os.path.exists(path):
        return {}
    with open(path) as f:
        return {int(r["frame"]): r for r in csv.DictReader(f)}


class View:
    """One figure; draw(frame, path) replaces the sheet, keeping the camera the user set."""

    def __init__(self, plt):
        self.plt = plt
        self.fig = plt.figure(figsize=(7, 7))
        self.ax = self.fig.add_subplot(projection="3d")
        self.sheet = None
        self.limits = None
        self.last_wall = None

    def draw(self, frame, path, stats):
        import numpy as np
        from mpl_toolkits.mplot3d.art3d import Poly3DCollection

        x, tris, _ = read_obj(path)
        polys = x[tris]
        n = np.cross(polys[:, 1] - polys[:, 0], polys[:, 2] - polys[:, 0])
        n /= np.maximum(np.linalg.norm(n, axis=1, keepdims=True), 1e-30)
        light = 0.45 + 0.55 * np.abs(n @ np.array([0.3, -0.4, 0.866]))  # both sides lit
        colours = np.clip(light[:, None] * np.array(PAPER)[None, :], 0, 1)
        if self.sheet is not None:
            self.sheet.remove()
        self.sheet = Poly3DCollection(polys, facecolors=colours, edgecolors="none")
        self.ax.add_collection3d(self.sheet)
        if self.limits is None:  # the first frame fixes the box, so the sheet moves in it
            lo, hi = x.min(axis=0), x.max(axis=0)
            c, r = (lo + hi) / 2, max(hi - lo) / 2 * 1.1
            self.limits = (c - r, c + r)
            for k, axis in enumerate((self.ax.set_xlim, self.ax.set_ylim, self.ax.set_zlim)):
                axis(self.limits[0][k], self.limits[1][k])
            self.ax.set_box_aspect((1, 1, 1))
        self.ax.set_title(self.caption(frame, stats, len(x), len(tris)))

    def caption(self, frame, stats, nv, nt):
        row = stats.get(frame)
        now = time.monotonic()
        if row:
            timing = "t = %.3f s, %.3f ms/frame" % (float(row["time"]), float(row["step_ms"]))
        elif self.last_wall is not None:
            timing = "%.0f ms since the last frame shown" % (1000 * (now - self.last_wall))
        else:
            timing = "frame time in stats.csv when the run ends"
        self.last_wall = now
        return "frame %d: %s\n%d vertices, %d triangles" % (frame, timing, nv, nt)


def start_run(folder, every, run_args):
    exe = os.path.join(ROOT, "build", "app", "crumple")
    cmd = [exe, "run", "--out", folder, "--every", str(every), "--quiet"] + run_args
    return subprocess.Popen(cmd)


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("folder", help="a `crumple run --out` folder")
    ap.add_argument("--live", action="store_true", help="start the run and follow it (options after --)")
    ap.add_argument("--every", type=int, default=5, help="live: write and show every K-th frame")
    ap.add_argument("--frame", type=int, help="screenshot: the frame to draw (default: the last)")
    ap.add_argument("--screenshot", help="draw one frame, save the window as this PNG, exit")
    argv = sys.argv[1:]
    run_args = argv[argv.index("--") + 1:] if "--" in argv else []
    a = ap.parse_args(argv[:argv.index("--")] if "--" in argv else argv)
    matplotlib.use("TkAgg")  # a window: needs a display (Xvfb in the test)
    import matplotlib.pyplot as plt

    run = None
    if a.live:
        os.makedirs(a.folder, exist_ok=True)
        for old in frame_files(a.folder).values():
            os.remove(old)
        run = start_run(a.folder, a.every, run_args)
    view = View(plt)
    if a.screenshot:
        frames = frame_files(a.folder)
        if not frames:
            sys.exit("view: no frame_*.obj in %s (run with --out and --every)" % a.folder)
        frame = a.frame if a.frame is not None else max(frames)
        if frame not in frames:
            sys.exit("view: no frame %d in %s" % (frame, a.folder))
        view.draw(frame, frames[frame], read_stats(a.folder))
        plt.show(block=False)
        plt.pause(0.5)  # let Tk map and paint the window
        view.fig.savefig(a.screenshot)
        return
    shown = set()

    def poll():  # draws the next frame not yet shown (in order), if any
        frames = frame_files(a.folder)
        todo = sorted(f for f in frames if f not in shown)
        if run is not None and run.poll() is None and todo and todo[-1] == max(frames):
            todo.pop()  # the newest file may still be being written
        if todo:
            shown.add(todo[0])
            view.draw(todo[0], frames[todo[0]], read_stats(a.folder))
            view.fig.canvas.draw_idle()

    timer = view.fig.canvas.new_timer(interval=100)
    timer.add_callback(poll)
    timer.start()
    plt.show()
    if run is not None and run.poll() is None:
        run.terminate()


if __name__ == "__main__":
    main()
