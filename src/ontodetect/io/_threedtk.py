"""3DTK scans: ``scanNNN.3d`` point files with ``scanNNN.pose`` poses.

3DTK (the 3D Toolkit, slam6d) stores scans in its "uos" layout: ASCII lines
``x y z [reflectance] [r g b]`` in centimetres, in a left-handed frame with y
up. ``scanNNN.pose`` holds the scan's position (x y z, cm) and orientation
(θx θy θz, degrees); ``scanNNN.frames`` (written by slam6d after registration)
holds one 4x4 matrix per line, the last one being the final pose.

Conventions, taken from 3DTK's sources (``include/slam6d/globals.icc`` and
``src/scanio/helper.cc``):

- ``readPoseHelper`` reads six numbers and converts the three angles from
  degrees to radians;
- ``EulerToMatrix4(rPos, rPosTheta, M)`` fills a column-major (OpenGL) matrix
  whose rotation part is ``R = Rx(θx) · Ry(θy) · Rz(θz)`` with the usual
  right-hand-rule matrices, and ``transform3`` maps a point to ``R p + t``;
  ``.frames`` lines are the same column-major 16 numbers (plus a colour code);
- ``ScanDataTransform_xyz`` turns a right-handed, z-up file in metres into
  3DTK's frame as ``(x, y, z)_3dtk = (-100 y, 100 z, 100 x)``; its inverse,
  used here after the pose, is ``(x, y, z) = (z, -x, y)_3dtk / 100``.
"""

from __future__ import annotations

import re
from collections.abc import Iterable
from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import NDArray

from ..cloud import PointCloud, point_cloud
from ..errors import CorruptFileError, InvalidParameterError, ReadError
from ._text import _to_colors, load_numeric_table

__all__ = ["pose_matrix", "read_3dtk", "threedtk_to_metric"]

#: 3DTK lengths are centimetres.
CM_PER_M = 100.0
#: Unit normals are recognised when every length is within this of 1.
UNIT_NORMAL_TOL = 1e-3

_SCAN_RE = re.compile(r"^scan(\d+)\.3d$", re.IGNORECASE)
# The optional first line of old uos files: "<columns> x <rows>".
_UOS_HEADER_RE = re.compile(rb"^\d+ x \d+\r?$")

#: Column layouts by number of columns (3DTK's uos, uosr, uos_rgb, uos_rrgb readers).
_LAYOUTS = {
    "uos": ["x", "y", "z"],
    "uosr": ["x", "y", "z", "intensity"],
    "uos_rgb": ["x", "y", "z", "r", "g", "b"],
    "uos_normal": ["x", "y", "z", "nx", "ny", "nz"],
    "uos_rrgb": ["x", "y", "z", "intensity", "r", "g", "b"],
    "uos_rgbr": ["x", "y", "z", "r", "g", "b", "intensity"],
}
_AUTO = {3: "uos", 4: "uosr", 6: "uos_rgb", 7: "uos_rrgb"}

# Right-handed z-up axes as rows over 3DTK's (x, y, z): x = z3, y = -x3, z = y3.
_TO_METRIC_AXES = np.array([[0.0, 0.0, 1.0], [-1.0, 0.0, 0.0], [0.0, 1.0, 0.0]])


def pose_matrix(position: Iterable[float], angles_deg: Iterable[float]) -> NDArray[np.float64]:
    """4x4 pose matrix of a 3DTK ``.pose`` (row-major, acting on column vectors).

    Parameters
    ----------
    position : (3,) float
        Translation in 3DTK's frame (cm).
    angles_deg : (3,) float
        θx, θy, θz in degrees.

    Returns
    -------
    (4, 4) float
        ``[[R, t], [0, 1]]`` with ``R = Rx(θx) Ry(θy) Rz(θz)`` as in 3DTK's
        ``EulerToMatrix4``.

    Examples
    --------
    >>> m = pose_matrix([10, 20, 30], [0, 90, 0])
    >>> (m @ [100, 0, 0, 1]).round(6).tolist()
    [10.0, 20.0, -70.0, 1.0]
    """
    t = np.asarray(list(position), dtype=np.float64)
    ax, ay, az = np.radians(np.asarray(list(angles_deg), dtype=np.float64))
    cx, sx, cy, sy, cz, sz = np.cos(ax), np.sin(ax), np.cos(ay), np.sin(ay), np.cos(az), np.sin(az)
    rx = np.array([[1, 0, 0], [0, cx, -sx], [0, sx, cx]])
    ry = np.array([[cy, 0, sy], [0, 1, 0], [-sy, 0, cy]])
    rz = np.array([[cz, -sz, 0], [sz, cz, 0], [0, 0, 1]])
    m = np.eye(4)
    m[:3, :3] = rx @ ry @ rz
    m[:3, 3] = t
    return m


def threedtk_to_metric(points: NDArray[np.float64], *, scale: bool = True) -> NDArray[np.float64]:
    """Points from 3DTK's frame (left-handed, y up, cm) to right-handed, z up, metres.

    Parameters
    ----------
    points : (n, 3) float
        3DTK coordinates (or directions, with ``scale=False``).
    scale : bool
        Divide by 100 (centimetres to metres); False for normals.

    Returns
    -------
    (n, 3) float
        ``(z, -x, y) / 100``.

    Examples
    --------
    >>> threedtk_to_metric(np.array([[100.0, 200.0, 300.0]])).tolist()
    [[3.0, -1.0, 2.0]]
    """
    out = np.asarray(points, dtype=np.float64) @ _TO_METRIC_AXES.T
    return out / CM_PER_M if scale else out


def _numbers(path: Path, text: str, what: str, need: int) -> list[float]:
    tokens = text.split()
    values: list[float] = []
    for tok in tokens[:need]:
        try:
            values.append(float(tok))
        except ValueError:
            raise CorruptFileError(path, f"{what}: expected numbers, found {tok[:40]!r}") from None
    if len(values) < need:
        raise CorruptFileError(path, f"{what}: expected {need} numbers, found {len(values)}")
    if not np.all(np.isfinite(values)):
        raise CorruptFileError(path, f"{what}: the numbers must be finite, found {values}")
    return values


def _read_text(path: Path) -> str:
    try:
        return path.read_bytes().decode("latin-1")
    except OSError as exc:
        raise ReadError(path, f"cannot read ({exc.strerror or exc})") from exc


def _scan_pose(
    scan_file: Path, number: str, use_frames: bool
) -> tuple[NDArray[np.float64], dict[str, Any] | None]:
    folder = scan_file.parent
    if use_frames:
        frames = folder / f"scan{number}.frames"
        if frames.is_file():
            lines = [ln for ln in _read_text(frames).splitlines() if ln.strip()]
            if not lines:
                raise CorruptFileError(frames, "is empty; expected 4x4 matrices, one per line")
            vals = _numbers(frames, lines[-1], f"line {len(lines)}", 16)
            m = np.array(vals[:16]).reshape(4, 4).T  # column-major on disk
            return m, {"frames": m.tolist()}
    pose = folder / f"scan{number}.pose"
    if not pose.is_file():
        return np.eye(4), None
    vals = _numbers(pose, _read_text(pose), "pose", 6)
    return pose_matrix(vals[:3], vals[3:6]), {"position_cm": vals[:3], "orientation_deg": vals[3:6]}


def _read_scan(path: Path, layout: str) -> tuple[NDArray[np.float64], list[str]]:
    try:
        with open(path, "rb") as fh:
            first = fh.readline(256)
    except OSError as exc:
        raise ReadError(path, f"cannot read ({exc.strerror or exc})") from exc
    skip = _UOS_HEADER_RE.match(first.rstrip(b"\n")) is not None
    table, _ = load_numeric_table(
        path, offset=len(first) if skip else 0, first_line=2 if skip else 1
    )
    if table.shape[0] == 0:
        raise CorruptFileError(path, "contains no points")
    ncols = table.shape[1]
    if ncols < 3:
        raise CorruptFileError(path, f"expected columns x y z, found {ncols} column(s)")
    name = layout if layout != "auto" else _AUTO.get(ncols)
    if name == "uos_rgb" and layout == "auto":
        # Six columns are colours or normals; unit-length rows on every line can
        # only be normals (as colours they would all be black but one channel).
        extra = table[:, 3:6]
        integral = np.all(extra == np.round(extra))
        if np.all(np.abs(np.linalg.norm(extra, axis=1) - 1) < UNIT_NORMAL_TOL):
            name = "uos_normal"
        elif not (integral and extra.min() >= 0 and extra.max() <= 255):
            name = None
    if name is None:
        names = ["x", "y", "z"] + [f"col{i}" for i in range(3, ncols)]
    else:
        names = _LAYOUTS[name]
        if len(names) != ncols:
            raise CorruptFileError(
                path, f"layout {name!r} has {len(names)} columns but the file has {ncols}"
            )
    return table, names


def read_3dtk(
    path: Path,
    *,
    scans: Iterable[int] | None = None,
    use_frames: bool = False,
    layout: str = "auto",
    on_nonfinite: str = "warn",
) -> PointCloud:
    """Read one 3DTK scan, or every scan of a folder, into one metric cloud.

    Each scan is moved by its pose in 3DTK's own frame, then converted to
    metres in a right-handed, z-up frame (see the module notes for the sources).

    Parameters
    ----------
    path : Path
        A ``scanNNN.3d`` file or a folder of them.
    scans : iterable of int, optional
        Scan numbers to read from a folder (all by default).
    use_frames : bool
        Take each scan's pose from the last line of ``scanNNN.frames`` (slam6d's
        registered pose) when that file exists, instead of ``scanNNN.pose``.
    layout : str
        Column layout: ``"auto"`` (by column count: 3 ``uos``, 4 ``uosr``,
        6 ``uos_normal`` when every row of columns 4-6 has unit length, else
        ``uos_rgb`` when they are integers 0..255, 7 ``uos_rrgb``), or one of ``"uos"``,
        ``"uosr"``, ``"uos_rgb"``, ``"uos_normal"``, ``"uos_rrgb"``, ``"uos_rgbr"``.
    on_nonfinite : {"warn", "drop", "raise"}
        Passed to :func:`~ontodetect.point_cloud`.

    Returns
    -------
    PointCloud
        ``xyz`` in metres; ``rgb`` when the scans have colours; fields ``scan``
        (int32, the scan number) and ``intensity`` (3DTK's reflectance, float64)
        when present. A scan without a pose file keeps the identity pose.
        ``meta["scans"]`` lists the scan numbers and ``meta["poses"]`` what was
        read for each.

    Raises
    ------
    ReadError
        The folder holds no ``scanNNN.3d`` file.
    CorruptFileError
        Non-numeric text (the message names the file and line), a short pose,
        a scan without points.

    Examples
    --------
    >>> import tempfile, pathlib
    >>> d = pathlib.Path(tempfile.mkdtemp())
    >>> _ = (d / "scan000.3d").write_text("100 0 0\\n")
    >>> _ = (d / "scan000.pose").write_text("10 20 30\\n0 90 0\\n")
    >>> read_3dtk(d).xyz.round(6).tolist()
    [[-0.7, -0.1, 0.2]]
    """
    path = Path(path)
    if layout != "auto" and layout not in _LAYOUTS:
        raise InvalidParameterError("layout", f"'auto' or one of {sorted(_LAYOUTS)}", layout)
    if path.is_dir():
        found = []
        for f in path.iterdir():
            m = _SCAN_RE.match(f.name)
            if m and f.is_file():
                found.append((int(m.group(1)), m.group(1), f))
        found.sort()
        if scans is not None:
            wanted = {int(s) for s in scans}
            found = [item for item in found if item[0] in wanted]
        if not found:
            raise ReadError(path, "holds no 3DTK scan (scanNNN.3d)")
    else:
        m = _SCAN_RE.match(path.name)
        number = m.group(1) if m else path.stem
        found = [(int(number) if number.isdigit() else 0, number, path)]

    parts_xyz: list[NDArray[np.float64]] = []
    parts_rgb: list[NDArray[np.uint8] | None] = []
    parts_nrm: list[NDArray[np.float64] | None] = []
    parts_int: list[NDArray[np.float64] | None] = []
    parts_scan: list[NDArray[np.int32]] = []
    extra_fields: dict[str, list[NDArray[np.float64]]] = {}
    poses: dict[int, Any] = {}
    for num, text_num, scan_file in found:
        table, names = _read_scan(scan_file, layout)
        where = {n: i for i, n in enumerate(names)}
        matrix, pose_info = _scan_pose(scan_file, text_num, use_frames)
        poses[num] = pose_info
        rot, shift = matrix[:3, :3], matrix[:3, 3]
        local = table[:, [where["x"], where["y"], where["z"]]]
        parts_xyz.append(threedtk_to_metric(local @ rot.T + shift))
        if {"r", "g", "b"} <= set(where):
            cols = [where["r"], where["g"], where["b"]]
            parts_rgb.append(_to_colors(scan_file, table[:, cols], ["r", "g", "b"]))
        else:
            parts_rgb.append(None)
        if {"nx", "ny", "nz"} <= set(where):
            nrm = table[:, [where["nx"], where["ny"], where["nz"]]] @ rot.T
            parts_nrm.append(threedtk_to_metric(nrm, scale=False))
        else:
            parts_nrm.append(None)
        parts_int.append(table[:, where["intensity"]] if "intensity" in where else None)
        for name in names:
            if name.startswith("col"):
                extra_fields.setdefault(name, []).append(table[:, where[name]])
        parts_scan.append(np.full(table.shape[0], num, dtype=np.int32))

    def joined(parts: list[Any]) -> NDArray[Any] | None:
        return None if any(p is None for p in parts) else np.concatenate(parts)

    fields: dict[str, NDArray[Any]] = {"scan": np.concatenate(parts_scan)}
    intensity = joined(parts_int)
    if intensity is not None:
        fields["intensity"] = intensity
    for name, parts in extra_fields.items():
        if len(parts) == len(found):
            fields[name] = np.concatenate(parts)
    meta = {
        "source": str(path),
        "scans": [item[0] for item in found],
        "poses": poses,
        "units": "m",
        "frame": "right-handed, z up (converted from 3DTK: x=z/100, y=-x/100, z=y/100)",
    }
    return point_cloud(
        np.concatenate(parts_xyz),
        rgb=joined(parts_rgb),
        normals=joined(parts_nrm),
        fields=fields,
        meta=meta,
        on_nonfinite=on_nonfinite,
        copy=False,
    )
