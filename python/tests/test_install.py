"""`cmake --install` puts the module where the prefix's Python finds it, and it works from there."""

import os
import subprocess
import sys

import pytest


def test_installed_module_imports_and_answers(tmp_path):
    build = os.environ.get("TETRAPAGE_BUILD")
    if not build:
        pytest.skip("TETRAPAGE_BUILD is not set (ctest sets it)")
    prefix = tmp_path / "prefix"
    subprocess.run([os.environ["CMAKE_COMMAND"], "--install", build, "--component", "python",
                    "--prefix", prefix], check=True, capture_output=True)
    site = prefix / os.environ["TETRAPAGE_PYTHON_INSTALL_DIR"]
    assert (site / "tetrapage" / "__init__.py").exists()
    check = ("import numpy as np, tetrapage; "
             "print(tetrapage.__file__); "
             "g = tetrapage.ObjectGroup([(np.eye(3), [[0, 1, 2]]), (np.eye(3), [[0, 1, 2]])]); "
             "print(len(g.step(np.array([[0, 0, 0, 1, 0, 0, 0]] * 2)).pairs))")
    environment = {key: value for key, value in os.environ.items() if key != "PYTHONPATH"}
    environment["PYTHONPATH"] = str(site)
    done = subprocess.run([sys.executable, "-c", check], capture_output=True, text=True,
                          env=environment, cwd=tmp_path)
    assert done.returncode == 0, done.stderr
    where, pairs = done.stdout.split()
    assert where.startswith(str(site)) and pairs == "1"
