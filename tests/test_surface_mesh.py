"""Surface reconstruction (Alg. 1 step 2): meshes of generated shapes with known surfaces,
the mesh file of ``detect --mesh``, and mesh adjacency for clustering."""

import json

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from scipy.sparse import coo_matrix
from scipy.sparse.csgraph import connected_components

from ontodetect.cli import main
from ontodetect.config import Config
from ontodetect.errors import InvalidParameterError, WriteError
from ontodetect.io import write_mesh
from ontodetect.preprocess import SurfaceMesh, _reconstruct, reconstruct_surface
from ontodetect.segment import euclidean_clusters, mesh_graph, radius_graph
from ontodetect.synth import synthesize, write_synth

CELL = 0.02


def sphere(n, radius, rng, center=(0.0, 0.0, 0.0)):
    """``n`` points on a sphere and their outward normals."""
    d = rng.normal(size=(n, 3))
    d /= np.linalg.norm(d, axis=1, keepdims=True)
    return np.asarray(center) + radius * d, d


def box_surface(size, n, rng):
    """``n`` points on the faces of a box of ``size`` centred at the origin."""
    size = np.asarray(size, dtype=np.float64)
    areas = np.array([size[1] * size[2], size[0] * size[2], size[0] * size[1]]).repeat(2)
    face = rng.choice(6, n, p=areas / areas.sum())
    pts = (rng.random((n, 3)) - 0.5) * size
    axis, side = face // 2, face % 2
    pts[np.arange(n), axis] = np.where(side == 1, 0.5, -0.5) * size[axis]
    return pts


def box_distance(points, size):
    """Unsigned distance of points to the surface of a centred box."""
    q = np.abs(points) - np.asarray(size) / 2
    outside = np.linalg.norm(np.maximum(q, 0.0), axis=1)
    return np.abs(outside + np.minimum(q.max(axis=1), 0.0))


def edge_uses(mesh):
    t = mesh.triangles.astype(np.int64)
    e = np.sort(np.concatenate([t[:, [0, 1]], t[:, [1, 2]], t[:, [2, 0]]]), axis=1)
    _, counts = np.unique(e, axis=0, return_counts=True)
    return counts


# -- blocks -----------------------------------------------------------------------------------
def test_blocks_meet_without_seams(rng, monkeypatch):
    """A sphere across many blocks: one closed surface, each vertex once, whatever the block."""
    pts, normals = sphere(20_000, 0.3, rng)
    large = reconstruct_surface(pts, normals, cell=CELL)
    monkeypatch.setattr(_reconstruct, "MC_BLOCK", 4)  # ~8 blocks across the sphere
    small = reconstruct_surface(pts, normals, cell=CELL)
    for mesh in (large, small):
        assert len(np.unique(mesh.vertices, axis=0)) == len(mesh.vertices)
        assert (edge_uses(mesh) == 2).all()
        # a sphere: V - E + F = 2, and one connected surface
        assert len(mesh.vertices) - len(mesh.edges) + len(mesh.triangles) == 2
        e = mesh.edges
        adj = coo_matrix((np.ones(len(e)), (e[:, 0], e[:, 1])), shape=(len(mesh.vertices),) * 2)
        assert connected_components(adj, directed=False)[0] == 1
    # the same surface: same vertices (the grid edges' crossings), same triangles
    assert len(small.vertices) == len(large.vertices)
    assert len(small.triangles) == len(large.triangles)
    a, b = large.vertices, small.vertices
    np.testing.assert_allclose(a[np.lexsort(a.T)], b[np.lexsort(b.T)], atol=1e-9)
    assert small.area == pytest.approx(large.area, rel=1e-9)


@pytest.mark.parametrize("block", [4, 32])
def test_a_surface_through_grid_nodes_is_closed(monkeypatch, block):
    """Signed distances of exactly 0 at many nodes, on block faces too: no vertex on a
    node is lost or doubled (0 counts as outside, as a distance just above it)."""
    monkeypatch.setattr(_reconstruct, "MC_BLOCK", block)
    ijk = np.stack(np.meshgrid(*[np.arange(1, 18)] * 3, indexing="ij"), -1).reshape(-1, 3)
    # an octahedron |i - 9| + |j - 9| + |k - 9| = 5, in whole cells
    values = np.abs(ijk - 9).sum(axis=1) - 5.0
    keys = _reconstruct._pack(ijk)
    order = np.argsort(keys)
    vertices, triangles = _reconstruct._marching_cubes(
        keys[order], values[order] * CELL, np.zeros(3), CELL
    )
    mesh = SurfaceMesh(vertices, triangles)
    assert np.isfinite(vertices).all() and (values == 0).sum() > 100
    assert len(np.unique(vertices, axis=0)) == len(vertices)
    assert (edge_uses(mesh) == 2).all()
    assert len(vertices) - len(mesh.edges) + len(triangles) == 2
    # on the octahedron, moved by at most about MIN_DISTANCE of a cell
    d = np.abs(vertices / CELL - 9).sum(axis=1) - 5.0
    assert np.abs(d).max() < 2 * _reconstruct.MIN_DISTANCE
    v = vertices[triangles]
    n = np.cross(v[:, 1] - v[:, 0], v[:, 2] - v[:, 0])
    assert (np.einsum("ij,ij->i", n, v.mean(axis=1) - 9 * CELL) > 0).all()  # outwards


# -- known surfaces ---------------------------------------------------------------------------
def test_sphere_mesh_lies_on_and_covers_the_sphere(rng):
    pts, normals = sphere(40_000, 0.5, rng)
    mesh = reconstruct_surface(pts, normals, cell=CELL)
    r = np.linalg.norm(mesh.vertices, axis=1)
    assert np.abs(r - 0.5).max() < 0.1 * CELL
    assert mesh.area == pytest.approx(4 * np.pi * 0.25, rel=0.02)
    # closed: every edge is shared by two triangles
    assert (edge_uses(mesh) == 2).all()
    # wound so that the triangles face where the normals point (outwards)
    v = mesh.vertices[mesh.triangles]
    n = np.cross(v[:, 1] - v[:, 0], v[:, 2] - v[:, 0])
    assert (np.einsum("ij,ij->i", n, v.mean(axis=1)) > 0).all()


def test_estimated_normals_face_the_viewpoint(rng):
    pts, _ = sphere(20_000, 0.5, rng)
    inward = reconstruct_surface(pts, cell=CELL)  # default viewpoint: the centroid
    outward = reconstruct_surface(pts, cell=CELL, viewpoint=(0.0, 0.0, 50.0))
    for mesh, sign in ((inward, -1), (outward, 1)):
        v = mesh.vertices[mesh.triangles]
        n = np.cross(v[:, 1] - v[:, 0], v[:, 2] - v[:, 0])
        facing = np.einsum("ij,ij->i", n, v.mean(axis=1)) * sign > 0
        # from far above, the normals of the lower half still turn outwards by the
        # viewpoint's rule only near the top; inside, all turn inwards
        assert facing.mean() > (0.99 if sign < 0 else 0.45)
    assert inward.area == pytest.approx(4 * np.pi * 0.25, rel=0.02)


def test_box_mesh_lies_on_and_covers_the_box(rng):
    size = (1.0, 0.6, 0.4)
    pts = box_surface(size, 30_000, rng)
    mesh = reconstruct_surface(pts, cell=CELL, viewpoint=(0.0, 0.0, 0.0))
    d = box_distance(mesh.vertices, size)
    # faces are flat to a fraction of a cell; edges and corners round off within a cell
    q = np.abs(mesh.vertices) - np.asarray(size) / 2
    near_edge = np.sort(q, axis=1)[:, 1] > -1.5 * CELL
    assert d[~near_edge].max() < 0.1 * CELL
    assert d.max() < CELL
    true_area = 2 * (1.0 * 0.6 + 1.0 * 0.4 + 0.6 * 0.4)
    assert mesh.area == pytest.approx(true_area, rel=0.10)
    # every face of the box is covered: its centre has a vertex within a cell
    from scipy.spatial import cKDTree

    centres = np.vstack([np.eye(3) * np.asarray(size) / 2, -np.eye(3) * np.asarray(size) / 2])
    d, _ = cKDTree(mesh.vertices).query(centres)
    assert d.max() < CELL


def test_open_sheet_ends_near_its_last_points(rng):
    """A table top sampled on 1 m x 1 m gives about 1 m² of mesh, not a plane running on."""
    xy = rng.random((2500, 2))
    pts = np.c_[xy, 0.75 + rng.normal(0, 0.002, 2500)]
    mesh = reconstruct_surface(pts, cell=CELL, viewpoint=(0.5, 0.5, 1.5))
    assert mesh.area == pytest.approx(1.0, rel=0.05)
    assert mesh.vertices[:, :2].min() > -2 * CELL and mesh.vertices[:, :2].max() < 1 + 2 * CELL
    assert np.abs(mesh.vertices[:, 2] - 0.75).max() < 0.01


def test_colours_are_carried(rng):
    size = (1.0, 0.6, 0.4)
    pts = box_surface(size, 30_000, rng)
    colors = np.where((pts[:, 0] < 0)[:, None], [200, 30, 10], [10, 40, 220]).astype(np.uint8)
    mesh = reconstruct_surface(pts, colors=colors, cell=CELL, viewpoint=(0, 0, 0))
    assert mesh.colors is not None and mesh.colors.dtype == np.uint8
    assert mesh.colors.shape == mesh.vertices.shape
    left, right = mesh.vertices[:, 0] < -0.1, mesh.vertices[:, 0] > 0.1
    assert (mesh.colors[left] == [200, 30, 10]).all()
    assert (mesh.colors[right] == [10, 40, 220]).all()
    assert reconstruct_surface(pts, cell=CELL).colors is None


def test_input_not_modified(rng):
    pts = box_surface((0.5, 0.5, 0.5), 5000, rng)
    before = pts.copy()
    reconstruct_surface(pts, cell=CELL)
    assert np.array_equal(pts, before)


# -- determinism ------------------------------------------------------------------------------
def test_same_input_same_file(rng, tmp_path):
    pts = box_surface((0.8, 0.5, 0.4), 20_000, rng)
    colors = rng.integers(0, 256, (len(pts), 3), dtype=np.uint8)
    files = []
    for k in range(2):
        mesh = reconstruct_surface(pts, colors=colors, cell=CELL)
        files.append(write_mesh(tmp_path / f"{k}.ply", mesh.vertices, mesh.triangles, mesh.colors))
    assert files[0].read_bytes() == files[1].read_bytes()


@settings(max_examples=8)
@given(st.integers(0, 2**32 - 1))
def test_point_order_does_not_change_the_mesh(seed):
    """The mesh depends on the set of points, not their order (same vertices, same count)."""
    rng = np.random.default_rng(7)
    pts = box_surface((0.5, 0.4, 0.3), 6000, rng)
    reference = reconstruct_surface(pts, cell=CELL, viewpoint=(0, 0, 0))
    shuffled = pts[np.random.default_rng(seed).permutation(len(pts))]
    mesh = reconstruct_surface(shuffled, cell=CELL, viewpoint=(0, 0, 0))
    assert len(mesh.vertices) == len(reference.vertices)
    assert len(mesh.triangles) == len(reference.triangles)
    np.testing.assert_allclose(mesh.vertices, reference.vertices, atol=1e-12)


# -- large scans and other methods --------------------------------------------------------------
def test_large_scans_are_meshed_at_a_coarser_cell(rng):
    pts, normals = sphere(20_000, 0.5, rng)
    full = reconstruct_surface(pts, normals, cell=CELL)
    capped = reconstruct_surface(pts, normals, cell=CELL, max_cells=2000)
    assert not full.info["capped"] and capped.info["capped"]
    assert capped.cell > CELL and capped.info["occupied_cells"] <= 2000
    assert capped.info["requested_cell"] == CELL
    assert len(capped.vertices) < len(full.vertices)
    assert capped.area == pytest.approx(full.area, rel=0.05)


def test_poisson_method(rng):
    pts, normals = sphere(3000, 0.5, rng)
    colors = np.full((len(pts), 3), 90, dtype=np.uint8)
    cell = 0.05
    mesh = reconstruct_surface(pts, normals, colors, cell=cell, method="poisson")
    assert mesh.info["method"] == "poisson" and len(mesh.triangles) > 500
    r = np.linalg.norm(mesh.vertices, axis=1)
    assert np.median(np.abs(r - 0.5)) < cell
    assert mesh.colors is not None and np.abs(mesh.colors.astype(int) - 90).max() <= 1
    again = reconstruct_surface(pts, normals, colors, cell=cell, method="poisson")
    assert np.array_equal(mesh.vertices, again.vertices)
    assert np.array_equal(mesh.triangles, again.triangles)


def test_tiny_input_gives_an_empty_mesh():
    mesh = reconstruct_surface([[0.0, 0.0, 0.0], [0.01, 0, 0]])
    assert isinstance(mesh, SurfaceMesh) and len(mesh) == 0 and mesh.area == 0.0


# -- parameters -------------------------------------------------------------------------------
@pytest.mark.parametrize(
    ("kwargs", "name"),
    [
        ({"cell": 0.0}, "cell"),
        ({"cell": -0.02}, "cell"),
        ({"cell": float("nan")}, "cell"),
        ({"method": "delaunay"}, "method"),
        ({"max_cells": 0}, "max_cells"),
        ({"max_cells": 2.5}, "max_cells"),
        ({"colors": np.zeros((3, 3), np.uint8)}, "colors"),
        ({"normals": np.zeros((3, 3))}, "normals"),
        ({"viewpoint": (0.0, 1.0)}, "viewpoint"),
    ],
)
def test_bad_parameters_are_named(rng, kwargs, name):
    pts = box_surface((0.5, 0.5, 0.5), 500, rng)
    with pytest.raises(InvalidParameterError, match=f"'{name}' parameter"):
        reconstruct_surface(pts, **kwargs)


def test_bad_points_are_named():
    with pytest.raises(InvalidParameterError, match="'points' parameter"):
        reconstruct_surface([[0.0, 0.0], [1.0, 1.0]])


def test_write_mesh_refuses_what_is_not_a_mesh(tmp_path):
    with pytest.raises(WriteError, match="outside"):
        write_mesh(tmp_path / "m.ply", np.zeros((3, 3)), [[0, 1, 5]])
    with pytest.raises(WriteError, match="colours"):
        write_mesh(tmp_path / "m.ply", np.zeros((3, 3)), [[0, 1, 2]], np.zeros((2, 3)))
    assert not (tmp_path / "m.ply").exists()


def test_written_mesh_reads_back_in_open3d_and_trimesh(rng, tmp_path):
    import open3d as o3d
    import trimesh

    pts, normals = sphere(5000, 0.3, rng, center=(400_000.0, 5_000_000.0, 10.0))
    colors = np.tile(np.array([[12, 34, 56]], np.uint8), (len(pts), 1))
    mesh = reconstruct_surface(pts, normals, colors, cell=CELL)
    path = write_mesh(tmp_path / "m.ply", mesh.vertices, mesh.triangles, mesh.colors)
    tm = trimesh.load(path, process=False)
    assert np.array_equal(tm.faces, mesh.triangles)
    # float64 coordinates: millimetres survive 5,000 km from the origin
    np.testing.assert_allclose(tm.vertices, mesh.vertices, atol=1e-9)
    om = o3d.io.read_triangle_mesh(str(path))
    assert len(om.triangles) == len(mesh.triangles)
    assert np.allclose(np.asarray(om.vertex_colors), np.array([12, 34, 56]) / 255)


# -- mesh adjacency -------------------------------------------------------------------------------
def _sheet(x0, x1, y0, y1, z, spacing=0.02):
    xs, ys = np.arange(x0, x1 + 1e-9, spacing), np.arange(y0, y1 + 1e-9, spacing)
    g = np.stack(np.meshgrid(xs, ys), -1).reshape(-1, 2)
    return np.c_[g, np.full(len(g), z)]


def test_mesh_adjacency_parts_objects_the_radius_graph_joins():
    """Two seats 10 cm apart: a 12 cm radius graph joins them, the surface does not.

    (A gap of up to about four cells looks like a hole between samples, and the mesh
    bridges it: the radius has to be wider than that for the two to differ.)"""
    left = _sheet(0.0, 0.4, 0.0, 0.4, 0.45)
    right = _sheet(0.5, 0.9, 0.0, 0.4, 0.47)
    pts = np.vstack([left, right])
    radius = 0.12
    assert euclidean_clusters(pts, radius).max() == 0
    mesh = reconstruct_surface(pts, cell=CELL, viewpoint=(0.4, 0.2, 1.5))
    g = mesh_graph(pts, mesh, radius)
    labels = euclidean_clusters(pts, radius, graph=g)
    assert labels.max() == 1
    assert len(set(labels[: len(left)])) == 1 and len(set(labels[len(left) :])) == 1
    assert labels[0] != labels[-1]


def test_mesh_adjacency_keeps_a_folded_object_whole():
    """A seat and the backrest rising from its edge are one surface: one cluster."""
    seat = _sheet(0.0, 0.44, 0.0, 0.44, 0.45)
    xs, zs = np.arange(0.0, 0.44 + 1e-9, 0.02), np.arange(0.47, 0.9 + 1e-9, 0.02)
    g = np.stack(np.meshgrid(xs, zs), -1).reshape(-1, 2)
    back = np.c_[g[:, 0], np.full(len(g), 0.44), g[:, 1]]
    pts = np.vstack([seat, back])
    mesh = reconstruct_surface(pts, cell=CELL, viewpoint=(0.2, -1.0, 1.5))
    radius = 0.05
    g = mesh_graph(pts, mesh, radius)
    assert euclidean_clusters(pts, radius, graph=g).max() == 0
    # a subgraph of the radius graph, with its distances
    full = radius_graph(pts, radius)
    r, c = g.nonzero()
    assert set(zip(r.tolist(), c.tolist())) <= set(zip(*[a.tolist() for a in full.nonzero()]))
    np.testing.assert_allclose(np.asarray(g[r, c]).ravel(), np.asarray(full[r, c]).ravel())
    assert abs(g - g.T).max() == 0
    assert g.nnz > 0.8 * full.nnz  # along a surface, nearly every neighbour stays


def test_mesh_graph_of_an_empty_mesh_joins_nothing():
    pts = _sheet(0.0, 0.1, 0.0, 0.1, 0.0)
    empty = SurfaceMesh(np.zeros((0, 3)), np.zeros((0, 3), np.int32), None, CELL)
    g = mesh_graph(pts, empty, 0.05)
    assert g.shape == (len(pts), len(pts)) and g.nnz == 0
    assert connected_components(g)[0] == len(pts)


def test_adjacency_setting():
    assert Config().cluster.adjacency == "radius"
    assert Config().with_overrides(["cluster.adjacency=mesh"]).cluster.adjacency == "mesh"
    with pytest.raises(InvalidParameterError, match=r"'cluster\.adjacency' parameter"):
        Config().with_overrides(["cluster.adjacency=delaunay"])


# -- end to end -------------------------------------------------------------------------------
@pytest.fixture(scope="module")
def scene(tmp_path_factory):
    out = tmp_path_factory.mktemp("mesh-scene")
    write_synth(synthesize("dining_room", "rgbd", seed=5, points=20_000), out)
    return out


def test_detect_writes_a_mesh_on_request(scene, tmp_path, capsys):
    import trimesh

    from ontodetect.io import read_cloud

    plain = tmp_path / "plain"
    assert main(["detect", str(scene / "cloud.ply"), "-o", str(plain), "--no-picture", "-q"]) == 0
    assert not (plain / "mesh.ply").exists()
    out = tmp_path / "meshed"
    code = main(
        ["detect", str(scene / "cloud.ply"), "-o", str(out), "--mesh", "--no-picture", "--json"]
    )
    assert code == 0
    doc = json.loads(capsys.readouterr().out)
    assert str(out / "mesh.ply") in doc["files"]
    # the mesh changes nothing else
    assert (out / "detections.json").read_bytes() == (plain / "detections.json").read_bytes()
    mesh = trimesh.load(out / "mesh.ply", process=False)
    assert len(mesh.faces) > 1000
    cloud = read_cloud(scene / "cloud.ply")
    lo, hi = cloud.xyz.min(axis=0), cloud.xyz.max(axis=0)
    assert (mesh.vertices >= lo - 0.1).all() and (mesh.vertices <= hi + 0.1).all()
    # in the input's frame: the vertices lie on the scan
    from scipy.spatial import cKDTree

    d, _ = cKDTree(cloud.xyz).query(mesh.vertices)
    assert np.median(d) < 0.03
    assert mesh.visual.vertex_colors.shape[0] == len(mesh.vertices)


def test_detect_with_mesh_adjacency_runs(scene, tmp_path):
    out = tmp_path / "adj"
    args = ["detect", str(scene / "cloud.ply"), "-o", str(out), "--no-picture", "-q"]
    assert main([*args, "--set", "cluster.adjacency=mesh"]) == 0
    doc = json.loads((out / "detections.json").read_text())
    assert doc["detections"]


def test_cli_bad_adjacency_and_mesh_with_tiles_exit_2(scene, tmp_path, capsys):
    args = ["detect", str(scene / "cloud.ply"), "-o", str(tmp_path / "x")]
    assert main([*args, "--set", "cluster.adjacency=delaunay"]) == 2
    err = capsys.readouterr().err
    assert "cluster.adjacency" in err and "Traceback" not in err
    assert main([*args, "--mesh", "--tile", "5"]) == 2
    assert "--mesh" in capsys.readouterr().err


def test_a_moved_scan_meets_the_same_grid(rng):
    """Moved by 400 km (UTM-like coordinates), the mesh is the same, moved."""
    pts = box_surface((0.8, 0.5, 0.4), 8000, rng)
    offset = np.array([400_000.0, 400_000.0, 0.0])
    here = reconstruct_surface(pts, cell=CELL, viewpoint=(0, 0, 0))
    there = reconstruct_surface(pts + offset, cell=CELL, viewpoint=offset)
    assert np.array_equal(here.triangles, there.triangles)
    np.testing.assert_allclose(there.vertices - offset, here.vertices, atol=1e-6)
