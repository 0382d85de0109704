"""The pipeline on simulated rooms: what it finds, determinism, index mapping, the demo."""

import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from ontodetect import InvalidParameterError, point_cloud
from ontodetect.config import Config
from ontodetect.demo import run_demo
from ontodetect.geometry import yaw_pose
from ontodetect.pipeline import detect
from ontodetect.synth import synthesize


@pytest.fixture(scope="module")
def dining():
    return synthesize("dining_room", "rgbd", seed=11, points=60_000).cloud


def test_same_input_and_seed_same_output(dining):
    a = detect(dining, seed=4).to_dict()
    b = detect(dining, seed=4).to_dict()
    a.pop("timings"), b.pop("timings")
    assert a == b


def test_detections_are_mostly_their_objects(dining):
    result = detect(dining, room="dining_room")
    truth = dining.fields["class_id"]
    names = {5: "chair", 6: "sofa", 7: "table", 14: "table"}
    labels = [d.label for d in result.detections]
    assert labels.count("chair") >= 2 and "table" in labels
    for d in result.detections:
        ids, counts = np.unique(truth[d.point_indices], return_counts=True)
        assert names.get(int(ids[np.argmax(counts)])) == d.label, d


def test_point_indices_are_rows_of_the_input_file(dining):
    # Put NaN rows in front of every fifth point: detections must still name file rows.
    n = len(dining)
    xyz = np.full((n + n // 5 + 1, 3), np.nan)
    keep = np.setdiff1d(np.arange(len(xyz)), np.arange(0, len(xyz), 6))[:n]
    xyz[keep] = dining.xyz
    rgb = np.zeros((len(xyz), 3), np.uint8)
    rgb[keep] = dining.rgb
    holey = point_cloud(xyz, rgb=rgb, on_nonfinite="drop")
    plain = detect(dining)
    mapped = detect(holey)
    assert [d.label for d in mapped.detections] == [d.label for d in plain.detections]
    for a, b in zip(plain.detections, mapped.detections):
        assert np.array_equal(keep[a.point_indices], b.point_indices)


def test_bad_inputs():
    with pytest.raises(InvalidParameterError, match="'cloud'"):
        detect(np.zeros((10, 3)))
    # Settings of the detection are the configuration's, checked by one rule each.
    with pytest.raises(InvalidParameterError, match=r"'detect\.none_likelihood'"):
        detect(
            point_cloud(np.zeros((10, 3))), config=Config().replace(detect={"none_likelihood": 0})
        )
    with pytest.raises(InvalidParameterError, match=r"'detect\.votes'"):
        detect(point_cloud(np.zeros((10, 3))), config=Config().replace(detect={"votes": 0}))
    for repeated in ("threshold", "beta", "none_likelihood", "context", "votes", "up", "scale"):
        with pytest.raises(TypeError, match=repeated):
            detect(point_cloud(np.zeros((10, 3))), **{repeated: 1})


def test_demo_runs_and_scores_itself(tmp_path):
    d = run_demo(tmp_path, room="tiny", seed=2)
    assert (tmp_path / "scan" / "cloud.ply").exists()
    assert d.files.detections.exists() and d.files.picture.exists()
    assert d.evaluation.per_class["chair"].num_gt == 1
    assert d.evaluation.overall.tp >= 1


def test_shelter_is_the_highest_top_beside_a_cluster():
    from types import SimpleNamespace

    from ontodetect.pipeline import shelter_heights

    def plane(tilt, height, area):
        return SimpleNamespace(tilt=tilt, height=height, area=area)

    def box(cx, cy, sx, sy, yaw=0.0):
        return SimpleNamespace(
            center=np.array([cx, cy, 0.5]), size=np.array([sx, sy, 1.0]), yaw=yaw
        )

    desk = SimpleNamespace(
        planes=[plane(1, 0.74, 1.2), plane(88, 0.4, 0.5)], box=box(0, 0, 1.6, 0.8)
    )
    backrest = SimpleNamespace(planes=[plane(70, 0.8, 0.15)], box=box(0, 0.7, 0.45, 0.25))
    # A 45-degree turn of a 0.4 m square reaches 0.28 m from its centre.
    far = SimpleNamespace(planes=[plane(2, 0.45, 0.2)], box=box(1.6, 0, 0.4, 0.4, math.pi / 4))
    got = shelter_heights([desk, backrest, far])
    assert got[1] == pytest.approx(0.74)  # the desk stands beside the backrest
    assert got[0] == -math.inf  # the backrest has no large horizontal plane
    # the rotated box's footprint reaches 1.32 m: 0.52 m from the desk, beyond the gap
    assert got[2] == -math.inf
    assert shelter_heights([]).shape == (0,)


# -- votes ---------------------------------------------------------------------------------
def test_open_below_sees_the_floor_under_a_table_and_not_under_a_box(rng):
    """The floor shows under a table on legs; under a closed box (a cabinet) it was never
    seen. Only horizontal planes at least OPEN_BELOW_HEIGHT high are measured."""
    from ontodetect.segment import segment
    from ontodetect.segment._measure import OPEN_BELOW_HEIGHT, describe_clusters, open_below
    from test_segmentation import rect, slab, table

    floor = rect(rng, (0, 0, 0), (5, 0, 0), (0, 3, 0), 0.03)
    box = ((2.6, 0.6, 0.0), (3.6, 1.2, 0.75))
    under_box = np.all((floor[:, :2] > box[0][:2]) & (floor[:, :2] < box[1][:2]), axis=1)
    pts = np.vstack(
        [
            floor[~under_box],
            table(rng, 0.5, 0.5),
            slab(rng, *box),
            slab(rng, (1.0, 2.0, 0.0), (1.9, 2.5, 0.4)),
        ]
    )
    seg = segment(pts, seed=0)
    values = open_below(seg)
    assert len(values) == len(seg)
    tops = {}
    for c, v in zip(seg, values, strict=True):
        assert len(v) == len(c.planes)
        for plane, share in zip(c.planes, v, strict=True):
            if plane.tilt > 10 or plane.height < OPEN_BELOW_HEIGHT:
                assert math.isnan(share)
            else:
                assert 0.0 <= share <= 1.0
                tops[round(float(plane.centroid[0]))] = share
    assert tops[1] > 0.8  # the table top, centred at x = 1.2
    assert tops[3] < 0.1  # the box, centred at x = 3.1
    assert len(tops) == 2  # the 0.4 m block is too low to be measured
    descs = describe_clusters(seg)
    assert [list(d.open_below) for d in descs] == [pytest.approx(v, nan_ok=True) for v in values]
    # From one view the top hides the floor under it: not measured.
    assert all(d.open_below is None for d in describe_clusters(seg, viewpoint=(0, 0, 1.5)))


def _armchair(rng, x0, y0):
    """An armchair 0.9 x 0.85 at (x0, y0): seat 0.42, arms and back top 0.64."""
    from test_segmentation import rect, slab

    return np.vstack(
        [
            rect(rng, (x0 + 0.2, y0, 0.42), (0.5, 0, 0), (0, 0.65, 0)),  # seat
            rect(rng, (x0 + 0.2, y0, 0.0), (0.5, 0, 0), (0, 0, 0.42)),  # its front
            slab(rng, (x0, y0, 0.0), (x0 + 0.2, y0 + 0.85, 0.64)),  # arm
            slab(rng, (x0 + 0.7, y0, 0.0), (x0 + 0.9, y0 + 0.85, 0.64)),  # arm
            slab(rng, (x0 + 0.2, y0 + 0.65, 0.0), (x0 + 0.7, y0 + 0.85, 0.64)),  # back
        ]
    )


def _level_shares(seg, values):
    """(plane, share) for every level plane of every cluster; tilted planes must be NaN."""
    out = []
    for c, v in zip(seg, values, strict=True):
        assert len(v) == len(c.planes)
        for plane, share in zip(c.planes, v, strict=True):
            if plane.tilt > 10:
                assert math.isnan(share)
            else:
                out.append((plane, share))
    return out


def test_seen_below_finds_a_seat_inside_the_u_of_an_armchair_and_nothing_in_a_box():
    """Inside the U of an armchair's arms and back top a lower seat is seen; under a closed
    box's top nothing is. Tilted planes are not measured."""
    from ontodetect.segment import seen_below, segment
    from test_segmentation import rect, slab

    rng = np.random.default_rng(1)  # a scan in which MSAC finds the seat among 8 planes
    floor = rect(rng, (0, 0, 0), (5, 0, 0), (0, 3, 0), 0.03)
    x0, y0 = 0.5, 0.5
    armchair = _armchair(rng, x0, y0)
    box = slab(rng, (2.6, 0.6, 0.0), (3.6, 1.2, 0.64))
    on_floor = ~(
        np.all((floor[:, :2] > (x0, y0)) & (floor[:, :2] < (x0 + 0.9, y0 + 0.85)), axis=1)
        | np.all((floor[:, :2] > (2.6, 0.6)) & (floor[:, :2] < (3.6, 1.2)), axis=1)
    )
    seg = segment(np.vstack([floor[on_floor], armchair, box]), seed=0)
    tops = {
        round(float(plane.centroid[0])): share
        for plane, share in _level_shares(seg, seen_below(seg))
        if plane.height > 0.55 and plane.area > 0.2
    }
    assert tops[3] < 0.05  # the box's top hides what is under it
    assert max(s for x, s in tops.items() if x < 2) > 0.25  # the seat shows inside the U


def test_covered_finds_a_top_over_a_shelf_and_nothing_over_an_armchairs_seat():
    """A desk's top covers the shelf under it; an armchair's arms stand beside its seat,
    not over it. Tilted planes are not measured; nothing higher, nothing covered."""
    from ontodetect.segment import covered_above, segment
    from test_segmentation import rect

    rng = np.random.default_rng(1)
    floor = rect(rng, (0, 0, 0), (5, 0, 0), (0, 3, 0), 0.03)
    x0, y0 = 0.5, 0.5
    armchair = _armchair(rng, x0, y0)
    x1, y1 = 2.6, 0.6  # a desk 1.2 x 0.6: a top at 0.72 on two side panels, a shelf at 0.45
    desk = np.vstack(
        [
            rect(rng, (x1, y1, 0.72), (1.2, 0, 0), (0, 0.6, 0)),
            rect(rng, (x1, y1, 0.0), (0, 0.6, 0), (0, 0, 0.72)),
            rect(rng, (x1 + 1.2, y1, 0.0), (0, 0.6, 0), (0, 0, 0.72)),
            rect(rng, (x1, y1, 0.45), (1.2, 0, 0), (0, 0.6, 0)),
        ]
    )
    on_floor = ~np.all((floor[:, :2] > (x0, y0)) & (floor[:, :2] < (x0 + 0.9, y0 + 0.85)), axis=1)
    seg = segment(np.vstack([floor[on_floor], armchair, desk]), seed=0)
    level = {
        (round(float(plane.centroid[0])), float(plane.height) > 0.6): share
        for plane, share in _level_shares(seg, covered_above(seg))
        if plane.area > 0.15
    }
    assert level[(3, False)] > 0.9  # the desk's shelf, under its top
    assert level[(3, True)] == 0.0  # nothing over the desk's top
    assert level[(1, False)] < 0.15  # the armchair's arms stand beside its seat
    assert level[(1, True)] == 0.0  # nor does anything stand over the arms


def _level_clusters(rng, *groups, turn=0.0, move=(0.0, 0.0, 0.0)):
    """Stand-in clusters for ``runs_on``: each a list of (corner, u, v) rectangles (planes)
    and the voxel ids it holds, the whole scene turned about the vertical by ``turn``
    degrees and moved by ``move``."""
    from types import SimpleNamespace

    from test_segmentation import rect

    pose = yaw_pose(move[0], move[1], math.radians(turn), move[2])
    out = []
    for rects, voxels in groups:
        centers, planes = [], []
        for corner, u, v in rects:
            pts = rect(rng, corner, u, v, 0.02) @ pose[:3, :3].T + pose[:3, 3]
            normal = np.cross(u, v) / np.linalg.norm(np.cross(u, v))
            first = sum(len(p) for p in centers)
            centers.append(pts)
            planes.append(
                SimpleNamespace(
                    tilt=math.degrees(math.acos(min(1.0, abs(float(normal[2]))))),
                    length=float(max(np.linalg.norm(u), np.linalg.norm(v))),
                    inliers=np.arange(first, first + len(pts)),
                )
            )
        out.append(
            SimpleNamespace(
                centers=np.vstack(centers), scored_planes=planes, voxels=np.asarray(voxels)
            )
        )
    return out


#: A chair-long piece of a bench (its seat and back), the rest of the bench's seat 2 cm on,
#: an arm's top 10 cm higher touching the seat, a seat at the same height 30 cm aside, and
#: a candidate overlapping the piece (sharing its voxels) that holds the same seat again.
_RUN_ON_SCENE = (
    (
        [
            ((0.0, 0.0, 0.45), (0.5, 0, 0), (0, 0.45, 0)),
            ((0.0, 0.45, 0.45), (0.5, 0, 0), (0, 0, 0.4)),
        ],
        [0, 1, 2],
    ),
    ([((0.52, 0.0, 0.46), (1.5, 0, 0), (0, 0.45, 0))], [3]),  # the rest of the bench
    ([((-0.12, 0.0, 0.55), (0.1, 0, 0), (0, 0.45, 0))], [4]),  # an arm's top, a step up
    ([((0.0, -0.75, 0.45), (0.5, 0, 0), (0, 0.45, 0))], [5]),  # a seat 30 cm aside
    ([((-0.3, 0.0, 0.45), (0.85, 0, 0), (0, 0.45, 0))], [2, 6]),  # overlapping candidate
)


def test_runs_on_measures_a_seat_that_goes_on_into_another_cluster():
    """A level plane continued at its height and touching by another cluster's level plane
    takes that plane's length; a step up, a seat out of reach and a cluster sharing its
    voxels give 0; tilted planes are not measured."""
    from ontodetect.segment import runs_on

    values = runs_on(_level_clusters(np.random.default_rng(0), *_RUN_ON_SCENE))
    assert values[0][0] == pytest.approx(1.5)  # the piece's seat goes on as the bench
    assert math.isnan(values[0][1])  # its back: upright
    assert values[1] == [pytest.approx(0.85)]  # the bench goes on into the overlapping one
    assert values[2] == [0.0] and values[3] == [0.0]
    assert values[4] == [pytest.approx(1.5)]  # it shares voxels with the piece, not the bench


@given(
    turn=st.floats(-180, 180, allow_nan=False),
    move=st.tuples(*[st.floats(-50, 50, allow_nan=False)] * 3),
)
@settings(max_examples=20, deadline=None)
def test_runs_on_does_not_depend_on_where_the_scene_stands(turn, move):
    """The same clusters turned about the vertical and moved give the same lengths."""
    from ontodetect.segment import runs_on

    here = runs_on(_level_clusters(np.random.default_rng(0), *_RUN_ON_SCENE))
    there = runs_on(_level_clusters(np.random.default_rng(0), *_RUN_ON_SCENE, turn=turn, move=move))
    assert there == [[pytest.approx(v, nan_ok=True) for v in row] for row in here]


def _runs_on_by_definition(seg):
    """``runs_on`` pair by pair, every level plane against every other cluster's."""
    from ontodetect.segment._measure import RUN_ON_GAP, RUN_ON_STEP

    out = []
    for i, c in enumerate(seg):
        row = []
        for p in c.scored_planes:
            if p.tilt > 10:
                row.append(math.nan)
                continue
            mine = c.centers[p.inliers]
            best = 0.0
            for j, o in enumerate(seg):
                if j == i or np.intersect1d(c.voxels, o.voxels).size:
                    continue
                for q in o.scored_planes:
                    theirs = o.centers[q.inliers]
                    if q.tilt > 10 or abs(np.median(theirs[:, 2]) - np.median(mine[:, 2])) > (
                        RUN_ON_STEP
                    ):
                        continue
                    d = np.linalg.norm(mine[:, None, :] - theirs[None, :, :], axis=2)
                    if d.min() <= RUN_ON_GAP:
                        best = max(best, q.length)
            row.append(best)
        out.append(row)
    return out


@given(seed=st.integers(0, 2**32 - 1))
@settings(max_examples=10, deadline=None)
def test_runs_on_is_its_definition_on_many_clusters(seed):
    """The spatial index finds the planes pair-by-pair comparison finds: random level and
    upright planes at a few heights, some clusters sharing voxels."""
    from types import SimpleNamespace

    from ontodetect.segment import runs_on

    rng = np.random.default_rng(seed)
    seg = []
    for i in range(60):
        corner, planes, pts = rng.uniform(0, 6, 2), [], []
        for q in range(int(rng.integers(1, 4))):
            z = float(rng.choice([0.44, 0.45, 0.47, 0.75]))
            xy = corner + rng.uniform(0, rng.uniform(0.1, 1.2), (20, 2))
            pts.append(np.column_stack([xy, z + rng.normal(0, 0.004, 20)]))
            planes.append(
                SimpleNamespace(
                    tilt=float(rng.choice([1.0, 80.0])),
                    length=float(rng.uniform(0.1, 1.5)),
                    inliers=np.arange(20 * q, 20 * (q + 1)),
                )
            )
        first = (i - 1 if rng.random() < 0.1 else i) * 100  # a tenth share a neighbour's
        seg.append(
            SimpleNamespace(
                centers=np.vstack(pts), scored_planes=planes, voxels=np.arange(first, first + 50)
            )
        )
    got, want = runs_on(seg), _runs_on_by_definition(seg)
    assert got == [[pytest.approx(v, nan_ok=True) for v in row] for row in want]


@pytest.mark.parametrize("seed", [0, 1])
def test_sunk_finds_a_basins_bowl_under_its_rim_and_nothing_under_a_table(seed):
    """Inside a basin's rim its bowl lies 12-20 cm lower; inside a desk's, a table's or a
    kitchen counter's top nothing of them does (legs, panels and aprons stand at the
    edge). Tilted planes are not measured."""
    from ontodetect.segment import segment, sunk_below
    from ontodetect.synth.furniture import make_furniture
    from ontodetect.synth.rooms import object_scene

    kinds = ["sink-wall-hung", "sink-pedestal", "desk-pedestal", "table-dining", "kitchen-counter"]
    shares = {}
    for kind in kinds:
        item = make_furniture(kind, seed, backsplash=True) if kind.startswith("sink") else kind
        cloud, scene = object_scene([item], points=40_000, seed=seed)
        seg = segment(cloud, seed=seed)
        inst = np.asarray(cloud.fields["instance"])
        (obj,) = (o.instance_id for o in scene.objects if o.kind == kind)
        tops = [
            share
            for c, v in zip(seg, sunk_below(seg), strict=True)
            if np.mean(inst[c.point_indices] == obj) > 0.5
            for plane, share in _level_shares([c], [v])
            if plane.height > 0.6 and plane.area > 0.1
        ]
        shares[kind] = max(tops)  # the rim or the top: the largest level plane up there
    assert shares["sink-wall-hung"] > 0.5 and shares["sink-pedestal"] > 0.5, shares
    assert max(shares[k] for k in kinds[2:]) < 0.2, shares


def _rows(a, b):
    return np.arange(a, b, dtype=np.int64)


def test_majority_keeps_what_most_passes_found():
    from ontodetect.pipeline import majority_labels

    chair, table, lone = _rows(0, 10), _rows(20, 30), _rows(40, 50)
    first = {0: "chair", 2: "chair"}
    others = [
        [("chair", chair), ("table", table)],
        [("table", table[1:]), ("chair", _rows(3, 13))],  # IoU 7/13 with the chair
    ]
    kept = majority_labels([chair, table, lone], first, others)
    # The chair: all three passes; the table: missed by the first pass, found by both
    # others; the lone chair only by the first pass: gone.
    assert kept == {0: ("chair", 3), 1: ("table", 2)}
    # Below the IoU needed a detection does not back a cluster.
    assert majority_labels([chair], {}, [[("chair", _rows(6, 16))]] * 2) == {}
    # Passes that disagree on the label: the majority label wins.
    split = [[("table", chair)], [("table", chair)], [("chair", chair)]]
    assert majority_labels([chair], {0: "chair"}, split) == {}
    assert majority_labels([chair], {0: "table"}, split) == {0: ("table", 3)}


def test_a_pass_that_cut_the_points_otherwise_abstains():
    """Given every cluster of the other passes, a pass none of whose clusters matches a
    first-pass cluster (point IoU >= 0.5) leaves the vote on it: the majority is of the
    passes that made that cluster."""
    from ontodetect.pipeline import majority_labels, pass_probabilities

    chair, desk = _rows(0, 10), _rows(10, 40)
    merged = _rows(0, 40)  # the chair and the desk it stands under, one cluster
    pieces = [_rows(0, 3), _rows(3, 7), _rows(7, 10)]  # the chair cut in three
    # Both other passes merged the chair with the desk and call that a table.
    others = [[("table", merged)], [("table", merged)]]
    assert majority_labels([chair], {0: "chair"}, others) == {}
    assert majority_labels([chair], {0: "chair"}, others, seen=[[merged], [merged]]) == {
        0: ("chair", 1)
    }
    # One pass cut it in three, the other made the same cluster and found it a chair.
    others = [[], [("chair", chair)]]
    seen = [pieces, [chair, desk]]
    assert majority_labels([chair], {0: "chair"}, others, seen=seen) == {0: ("chair", 2)}
    # A pass that made the same cluster and found no object there still votes against.
    assert majority_labels([chair], {0: "chair"}, [[], []], seen=[[chair], pieces]) == {}
    # Without the first pass's label the abstainers cannot make a majority of one.
    assert majority_labels([chair], {}, [[], [("chair", chair)]], seen=[pieces, [chair]]) == {}
    # The mean leaves the abstainer out instead of counting it as "none".
    first = [{"chair": 0.6, "none": 0.4}]
    runs = [
        [(h, {"chair": 0.9, "none": 0.1}) for h in pieces],
        [(chair, {"chair": 0.8, "none": 0.2})],
    ]
    assert pass_probabilities([chair], first, runs)[0] == pytest.approx(
        {"chair": 1.4 / 3, "none": 1.6 / 3}
    )
    assert pass_probabilities([chair], first, runs, abstain=True)[0] == pytest.approx(
        {"chair": 0.7, "none": 0.3}
    )
    with pytest.raises(InvalidParameterError, match="seen"):
        majority_labels([chair], {0: "chair"}, [[], []], seen=[pieces])


def test_pass_probabilities_average_the_covering_clusters():
    from ontodetect.pipeline import pass_probabilities

    chair, other = np.arange(100), np.arange(200, 300)
    first = [{"chair": 0.1, "table": 0.2, "none": 0.7}, {"table": 0.6, "none": 0.4}]
    others = [
        # A cluster that covers the chair (IoU 0.9) and one beside it (IoU 0).
        [(np.arange(10, 100), {"chair": 0.7, "none": 0.3}), (other + 50, {"table": 1.0})],
        # Too little of the chair (IoU 0.4): this pass saw no object there.
        [(np.arange(60, 100), {"chair": 0.9, "none": 0.1}), (other, {"table": 0.9, "none": 0.1})],
    ]
    got = pass_probabilities([chair, other], first, others)
    assert got[0] == pytest.approx({"chair": 0.8 / 3, "table": 0.2 / 3, "none": 2.0 / 3})
    # other + 50 covers half of it with IoU 1/3: below VOTE_IOU, a "none".
    assert got[1] == pytest.approx({"table": 1.5 / 3, "none": 1.5 / 3})
    assert all(sum(p.values()) == pytest.approx(1.0) for p in got)
    assert pass_probabilities([], [], others) == []


def test_pass_ballots_say_what_every_pass_made_of_a_cluster():
    from ontodetect.pipeline import VOTE_IOU, pass_ballots

    chair, lone = np.arange(100), np.arange(500, 520)
    first = [(chair, {"chair": 0.8, "none": 0.2}, "chair"), (lone, {"none": 1.0}, None)]
    others = [
        # The chair whole (IoU 0.9) and a bit of it (IoU 0.1): the larger share speaks.
        [(np.arange(10, 100), {"chair": 0.7, "none": 0.3}, "chair"), (np.arange(10), {}, None)],
        # The chair merged with a table (IoU 100 / 300): a table, too little to count.
        [(np.arange(300), {"table": 0.6, "chair": 0.1, "none": 0.3}, "table")],
    ]
    got = pass_ballots({0: chair, 1: lone}, first, others, [0.7, -0.7])
    a = got[0]
    assert [b.turn for b in a] == [0.0, 0.7, -0.7]
    assert [b.label for b in a] == ["chair", "chair", "table"]
    assert [b.best for b in a] == ["chair", "chair", "table"]
    assert a[1].iou == pytest.approx(0.9) and a[1].probability == pytest.approx(0.7)
    assert a[2].iou == pytest.approx(1 / 3) and a[2].iou < VOTE_IOU and a[2].num_points == 300
    assert [b.counts for b in a] == [True, True, False]
    # No cluster of a pass shares a point with the lone cluster: an empty ballot.
    assert [(b.label, b.iou, b.num_points, b.best) for b in got[1][1:]] == [
        (None, 0.0, 0, None)
    ] * 2
    assert a[2].to_dict()["counts"] is False and a[2].to_dict()["class"] == "table"
    assert pass_ballots({}, first, others, [0.7, -0.7]) == {}
    with pytest.raises(InvalidParameterError, match="turns"):
        pass_ballots({0: chair}, first, others, [0.7])


def test_class_for_label_takes_the_cheapest_reported_class():
    """A detection the first pass left out is reported as the class of its label that the
    energy ranks first, not the first such class in the file."""
    from ontodetect.errors import InvalidParameterError
    from ontodetect.ontology import builtin_ontology
    from ontodetect.pipeline import class_for_label

    o = builtin_ontology()
    assert (
        class_for_label(o, "table", {"table": 0.6, "side_table": 0.4, "chair": 0.1}) == "side_table"
    )
    assert class_for_label(o, "table", {"table": 0.4, "side_table": 0.6}) == "table"
    assert class_for_label(o, "table", {}) == "side_table"  # no costs: by name
    assert class_for_label(o, "chair", {"side_table": 0.1}) == "chair"
    with pytest.raises(InvalidParameterError, match="label"):
        class_for_label(o, "stool", {"stool": 0.1})  # not reported


def test_vote_turns_alternate():
    from ontodetect.pipeline import vote_turns

    assert vote_turns(1, 0.7) == []
    assert vote_turns(4, 0.5) == [0.5, -0.5, 1.0]


def test_votes_keep_detections_in_the_input_frame(dining):
    from ontodetect.config import Config

    one = detect(dining, config=Config().replace(detect={"votes": 1}))
    three = detect(dining, config=Config().replace(detect={"votes": 3}))
    # Passes in worker processes or all here: the same result.
    here = detect(dining, config=Config().replace(detect={"votes": 3}), jobs=1)
    a, b = three.to_dict(), here.to_dict()
    a.pop("timings"), b.pop("timings")
    assert a == b
    assert "votes" in three.timings
    labels = [d.label for d in three.detections]
    assert labels.count("chair") >= 2 and "table" in labels
    truth = dining.fields["class_id"]
    names = {5: "chair", 6: "sofa", 7: "table", 14: "table"}
    for d in three.detections:
        assert d.votes in (2, 3) and d.to_dict()["votes"] == d.votes
        # The probabilities are means over the passes, and the score is the label's: a
        # table's is the table's and the side table's (both written "table").
        same = {"table": ("table", "side_table")}.get(d.label, (d.label,))
        assert d.score == pytest.approx(sum(d.probabilities[n] for n in same))
        assert d.score >= 0.15 * d.votes / 3
        ids, counts = np.unique(truth[d.point_indices], return_counts=True)
        assert names.get(int(ids[np.argmax(counts)])) == d.label, d
        # The box is in the input frame, around the object's points.
        pts = dining.xyz[d.point_indices]
        assert np.all(d.center[:2] > pts[:, :2].min(axis=0))
        assert np.all(d.center[:2] < pts[:, :2].max(axis=0))
    assert all(d.votes is None for d in one.detections)
    # What every pass made of each detection's points: the passes counted are its votes.
    for d in three.detections:
        ballots = three.ballots[d.cluster]
        assert [b.turn for b in ballots] == [0.0, 0.7, -0.7]
        assert sum(b.counts and b.label == d.label for b in ballots) == d.votes
    assert one.ballots == {}
    # A cloud denser than detect.vote_max_points gets one pass.
    dense = detect(dining, config=Config().replace(detect={"vote_max_points": 1000}))
    assert [d.to_dict() for d in dense.detections] == [d.to_dict() for d in one.detections]
    label, instance = three.point_labels()
    assert set(label[instance > 0]) == {three.class_names.index(d.label) for d in three.detections}
    assert set(np.unique(instance)) == {0, *(d.id for d in three.detections)}


def test_a_failed_first_labelling_stops_the_vote_workers(dining, monkeypatch):
    # The workers start before the first labelling and wait for the priors it gives: when
    # it fails, the error reaches the caller and the workers are let go (no hang).
    from ontodetect.pipeline import _detect

    def fail(*args, **kwargs):
        raise RuntimeError("first labelling failed")

    monkeypatch.setattr(_detect, "_room_pass", fail)
    with pytest.raises(RuntimeError, match="first labelling failed"):
        detect(dining, jobs=2)


def test_vote_workers_fork_only_when_safe():
    import threading

    from ontodetect._parallel import cpu_count
    from ontodetect.pipeline._detect import _vote_workers

    assert _vote_workers(1, 2) == 0 and _vote_workers(4, 0) == 0
    assert _vote_workers(4, 2) == 2 and _vote_workers(2, 4) == 2
    # 0: one per usable CPU, as the evaluation's jobs=0.
    assert _vote_workers(0, 2) == (min(2, cpu_count()) if cpu_count() > 1 else 0)
    # Another thread in this process: no fork, the passes run here.
    stop = threading.Event()
    other = threading.Thread(target=stop.wait)
    other.start()
    try:
        assert _vote_workers(None, 2) == 0
        assert _vote_workers(4, 2) == 2  # asked for: the caller knows its threads
    finally:
        stop.set()
        other.join()
    with pytest.raises(InvalidParameterError, match="'jobs'"):
        _vote_workers(-1, 2)


def _tiny_detections(_):
    from ontodetect.synth import synthesize

    return sorted(d.label for d in detect(synthesize("tiny", seed=1).cloud).detections)


def test_votes_inside_a_pool_worker():
    # multiprocessing.Pool workers are daemonic and may not fork: the passes run there.
    import multiprocessing

    if "fork" not in multiprocessing.get_all_start_methods():
        pytest.skip("needs fork")
    with multiprocessing.get_context("fork").Pool(1) as pool:
        assert pool.map(_tiny_detections, [0]) == [_tiny_detections(0)]


def test_blas_libraries_keep_one_thread_while_detecting_and_theirs_afterwards(monkeypatch):
    threadpoolctl = pytest.importorskip("threadpoolctl")
    from ontodetect import _parallel

    def blas_threads():
        return [
            i["num_threads"] for i in threadpoolctl.threadpool_info() if i["user_api"] == "blas"
        ]

    @_parallel.one_blas_thread
    def inside():
        return blas_threads()

    with threadpoolctl.threadpool_limits(limits=2, user_api="blas"):
        before = blas_threads()
        assert inside() == [1] * len(before)
        assert blas_threads() == before
    # the detection itself runs under the limit
    seen = []
    from ontodetect.pipeline import _detect

    original = _detect._one_pass

    def spy(*args, **kwargs):
        seen.append(blas_threads())
        return original(*args, **kwargs)

    monkeypatch.setattr(_detect, "_one_pass", spy)
    detect(synthesize("tiny", seed=1).cloud, jobs=1)
    assert seen and all(set(s) <= {1} for s in seen)
