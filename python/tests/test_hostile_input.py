"""Hostile input found by review: each case once crashed, hung or raised an error naming nothing.
The cases that crashed or hung run in a subprocess, so that a regression fails the test instead
of killing (or stalling) the whole run."""

import os
import subprocess
import sys
import textwrap

import numpy as np
import pytest

import tetrapage
from conftest import corner_tetrahedron, cube, pose


def run_isolated(code, cube_index, timeout=60):
    """Runs `code` (with tetrapage, numpy as np, `index` open on cube_index, `vertices` and
    `triangles` of the unit cube) in a fresh interpreter; returns (exit code, stderr)."""
    prelude = textwrap.dedent(f"""\
        import numpy as np
        import tetrapage
        index = tetrapage.Index({str(cube_index)!r})
        vertices = np.array([[x, y, z] for x in (0., 1.) for y in (0., 1.) for z in (0., 1.)])
        triangles = np.array([[0, 1, 3], [0, 3, 2], [4, 6, 7], [4, 7, 5], [0, 4, 5], [0, 5, 1],
                              [2, 3, 7], [2, 7, 6], [0, 2, 6], [0, 6, 4], [1, 5, 7], [1, 7, 3]])
        """)
    environment = dict(os.environ, PYTHONPATH=os.pathsep.join(sys.path))
    try:
        done = subprocess.run([sys.executable, "-X", "faulthandler", "-c",
                               prelude + textwrap.dedent(code)],
                              capture_output=True, text=True, timeout=timeout, env=environment)
    except subprocess.TimeoutExpired:
        pytest.fail(f"hung for {timeout} s: {code}")
    return done.returncode, done.stderr


def expect_refused_isolated(statement, message, cube_index, timeout=60):
    """Runs `statement` as run_isolated does: it must raise an InputError naming `message`, and
    neither crash nor hang."""
    code = f"""
        try:
            {statement}
        except tetrapage.InputError as error:
            assert {message!r} in str(error), error
            print("refused")
        else:
            raise SystemExit("accepted")
        """
    returncode, stderr = run_isolated(code, cube_index, timeout)
    assert returncode == 0, stderr


@pytest.mark.parametrize("code", [
    # numpy refuses a ragged list: py::array::ensure returned a null array, read as an array.
    "index.object(vertices * 0.1, triangles).collides([[1, 2], [3]])",
    "index.object(vertices * 0.1, triangles).query([[1, 2], [3]])",
    "tetrapage.Mesh([[0, 0, 0], [1, 0]], triangles)",
    "tetrapage.Mesh(vertices, [[0, 1, 2], [3]])",
    "tetrapage.Mesh(vertices, triangles, part_of=[[0], [0, 0]])",
    "tetrapage.write_poses('unused.csv', [[1, 2], [3]])",
])
def test_ragged_lists_are_input_errors(cube_index, code):
    expect_refused_isolated(code, "not an array of numbers", cube_index)


@pytest.mark.parametrize("part_id", [2**31, 2**40, 2**64 - 1])
def test_huge_part_ids_are_refused_without_making_names(cube_index, part_id):
    # Unnamed part ids got a made-up name each up to the largest: 2**40 names.
    expect_refused_isolated(
        f"tetrapage.Mesh(vertices, triangles, part_of=np.full(12, {part_id}, dtype=np.uint64))",
        "part", cube_index, timeout=30)


def test_part_ids_and_names(cube_index):
    vertices, triangles = cube()
    mesh = tetrapage.Mesh(vertices, triangles, part_of=[0] * 6 + [3] * 6)
    assert mesh.part_names == ["part 0", "part 1", "part 2", "part 3"]
    assert list(mesh.part_of) == [0] * 6 + [3] * 6
    assert tetrapage.Mesh(vertices, triangles, part_of=[5] * 12,
                          part_names=list("abcdef")).part_names[5] == "f"
    with pytest.raises(tetrapage.InputError, match="integer type"):
        tetrapage.Mesh(vertices, triangles, part_of=np.full(12, 1.5))
    with pytest.raises(tetrapage.InputError, match=r"part_of\[0\] is negative"):
        tetrapage.Mesh(vertices, triangles, part_of=[-1] * 12)
    with pytest.raises(tetrapage.InputError, match="part_names: 1 names"):
        tetrapage.Mesh(vertices, triangles, part_of=[0] * 11 + [7], part_names=["a"])


@pytest.mark.parametrize("make", [
    "index.object(vertices * 1e308, triangles)",
    "tetrapage.Obstacles(index).insert((vertices * 1e308, triangles), [0, 0, 0, 1, 0, 0, 0])",
    "tetrapage.ObjectGroup([(vertices * 1e308, triangles)])",
])
def test_coordinates_near_the_largest_double_are_refused(cube_index, make):
    # Finite but beyond the accepted 1e150: the object's BVH overflowed (and crashed) before
    # the check ran.
    expect_refused_isolated(make, "beyond 1e+150", cube_index)


@pytest.mark.parametrize("keyword, value, message", [
    ("memory", 2**70, "beyond 2\\*\\*64 - 1"),
    ("threads", 2**70, "threads: 1180591620717411303424 is not a whole number"),
    ("region_triangles", 2**64, "region_triangles: 18446744073709551616"),
    ("length_unit", 5, "length_unit: 5 is not a unit text"),
    ("query_extent", "far", "query_extent: 'far' is not a length"),
    ("spill_folder", 3, "spill_folder: 3 is not a path"),
])
def test_preprocess_arguments_out_of_range_are_named(tmp_path, keyword, value, message):
    vertices, triangles = corner_tetrahedron()
    tetrapage.write_mesh(tmp_path / "t.ply", (vertices, triangles))
    with pytest.raises(tetrapage.InputError, match=message):
        tetrapage.preprocess([tmp_path / "t.ply"], tmp_path / "t.tpi", **{keyword: value})
    with pytest.raises(tetrapage.InputError, match="inputs: None is not a path"):
        tetrapage.preprocess([None], tmp_path / "t.tpi")
    assert not (tmp_path / "t.tpi").exists()


def test_index_budgets_beyond_int64(cube_index):
    # Budgets were cast to long long: 2**63, a valid uint64 budget, raised a RuntimeError naming
    # nothing.
    assert tetrapage.Index(cube_index, memory=2**63).memory == 2**63
    assert tetrapage.Index(cube_index, memory=2**64 - 1).memory == 2**64 - 1
    with pytest.raises(tetrapage.InputError, match="memory: 18446744073709551616 bytes"):
        tetrapage.Index(cube_index, memory=2**64)


def test_containment_has_no_closest_points(cube_index):
    # Inside the closed cube the answer is "touching" with nothing measured: the C++ points are
    # zeros, which read as a point at the origin; the binding says NaN.
    obj = tetrapage.Index(cube_index).object(*corner_tetrahedron())
    inside = pose(0.4, 0.4, 0.4)
    answer = obj.distance(inside)
    assert answer.containment == "object_inside_obstacle"
    assert answer.separation == "touching" and answer.environment_triangle is None
    assert np.isnan(answer.on_environment).all() and np.isnan(answer.on_object).all()
    rows = obj.distances(np.array([inside, pose(0.95, 0.4, 0.4)]))
    assert np.isnan(rows["on_environment"][0]).all() and np.isnan(rows["on_object"][0]).all()
    assert rows["environment_triangle"][0] == -1
    # A surface contact keeps its point.
    assert rows["separation"][1] == tetrapage.TOUCHING
    assert np.isfinite(rows["on_environment"][1]).all()
    assert rows["environment_triangle"][1] >= 0


SIGNAL_PRELUDE = """
    import signal
    obj = index.object(vertices * 0.1, triangles)
    obstacles = tetrapage.Obstacles(index)
    part = obstacles.insert((vertices, triangles), [5, 5, 5, 1, 0, 0, 0])
    obj.obstacles = obstacles
    other = index.object(vertices * 0.1, triangles)
    other.obstacles = obstacles
    far = np.array([2.0, 2.0, 2.0, 1.0, 0.0, 0.0, 0.0])
    poses = np.tile(far, (4_000_000, 1))  # long enough for the timer to fire during the batch
    calls = []

    def handler(*_):
        signal.setitimer(signal.ITIMER_REAL, 0)  # once: a later one would raise again
        calls.append(1)
        HANDLER

    signal.signal(signal.SIGALRM, handler)
    signal.setitimer(signal.ITIMER_REAL, 0.01, 0.01)
    """


@pytest.mark.parametrize("handler", [
    "obj.distance(far)",
    "obstacles.insert((vertices, triangles), far)",
    "obstacles.move(part, far)",
    "obj.obstacles = None",
])
def test_a_signal_handler_reentering_the_query_is_refused(cube_index, handler):
    # The Ctrl-C check runs signal handlers with the object's lock and its overlay's held: a
    # handler waiting for either waited forever for its own thread.
    code = SIGNAL_PRELUDE.replace("HANDLER", handler) + """
    try:
        obj.collides(poses)
        raise SystemExit("the handler did not run during the query")
    except tetrapage.InputError as error:
        assert "a query in progress on this thread" in str(error), error
    """
    returncode, stderr = run_isolated(code, cube_index, timeout=30)
    assert returncode == 0, stderr


def test_a_signal_handler_may_use_other_objects_and_read_the_obstacles(cube_index):
    code = SIGNAL_PRELUDE.replace("HANDLER", "other.distance(far); len(obstacles)") + """
    assert not obj.collides(poses).any()
    assert calls
    """
    returncode, stderr = run_isolated(code, cube_index, timeout=30)
    assert returncode == 0, stderr


def test_ids_and_counts_out_of_range_are_named(cube_index):
    obstacles = tetrapage.Obstacles(tetrapage.Index(cube_index))
    for call, message in [(lambda: obstacles.move(-1, [0, 0, 0, 1, 0, 0, 0]), "id: -1"),
                          (lambda: obstacles.remove(2**40), "id: 1099511627776"),
                          (lambda: obstacles.hide_part(2**40), "part: 1099511627776"),
                          (lambda: obstacles.show_part(1.5), "part: 1.5")]:
        with pytest.raises(tetrapage.InputError) as raised:
            call()
        assert message in str(raised.value)
    obj = tetrapage.Index(cube_index).object(np.eye(3), [[0, 1, 2]])
    with pytest.raises(tetrapage.InputError, match="max_iterations: 0"):
        obj.time_of_impact([5, 5, 5, 1, 0, 0, 0], [6, 5, 5, 1, 0, 0, 0], max_iterations=0)


def test_names_without_ids_and_an_empty_mesh(tmp_path):
    with pytest.raises(tetrapage.InputError, match="part_names: 2 names"):
        tetrapage.Mesh(np.eye(3), [[0, 1, 2]], part_names=["a", "b"])
    assert np.isnan(tetrapage.Mesh(np.zeros((0, 3)), np.zeros((0, 3), dtype=int)).bounds).all()
    source = tmp_path / "t.obj"
    tetrapage.write_mesh(source, (np.eye(3), [[0, 1, 2]]))
    for extent in (0.0, -1.0, float("nan")):
        with pytest.raises(tetrapage.InputError, match="query_extent"):
            tetrapage.preprocess(source, tmp_path / "t.tpi", query_extent=extent)


def test_obstacles_save_replaces_nothing_but_an_overlay(cube_index, tmp_path):
    """save on the index it was opened from, on another index or on a device is refused and
    leaves the file as it was; an overlay is replaced."""
    before = cube_index.read_bytes()
    obstacles = tetrapage.Obstacles(tetrapage.Index(cube_index))
    vertices, triangles = cube()
    obstacles.insert((vertices * 0.1, triangles), pose(0.4, 0.4, 0.4), name="box")
    with pytest.raises(tetrapage.InputError, match="refusing"):
        obstacles.save(cube_index)
    assert cube_index.read_bytes() == before
    other = tmp_path / "other.tpi"
    other.write_bytes(before)
    with pytest.raises(tetrapage.InputError, match="something else"):
        obstacles.save(other)
    assert other.read_bytes() == before
    with pytest.raises(tetrapage.InputError, match="character device"):
        obstacles.save("/dev/full")
    saved = tmp_path / "v.tpo"
    obstacles.save(saved)
    obstacles.save(saved)
    assert sorted(p.name for p in tmp_path.iterdir()) == ["other.tpi", "v.tpo"]
    with pytest.raises(tetrapage.InputError, match="line break"):
        obstacles.insert((vertices * 0.1, triangles), pose(0.4, 0.4, 0.4), name="a\nb")


def test_read_mesh_reads_manifests_as_the_commands_do(tmp_path):
    """A manifest in mm placing one file twice: read_mesh gives both placements, in mm."""
    vertices, triangles = cube()
    tetrapage.write_mesh(tmp_path / "cube.ply", (vertices, triangles))
    (tmp_path / "a.json").write_text(
        '{"units": "mm", "parts": [{"file": "cube.ply", "instances": '
        '[{"translation": [0, 0, 0]}, {"translation": [5, 0, 0]}]}]}')
    mesh = tetrapage.read_mesh(tmp_path / "a.json")
    assert mesh.length_unit == "mm"
    assert len(mesh) == 2 * len(triangles)
    assert mesh.vertices[:, 0].max() == 6.0


def _resident_bytes():
    with open("/proc/self/status") as status:
        for line in status:
            if line.startswith("VmRSS:"):
                return int(line.split()[1]) * 1024
    return 0


def test_repeated_cad_reads_keep_the_interpreters_memory_flat():
    """STEP and IGES are read in a child process: what OpenCASCADE keeps stays there, and the
    module keeps nothing of a read it returned."""
    samples = ["/usr/share/opencascade/data/step/screw.step",
               "/usr/share/opencascade/data/iges/hammer.iges"]
    for sample in samples:  # allocators warmed up
        tetrapage.read_mesh(sample)
    before = _resident_bytes()
    for _ in range(30):
        for sample in samples:
            assert len(tetrapage.read_mesh(sample)) > 0
    growth = _resident_bytes() - before
    assert growth < 8 << 20, f"resident memory grew by {growth} bytes over 60 reads"
