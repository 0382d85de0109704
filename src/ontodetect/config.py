"""One typed, validated configuration for every stage of the pipeline.

A :class:`Config` holds one frozen section per stage: :class:`PrepareConfig`
(scale, denoising, levelling, voxel grid, floor/walls/ceiling),
:class:`ClusterConfig` (candidate object clusters) and :class:`PlaneConfig`
(MSAC planes inside each cluster). Defaults come from Table 4.1 of the thesis
where it has them; each is cited next to its field. Counts of points depend on
the sensor (a 50,000-point ScanNet room and a 5-million-point lidar scan of the
same room), so this configuration speaks in surfaces (m²) and lengths instead:
an area is turned into a number of voxels with the sampling spacing of the scene.

Every value is checked in one place, :func:`validate_section`, against the rule
declared next to its field; a bad value raises
:class:`~ontodetect.errors.InvalidParameterError` naming its dotted path, e.g.
``cluster.radius``. A configuration round-trips through plain dictionaries and
YAML, and the command line overrides single values with ``section.key=value``.

Later stages add their own sections by adding a field to :class:`Config` whose
type is a frozen dataclass with ``SECTION`` set; loading, validation,
overrides and serialisation pick it up without other changes.

Examples
--------
>>> cfg = Config().with_overrides(["cluster.radius=0.04"])
>>> cfg.cluster.radius
0.04
>>> Config.from_dict({"prepare": {"voxel_size": 0.03}}).prepare.voxel_size
0.03
"""

from __future__ import annotations

import dataclasses
import os
from collections.abc import Iterable, Mapping
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, ClassVar

import yaml

from ._rules import (
    ANGLE,
    COUNT,
    FRACTION,
    NON_NEGATIVE,
    POSITIVE,
    SHARE,
    Boolean,
    Interval,
    Names,
    Nullable,
    OneOf,
    Pair,
    _Rule,
    check_param,
)
from .errors import InvalidParameterError, OntoDetectError, ReadError
from .io._atomic import atomic_write_text
from .io._textfile import read_text
from .io._yaml import describe_yaml_error, load_yaml

__all__ = [
    "ANGLE",
    "COUNT",
    "FRACTION",
    "NON_NEGATIVE",
    "POSITIVE",
    "SHARE",
    "Boolean",
    "ClusterConfig",
    "Config",
    "ConfigValueError",
    "DetectConfig",
    "Interval",
    "Nullable",
    "OneOf",
    "Pair",
    "PlaneConfig",
    "PrepareConfig",
    "UnknownKeyError",
    "check_param",
    "parse_override",
    "validate_section",
]

FORMAT = "ontodetect.config/1"


class UnknownKeyError(InvalidParameterError):
    """A configuration names a section or parameter that does not exist."""

    def __init__(self, key: str, known: Iterable[str], source: str | None = None) -> None:
        self.source = source
        known_list = ", ".join(sorted(known))
        OntoDetectError.__init__(
            self,
            f"{source + ': ' if source else ''}unknown configuration key {key!r} "
            f"(expected one of: {known_list})",
        )
        self.name, self.rule, self.value = key, f"one of {known_list}", key


class ConfigValueError(InvalidParameterError):
    """A value in a configuration file breaks its rule; the message names the file too."""

    def __init__(self, source: str, error: InvalidParameterError) -> None:
        self.source = source
        self.name, self.rule, self.value = error.name, error.rule, error.value
        OntoDetectError.__init__(self, f"{source}: {error}")


def _param(default: Any, rule: _Rule, doc: str) -> Any:
    """A dataclass field with its validation rule and a one-line description."""
    return field(default=default, metadata={"rule": rule, "doc": doc})


UP_CHOICES = ("z", "-z", "y", "-y", "x", "-x", "auto", "auto-frame")


def validate_section(section: Any) -> dict[str, Any]:
    """Check every field of a configuration section against its rule.

    Parameters
    ----------
    section : dataclass instance
        A section such as :class:`ClusterConfig`.

    Returns
    -------
    dict
        Field name -> normalised value (ints for integer fields, tuples for pairs).

    Raises
    ------
    InvalidParameterError
        Naming ``<section>.<field>``, the rule and the value.
    """
    out = {}
    prefix = getattr(section, "SECTION", type(section).__name__)
    for f in dataclasses.fields(section):
        rule = f.metadata.get("rule")
        value = getattr(section, f.name)
        out[f.name] = value if rule is None else rule.check(f"{prefix}.{f.name}", value)
    return out


class _Section:
    """Shared behaviour of the frozen section dataclasses: validate on creation."""

    SECTION: ClassVar[str] = ""

    def __post_init__(self) -> None:
        for name, value in validate_section(self).items():
            object.__setattr__(self, name, value)

    def to_dict(self) -> dict[str, Any]:
        """Plain values (pairs as lists), ready for YAML or JSON."""
        return {
            f.name: list(v) if isinstance(v, tuple) else v
            for f in dataclasses.fields(self)  # type: ignore[arg-type]
            for v in [getattr(self, f.name)]
        }

    @classmethod
    def describe(cls) -> list[tuple[str, Any, str, str]]:
        """(name, default, rule, description) of every field, for documentation."""
        rows = []
        for f in dataclasses.fields(cls):  # type: ignore[arg-type]
            rule = f.metadata.get("rule")
            rows.append(
                (f.name, f.default, rule.describe() if rule else "", f.metadata.get("doc", ""))
            )
        return rows


# -- sections ------------------------------------------------------------------------------
@dataclass(frozen=True)
class PrepareConfig(_Section):
    """Preparation: scale, denoising, levelling, voxel grid and structural planes (§3.2–3.3)."""

    SECTION: ClassVar[str] = "prepare"

    # Table 4.1: voxel size 2 cm. The voxel grid is also the thesis's downsampling step
    # (Table 4.1: downsampling rate 20–25): a grid average keeps one point per occupied
    # voxel whatever the sensor's density, which a fixed rate cannot.
    voxel_size: float = _param(0.02, POSITIVE, "Voxel edge (m) of the grid-average cloud.")
    # §3.2: X_sc = k_s X_c. None = 1, unless the units guess says millimetres.
    scale: float | None = _param(
        None, Nullable(POSITIVE), "Scale factor k_s; null = from units guess or travel."
    )
    guess_units: bool = _param(
        True, Boolean(), "Rescale clouds whose size says millimetres to metres."
    )
    # A camera frame is rarely level and its y points down; a fused room scan or map
    # is z up (ScanNet, lidar), and estimating its axis would only move its results.
    up: str = _param(
        "auto-frame",
        OneOf(UP_CHOICES),
        "Up axis of the input, 'auto' to estimate it from floor and walls, or "
        "'auto-frame': auto for an organized or single-view cloud, z otherwise.",
    )
    # Scans drift and maps are rarely exactly level: the floor's own normal is taken as up
    # when it is within a few degrees of the given or estimated axis.
    level_on_floor: bool = _param(
        True, Boolean(), "Refine the up direction with the floor plane's normal."
    )
    # Grids (voxels, cells, floor tiles) are laid along the levelled frame's axes from the
    # points' minimum corner. "canonical" turns that frame about the vertical so that the
    # walls' main direction is its x axis, puts its origin at the median of the scan and lays
    # every grid from that origin: the same room then meets the same grids however its file
    # turned or moved it. Opt-in: on scannet-dev it changed clusters and cost tables
    # (docs/benchmarks.md, "Where detections move").
    frame: str = _param(
        "input",
        OneOf(("canonical", "input")),
        "Horizontal frame of the grids: 'canonical' (walls along x, origin at the scan's "
        "median) or 'input' (the file's axes).",
    )
    # The voxel grid and the cells are laid along the levelled frame's axes; a turn about
    # the vertical shows the same scan to them from another angle (detect's votes).
    turn: float = _param(
        0.0,
        Interval(-180.0, 180.0, "both"),
        "Extra turn (deg) of the levelled frame about the vertical.",
    )
    # A turn by a multiple of 90° about z is exact (axes swapped and negated): a scan turned
    # into a pose its own points choose is the same input whichever quarter it came in.
    quarter_turns: bool = _param(
        False,
        Boolean(),
        "Prepare a scan (no sensor, z up, input frame) turned by the quarter turns its own "
        "points choose (the longer spread along x, the skewed side to +x).",
    )
    # Any turn about z, not only a quarter: the scan is first turned so that its walls run
    # along x and y (preprocess.wall_yaw, read to the rounding error), then by the quarter
    # its points choose, moved to its lowest corner and read to the nanometre, so that the
    # same scan turned by any angle or moved is the same input to the last bit.
    walls_to_axes: bool = _param(
        False,
        Boolean(),
        "Prepare a scan (no sensor, z up, input frame) turned so that its walls run along "
        "x and y, then by the quarter turns its points choose (any turn gives one input).",
    )
    # Reconstructions bend: real scanned floors rise 20 cm across a room. Heights are
    # measured above a floor height map with tiles of this size; 0 = one flat floor.
    floor_tile: float = _param(
        0.5, NON_NEGATIVE, "Tile (m) of the floor height map; 0 = flat floor plane."
    )
    max_floor_warp: float = _param(
        0.3, NON_NEGATIVE, "Largest deviation (m) of the floor from its plane."
    )
    denoise: str = _param(
        "statistical",
        OneOf(("statistical", "radius", "both", "none")),
        "Outlier removal on the voxel grid (§3.3 filtering).",
    )
    sor_neighbors: int = _param(
        8,
        Interval(1, 1000, "both", integer=True),
        "Statistical outlier removal: neighbours per voxel.",
    )
    sor_std_ratio: float = _param(
        3.0, POSITIVE, "Statistical outlier removal: cut at mean + ratio * std."
    )
    ror_radius: float = _param(0.1, POSITIVE, "Radius outlier removal: radius (m).")
    ror_min_neighbors: int = _param(
        2,
        Interval(1, 10_000, "both", integer=True),
        "Radius outlier removal: fewest occupied voxels around.",
    )
    far_percentile: float = _param(
        0.5, Interval(0.0, 50.0, "left"), "Far outliers: percent trimmed per side for the box."
    )
    far_margin: float = _param(
        1.0, NON_NEGATIVE, "Far outliers: points this far (m) outside the box are dropped."
    )
    smoothing: bool = _param(
        False, Boolean(), "Project voxel centres on local planes (less scatter on planes)."
    )
    # A surface whose points scatter by sigma keeps erf(t / (sigma sqrt 2)) of them within
    # MSAC's inlier distance t: under 75 % once sigma > t / 1.15, and planes then break into
    # strips. Measured on real scans with Gaussian noise added (docs/benchmarks.md, "Noise
    # on the surfaces"): smoothing loses chairs at 5-7 mm and wins them back at 1 cm.
    auto_smoothing: bool = _param(
        True,
        Boolean(),
        "Smooth as 'smoothing' does when the floor scatters so much that more than a "
        "quarter of a plane's points fall outside the plane inlier distance.",
    )
    depth_smoothing: bool = _param(
        True,
        Boolean(),
        "Single camera frames: bilateral filter of inverse depth over the pixel grid "
        "(depth steps).",
    )
    # Table 4.1: altitude cut-off 140 cm; no seat or table is higher.
    altitude_cutoff: float = _param(
        1.4, POSITIVE, "Objects are searched below this height (m) above floor."
    )
    structure: bool = _param(True, Boolean(), "Find floor, walls and ceiling and keep them apart.")
    structure_cell: float = _param(
        0.1,
        POSITIVE,
        "Smallest cell (m) of the coarse plane fits (floor, walls, up); "
        "at least 5 sampling spacings.",
    )
    floor_band: float = _param(
        0.03, NON_NEGATIVE, "Voxels up to this height (m) above the floor are floor."
    )
    min_floor_area: float = _param(
        0.5, POSITIVE, "Smallest horizontal surface (m²) taken as floor or ceiling."
    )
    min_wall_length: float = _param(1.0, POSITIVE, "Shortest vertical plane (m) taken as a wall.")
    min_wall_height: float = _param(1.2, POSITIVE, "Lowest vertical extent (m) of a wall.")
    wall_band: float = _param(
        0.04, NON_NEGATIVE, "Voxels within this distance (m) of a wall plane are wall."
    )
    low_scan_walls: bool = _param(
        False,
        Boolean(),
        "In a scan that stops below 1.5 m (its 99th height percentile), a wall need only "
        "reach to within a cell of the scan's top.",
    )
    # Open-plan rooms: glazing and curtains show no wall plane, and a SLAM map that closed
    # a loop late keeps a drifted copy of part of the floor (issue 20).
    shell_walls: bool = _param(
        False,
        Boolean(),
        "Glazed and curtained walls: tall surfaces from near the floor, gaps allowed, in "
        "lines at the room's boundary, are wall.",
    )
    floor_layers: bool = _param(
        True,
        Boolean(),
        "A drifted second floor layer (a large thin sheet up to 15 cm above or below the "
        "floor) is floor.",
    )


@dataclass(frozen=True)
class ClusterConfig(_Section):
    """Candidate object clusters (§3.3, Algorithm 1 step 7)."""

    SECTION: ClassVar[str] = "cluster"

    method: str = _param(
        "parts",
        OneOf(("parts", "dbscan", "euclidean", "region_growing")),
        "Clustering: density regions split at seat/table parts, or plain.",
    )
    # Table 4.1: neighbourhood radius for density-based clustering 2–5 cm.
    radius: float = _param(0.05, POSITIVE, "Neighbourhood radius (m) of density clustering.")
    # Sparse scans (a few cm between points) would fall apart at 5 cm: the radius is
    # raised to this multiple of the scene's sampling spacing when that is larger.
    spacing_factor: float = _param(
        2.5, NON_NEGATIVE, "Radius is at least this times the sampling spacing; 0 = off."
    )
    # Table 4.1: cluster density >= 990 points. As a density: a voxel is a core voxel
    # when its neighbourhood is at least this full compared with a flat surface.
    core_fill: float = _param(
        0.05, FRACTION, "Core voxel: share of a flat disc of the radius that is occupied."
    )
    # Table 4.1: cluster density >= 990 points, i.e. about 0.4 m² at the thesis's 2 cm
    # voxels of a complete scan; occluded single views show less, hence a smaller floor.
    min_surface: float = _param(0.04, NON_NEGATIVE, "Smallest cluster surface (m²).")
    # Table 4.1: length of cluster (in any direction) 30–200 cm.
    length: tuple[float, float] = _param(
        (0.3, 2.0), Pair(NON_NEGATIVE), "Cluster length range (m) in any direction."
    )
    # Clusters outside the limits are kept with a flag, not dropped, unless asked.
    drop_flagged: bool = _param(False, Boolean(), "Drop flagged clusters instead of keeping them.")
    # Table 4.1: number of planes in a cluster >= 2.
    min_planes: int = _param(
        2,
        Interval(0, 1000, "both", integer=True),
        "Fewest MSAC planes for a cluster not to be flagged.",
    )
    # Table 4.1: height of seating plane 35–75 cm; tables reach a little higher.
    part_height: tuple[float, float] = _param(
        (0.3, 1.1), Pair(NON_NEGATIVE), "Heights (m) of horizontal parts that seed clusters."
    )
    # Table 4.1: inclination of seating plane ±6°; voxel normals of a sparse scan scatter
    # more than a fitted plane does, so the per-voxel tolerance is wider.
    part_tilt: float = _param(
        20.0, ANGLE, "Largest tilt (deg) of a voxel normal in a horizontal part."
    )
    min_part_area: float = _param(
        0.02, NON_NEGATIVE, "Smallest horizontal part (m²) that seeds a cluster."
    )
    # Table 4.1: plane size 25–150 cm. Armrests and backrest rails are narrower; a seat
    # seen partly behind a table edge a little narrower, hence 20 cm.
    min_part_width: float = _param(
        0.2, NON_NEGATIVE, "Shortest side (m) of a horizontal part that seeds a cluster."
    )
    max_part_step: float = _param(
        0.03, POSITIVE, "Largest height step (m) between neighbours within a part."
    )
    # A horizontal part takes its seed style by height: seats up to 0.75 m (Table 4.1), so a
    # table top at 0.72-0.75 m (EN 527-1, EN 1730) claims chairs around it as a seat claims
    # its backrest. By height and size, the part's length and width are within one sigma of
    # a seed part of the style (a 2.4 x 1.0 m top is no seat). In single views by default:
    # there it frees the chairs pushed under tables and costs nothing; on fused scans it
    # costs a real chair and reads a box under a desk as one (docs/benchmarks.md).
    seed_by_size: str = _param(
        "views",
        OneOf(("off", "views", "on"), booleans=("off", "on")),
        "A horizontal part takes its seed style by its height and size, not its height "
        "alone: 'views' in single views (a sensor position), 'on' everywhere, 'off' nowhere.",
    )
    max_grow: float = _param(1.2, POSITIVE, "Parts claim voxels up to this path length (m) away.")
    # Region growing: neighbours join while their normals differ by less than this.
    smoothness: float = _param(15.0, ANGLE, "Region growing: largest normal change (deg).")
    # Alg. 1 step 2 meshes the scan before segmenting it. Opt-in: on the generalization
    # benchmark it did not pay its way (docs/benchmarks.md, "Surface reconstruction").
    adjacency: str = _param(
        "radius",
        OneOf(("radius", "mesh")),
        "Clustering graph: 'radius' (voxels within the radius) or 'mesh' (those pairs the "
        "surface mesh of the object voxels also joins).",
    )


@dataclass(frozen=True)
class PlaneConfig(_Section):
    """MSAC planes inside each cluster (§3.3, Algorithm 1 step 8)."""

    SECTION: ClassVar[str] = "planes"

    # Table 4.1: plane inlier distance 0.5–1.5 cm; §4.1 sets 1 cm.
    threshold: float = _param(0.01, POSITIVE, "MSAC inlier distance (m).")
    # Table 4.1: plane size 25–150 cm; a plane shorter than this is a leg or clutter.
    min_extent: float = _param(0.25, NON_NEGATIVE, "Shortest plane length (m) kept.")
    min_area: float = _param(0.01, NON_NEGATIVE, "Smallest plane surface (m²) kept.")
    max_planes: int = _param(
        8, Interval(1, 1000, "both", integer=True), "Most planes extracted per cluster."
    )
    max_trials: int = _param(
        1000, Interval(1, 10**7, "both", integer=True), "MSAC hypotheses per plane."
    )
    # Random minimal samples settle on any plane whose cost is within their sampling noise
    # (a seat found whole or in part, a backrest or not), and a detection with it: on
    # scannet-dev another seed loses 2 of 7 detections of a room. "surface" hypotheses are
    # the same every time. Opt-in until the benchmark says it costs nothing.
    hypotheses: str = _param(
        "random",
        OneOf(("surface", "random")),
        "Plane hypotheses: 'surface' (through the most planar points along their normals; "
        "deterministic) or 'random' (MSAC's random triples, Table 4.1).",
    )
    # A gently curved seat gives MSAC no plane with more inliers than a slanted one through
    # seat and backrest, yet its heights pile up in one band: seats and tops are level
    # (Table 4.1: seat inclination within ±6°) in a levelled scan.
    level_first: bool = _param(
        False,
        Boolean(),
        "Take each cluster's densest level layer that makes a plane (points within the "
        "inlier distance of one height, fitted level) before MSAC looks for the others.",
    )
    # Issue 21's curved parts: a shell seat or a body-shaped backrest is cut by MSAC into
    # strips; joined along their seams they are one part. Opt-in until the benchmark
    # says it pays (docs/benchmarks.md, "Curved parts").
    curved: bool = _param(
        False,
        Boolean(),
        "Offer the scoring each cluster's curved surfaces (planes meeting along seams with "
        "normals within 30 deg) as parts besides its planes.",
    )
    # Issue 21's beds found whole: MSAC takes the largest flat piece of a made bed; the
    # lying surface its level pieces make is measured whole, for the parts that say
    # ``lying`` (docs/benchmarks.md, "Lying surfaces").
    level_surfaces: bool = _param(
        True,
        Boolean(),
        "Offer the scoring each cluster's lying surfaces (level planes that meet, their "
        "centroids within 8 cm in height) as parts besides its planes.",
    )
    # Issue 21's seats that are not planes: an upholstered or cane seat is level but not
    # flat, and MSAC's best plane runs slanted through seat and backrest. Opt-in until the
    # benchmark says it pays (docs/benchmarks.md, "A seat that faces up").
    seat_layer: bool = _param(
        False,
        Boolean(),
        "Offer the scoring each cluster's upward-facing level layer at seat height (30-75 "
        "cm) where MSAC fitted no level plane there, for the parts that say 'layer'.",
    )


@dataclass(frozen=True)
class DetectConfig(_Section):
    """Scoring and labelling (§3.4–3.6, Algorithm 1 steps 10–18, Eq. 3.6–3.8)."""

    SECTION: ClassVar[str] = "detect"

    # Table 4.1: threshold for probabilistic decision 15 %.
    threshold: float = _param(0.15, FRACTION, "Decision threshold on P_obj|ont.")
    # Eq. 3.7: beta + gamma = 1; the thesis gives no value, equal weights by default.
    beta: float = _param(0.5, FRACTION, "Energy weight of the class probability; gamma = 1 - beta.")
    none_likelihood: float = _param(
        0.05, Interval(0.0, 1.0, "right"), "Likelihood of a cluster under 'none of the classes'."
    )
    context: float = _param(0.0, NON_NEGATIVE, "Strength of the seat-near-table pairwise term.")
    # Eq. 3.7's plane-size term can give a cluster to a chair that the ontology finds likelier
    # to be a sink, in a room read as a bathroom: the competing class is there to explain
    # such a cluster away (thesis Tables 4.14-4.16: a chair in an unlikely room costs more).
    explain_away: bool = _param(
        True,
        Boolean(),
        "A cluster whose likeliest label is one not reported (a sink, a WC), in a room whose "
        "prior favours it over the label's class, gets no reported label of another kind "
        "(a stool never bars a chair: both are seating).",
    )
    # One pass decides on one voxel grid: which voxels the points fall in moves planes and
    # clusters enough to make or break a detection. A majority of passes over the scan
    # turned by a fraction of a degree keeps what does not depend on the grid.
    votes: int = _param(
        3,
        Interval(1, 15, "both", integer=True),
        "Passes over the scan, each turned by vote_turn more; a majority keeps a detection.",
    )
    vote_turn: float = _param(
        0.7, Interval(0.0, 45.0, "neither"), "Turn (deg) between the passes of a vote."
    )
    # A pass whose segmentation cut or merged an object's points otherwise than the first
    # pass did cannot say what that object is: it may abstain instead of counting as "no".
    vote_abstain: bool = _param(
        False,
        Boolean(),
        "In the vote, a pass with no cluster covering a first-pass cluster (point IoU "
        ">= 0.5) abstains on it instead of voting 'no object'.",
    )
    # A depth camera's frame saved without its pixel grid or viewpoint (a PLY in the
    # camera's coordinates, SUN RGB-D's frames as VoteNet stores them) has its sensor at the
    # origin, and only one surface on each sight line from there.
    infer_view: bool = _param(
        True,
        Boolean(),
        "A cloud with no viewpoint and no pixel grid that looks like one view from the "
        "origin (all of it in a cone from there, one surface per sight line) is taken as one, "
        "its sensor at the origin.",
    )
    # Every pass holds its own voxels and clusters: a dense scan gets one.
    vote_max_points: int = _param(
        2_000_000,
        Interval(0, 10**12, "both", integer=True),
        "Clouds with more points than this get a single pass.",
    )
    # Which classes a detection may carry: those the ontology reports (detect: true), all of
    # them (the competing classes too: toilets, sinks, beds...) or the ones named.
    classes: str = _param(
        "reported",
        Names(("reported", "all")),
        "Classes reported: 'reported' (the ontology's detect: true), 'all' (the competing "
        "classes too) or a comma-separated list of class names.",
    )
    # With the room prior estimated from the scan (detect's room="auto"), the floor area the
    # scan covers is one more piece of evidence about the room (docs/environment.md). Off by
    # default: on scannet-dev it dropped one true table of a studio flat (with one false).
    room_shape: bool = _param(
        False,
        Boolean(),
        "Room prior from the scan: also weigh the floor area it covers (areas per category).",
    )
    # Issue 20, opt-in: "recognition" makes many candidate objects from an over-segmentation,
    # scores every one and keeps the best non-overlapping set (no vote).
    proposals: str = _param(
        "vote",
        OneOf(("vote", "recognition")),
        "Object proposals: 'vote' (part-seeded clusters, majority of turned passes) or "
        "'recognition' (many candidates scored by the ontology, best disjoint set chosen).",
    )
    # Recognition's candidates include pieces of objects (a backrest without its seat, a
    # desk with a chair's legs) that score as well as the whole. A whole piece of furniture
    # stands apart from what surrounds it but the floor and walls, a piece is cut out of
    # something: each candidate loses this much log-odds per unit of its cut share
    # (segment.cut_shares), given back where it meets another chosen candidate.
    cut_cost: float = _param(
        40.0,
        NON_NEGATIVE,
        "Recognition: log-odds a candidate loses per unit of the share of its graph edges "
        "that lead to other object points (0: none).",
    )


# -- the whole configuration ---------------------------------------------------------------
@dataclass(frozen=True)
class Config:
    """The configuration of every stage, one section each.

    Attributes
    ----------
    prepare : PrepareConfig
    cluster : ClusterConfig
    planes : PlaneConfig

    Examples
    --------
    >>> cfg = Config()
    >>> cfg.cluster.length
    (0.3, 2.0)
    >>> cfg.get("planes.threshold")
    0.01
    """

    prepare: PrepareConfig = field(default_factory=PrepareConfig)
    cluster: ClusterConfig = field(default_factory=ClusterConfig)
    planes: PlaneConfig = field(default_factory=PlaneConfig)
    detect: DetectConfig = field(default_factory=DetectConfig)

    def __post_init__(self) -> None:
        for name, cls in self.section_classes().items():
            value = getattr(self, name)
            if not isinstance(value, cls):
                raise InvalidParameterError(name, f"a {cls.__name__}", type(value).__name__)

    # -- structure ---------------------------------------------------------------------
    @classmethod
    def section_classes(cls) -> dict[str, type]:
        """Section name -> its dataclass, for every section this configuration holds."""
        out = {}
        for f in dataclasses.fields(cls):
            factory = f.default_factory  # every section field has one
            out[f.name] = factory  # type: ignore[assignment]
        return out

    # -- dictionaries and YAML -----------------------------------------------------------
    @classmethod
    def from_dict(cls, data: Mapping[str, Any] | None, *, source: str | None = None) -> Config:
        """Build from nested mappings; missing keys keep their defaults.

        Parameters
        ----------
        data : mapping
            ``{"cluster": {"radius": 0.04}, ...}``. A ``format`` key, if present,
            must be ``"ontodetect.config/1"``.
        source : str, optional
            File the data came from, named in error messages.

        Raises
        ------
        InvalidParameterError
            An unknown section or key (the message names it and the file), or a
            value breaking its rule.
        """
        try:
            return cls._from_dict(data, source)
        except (UnknownKeyError, ConfigValueError):
            raise
        except InvalidParameterError as exc:
            if source is None:
                raise
            raise ConfigValueError(source, exc) from None

    @classmethod
    def _from_dict(cls, data: Mapping[str, Any] | None, source: str | None) -> Config:
        if data is None:
            data = {}
        if not isinstance(data, Mapping):
            raise InvalidParameterError(
                "configuration", "a mapping of sections", type(data).__name__
            )
        classes = cls.section_classes()
        sections: dict[str, Any] = {}
        for key, values in data.items():
            if key == "format":
                if values != FORMAT:
                    raise InvalidParameterError("format", repr(FORMAT), values)
                continue
            if key not in classes:
                raise UnknownKeyError(str(key), classes, source)
            if values is None:
                values = {}
            if not isinstance(values, Mapping):
                raise InvalidParameterError(key, "a mapping of parameters", values)
            names = {f.name for f in dataclasses.fields(classes[key])}
            for name in values:
                if name not in names:
                    raise UnknownKeyError(f"{key}.{name}", (f"{key}.{n}" for n in names), source)
            sections[key] = classes[key](**values)
        return cls(**sections)

    def to_dict(self) -> dict[str, Any]:
        """Nested plain dictionary with a ``format`` key; ``from_dict`` reads it back."""
        out: dict[str, Any] = {"format": FORMAT}
        for name in self.section_classes():
            out[name] = getattr(self, name).to_dict()
        return out

    @classmethod
    def from_yaml(cls, path: str | os.PathLike[str]) -> Config:
        """Read a YAML configuration file (any subset of sections and keys).

        Raises
        ------
        ReadError
            The file cannot be read or is not valid YAML.
        InvalidParameterError
            An unknown key or a bad value; the message names the key and the file.
        """
        return cls.from_yaml_text(read_text(path, "configuration file"), source=str(Path(path)))

    @classmethod
    def from_yaml_text(cls, text: str, *, source: str | None = None) -> Config:
        """Parse YAML text; ``source`` names it in error messages."""
        try:
            data = load_yaml(text)
        except yaml.YAMLError as exc:
            raise ReadError(
                source or "<config>", f"invalid YAML{describe_yaml_error(exc)}"
            ) from None
        return cls.from_dict(data, source=source)

    def to_yaml(self, path: str | os.PathLike[str] | None = None) -> str:
        """YAML text of the whole configuration; written atomically to ``path`` if given."""
        text = yaml.dump(self.to_dict(), Dumper=_Dumper, sort_keys=False)
        if path is not None:
            atomic_write_text(Path(path), text)
        return text

    # -- single values -------------------------------------------------------------------
    def get(self, key: str) -> Any:
        """The value at a dotted path such as ``"cluster.radius"``."""
        section, name = self._split(key)
        return getattr(getattr(self, section), name)

    def replace(self, **changes: Mapping[str, Any]) -> Config:
        """A copy with some parameters changed: ``cfg.replace(cluster={"radius": 0.04})``."""
        classes = self.section_classes()
        new = {}
        for section, values in changes.items():
            if section not in classes:
                raise UnknownKeyError(section, classes)
            merged = getattr(self, section).to_dict()
            for name in values:
                if name not in merged:
                    raise UnknownKeyError(f"{section}.{name}", (f"{section}.{n}" for n in merged))
            merged.update(values)
            new[section] = classes[section](**merged)
        return dataclasses.replace(self, **new)

    def with_overrides(self, overrides: Iterable[str]) -> Config:
        """Apply ``section.key=value`` strings (values parsed as YAML scalars or lists).

        Examples
        --------
        >>> Config().with_overrides(["cluster.length=[0.2, 3]"]).cluster.length
        (0.2, 3.0)
        """
        changes: dict[str, dict[str, Any]] = {}
        for text in overrides:
            key, value = parse_override(text)
            section, name = self._split(key)
            changes.setdefault(section, {})[name] = value
        return self.replace(**changes)

    def _split(self, key: str) -> tuple[str, str]:
        section, _, name = key.partition(".")
        classes = self.section_classes()
        if section not in classes:
            raise UnknownKeyError(key, (f"{c}.<key>" for c in classes))
        names = {f.name for f in dataclasses.fields(classes[section])}
        if name not in names:
            raise UnknownKeyError(key, (f"{section}.{n}" for n in names))
        return section, name


class _Dumper(yaml.SafeDumper):
    """Block style for sections, flow style for ``[low, high]`` pairs; no aliases (the YAML
    loader refuses them)."""

    def ignore_aliases(self, data: object) -> bool:
        return True


_Dumper.add_representer(
    list, lambda d, v: d.represent_sequence("tag:yaml.org,2002:seq", v, flow_style=True)
)


def parse_override(text: str) -> tuple[str, Any]:
    """Split ``"section.key=value"``; the value is read as YAML (``0.04``, ``[1, 2]``, ``null``).

    Examples
    --------
    >>> parse_override("cluster.method=dbscan")
    ('cluster.method', 'dbscan')
    >>> parse_override("prepare.scale=null")
    ('prepare.scale', None)
    """
    key, sep, raw = text.partition("=")
    key = key.strip()
    if not sep or not key:
        raise InvalidParameterError("--set", "of the form section.key=value", text)
    try:
        value = load_yaml(raw) if raw.strip() else None
    except yaml.YAMLError:
        value = raw.strip()
    return key, value
