"""``detect`` on several scans: a progress row per scan in flight and an overall row."""

import io
import queue

from rich.console import Console

from ontodetect._progress import progress, use_reporter
from ontodetect.cli._scans import ScanRows, StageSender


def _rows(channel):
    console = Console(file=io.StringIO(), force_terminal=True, width=120)
    return ScanRows(channel, console=console)


def test_each_scan_shows_its_innermost_stage_until_it_is_done():
    channel = queue.SimpleQueue()
    rows = _rows(channel)
    a, b = StageSender(channel, "room_a"), StageSender(channel, "room_b")
    a.begin()
    b.begin()
    with use_reporter(a), progress("Votes", total=3) as vote:
        vote(1)
        with progress("Voxelizing and denoising"):
            rows.drain()
            shown = {t.fields["scan"]: t.description for t in rows.progress.tasks}
            assert shown == {"room_a": "Voxelizing and denoising", "room_b": "starting"}
        rows.drain()
        task = next(t for t in rows.progress.tasks if t.fields["scan"] == "room_a")
        assert (task.description, task.total, task.completed) == ("Votes", 3, 1)
    a.end()
    rows.drain()
    assert [t.fields["scan"] for t in rows.progress.tasks] == ["room_b"]
    b.end()
    rows.drain()
    assert rows.progress.tasks == [] and rows.rows == {}


def test_the_batch_count_is_the_overall_row():
    rows = _rows(queue.SimpleQueue())
    with use_reporter(rows), progress("Scans", total=2) as done:
        done(1)
        (task,) = rows.progress.tasks
        assert task.fields["scan"] == "all scans" and task.completed == 1
    assert rows.progress.tasks == []
