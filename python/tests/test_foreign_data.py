"""Data this project did not make: Debian's assimp test models, a closed figure in a float binary
STL and an open sphere with a hole in an ASCII STL, in one assembly. Python preprocesses it and
flies through it; CGAL's reference oracle (`tetrapage generate flight --answers`), which shares
no code with the runtime, decides every pose."""

import json
from pathlib import Path

import numpy as np
import pytest

import tetrapage
from conftest import read_csv, run_cli

MODELS = Path("/usr/share/assimp/models/STL")


@pytest.mark.skipif(not (MODELS / "Wuson.stl").exists(), reason="assimp-testmodels is not installed")
def test_python_answers_as_the_oracle_on_foreign_meshes(tmp_path):
    assembly = tmp_path / "assembly.json"
    assembly.write_text(json.dumps({"parts": [
        {"name": "wuson", "file": str(MODELS / "Wuson.stl")},
        {"name": "sphere with a hole", "file": str(MODELS / "sphereWithHole.stl"),
         "instances": [{"translation": [-1.5, 0.0, -1.5], "rotation": [1, 0, 0, 0], "scale": 1}]},
    ]}))
    run_cli("generate", "object", "--triangles", 200, "--size", 0.2, "-o", tmp_path / "object.ply")
    run_cli("generate", "flight", "--env", assembly, "--object", tmp_path / "object.ply",
            "--steps", 1500, "--seed", 3, "--displacement", 0.02, "-o", tmp_path / "flight.csv",
            "--answers", tmp_path / "oracle.csv")
    oracle = np.array([row["collides"] == "1" for row in read_csv(tmp_path / "oracle.csv")])
    assert 0 < oracle.sum() < len(oracle)

    summary = tetrapage.preprocess(assembly, tmp_path / "assembly.tpi")
    assert summary["parts"] == 2 and summary["precision"] == "exact"
    index = tetrapage.Index(tmp_path / "assembly.tpi")
    assert [part.name for part in index.parts] == ["wuson", "sphere with a hole"]
    obj = index.object(tetrapage.read_mesh(tmp_path / "object.ply"))
    poses = tetrapage.read_poses(tmp_path / "flight.csv")
    np.testing.assert_array_equal(obj.collides(poses), oracle)
    # Each collision names a part, and its contacts' points lie in the model's box.
    for k in np.flatnonzero(oracle)[:20]:
        answer = obj.query(poses[k], mode="all_contacts")
        assert answer.collides
        points = answer.contacts["point"][answer.contacts["shape"] > 0]
        assert np.all(points >= index.bounds[0] - 1e-9) and np.all(points <= index.bounds[1] + 1e-9)
