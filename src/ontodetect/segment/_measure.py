"""Scene measurements the ontology's scoring needs beyond a cluster's own planes: what
stands beside a cluster (:func:`shelter_heights`), what it hides from a single view
(:func:`hidden_heights`), whether the floor shows under its tops (:func:`open_below`),
whether a lower surface of the cluster shows inside a top's outline (:func:`seen_below`)
and whether something of it is sunk just under a top, as a basin's bowl is under its rim
(:func:`sunk_below`); :func:`describe_clusters` gathers them into the scoring's input.
"""

from __future__ import annotations

import functools
import itertools
import math
from collections.abc import Callable, Sequence
from typing import Any

import numpy as np
from numpy.typing import NDArray

from ..geometry import box_footprint
from ..ontology import ClusterDescription
from ..ontology._features import HIDDEN_DEPTH
from ..ontology._score import (
    HIDDEN_MARGIN,
    HIDDEN_SEAT_TOP,
    HORIZONTAL_TILT,
    LEG_SHARE,
    SHELTER_AREA,
    SHELTER_TOLERANCE,
)
from ..preprocess._structure import FLOOR, WALL
from ._segmentation import Cluster, Segmentation

__all__ = [
    "FLOOR_CELL",
    "OPEN_BELOW_HEIGHT",
    "OPEN_BELOW_RIM",
    "RUN_ON_GAP",
    "RUN_ON_STEP",
    "SEEN_BELOW_CELL",
    "SEEN_BELOW_DROP",
    "SELF_SHADOW",
    "SELF_SHADOW_DISTANCE",
    "SHELTER_AREA",
    "SHELTER_GAP",
    "SUNK_DEPTH",
    "SUNK_RIM",
    "covered_above",
    "describe_cluster",
    "describe_clusters",
    "hidden_heights",
    "open_below",
    "runs_on",
    "seen_below",
    "shelter_heights",
    "sight_shelters",
    "standing_base",
    "sunk_below",
    "wall_gaps",
]


def describe_cluster(
    cluster: Cluster,
    shelter: float = -math.inf,
    ceiling: float = math.inf,
    hidden_below: float = -math.inf,
    open_below: Sequence[float] | None = None,
    seen_below: Sequence[float] | None = None,
    covered: Sequence[float] | None = None,
    sunk: Sequence[float] | None = None,
    runs_on: Sequence[float] | None = None,
    wall_gap: float = math.nan,
) -> ClusterDescription:
    """What the ontology scoring needs to know about a cluster (``shelter``: see
    :func:`shelter_heights`; ``ceiling``: the top of the search volume;
    ``hidden_below``: see :func:`hidden_heights`; ``open_below``: see
    :func:`open_below`; ``seen_below``, ``covered``, ``sunk`` and ``runs_on``: see
    :func:`seen_below`, :func:`covered_above`, :func:`sunk_below` and :func:`runs_on`;
    ``wall_gap``: see :func:`wall_gaps`)."""
    return ClusterDescription(
        planes=cluster.scored_planes,
        relations=cluster.scored_relations,
        length=cluster.length,
        breadth=cluster.breadth,
        height=cluster.height,
        bottom=cluster.bottom,
        shelter=shelter,
        ceiling=ceiling,
        hidden_below=hidden_below,
        open_below=open_below,
        base=standing_base(cluster.centers[:, 2]),
        wall_gap=float(wall_gap),
        scene={
            name: values
            for name, values in (
                ("seen_below", seen_below),
                ("covered", covered),
                ("sunk", sunk),
                ("runs_on", runs_on),
            )
            if values is not None
        },
    )


def standing_base(heights: NDArray[np.float64]) -> float:
    """Height above the floor (m) under which ``LEG_SHARE`` of a cluster's voxel heights
    lie (``ClusterDescription.base``; ``-inf`` for no voxels).

    A chair seen from behind in a single view shows its legs under the backrest that hides
    its seat: a few narrow uprights, less than a tenth of its voxels, so its base is above
    them. A cabinet's front, a desk's panel or a sofa's side that reaches the floor puts
    its base at the floor.

    Examples
    --------
    >>> import numpy as np
    >>> back = np.linspace(0.45, 0.9, 95)  # a backrest's voxels, and five of its legs'
    >>> round(standing_base(np.r_[np.linspace(0.0, 0.4, 5), back]), 2)
    0.47
    >>> round(standing_base(np.linspace(0.0, 0.9, 100)), 2)  # a panel down to the floor
    0.09
    """
    z = np.asarray(heights, dtype=np.float64)
    return float(np.quantile(z, LEG_SHARE)) if z.size else -math.inf


def describe_clusters(
    seg: Segmentation, viewpoint: Sequence[float] | None = None
) -> list[ClusterDescription]:
    """:func:`describe_cluster` for every cluster, with what stands beside it and the
    altitude cut-off of the search.

    ``viewpoint`` is the sensor's position in the input frame when the scan is one view
    (:func:`ontodetect.cloud.sensor_position`); then a cluster may also hide what
    stands behind it (:func:`hidden_heights`), and whether the floor shows under a top
    (:func:`open_below`) is not measured, since the top itself hides most of it.
    """
    ceiling = float(seg.config.prepare.altitude_cutoff)
    hidden = np.full(len(seg), -math.inf)
    shelter = shelter_heights(seg)
    if viewpoint is not None and len(seg):
        eye = seg.prepared.level(np.asarray(viewpoint, dtype=np.float64))[0]
        hidden = hidden_heights(
            np.array([c.height for c in seg], dtype=np.float64),
            np.array([c.box.center[:2] for c in seg], dtype=np.float64),
            eye,
        )
        shelter = np.maximum(shelter, sight_shelters(seg, eye))
    # From one view the floor under a top is hidden by the top itself: not measured there.
    below = open_below(seg) if viewpoint is None else [None] * len(seg)
    lower, higher, sunk = _outline_shares(seg, (-1, 1), sunk=True)
    onward = runs_on(seg)
    walls = wall_gaps(seg)
    return [
        describe_cluster(c, float(h), ceiling, float(b), o, s, a, k, r, float(w))
        for c, h, b, o, s, a, k, r, w in zip(
            seg,
            shelter,
            hidden,
            below,
            lower,
            higher,
            sunk,
            onward,
            walls,
            strict=True,
        )
    ]


#: The sight line to what a top hides is drawn to this far (m) under the cluster's lowest
#: point: as far as a part hidden below what is seen may begin.
SIGHT_DROP = HIDDEN_MARGIN
#: ... at the cluster's centre and this far (m) from it towards the sensor: a seat reaches
#: a seat's depth in front of its backrest (EN 1335-1: 380-470 mm).
SIGHT_REACH = (0.0, 0.2, 0.4)


def sight_shelters(seg: Segmentation, eye: Sequence[float]) -> NDArray[np.float64]:
    """(clusters,) in a single view, the height of the highest level plane of another
    cluster (``SHELTER_AREA`` or more) that a sight line from ``eye`` to ``SIGHT_DROP``
    under the cluster's lowest point (at its centre and ``SIGHT_REACH`` from it towards
    the sensor) crosses inside the plane's outline (``SEEN_BELOW_CELL`` grid), when the
    plane stands no lower than the cluster's lowest point less ``SHELTER_TOLERANCE``;
    ``-inf`` when none does, and for clusters no higher than ``HIDDEN_SEAT_TOP``.

    A chair seen across a table shows its backrest over the table's top: the top, not
    anything beside the chair, hides its seat, however far the chair stands back from it.
    :func:`shelter_heights` finds a top within ``SHELTER_GAP`` of the chair; this finds
    the one in the way. What rises no higher than a table's top may be a desk's panel
    seen under another desk's top, as with what a cluster hides itself
    (``ontology._score.HIDDEN_SEAT_TOP``).
    """
    eye = np.asarray(eye, dtype=np.float64)
    out = np.full(len(seg), -math.inf)
    tops = [
        (k, float(p.height), np.asarray(c.centers)[p.inliers, :2])
        for k, c in enumerate(seg)
        for p in _sheltering_planes(c)
    ]
    outlines: dict[int, NDArray[np.int64]] = {}
    for k, c in enumerate(seg):
        bottom = float(c.bottom)
        if eye[2] <= bottom or float(c.height) <= HIDDEN_SEAT_TOP:
            continue
        center = np.asarray(c.box.center, dtype=np.float64)[:2]
        toward = eye[:2] - center
        toward = toward / max(float(np.linalg.norm(toward)), 1e-9)
        targets = center + np.outer(SIGHT_REACH, toward)
        low = bottom - SIGHT_DROP
        for t, (j, z, xy) in enumerate(tops):
            if j == k or z < bottom - SHELTER_TOLERANCE or z >= eye[2] or z <= out[k]:
                continue
            s = (eye[2] - z) / (eye[2] - low)
            cross = eye[:2] + s * (targets - eye[:2])
            if t not in outlines:
                outlines[t] = _cells_inside(xy)
            if np.isin(_cell_keys(cross, SEEN_BELOW_CELL), outlines[t]).any():
                out[k] = z
    return out


def wall_gaps(seg: Segmentation) -> NDArray[np.float64]:
    """Per cluster, the horizontal distance (m) from its nearest voxel to the nearest voxel
    the preparation took as wall (``structure_label`` 2); NaN for every cluster when the
    scan shows no wall.

    What hangs on a wall, a radiator on its brackets (EN 442: 25-50 mm off it), stands
    within a few centimetres of one.
    """
    from scipy.spatial import cKDTree  # heavy: imported when used (start-up)

    out = np.full(len(seg), math.nan)
    prepared = seg.prepared
    wall = prepared.structure_label == WALL
    if not len(seg) or not wall.any():
        return out
    tree = cKDTree(prepared.centers[wall, :2])
    for k, c in enumerate(seg):
        if len(c.centers):
            out[k] = float(tree.query(np.asarray(c.centers)[:, :2], k=1)[0].min())
    return out


#: Cell of the horizontal grid on which :func:`open_below` compares a plane's footprint
#: with the floor seen (m).
FLOOR_CELL = 0.1
#: Under a lower plane (m above the floor) the floor is seldom seen from eye height, so
#: :func:`open_below` does not measure it: a coffee table looks closed below.
OPEN_BELOW_HEIGHT = 0.55
#: Rings of cells left out at the rim of a footprint, where the floor beyond the edge
#: and the foot of the sides show (fewer when nothing would be left).
OPEN_BELOW_RIM = 2


def _pack(ij: NDArray[np.int64]) -> NDArray[np.int64]:
    """One integer per grid cell (i, j)."""
    return (ij[:, 0] << 32) + (ij[:, 1] + (1 << 31))  # a step in j is a step of 1


def _cell_keys(xy: NDArray[np.float64], cell: float) -> NDArray[np.int64]:
    """One integer per ``cell`` cell of the points ``xy``."""
    return _pack(np.floor(xy / cell).astype(np.int64))


def _shrink(cells: NDArray[np.int64], rings: int) -> NDArray[np.int64]:
    """The packed grid ``cells`` less ``rings`` rings at their rim: those whose four
    neighbours are all in, ring by ring (fewer rings when nothing would be left)."""
    for _ in range(rings):
        inner = cells
        for step in ((1 << 32), -(1 << 32), 1, -1):
            inner = inner[np.isin(inner + step, cells)]
        if not len(inner):
            break
        cells = inner
    return cells


def open_below(seg: Segmentation) -> list[list[float]]:
    """Per cluster and plane, the share of a horizontal plane's footprint under which the
    floor was seen (0..1); NaN for tilted planes and planes lower than
    ``OPEN_BELOW_HEIGHT``, and for all when no floor was found.

    A top on legs or a pedestal leaves the floor under it open to the sensor; a cabinet,
    a bed, a box or an upholstered seat hides it. The footprint is the plane's cells on a
    ``FLOOR_CELL`` grid less ``OPEN_BELOW_RIM`` rings of cells at its rim (where the
    floor beyond the edge and the foot of a box's sides show), fewer when nothing would
    be left; the floor is the voxels the preparation labelled floor.
    """
    prep = seg.prepared
    floor = prep.voxels.centers[prep.structure_label == FLOOR]
    out: list[list[float]] = []
    if not prep.floor_found or not len(floor):
        return [[math.nan] * len(c.scored_planes) for c in seg]
    seen = np.unique(_cell_keys(floor[:, :2], FLOOR_CELL))
    for c in seg:
        values = []
        centers = np.asarray(c.centers)
        for plane in c.scored_planes:
            if float(plane.tilt) > HORIZONTAL_TILT or float(plane.height) < OPEN_BELOW_HEIGHT:
                values.append(math.nan)
                continue
            use = np.unique(_cell_keys(centers[plane.inliers, :2], FLOOR_CELL))
            use = _shrink(use, OPEN_BELOW_RIM)
            values.append(float(np.isin(use, seen).mean()))
        out.append(values)
    return out


#: Cell of the horizontal grid on which :func:`seen_below` compares a top's outline with
#: the surfaces under it (m): about the spacing of a 50,000-point room's points.
SEEN_BELOW_CELL = 0.05
#: A horizontal plane counts as under a top when its centroid lies at least this much
#: lower (m): two pieces of one top split by a seam differ by less (the continuation step
#: of the scoring, 5 cm), an armchair's seat lies 12 cm and more under its arms.
SEEN_BELOW_DROP = 0.1


def _cells_inside(xy: NDArray[np.float64]) -> NDArray[np.int64]:
    """The grid cells whose centres lie inside the convex hull of the points ``xy``
    (the occupied cells themselves when the hull is degenerate)."""
    from scipy.spatial import Delaunay, QhullError

    cells = np.floor(xy / SEEN_BELOW_CELL).astype(np.int64)
    own = np.unique(_pack(cells))
    lo, hi = cells.min(axis=0), cells.max(axis=0)
    ii, jj = np.meshgrid(np.arange(lo[0], hi[0] + 1), np.arange(lo[1], hi[1] + 1))
    ij = np.column_stack([ii.ravel(), jj.ravel()])
    try:
        hull = Delaunay(np.unique(cells, axis=0) + 0.5)
    except QhullError:
        return own
    inside = ij[hull.find_simplex(ij + 0.5) >= 0]
    return np.union1d(_pack(inside), own)


#: A basin's bowl is sunk 120-200 mm under its rim (catalogue washbasins and kitchen
#: sinks; EN 31 and EN 695 give their fixing dimensions, catalogues the bowl depths):
#: what lies this far (m) under a top, inside its outline, is sunk in it. The upper bound
#: is the deepest bowl and a few centimetres of scatter; the lower one clears the top's
#: own thickness and the scatter of its points.
SUNK_DEPTH = (0.04, 0.25)
#: Rings of ``SEEN_BELOW_CELL`` cells left out at the rim of a top's outline, where a
#: table's apron and a cabinet's front drop from its edge.
SUNK_RIM = 1


def _sunk_share(
    centers: NDArray[np.float64],
    z: float,
    outline: Callable[[], NDArray[np.int64]],
    boards: NDArray[np.bool_],
) -> float:
    """:func:`sunk_below` for one plane at height ``z`` (``outline``: its cells, worked out
    when first asked for; ``boards``: the cluster's points on its level planes, left out)."""
    lo, hi = SUNK_DEPTH
    depth = z - centers[:, 2]
    under = centers[(depth >= lo) & (depth <= hi) & ~boards, :2]
    if not len(under):
        return 0.0
    inner = _shrink(outline(), SUNK_RIM)
    cells = np.unique(_cell_keys(under, SEEN_BELOW_CELL))
    return float(np.isin(inner, cells).mean())


def _outline_shares(
    seg: Segmentation, signs: Sequence[int], *, sunk: bool = False
) -> list[list[list[float]]]:
    """For each ``sign`` in ``signs``, per cluster and plane, the share of a horizontal
    plane's outline over which another horizontal plane of the cluster was seen, lower
    (``sign`` -1) or higher (+1) by at least ``SEEN_BELOW_DROP``; NaN for tilted planes.
    With ``sunk``, :func:`sunk_below` after them. Each plane's outline is worked out once
    for all, and only when one of them needs it."""
    out: list[list[list[float]]] = [[] for _ in range(len(signs) + sunk)]
    for c in seg:
        centers = np.asarray(c.centers)
        planes = c.scored_planes
        flat = [float(p.tilt) <= HORIZONTAL_TILT for p in planes]
        if sunk:  # the cluster's points on its level planes, which no bowl is
            boards = np.zeros(len(centers), dtype=bool)
            for plane in itertools.compress(planes, flat):
                boards[np.asarray(plane.inliers)] = True
        values: list[list[float]] = [[] for _ in out]
        for i, plane in enumerate(planes):
            if not flat[i]:
                for row in values:
                    row.append(math.nan)
                continue
            outline = functools.cache(functools.partial(_cells_inside, centers[plane.inliers, :2]))
            z = float(plane.centroid[2])
            for sign, row in zip(signs, values, strict=False):  # the sunk row, if any, is last
                others = [
                    q
                    for k, q in enumerate(planes)
                    if flat[k] and sign * (float(q.centroid[2]) - z) >= SEEN_BELOW_DROP
                ]
                if not others:
                    row.append(0.0)
                    continue
                cells = [_cell_keys(centers[q.inliers, :2], SEEN_BELOW_CELL) for q in others]
                row.append(float(np.isin(outline(), np.unique(np.concatenate(cells))).mean()))
            if sunk:
                values[-1].append(_sunk_share(centers, z, outline, boards))
        for rows, row in zip(out, values, strict=True):
            rows.append(row)
    return out


def seen_below(seg: Segmentation) -> list[list[float]]:
    """Per cluster and plane, the share of a horizontal plane's outline (the convex hull of
    its points, on a ``SEEN_BELOW_CELL`` grid) over which a lower horizontal plane of the
    same cluster was seen (0..1); NaN for tilted planes.

    A closed top hides what lies under it: a cabinet's inside is never seen, so nothing
    shows within its outline. What is seen there was seen through the top, which is then
    no closed top: the U of a club armchair's arms and back top, with the seat inside
    it, lower. A horizontal plane lies under the top when its centroid is at least
    ``SEEN_BELOW_DROP`` lower.
    """
    return _outline_shares(seg, (-1,))[0]


def sunk_below(seg: Segmentation) -> list[list[float]]:
    """Per cluster and plane, the share of a horizontal plane's outline (the convex hull of
    its points on a ``SEEN_BELOW_CELL`` grid, less ``SUNK_RIM`` rings at its rim) over
    which points of the same cluster lie ``SUNK_DEPTH`` under it (0..1), those on the
    cluster's level planes left out; NaN for tilted planes.

    A basin's bowl is sunk in its rim: inside the rim's outline the cluster goes on
    12-20 cm lower, over most of it. A table's top is a plate over knee space (legs and
    apron stand at its edge), and a cabinet's top is closed: inside their outlines
    nothing of them shows just under the top. A board under a top (a desk's tray or
    shelf) is level and makes a plane, which :func:`seen_below` measures; a
    bowl is curved and seldom makes one, so this counts what no level plane holds.
    """
    return _outline_shares(seg, (), sunk=True)[0]


#: Two level planes of different clusters are one surface when the medians of their heights
#: differ by at most this (m: MSAC's band about a sagging seat) ...
RUN_ON_STEP = 0.03
#: ... and their points come within this of each other (m): touching, a voxel or two apart.
RUN_ON_GAP = 0.06


def runs_on(seg: Sequence[Any]) -> list[list[float]]:
    """Per cluster and plane, the length (m) of the longest level plane of another cluster
    that goes on from a level plane of this one, at its height (``RUN_ON_STEP``) and
    touching it (``RUN_ON_GAP``); 0 when none does; NaN for tilted planes. A cluster that
    shares voxels with this one (overlapping candidates of segmentation by recognition)
    does not count.

    A seat ends where its chair ends: a level surface at the seat's height that goes on into
    the next cluster for more than a place is the rest of a bench or a sofa the segmentation
    cut (a bench is cut where it is longer than a cluster may be), not a chair's.
    """
    from scipy.spatial import cKDTree  # lazy: only when clusters are described

    out: list[list[float]] = [[math.nan] * len(c.scored_planes) for c in seg]
    # Every level plane of every cluster: its cluster, index, height, length and points.
    level: list[tuple[int, int, float, float, NDArray[np.float64]]] = []
    for i, c in enumerate(seg):
        centers = np.asarray(c.centers)
        for k, p in enumerate(c.scored_planes):
            if float(p.tilt) <= HORIZONTAL_TILT:
                out[i][k] = 0.0
                pts = centers[np.asarray(p.inliers)]
                if len(pts):
                    level.append((i, k, float(np.median(pts[:, 2])), float(p.length), pts))
    if len(level) < 2:
        return out
    lo = np.array([pts.min(axis=0) for *_, pts in level]) - RUN_ON_GAP
    hi = np.array([pts.max(axis=0) for *_, pts in level]) + RUN_ON_GAP
    # Planes that touch have overlapping boxes, grown by the gap: found by their centres,
    # within the two half diagonals (a building floor holds tens of thousands of clusters).
    middle, half = (lo[:, :2] + hi[:, :2]) / 2, np.linalg.norm(hi[:, :2] - lo[:, :2], axis=1) / 2
    near = cKDTree(middle).query_ball_point(middle, half + half.max())
    shared: dict[tuple[int, int], bool] = {}
    for a, (i, k, z, _, mine) in enumerate(level):
        tree = None
        for b in near[a]:  # the result is the longest, whatever the order
            j, _, other_z, length, theirs = level[b]
            if j == i or length <= out[i][k] or abs(other_z - z) > RUN_ON_STEP:
                continue
            if not (np.all(lo[b] <= hi[a]) and np.all(hi[b] >= lo[a])):
                continue
            pair = (min(i, j), max(i, j))
            if pair not in shared:
                mine_voxels = getattr(seg[i], "voxels", None)
                theirs_voxels = getattr(seg[j], "voxels", None)
                shared[pair] = bool(
                    mine_voxels is not None
                    and theirs_voxels is not None
                    and np.intersect1d(mine_voxels, theirs_voxels).size
                )
            if shared[pair]:
                continue
            if tree is None:
                tree = cKDTree(mine)
            gap, _ = tree.query(theirs, k=1, distance_upper_bound=RUN_ON_GAP)
            if np.isfinite(gap).any():
                out[i][k] = length
    return out


def covered_above(seg: Segmentation) -> list[list[float]]:
    """Per cluster and plane, the share of a horizontal plane's outline over which a higher
    horizontal plane of the same cluster was seen (0..1, at least ``SEEN_BELOW_DROP``
    higher); NaN for tilted planes.

    Nothing of a chair stands over its seat, where someone sits: its arms stand beside
    the seat and its back behind it. A desk's pedestal or a shelf under a top is covered.
    """
    return _outline_shares(seg, (1,))[0]


#: What a cluster hides behind it must lie in its shadow for at least this far (m),
#: about the depth of a seat behind its backrest: the depth the scoring lets a single
#: view's cluster go on behind what is seen (``ontology._features.HIDDEN_DEPTH``).
SELF_SHADOW = HIDDEN_DEPTH
#: The sensor must stand at least this far (m, horizontally) from the cluster's centre.
SELF_SHADOW_DISTANCE = 0.5


def hidden_heights(tops: NDArray, centers: NDArray, eye: Sequence[float]) -> NDArray:
    """(clusters,) height under which each cluster hides what stands behind it.

    Seen over an object's top at height ``top`` from an eye at height ``eye_z`` and
    horizontal distance ``d``, the sight line comes down to height ``h`` only
    ``(top − h) · d / (eye_z − top)`` beyond the object. Whatever stands behind it
    lower than ``top − SELF_SHADOW · (eye_z − top) / d`` is out of sight for at least
    ``SELF_SHADOW``: that height is returned (the top itself when the eye is not
    above it), and ``-inf`` when the eye stands closer than ``SELF_SHADOW_DISTANCE``.

    Parameters
    ----------
    tops : (k,) float
        Top of each cluster above the floor (levelled frame).
    centers : (k, 2) float
        Horizontal centre of each cluster (levelled frame).
    eye : (3,) float
        The sensor's position in the levelled frame.

    Examples
    --------
    >>> import numpy as np
    >>> tops, centers = np.array([0.9, 0.9, 1.6]), np.array([[2.0, 0], [0.3, 0], [2.0, 0]])
    >>> hidden_heights(tops, centers, [0.0, 0.0, 1.5]).round(3).tolist()
    [0.81, -inf, 1.6]
    """
    tops = np.asarray(tops, dtype=np.float64)
    eye = np.asarray(eye, dtype=np.float64)
    d = np.linalg.norm(np.asarray(centers, dtype=np.float64).reshape(-1, 2) - eye[:2], axis=1)
    above = np.maximum(eye[2] - tops, 0.0)
    hidden = tops - SELF_SHADOW * above / np.maximum(d, 1e-9)
    return np.where(d >= SELF_SHADOW_DISTANCE, hidden, -math.inf)


#: Horizontal planes of at least SHELTER_AREA (m², ontology._score) can hide what stands
#: within this horizontal gap of their cluster's box (m).
SHELTER_GAP = 0.4


def _footprint(box: Any) -> NDArray:
    """(2, 2) min and max corner of the xy rectangle around an upright box."""
    xy = box_footprint(box.center, box.size, box.yaw)
    return np.stack([xy.min(axis=0), xy.max(axis=0)])


#: Clusters compared at once by :func:`shelter_heights` (bounds its memory).
SHELTER_BLOCK = 2048


def shelter_heights(seg: Segmentation) -> NDArray:
    """(clusters,) height of the highest large horizontal surface beside each cluster.

    For every cluster, the highest horizontal plane (a desk or table top) of any other
    cluster whose footprint comes within ``SHELTER_GAP`` of its own; ``-inf`` when there
    is none. A chair pushed under a desk shows only its backrest above the desk's top:
    this is what tells the scoring its seat may be hidden rather than absent.
    """
    n = len(seg)
    tops = np.full(n, -math.inf)
    boxes = np.zeros((n, 2, 2))
    for k, c in enumerate(seg):
        tops[k] = max((float(p.height) for p in _sheltering_planes(c)), default=-math.inf)
        boxes[k] = _footprint(c.box)
    return nearest_tops(boxes, tops)


def _sheltering_planes(cluster: Any) -> list[Any]:
    """The cluster's planes that can hide a part of another cluster: horizontal, at least
    ``SHELTER_AREA`` large (:func:`shelter_heights`, :func:`sight_shelters`)."""
    return [
        p
        for p in cluster.planes
        if float(p.tilt) < HORIZONTAL_TILT and float(p.area) >= SHELTER_AREA
    ]


def nearest_tops(boxes: NDArray[np.float64], tops: NDArray[np.float64]) -> NDArray[np.float64]:
    """For each footprint ``boxes[k]`` (``[[xmin, ymin], [xmax, ymax]]``), the highest of
    the other footprints' ``tops`` within ``SHELTER_GAP`` of it (``-inf``: none).

    Only footprints with a finite top can shelter another, so every footprint is compared
    with those alone, a block of rows at a time: a building floor has tens of thousands of
    clusters, and an all-pairs table of them would not fit in memory.

    Examples
    --------
    >>> boxes = np.array([[[0, 0], [1, 1]], [[1.05, 0], [2, 1]], [[5, 5], [6, 6]]], float)
    >>> nearest_tops(boxes, np.array([0.75, -np.inf, 0.7])).tolist()
    [-inf, 0.75, -inf]
    """
    n = len(boxes)
    out = np.full(n, -math.inf)
    shelters = np.flatnonzero(np.isfinite(tops))
    if n == 0 or not len(shelters):
        return out
    theirs = boxes[shelters]
    for start in range(0, n, SHELTER_BLOCK):
        rows = np.arange(start, min(n, start + SHELTER_BLOCK))
        mine = boxes[rows]
        gap = np.maximum(
            theirs[None, :, 0] - mine[:, None, 1], mine[:, None, 0] - theirs[None, :, 1]
        )
        near = np.all(gap <= SHELTER_GAP, axis=2) & (rows[:, None] != shelters[None, :])
        out[rows] = np.where(near, tops[shelters][None, :], -math.inf).max(axis=1)
    return out
