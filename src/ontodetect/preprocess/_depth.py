"""Depth steps of a single camera frame, smoothed over its pixel grid.

A structured-light or stereo camera measures disparity in steps (a Kinect: 1/8
pixel), so depth comes in layers whose spacing grows with the square of the
distance: 3 mm at 1 m, 5 cm at 4 m. Every surface seen at a slant, and anything
leafy or rough, turns into a stack of flat layers facing the camera, and plane
fitting finds those layers instead of the surface (a backrest at the camera's
pitch, a plant made of "seats"). As KinectFusion does before anything else, the
frame is filtered with an edge-preserving bilateral filter over its pixel grid:
on inverse depth, where the steps are all the same size, so one value sigma
serves every distance, and points move only along their rays.
"""

from __future__ import annotations

import numpy as np

from ..cloud import PointCloud, pixel_grid, sensor_position

__all__ = ["smooth_depth"]

#: Filter window (pixels): a round kernel of this diameter.
DEPTH_KERNEL = 7
#: Spatial sigma of the filter (pixels).
DEPTH_PIXEL_SIGMA = 2.0
#: Value sigma on inverse depth (1/m): three disparity steps of a Kinect (1/8 pixel,
#: f = 525 px, baseline 7.5 cm); a depth edge between objects is far larger.
DEPTH_VALUE_SIGMA = 0.01


def smooth_depth(cloud: PointCloud) -> PointCloud:
    """``cloud`` with its depth steps smoothed, when it is one organized frame.

    Needs the pixel grid (:func:`ontodetect.cloud.pixel_grid`) and the sensor's
    position (:func:`ontodetect.cloud.sensor_position`); any other cloud, or one this
    function already smoothed (``meta["depth_smoothed"]``), comes back unchanged. Each
    point keeps its row, colour and fields and moves along the ray
    from the sensor to the bilaterally filtered inverse range of its pixel
    (Open3D's ``Image.filter_bilateral``; pixels without a return weigh nothing,
    since their value 0 is far from any real inverse depth).

    Examples
    --------
    >>> import numpy as np
    >>> from ontodetect import point_cloud
    >>> v, u = np.mgrid[0:20, 0:20]
    >>> rays = np.c_[(u.ravel() - 10) / 50, (v.ravel() - 10) / 50, np.ones(400)]
    >>> steps = 2.0 + 0.03 * (u.ravel() % 2)           # a wall at 2 m, in 3 cm layers
    >>> frame = point_cloud(rays * steps[:, None]).with_meta(
    ...     organized=True, width=20, height=20, viewpoint=[0, 0, 0, 1, 0, 0, 0])
    >>> depth = smooth_depth(frame).xyz[:, 2].reshape(20, 20)
    >>> round(float(np.ptp(steps)), 3), round(float(np.ptp(depth[5:15, 5:15])), 3)  # 3 cm: 7 mm
    (0.03, 0.007)
    """
    if cloud.meta.get("depth_smoothed"):
        return cloud
    grid = pixel_grid(cloud)
    eye = sensor_position(cloud)
    if grid is None or eye is None or not len(cloud):
        return cloud
    import open3d as o3d

    pixels, width, height = grid
    rays = cloud.xyz - eye
    distance = np.linalg.norm(rays, axis=1)
    valid = distance > 0
    image = np.zeros(width * height, dtype=np.float32)
    image[pixels[valid]] = 1.0 / distance[valid]
    filtered = (
        o3d.t.geometry.Image(o3d.core.Tensor(image.reshape(height, width)))
        .filter_bilateral(DEPTH_KERNEL, DEPTH_VALUE_SIGMA, DEPTH_PIXEL_SIGMA)
        .as_tensor()
        .numpy()
        .reshape(-1)
        .astype(np.float64)
    )
    inverse = filtered[pixels]
    moved = valid & (inverse > 0)
    factor = np.ones(len(cloud))
    factor[moved] = 1.0 / (inverse[moved] * distance[moved])
    return cloud.replace(xyz=eye + rays * factor[:, None]).with_meta(depth_smoothed=True)
