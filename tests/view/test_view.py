"""scripts/view.py in a real Tk window on a virtual X server (Xvfb): screenshots of two known
frames of a run must show the sheet (enough pixels of its paper colour) and differ from each
other (the viewer follows the frames), and a blank image must fail the same check.

Run by ctest as: /usr/bin/python3 -m unittest -v test_view   (CRUMPLE_EXE: the command)
"""
import os
import shutil
import subprocess
import tempfile
import unittest

from PIL import Image

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
VIEW = os.path.join(ROOT, "scripts", "view.py")


def sheet_mask(path):
    """Per pixel: True where the paper colour is (r clearly above b, not dark): view.py paints the
    sheet (0.93, 0.90, 0.80) times a light factor in [0.45, 1]; the axes, panes and text are grey
    or black (r = g = b)."""
    img = Image.open(path).convert("RGB")
    return [r > 60 and r > 1.08 * b for (r, g, b) in img.getdata()], img.size


def sheet_fraction(path):
    mask, _ = sheet_mask(path)
    return sum(mask) / len(mask)


class ViewScreenshots(unittest.TestCase):
    @classmethod
    def setUpClass(cls):
        if not shutil.which("xvfb-run"):
            raise unittest.SkipTest("xvfb-run missing: scripts/install_deps.sh installs xvfb")
        cls.tmp = tempfile.mkdtemp(prefix="crumple_view_")
        run = os.path.join(cls.tmp, "run")
        subprocess.run([os.environ["CRUMPLE_EXE"], "run", "--grid", "24", "--frames", "120", "--every", "30",
                        "--out", run, "--quiet"], check=True)
        cls.shots = {}
        for frame in (30, 120):
            png = os.path.join(cls.tmp, "frame%d.png" % frame)
            subprocess.run(["xvfb-run", "-a", "/usr/bin/python3", VIEW, run, "--frame", str(frame),
                            "--screenshot", png], check=True, timeout=120)
            cls.shots[frame] = png

    @classmethod
    def tearDownClass(cls):
        shutil.rmtree(cls.tmp, ignore_errors=True)

    # Catches a window that shows no sheet (an empty or mis-scaled axes, faces not drawn).
    def test_sheet_is_drawn(self):
        for frame, png in self.shots.items():
            self.assertGreater(sheet_fraction(png), 0.03, "frame %d: too little of the sheet on screen" % frame)

    # Catches a viewer stuck on one frame: by frame 120 the sphere has crumpled the sheet.
    def test_frames_differ(self):
        a, size = sheet_mask(self.shots[30])
        b, _ = sheet_mask(self.shots[120])
        changed = sum(x != y for x, y in zip(a, b)) / len(a)
        self.assertGreater(changed, 0.01)

    # The check itself can fail: a blank window has no sheet pixels.
    def test_blank_image_fails_the_check(self):
        blank = os.path.join(self.tmp, "blank.png")
        Image.new("RGB", (700, 700), (255, 255, 255)).save(blank)
        self.assertLess(sheet_fraction(blank), 0.03)


if __name__ == "__main__":
    unittest.main()
