"""Virtual captures of posed bodies, measured by the estimator's own code: the training and test material.

:func:`render_samples` takes a population table (phenotypes and true WBSA), poses each body with a
:data:`~wbsa.bodies.posture.PoseBody` callable (swap in another posture model without touching
anything else), draws captures (:func:`~wbsa.training.capture.sample_capture`), renders each with
:func:`wbsa.simulate.simulate_view` (sensor on), by default standing in a room whose floor and subject are
then found by :func:`~wbsa.estimation.subject.segment.segment_subject` as in a real image, and measures the sensed
frame with :func:`~wbsa.estimation.subject.measure.measure_subject`. A share of the bodies is dressed in a layer of
clothes (:mod:`wbsa.bodies.clothing`) whose thickness the row records (``clothing_m``), as a user states it;
the truth stays the bare skin's WBSA. Sample ``i`` draws from its own
stream ``SeedSequence([seed, i])``: the same seed gives the same rows whatever the chunking or workers.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import pandas as pd

from wbsa.estimation.subject.cloud import Plane
from wbsa.sensor.technology import envelope_model
from wbsa.training.capture import as_scan_render, sample_capture
from wbsa.training.samples import Samples
from wbsa.training.settings import RenderSettings
from wbsa.training.store import RenderStore

#: Truth columns copied from the population table into every sample row.
TRUTH_COLUMNS = ("subject_id", "sex", "age_years", "stature_m", "mass_kg", "wbsa_m2")


def render_floor(pose, rng: np.random.Generator, error_m: float, tilt_deg: float, sensor=None) -> Plane:
    """The floor z = 0 of a render in its camera frame, with a small random error (as if detected), with the
    depth-noise envelope ``sensor`` (:func:`wbsa.sensor.technology.envelope_model` of the camera)."""
    n = pose.R @ np.array([0.0, 0.0, 1.0])
    d = float(n @ pose.T)
    tilt = rng.normal(0.0, np.radians(tilt_deg), size=3)
    n = n + np.cross(tilt, n)
    return Plane(n / np.linalg.norm(n), d + float(rng.normal(0.0, error_m)), sensor=sensor)


@dataclass(frozen=True)
class DrawnCapture:
    """One training capture as the estimator receives it, before it is measured.

    Attributes
    ----------
    row : dict
        The sample's table row so far: :data:`TRUTH_COLUMNS`, ``sample``, the capture's conditions (see
        :class:`~wbsa.training.samples.Samples`), ``alone`` in a room, and without a room the render's
        ``vbsa_visible_m2`` and ``vbsa_recon_grid_m2``.
    camera : wbsa.camera.Intrinsics
        The camera that took it.
    depth_m : (h, w) float64
        The sensed depth image, metres (0: no return), its mixed pixels repaired.
    mixed : (h, w) bool or None
        The returns :func:`~wbsa.estimation.subject.mixed_pixels.repair_mixed_pixels` found mixed.
    mask : (h, w) bool or None
        The subject's pixels as found (segmented in a room); None where no subject was found or the render had
        almost no returns.
    floor : Plane or None
        The floor found (in a room) or the render's floor with its drawn error (without one).
    """

    row: dict
    camera: object
    depth_m: np.ndarray
    mixed: np.ndarray | None
    mask: np.ndarray | None
    floor: Plane | None


def draw_captures(population: pd.DataFrame, first_sample: int, settings: RenderSettings, seed: int = 0,
                  posture_names: tuple[str, ...] | None = None):
    """Yield the :class:`DrawnCapture` of ``settings.views_per_subject`` captures of every body of ``population``.

    Sample numbers start at ``first_sample`` (its seeds are ``SeedSequence([seed, sample])``). Run under
    :func:`wbsa.parallel.single_threaded_math` as :func:`render_chunk` does: the captures are its, before
    they are measured.
    """
    from wbsa.bodies.body_model import BodyModel
    from wbsa.bodies.clothing import COVERED_BONES, dressed_vertices
    from wbsa.camera.extrinsics import pose_from_view
    from wbsa.camera.scene import MeshScene
    from wbsa.estimation.subject.mixed_pixels import repair_mixed_pixels
    from wbsa.training.room import with_edge_pixels
    from wbsa.bodies.posture import RandomPosture
    from wbsa.simulate import simulate_view

    model = BodyModel()
    poser = RandomPosture(model, settings.postures if posture_names is None else posture_names)
    bodies = model.rest_bodies(population)
    covered = model.vertices_of_bones(COVERED_BONES)
    sample = first_sample
    for b in range(len(population)):
        truth = population.iloc[b]
        for _ in range(settings.views_per_subject):
            rng = np.random.default_rng(np.random.SeedSequence([seed, sample]))
            # the sixth stream is the scan draw's, the seventh the clothes': spawning more leaves the first
            # ones as they were
            pose_rng, capture_rng, floor_rng, room_rng, edge_rng, scan_rng, clothes_rng = rng.spawn(7)
            vertices, posture = poser(bodies.vertices[b], bodies.bone_heads[b], pose_rng)
            clothing_m = 0.0
            if settings.clothed_share > 0 and clothes_rng.uniform() < settings.clothed_share:
                clothing_m = float(clothes_rng.uniform(*settings.clothing_m))
            cap = sample_capture(vertices, capture_rng, settings.capture)
            mesh = model.skin_mesh(dressed_vertices(vertices, model.skin_faces, covered, clothing_m))
            alone = settings.room and settings.alone_share > 0 and bool(room_rng.uniform() < settings.alone_share)
            if alone and settings.scan_share > 0 and scan_rng.uniform() < settings.scan_share:
                cap = as_scan_render(cap)
            row = {c: truth[c] for c in TRUTH_COLUMNS if c in truth.index}
            row.update(sample=sample, posture=posture, camera=cap.camera.name, azimuth_deg=cap.view.azimuth_deg,
                       elevation_deg=cap.view.elevation_deg, distance_m=cap.view.distance_m,
                       camera_height_m=cap.camera_height_m, fits=cap.fits,
                       holes_fraction=cap.sensor.holes_fraction, pixel_dropout=cap.sensor.pixel_dropout,
                       noise_scale=cap.sensor.effective_noise_scale,
                       ideal_sensor=cap.sensor.is_ideal,
                       edge_pixels=cap.edge_pixels, edge_share=cap.edge_share, clothing_m=clothing_m)
            if settings.room:
                row.update(alone=alone)
                depth, mixed, mask, floor = _room_capture(mesh, cap, alone, room_rng, edge_rng, settings, seed,
                                                          sample)
            else:
                scene = MeshScene(mesh, nthreads=1)
                sim = simulate_view(scene, cap.camera, cap.view, sensor=cap.sensor, seed=seed,
                                    subject_id=sample, reconstruct=("grid",), keep_frame=True)
                floor = render_floor(pose_from_view(cap.view, scene.center), floor_rng, settings.floor_error_m,
                                     settings.floor_tilt_deg, envelope_model(cap.camera))
                row.update(vbsa_visible_m2=sim.row["vbsa_visible_m2"],
                           vbsa_recon_grid_m2=sim.row["vbsa_recon_grid_m2"])
                depth, mixed = repair_mixed_pixels(
                    with_edge_pixels(sim.frame.depth_m, cap.edge_pixels, cap.edge_share, edge_rng), cap.camera.fx,
                    envelope_model(cap.camera))
                mask = depth > 0 if np.count_nonzero(depth) >= 200 else None
            yield DrawnCapture(row, cap.camera, depth, mixed, mask, floor)
            sample += 1


def render_chunk(population: pd.DataFrame, first_sample: int, settings: RenderSettings, seed: int = 0,
                 posture_names: tuple[str, ...] | None = None) -> Samples:
    """Render and measure ``settings.views_per_subject`` captures of every body of ``population``.

    Sample numbers start at ``first_sample`` (its seeds are ``SeedSequence([seed, sample])``); the captures are
    :func:`draw_captures`'.
    """
    from wbsa.estimation.subject.measure import measure_subject
    from wbsa.parallel import keep_large_allocations, single_threaded_math

    keep_large_allocations()
    rows, descriptors = [], []
    with single_threaded_math():
        for drawn in draw_captures(population, first_sample, settings, seed, posture_names):
            row = drawn.row
            if drawn.mask is None:
                row.update(m_ok=False)
                rows.append(row)
                descriptors.append(None)
                continue
            m = measure_subject(drawn.depth_m, drawn.mask, drawn.camera, drawn.floor, drawn.mixed)
            row.update({f"m_{k}": v for k, v in m.features().items()})
            row.update(m_ok=True, m_touches_border=m.touches_border)
            rows.append(row)
            descriptors.append(np.concatenate([m.descriptor, m.shape]))
    width = next((len(d) for d in descriptors if d is not None), 0)
    desc = np.stack([d if d is not None else np.full(width, np.nan, np.float32) for d in descriptors]) \
        if descriptors else np.zeros((0, width), np.float32)
    return Samples(pd.DataFrame(rows), desc)


def _room_capture(mesh, cap, alone: bool, rng: np.random.Generator, edge_rng: np.random.Generator,
                  settings: RenderSettings, seed: int, sample: int):
    """(depth (h, w) float64 in whole millimetres, mixed returns, subject mask or None, detected floor) of
    ``mesh`` in a room, or ``alone`` (no floor, no wall)."""
    from wbsa.errors import WbsaError
    from wbsa.estimation.subject.mixed_pixels import repair_mixed_pixels
    from wbsa.training.room import capture_room, compose_room, with_edge_pixels
    from wbsa.estimation.subject.segment import SegmentSettings, segment_subject

    if alone:
        room = compose_room(mesh, cap.view.azimuth_deg, wall_behind_m=None, floor=False)
    else:
        room = compose_room(mesh, cap.view.azimuth_deg, wall_behind_m=float(rng.uniform(*settings.wall_behind_m)))
    _, depth = capture_room(room, cap, seed=seed, subject_id=sample)
    sensor = envelope_model(cap.camera)
    depth, mixed = repair_mixed_pixels(with_edge_pixels(depth, cap.edge_pixels, cap.edge_share, edge_rng),
                                        cap.camera.fx, sensor)
    try:
        seg = segment_subject(depth, cap.camera, SegmentSettings(pick="center"), sensor=sensor)
    except WbsaError:
        return depth, mixed, None, None
    if np.count_nonzero(seg.mask) < 200:
        return depth, mixed, None, None
    return depth, mixed, seg.mask, seg.floor


def render_samples(population: pd.DataFrame, settings: RenderSettings = RenderSettings(), seed: int = 0, *,
                   workers: int = 1, chunk_subjects: int = 25, store: RenderStore | None = None,
                   show_progress: bool | None = None, log_lines: bool = False) -> Samples:
    """Render and measure captures of every body of a population table (see the module doc).

    Parameters
    ----------
    population : pandas.DataFrame
        Phenotype columns and the truth (:data:`TRUTH_COLUMNS`), e.g. from
        :func:`wbsa.bodies.table.measure_population`.
    settings : RenderSettings
    seed : int
        Sample ``i`` draws from ``SeedSequence([seed, i])``.
    workers : int
        Local worker processes (dask); the rows do not depend on it.
    chunk_subjects : int
        Bodies per task.
    store : RenderStore, optional
        Where finished chunks are kept: chunks found there are read instead of rendered (a run killed
        half-way resumes), new ones are written as they finish.

    Returns
    -------
    Samples
        Rows in sample order.
    """
    from wbsa.parallel import map_chunks
    from wbsa.progress import progress

    v = settings.views_per_subject
    starts = list(range(0, len(population), chunk_subjects))
    done = {s: store.read(s * v) for s in starts} if store is not None else {}
    done = {s: part for s, part in done.items() if part is not None}
    todo = [s for s in starts if s not in done]
    args = [(population.iloc[s:s + chunk_subjects].reset_index(drop=True), s * v, settings, seed) for s in todo]
    bar = progress(total=len(population) * v, desc="renders", unit="view", enabled=show_progress, log_lines=log_lines)
    bar.update(sum(len(p) for p in done.values()))

    def finished(part: Samples) -> None:
        if store is not None:
            store.write(part)
        bar.update(len(part))

    try:
        parts = map_chunks(render_chunk, args, workers=workers, tag="estimator-renders", on_result=finished)
    finally:
        bar.close()
    by_start = {**done, **dict(zip(todo, parts))}
    return Samples.concat([by_start[s] for s in starts])
