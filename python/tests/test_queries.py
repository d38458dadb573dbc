"""Several objects and obstacles that change, on scenes whose answers are known in closed form."""

import numpy as np

import tetrapage
from conftest import corner_tetrahedron, cube, pose


def test_group_pairs_and_containment():
    group = tetrapage.ObjectGroup([corner_tetrahedron(), corner_tetrahedron(), cube()])
    assert len(group) == 3
    # 0's corner (0.125, 0, 0) is 1's origin: they touch at a point; 2 is far away.
    answer = group.step(np.array([pose(0, 0, 0), pose(0.125, 0, 0), pose(10, 10, 10)]))
    assert answer.environment.shape == (0,)
    assert [(p["first"], p["second"]) for p in answer.pairs] == [(0, 1)]
    pair = answer.pairs[0]
    assert pair["containment"] == 0 and pair["triangle_pairs_end"] > pair["triangle_pairs_begin"]
    apart = group.step(np.array([pose(0, 0, 0), pose(0.125 + 2.0**-30, 0, 0), pose(10, 10, 10)]))
    assert len(apart.pairs) == 0
    # Object 0 inside the cube (object 2): no surfaces touch, the cube holds it.
    inside = group.step(np.array([pose(10.25, 10.25, 10.25), pose(0, 0, 0), pose(10, 10, 10)]))
    assert [(p["first"], p["second"], p["containment"]) for p in inside.pairs] == [(0, 2, 1)]
    every = group.step(np.array([pose(0, 0, 0), pose(0.0625, 0, 0), pose(10, 10, 10)]),
                       pair_mode="all_contacts")
    assert len(every.triangle_pairs) > 1 and every.triangle_pairs.shape[1] == 2


def test_group_against_the_environment(cube_index):
    index = tetrapage.Index(cube_index)
    group = tetrapage.ObjectGroup([corner_tetrahedron(), corner_tetrahedron()], index)
    answer = group.step(np.array([pose(1.0, 0.5, 0.5), pose(1.5, 0.5, 0.5)]), parallel=True)
    np.testing.assert_array_equal(answer.environment, [True, False])
    assert answer.world_boxes.shape == (2, 2, 3)


def test_obstacles_inserted_moved_hidden_saved(cube_index, tmp_path):
    index = tetrapage.Index(cube_index)
    obj = index.object(*corner_tetrahedron())
    obstacles = tetrapage.Obstacles(index)
    obj.obstacles = obstacles
    free = pose(2.0, 0.5, 0.5)
    assert not obj.collides(free)
    block = obstacles.insert(cube(0.0, 0.25), pose(2.0625, 0.5, 0.5), name="block")
    assert block > 0 and obstacles.parts == [(block, "block")] and len(obstacles) == 1
    answer = obj.query(free, mode="all_contacts")
    assert answer.collides and set(answer.contacts["dynamic_part"]) == {block}
    obstacles.move(block, pose(4.0, 0.5, 0.5))
    assert not obj.collides(free)
    obstacles.move(block, pose(2.0625, 0.5, 0.5))
    saved = tmp_path / "scene.obstacles"
    obstacles.save(saved)
    obstacles.remove(block)
    assert not obj.collides(free) and len(obstacles) == 0
    # Hiding the cube frees a pose that touches it.
    touching = pose(1.0, 0.5, 0.5)
    assert obj.collides(touching)
    obstacles.hide_part(0)
    assert obstacles.hidden_parts == [0] and not obj.collides(touching)
    obstacles.show_part(0)
    assert obj.collides(touching)
    # What was saved comes back.
    loaded = tetrapage.Obstacles.load(index, saved)
    obj.obstacles = loaded
    assert obj.collides(free) and loaded.parts == [(block, "block")]
    obj.obstacles = None
    assert not obj.collides(free) and obj.obstacles is None


def test_a_model_is_shared_by_objects_obstacles_and_groups(cube_index):
    index = tetrapage.Index(cube_index)
    model = tetrapage.Model(*corner_tetrahedron())
    assert model.triangles == 4 and model.closed
    np.testing.assert_array_equal(model.bounds, [[0, 0, 0], [0.125, 0.125, 0.125]])
    poses = np.array([pose(1.0 + gap, 0.5, 0.5) for gap in (0.25, 0.0, -0.5)])
    from_model = index.object(model).collides(poses)
    np.testing.assert_array_equal(from_model, index.object(*corner_tetrahedron()).collides(poses))
    np.testing.assert_array_equal(from_model, [False, True, True])
    # One model inserted many times: each copy is its own part.
    obstacles = tetrapage.Obstacles(index)
    ids = [obstacles.insert(model, pose(3.0 + k, 0.0, 0.0)) for k in range(5)]
    assert len(set(ids)) == 5 and len(obstacles) == 5
    flying = index.object(model)
    flying.obstacles = obstacles
    assert flying.collides(pose(5.0625, 0.0, 0.0)) and not flying.collides(pose(5.5, 0.0, 0.0))
    group = tetrapage.ObjectGroup([model, model])
    assert len(group.step(np.array([pose(0, 0, 0), pose(0.125, 0, 0)])).pairs) == 1
