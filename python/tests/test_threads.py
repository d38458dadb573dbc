"""One Index shared by Python threads, each with its own object: the answers are those of one
thread, and queries release the GIL (other Python code runs meanwhile)."""

import threading
from concurrent.futures import ThreadPoolExecutor

import numpy as np

import tetrapage
from conftest import corner_tetrahedron, cube, pose


def test_threads_share_an_index(demo):
    index = tetrapage.Index(demo / "scene.tpi", memory="8M")
    mesh = tetrapage.Model(tetrapage.read_mesh(demo / "object.ply"))  # shared by the threads
    poses = tetrapage.read_poses(demo / "flight.csv")
    expected = index.object(mesh).collides(poses)
    assert expected.any()

    def fly(offset):
        # Each thread starts elsewhere on the flight: the threads page different shards at once.
        order = np.roll(np.arange(len(poses)), offset)
        answers = index.object(mesh).collides(poses[order])
        return np.array_equal(answers, expected[order])

    with ThreadPoolExecutor(max_workers=4) as pool:
        assert all(pool.map(fly, [0, 250, 500, 750]))


def test_one_object_used_by_two_threads_waits_its_turn(demo):
    index = tetrapage.Index(demo / "scene.tpi")
    obj = index.object(tetrapage.read_mesh(demo / "object.ply"))
    poses = tetrapage.read_poses(demo / "flight.csv")
    expected = index.object(tetrapage.read_mesh(demo / "object.ply")).collides(poses)
    with ThreadPoolExecutor(max_workers=2) as pool:
        results = list(pool.map(lambda _: obj.collides(poses), range(4)))
    for answers in results:
        np.testing.assert_array_equal(answers, expected)


def test_queries_release_the_gil(demo):
    index = tetrapage.Index(demo / "scene.tpi")
    obj = index.object(tetrapage.read_mesh(demo / "object.ply"))
    poses = np.tile(tetrapage.read_poses(demo / "flight.csv"), (20, 1))
    running = threading.Event()
    done = threading.Event()
    ticks = []

    def count():
        running.set()
        while not done.is_set():
            ticks.append(None)

    counter = threading.Thread(target=count)
    counter.start()
    running.wait()
    before = len(ticks)
    obj.collides(poses)  # tens of milliseconds in C++: the counter runs only if the GIL is free
    during = len(ticks) - before
    done.set()
    counter.join()
    assert during > 0


def test_obstacles_change_while_threads_fly(cube_index):
    index = tetrapage.Index(cube_index)
    obstacles = tetrapage.Obstacles(index)
    block = cube(0.0, 0.25)
    part = obstacles.insert(block, pose(2.0, 0.0, 0.0), name="block")
    poses = np.array([pose(2.0 + 0.001 * k, 0.1, 0.1) for k in range(200)])
    stop = threading.Event()

    def mover():
        k = 0
        while not stop.is_set():
            obstacles.move(part, pose(2.0 if k % 2 else 5.0, 0.0, 0.0))
            k += 1

    def fly(_):
        obj = index.object(*corner_tetrahedron())
        obj.obstacles = obstacles
        for _ in range(20):
            answers = obj.collides(poses)
            # The block is either here (every pose meets it) or far away (none does).
            if answers.any() and not answers.all():
                return False
        return True

    moving = threading.Thread(target=mover)
    moving.start()
    with ThreadPoolExecutor(max_workers=2) as pool:
        results = list(pool.map(fly, range(2)))
    stop.set()
    moving.join()
    assert all(results)
