"""`python -m benchmarks compare`: two generalization runs side by side, on hand-made files."""

from __future__ import annotations

import json

import pytest
from benchmarks import bench_compare as C
from benchmarks import bench_generalization as B
from rich.console import Console
from rich.table import Table


def fig(tp, det, gt):
    return {
        "tp": tp,
        "det": det,
        "gt": gt,
        "precision": tp / det if det else 0.0,
        "recall": tp / gt if gt else 0.0,
    }


def run_doc(
    *,
    chairs=(8, 10, 12),
    wc_as_chair=2,
    merged=2,
    mean=0.9,
    stability=True,
    real=True,
    noisy=(5, 6),
    frames=(4, 5, 9),
    sparse=(20, 24),
):
    key = "iou@0.25"
    doc = {
        "format": B.FORMAT,
        "room": "auto",
        "overrides": [],
        "simulated": {
            "per_class": {key: {"chair": fig(*chairs), "table": fig(3, 4, 5)}},
            "by_room_type": {
                "office": {key: {"chair": fig(*chairs), "overall": fig(9, 12, 14)}},
                "bathroom": {key: {"chair": fig(0, wc_as_chair, 0)}},
            },
            "chair_groups": {key: {"easy chairs": {"found": 2, "gt": 3, "recall": 0.67}}},
            "false_detections": {
                key: {"toilet": {"total": wc_as_chair, "as": {"chair": wc_as_chair}}}
            },
            "missed": {
                key: {"chair": {"total": merged + 2, "causes": {"merged": merged, "scored": 2}}}
            },
        },
    }
    if frames is not None:
        doc["frames"] = {
            "per_class": {key: {"chair": fig(*frames)}},
            "by_room_type": {"office": {key: {"chair": fig(*frames)}}},
            "chair_groups": {key: {"easy chairs": {"found": 1, "gt": 2, "recall": 0.5}}},
            "false_detections": {key: {}},
            "missed": {key: {}},
        }
    if real:
        doc["real"] = {
            "per_class": {key: {"chair": fig(23, 25, 26)}},
            "false_detections": {key: {}},
        }
    if noisy is not None:
        doc["robustness"] = {
            "changes": {
                "noise 1 cm": {
                    "per_class": {"chair": fig(*noisy, 12), "table": fig(2, 3, 4)},
                    "floor_scatter": 0.0099,
                }
            }
        }
    if sparse is not None:
        doc["sparse"] = {
            "changes": {
                "a quarter of the points": {
                    "per_class": {"chair": fig(*sparse, 30)},
                    "floor_scatter": 0.006,
                }
            }
        }
    if stability:
        doc["stability"] = {
            "mean": mean,
            "worst": 0.5,
            "per_transform": {"turn 90°": {"mean": mean, "worst": 0.5}},
        }
    return doc


def write(tmp_path, name, doc):
    path = tmp_path / name
    path.write_text(json.dumps(doc), encoding="utf-8")
    return path


def cells(table: Table) -> list[list[str]]:
    """The table's rows as lists of strings."""
    columns = [list(c.cells) for c in table.columns]
    return [list(row) for row in zip(*columns)]


def test_class_rows_give_before_and_after_side_by_side():
    rows = C.class_rows({"chair": fig(8, 10, 12)}, {"chair": fig(9, 10, 12), "sofa": fig(1, 2, 2)})
    assert rows == [
        ("chair", "8/10/12", "9/10/12", "0.80 / 0.67", "0.90 / 0.75"),
        ("sofa", "-", "1/2/2", "-", "0.50 / 0.50"),
    ]


def test_room_rows_give_each_reported_class_per_room():
    key = "iou@0.25"
    before = {"office": {key: {"chair": fig(8, 10, 12), "overall": fig(8, 10, 12)}}}
    after = {"office": {key: {"chair": fig(9, 10, 12)}}, "bathroom": {key: {"chair": fig(0, 1, 0)}}}
    classes, rows = C.room_rows(before, after, key)
    assert classes == ["chair"]  # "overall" is no class
    assert rows == [("office", "8/10", "9/10"), ("bathroom", "-", "0/1")]


def test_false_rows_come_most_frequent_first_with_what_they_were_taken_for():
    before = {"toilet": {"total": 2, "as": {"chair": 2}}, "sink": {"total": 5, "as": {"table": 5}}}
    after = {"sink": {"total": 1, "as": {"table": 1}}, "bed": {"total": 3, "as": {"sofa": 2}}}
    assert C.false_rows(before, after) == [
        ("sink", 5, 1, "table 5", "table 1"),
        ("bed", 0, 3, "", "sofa 2"),
        ("toilet", 2, 0, "chair 2", ""),
    ]


def test_missed_rows_give_each_class_total_then_its_causes_in_the_benchmarks_order():
    before = {"chair": {"total": 5, "causes": {"scored": 3, "merged": 2}}}
    after = {
        "chair": {"total": 4, "causes": {"scored": 3, "odd": 1}},
        "table": {"total": 1, "causes": {"vote": 1}},
    }
    assert C.missed_rows(before, after) == [
        ("chair, all", 5, 4),
        ("chair, merged", 2, 0),
        ("chair, scored", 3, 3),
        ("chair, odd", 0, 1),  # a cause the benchmark may add later comes last
        ("table, all", 0, 1),
        ("table, vote", 0, 1),
    ]


def test_stability_rows_give_mean_and_worst_per_change():
    before = {"mean": 0.9, "worst": 0.5, "per_transform": {"turn 90°": {"mean": 0.8, "worst": 0.5}}}
    after = {"mean": 0.95, "worst": 0.75, "per_transform": {}}
    assert C.stability_rows(before, after) == [
        ("all", "0.9000 / 0.5000", "0.9500 / 0.7500"),
        ("turn 90°", "0.8000 / 0.5000", "-"),
    ]


def _unsteady(scene, label, really, lost):
    return {
        "scene": scene,
        "id": 1,
        "label": label,
        "score": 0.3,
        "is": really,
        "lost_under": ["turn 90°"] * lost,
    }


def test_stability_objects_count_each_unsteady_detection_by_what_it_is():
    cabinet = ("conf", "chair", "false: cabinet (cabinet)")
    before = {"transforms": ["turn 90°", "shuffle"], "unsteady": [
        _unsteady(*cabinet, 2), _unsteady("room", "chair", "chair", 1),
        _unsteady("room", "chair", "chair", 2),
    ]}  # fmt: skip
    after = {"transforms": ["turn 90°", "shuffle"], "unsteady": [
        _unsteady("room", "chair", "chair", 2), _unsteady("room", "chair", "chair", 1),
        _unsteady("room", "table", "table", 1),
    ]}  # fmt: skip
    assert C.stability_objects(before, after) == [
        ("conf: chair (false: cabinet (cabinet))", "lost 2/2", "-"),
        ("room: table (table)", "-", "lost 1/2"),
    ]  # the two chairs of "room" are lost as often before as after, renumbered or not
    doc_b, doc_a = run_doc(), run_doc()
    doc_b["stability"].update(before)
    doc_a["stability"].update(after)
    tables = {i.title: i for i in C.compare(doc_b, doc_a, changed=True) if isinstance(i, Table)}
    assert len(cells(tables["Stability: the objects that changed"])) == 2
    # runs written before the list: a line says which lacks it
    assert "Stability: the objects that changed: not listed in the first run" in C.compare(
        run_doc(), doc_a
    )


def test_robustness_rows_give_each_change_and_class_before_and_after():
    before = run_doc()["robustness"]
    after = run_doc(noisy=(9, 10))["robustness"]
    assert C.robustness_rows(before, after) == [
        ("noise 1 cm, chair", "5/6/12", "9/10/12", "0.83 / 0.42", "0.90 / 0.75"),
        ("noise 1 cm, table", "2/3/4", "2/3/4", "0.67 / 0.50", "0.67 / 0.50"),
    ]
    items = C.compare(run_doc(), run_doc(noisy=None), changed=True)
    assert "Robustness: not in the second run" in items


def test_the_real_scans_in_their_four_orientations_are_pooled_last():
    """The scans as they are and their files' axes turned by 90, 180 and 270 degrees, summed:
    the real figure without the draw of the files' axes."""
    before = run_doc()
    turned = {
        f"axes turned {a}°": {"per_class": {"chair": fig(t, t + 1, 12)}}
        for a, t in ((90, 7), (180, 8), (270, 6))
    }
    before["robustness"]["changes"].update(turned)
    after = json.loads(json.dumps(before))
    after["robustness"]["changes"]["axes turned 90°"]["per_class"]["chair"] = fig(9, 9, 12)
    rows = C.robustness_rows(
        before["robustness"], after["robustness"], C._real(before), C._real(after)
    )
    pooled = {r[0]: r[1:3] for r in rows if r[0].startswith(C.POOLED)}
    real = before["real"]["per_class"]["iou@0.25"]["chair"]
    tp, det = real["tp"] + 7 + 8 + 6, real["det"] + 8 + 9 + 7
    assert pooled[f"{C.POOLED}, chair"] == (
        f"{tp}/{det}/{real['gt'] + 36}",
        f"{tp + 2}/{det + 1}/{real['gt'] + 36}",
    )
    # Without all three turns there is nothing to pool.
    assert not [
        r
        for r in C.robustness_rows(
            run_doc()["robustness"], run_doc()["robustness"], C._real(before), C._real(after)
        )
        if r[0].startswith(C.POOLED)
    ]


def test_compare_of_a_run_with_itself_changes_nothing():
    doc = run_doc()
    items = C.compare(doc, doc, changed=True)
    assert items and all(isinstance(i, str) and i.endswith("no change") for i in items)
    # Without --changed every row is printed, dim.
    tables = [i for i in C.compare(doc, doc) if isinstance(i, Table)]
    assert tables and all(row.style == "dim" for t in tables for row in t.rows)


def test_compare_keeps_only_what_changed_and_says_what_a_run_lacks():
    before = run_doc()
    after = run_doc(chairs=(9, 10, 12), wc_as_chair=0, merged=0, mean=0.95, real=False)
    items = C.compare(before, after, changed=True)
    text = [i for i in items if isinstance(i, str)]
    assert "Real scans: not in the second run" in text
    tables = {i.title: i for i in items if isinstance(i, Table)}
    sim = cells(tables["Simulated rooms, TP/det/GT at point IoU 0.25"])
    assert sim == [["chair", "8/10/12", "9/10/12", "0.80 / 0.67", "0.90 / 0.75"]]
    rooms = cells(tables["Simulated rooms by room type, TP/det"])
    assert rooms == [["office", "8/10", "9/10"], ["bathroom", "0/2", "0/0"]]
    false = cells(tables["Simulated rooms: what the false detections are"])
    assert false == [["toilet", "2", "0", "chair 2", ""]]
    missed = cells(tables["Simulated rooms: missed, by cause"])
    assert missed == [["chair, all", "4", "2"], ["chair, merged", "2", "0"]]
    stab = cells(tables["Stability: detections that reappear, mean / worst"])
    assert stab == [
        ["all", "0.9000 / 0.5000", "0.9500 / 0.5000"],
        ["turn 90°", "0.9000 / 0.5000", "0.9500 / 0.5000"],
    ]


def test_single_frames_are_compared_as_the_simulated_rooms_are():
    items = C.compare(run_doc(), run_doc(frames=(6, 7, 9)), changed=True)
    tables = {i.title: i for i in items if isinstance(i, Table)}
    frames = cells(tables["Single frames, TP/det/GT at point IoU 0.25"])
    assert frames == [["chair", "4/5/9", "6/7/9", "0.80 / 0.44", "0.86 / 0.67"]]
    rooms = cells(tables["Single frames by room type, TP/det"])
    assert rooms == [["office", "4/5", "6/7"]]
    # a run without the part (older runs) says so
    text = C.compare(run_doc(frames=None), run_doc(), changed=True)
    assert "Single frames: not in the first run" in text


def test_main_prints_both_runs_settings_and_the_tables(tmp_path, capsys, monkeypatch):
    monkeypatch.setattr(C, "console", Console(width=200, highlight=False))
    before = write(tmp_path, "a.json", run_doc())
    after_doc = run_doc(chairs=(9, 10, 12))
    after_doc["overrides"] = ["detect.votes=1"]
    after_doc["ontology"] = [{"path": "mine.yaml", "sha256": "ab" * 32, "only": False}]
    after = write(tmp_path, "b.json", after_doc)
    assert C.main([str(before), str(after), "--changed"]) == 0
    out = capsys.readouterr().out
    assert "--set detect.votes=1" in out and "--ontology mine.yaml" in out
    assert "8/10/12" in out and "9/10/12" in out
    assert "Real scans, TP/det/GT at point IoU 0.25: no change" in out


def test_runs_under_other_seeds_are_pooled_count_by_count():
    one = run_doc(chairs=(8, 10, 12), wc_as_chair=2, merged=2)
    two = run_doc(chairs=(9, 11, 12), wc_as_chair=0, merged=1)
    two["simulated"]["false_detections"]["iou@0.25"]["sink"] = {"total": 1, "as": {"table": 1}}
    pooled = C.pool_runs([one, two])
    sim = pooled["simulated"]
    assert sim["per_class"]["iou@0.25"]["chair"] == {
        "tp": 17, "det": 21, "gt": 24, "precision": 0.8095, "recall": 0.7083
    }  # fmt: skip
    assert sim["by_room_type"]["office"]["iou@0.25"]["overall"]["tp"] == 18
    false = sim["false_detections"]["iou@0.25"]
    assert false["toilet"]["total"] == 2 and false["sink"] == {"total": 1, "as": {"table": 1}}
    assert sim["missed"]["iou@0.25"]["chair"]["causes"] == {"merged": 3, "scored": 4}
    assert pooled["sparse"]["changes"]["a quarter of the points"]["per_class"]["chair"]["gt"] == 60
    assert "stability" not in pooled and pooled["pooled_runs"] == 2
    assert pooled["room"] == "auto"  # what is not a count: the first run's


def test_main_pools_comma_separated_runs(tmp_path, capsys, monkeypatch):
    monkeypatch.setattr(C, "console", Console(width=200, highlight=False))
    a = write(tmp_path, "a.json", run_doc(chairs=(8, 10, 12)))
    b = write(tmp_path, "b.json", run_doc(chairs=(9, 10, 12)))
    c = write(tmp_path, "c.json", run_doc(chairs=(10, 10, 12)))
    assert C.main([f"{a},{b}", str(c), "--changed"]) == 0
    out = capsys.readouterr().out
    assert "2 runs pooled" in out and "17/20/24" in out and "10/10/12" in out
    assert "Stability: not in the first run" in out


@pytest.mark.parametrize(
    ("content", "says"),
    [
        (None, "cannot read it"),
        ("{not json", "not JSON"),
        ('{"rooms": 1}', "not a generalization benchmark result"),
        ('{"format": "other/1", "real": {}}', "format 'other/1'"),
    ],
)
def test_a_bad_file_is_one_line_naming_it_and_exit_2(tmp_path, capsys, content, says):
    bad = tmp_path / "bad.json"
    if content is not None:
        bad.write_text(content, encoding="utf-8")
    good = write(tmp_path, "good.json", run_doc())
    assert C.main([str(good), str(bad)]) == 2
    lines = capsys.readouterr().err.strip().splitlines()
    assert len(lines) == 1 and str(bad) in lines[0] and says in lines[0]


def test_only_the_two_overlaps_of_the_benchmark_are_compared(tmp_path, capsys):
    good = write(tmp_path, "good.json", run_doc())
    assert C.main([str(good), str(good), "--iou", "0.3"]) == 2
    assert "--iou" in capsys.readouterr().err


# -- the generalization benchmark's --ontology ---------------------------------------------
def test_a_bad_ontology_file_is_one_line_and_exit_2_before_any_scan_is_read(tmp_path, capsys):
    bad = tmp_path / "mine.yaml"
    bad.write_text("classes: [1, 2\n", encoding="utf-8")
    out = tmp_path / "out"
    argv = ["--real", str(tmp_path / "nowhere"), "--out", str(out), "--ontology", str(bad)]
    assert B.main(argv) == 2
    lines = capsys.readouterr().err.strip().splitlines()
    assert len(lines) == 1 and str(bad) in lines[0]
    assert not out.exists()
    # --ontology-only without a file is refused the same way.
    assert B.main(["--real", str(tmp_path), "--out", str(out), "--ontology-only"]) == 2
    assert "--ontology-only" in capsys.readouterr().err


def test_the_ontology_files_are_recorded_with_their_digest(tmp_path):
    mine = tmp_path / "mine.yaml"
    mine.write_text("format: ontodetect.ontology/1\nclasses: {}\n", encoding="utf-8")
    (record,) = B._ontology_record([mine], True)
    assert record["path"] == str(mine) and record["only"] is True
    assert len(record["sha256"]) == 64
    assert B._ontology_record([], False) == []


def test_markdown_gives_a_pipe_table_per_table_and_a_paragraph_per_line(tmp_path, capsys):
    before = run_doc()
    after = run_doc(chairs=(9, 10, 12), stability=False)
    text = C.markdown(C.compare(before, after, changed=True))
    assert "**Simulated rooms, TP/det/GT at point IoU 0.25**" in text
    assert "| class | before | after | P / R before | P / R after |" in text
    assert "| --- | ---: | ---: | ---: | ---: |" in text
    assert "| chair | 8/10/12 | 9/10/12 | 0.80 / 0.67 | 0.90 / 0.75 |" in text
    assert "Stability: not in the second run" in text.splitlines()
    # A cell holding a pipe does not break its row.
    table = Table(title="t")
    table.add_column("a")
    table.add_row("x|y")
    assert "| x\\|y |" in C.markdown([table])
    # The command line prints the same, with both runs' settings first.
    a, b = write(tmp_path, "a.json", before), write(tmp_path, "b.json", after)
    assert C.main([str(a), str(b), "--changed", "--markdown"]) == 0
    out = capsys.readouterr().out
    assert out.startswith(f"before: {a} (room auto)")
    assert "| chair | 8/10/12 | 9/10/12 | 0.80 / 0.67 | 0.90 / 0.75 |" in out


def mistakes(missed=(), false=()):
    """A part's ``mistakes`` at IoU 0.25: missed (scene, id, kind, cause, as) and false
    (scene, instance, kind, label) objects."""
    return {
        "iou@0.25": {
            "missed": [
                {"scene": s, "id": i, "label": "chair", "kind": k, "cause": c, "iou": 0.6, "as": a}
                for s, i, k, c, a in missed
            ],
            "false": [
                {"scene": s, "label": lab, "is": k, "kind": k, "instance": i, "share": 0.9}
                for s, i, k, lab in false
            ],
        }
    }


def test_object_rows_name_each_object_gained_or_lost_by_scan():
    before = mistakes(
        missed=[
            ("office-s0", 4, "chair-dining", "scored", "table"),
            ("bath-s1", 2, "chair", "vote", "chair"),
        ],
        false=[("bath-s1", 7, "toilet", "chair"), ("office-s0", 9, "desk", "chair")],
    )["iou@0.25"]
    after = mistakes(
        missed=[("bath-s1", 2, "chair", "merged", "")],
        false=[
            ("office-s0", 9, "desk", "chair"),
            ("office-s0", 9, "desk", "chair"),
            ("office-s0", 0, "nothing", "table"),
        ],
    )["iou@0.25"]
    assert C.object_rows(before, after) == [
        ("bath-s1: chair #2", "missed (vote, as chair)", "missed (merged)"),
        ("bath-s1: toilet #7 as chair", "false", "-"),
        ("office-s0: chair-dining #4", "missed (scored, as table)", "found"),
        ("office-s0: desk #9 as chair", "false", "false x2"),
        ("office-s0: nothing (no object) as table", "-", "false"),
    ]
    assert C.object_rows(before, before) == []
    assert C.object_rows(None, after) is None


def test_compare_lists_the_objects_that_changed_and_says_when_a_run_has_no_list():
    lost = ("office-s0", 4, "chair-dining", "scored", "table")
    before, after = run_doc(), run_doc()
    before["simulated"]["mistakes"] = mistakes(false=[("bath-s1", 7, "toilet", "chair")])
    after["simulated"]["mistakes"] = mistakes(missed=[lost])
    items = C.compare(before, after, changed=True)
    tables = {i.title: i for i in items if isinstance(i, Table)}
    assert cells(tables["Simulated rooms: the objects that changed"]) == [
        ["bath-s1: toilet #7 as chair", "false", "-"],
        ["office-s0: chair-dining #4", "found", "missed (scored, as table)"],
    ]
    assert "Simulated rooms: the objects that changed: no change" in C.compare(after, after)
    # runs written before the lists: nothing when neither has them, a line when one lacks them
    assert not any("objects that changed" in str(i) for i in C.compare(run_doc(), run_doc()))
    assert "Simulated rooms: the objects that changed: not listed in the first run" in C.compare(
        run_doc(), after
    )


def test_the_benchmark_lists_every_mistake_with_what_names_it_across_runs():
    f = {"scene": "s", "id": 3, "label": "chair", "is": "toilet", "kind": "toilet"}
    m = {"scene": "s", "id": 4, "label": "chair", "kind": "chair-dining", "cause": "scored"}
    false = {"iou@0.25": [{**f, "instance": 7, "share": 0.9}]}
    missed = {
        "iou@0.25": [{**m, "iou": 0.61, "cover": 0.9, "as": "table", "lacks": "seat.missing"}]
    }
    items = B.mistake_items(false, missed)
    assert list(items) == ["iou@0.25"]
    # the detection's id changes from run to run: the labelled instance names the object
    assert items["iou@0.25"]["false"] == [
        {
            "scene": "s",
            "label": "chair",
            "is": "toilet",
            "kind": "toilet",
            "instance": 7,
            "share": 0.9,
        }
    ]
    assert items["iou@0.25"]["missed"] == [
        {"scene": "s", "id": 4, "label": "chair", "kind": "chair-dining", "cause": "scored",
         "iou": 0.61, "as": "table", "lacks": "seat.missing"}
    ]  # fmt: skip


def test_the_robustness_part_lists_the_objects_that_changed_under_each_change():
    before, after = run_doc(), run_doc()
    lost = ("scene0005_00", 12, "chair", "merged", "table")
    before["robustness"]["changes"]["noise 1 cm"]["mistakes"] = mistakes()
    after["robustness"]["changes"]["noise 1 cm"]["mistakes"] = mistakes(missed=[lost])
    assert C.robustness_objects(before["robustness"], after["robustness"]) == [
        ("noise 1 cm / scene0005_00: chair #12", "found", "missed (merged, as table)")
    ]
    tables = {i.title: i for i in C.compare(before, after, changed=True) if isinstance(i, Table)}
    assert cells(tables["Robustness: the objects that changed"]) == [
        ["noise 1 cm / scene0005_00: chair #12", "found", "missed (merged, as table)"]
    ]
    # a run that does not list them: a line says so; neither run: nothing is said
    assert C.robustness_objects(run_doc()["robustness"], after["robustness"]) is None
    line = "Robustness: the objects that changed: not listed in the first run"
    assert line in C.compare(run_doc(), after)
    assert not any("Robustness: the objects" in str(i) for i in C.compare(run_doc(), run_doc()))


def test_the_sparse_part_is_compared_as_the_robustness_part_is():
    """The simulated fused scans with fewer points: TP/det/GT and P / R per change and
    class, and the objects that changed under each change; a run without the part (runs
    made before it) says so."""
    before, after = run_doc(), run_doc(sparse=(22, 25))
    lost = ("office-s0-fused", 16, "chair", "scored", "")
    before["sparse"]["changes"]["a quarter of the points"]["mistakes"] = mistakes(missed=[lost])
    after["sparse"]["changes"]["a quarter of the points"]["mistakes"] = mistakes()
    tables = {i.title: i for i in C.compare(before, after, changed=True) if isinstance(i, Table)}
    rows = cells(
        tables["Sparse: the simulated fused scans with fewer points, TP/det/GT at point IoU 0.25"]
    )
    assert rows == [
        ["a quarter of the points, chair", "20/24/30", "22/25/30", "0.83 / 0.67", "0.88 / 0.73"]
    ]
    assert cells(tables["Sparse: the objects that changed"]) == [
        ["a quarter of the points / office-s0-fused: chair #16", "missed (scored)", "found"]
    ]
    assert "Sparse: not in the first run" in C.compare(run_doc(sparse=None), after)
