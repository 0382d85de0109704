"""Damaged files of the text, LAS/LAZ, 3DTK, ScanNet and S3DIS readers.

Whatever the damage (a file cut short, random bytes overwritten, a byte
inserted or dropped), a reader either returns a cloud or raises an
``OntoDetectError``; never another exception, never a hang.
"""

from __future__ import annotations

import contextlib
import json
import signal
import struct
import warnings

import numpy as np
import pytest

from ontodetect import DataWarning, OntoDetectError, point_cloud
from ontodetect.io._las import read_las, write_las
from ontodetect.io._s3dis import read_s3dis
from ontodetect.io._scannet import read_scannet, read_scannet_votenet
from ontodetect.io._text import read_text, write_text
from ontodetect.io._threedtk import read_3dtk

#: Seconds one read may take before it counts as a hang (real reads take milliseconds).
DEADLINE_S = 10
#: Cut points per file and damaged copies per file.
CUTS = 12
DAMAGES = 30


@contextlib.contextmanager
def deadline(seconds: float):
    def timeout(signum, frame):
        raise TimeoutError(f"read took longer than {seconds} s")

    previous = signal.signal(signal.SIGALRM, timeout)
    signal.setitimer(signal.ITIMER_REAL, seconds)
    try:
        yield
    finally:
        signal.setitimer(signal.ITIMER_REAL, 0)
        signal.signal(signal.SIGALRM, previous)


def read_or_fail_cleanly(read, target):
    with deadline(DEADLINE_S), warnings.catch_warnings():
        warnings.simplefilter("ignore", DataWarning)
        with contextlib.suppress(OntoDetectError):
            read(target)


def _sample(rng, n=40, fields=True):
    xyz = rng.uniform(-5, 5, (n, 3))
    rgb = rng.integers(0, 256, (n, 3))
    extra = {"classification": rng.integers(0, 30, n), "intensity": rng.integers(0, 999, n)}
    return point_cloud(xyz, rgb=rgb, fields=extra if fields else None)


# -- one generated scan per reader: (reader, what to read, files to damage) ----------
def _text_case(tmp_path, rng, ext):
    f = write_text(tmp_path / f"c{ext}", _sample(rng), precision=4)
    return read_text, f, [f]


def _las_case(tmp_path, rng, ext):
    f = write_las(tmp_path / f"c{ext}", _sample(rng))
    return read_las, f, [f]


def _threedtk_case(tmp_path, rng, _):
    pts = rng.uniform(-300, 300, (40, 3))
    lines = "\n".join(f"{x:.2f} {y:.2f} {z:.2f} {i % 7}" for i, (x, y, z) in enumerate(pts))
    (tmp_path / "scan000.3d").write_text("40 x 1\n" + lines + "\n")
    (tmp_path / "scan000.pose").write_text("10 20 30\n1 45 2\n")
    (tmp_path / "scan001.3d").write_text(lines + "\n")
    return read_3dtk, tmp_path, [tmp_path / "scan000.3d", tmp_path / "scan000.pose"]


def _scannet_case(tmp_path, rng, _):
    scene, n = "scene0001_00", 30
    header = (
        "ply\nformat binary_little_endian 1.0\ncomment VCGLIB generated\n"
        f"element vertex {n}\nproperty float x\nproperty float y\nproperty float z\n"
        "property uchar red\nproperty uchar green\nproperty uchar blue\nproperty uchar alpha\n"
        f"element face {n - 2}\nproperty list uchar int vertex_indices\nend_header\n"
    )
    vertex = np.zeros(n, dtype=[("xyz", "<f4", 3), ("rgba", "u1", 4)])
    vertex["xyz"] = rng.uniform(0, 3, (n, 3))
    vertex["rgba"] = rng.integers(0, 256, (n, 4))
    faces = b"".join(struct.pack("<B3i", 3, i, i + 1, i + 2) for i in range(n - 2))
    mesh = tmp_path / f"{scene}_vh_clean_2.ply"
    mesh.write_bytes(header.encode() + vertex.tobytes() + faces)
    segs = tmp_path / f"{scene}_vh_clean_2.0.010000.segs.json"
    segs.write_text(json.dumps({"segIndices": (np.arange(n) // 5).tolist()}))
    agg = tmp_path / f"{scene}.aggregation.json"
    groups = [
        {"objectId": k, "label": ["chair", "table"][k % 2], "segments": [k]} for k in range(5)
    ]
    agg.write_text(json.dumps({"segGroups": groups}))
    table = tmp_path / "scannetv2-labels.combined.tsv"
    table.write_text("id\traw_category\tnyu40id\n1\tchair\t5\n2\ttable\t7\n")
    return read_scannet, tmp_path, [mesh, segs, agg, table]


def _votenet_case(tmp_path, rng, _):
    scene, n = "scene0002_00", 40
    vert = np.column_stack([rng.uniform(0, 3, (n, 3)), rng.integers(0, 256, (n, 3))])
    np.save(tmp_path / f"{scene}_vert.npy", vert.astype(np.float32))
    np.save(tmp_path / f"{scene}_sem_label.npy", rng.integers(0, 41, n).astype(np.uint32))
    np.save(tmp_path / f"{scene}_ins_label.npy", rng.integers(0, 5, n).astype(np.uint32))
    np.save(tmp_path / f"{scene}_bbox.npy", rng.uniform(0, 1, (3, 7)))
    files = sorted(tmp_path.glob("*.npy"))
    return read_scannet_votenet, tmp_path / f"{scene}_vert.npy", files


def _s3dis_case(tmp_path, rng, _):
    room = tmp_path / "Area_1" / "office_1"
    (room / "Annotations").mkdir(parents=True)
    files = []
    for stem in ("chair_1", "table_1", "floor_1"):
        pts = np.column_stack([rng.uniform(0, 5, (20, 3)), rng.integers(0, 256, (20, 3))])
        f = room / "Annotations" / f"{stem}.txt"
        f.write_text(
            "".join(
                f"{a:.3f} {b:.3f} {c:.3f} {r:.0f} {g:.0f} {b2:.0f}\n" for a, b, c, r, g, b2 in pts
            )
        )
        files.append(f)
    return read_s3dis, room, files


CASES = {
    "xyz": (_text_case, ".xyz"),
    "csv": (_text_case, ".csv"),
    "pts": (_text_case, ".pts"),
    "las": (_las_case, ".las"),
    "laz": (_las_case, ".laz"),
    "3dtk": (_threedtk_case, None),
    "scannet": (_scannet_case, None),
    "scannet-votenet": (_votenet_case, None),
    "s3dis": (_s3dis_case, None),
}


def _build(name, tmp_path, rng):
    make, ext = CASES[name]
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", DataWarning)  # the PTS writer drops class ids
        read, target, files = make(tmp_path, rng, ext)
    read(target)  # the undamaged scan reads
    return read, target, files


@pytest.mark.parametrize("name", list(CASES))
def test_truncated_files(tmp_path, rng, name):
    read, target, files = _build(name, tmp_path, rng)
    for f in files:
        original = f.read_bytes()
        cuts = sorted(
            {0, 1, len(original) - 1, *np.linspace(2, len(original) - 2, CUTS).astype(int)}
        )
        for cut in cuts:
            f.write_bytes(original[:cut])
            read_or_fail_cleanly(read, target)
        f.write_bytes(original)


@pytest.mark.parametrize("name", list(CASES))
def test_randomly_damaged_files(tmp_path, rng, name):
    read, target, files = _build(name, tmp_path, rng)
    for f in files:
        original = f.read_bytes()
        for trial in range(DAMAGES):
            data = bytearray(original)
            if trial % 5 == 4:  # a byte inserted or dropped shifts everything after it
                at = int(rng.integers(0, len(data)))
                data[at:at] = bytes([int(rng.integers(0, 256))]) if trial % 2 else b""
                if not trial % 2:
                    del data[at]
            else:
                # Headers hold the counts and offsets: damage them more often.
                span = min(len(data), 400) if trial % 2 else len(data)
                for at in rng.integers(0, span, int(rng.integers(1, 8))):
                    data[at] = int(rng.integers(0, 256))
            f.write_bytes(bytes(data))
            read_or_fail_cleanly(read, target)
        f.write_bytes(original)
