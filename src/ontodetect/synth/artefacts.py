"""Artefacts of real scans, applied to a simulated (or any) point cloud.

Pure functions: each takes a :class:`~ontodetect.cloud.PointCloud` and ``rng`` and returns a
new cloud whose colours, normals, per-point fields (``instance``, ``class_id`` ...) and rows
(``index``) stay aligned with its points, and whose ``meta["artefacts"]`` lists what was done
(JSON-ready dicts, in order), so that a scan written afterwards records its own making.

- :func:`scannet_sampling`: a dense fused scan reduced to 50,000 points as ScanNet's VoteNet
  preprocessing samples its mesh vertices (a uniform random subsample, in random order);
- :func:`duplicate_floor_layer`: part of the floor seen a second time, 2-10 cm higher or lower
  and slightly tilted, as a SLAM map with drift keeps it (labelled floor);
- :func:`punch_holes`: discs of surface the sensor never saw;
- :func:`tilt`: the whole scan turned a few degrees about a horizontal axis (a sensor whose
  gravity estimate is off).

Single camera frames come from the ``rgbd-frame`` sensor
(:func:`~ontodetect.synth.sensors.scan_rgbd_frame`).
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from typing import Any

import numpy as np
from numpy.typing import NDArray

from ..cloud import PointCloud, sensor_position
from ..config import Interval
from ..errors import InvalidParameterError
from .scene import CLASS_IDS

__all__ = [
    "FLOOR_CLASS",
    "SCANNET_POINTS",
    "duplicate_floor_layer",
    "punch_holes",
    "scannet_sampling",
    "tilt",
]

#: Points of a ScanNet scan as VoteNet's preprocessing samples it (data/README.md).
SCANNET_POINTS = 50_000
#: Class id of the floor (NYU40 and the simulator agree).
FLOOR_CLASS = CLASS_IDS["floor"]
#: Drifted floor layer: share of the floor copied, vertical offset (m), tilt (degrees). A
#: loop closed late in RGB-D SLAM leaves a second floor a few centimetres off (the rooms kept
#: aside in DESIGN.md); a larger offset would be a step, not a drifted layer.
FLOOR_SHARE = (0.2, 0.5)
FLOOR_OFFSET = (0.02, 0.10)
FLOOR_TILT_DEG = 1.0
#: Holes: how many, and their radius (m): missed patches of a hand-held scan, 15-40 cm.
HOLE_COUNT = 6
HOLE_RADIUS = (0.15, 0.4)
#: Tilt of a sensor whose gravity estimate is off (degrees).
TILT_DEG = (2.0, 5.0)

_POSITIVE = Interval(0.0, math.inf, "neither")
_NON_NEGATIVE = Interval(0.0, math.inf, "left")
_SHARE = Interval(0.0, 1.0, "right")


def _range(name: str, value: float | Sequence[float], rule: Interval) -> tuple[float, float]:
    """A number or a (low, high) pair of numbers that ``rule`` accepts, as (low, high)."""
    if isinstance(value, (int, float)) and not isinstance(value, bool):
        v = rule.check(name, value)
        return v, v
    try:
        low, high = value  # type: ignore[misc]
    except (TypeError, ValueError):
        raise InvalidParameterError(
            name, f"{rule.describe()} or a (low, high) pair of them", value
        ) from None
    low, high = rule.check(name, low), rule.check(name, high)
    if low > high:
        raise InvalidParameterError(name, "a (low, high) pair with low <= high", value)
    return low, high


def _draw(rng: np.random.Generator, bounds: tuple[float, float]) -> float:
    low, high = bounds
    return low if low == high else float(rng.uniform(low, high))


def _record(cloud: PointCloud, **entry: Any) -> PointCloud:
    done = list(cloud.meta.get("artefacts", ()))
    return cloud.with_meta(artefacts=[*done, entry])


def _rotation(axis: NDArray[np.float64], angle: float) -> NDArray[np.float64]:
    """Rotation matrix by ``angle`` (radians) about the unit ``axis`` (Rodrigues)."""
    x, y, z = axis
    k = np.array([[0.0, -z, y], [z, 0.0, -x], [-y, x, 0.0]])
    return np.eye(3) + math.sin(angle) * k + (1.0 - math.cos(angle)) * (k @ k)


def _horizontal_axis(rng: np.random.Generator) -> NDArray[np.float64]:
    azimuth = rng.uniform(0.0, 2.0 * math.pi)
    return np.array([math.cos(azimuth), math.sin(azimuth), 0.0])


def scannet_sampling(
    cloud: PointCloud, rng: int | np.random.Generator | None = None, *, points: int = SCANNET_POINTS
) -> PointCloud:
    """Reduce a dense fused scan to ``points`` points as ScanNet's VoteNet files were made.

    VoteNet's preprocessing draws the kept mesh vertices uniformly at random without
    replacement (``numpy.random.choice``), which also leaves them in random order; so does
    this. A cloud with no more than ``points`` points keeps them all, shuffled.

    Parameters
    ----------
    cloud : PointCloud
        The dense scan (a simulated RGB-D trajectory fused on a 1-2 cm grid stands in for
        the reconstructed mesh's vertices).
    rng : int or Generator, optional
    points : int
        Points to keep.

    Returns
    -------
    PointCloud
        ``min(points, len(cloud))`` points; ``index`` holds their rows in ``cloud``'s file.

    Examples
    --------
    >>> from ontodetect import point_cloud
    >>> c = point_cloud(np.arange(30.0).reshape(10, 3))
    >>> sorted(scannet_sampling(c, 0, points=4).index.tolist())
    [2, 4, 5, 7]
    """
    n = Interval(1, math.inf, "left", integer=True).check("points", points)
    rng = np.random.default_rng(rng)
    keep = min(n, len(cloud))
    chosen = rng.choice(len(cloud), keep, replace=False)
    return _record(cloud.select(chosen), name="scannet_sampling", points=keep, of=len(cloud))


def duplicate_floor_layer(
    cloud: PointCloud,
    rng: int | np.random.Generator | None = None,
    *,
    share: float | Sequence[float] = FLOOR_SHARE,
    offset: float | Sequence[float] = FLOOR_OFFSET,
    max_tilt_deg: float = FLOOR_TILT_DEG,
    floor_class: int = FLOOR_CLASS,
) -> PointCloud:
    """Add a drifted copy of part of the floor, as a SLAM map that closed a loop late keeps.

    A patch of the floor (the floor points nearest, on the floor plane, to a floor point
    drawn at random; ``share`` of them) is copied, turned by up to ``max_tilt_deg`` about a
    horizontal axis through its centre, and moved up or down (sign at random) by
    ``offset``. The copies keep their source points' colours and fields, so they are
    labelled floor.

    Parameters
    ----------
    cloud : PointCloud
        A labelled scan, z up, with a ``class_id`` field.
    rng : int or Generator, optional
    share : float or (2,) float
        Share of the floor points copied, in (0, 1], or a range to draw it from.
    offset : float or (2,) float
        Vertical shift of the copy (m), or a range to draw its size from.
    max_tilt_deg : float
        Largest tilt of the copy (degrees; drawn uniformly up to it).
    floor_class : int
        ``class_id`` of the floor.

    Returns
    -------
    PointCloud
        The input's points, then the copies, whose ``index`` continues after the largest
        row of the input (rows a file holding both would give them).

    Raises
    ------
    InvalidParameterError
        A parameter is out of range, or the cloud has no ``class_id`` field or no floor.

    Examples
    --------
    >>> from ontodetect import point_cloud
    >>> xy = np.stack(np.meshgrid(np.arange(10.0), np.arange(10.0)), -1).reshape(-1, 2)
    >>> floor = point_cloud(np.c_[xy, np.zeros(100)], fields={"class_id": np.full(100, 2)})
    >>> out = duplicate_floor_layer(floor, 0, share=0.3, offset=0.05, max_tilt_deg=0.0)
    >>> len(out), sorted(set(np.abs(out.xyz[100:, 2]).round(6).tolist()))
    (130, [0.05])
    >>> int(out.fields["class_id"][-1])
    2
    """
    share_range = _range("share", share, _SHARE)
    offset_range = _range("offset", offset, _NON_NEGATIVE)
    max_tilt = _NON_NEGATIVE.check("max_tilt_deg", max_tilt_deg)
    if "class_id" not in cloud.fields:
        raise InvalidParameterError("cloud", "a cloud with a per-point 'class_id' field", cloud)
    rng = np.random.default_rng(rng)
    floor = np.flatnonzero(np.asarray(cloud.fields["class_id"]) == floor_class)
    if not len(floor):
        raise InvalidParameterError("cloud", f"a cloud with floor points (class {floor_class})", 0)
    centre = cloud.xyz[floor[rng.integers(len(floor))]]
    fraction = _draw(rng, share_range)
    count = max(1, round(fraction * len(floor)))
    distance = np.linalg.norm(cloud.xyz[floor, :2] - centre[:2], axis=1)
    source = floor[np.sort(np.argsort(distance, kind="stable")[:count])]
    shift = _draw(rng, offset_range) * (1.0 if rng.random() < 0.5 else -1.0)
    angle = math.radians(float(rng.uniform(0.0, max_tilt))) if max_tilt else 0.0
    rot = _rotation(_horizontal_axis(rng), angle)
    pivot = cloud.xyz[source].mean(axis=0)
    copied = (cloud.xyz[source] - pivot) @ rot.T + pivot + [0.0, 0.0, shift]
    rows = int(cloud.index.max()) + 1 if len(cloud) else 0
    normals = None
    if cloud.normals is not None:
        normals = np.concatenate([cloud.normals, cloud.normals[source] @ rot.T])
    out = cloud.replace(
        xyz=np.concatenate([cloud.xyz, copied]),
        rgb=None if cloud.rgb is None else np.concatenate([cloud.rgb, cloud.rgb[source]]),
        normals=normals,
        fields={k: np.concatenate([v, v[source]]) for k, v in cloud.fields.items()},
        index=np.concatenate([cloud.index, rows + np.arange(count, dtype=np.int64)]),
    )
    return _record(
        out,
        name="duplicate_floor_layer",
        points=count,
        share=round(fraction, 4),
        offset=round(shift, 4),
        tilt_deg=round(math.degrees(angle), 4),
    )


def punch_holes(
    cloud: PointCloud,
    rng: int | np.random.Generator | None = None,
    *,
    count: int = HOLE_COUNT,
    radius: float | Sequence[float] = HOLE_RADIUS,
) -> PointCloud:
    """Remove ``count`` discs of surface: every point within ``radius`` of a centre.

    Centres are points of the cloud drawn at random, so every hole lies on a surface; a
    ball meets a surface in a disc (and takes a corner's two faces together, as a missed
    view would).

    Parameters
    ----------
    cloud : PointCloud
    rng : int or Generator, optional
    count : int
        Holes to make.
    radius : float or (2,) float
        Radius of each hole (m), or a range to draw each from.

    Returns
    -------
    PointCloud
        The points outside every hole, in their order, keeping their rows.

    Examples
    --------
    >>> from ontodetect import point_cloud
    >>> line = point_cloud(np.c_[np.arange(100) * 0.01, np.zeros((100, 2))])
    >>> len(punch_holes(line, 0, count=1, radius=0.1)) in range(79, 91)
    True
    """
    holes = Interval(0, math.inf, "left", integer=True).check("count", count)
    radius_range = _range("radius", radius, _POSITIVE)
    rng = np.random.default_rng(rng)
    keep = np.ones(len(cloud), dtype=bool)
    entries = []
    for _ in range(holes if len(cloud) else 0):
        centre = cloud.xyz[rng.integers(len(cloud))]
        r = _draw(rng, radius_range)
        inside = np.sum((cloud.xyz - centre) ** 2, axis=1) <= r * r
        keep &= ~inside
        entries.append({"center": [float(v) for v in centre], "radius": r})
    return _record(
        cloud.select(keep), name="punch_holes", holes=entries, removed=int(len(cloud) - keep.sum())
    )


def tilt(
    cloud: PointCloud,
    rng: int | np.random.Generator | None = None,
    *,
    degrees: float | Sequence[float] = TILT_DEG,
) -> PointCloud:
    """Turn the scan by a few degrees about a horizontal axis through its box's centre.

    Parameters
    ----------
    cloud : PointCloud
    rng : int or Generator, optional
        Draws the axis's azimuth (and the angle from a range).
    degrees : float or (2,) float
        The tilt, or a range to draw it from.

    Returns
    -------
    PointCloud
        Points (and normals, and a single view's ``meta["sensor_position"]``) turned; the
        ``meta["artefacts"]`` entry gives the angle and the axis.

    Examples
    --------
    >>> from ontodetect import point_cloud
    >>> flat = point_cloud([[0.0, 0, 0], [1, 0, 0], [0, 1, 0], [1, 1, 0]])
    >>> t = tilt(flat, 0, degrees=3.0)
    >>> n = np.cross(t.xyz[1] - t.xyz[0], t.xyz[2] - t.xyz[0])
    >>> round(float(np.degrees(np.arccos(n[2] / np.linalg.norm(n)))), 6)
    3.0
    """
    angle_range = _range("degrees", degrees, Interval(0.0, 90.0, "both"))
    rng = np.random.default_rng(rng)
    axis = _horizontal_axis(rng)
    angle = _draw(rng, angle_range)
    rot = _rotation(axis, math.radians(angle))
    lo, hi = cloud.bounds
    pivot = (lo + hi) / 2
    out = cloud.replace(
        xyz=(cloud.xyz - pivot) @ rot.T + pivot,
        normals=None if cloud.normals is None else cloud.normals @ rot.T,
    )
    eye = sensor_position(cloud)
    if eye is not None:
        out = out.with_meta(sensor_position=((eye - pivot) @ rot.T + pivot).tolist())
    return _record(
        out,
        name="tilt",
        degrees=round(angle, 6),
        axis=[round(float(v), 9) for v in axis],
        pivot=[round(float(v), 6) for v in pivot],
    )
