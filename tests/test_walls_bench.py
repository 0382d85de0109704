"""The walls-under-a-turn benchmark's pieces, on hand-made data with known answers."""

from __future__ import annotations

import json

import numpy as np
from benchmarks import bench_walls as W

from ontodetect import point_cloud
from ontodetect.io import write_cloud


def test_disagreement_is_the_share_of_either_that_only_one_holds():
    a = np.array([1, 1, 1, 1, 0, 0], bool)
    b = np.array([1, 1, 0, 0, 1, 0], bool)
    assert W.disagreement(a, b) == 3 / 5
    assert W.disagreement(a, a) == 0.0
    assert W.disagreement(np.zeros(3, bool), np.zeros(3, bool)) == 0.0


def _room(rng) -> np.ndarray:
    """A 4 x 3 m floor and four walls to 2.4 m, 3 cm apart, jittered."""
    g = np.mgrid[0:4:0.03, 0:3:0.03].reshape(2, -1).T
    floor = np.c_[g, np.zeros(len(g))]
    walls = []
    for length, place in (
        (4.0, lambda s, z: (s, 0 * s, z)),
        (4.0, lambda s, z: (s, 0 * s + 3, z)),
        (3.0, lambda s, z: (0 * s, s, z)),
        (3.0, lambda s, z: (0 * s + 4, s, z)),
    ):
        s, z = np.mgrid[0:length:0.03, 0:2.4:0.03].reshape(2, -1)
        walls.append(np.c_[place(s, z)])
    pts = np.vstack([floor, *walls])
    return pts + rng.normal(0.0, 0.002, pts.shape)


def test_plain_walls_do_not_move_with_the_turn(tmp_path, capsys):
    rng = np.random.default_rng(3)
    scan = tmp_path / "room-s0"
    scan.mkdir()
    write_cloud(scan / "cloud.ply", point_cloud(_room(rng)))
    (tmp_path / "not-a-scan").mkdir()
    out = tmp_path / "walls.json"
    assert W.main(["--sim", str(tmp_path), "--out", str(out)]) == 0
    report = json.loads(out.read_text())
    assert report["summary"]["scans"] == 1
    (row,) = report["scans"]
    assert row["scan"] == "room-s0"
    assert row["wall_points"] > 0.9 * 4 * (4 + 3) * 2.4 / 0.03**2 / 2  # most of the walls
    assert max(row["moved"]) < 0.01
    assert "scans over 0.1: 0 of 1" in capsys.readouterr().out
