"""The truth-started drift of the body fit (``bench_body_fit.py --drift``): fits started at the true body, per
camera × distance band.

A fit started at the true shape, posture and placement shows how far the objective's minimum lies from the
truth under each camera's noise, apart from the start, the segmentation and the floor: the data term's and the
priors' pull alone.
"""

from __future__ import annotations

import numpy as np
import pandas as pd

#: Cameras and distance bands (m) of the truth-started drift benchmark: the benchmark's bands, each seen from its
#: middle or, where the camera's working range less the captures' 0.4 m margin ends inside the band, from that end
#: (a band the camera does not reach is skipped, as the held-out captures skip it).
DRIFT_CAMERAS = ("kinect-v1", "kinect-v2", "azure-kinect-nfov", "realsense-d435", "realsense-d455", "phone-lidar")
DRIFT_BANDS_M = ((1.5, 2.5), (2.5, 3.5), (3.5, 4.5))
#: Stream tag of the drift captures.
DRIFT_STREAM = 0xD1F7


def truth_start(params: np.ndarray, angles_deg: np.ndarray, posed: np.ndarray, world_to_camera):
    """``start(obs, fit_model)`` for :func:`wbsa.estimation.methods.body_fit.fit_body`: the true body, posture and placement.

    ``params (15,)`` and ``angles_deg (10,)`` are the body's; ``posed (n, 3)`` its posed vertices standing on z = 0
    (anny's frame), which ``world_to_camera`` (a :class:`wbsa.camera.extrinsics.Pose`) puts in the camera frame. The
    placement (a turn about the floor's normal and a shift) maps ``posed`` onto its place in the fit's view frame.
    """
    from wbsa.estimation.methods.body_fit.init import Starts

    def start(obs, fit_model):
        r = obs.basis @ world_to_camera.R  # anny's frame to the view frame; a turn about +Z on a true floor
        yaw = float(np.arctan2(r[1, 0], r[0, 0]))
        c, s = np.cos(yaw), np.sin(yaw)
        rz = np.array([[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]])
        in_view = (world_to_camera.apply(posed) - obs.origin) @ obs.basis.T
        shift = (in_view - posed @ rz.T).mean(0)
        return Starts(params=params[None].astype(np.float64), angles_rad=np.radians(angles_deg)[None],
                      yaw_rad=np.array([yaw]), shift_m=shift[None], score=np.zeros(1), label=("truth",))

    return start


def band_distance_m(camera, band: tuple[float, float]) -> float | None:
    """Where the drift benchmark sees a band from with ``camera`` (see :data:`DRIFT_BANDS_M`), or None."""
    distance = min(0.5 * (band[0] + band[1]), camera.max_range_m - 0.4)
    return distance if distance >= max(band[0], camera.min_range_m + 0.5) else None


def drift_chunk(population: pd.DataFrame, seed: int, draws: int, cameras: tuple[str, ...],
                bands: tuple[tuple[float, float], ...], fit_settings) -> pd.DataFrame:
    """Fits started at the true body: each subject (a random posture) in a room, seen by each camera at each
    distance (a random azimuth) with ``draws`` draws of its sensor's noise (the held-out captures' sensor of the
    camera, :func:`wbsa.training.capture.sensor_for`: axial and lateral noise, grazing dropout, the camera's
    disparity quantisation, the working range; no holes or dropped pixels); the subject's true pixels and floor.
    A capture that cuts the body off (:func:`wbsa.training.capture.fits_frame`) is skipped, as the held-out
    captures step back until the body fits.
    Returns one row per fit: the fitted body's WBSA error against the subject's."""
    from wbsa.bodies.body_model import BodyModel, body_parameter_array
    from wbsa.bodies.posture import POSTURES, draw_angles, settle_posture
    from wbsa.camera.extrinsics import pose_from_view
    from wbsa.camera.presets import camera_record
    from wbsa.camera.views import View
    from wbsa.estimation.methods.body_fit import fit_body
    from wbsa.estimation.subject.cloud import Plane
    from wbsa.sensor.technology import envelope_model
    from wbsa.training.capture import Capture, CaptureSettings, fits_frame, sensor_for
    from wbsa.training.room import capture_room, compose_room

    body_model = BodyModel()
    bodies = body_model.rest_bodies(population)
    params = body_parameter_array(population)
    names = tuple(POSTURES)
    rows = []
    for b in range(len(population)):
        t = population.iloc[b]
        rng = np.random.default_rng(np.random.SeedSequence([seed, b, DRIFT_STREAM]))
        name = names[int(rng.integers(len(names)))]
        angles, posed = settle_posture(bodies.vertices[b], bodies.bone_heads[b], draw_angles(name, rng), body_model.rig)
        subject = body_model.skin_mesh(posed)
        for camera_name in cameras:
            cam_index = DRIFT_CAMERAS.index(camera_name) if camera_name in DRIFT_CAMERAS else 99
            record = camera_record(camera_name)
            camera = record.intrinsics
            # the held-out captures' sensor of this camera (wbsa.training.capture.sensor_for), no holes
            sensor = sensor_for(record, np.random.default_rng(0), CaptureSettings(max_holes_fraction=0.0,
                                                                                 max_pixel_dropout=0.0))
            for band_index, band in enumerate(bands):
                distance = band_distance_m(camera, band)
                if distance is None:
                    continue
                for k in range(draws):  # each fit's own stream: the same captures whichever cameras are run
                    cell = [seed, b, DRIFT_STREAM, cam_index, band_index, k]
                    az = float(np.random.default_rng(np.random.SeedSequence(cell)).uniform(0.0, 360.0))
                    room = compose_room(subject, az, wall_behind_m=1.0)
                    centre = room.subject_center
                    el = float(np.degrees(np.arcsin(np.clip((1.2 - centre[2]) / distance, -0.95, 0.95))))
                    view = View(az, el, distance)
                    if not fits_frame(posed, camera, view, centre):  # cut off: the held-out captures step back
                        print(f"subject {b} {name}, {camera_name} {distance:g} m, draw {k}: cut off, skipped")
                        continue
                    cap = Capture(camera, view, sensor, 1.2, True)
                    frame, depth = capture_room(room, cap, seed=seed,
                                                subject_id=((b * 100 + cam_index) * 10 + band_index) * 100 + k)
                    mask = room.is_subject(frame.triangle_id) & (depth > 0)
                    pose = pose_from_view(view, centre)
                    normal = pose.R @ np.array([0.0, 0.0, 1.0])
                    floor = Plane(normal, float(normal @ pose.T))
                    fit = fit_body(depth, mask, camera, floor, settings=fit_settings, seed=b,
                                   start=truth_start(params[b], angles, posed, pose), sensor=envelope_model(camera))
                    rows.append(dict(subject=b, posture=name, camera=camera_name, band=f"{band[0]:g}-{band[1]:g} m",
                                     distance_m=distance, draw=k,
                                     azimuth_deg=az, wbsa_m2=float(t["wbsa_m2"]), fit_wbsa_m2=fit.wbsa_m2,
                                     error_pct=100 * (fit.wbsa_m2 / float(t["wbsa_m2"]) - 1), steps=fit.steps,
                                     seconds=fit.seconds))
                    print(f"subject {b} {name}, {camera_name} {distance:g} m, draw {k}: "
                          f"{rows[-1]['error_pct']:+.2f} %, {fit.steps} steps, {fit.seconds:.1f} s", flush=True)
    return pd.DataFrame(rows)


def report_drift(res: pd.DataFrame) -> None:
    """The drift per camera × distance band: mean, SD and n of the fitted body's WBSA error, against ±0.5 %."""
    keys = ["camera", "band", "distance_m"]
    g = res.groupby(keys)["error_pct"]
    table = pd.DataFrame({"n": g.size(), "mean_pct": g.mean(), "sd_pct": g.std(ddof=1),
                          "subjects": res.groupby(keys)["subject"].nunique()})
    table["within ±0.5 %"] = table["mean_pct"].abs() <= 0.5
    pd.set_option("display.width", 200)
    print("\ntruth-started drift (WBSA error of fits started at the true body, %):")
    print(table.round(2).to_string())
    print(f"all: n={len(res)}, mean {res['error_pct'].mean():+.2f} %, SD {res['error_pct'].std(ddof=1):.2f} %; "
          f"cells within ±0.5 %: {int(table['within ±0.5 %'].sum())} of {len(table)}")
