import json

import pytest

from ontodetect.errors import CorruptFileError
from ontodetect.io._detections import read_detections, write_detections


def doc(**over):
    d = {
        "format": "ontodetect.detections/1",
        "source": "scan.ply",
        "num_points": 100,
        "frame": {"up": [0, 0, 1], "ground_z": 0.0, "scale": 1.0},
        "detections": [
            {
                "id": 1,
                "label": "chair",
                "score": 0.6,
                "probabilities": {"chair": 0.6},
                "costs": {"chair": 0.4},
                "box": {"center": [1, 2, 0.4], "size": [0.5, 0.5, 0.9], "yaw": 0.3},
                "point_indices": list(range(10, 30)),
                "parts": [],
            }
        ],
    }
    d.update(over)
    return d


def test_round_trip_and_compact_indices(tmp_path):
    p = write_detections(tmp_path / "detections.json", doc())
    text = p.read_text()
    assert '"point_indices": [10, 11, 12' in text
    assert read_detections(tmp_path) == json.loads(text)


@pytest.mark.parametrize(
    ("change", "where"),
    [
        ({"format": "x"}, "format"),
        ({"num_points": -1}, "num_points"),
        ({"frame": {}}, "frame"),
    ],
)
def test_contract_violations_name_the_key(tmp_path, change, where):
    with pytest.raises(CorruptFileError, match=where):
        write_detections(tmp_path / "d.json", doc(**change))
    assert not (tmp_path / "d.json").exists()


def test_indices_out_of_range(tmp_path):
    bad = doc()
    bad["detections"][0]["point_indices"] = [5, 100]
    with pytest.raises(CorruptFileError, match=r"detections\[0\].point_indices"):
        write_detections(tmp_path / "d.json", bad)


def test_bad_json(tmp_path):
    (tmp_path / "detections.json").write_text("{oops")
    with pytest.raises(CorruptFileError, match="not valid JSON"):
        read_detections(tmp_path / "detections.json")
