"""docs/USAGE.md's "From Python" script runs as written."""

import importlib.util
import os
import re
import subprocess
import sys
from pathlib import Path

import pytest


def usage_script():
    source = os.environ.get("TETRAPAGE_SOURCE")
    if not source:
        pytest.skip("TETRAPAGE_SOURCE is not set (ctest sets it)")
    text = (Path(source) / "docs" / "USAGE.md").read_text()
    section = text.split("\n## From Python\n", 1)[1].split("\n## ", 1)[0]
    blocks = re.findall(r"```python\n(.*?)```", section, re.S)
    assert len(blocks) == 1, "the section holds one complete script"
    return blocks[0]


def check_usage_output(output, work):
    collide = re.search(r"(\d+) of 10000 poses collide", output)
    assert collide and 0 < int(collide.group(1)) < 10000
    assert "first collision at pose" in output and "one pose per call" in output
    assert (work / "scene.tpi").exists()
    plotted = importlib.util.find_spec("matplotlib") is not None
    assert (work / "latency.png").exists() == plotted


def test_the_usage_script_runs(tmp_path):
    script = tmp_path / "fly.py"
    script.write_text(usage_script())
    done = subprocess.run([sys.executable, script, tmp_path / "work"], capture_output=True,
                          text=True, timeout=300)
    assert done.returncode == 0, done.stderr
    check_usage_output(done.stdout, tmp_path / "work")
