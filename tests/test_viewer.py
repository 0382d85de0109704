"""``ontodetect view``: the page carries everything, and headless Chromium draws it."""

import base64
import json
import os
import re
import shutil
import subprocess

import numpy as np
import pytest

from ontodetect.cli import main
from ontodetect.errors import InvalidParameterError, ReadError
from ontodetect.io import read_cloud, read_detections
from ontodetect.outputs import write_outputs
from ontodetect.pipeline import detect
from ontodetect.render import viewer_html
from ontodetect.synth import synthesize, write_synth

#: Chromium flags that work in a container without a display, GPU or network.
CHROMIUM_FLAGS = (
    "--headless",
    "--no-sandbox",
    "--disable-gpu",
    "--disable-quic",
    "--no-first-run",
    "--disable-background-networking",
    "--disable-component-update",
    "--disable-sync",
    "--hide-scrollbars",
    "--window-size=1200,800",
    # the page draws at load; virtual time lets it finish before the dump or the screenshot
    "--virtual-time-budget=10000",
)


def chromium() -> str | None:
    """Debian's chromium, installed with apt-get when missing and we are root (as in CI)."""
    found = shutil.which("chromium") or shutil.which("chromium-browser")
    if found is None and os.geteuid() == 0 and shutil.which("apt-get"):
        env = {**os.environ, "DEBIAN_FRONTEND": "noninteractive"}
        subprocess.run(["apt-get", "update", "-qq"], env=env, check=False, capture_output=True)
        subprocess.run(
            ["apt-get", "install", "-y", "-qq", "chromium"],
            env=env,
            check=False,
            capture_output=True,
        )
        found = shutil.which("chromium")
    return found


@pytest.fixture(scope="module")
def run(tmp_path_factory):
    folder = tmp_path_factory.mktemp("scene")
    write_synth(synthesize("dining_room", "rgbd", seed=5, points=30_000), folder)
    res = detect(read_cloud(folder / "cloud.ply"), room="dining_room", seed=0)
    out = tmp_path_factory.mktemp("out")
    write_outputs(res, out, picture=False)
    return out


def test_the_page_is_self_contained_and_decimated(run):
    page = viewer_html(run, max_points=5_000)
    assert "<script src" not in page and "http://" not in page and "https://" not in page
    doc = read_detections(run / "detections.json")
    assert page.count('"corners"') == len(doc["detections"])
    data = re.search(r'<script id="scene-data" type="application/json">(.*?)</script>', page, re.S)
    layers = json.loads(data.group(1))["layers"]
    total = sum(len(base64.b64decode(la["xyz"])) // 12 for la in layers)
    assert total <= 5_000
    names = [la["name"] for la in layers]
    assert "other points" in names and {d["label"] for d in doc["detections"]} <= set(names)
    assert viewer_html(run, max_points=5_000) == page  # seeded: the same page twice


def test_bad_folder_and_budget_are_refused(run, tmp_path):
    with pytest.raises(InvalidParameterError, match="max_points"):
        viewer_html(run, max_points=0)
    (tmp_path / "detections.json").write_text((run / "detections.json").read_text())
    with pytest.raises(ReadError, match="labelled"):
        viewer_html(tmp_path)


def test_headless_chromium_draws_every_box(run, tmp_path):
    browser = chromium()
    if browser is None:  # pragma: no cover - only without root or apt-get
        pytest.skip("chromium is not installed and cannot be installed here")
    assert main(["view", str(run), "-q"]) == 0
    page = (run / "view.html").as_uri()
    n = len(read_detections(run / "detections.json")["detections"])
    profile = tmp_path / "profile"
    profile.mkdir()
    base = [browser, *CHROMIUM_FLAGS, f"--user-data-dir={profile}"]
    dom = subprocess.run(
        [*base, "--dump-dom", page], capture_output=True, text=True, timeout=60, check=True
    ).stdout
    body = re.search(r"<body([^>]*)>", dom).group(1)
    assert 'data-ready="1"' in body
    assert int(re.search(r'data-boxes-drawn="(\d+)"', body).group(1)) == n
    assert int(re.search(r'data-nonblank-pixels="(\d+)"', body).group(1)) > 5_000
    shot = tmp_path / "view.png"
    subprocess.run(
        [*base, f"--screenshot={shot}", page], capture_output=True, timeout=60, check=True
    )
    png = shot.read_bytes()
    assert png[:8] == b"\x89PNG\r\n\x1a\n" and len(png) > 20_000
    assert np.frombuffer(png[16:24], ">u4").tolist() == [1200, 800]
