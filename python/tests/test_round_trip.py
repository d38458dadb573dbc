"""preprocess -> open -> query from Python alone, on scenes whose answers are known in closed
form: a tetrahedron at exact (dyadic) gaps from a unit cube's face."""

import numpy as np
import pytest

import tetrapage
from conftest import corner_tetrahedron, cube, pose

GAPS = [0.25, 2.0**-30, 0.0, -(2.0**-10)]


def test_touching_is_decided_exactly(cube_index):
    index = tetrapage.Index(cube_index)
    obj = index.object(*corner_tetrahedron())
    # The tetrahedron's lowest x is the translation's: it meets the face x = 1 iff gap <= 0.
    answers = obj.collides(np.array([pose(1.0 + gap, 0.5, 0.5) for gap in GAPS]))
    np.testing.assert_array_equal(answers, [gap <= 0 for gap in GAPS])


def test_the_summary_and_the_inspection_describe_the_model(cube_index):
    index = tetrapage.Index(cube_index, memory="64M")
    info = index.inspect()
    assert info["triangles"] == 14 and index.triangles == 14
    assert [p.name for p in index.parts] == ["cube", "plate"]
    assert [p.triangles for p in index.parts] == [12, 2]
    np.testing.assert_array_equal(index.bounds, [[0, 0, 0], [1, 1, 3]])
    assert index.memory == 64 << 20 and index.has_interiors
    assert index.precision == "exact" and info["precision"] == "exact"
    assert index.shard_bytes.sum() == index.total_shard_bytes > 0
    # The summary `tetrapage inspect --report` writes, under its names.
    assert info["parts"] == 2 and info["shards"] == len(index.shard_bytes)
    assert 0 < info["shard_stored_bytes"] and 0 < info["shard_decoded_bytes"]
    assert info["interiors"] is True and info["memory_budget_bytes"] == 64 << 20
    assert info["grid_shards"] + info["rtree_shards"] == info["shards"]
    # The default budget is every command's.
    assert tetrapage.Index(cube_index).memory == tetrapage.DEFAULT_MEMORY == 1 << 30


def test_contacts_name_the_part_and_where_the_triangles_meet(cube_index):
    index = tetrapage.Index(cube_index)
    obj = index.object(*corner_tetrahedron())
    answer = obj.query(pose(1.0, 0.5, 0.5), mode="all_contacts")
    assert answer.collides and answer.containment == "none"
    contacts = answer.contacts
    assert len(contacts) > 0 and set(contacts["part"]) == {0}
    # Every meeting point lies on the face x = 1, inside the tetrahedron's face there.
    assert np.all(contacts["point"][:, 0] == 1.0)
    assert np.all(contacts["point"][:, 1:] >= 0.5) and np.all(contacts["point"][:, 1:] <= 0.625)
    # The cube's normal at x = 1 points out (+x).
    on_face = contacts["environment_normal"]
    np.testing.assert_allclose(np.abs(on_face[:, 0]), 1.0)
    first = obj.query(pose(1.0, 0.5, 0.5))
    assert len(first.contacts) == 1


def test_containment_needs_the_interiors(cube_index, tmp_path):
    index = tetrapage.Index(cube_index)
    inside = pose(0.375, 0.375, 0.375)
    answer = index.object(*corner_tetrahedron()).query(inside)
    assert answer.collides and answer.containment == "object_inside_obstacle"
    assert answer.containing_part == 0 and len(answer.contacts) == 0
    far_and_inside = index.object(*corner_tetrahedron()).distances(np.array([pose(1.25, 0.5, 0.5), inside]))
    np.testing.assert_array_equal(far_and_inside["containment"], [0, tetrapage.OBJECT_INSIDE_OBSTACLE])
    assert far_and_inside["separation"][1] == tetrapage.TOUCHING and far_and_inside["containing_part"][1] == 0
    # Without the interiors (stored by default, as `preprocess --interiors on`) only touching
    # surfaces count.
    vertices, triangles = cube()
    source = tmp_path / "cube.off"
    tetrapage.write_mesh(source, (vertices, triangles))
    tetrapage.preprocess(source, tmp_path / "surface.tpi", interiors=False)
    surface_only = tetrapage.Index(tmp_path / "surface.tpi")
    assert not surface_only.object(*corner_tetrahedron()).collides(inside)


def test_distance_is_the_gap(cube_index):
    obj = tetrapage.Index(cube_index).object(*corner_tetrahedron())
    far = obj.distance(pose(1.25, 0.5, 0.5))
    assert far.separation == "apart"
    assert far.lower_bound <= 0.25 <= far.upper_bound and abs(far.distance - 0.25) < 1e-15
    assert abs(far.on_environment[0] - 1.0) < 1e-15 and far.environment_part == 0
    assert obj.distance(pose(1.0, 0.5, 0.5)).separation == "touching"
    beyond = obj.distance(pose(1.25, 0.5, 0.5), max_distance=0.125)
    assert beyond.separation == "farther" and beyond.environment_triangle is None


def test_time_of_impact_brackets_the_contact(cube_index):
    obj = tetrapage.Index(cube_index).object(*corner_tetrahedron())
    # From gap 0.5 to gap -0.5: the face is met halfway.
    hit = obj.time_of_impact(pose(1.5, 0.5, 0.5), pose(0.5, 0.5, 0.5), tolerance=1e-6)
    assert hit.impact == "hit"
    assert hit.free_until <= 0.5 <= hit.contact_at and hit.contact_at - hit.free_until <= 1e-6
    assert hit.environment_part == 0 and hit.environment_triangle is not None
    miss = obj.time_of_impact(pose(1.5, 0.5, 0.5), pose(1.5, 0.5, 2.0))
    assert miss.impact == "none" and miss.free_until == 1.0


def test_progress_is_told_and_an_exception_stops_the_run(tmp_path):
    vertices, triangles = cube()
    source = tmp_path / "cube.obj"
    tetrapage.write_mesh(source, tetrapage.Mesh(vertices, triangles))
    calls = []
    summary = tetrapage.preprocess([source], tmp_path / "told.tpi",
                                   progress=lambda stage, done, total: calls.append((stage, done, total)))
    assert summary["triangles_read"] == 12 and summary["parts"] == 1
    stages = [stage for stage, _, _ in calls]
    assert "reading parts" in stages and "building shards" in stages
    assert all(done <= total for _, done, total in calls if total)

    class Stop(Exception):
        pass

    def stop(stage, done, total):
        raise Stop(stage)

    output = tmp_path / "stopped.tpi"
    with pytest.raises(Stop):
        tetrapage.preprocess([source], output, progress=stop)
    assert not output.exists()
    assert [p.name for p in tmp_path.iterdir() if p.name.startswith("stopped")] == []


def test_meshes_round_trip_through_files(tmp_path):
    vertices, triangles = cube(-2.5, 1e9)
    mesh = tetrapage.Mesh(vertices, triangles, part_of=[0] * 6 + [1] * 6, part_names=["a", "b"])
    for name in ("m.ply", "m.obj"):
        tetrapage.write_mesh(tmp_path / name, mesh)
        back = tetrapage.read_mesh(tmp_path / name)
        np.testing.assert_array_equal(back.vertices[back.triangles], vertices[triangles])
        assert back.part_names == ["a", "b"]
        np.testing.assert_array_equal(back.part_of, mesh.part_of)
    poses = np.array([pose(0.1, 1e-9, -3e9), [0, 0, 0, 0.5, 0.5, 0.5, 0.5]])
    tetrapage.write_poses(tmp_path / "p.csv", poses)
    np.testing.assert_array_equal(tetrapage.read_poses(tmp_path / "p.csv"), poses)


def test_the_version_is_the_commands(tmp_path):
    from conftest import run_cli
    assert run_cli("--version").split()[1] == tetrapage.__version__


def test_meshes_convert_between_units(tmp_path):
    vertices, triangles = corner_tetrahedron(1.0)
    mesh = tetrapage.Mesh(vertices, triangles)
    assert mesh.length_unit == ""
    in_mm = mesh.in_unit("mm", from_unit="m")
    assert in_mm.length_unit == "mm"
    np.testing.assert_array_equal(in_mm.vertices, vertices * 1000)
    np.testing.assert_array_equal(in_mm.in_unit("m").vertices, vertices)
    np.testing.assert_allclose(in_mm.in_unit("in").vertices, vertices / 0.0254, rtol=1e-15)
    with pytest.raises(tetrapage.InputError, match="states no unit"):
        mesh.in_unit("mm")
    with pytest.raises(tetrapage.InputError, match="furlong"):
        mesh.in_unit("mm", from_unit="furlong")
    with pytest.raises(tetrapage.InputError, match="but the mesh states mm"):
        in_mm.in_unit("m", from_unit="in")
    np.testing.assert_array_equal(mesh.scaled(0.5).vertices, vertices * 0.5)
    with pytest.raises(tetrapage.InputError):
        mesh.scaled(-1.0)
