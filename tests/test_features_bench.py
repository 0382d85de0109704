"""benchmarks/bench_features.py: what a measure reads on every cluster, by what it is."""

from __future__ import annotations

import json
import math

import numpy as np
import pytest
from benchmarks import bench_features as F
from hypothesis import given
from hypothesis import strategies as st

from ontodetect.errors import InvalidParameterError
from ontodetect.evaluation import SceneSource
from ontodetect.synth import load_synth, synthesize, write_synth

finite = st.floats(-10, 10, allow_nan=False)


@given(finite, finite)
def test_a_bound_reads_back_whatever_its_order(a, b):
    low, high = min(a, b), max(a, b)
    assert F.parse_bound(f"min={low!r},max={high!r}") == (low, high)
    assert F.parse_bound(f"max={high!r},min={low!r}") == (low, high)
    assert F.parse_bound(f"max={high!r}") == (-math.inf, high)


@pytest.mark.parametrize("text", ["min=", "low=0.3", "min=0.5,max=0.1", "max=nan", "0.3"])
def test_a_bad_bound_names_the_option(text):
    with pytest.raises(InvalidParameterError, match="--bound"):
        F.parse_bound(text)


def test_a_survey_knows_its_scope_and_checks_its_feature():
    assert (F.Survey("sunk").scope, F.Survey("sunk").name) == ("part", "sunk")
    survey = F.Survey("cluster.height")
    assert (survey.scope, survey.name) == ("cluster", "height")
    assert survey.check() is survey
    with pytest.raises(InvalidParameterError, match=r"cluster\.breadth"):
        F.Survey("cluster.sunk").check()  # a part feature asked of the cluster
    with pytest.raises(InvalidParameterError, match="--feature"):
        F.Survey("seat").check()
    with pytest.raises(InvalidParameterError, match="--height"):
        F.Survey("sunk", height=(0.6, 0.3)).check()


def test_a_survey_of_a_class_names_its_parts():
    survey = F.Survey("backrest~seat.behind", of="chair").check()
    assert (survey.scope, survey.name, survey.parts) == ("relation", "behind", ("backrest", "seat"))
    survey = F.Survey("seat.height", of="chair").check()
    assert (survey.scope, survey.name, survey.parts) == ("part", "height", ("seat",))
    assert F.Survey("cluster.height", of="chair").check().parts == ()
    with pytest.raises(InvalidParameterError, match="parts of chair"):
        F.Survey("wing.height", of="chair").check()
    with pytest.raises(InvalidParameterError, match="A~B"):
        F.Survey("seat~back~arm.gap", of="chair").check()
    with pytest.raises(InvalidParameterError, match=r"--of.*sofa"):
        F.Survey("seat.height", of="throne").check()
    with pytest.raises(InvalidParameterError, match="--feature"):
        F.Survey("seat.height").check()  # a part of a class needs the class
    with pytest.raises(InvalidParameterError, match="--of"):
        F.Survey("seat.height", height=(0.3, 0.6), of="chair").check()


def test_the_summary_counts_quantiles_and_the_share_inside_a_bound():
    rows = [{"kind": "desk", "value": v} for v in (0.0, 0.1, 0.2, 0.3, 1.0)]
    rows += [{"kind": "chair", "value": None}, {"kind": "chair", "value": 0.5}]
    rows += [{"kind": "wall", "value": None}] * 6
    out = F.summarize(rows, (0.15, 0.5))
    assert list(out) == ["desk", "chair", "wall"]  # most measured values first
    assert out["desk"] == {
        "n": 5,
        "nan": 0,
        "quantiles": pytest.approx([0.0, 0.04, 0.2, 0.72, 1.0]),
        "inside": 2,
    }
    assert out["chair"]["nan"] == 1 and out["chair"]["inside"] == 1
    assert F.summarize(rows)["desk"]["inside"] is None
    assert F.summarize([{"kind": "wall", "value": None}])["wall"]["quantiles"] == []
    table = F.summary_table("t", out, (0.15, 0.5))
    assert table.row_count == 3 and len(table.columns) == 9


@pytest.fixture(scope="module")
def dining_room(tmp_path_factory):
    folder = tmp_path_factory.mktemp("features") / "room"
    write_synth(synthesize("dining_room", "rgbd", seed=5, points=30_000), folder)
    return SceneSource("room", str(folder), "ontodetect", "room")


def test_clusters_are_named_by_what_holds_most_of_their_points(dining_room):
    rows = F.measure_scan(dining_room, F.Survey("cluster.height"))
    _, objects, _ = load_synth(dining_room.path)
    kinds = {str(o.get("kind") or o["class"]) for o in objects} | {F.NOTHING}
    assert rows and {r["kind"] for r in rows} <= kinds
    assert all(r["plane"] is None and 0.0 < r["share"] <= 1.0 for r in rows)
    chairs = [r["value"] for r in rows if r["kind"].startswith("chair") and r["share"] > 0.9]
    # A dining chair's cluster is as tall as its backrest, 0.8-0.9 m (EN 12520, catalogue),
    # when it is seen whole; pieces of one (legs, a chair half hidden) are lower.
    assert sum(0.75 < v < 0.95 for v in chairs) >= 4 and max(chairs) < 0.95


def test_part_features_are_read_on_the_planes_the_filters_let_through(dining_room):
    survey = F.Survey("height", tilt=(0.0, 8.0), height=(0.3, 0.62), min_area=0.04)
    rows = F.measure_scan(dining_room, survey)
    assert rows and all(0.3 <= r["value"] <= 0.62 for r in rows)
    seats = [r for r in rows if r["kind"].startswith("chair")]
    assert seats  # the chairs' seats are level planes at seat height
    everything = F.measure_scan(dining_room, F.Survey("height"))
    assert len(everything) > len(rows)
    assert {(r["cluster"], r["plane"]) for r in rows} <= {
        (r["cluster"], r["plane"]) for r in everything
    }


def test_a_class_is_read_on_its_own_best_assignment(dining_room):
    seats = F.measure_scan(dining_room, F.Survey("seat.height", of="chair"))
    behind = F.measure_scan(dining_room, F.Survey("backrest~seat.behind", of="chair"))
    assert [(r["cluster"], r["kind"]) for r in seats] == [(r["cluster"], r["kind"]) for r in behind]
    chairs = [
        (s["value"], b["value"]) for s, b in zip(seats, behind) if s["kind"].startswith("chair")
    ]
    found = [(h, d) for h, d in chairs if h is not None and d is not None]
    assert len(found) >= 4
    # EN 12520 / catalogue dining chairs: seats at 0.42-0.48 m, a seat 0.4-0.45 m deep in
    # front of its backrest (one sits in front of it: its centroid half a seat ahead).
    for height, ahead in found:
        assert 0.35 < height < 0.55 and -0.4 < ahead < -0.1
    # A cluster the chair gives no seat has nothing to read: not measured.
    assert all(r["plane"] is None for r in seats if r["value"] is None)


def test_each_cluster_says_what_the_ontology_reads_it_as(dining_room):
    from ontodetect.ontology import builtin_ontology

    rows = F.measure_scan(dining_room, F.Survey("cluster.height"))
    assert {r["read_as"] for r in rows} <= set(builtin_ontology().names) | {"none"}
    # The dining room's chairs, seen whole, are read as chairs; its walls as nothing.
    chairs = [r for r in rows if r["kind"].startswith("chair") and r["share"] > 0.9]
    assert sum(r["read_as"] in ("chair", "easy_chair") for r in chairs) >= 4
    walls = [r for r in rows if r["kind"] == "wall" and r["share"] > 0.9]
    assert not any(r["read_as"] in ("chair", "easy_chair") for r in walls)


def test_read_as_takes_classes_of_the_ontology():
    assert F.read_as_option(None) is None
    assert F.read_as_option("chair,easy_chair") == {"chair", "easy_chair"}
    for text in ("throne", "chair,throne", " , "):
        with pytest.raises(InvalidParameterError, match="--read-as"):
            F.read_as_option(text)


def test_the_command_writes_every_value_and_refuses_bad_options(dining_room, tmp_path, capsys):
    with pytest.raises(InvalidParameterError, match="--sim-set"):
        F.scan_sources(tmp_path, None)  # no manifest
    out = tmp_path / "values.jsonl"
    # A set's folder: its manifest names its scans.
    (tmp_path / "set").mkdir()
    (tmp_path / "set" / "manifest.json").write_text(json.dumps({"key": {"scans": ["room"]}}))
    (tmp_path / "set" / "room").symlink_to(dining_room.path, target_is_directory=True)
    argv = ["--sim-set", str(tmp_path / "set"), "--feature", "cluster.height", "--jobs", "1"]
    assert F.main([*argv, "--bound", "max=1.3", "--jsonl", str(out)]) == 0
    rows = [json.loads(line) for line in out.read_text().splitlines()]
    assert rows == F.measure_scan(dining_room, F.Survey("cluster.height"))
    assert "cluster.height on 1 scans" in capsys.readouterr().out
    assert F.main([*argv[:2], "--feature", "nope"]) == 2
    assert F.main(["--feature", "sunk"]) == 2
    assert F.main([*argv, "--set", "cluster.nope=1"]) == 2
    assert "cluster.nope" in capsys.readouterr().err
    assert F.main([*argv, "--ontology", str(tmp_path / "none.yaml"), "--ontology-only"]) == 2
    assert "none.yaml" in capsys.readouterr().err
    assert F.main([*argv[:2], "--feature", "seat.tilt", "--of", "chair", "--jobs", "1"]) == 0
    assert "seat.tilt of chair on 1 scans" in capsys.readouterr().out
    only = tmp_path / "chairs.jsonl"
    assert F.main([*argv, "--read-as", "chair,easy_chair", "--jsonl", str(only)]) == 0
    assert "read as chair,easy_chair" in capsys.readouterr().out
    kept = [json.loads(line) for line in only.read_text().splitlines()]
    assert kept == [r for r in rows if r["read_as"] in ("chair", "easy_chair")] and kept
    assert F.main([*argv, "--read-as", "throne"]) == 2
    assert "--read-as" in capsys.readouterr().err
    assert np.isfinite([r["value"] for r in rows]).all()


def test_every_feature_of_an_assignment_is_read_as_one_feature_reads_it(dining_room):
    every = F.measure_scan(dining_room, F.Survey("all", of="chair"))
    seats = F.measure_scan(dining_room, F.Survey("seat.height", of="chair"))
    behind = F.measure_scan(dining_room, F.Survey("backrest~seat.behind", of="chair"))
    cluster = F.measure_scan(dining_room, F.Survey("cluster.height", of="chair"))
    for single in (seats, behind, cluster):
        name = single[0]["feature"]
        same = [(r["cluster"], r["value"]) for r in every if r["feature"] == name]
        assert same == [(r["cluster"], r["value"]) for r in single if r["value"] is not None]
    # A cluster with a seat and a backrest has both orders of their relation, every part
    # feature of both and every cluster feature; one with neither has cluster features only.
    by = {}
    for r in every:
        by.setdefault(r["cluster"], set()).add(r["feature"])
    full = [names for names in by.values() if "seat~backrest.aside" in names]
    assert full
    for names in full:
        assert {"backrest~seat.aside", "seat.height", "backrest.tilt", "cluster.rise"} <= names
    assert all(r["plane"] is None for r in every)
    with pytest.raises(InvalidParameterError, match="all with --of"):
        F.Survey("all").check()
    with pytest.raises(InvalidParameterError, match="--of"):
        F.Survey("all", of="throne").check()


def test_separation_ranks_the_features_by_what_lies_outside_the_kept_range():
    def row(feature, kind, value, share=1.0):
        return {"feature": feature, "kind": kind, "value": value, "share": share}

    rows = [row("h", "chair-office", 0.45), row("h", "chair-dining", 0.5)]
    rows += [row("h", "toilet", 0.41), row("h", "desk", 0.75), row("h", "desk", 0.46)]
    rows += [row("w", "chair-office", 0.3), row("w", "chair-dining", 0.6)]
    rows += [row("w", "toilet", 0.2), row("w", "desk", 0.1), row("w", "desk", 0.9)]
    rows += [row("w", "desk", 5.0, share=0.4), row("w", "chair-x", 9.0, share=0.3)]
    rows += [row("w", "chair-office", None), row("z", "desk", 1.0)]
    out = F.separation(rows, ["chair"])
    assert [s["feature"] for s in out] == ["w", "h"]  # three set apart, then two; z: no chair
    w = out[0]
    assert w["range"] == (0.3, 0.6) and (w["kept"], w["others"]) == (2, 3)
    assert w["below"] == [(0.1, "desk"), (0.2, "toilet")] and w["above"] == [(0.9, "desk")]
    assert out[1]["below"] == [(0.41, "toilet")] and out[1]["above"] == [(0.75, "desk")]
    table = F.separation_table("t", out, top=1)
    assert table.row_count == 1
    assert F.separate_option(" chair ,armchair") == ("chair", "armchair")
    with pytest.raises(InvalidParameterError, match="--separate"):
        F.separate_option(" , ")


def test_the_command_separates_kinds_on_every_feature(dining_room, tmp_path, capsys):
    (tmp_path / "set").mkdir()
    (tmp_path / "set" / "manifest.json").write_text(json.dumps({"key": {"scans": ["room"]}}))
    (tmp_path / "set" / "room").symlink_to(dining_room.path, target_is_directory=True)
    argv = ["--sim-set", str(tmp_path / "set"), "--jobs", "1", "--of", "chair"]
    assert F.main([*argv, "--feature", "all", "--separate", "chair", "--top", "5"]) == 0
    out = capsys.readouterr().out
    assert "set other kinds apart from chair" in out and "really is" not in out
    assert F.main([*argv, "--feature", "seat.height", "--separate", "chair"]) == 0
    out = capsys.readouterr().out
    assert "really is" in out and "apart from chair" in out
    for bad, option in (
        (["--feature", "all"], "--separate"),
        (["--feature", "all", "--separate", ","], "--separate"),
        (["--feature", "all", "--separate", "chair", "--top", "0"], "--top"),
    ):
        assert F.main([*argv, *bad]) == 2
        assert option in capsys.readouterr().err
