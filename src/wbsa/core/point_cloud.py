"""Point clouds (PCL's ``.pcd``, ``.ply``) as depth images: read through Open3D, in the camera's frame.

An organised ``.pcd`` (``WIDTH`` × ``HEIGHT`` > 1, as a depth camera's driver writes it) keeps its pixel grid:
its depth image is the points' z in grid order, and its camera is recovered from its own points
(:func:`grid_intrinsics`), so none is guessed; a preset it matches is taken with its sensor model. A ``.ply`` or an unorganised ``.pcd`` has no grid: its points are
projected through a stated camera (:func:`project_points`), or refused without one.

The points are taken as the camera sees them (x right, y down, z forward; metres unless a scale is given).
"""

from __future__ import annotations

import os
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from wbsa.errors import WbsaError

#: Point-cloud file types :func:`read_point_cloud` reads.
POINT_CLOUD_SUFFIXES = (".pcd", ".ply")
#: Fewest pixels with a return an organised cloud needs for its camera to be recovered.
MIN_GRID_RETURNS = 100


@dataclass(frozen=True)
class PointCloud:
    """Points read from a file.

    Attributes
    ----------
    points_m : (n, 3) float64
        The points in the camera's frame (metres); NaN rows are pixels without a return (organised clouds).
    grid : (int, int) or None
        (height, width) of an organised cloud, whose points are its pixels row by row; None for an
        unorganised one.
    """

    points_m: np.ndarray
    grid: tuple[int, int] | None


def is_point_cloud_path(path) -> bool:
    """Whether ``path`` is a path whose suffix is a point-cloud type (:data:`POINT_CLOUD_SUFFIXES`).

    Parameters
    ----------
    path : object
        Anything; only a str or path-like with a ``.pcd`` or ``.ply`` suffix is a point cloud.
    """
    return isinstance(path, (str, os.PathLike)) and Path(path).suffix.lower() in POINT_CLOUD_SUFFIXES


def _pcd_header(path: Path) -> dict[str, str]:
    """The text header of a ``.pcd`` file (keys to values), up to its ``DATA`` line."""
    header: dict[str, str] = {}
    with open(path, "rb") as fh:
        for _ in range(64):  # the header is a dozen lines; a file without DATA is not a PCD
            line = fh.readline()
            if not line:
                break
            key, _, value = line.decode("ascii", errors="replace").strip().partition(" ")
            if key == "DATA":
                header[key] = value
                return header
            if key and not key.startswith("#"):
                header[key] = value
    raise WbsaError(f"{path} has no PCD header (no DATA line); save it with PCL or Open3D")


def read_point_cloud(path: str | os.PathLike, *, units_per_m: float = 1.0) -> PointCloud:
    """Read a ``.pcd`` or ``.ply`` file with Open3D, keeping an organised PCD's grid.

    Parameters
    ----------
    path : str or path
    units_per_m : float
        Coordinate units per metre in the file (1: metres; 1000: millimetres).

    Returns
    -------
    PointCloud

    Raises
    ------
    WbsaError
        A missing or unreadable file, an unknown suffix, no points, or a grid that does not match the points.
    """
    from wbsa.core.depth_image import check_depth_path
    from wbsa.core.mesh_io import quiet_stderr

    path = Path(path)
    if isinstance(units_per_m, bool) or not isinstance(units_per_m, (int, float, np.number)) or not (
            np.isfinite(units_per_m) and units_per_m > 0):
        raise WbsaError(f"depth scale {units_per_m!r} must be a positive number of coordinate units per metre, "
                        "e.g. 1000 for millimetres")
    suffix = path.suffix.lower()
    if suffix not in POINT_CLOUD_SUFFIXES:
        raise WbsaError(f"cannot read a point cloud from {path.name}: use a {' or '.join(POINT_CLOUD_SUFFIXES)} file")
    check_depth_path(path)
    grid = None
    if suffix == ".pcd":
        header = _pcd_header(path)
        try:
            width, height = int(header.get("WIDTH", "0")), int(header.get("HEIGHT", "1"))
        except ValueError:
            raise WbsaError(f"{path} has a PCD header whose WIDTH or HEIGHT is not a whole number; check the "
                            "file") from None
        if height > 1:
            from wbsa.core.limits import check_image_size

            check_image_size(width, height, f"point cloud {path}")
            grid = (height, width)
    import open3d as o3d

    with quiet_stderr(), o3d.utility.VerbosityContextManager(o3d.utility.VerbosityLevel.Error):  # its own errors
        cloud = o3d.io.read_point_cloud(str(path), remove_nan_points=False, remove_infinite_points=False)
    points = np.asarray(cloud.points, dtype=np.float64) / float(units_per_m)
    if len(points) == 0:
        raise WbsaError(f"{path} holds no points Open3D can read; check that it is a point cloud "
                        "(x, y, z fields)")
    if grid is not None and len(points) != grid[0] * grid[1]:
        raise WbsaError(f"{path} announces a {grid[1]} x {grid[0]} grid but holds {len(points)} points; "
                        "check the file")
    points[~np.isfinite(points).all(axis=1)] = np.nan
    return PointCloud(points, grid)


def grid_intrinsics(points_m: np.ndarray, name: str = "custom"):
    """The pinhole camera whose pixel grid an organised cloud's points lie on.

    Each pixel (u, v) with a return satisfies u = fx·x/z + cx and v = fy·y/z + cy; the two lines are fitted
    by least squares over every such pixel, and kept to a thousandth of a pixel (points stored as float32
    carry no finer: PCL's ``five_people.pcd`` fits 525.0000056, which is 525.000).

    Parameters
    ----------
    points_m : (h, w, 3) float64
        The organised cloud's points, pixel by pixel (NaN or z <= 0: no return).
    name : str
        The name the camera takes.

    Returns
    -------
    wbsa.camera.Intrinsics
        Image size (w, h), fitted focal lengths and principal point.

    Raises
    ------
    WbsaError
        Fewer than :data:`MIN_GRID_RETURNS` returns, or points that do not lie on a pinhole grid.
    """
    from wbsa.camera.intrinsics import Intrinsics

    height, width = points_m.shape[:2]
    x, y, z = (points_m[..., k] for k in range(3))
    ok = np.isfinite(z) & (z > 0)
    if ok.sum() < MIN_GRID_RETURNS:
        raise WbsaError(f"the point cloud's grid holds {int(ok.sum())} returns, too few to recover its camera "
                        f"(at least {MIN_GRID_RETURNS}); give a frame with the person in it")
    v, u = np.nonzero(ok)
    fit = {}
    for axis, coord, pixel in (("x", x[ok] / z[ok], u), ("y", y[ok] / z[ok], v)):
        design = np.column_stack([coord, np.ones_like(coord)])
        (f, c), *_ = np.linalg.lstsq(design, pixel.astype(np.float64), rcond=None)
        residual = np.abs(design @ (f, c) - pixel)
        if not (np.isfinite(f) and f > 0) or np.percentile(residual, 99) > 1.0:
            raise WbsaError(f"the point cloud's points do not lie on a pinhole camera's pixel grid ({axis}/z does "
                            "not grow with the pixel column); give the depth image, or a .ply with --camera")
        fit[axis] = (round(float(f), 3), round(float(c), 3))
    return Intrinsics(width, height, fit["x"][0], fit["y"][0], fit["x"][1], fit["y"][1], name=name)


def project_points(points_m: np.ndarray, camera) -> np.ndarray:
    """The depth image of a cloud seen by ``camera``: each point projected to its pixel, the nearest kept.

    Parameters
    ----------
    points_m : (n, 3) float64
        Points in the camera's frame (metres); NaN rows and points behind the camera are skipped.
    camera : wbsa.camera.Intrinsics

    Returns
    -------
    (h, w) float64
        z-depth in metres, 0 = no point.

    Raises
    ------
    WbsaError
        If no point falls inside the image.
    """
    p = np.asarray(points_m, dtype=np.float64)
    p = p[np.isfinite(p).all(axis=1) & (p[:, 2] > 0)]
    with np.errstate(over="ignore", invalid="ignore"):  # absurd coordinates project nowhere, without a warning
        u = np.rint(camera.fx * p[:, 0] / p[:, 2] + camera.skew * p[:, 1] / p[:, 2] + camera.cx)
        v = np.rint(camera.fy * p[:, 1] / p[:, 2] + camera.cy)
        inside = (u >= 0) & (u < camera.width) & (v >= 0) & (v < camera.height)
    if not inside.any():
        raise WbsaError(f"none of the {len(points_m)} points falls in the {camera.name} camera's image; the cloud "
                        "must be in the camera's frame (x right, y down, z forward, metres)")
    depth = np.full(camera.width * camera.height, np.inf)
    np.minimum.at(depth, (v[inside] * camera.width + u[inside]).astype(np.int64), p[inside, 2])
    depth[~np.isfinite(depth)] = 0.0
    return depth.reshape(camera.height, camera.width)


def _same_camera(a, b) -> bool:
    """Whether two intrinsics are one camera: the same size, focal lengths within 1 %, centres within 2 px."""
    return ((a.width, a.height) == (b.width, b.height) and abs(a.fx / b.fx - 1) <= 0.01
            and abs(a.fy / b.fy - 1) <= 0.01 and abs(a.cx - b.cx) <= 2 and abs(a.cy - b.cy) <= 2)


def point_cloud_depth(path: str | os.PathLike, camera=None, *, units_per_m: float | None = None):
    """The depth image and camera of a point-cloud file.

    Parameters
    ----------
    path : str or path
        A ``.pcd`` or ``.ply`` file.
    camera : wbsa.camera.Intrinsics or None
        The stated camera, or None. An organised ``.pcd`` needs none: its own is recovered, and where a preset
        agrees with it (the same size, focal lengths within 1 %, principal point within 2 pixels) that preset
        is used, with its sensor model and working range; a stated one must agree with it likewise and is then
        used. A cloud without a grid needs one.
    units_per_m : float or None
        Coordinate units per metre in the file; None: 1 (metres).

    Returns
    -------
    depth_m : (h, w) float64
        z-depth in metres, 0 = no return.
    camera : wbsa.camera.Intrinsics

    Raises
    ------
    WbsaError
        An unreadable file, a cloud without a grid and no camera, or a stated camera the grid contradicts.
    """
    path = Path(path)
    cloud = read_point_cloud(path, units_per_m=1.0 if units_per_m is None else units_per_m)
    if cloud.grid is None:
        if camera is None:
            kind = "an unorganised .pcd" if path.suffix.lower() == ".pcd" else "a .ply"
            raise WbsaError(f"{path.name} is {kind} point cloud, without a pixel grid to recover its camera from; "
                            "give the camera that took it (--camera PRESET or an intrinsics JSON)")
        return project_points(cloud.points_m, camera), camera
    grid = cloud.points_m.reshape(*cloud.grid, 3)
    own = grid_intrinsics(grid, name=f"{path.name}'s grid")
    if camera is None:  # a preset the grid matches brings its sensor model and working range too
        from wbsa.camera.presets import PRESETS

        camera = next((k for k in PRESETS.values() if _same_camera(k, own)), None)
        own = camera or own
    elif not _same_camera(camera, own):
        raise WbsaError(f"{path.name}'s points lie on the grid of a {own.width}x{own.height} camera with "
                        f"fx {own.fx:.1f}, fy {own.fy:.1f}, centre ({own.cx:.1f}, {own.cy:.1f}) px, which the "
                        f"stated camera {camera.name} ({camera.width}x{camera.height}, fx {camera.fx:.1f}) does "
                        "not match; leave out --camera to use the cloud's own")
    else:
        own = camera
    z = grid[..., 2]
    return np.where(np.isfinite(z) & (z > 0), z, 0.0), own
