"""Fixtures of the Python tests: the `tetrapage` CLI (TETRAPAGE_CLI, set by ctest), a demo
scene flown by `tetrapage fly`, and small scenes made with numpy whose answers are known in
closed form (an oracle that shares nothing with the runtime)."""

import csv
import os
import subprocess

import numpy as np
import pytest

import tetrapage


def run_cli(*arguments):
    """Runs the CLI; returns its stdout. Fails the test with stderr on a non-zero exit."""
    cli = os.environ.get("TETRAPAGE_CLI")
    if not cli:
        pytest.skip("TETRAPAGE_CLI is not set (ctest sets it)")
    done = subprocess.run([cli, *map(str, arguments)], capture_output=True, text=True)
    assert done.returncode == 0, f"tetrapage {' '.join(map(str, arguments))}: {done.stderr}"
    return done.stdout


def read_csv(path):
    with open(path, newline="") as handle:
        return list(csv.DictReader(handle))


@pytest.fixture(scope="session")
def demo(tmp_path_factory):
    """The demo's workload, scaled down: a generated scene (real CGAL meshes), an object, a
    billiard flight with the reference oracle's answers, the index, and `tetrapage fly`'s own
    answers: collisions, distances, every contact and the times of impact."""
    folder = tmp_path_factory.mktemp("demo")
    scene, obj, flight = folder / "scene.ply", folder / "object.ply", folder / "flight.csv"
    run_cli("generate", "scene", "--triangles", 40000, "--seed", 1, "-o", scene)
    run_cli("generate", "object", "--triangles", 1000, "-o", obj)
    run_cli("generate", "flight", "--env", scene, "--object", obj, "--steps", 1000, "--seed", 2,
            "--displacement", 0.02, "-o", flight, "--answers", folder / "oracle.csv")
    index = folder / "scene.tpi"
    run_cli("preprocess", scene, "-o", index)
    run_cli("fly", index, "--object", obj, "--path", flight, "--answers", folder / "fly.csv")
    run_cli("fly", index, "--object", obj, "--path", flight, "--query", "distance",
            "--answers", folder / "distance.csv")
    run_cli("fly", index, "--object", obj, "--path", flight, "--query", "contacts",
            "--answers", folder / "contacts.csv")
    run_cli("fly", index, "--object", obj, "--path", flight, "--query", "toi",
            "--answers", folder / "toi.csv")
    return folder


# --- Scenes in closed form -------------------------------------------------------------------

def cube(lo=0.0, hi=1.0):
    """The closed cube [lo, hi]^3: 8 vertices, 12 outward triangles."""
    corners = np.array([[x, y, z] for x in (lo, hi) for y in (lo, hi) for z in (lo, hi)])
    faces = np.array([[0, 1, 3], [0, 3, 2], [4, 6, 7], [4, 7, 5], [0, 4, 5], [0, 5, 1],
                      [2, 3, 7], [2, 7, 6], [0, 2, 6], [0, 6, 4], [1, 5, 7], [1, 7, 3]])
    return corners, faces


def corner_tetrahedron(size=0.125):
    """A closed tetrahedron with its right-angle corner at the origin, along +x, +y, +z."""
    vertices = np.array([[0.0, 0.0, 0.0], [size, 0.0, 0.0], [0.0, size, 0.0], [0.0, 0.0, size]])
    triangles = np.array([[0, 2, 1], [0, 1, 3], [0, 3, 2], [1, 2, 3]])
    return vertices, triangles


def pose(x, y, z):
    return np.array([x, y, z, 1.0, 0.0, 0.0, 0.0])


@pytest.fixture(scope="session")
def cube_index(tmp_path_factory):
    """An index of the unit cube (closed) and an open square plate at z = 3, with interiors
    stored; everything dyadic, so the gaps below are exact."""
    folder = tmp_path_factory.mktemp("cube")
    vertices, triangles = cube()
    plate = np.array([[0.0, 0.0, 3.0], [1.0, 0.0, 3.0], [1.0, 1.0, 3.0], [0.0, 1.0, 3.0]])
    mesh = tetrapage.Mesh(np.vstack([vertices, plate]),
                          np.vstack([triangles, [[8, 9, 10], [8, 10, 11]]]),
                          part_of=[0] * 12 + [1, 1], part_names=["cube", "plate"])
    source = folder / "cube.ply"
    tetrapage.write_mesh(source, mesh)
    output = folder / "cube.tpi"
    tetrapage.preprocess([source], output, interiors=True, threads=1)
    return output
