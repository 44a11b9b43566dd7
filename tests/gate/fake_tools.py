"""What the script tests with fake binaries share: a temporary folder with a call log, and fake
executables written into it (each test module formats its own fake's text)."""
import os
import stat
import tempfile
import unittest
from pathlib import Path


class FakeToolsCase(unittest.TestCase):
    """A test case whose fakes live in self.dir and log their calls to self.log."""

    def setUp(self):
        self.dir = tempfile.TemporaryDirectory()
        self.log = os.path.join(self.dir.name, "calls.log")

    def tearDown(self):
        self.dir.cleanup()

    def write_fake(self, name, text):
        """An executable file `name` in self.dir holding `text`; returns its path."""
        path = os.path.join(self.dir.name, name)
        Path(path).write_text(text)
        os.chmod(path, os.stat(path).st_mode | stat.S_IXUSR)
        return path
