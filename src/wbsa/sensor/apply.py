"""Turn an ideal ray-cast frame into what a depth sensor would return."""

from __future__ import annotations

import dataclasses

import numpy as np
from scipy import ndimage

from wbsa.core.frame import DepthFrame
from wbsa.errors import WbsaError
from wbsa.sensor import technology
from wbsa.sensor.settings import SensorSettings
from wbsa.core.backproject import ray_directions

#: Background pixels within this many pixels of a return may pick it up through lateral noise.
_LATERAL_REACH_PX = 2
#: Lateral resampling interpolates depth bilinearly only between pixels closer than this relative depth.
_SAME_SURFACE_RATIO = 0.05


def apply_sensor(frame: DepthFrame, sensor: SensorSettings, rng: np.random.Generator) -> DepthFrame:
    """Simulate a depth sensor on an ideal frame.

    The effects of ``sensor`` are applied in this order, each drawing from its own child stream of
    ``rng`` (so enabling one effect does not change the others' draws):

    1. holes: drop ``holes_fraction`` of the visible triangles (exactly ``round(f · n_visible)`` of
       them, chosen without replacement) and every pixel that hit them (the paper, section 2.4);
    2. grazing dropout: drop returns with angle θ between normal and ray above 90° − ``grazing_dropout_deg``
       (None: the noise model's);
    3. lateral noise (the noise model's, :meth:`SensorSettings.model_for`: ``nguyen2012`` or the camera's
       technology, :mod:`wbsa.sensor.technology`): each pixel samples the surface at a position moved by
       N(0, ``noise_scale`` · σL(θ)) pixels along each image axis (bilinear depth on one surface, nearest pixel across
       depth jumps and at the silhouette, which therefore both grows and shrinks);
    4. axial noise (the noise model's): z += N(0, ``noise_scale`` · σz(z, θ));
    5. disparity quantisation: z = f·b / (round(f·b / (z·q)) · q) with q = ``disparity_step_px`` (the camera
       preset's b and q with noise ``camera``; none for a camera without a disparity);
    6. range limits: drop z outside the camera's ``[min_range_m, max_range_m]``;
    7. pixel dropout: drop each remaining return with probability ``pixel_dropout``.

    Points are then back-projected from the new depth along each pixel's own ray, as a real sensor's
    depth image would give them; normals and triangle IDs are those of the surface point sampled.

    Parameters
    ----------
    frame : DepthFrame
        An ideal frame (from :func:`wbsa.camera.render`, or :func:`wbsa.core.frame_from_depth_image`
        for effects that need no triangle IDs).
    sensor : SensorSettings
    rng : numpy.random.Generator
        Source of randomness; same generator state and settings give the same frame.

    Returns
    -------
    DepthFrame
        Same contract as the input; lost pixels have depth 0, triangle_id -1 and NaN points/normals.
        ``settings["sensor"]`` records ``sensor.to_dict()``.

    Raises
    ------
    WbsaError
        If triangle holes are asked for on a frame without triangle IDs, or noise ``camera`` without a
        technology on a camera that is no preset.
    """
    settings = {**frame.settings, "sensor": sensor.to_dict()}
    model, disparity = sensor.model_for(frame.intrinsics)
    holes_stream, lateral_stream, axial_stream, dropout_stream = rng.spawn(4)
    if sensor.is_ideal:
        return dataclasses.replace(frame, settings=settings)

    h, w = frame.depth_m.shape
    valid_full = frame.depth_m > 0
    if not valid_full.any():
        return dataclasses.replace(frame, settings=settings)
    rows = np.flatnonzero(valid_full.any(axis=1))
    cols = np.flatnonzero(valid_full.any(axis=0))
    pad = _LATERAL_REACH_PX + 2
    r0, r1 = max(rows[0] - pad, 0), min(rows[-1] + pad + 1, h)
    c0, c1 = max(cols[0] - pad, 0), min(cols[-1] + pad + 1, w)
    crop = (slice(r0, r1), slice(c0, c1))

    depth = frame.depth_m[crop].astype(np.float64)
    valid = depth > 0
    tri = np.where(valid, frame.triangle_id[crop], -1).astype(np.int64)
    normals = np.asarray(frame.normals_cam[crop], dtype=np.float64)
    rays = ray_directions(frame.intrinsics, np.arange(r0, r1)[:, None], np.arange(c0, c1)[None, :])
    rays /= np.linalg.norm(rays, axis=-1, keepdims=True)
    depth_changed = False

    # 1. the paper's holes: drop a random subset of the visible triangles
    if sensor.holes_fraction > 0:
        visible = np.unique(tri[valid])
        visible = visible[visible >= 0]
        if visible.size == 0:
            raise WbsaError("triangle holes need a rendered frame with triangle IDs; "
                            "use pixel_dropout (--pixel-dropout) for depth images")
        n_drop = int(round(sensor.holes_fraction * visible.size))
        dropped = holes_stream.choice(visible, size=n_drop, replace=False)
        valid &= ~np.isin(tri, dropped)

    # 2. grazing-angle dropout
    theta = _incidence_rad(normals, rays, valid)
    grazing_deg = sensor.effective_grazing_dropout_deg
    if grazing_deg is None:
        grazing_deg = model.noise.grazing_dropout_deg
    if grazing_deg > 0:
        valid &= theta <= np.deg2rad(90.0 - grazing_deg)

    if model is not None:
        # 3. lateral noise: resample the image at jittered positions
        if sensor.lateral_noise and min(depth.shape) >= 2:
            sigma_px = np.where(valid, sensor.noise_scale * technology.lateral_sigma_px(model, np.where(valid, theta, 0.0)),
                                0.0)
            reach = 2 * _LATERAL_REACH_PX + 1
            sigma_px = np.where(valid, sigma_px, ndimage.grey_dilation(sigma_px, size=(reach, reach)))
            dv = lateral_stream.standard_normal(depth.shape) * sigma_px
            du = lateral_stream.standard_normal(depth.shape) * sigma_px
            depth, valid, normals, tri = _resample(depth, valid, normals, tri, dv, du)
            theta = _incidence_rad(normals, rays, valid)
        # 4. axial noise
        sigma_z = sensor.noise_scale * technology.axial_sigma_m(model, np.where(valid, depth, 1.0),
                                                                np.where(valid, theta, 0.0))
        depth = depth + axial_stream.standard_normal(depth.shape) * np.where(valid, sigma_z, 0.0)
        valid &= depth > 0
        depth_changed = True

    # 5. disparity quantisation
    if sensor.quantise and disparity is not None:
        baseline_m, q = disparity
        fb = float(frame.intrinsics.fx) * baseline_m
        with np.errstate(divide="ignore", invalid="ignore"):
            disparity = np.round(fb / np.where(valid, depth, np.inf) / q) * q
            depth = np.where(disparity > 0, fb / disparity, 0.0)
        valid &= depth > 0
        depth_changed = True

    # 6. range limits of the camera
    if sensor.range_limits:
        lo = float(getattr(frame.intrinsics, "min_range_m", 0.0))
        hi = float(getattr(frame.intrinsics, "max_range_m", np.inf))
        valid &= (depth >= lo) & (depth <= hi)

    # 7. random pixel dropout
    if sensor.pixel_dropout > 0:
        valid &= dropout_stream.random(depth.shape) >= sensor.pixel_dropout

    out_depth = np.zeros((h, w), dtype=np.float32)
    out_depth[crop] = np.where(valid, depth, 0.0)
    out_tri = np.full((h, w), -1, dtype=np.int64)
    out_tri[crop] = np.where(valid, tri, -1)
    out_normals = np.full((h, w, 3), np.nan, dtype=np.float32)
    out_normals[crop] = np.where(valid[..., None], normals, np.nan)
    out_points = np.full((h, w, 3), np.nan, dtype=np.float32)
    if depth_changed:
        out_points[crop] = np.where(valid[..., None], rays / rays[..., 2:3] * depth[..., None], np.nan)
    else:
        out_points[crop] = np.where(valid[..., None], frame.points_cam[crop], np.nan)
    return DepthFrame(depth_m=out_depth, points_cam=out_points, normals_cam=out_normals, triangle_id=out_tri,
                      intrinsics=frame.intrinsics, pose=frame.pose, settings=settings)


def _incidence_rad(normals: np.ndarray, rays_unit: np.ndarray, valid: np.ndarray) -> np.ndarray:
    """(h, w) angle θ between surface normal and viewing ray (radians); π/2 where invalid."""
    cos = np.abs(np.einsum("...k,...k->...", np.where(valid[..., None], normals, 0.0), rays_unit))
    return np.where(valid, np.arccos(np.clip(cos, 0.0, 1.0)), np.pi / 2)


def _resample(depth, valid, normals, tri, dv, du):
    """Sample the image at (i + dv, j + du): validity, normal and triangle from the nearest pixel,
    depth bilinear when the four surrounding pixels are returns on one surface, nearest otherwise."""
    h, w = depth.shape
    ii, jj = np.meshgrid(np.arange(h), np.arange(w), indexing="ij")
    y = np.clip(ii + dv, 0, h - 1)
    x = np.clip(jj + du, 0, w - 1)
    ni = np.rint(y).astype(np.intp)
    nj = np.rint(x).astype(np.intp)
    i0 = np.minimum(np.floor(y).astype(np.intp), h - 2)
    j0 = np.minimum(np.floor(x).astype(np.intp), w - 2)
    fy, fx = y - i0, x - j0
    z00, z01 = depth[i0, j0], depth[i0, j0 + 1]
    z10, z11 = depth[i0 + 1, j0], depth[i0 + 1, j0 + 1]
    corners = np.stack([z00, z01, z10, z11])
    all_valid = valid[i0, j0] & valid[i0, j0 + 1] & valid[i0 + 1, j0] & valid[i0 + 1, j0 + 1]
    same = all_valid & (corners.max(0) - corners.min(0) <= _SAME_SURFACE_RATIO * corners.min(0))
    bilinear = (z00 * (1 - fy) * (1 - fx) + z01 * (1 - fy) * fx + z10 * fy * (1 - fx) + z11 * fy * fx)
    new_valid = valid[ni, nj]
    new_depth = np.where(same, bilinear, depth[ni, nj])
    return new_depth, new_valid, normals[ni, nj], tri[ni, nj]
