"""The pipeline on simulated rooms: what it finds, determinism, index mapping, the demo."""

import math

import numpy as np
import pytest

from ontodetect import InvalidParameterError, point_cloud
from ontodetect.demo import run_demo
from ontodetect.pipeline import detect
from ontodetect.synth import synthesize


@pytest.fixture(scope="module")
def dining():
    return synthesize("dining_room", "rgbd", seed=11, points=60_000).cloud


def test_same_input_and_seed_same_output(dining):
    a = detect(dining, seed=4).to_dict()
    b = detect(dining, seed=4).to_dict()
    a.pop("timings"), b.pop("timings")
    assert a == b


def test_detections_are_mostly_their_objects(dining):
    result = detect(dining, room="dining_room")
    truth = dining.fields["class_id"]
    names = {5: "chair", 6: "sofa", 7: "table", 14: "table"}
    labels = [d.label for d in result.detections]
    assert labels.count("chair") >= 2 and "table" in labels
    for d in result.detections:
        ids, counts = np.unique(truth[d.point_indices], return_counts=True)
        assert names.get(int(ids[np.argmax(counts)])) == d.label, d


def test_point_indices_are_rows_of_the_input_file(dining):
    # Put NaN rows in front of every fifth point: detections must still name file rows.
    n = len(dining)
    xyz = np.full((n + n // 5 + 1, 3), np.nan)
    keep = np.setdiff1d(np.arange(len(xyz)), np.arange(0, len(xyz), 6))[:n]
    xyz[keep] = dining.xyz
    rgb = np.zeros((len(xyz), 3), np.uint8)
    rgb[keep] = dining.rgb
    holey = point_cloud(xyz, rgb=rgb, on_nonfinite="drop")
    plain = detect(dining)
    mapped = detect(holey)
    assert [d.label for d in mapped.detections] == [d.label for d in plain.detections]
    for a, b in zip(plain.detections, mapped.detections):
        assert np.array_equal(keep[a.point_indices], b.point_indices)


def test_bad_inputs():
    with pytest.raises(InvalidParameterError, match="'cloud'"):
        detect(np.zeros((10, 3)))
    with pytest.raises(InvalidParameterError, match="none_likelihood"):
        detect(point_cloud(np.zeros((10, 3))), none_likelihood=0)


def test_demo_runs_and_scores_itself(tmp_path):
    d = run_demo(tmp_path, room="tiny", seed=2)
    assert (tmp_path / "scan" / "cloud.ply").exists()
    assert d.files.detections.exists() and d.files.picture.exists()
    assert d.evaluation.per_class["chair"].num_gt == 1
    assert d.evaluation.overall.tp >= 1


def test_shelter_is_the_highest_top_beside_a_cluster():
    from types import SimpleNamespace

    from ontodetect.pipeline import shelter_heights

    def plane(tilt, height, area):
        return SimpleNamespace(tilt=tilt, height=height, area=area)

    def box(cx, cy, sx, sy, yaw=0.0):
        return SimpleNamespace(center=np.array([cx, cy, 0.5]), size=np.array([sx, sy, 1.0]),
                               yaw=yaw)

    desk = SimpleNamespace(planes=[plane(1, 0.74, 1.2), plane(88, 0.4, 0.5)],
                           box=box(0, 0, 1.6, 0.8))
    backrest = SimpleNamespace(planes=[plane(70, 0.8, 0.15)], box=box(0, 0.7, 0.45, 0.25))
    # A 45-degree turn of a 0.4 m square reaches 0.28 m from its centre.
    far = SimpleNamespace(planes=[plane(2, 0.45, 0.2)], box=box(1.6, 0, 0.4, 0.4, math.pi / 4))
    got = shelter_heights([desk, backrest, far])
    assert got[1] == pytest.approx(0.74)  # the desk stands beside the backrest
    assert got[0] == -math.inf  # the backrest has no large horizontal plane
    # the rotated box's footprint reaches 1.32 m: 0.52 m from the desk, beyond the gap
    assert got[2] == -math.inf
    assert shelter_heights([]).shape == (0,)
