"""Single camera frames: the sensor's position, depth steps smoothed over the pixel grid, and
parts an object hides from the sensor itself."""

from __future__ import annotations

import dataclasses
import math
from types import SimpleNamespace

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from ontodetect import InvalidParameterError, point_cloud
from ontodetect.cloud import DataWarning, pixel_grid, sensor_position
from ontodetect.config import Config
from ontodetect.geometry import yaw_pose
from ontodetect.ontology import ClusterDescription, builtin_ontology
from ontodetect.ontology._score import (
    HIDDEN_SEAT_TOP,
    LIFTED_BOTTOM,
    cluster_log_factor,
    missing_factor,
)
from ontodetect.pipeline import detect, hidden_heights
from ontodetect.preprocess import smooth_depth
from ontodetect.segment import standing_base
from ontodetect.synth import synthesize
from ontodetect.synth.furniture import make_furniture, place
from ontodetect.synth.sensors import _look_at, scan_rgbd_frame
from test_synth_sensors import box_room

IDENTITY_VIEW = [0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0]


def frame_of(depth: np.ndarray, f: float = 500.0) -> tuple[np.ndarray, np.ndarray]:
    """Camera-frame points of a depth image (NaN: no return) and their row-major pixels."""
    h, w = depth.shape
    v, u = np.mgrid[0:h, 0:w]
    rays = np.stack([(u - w / 2) / f, (v - h / 2) / f, np.ones_like(depth)], -1).reshape(-1, 3)
    z = depth.reshape(-1)
    keep = np.isfinite(z)
    return rays[keep] * z[keep, None], np.flatnonzero(keep)


def organized(depth: np.ndarray, **meta) -> object:
    xyz, pixels = frame_of(depth)
    h, w = depth.shape
    return point_cloud(xyz, index=pixels).with_meta(
        organized=True, width=w, height=h, viewpoint=IDENTITY_VIEW, **meta
    )


# -- where the sensor was ---------------------------------------------------------------------
def test_sensor_position_of_frames_and_of_fused_scans():
    frame = organized(np.full((4, 4), 2.0))
    assert sensor_position(frame).tolist() == [0.0, 0.0, 0.0]
    moved = frame.with_meta(viewpoint=[1.0, 2.0, 3.0, 1.0, 0.0, 0.0, 0.0])
    assert sensor_position(moved).tolist() == [1.0, 2.0, 3.0]
    # an explicit position wins; a fused scan has none, even with a PCD's default VIEWPOINT
    assert sensor_position(frame.with_meta(sensor_position=[0, 0, 1])).tolist() == [0, 0, 1]
    fused = point_cloud(np.zeros((3, 3))).with_meta(organized=False, viewpoint=IDENTITY_VIEW)
    assert sensor_position(fused) is None


@pytest.mark.parametrize("bad", [[1.0, 2.0], [0.0, math.nan, 1.0], "here"])
def test_a_bad_viewpoint_is_refused_by_name(bad):
    with pytest.raises(InvalidParameterError, match="viewpoint"):
        detect(point_cloud(np.zeros((5, 3))), viewpoint=bad)


def test_a_viewpoint_without_a_pixel_grid_is_used_with_a_warning():
    scan = synthesize("tiny", seed=1).cloud  # fused from many frames: rows are no pixels
    with pytest.warns(DataWarning, match="pixel grid"):
        detect(scan, viewpoint=[0.5, 0.5, 1.5], config=Config().replace(detect={"votes": 1}))


def test_pixel_grid_from_organized_rows_or_a_pixel_field():
    frame = organized(np.array([[2.0, np.nan], [2.0, 2.0]]))
    pixels, w, h = pixel_grid(frame)
    assert pixels.tolist() == [0, 2, 3] and (w, h) == (2, 2)
    world = point_cloud(np.zeros((2, 3)), fields={"pixel": np.array([5, 1])}).with_meta(
        width=3, height=2
    )
    assert pixel_grid(world)[0].tolist() == [5, 1]
    assert pixel_grid(point_cloud(np.zeros((2, 3)))) is None
    assert pixel_grid(world.with_meta(width=2)) is None  # pixel 5 is outside a 2 x 2 grid


# -- depth steps --------------------------------------------------------------------------------
def test_depth_steps_of_a_slanted_floor_are_smoothed_along_the_rays():
    # The floor z_cam = 3 + 2 y_cam seen by a camera pitched down, its depth in 3 cm
    # steps (a Kinect at 3 m): depth along pixel row v is 3 / (1 - 2 (v - h/2) / f).
    h, w = 60, 80
    v, _ = np.mgrid[0:h, 0:w]
    true = 3.0 / (1.0 - 2.0 * (v - h / 2) / 500.0)
    frame = organized(np.round(true / 0.03) * 0.03)
    smooth = smooth_depth(frame)

    def off_plane(xyz: np.ndarray) -> np.ndarray:
        return np.abs(xyz[:, 2] - 3.0 - 2.0 * xyz[:, 1]) / math.hypot(1.0, 2.0)

    inner = np.zeros((h, w), bool)
    inner[4:-4, 4:-4] = True  # the filter's window stays inside the image
    inner = inner.reshape(-1)
    before, after = off_plane(frame.xyz[inner]), off_plane(smooth.xyz[inner])
    assert before.mean() > 0.003 and before.max() > 0.006  # up to half a step off the floor
    assert after.mean() < 0.3 * before.mean() and after.max() < 0.4 * before.max()
    # points moved only along their rays; rows, fields and meta are kept
    cos = np.einsum("ij,ij->i", smooth.xyz, frame.xyz) / (
        np.linalg.norm(smooth.xyz, axis=1) * np.linalg.norm(frame.xyz, axis=1)
    )
    assert np.all(cos > 1 - 1e-9)
    assert np.array_equal(smooth.index, frame.index)
    assert smooth.meta == {**frame.meta, "depth_smoothed": True}
    assert smooth_depth(smooth) is smooth  # smoothed once, as detect does for all passes


def test_depth_edges_between_objects_stay_sharp():
    depth = np.full((40, 40), 3.0)
    depth[:, :20] = 2.0  # a box 1 m in front of a wall
    smooth = smooth_depth(organized(depth)).xyz[:, 2]
    assert np.all((np.abs(smooth - 2.0) < 0.005) | (np.abs(smooth - 3.0) < 0.005))


def test_clouds_that_are_not_one_frame_are_left_alone():
    fused = point_cloud(np.random.default_rng(0).random((50, 3)))
    assert smooth_depth(fused) is fused
    frame = organized(np.full((4, 4), 2.0))
    no_sensor = frame.with_meta(organized=False)  # rows are not pixels any more
    assert smooth_depth(no_sensor) is no_sensor


# -- what an object hides itself ------------------------------------------------------------------
@settings(max_examples=60, deadline=None)
@given(top=st.floats(0.3, 1.4), eye=st.floats(0.2, 2.5), d=st.floats(0.5, 8.0))
def test_hidden_height_lies_under_the_top_and_rises_with_distance(top, eye, d):
    tops = np.array([top, top])
    near_far = np.array([[d, 0.0], [d + 1.0, 0.0]])
    near, far = hidden_heights(tops, near_far, [0.0, 0.0, eye])
    assert near <= top and near <= far <= top
    if eye <= top:  # looking up at it or level with its top: everything behind is hidden
        assert near == far == top
    # the shadow really is SELF_SHADOW long at that height
    if eye > top:
        assert math.isclose((top - near) * d / (eye - top), 0.3, rel_tol=1e-9)


def _backrest_only(
    bottom: float, hidden_below: float, shelter: float = -math.inf, breadth: float = 0.2
):
    return ClusterDescription(
        planes=[],
        relations={},
        length=0.5,
        breadth=breadth,
        height=0.95,
        bottom=bottom,
        shelter=shelter,
        hidden_below=hidden_below,
    )


def test_a_seat_hidden_behind_its_backrest_counts_as_occluded():
    seat = next(p for p in builtin_ontology()["chair"].parts if p.name == "seat")
    # seen from behind: the seat's height (0.35-0.75, centre 0.55) is in the backrest's shadow
    assert missing_factor(seat, _backrest_only(0.4, hidden_below=0.85)) == seat.occluded
    # fused scan (nothing known), or the sensor too close above it to be hidden
    assert missing_factor(seat, _backrest_only(0.4, hidden_below=-math.inf)) == seat.missing
    assert missing_factor(seat, _backrest_only(0.4, hidden_below=0.5)) == seat.missing
    # a screen standing on a desk (bottom 0.75): no seat hides 20 cm under what is seen
    assert missing_factor(seat, _backrest_only(0.75, hidden_below=1.1)) == seat.missing
    # standing on the floor: its lower part is not hidden but absent
    assert missing_factor(seat, _backrest_only(0.05, hidden_below=0.85)) == seat.missing


def test_a_chair_seen_from_behind_on_its_legs_is_lifted_off_the_floor():
    seat = next(p for p in builtin_ontology()["chair"].parts if p.name == "seat")
    legs = dataclasses.replace(_backrest_only(0.0, hidden_below=0.85), base=0.47)
    board = dataclasses.replace(legs, base=0.09)
    # its legs reach the floor, but what stands above them hides the seat
    assert missing_factor(seat, legs) == seat.occluded
    # a board or a front that reaches the floor hides nothing it stands on
    assert missing_factor(seat, board) == seat.missing
    # a scan fused from many views hides nothing behind a backrest, on legs or not; beside a
    # neighbour's top only what shows from just under the seat's height counts
    fused = dataclasses.replace(legs, hidden_below=-math.inf)
    assert missing_factor(seat, fused) == seat.missing
    assert missing_factor(seat, dataclasses.replace(fused, shelter=0.72)) == seat.missing


@settings(max_examples=60, deadline=None)
@given(top=st.floats(0.45, 1.3), bottom=st.floats(0.36, 0.45))
def test_what_hides_a_seat_in_a_single_view_rises_above_a_table_top(top, bottom):
    seat = next(p for p in builtin_ontology()["chair"].parts if p.name == "seat")
    seen = dataclasses.replace(_backrest_only(bottom, hidden_below=top - 0.05), height=top)
    # a desk's panel seen without its top ends at the top's height or under it; a
    # chair's back rises higher
    expected = seat.occluded if top > HIDDEN_SEAT_TOP else seat.missing
    assert missing_factor(seat, seen) == expected
    # beside a neighbour's top (a chair pushed under a desk), the back may end lower
    sheltered = dataclasses.replace(seen, shelter=bottom)
    assert missing_factor(seat, sheltered) == seat.occluded


@settings(max_examples=60, deadline=None)
@given(legs=st.integers(0, 9), low=st.floats(0.25, 0.6), top=st.floats(0.8, 1.3))
def test_the_base_of_what_stands_on_legs_is_above_them(legs, low, top):
    back = np.linspace(low, top, 100)  # the voxel heights of what a backrest shows
    on_legs = np.r_[np.linspace(0.0, low, legs, endpoint=False), back]
    assert standing_base(on_legs) >= low
    # a surface down to the floor, as high as a chair may be: its base is at the floor
    assert standing_base(np.linspace(0.0, top, 100)) < LIFTED_BOTTOM
    assert standing_base(np.array([])) == -math.inf


def test_the_depth_a_single_view_hides_is_only_a_lower_bound():
    rule = builtin_ontology()["chair"].cluster.constraints["breadth"]  # {min: 0.15, soft: 0.05}
    thin = 0.06  # a backrest's own depth, seen from behind
    fused = cluster_log_factor(rule, _backrest_only(0.4, -math.inf, breadth=thin), "breadth")
    hidden = cluster_log_factor(rule, _backrest_only(0.4, 0.85, breadth=thin), "breadth")
    assert fused == pytest.approx(float(rule.log(thin)))  # fused: the breadth as seen
    assert math.exp(fused) < 0.25 < 0.85 < math.exp(hidden) < 1.0
    # the mean of the rule over the 30 cm behind what is seen
    expected = np.log(np.mean(np.exp(rule.log(np.linspace(thin, thin + 0.3, 13)))))
    assert hidden == pytest.approx(expected)
    # what hides nothing behind it above its own bottom is measured as seen
    low = _backrest_only(0.4, 0.3, breadth=thin)
    assert cluster_log_factor(rule, low, "breadth") == pytest.approx(fused)
    # a deep enough cluster costs nothing either way
    deep = [_backrest_only(0.4, h, breadth=0.45) for h in (-math.inf, 0.85)]
    assert [cluster_log_factor(rule, d, "breadth") for d in deep] == pytest.approx([0.0, 0.0])


def test_an_office_chair_seen_from_behind_is_found_in_a_single_frame():
    chair = dataclasses.replace(
        place(make_furniture("chair-office", 4), 3.0, 3.5, 0.0), instance_id=7
    )
    scene = box_room([chair], size=(6.0, 6.0, 2.6))
    # the camera stands 2.75 m behind the chair, 1.2 m up: the backrest hides the seat
    pose = _look_at(np.array([[3.0, 0.75, 1.2]]), np.array([[3.0, 3.5, 0.5]]))[0]
    frame = scan_rgbd_frame(scene, pose=pose, rng=0, stride=2, disparity_step=0).world_cloud()
    assert np.allclose(sensor_position(frame), [3.0, 0.75, 1.2])
    plain = Config().with_overrides(["prepare.depth_smoothing=false"])  # no depth steps here
    found = detect(frame, seed=0, config=plain)
    assert [d.label for d in found.detections] == ["chair"]
    chair_pixels = frame.index[frame.fields["instance"] == 7]  # a frame's rows are pixels
    rows = found.detections[0].point_indices
    assert np.isin(rows, chair_pixels).mean() > 0.95 and len(rows) > 0.5 * len(chair_pixels)
    scores = found.scores[found.detections[0].cluster].classes["chair"]
    assert scores.assignment["seat"] is None
    # the same points as a scan of unknown origin: a lone backrest is not a chair
    fused = frame.with_meta(sensor_position=None, organized=False)
    assert detect(fused, seed=0, config=plain).detections == []


def _stand_ins(turn=0.0, move=(0.0, 0.0, 0.0)):
    """Stand-in clusters for ``sight_shelters``, turned about the vertical by ``turn``
    degrees and moved: a table's top (1.5 x 1.6 m at 0.74 m, its far edge at x = 2.5),
    a chair's backrest seen over it 0.5 m beyond that edge, the same 1.5 m beyond it, a
    desk's panel where the first backrest stands, and a small board (0.05 m²) at 0.74 m."""
    pose = yaw_pose(move[0], move[1], math.radians(turn), move[2])
    grid = np.stack(np.meshgrid(np.linspace(0, 1, 16), np.linspace(0, 1, 16)), -1).reshape(-1, 2)

    def moved(p):
        return np.asarray(p, dtype=float) @ pose[:3, :3].T + pose[:3, 3]

    def level(x0, y0, dx, dy, z):
        pts = moved(np.c_[x0 + dx * grid[:, 0], y0 + dy * grid[:, 1], np.full(len(grid), z)])
        plane = SimpleNamespace(tilt=0.0, area=dx * dy, height=z, inliers=np.arange(len(pts)))
        return SimpleNamespace(
            centers=pts, planes=[plane], bottom=0.0, height=z + 0.02, box=_box(pts)
        )

    def upright(x, bottom, top):
        pts = moved(
            np.c_[
                np.full(len(grid), x), -0.2 + 0.4 * grid[:, 0], bottom + (top - bottom) * grid[:, 1]
            ]
        )
        plane = SimpleNamespace(
            tilt=85.0,
            area=0.4 * (top - bottom),
            height=(top + bottom) / 2,
            inliers=np.arange(len(pts)),
        )
        return SimpleNamespace(
            centers=pts, planes=[plane], bottom=bottom, height=top, box=_box(pts)
        )

    return [
        level(1.0, -0.8, 1.5, 1.6, 0.74),  # the table's top
        upright(3.0, 0.7, 0.95),  # a backrest 0.5 m beyond its far edge
        upright(4.0, 0.7, 0.95),  # one 1.5 m beyond it
        upright(3.0, 0.45, 0.74),  # a desk's panel, no higher than a top
        level(3.2, 1.5, 0.25, 0.2, 0.74),  # a board too small to hide anything
    ], moved


def _box(pts):
    lo, hi = pts.min(axis=0), pts.max(axis=0)
    return SimpleNamespace(center=(lo + hi) / 2, size=hi - lo, yaw=0.0)


def test_the_top_in_the_way_hides_a_seat_however_far_the_chair_stands_back():
    """Seen across a table, the backrest 0.5 m beyond its far edge has its seat hidden by
    the table's top (no top stands within ``SHELTER_GAP`` of it); one 1.5 m beyond, a
    desk's panel and anything seen from behind are not sheltered by it."""
    from ontodetect.segment import shelter_heights, sight_shelters

    seg, moved = _stand_ins()
    got = sight_shelters(seg, moved([[0.0, 0.0, 1.5]])[0])
    assert got[1] == pytest.approx(0.74)
    assert shelter_heights(seg)[1] == -math.inf  # nothing beside it
    assert got[2] == -math.inf  # the sight line to its seat passes beyond the top
    assert got[3] == -math.inf  # no higher than a table's top: a desk's panel
    assert got[0] == -math.inf and got[4] == -math.inf
    behind = sight_shelters(seg, moved([[6.0, 0.0, 1.5]])[0])
    assert behind[1] == -math.inf  # seen from behind, the table is not in the way
    low = sight_shelters(seg, moved([[0.0, 0.0, 0.6]])[0])
    assert low[1] == -math.inf  # from under the backrest's bottom nothing is seen over a top


@given(
    turn=st.floats(-180, 180, allow_nan=False),
    move=st.tuples(*[st.floats(-50, 50, allow_nan=False)] * 3),
)
@settings(max_examples=25, deadline=None)
def test_the_top_in_the_way_does_not_depend_on_where_the_scene_stands(turn, move):
    from ontodetect.segment import sight_shelters

    seg, moved = _stand_ins(turn, (move[0], move[1], 0.0))
    got = sight_shelters(seg, moved([[0.0, 0.0, 1.5]])[0])
    assert got[1] == pytest.approx(0.74)
    assert np.isinf(got[[0, 2, 3, 4]]).all()


def test_a_table_in_front_shelters_the_chair_behind_it_in_a_generated_frame():
    """Through segmentation: a dining chair 0.6 m behind a table, seen across the table
    from 1.8 m up, is sheltered by the table's top in the frame's description, not in a
    scan of unknown origin, and by no top beside it."""
    from ontodetect.segment import describe_clusters, segment, shelter_heights

    table = dataclasses.replace(
        place(make_furniture("table-dining", 1), 3.0, 3.0, 0.0), instance_id=7
    )
    far_edge = float(np.asarray(table.box.center)[1] + np.asarray(table.box.size)[1] / 2)
    chair = make_furniture("chair-4leg", 1)
    back = far_edge + 0.6 + float(np.asarray(chair.box.size)[1]) / 2
    chair = dataclasses.replace(place(chair, 3.0, back, np.pi), instance_id=8)
    scene = box_room([table, chair], size=(6.0, 6.0, 2.6))
    pose = _look_at(np.array([[3.0, 0.6, 1.8]]), np.array([[3.0, 4.0, 0.6]]))[0]
    frame = scan_rgbd_frame(scene, pose=pose, rng=0, stride=2, disparity_step=0).world_cloud()
    seg = segment(frame, Config().with_overrides(["prepare.depth_smoothing=false"]))
    instance = frame.fields["instance"]
    k = max(range(len(seg)), key=lambda k: int((instance[seg[k].point_indices] == 8).sum()))
    assert (instance[seg[k].point_indices] == 8).mean() > 0.9
    seen = describe_clusters(seg, sensor_position(frame))[k]
    top = max(float(p.height) for c in seg for p in c.planes if float(p.tilt) < 10 and p.area > 0.5)
    assert seen.shelter == pytest.approx(top) and 0.7 < top < 0.77
    assert shelter_heights(seg)[k] == -math.inf
    assert describe_clusters(seg)[k].shelter == -math.inf
