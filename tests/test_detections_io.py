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


# -- the shipped JSON Schema ------------------------------------------------------------
def _schema_errors(document):
    import jsonschema

    from ontodetect.io import detections_schema

    validator = jsonschema.Draft202012Validator(detections_schema())
    return [f"{e.json_path}: {e.message}" for e in validator.iter_errors(document)]


def test_the_shipped_schema_is_a_valid_draft_2020_12_schema():
    import jsonschema

    from ontodetect.io import detections_schema

    schema = detections_schema()
    assert schema["$schema"] == "https://json-schema.org/draft/2020-12/schema"
    jsonschema.Draft202012Validator.check_schema(schema)
    assert detections_schema() is not detections_schema()  # a fresh copy each call


def test_what_the_writer_writes_validates_against_the_schema(tmp_path):
    p = write_detections(tmp_path / "detections.json", doc())
    assert _schema_errors(json.loads(p.read_text())) == []


def test_a_detection_result_validates_against_the_schema():
    from ontodetect.config import Config
    from ontodetect.pipeline import detect
    from ontodetect.synth import synthesize

    result = detect(synthesize("tiny", seed=1).cloud, config=Config().replace(detect={"votes": 1}))
    document = json.loads(json.dumps(result.to_dict()))
    assert document["detections"] and _schema_errors(document) == []


@pytest.mark.parametrize(
    ("change", "word"),
    [
        ({"format": "x"}, "format"),
        ({"num_points": -1}, "minimum"),
        ({"frame": {}}, "up"),
        ({"detections": [{"id": 1, "label": "chair", "score": 0.5}]}, "box"),
    ],
)
def test_the_schema_refuses_what_the_reader_refuses(change, word):
    errors = _schema_errors(doc(**change))
    assert errors and any(word in e for e in errors)


def test_the_example_in_the_docs_validates():
    import re
    from pathlib import Path

    text = (Path(__file__).parents[1] / "docs" / "detections-format.md").read_text("utf-8")
    example = re.search(r"## An example\s+```json\n(.*?)```", text, re.S).group(1)
    assert _schema_errors(json.loads(example)) == []
