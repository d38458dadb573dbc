"""`pip install .` puts the module into a virtual environment, where it imports and runs the
USAGE script; `pip uninstall` takes it out again. The build tree ctest runs in is reused
(TETRAPAGE_BUILD_DIR), so the install builds nothing new."""

import os
import subprocess
import sys
from pathlib import Path

import pytest

from test_usage_script import check_usage_output, usage_script


def environment():
    build = os.environ.get("TETRAPAGE_BUILD")
    if not build:
        pytest.skip("TETRAPAGE_BUILD is not set (ctest sets it)")
    # Nothing of the build tree's own module may leak in: only the installed one counts.
    settings = {key: value for key, value in os.environ.items() if key != "PYTHONPATH"}
    settings["TETRAPAGE_BUILD_DIR"] = build
    settings["PIP_NO_INDEX"] = "1"  # nothing may come from a package index
    settings["PIP_DISABLE_PIP_VERSION_CHECK"] = "1"
    return settings


def make_venv(where):
    # --system-site-packages: numpy (the module's one requirement) comes from Debian.
    subprocess.run([sys.executable, "-m", "venv", "--system-site-packages", where], check=True)
    return where / "bin" / "python"


def pip(python, *arguments, cwd):
    done = subprocess.run([python, "-m", "pip", *arguments], capture_output=True, text=True,
                          env=environment(), cwd=cwd, timeout=600)
    assert done.returncode == 0, done.stdout + done.stderr
    return done.stdout


def where_imported(python, cwd):
    done = subprocess.run([python, "-c", "import tetrapage; print(tetrapage.__file__)"],
                          capture_output=True, text=True, env=environment(), cwd=cwd)
    return done.returncode, done.stdout.strip(), done.stderr


@pytest.mark.parametrize("isolation", [True, False], ids=["build-isolation", "no-build-isolation"])
def test_pip_installs_into_a_virtual_environment(tmp_path, isolation):
    source = os.environ.get("TETRAPAGE_SOURCE")
    if not source:
        pytest.skip("TETRAPAGE_SOURCE is not set (ctest sets it)")
    python = make_venv(tmp_path / "venv")
    pip(python, "install", *([] if isolation else ["--no-build-isolation"]), source, cwd=tmp_path)
    status, where, errors = where_imported(python, tmp_path)
    assert status == 0, errors
    site = subprocess.run([python, "-c", "import sysconfig; print(sysconfig.get_path('platlib'))"],
                          capture_output=True, text=True, check=True).stdout.strip()
    assert Path(where) == Path(site) / "tetrapage" / "__init__.py"
    assert "tetrapage" in pip(python, "list", "--format=freeze", cwd=tmp_path)

    pip(python, "uninstall", "--yes", "tetrapage", cwd=tmp_path)
    status, _, errors = where_imported(python, tmp_path)
    assert status != 0 and "No module named 'tetrapage'" in errors
    assert not (Path(site) / "tetrapage").exists()


def test_the_usage_script_runs_from_a_pip_installed_module(tmp_path):
    source = os.environ.get("TETRAPAGE_SOURCE")
    if not source:
        pytest.skip("TETRAPAGE_SOURCE is not set (ctest sets it)")
    python = make_venv(tmp_path / "venv")
    pip(python, "install", source, cwd=tmp_path)
    script = tmp_path / "fly.py"
    script.write_text(usage_script())
    done = subprocess.run([python, script, tmp_path / "work"], capture_output=True, text=True,
                          env=environment(), cwd=tmp_path, timeout=300)
    assert done.returncode == 0, done.stderr
    check_usage_output(done.stdout, tmp_path / "work")
