"""Depth noise of every camera preset's technology model, measured on rendered planes.

Usage::

    python benchmarks/bench_sensor_noise.py [--distances 1 2 3 4] [--seed 0]

For each preset and distance within its working range, a plane facing the camera is rendered and read
through ``SensorSettings(noise="camera", lateral_noise=False)`` (axial noise only) and again with
``quantise=True``; the standard deviation of the depth error over the interior pixels is printed next to
the model's σz (:func:`wbsa.sensor.technology.axial_sigma_m`), the depth step of the camera's disparity
(z²·s/(f·b)) and the estimator's envelope (:func:`wbsa.sensor.technology.envelope_m`), in millimetres.
Seeded: the same arguments print the same table.
"""

from __future__ import annotations

import argparse

import numpy as np
from scipy import ndimage


def plane(camera, distance_m: float):
    """A 12 m square facing the camera at ``distance_m`` (fills the frame), rendered by the camera stage."""
    from wbsa.camera import MeshScene, Pose, render
    from wbsa.core.mesh import TriangleMesh

    verts = np.array([[-6.0, -6.0, distance_m], [6.0, -6.0, distance_m], [6.0, 6.0, distance_m],
                      [-6.0, 6.0, distance_m]])
    faces = np.array([[0, 1, 2], [0, 2, 3]], dtype=np.int32)
    return render(MeshScene(TriangleMesh(verts, faces)), camera, Pose(np.eye(3), np.zeros(3)))


def measure(name: str, distance_m: float, seed: int) -> dict:
    """One row: model and measured noise of preset ``name`` at ``distance_m`` (mm)."""
    from wbsa.camera.presets import camera_record
    from wbsa.sensor import SensorSettings, apply_sensor
    from wbsa.sensor.technology import axial_sigma_m, camera_model, envelope_m

    record = camera_record(name)
    model = camera_model(record)
    frame = plane(record.intrinsics, distance_m)
    inner = ndimage.binary_erosion(frame.valid, iterations=3, border_value=0)
    row = {"camera": name, "technology": record.technology, "z_m": distance_m,
           "model_sigma_mm": 1e3 * float(axial_sigma_m(model, distance_m, 0.0))}
    for label, quantise in (("noise", False), ("noise+quantised", True)):
        out = apply_sensor(frame, SensorSettings(noise="camera", lateral_noise=False, quantise=quantise),
                           np.random.default_rng(seed))
        both = inner & out.valid
        err = out.depth_m[both].astype(np.float64) - frame.depth_m[both]
        row[f"measured_{label}_mm"] = 1e3 * float(err.std())
    row["depth_step_mm"] = 1e3 * model.depth_step_per_m * distance_m**2
    row["envelope_mm"] = 1e3 * float(envelope_m(model, distance_m))
    row["stand_in"] = "yes" if model.noise.stand_in else ""
    return row


def main() -> None:
    import pandas as pd

    from wbsa.camera.presets import CAMERAS

    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--distances", type=float, nargs="+", default=[1.0, 2.0, 3.0, 4.0])
    p.add_argument("--seed", type=int, default=0)
    args = p.parse_args()
    rows = [measure(name, z, args.seed) for name, record in CAMERAS.items() for z in args.distances
            if record.working_range_m[0] <= z <= record.working_range_m[1]]
    table = pd.DataFrame(rows).round(1)
    print("| " + " | ".join(table.columns) + " |\n|" + "---|" * len(table.columns))
    for row in table.itertuples(index=False):
        print("| " + " | ".join(f"{v:g}" if isinstance(v, float) else str(v) for v in row) + " |")
    from wbsa.sensor.technology import TECHNOLOGIES

    print()
    for t in TECHNOLOGIES.values():
        print(f"- {t.technology}: {t.source}" + (f"; {t.stand_in}" if t.stand_in else ""))


if __name__ == "__main__":
    main()
