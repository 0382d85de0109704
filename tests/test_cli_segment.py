"""``ontodetect segment`` run in-process on a generated scan."""

from __future__ import annotations

import json

import numpy as np
import pytest

from ontodetect import point_cloud, read_cloud, write_cloud
from ontodetect.cli import main


def rect(rng, corner, u, v, spacing=0.02):
    corner, u, v = (np.asarray(a, dtype=float) for a in (corner, u, v))
    nu = max(2, int(np.linalg.norm(u) / spacing))
    nv = max(2, int(np.linalg.norm(v) / spacing))
    s, t = np.meshgrid((np.arange(nu) + rng.random(nu)) / nu, (np.arange(nv) + rng.random(nv)) / nv)
    return corner + s.reshape(-1, 1) * u + t.reshape(-1, 1) * v


def slab(rng, lo, hi):
    lo, hi = np.asarray(lo, float), np.asarray(hi, float)
    ex, ey, ez = np.diag(hi - lo)
    faces = [(lo + ez, ex, ey), (lo, ex, ez), (lo + ey, ex, ez), (lo, ey, ez), (lo + ex, ey, ez)]
    return np.vstack([rect(rng, c, u, v, 0.015) for c, u, v in faces])


@pytest.fixture
def scan(tmp_path):
    """A floor 30 cm below z = 0 with a low table and a stool on it, as a PLY file."""
    rng = np.random.default_rng(11)
    floor = rect(rng, (0, 0, 0), (3, 0, 0), (0, 3, 0), 0.03)
    table = slab(rng, (0.5, 0.5, 0.0), (1.5, 1.1, 0.7))
    stool = slab(rng, (2.0, 2.0, 0.0), (2.4, 2.4, 0.45))
    pts = np.vstack([floor, table, stool]) - [0, 0, 0.3]
    colors = np.full((len(pts), 3), 200, dtype=np.uint8)
    path = tmp_path / "scan.ply"
    write_cloud(path, point_cloud(pts, colors))
    return path, len(pts)


def test_segment_writes_ply_and_json(scan, tmp_path, capsys):
    path, n = scan
    out = tmp_path / "seg"
    code = main(["segment", str(path), "-o", str(out), "--set", "cluster.radius=0.04"])
    captured = capsys.readouterr()
    assert code == 0, captured.err
    ply, js = out / "segments.ply", out / "planes.json"
    assert ply.is_file() and js.is_file()
    data = json.loads(js.read_text())
    assert data["format"] == "ontodetect.segmentation/1"
    assert data["config"]["cluster"]["radius"] == 0.04
    assert data["frame"]["ground_z"] == pytest.approx(-0.3, abs=0.01)
    assert data["num_clusters"] >= 2
    assert all("planes" in c and "flags" in c for c in data["clusters"])
    cloud = read_cloud(ply)
    assert len(cloud) == n
    assert {"cluster", "plane"} <= set(cloud.fields)
    clusters = np.asarray(cloud.fields["cluster"])
    assert set(np.unique(clusters)) >= {-1, 0, 1}
    # Points stay in the input frame: the floor is still at z = -0.3.
    assert cloud.xyz[:, 2].min() == pytest.approx(-0.3, abs=0.01)
    assert "clusters" in captured.out and "wrote" in captured.out
    # Seconds go to timings.json: the same input and seed write the same planes.json.
    assert "timings" not in data["prepare"]
    assert json.loads((out / "timings.json").read_text())
    again = tmp_path / "again"
    assert main(["-q", "segment", str(path), "-o", str(again), "--set", "cluster.radius=0.04"]) == 0
    assert (again / "planes.json").read_bytes() == js.read_bytes()


def test_config_file_and_verbose(scan, tmp_path, capsys):
    path, _ = scan
    cfg = tmp_path / "cfg.yaml"
    cfg.write_text("cluster:\n  method: dbscan\n")
    code = main(["-v", "segment", str(path), "-o", str(tmp_path / "o"), "--config", str(cfg)])
    captured = capsys.readouterr()
    assert code == 0, captured.err
    data = json.loads((tmp_path / "o" / "planes.json").read_text())
    assert data["method"] == "dbscan"


@pytest.mark.parametrize(
    ("args", "message"),
    [
        (["--set", "cluster.radius=-1"], "'cluster.radius' parameter must be a float"),
        (["--set", "cluster.radiuss=1"], "unknown configuration key 'cluster.radiuss'"),
        (["--set", "radius"], "section.key=value"),
        (["--up", "w"], "'--up' parameter must be one of 'z', '-z', 'y', '-y', 'x', '-x', 'auto'"),
    ],
)
def test_bad_options_exit_2(scan, tmp_path, capsys, args, message):
    path, _ = scan
    code = main(["segment", str(path), "-o", str(tmp_path / "o"), *args])
    captured = capsys.readouterr()
    assert code == 2
    assert captured.err.startswith("error:")
    assert message in " ".join(captured.err.split())


def test_bad_config_file_exits_2(scan, tmp_path, capsys):
    path, _ = scan
    cfg = tmp_path / "cfg.yaml"
    cfg.write_text("planes:\n  treshold: 0.01\n")
    code = main(["segment", str(path), "-o", str(tmp_path / "o"), "--config", str(cfg)])
    captured = capsys.readouterr()
    assert code == 2
    assert "cfg.yaml" in captured.err and "planes.treshold" in captured.err


def test_missing_input_exits_2(tmp_path, capsys):
    code = main(["segment", str(tmp_path / "nope.ply"), "-o", str(tmp_path / "o")])
    assert code == 2
    assert "no such file" in capsys.readouterr().err
