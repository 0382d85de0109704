"""``-q``: no progress, tables or summaries from any command; errors, warnings and what
``info``, ``cad models``, ``--json`` and ``--explain`` print still appear (what its help
says)."""

from __future__ import annotations

import json

import numpy as np
import typer

from ontodetect.cli import app, main


def test_the_help_says_what_quiet_leaves_out_and_keeps():
    quiet = next(p for p in typer.main.get_command(app).params if p.name == "quiet")
    assert quiet.help == (
        "No progress bars, tables or summaries (the files are written all the same); "
        "errors, warnings and what info, cad models, --json and --explain print still appear."
    )


def test_synth_prints_no_summary_with_quiet(tmp_path, capsys):
    out = tmp_path / "out"
    args = ["synth", "--room", "tiny", "--seed", "3", "--points", "3000", "-o", str(out)]
    assert main(["-q", *args]) == 0
    captured = capsys.readouterr()
    assert captured.out == "" and captured.err == ""
    assert json.loads((out / "scene.json").read_text())["num_points"] == 3000


def test_demo_prints_no_table_with_quiet(tmp_path, capsys, monkeypatch):
    import ontodetect.demo

    ran = []
    # The run itself is the demo's own business (and minutes of work): only what the
    # command prints after it is looked at here.
    monkeypatch.setattr(ontodetect.demo, "run_demo", lambda out, **kw: ran.append(out))
    assert main(["-q", "demo", "-o", str(tmp_path / "d")]) == 0
    assert ran == [tmp_path / "d"]
    assert capsys.readouterr().out == ""


def test_info_still_prints_its_description_with_quiet(tmp_path, capsys):
    f = tmp_path / "p.npy"
    np.save(f, np.array([[0.0, 0, 0], [1, 0, 0], [0, 1, 0], [0, 0, 1]]))
    assert main(["-q", "info", str(f)]) == 0
    lines = capsys.readouterr().out.splitlines()
    assert lines[:3] == [str(f), "format           npy", "points           4"]


def test_cad_models_still_prints_its_list_with_quiet(tmp_path, capsys):
    from ontodetect.cad import builtin_library

    png = tmp_path / "models.png"
    assert main(["-q", "cad", "models", "--picture", str(png)]) == 0
    captured = capsys.readouterr()
    lib = builtin_library()
    assert captured.out.lstrip().startswith(f"{len(lib)} models")
    for name in lib:
        assert name in captured.out
    assert "wrote" not in captured.out  # the summary line is left out
    assert captured.err == ""
    assert png.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
