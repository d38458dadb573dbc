"""Bad input raises a tetrapage error (InputError is a ValueError, IoError an OSError) with a
message naming what is wrong; nothing crashes and nothing is left behind."""

import shutil

import numpy as np
import pytest

import tetrapage
from conftest import corner_tetrahedron, cube, pose


@pytest.fixture(scope="module")
def obj(cube_index):
    return tetrapage.Index(cube_index).object(*corner_tetrahedron())


@pytest.mark.parametrize("poses, message", [
    (np.zeros((3, 6)), "shape (3, 6)"),
    (np.zeros((2, 3, 3)), "shape (2, 3, 3)"),
    (np.array(["a"] * 7), "dtype <U1"),
    (np.zeros(7, dtype=complex), "dtype complex128"),
    (np.ones(7, dtype=bool), "dtype bool"),
    ("not a pose", "is not a real number type"),
    ([[0, 0, 0, 1, 0, 0, 0], [0, 0, 0, 2, 0, 0, 0]], "poses[1]"),
    ([[0, 0, np.nan, 1, 0, 0, 0]], "poses[0]"),
    ([[0, 0, 0, 0, 0, 0, 0]], "poses[0]"),
    ([[0, 0, 0, 1, np.inf, 0, 0]], "poses[0]"),
    (np.diag([2.0, 1.0, 1.0, 1.0]), "not orthonormal"),
    (np.diag([-1.0, 1.0, 1.0, 1.0]), "reflection"),
    (np.array([np.eye(4), np.eye(4) + np.eye(4, k=-3)]), "poses[1]: the last row"),
])
def test_bad_poses(obj, poses, message):
    with pytest.raises(tetrapage.InputError) as raised:
        obj.collides(poses)
    assert message in str(raised.value)
    assert isinstance(raised.value, ValueError) and isinstance(raised.value, tetrapage.Error)


def test_non_unit_quaternion_is_named(obj):
    with pytest.raises(ValueError) as raised:
        obj.query(np.array([0, 0, 0, 1, 1, 0, 0.0]))
    assert "pose" in str(raised.value) and "quaternion" in str(raised.value)


@pytest.mark.parametrize("vertices, triangles, message", [
    (np.zeros((4, 2)), [[0, 1, 2]], "vertices: shape (4, 2)"),
    (np.zeros((4, 3)), np.array([[0, 1, 2.0]]), "is not an integer type"),
    (np.eye(3), [[0, 1, 3]], "triangles[0, 2] = 3"),
    (np.eye(3), [[0, -1, 2]], "triangles[0, 1] = -1"),
    (np.eye(3), np.array([[0, 1, 2**63]], dtype=np.uint64), "not below the vertex count"),
    (np.eye(3), np.zeros((0, 3), dtype=int), "no triangle"),
    (np.array([[0, 0, 0], [1, 0, 0], [np.nan, 1, 0]]), [[0, 1, 2]], "non-finite"),
    (np.array([[0, 0, 0], [1, 0, 0], [2, 0, 0]]), [[0, 1, 2]], "zero area"),
])
def test_bad_objects(cube_index, vertices, triangles, message):
    index = tetrapage.Index(cube_index)
    with pytest.raises(tetrapage.InputError) as raised:
        index.object(vertices, triangles)
    assert message in str(raised.value)


@pytest.mark.parametrize("keyword, value, message", [
    ("mode", "every", "mode 'every' is not one of first_hit, all_contacts"),
    ("accuracy", "sloppy", "sloppy"),
    ("shape", "sphere", "shape 'sphere'"),
    ("motion", "teleport", "motion 'teleport'"),
])
def test_bad_options(obj, keyword, value, message):
    with pytest.raises(tetrapage.InputError) as raised:
        obj.query(pose(2, 0, 0), **{keyword: value})
    assert message in str(raised.value)


def test_unknown_keyword_is_a_type_error(obj):
    with pytest.raises(TypeError):
        obj.collides(pose(2, 0, 0), acuracy="exact")


def test_missing_and_damaged_files(cube_index, tmp_path):
    with pytest.raises(tetrapage.IoError) as raised:
        tetrapage.Index(tmp_path / "missing.tpi")
    assert "missing.tpi" in str(raised.value) and isinstance(raised.value, OSError)
    damaged = tmp_path / "damaged.tpi"
    shutil.copy(cube_index, damaged)
    with open(damaged, "r+b") as handle:
        handle.truncate(damaged.stat().st_size // 2)
    with pytest.raises(tetrapage.Error) as raised:
        tetrapage.Index(damaged)
    assert "damaged.tpi" in str(raised.value)
    not_an_index = tmp_path / "text.tpi"
    not_an_index.write_text("hello\n")
    with pytest.raises((tetrapage.FormatError, tetrapage.IoError)):
        tetrapage.Index(not_an_index)
    garbage = tmp_path / "garbage.obj"
    garbage.write_text("v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 9\n")
    with pytest.raises(tetrapage.InputError) as raised:
        tetrapage.read_mesh(garbage)
    assert "garbage.obj" in str(raised.value)


def test_bad_budgets(cube_index):
    for memory, message in [("lots", "lots"), (-5, "not a budget"), (1.5, "byte count")]:
        with pytest.raises(tetrapage.InputError) as raised:
            tetrapage.Index(cube_index, memory=memory)
        assert message in str(raised.value)
    with pytest.raises(tetrapage.InputError) as raised:
        tetrapage.Index(cube_index, memory=16)
    assert "shard" in str(raised.value)


def test_bad_preprocess_leaves_nothing(tmp_path):
    vertices, triangles = cube()
    source = tmp_path / "cube.off"
    tetrapage.write_mesh(source, (vertices, triangles))
    output = tmp_path / "out.tpi"
    for keywords, exception in [({"shard": "octree"}, tetrapage.InputError),
                                ({"precision": "half"}, tetrapage.InputError),
                                ({"progress": 5}, tetrapage.InputError),
                                ({"deflection": "-1"}, tetrapage.InputError),
                                ({"threads": -1}, tetrapage.InputError),
                                ({"region_triangles": 2.5}, tetrapage.InputError)]:
        with pytest.raises(exception):
            tetrapage.preprocess(source, output, **keywords)
    with pytest.raises(tetrapage.IoError):
        tetrapage.preprocess(tmp_path / "missing.obj", output)
    assert sorted(p.name for p in tmp_path.iterdir()) == ["cube.off"]
