"""tetrapage's own PEP 517 build backend: `pip install .` builds the module with CMake.

It needs nothing from a package index (the build requires no Python package: only the
standard library, CMake, a C++ compiler and the Debian packages of `make deps`), so it works
with pip's build isolation, in a virtual environment and under pyenv alike.

The module is built for the Python that runs pip, in <source>/build/wheel-<tag>-<hash> (one
build tree per interpreter), unless TETRAPAGE_BUILD_DIR names a configured build tree to
reuse; then its module must be built for this same Python (the same extension suffix).
CMAKE_BUILD_PARALLEL_LEVEL sets the build's jobs (default: all cores).
"""

import base64
import hashlib
import io
import os
import re
import subprocess
import sys
import sysconfig
import tarfile
import zipfile
from pathlib import Path

SOURCE = Path(__file__).resolve().parents[2]
NAME = "tetrapage"
SUMMARY = "Exact collision detection in huge CAD models, paged from disk"


class BuildError(RuntimeError):
    pass


def version():
    text = (SOURCE / "CMakeLists.txt").read_text()
    found = re.search(r"project\(\s*tetrapage\s+VERSION\s+([0-9][0-9.]*)", text)
    if not found:
        raise BuildError(f"{SOURCE / 'CMakeLists.txt'}: no `project(tetrapage VERSION x.y.z)`")
    return found.group(1)


def wheel_tag():
    implementation = {"cpython": "cp", "pypy": "pp"}.get(sys.implementation.name, "py")
    python = f"{implementation}{sys.version_info.major}{sys.version_info.minor}"
    platform = re.sub(r"[-.]", "_", sysconfig.get_platform())
    return f"{python}-{python}{sys.abiflags}-{platform}"


def metadata_text():
    return (f"Metadata-Version: 2.1\nName: {NAME}\nVersion: {version()}\nSummary: {SUMMARY}\n"
            "License: Proprietary\nRequires-Python: >=3.9\nRequires-Dist: numpy\n")


def wheel_text():
    return (f"Wheel-Version: 1.0\nGenerator: {NAME} ({Path(__file__).name})\n"
            f"Root-Is-Purelib: false\nTag: {wheel_tag()}\n")


def dist_info():
    return f"{NAME}-{version()}.dist-info"


def run(command, what):
    print("tetrapage:", " ".join(str(part) for part in command), flush=True)
    try:
        subprocess.run([str(part) for part in command], check=True)
    except FileNotFoundError:
        raise BuildError(f"{what}: {command[0]} not found (the build needs CMake and a C++ "
                         "compiler; `make deps` installs them and the libraries on Debian)")
    except subprocess.CalledProcessError as failed:
        raise BuildError(f"{what} failed (exit {failed.returncode}); its output is above "
                         "(`pip install -v` shows it)")


def build_tree():
    """The configured build tree whose `tetrapage_python` target makes this Python's module."""
    given = os.environ.get("TETRAPAGE_BUILD_DIR")
    if given:
        tree = Path(given).resolve()
        if not (tree / "CMakeCache.txt").is_file():
            raise BuildError(f"TETRAPAGE_BUILD_DIR={given}: not a configured CMake build tree "
                             "(no CMakeCache.txt)")
        return tree
    interpreter = os.path.realpath(getattr(sys, "_base_executable", sys.executable))
    key = hashlib.sha256(interpreter.encode()).hexdigest()[:8]
    tree = SOURCE / "build" / f"wheel-{wheel_tag()}-{key}"
    if not (tree / "CMakeCache.txt").is_file():
        run(["cmake", "-S", SOURCE, "-B", tree, "-DCMAKE_BUILD_TYPE=Release",
             f"-DPython_EXECUTABLE={sys.executable}", "-DTETRAPAGE_BUILD_PYTHON=ON",
             "-DTETRAPAGE_BUILD_TESTS=OFF", "-DTETRAPAGE_BUILD_BENCH=OFF"],
            "configuring tetrapage")
    return tree


def build_module():
    """Builds (or brings up to date) the extension module and returns its file."""
    tree = build_tree()
    jobs = os.environ.get("CMAKE_BUILD_PARALLEL_LEVEL") or str(os.cpu_count() or 1)
    run(["cmake", "--build", tree, "--target", "tetrapage_python", "--parallel", jobs],
        "building the tetrapage module")
    suffix = sysconfig.get_config_var("EXT_SUFFIX")
    module = tree / "python" / NAME / f"_tetrapage{suffix}"
    if not module.is_file():
        built = sorted(p.name for p in (tree / "python" / NAME).glob("_tetrapage*"))
        raise BuildError(f"{tree}: no {module.name} for this Python ({sys.executable}); the "
                         f"tree holds {', '.join(built) or 'no module'}: it was configured for "
                         "another Python (unset TETRAPAGE_BUILD_DIR to build one for this one)")
    return module


def record_line(path, data):
    digest = base64.urlsafe_b64encode(hashlib.sha256(data).digest()).rstrip(b"=").decode()
    return f"{path},sha256={digest},{len(data)}"


def wheel_files(module):
    files = {f"{NAME}/{p.name}": p.read_bytes() for p in (SOURCE / "python" / NAME).glob("*.py")}
    files[f"{NAME}/{module.name}"] = module.read_bytes()
    files[f"{dist_info()}/METADATA"] = metadata_text().encode()
    files[f"{dist_info()}/WHEEL"] = wheel_text().encode()
    return files


def write_wheel(directory, files):
    name = f"{NAME}-{version()}-{wheel_tag()}.whl"
    record = f"{dist_info()}/RECORD"
    lines = [record_line(path, data) for path, data in files.items()] + [f"{record},,"]
    # Written under a temporary name: a failed build leaves no wheel behind.
    target = Path(directory) / name
    partial = target.with_name(name + ".partial")
    with zipfile.ZipFile(partial, "w", zipfile.ZIP_DEFLATED) as wheel:
        for path, data in files.items():
            wheel.writestr(path, data)
        wheel.writestr(record, "\n".join(lines) + "\n")
    partial.replace(target)
    return name


# The PEP 517 hooks.

def get_requires_for_build_wheel(config_settings=None):
    return []


def get_requires_for_build_sdist(config_settings=None):
    return []


def prepare_metadata_for_build_wheel(metadata_directory, config_settings=None):
    where = Path(metadata_directory) / dist_info()
    where.mkdir(parents=True, exist_ok=True)
    (where / "METADATA").write_text(metadata_text())
    (where / "WHEEL").write_text(wheel_text())
    return dist_info()


def build_wheel(wheel_directory, config_settings=None, metadata_directory=None):
    try:
        return write_wheel(wheel_directory, wheel_files(build_module()))
    except BuildError as error:
        sys.exit(f"tetrapage: {error}")


def source_files():
    try:
        listed = subprocess.run(["git", "-C", SOURCE, "ls-files", "-z"], check=True,
                                capture_output=True).stdout.split(b"\0")
        return sorted(p.decode() for p in listed if p)
    except (OSError, subprocess.CalledProcessError):
        skipped = {".git", "build", "out"}
        return sorted(str(p.relative_to(SOURCE)) for p in SOURCE.rglob("*")
                      if p.is_file() and p.relative_to(SOURCE).parts[0] not in skipped)


def build_sdist(sdist_directory, config_settings=None):
    base = f"{NAME}-{version()}"
    target = Path(sdist_directory) / f"{base}.tar.gz"
    partial = target.with_name(target.name + ".partial")
    with tarfile.open(partial, "w:gz") as sdist:
        for path in source_files():
            sdist.add(SOURCE / path, arcname=f"{base}/{path}", recursive=False)
        info = metadata_text().encode()
        entry = tarfile.TarInfo(f"{base}/PKG-INFO")
        entry.size = len(info)
        sdist.addfile(entry, io.BytesIO(info))
    partial.replace(target)
    return target.name
