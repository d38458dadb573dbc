"""The module answers as `tetrapage fly` does on the demo flight, and as the reference oracle."""

import numpy as np

import tetrapage
from conftest import read_csv


def open_demo(demo):
    index = tetrapage.Index(demo / "scene.tpi")
    return index, index.object(tetrapage.read_mesh(demo / "object.ply"))


def test_collides_equals_fly_and_the_oracle(demo):
    _, obj = open_demo(demo)
    poses = tetrapage.read_poses(demo / "flight.csv")
    answers = obj.collides(poses)
    assert answers.dtype == np.bool_ and answers.shape == (len(poses),)
    fly = np.array([row["collides"] == "1" for row in read_csv(demo / "fly.csv")])
    oracle = np.array([row["collides"] == "1" for row in read_csv(demo / "oracle.csv")])
    assert 0 < fly.sum() < len(fly), "the flight must both collide and fly free"
    np.testing.assert_array_equal(answers, fly)
    np.testing.assert_array_equal(answers, oracle)


def test_one_pose_at_a_time_equals_the_batch(demo):
    _, batch_object = open_demo(demo)
    _, single_object = open_demo(demo)
    poses = tetrapage.read_poses(demo / "flight.csv")[:200]
    singles = [single_object.collides(p) for p in poses]
    assert all(isinstance(answer, bool) for answer in singles)
    np.testing.assert_array_equal(batch_object.collides(poses), singles)


def quaternion_matrix(q):
    w, x, y, z = q
    return np.array([[1 - 2 * (y * y + z * z), 2 * (x * y - w * z), 2 * (x * z + w * y)],
                     [2 * (x * y + w * z), 1 - 2 * (x * x + z * z), 2 * (y * z - w * x)],
                     [2 * (x * z - w * y), 2 * (y * z + w * x), 1 - 2 * (x * x + y * y)]])


def test_matrices_give_the_same_answers(demo):
    # Rotations by quarter turns are exact both as quaternions and as matrices.
    half = np.sqrt(0.5)
    turns = [(1, 0, 0, 0), (half, half, 0, 0), (0, 0, 1, 0), (half, 0, 0, half)]
    poses = tetrapage.read_poses(demo / "flight.csv")[::3]
    as_rows, as_matrices = [], []
    for k, p in enumerate(poses):
        q = turns[k % len(turns)]
        as_rows.append([*p[:3], *q])
        m = np.eye(4)
        m[:3, :3] = quaternion_matrix(q)
        m[:3, 3] = p[:3]
        as_matrices.append(m)
    _, a = open_demo(demo)
    _, b = open_demo(demo)
    rows = a.collides(np.array(as_rows))
    assert rows.any() and not rows.all()
    np.testing.assert_array_equal(rows, b.collides(np.array(as_matrices)))


def test_distances_equal_fly(demo):
    _, obj = open_demo(demo)
    poses = tetrapage.read_poses(demo / "flight.csv")
    records = obj.distances(poses)
    rows = read_csv(demo / "distance.csv")
    assert len(rows) == len(poses)
    expected = np.array([float(row["distance"]) for row in rows])
    np.testing.assert_array_equal(records["distance"], expected)
    touching = np.array([row["separation"] == "touching" for row in rows])
    np.testing.assert_array_equal(records["separation"] == tetrapage.TOUCHING, touching)
    apart = records["separation"] == tetrapage.APART
    assert apart.any()
    assert np.all(records["lower_bound"][apart] <= records["distance"][apart])
    assert np.all(records["distance"][apart] <= records["upper_bound"][apart])
    gap = np.linalg.norm(records["on_environment"] - records["on_object"], axis=1)
    np.testing.assert_allclose(gap[apart], records["distance"][apart], rtol=1e-12)


def test_contacts_equal_fly(demo):
    _, obj = open_demo(demo)
    poses = tetrapage.read_poses(demo / "flight.csv")
    expected = {}
    for row in read_csv(demo / "contacts.csv"):
        if row["kind"] in ("object_inside", "obstacle_inside"):
            continue  # a containment row: no triangle pair (the answer's containment says it)
        expected.setdefault(int(row["step"]), set()).add(
            (int(row["environment_triangle"]), int(row["object_triangle"])))
    found = {}
    for step, p in enumerate(poses):
        answer = obj.query(p, mode="all_contacts")
        if answer.collides:
            contacts = answer.contacts
            found[step] = set(zip(contacts["environment_triangle"].tolist(),
                                  contacts["object_triangle"].tolist()))
            assert np.all(contacts["shape"] > 0)
            assert np.all(np.isfinite(contacts["point"]))
            assert set(answer.counters) >= {"candidates", "triangle_tests", "shard_misses"}
    assert found and found == expected


def test_times_of_impact_equal_fly(demo):
    _, obj = open_demo(demo)
    poses = tetrapage.read_poses(demo / "flight.csv")
    records = obj.times_of_impact(poses)
    rows = read_csv(demo / "toi.csv")
    assert len(rows) == len(poses) == len(records)
    names = {"none": tetrapage.IMPACT_NONE, "hit": tetrapage.IMPACT_HIT,
             "unresolved": tetrapage.IMPACT_UNRESOLVED}
    np.testing.assert_array_equal(records["impact"], [names[row["impact"]] for row in rows])
    assert (records["impact"] == tetrapage.IMPACT_HIT).any()
    np.testing.assert_array_equal(records["free_until"], [float(row["free_until"]) for row in rows])
    np.testing.assert_array_equal(records["contact_at"], [float(row["contact_at"]) for row in rows])
    hits = records["impact"] == tetrapage.IMPACT_HIT
    assert np.all(records["contact_at"][hits] - records["free_until"][hits] <= 1e-4)
