"""Read one view through the simulated sensor and measure what it returns (shared by view and scan)."""

from __future__ import annotations

import numpy as np

from wbsa.core.frame import DepthFrame
from wbsa.core.limits import check_seed


def view_rng(seed: int, subject_id: int, view) -> np.random.Generator:
    """The sensor's random stream for one subject at one view.

    The child of ``SeedSequence([seed, subject_id])`` keyed by the view's azimuth, elevation
    (micro-degrees) and distance (micrometres): it depends only on (seed, subject, view), never on
    chunking, on the workers or on which other views are scanned, so ``wbsa view`` and ``wbsa scan``
    give the same noisy image.

    Parameters
    ----------
    seed : int
        The sensor seed (non-negative; checked by :func:`wbsa.core.limits.check_seed`).
    subject_id : int
        The subject's id.
    view : wbsa.camera.View
        The view; its ``azimuth_deg``, ``elevation_deg`` and ``distance_m`` key the stream.

    Returns
    -------
    numpy.random.Generator
    """
    key = (round(view.azimuth_deg * 1e6), round((view.elevation_deg + 90.0) * 1e6), round(view.distance_m * 1e6))
    check_seed(seed, "the sensor seed")
    return np.random.default_rng(np.random.SeedSequence([int(seed), int(subject_id)], spawn_key=key))


def sense_view(frame: DepthFrame, scene, sensor, rng: np.random.Generator) -> tuple[DepthFrame, dict]:
    """The frame a simulated sensor returns, and the visible-area columns measured on it.

    The hit area counts only triangles that still return; the visible area is the per-pixel estimate
    of the returns, without the mesh, so returns the sensor dropped are not counted back.

    Parameters
    ----------
    frame : DepthFrame
        The ideal frame of the view (with triangle ids).
    scene : MeshScene
        The scene the frame was rendered from (for the triangle areas).
    sensor : SensorSettings
        The sensor's effects (:func:`wbsa.sensor.apply.apply_sensor`).
    rng : numpy.random.Generator
        The view's stream (:func:`view_rng`).

    Returns
    -------
    DepthFrame, dict
        The sensed frame and ``{"n_pixels_sensor", "vbsa_hit_sensor_m2", "vbsa_visible_sensor_m2",
        "sensor_<setting>"...}``.
    """
    from wbsa.camera.area import vbsa_hit_m2, vbsa_visible_m2
    from wbsa.sensor.apply import apply_sensor

    sensed = apply_sensor(frame, sensor, rng)
    row = {"n_pixels_sensor": sensed.n_pixels, "vbsa_hit_sensor_m2": vbsa_hit_m2(sensed, scene),
           "vbsa_visible_sensor_m2": vbsa_visible_m2(sensed)}
    row.update({f"sensor_{k}": v for k, v in sensor.to_dict().items()})
    return sensed, row
