"""``ontodetect synth`` run in-process."""

from __future__ import annotations

import json

from ontodetect.cli import main
from ontodetect.synth import SENSORS, room_types


def test_one_scene(tmp_path, capsys):
    out = tmp_path / "out"
    code = main(
        [
            "synth",
            "--room",
            "tiny",
            "--sensor",
            "rgbd",
            "--seed",
            "3",
            "--points",
            "3000",
            "-o",
            str(out),
        ]
    )
    captured = capsys.readouterr()
    assert code == 0, captured.err
    for name in ("cloud.ply", "objects.json", "scene.json", "mesh.ply"):
        assert (out / name).is_file()
    scene = json.loads((out / "scene.json").read_text())
    assert scene["seed"] == 3 and scene["room_type"] == "tiny" and scene["num_points"] == 3000
    lines = captured.out.strip().splitlines()
    assert len(lines) == 1
    assert "3,000 points" in lines[0] and "chair" in lines[0] and "table" in lines[0]


def test_count_writes_numbered_scenes(tmp_path, capsys):
    out = tmp_path / "ds"
    code = main(
        [
            "synth",
            "--room",
            "tiny",
            "--count",
            "2",
            "--seed",
            "5",
            "--points",
            "1500",
            "--sensor",
            "tls",
            "-o",
            str(out),
        ]
    )
    captured = capsys.readouterr()
    assert code == 0, captured.err
    seeds = [
        json.loads((out / f"scene_000{i}" / "scene.json").read_text())["seed"] for i in range(2)
    ]
    assert seeds == [5, 6]
    assert len(captured.out.strip().splitlines()) == 2


def test_sensor_options(tmp_path, capsys):
    out = tmp_path / "opt"
    code = main(
        [
            "synth",
            "--room",
            "tiny",
            "-O",
            "num_frames=3",
            "-O",
            "stride=16",
            "-O",
            "noise=[0.002, 0.001]",
            "-o",
            str(out),
        ]
    )
    assert code == 0, capsys.readouterr().err
    params = json.loads((out / "scene.json").read_text())["sensor"]["parameters"]
    assert params["num_frames"] == 3 and params["stride"] == 16
    assert params["noise"] == [0.002, 0.001]


def test_list(capsys):
    assert main(["synth", "--list"]) == 0
    text = capsys.readouterr().out
    for name in (*room_types(), *SENSORS):
        assert name in text


def test_bad_room_is_one_line_naming_the_parameter(tmp_path, capsys):
    code = main(["synth", "--room", "castle", "-o", str(tmp_path / "x")])
    err = capsys.readouterr().err.strip()
    assert code == 2
    assert len(err.splitlines()) == 1
    assert err.startswith("error:") and "'room'" in err and "castle" in err
    for name in room_types():
        assert name in err
    assert not (tmp_path / "x").exists()


def test_bad_sensor_option_and_missing_output(tmp_path, capsys):
    assert main(["synth", "--room", "tiny", "-O", "zoom=2", "-o", str(tmp_path / "y")]) == 2
    assert "'zoom'" in capsys.readouterr().err
    assert main(["synth", "--room", "tiny", "-O", "stride", "-o", str(tmp_path / "y")]) == 2
    assert "'option'" in capsys.readouterr().err
    assert main(["synth", "--room", "tiny"]) == 2
    assert "'out'" in capsys.readouterr().err
