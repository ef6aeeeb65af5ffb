"""sensor stage: what a real depth camera does to an ideal ray-cast view.

Depth noise per camera technology (:mod:`wbsa.sensor.technology`: one table of constants, one formula for
numpy and torch; Nguyen et al. 2012 Kinect v1 noise the paper's), disparity quantisation, range limits and holes (the paper's
dropped triangles, random pixel dropout, grazing-angle dropout), all seeded and optional
(:class:`SensorSettings`, :func:`apply_sensor`); what a camera returns at depth edges, on depth images
(:func:`edge_pixels`: time-of-flight mixed pixels, or none); depth PNG I/O lives in
:mod:`wbsa.core.depth_image`.

Names are imported lazily, so ``from wbsa.sensor.cli import add_sensor_arguments`` stays cheap
for the CLI.
"""

from __future__ import annotations

from wbsa.lazy import lazy_exports

_EXPORTS = {
    "apply_sensor": "wbsa.sensor.apply",
    "edge_pixels": "wbsa.sensor.depth_edges",
    "NOISE_MODELS": "wbsa.typing",
    "SensorSettings": "wbsa.sensor.settings",
    "axial_sigma_m": "wbsa.sensor.nguyen2012",
    "lateral_sigma_m": "wbsa.sensor.nguyen2012",
    "lateral_sigma_px": "wbsa.sensor.nguyen2012",
    "TECHNOLOGIES": "wbsa.sensor.technology",
    "SensorModel": "wbsa.sensor.technology",
    "camera_model": "wbsa.sensor.technology",
    "envelope_m": "wbsa.sensor.technology",
    "add_sensor_arguments": "wbsa.sensor.cli",
    "sensor_settings_from_args": "wbsa.sensor.cli",
    "view_rng": "wbsa.sensor.measure",
    "sense_view": "wbsa.sensor.measure",
}
__all__ = sorted(_EXPORTS)
__getattr__, __dir__ = lazy_exports(__name__, _EXPORTS)
