"""The plain Open3D recipe every benchmark compares against, in one place.

Statistical outlier removal, the altitude cut-off, DBSCAN at full resolution and
repeated RANSAC ``segment_plane`` per cluster: what a user of Open3D would write
to get clusters and planes, with Table 4.1's radius and inlier distance.
"""

from __future__ import annotations

import numpy as np

from ontodetect.config import Config

#: remove_statistical_outlier(nb_neighbors, std_ratio).
O3D_SOR = (20, 2.0)
#: cluster_dbscan(eps, min_points): Table 4.1's 5 cm radius.
O3D_DBSCAN = (0.05, 10)
#: segment_plane(distance_threshold, ransac_n, num_iterations): Table 4.1's 1 cm.
O3D_PLANE = (0.01, 3, 1000)
#: As many planes per cluster as ontodetect extracts (``planes.max_planes``).
O3D_MAX_PLANES = Config().planes.max_planes
O3D_MIN_CLUSTER = 100
O3D_MIN_PLANE = 30
#: Table 4.1: objects are searched below 1.4 m.
CUTOFF = 1.4


def cluster(pc):
    """Outlier removal, altitude cut-off and DBSCAN; returns the kept cloud and its labels."""
    pc, _ = pc.remove_statistical_outlier(*O3D_SOR)
    pts = np.asarray(pc.points)
    pc = pc.select_by_index(np.flatnonzero(pts[:, 2] < CUTOFF))
    return pc, np.asarray(pc.cluster_dbscan(*O3D_DBSCAN))


def planes(pc, labels: np.ndarray) -> int:
    """Repeated ``segment_plane`` in every cluster; returns how many planes were found."""
    import open3d as o3d

    found = 0
    pts = np.asarray(pc.points)
    for k in range(int(labels.max()) + 1 if labels.size else 0):
        idx = np.flatnonzero(labels == k)
        if len(idx) < O3D_MIN_CLUSTER:
            continue
        rest = o3d.geometry.PointCloud(o3d.utility.Vector3dVector(pts[idx]))
        for _ in range(O3D_MAX_PLANES):
            if len(rest.points) < O3D_MIN_PLANE:
                break
            _, inl = rest.segment_plane(*O3D_PLANE)
            if len(inl) < O3D_MIN_PLANE:
                break
            found += 1
            rest = rest.select_by_index(inl, invert=True)
    return found


def main(argv: list[str] | None = None) -> None:
    """``python -m benchmarks._open3d_recipe SCAN``: read a scan and run the recipe on it, as
    a whole process (the end-to-end comparison of ``python -m benchmarks detect --cli``)."""
    import sys

    import open3d as o3d

    from ontodetect.io import read_cloud

    (path,) = sys.argv[1:] if argv is None else argv
    xyz = np.array(read_cloud(path).xyz)  # Open3D wants a writeable copy
    pc, labels = cluster(o3d.geometry.PointCloud(o3d.utility.Vector3dVector(xyz)))
    print(f"{int(labels.max()) + 1 if labels.size else 0} clusters, {planes(pc, labels)} planes")


if __name__ == "__main__":
    main()
