"""Held-out room captures for judging the estimator (``benchmarks/bench_estimate.py``).

Each subject is posed, stood in a room (floor, a wall 0.5–1.5 m behind, sometimes a second person at the
side), captured with a random camera, distance, camera height and azimuth, read through the sensor, stored
as a millimetre depth image would be, and handed to :func:`wbsa.estimation.estimate` without its view.
The row records the truth, the estimate, its flags and the segmentation against the render's own labels.
Image ``i`` draws from ``SeedSequence([seed, i])``: rows do not depend on chunking or workers.
"""

from __future__ import annotations

import time
from dataclasses import dataclass, field, replace

import numpy as np
import pandas as pd

from wbsa.training.capture import CaptureSettings, sample_capture
from wbsa.estimation.limits import MAX_CLOTHING_M
from wbsa.errors import WbsaError
from wbsa.typing import EdgePixels, TestRenderer, TestScene
from wbsa.settings_io import check_types

#: Stream tag of the plain renderer's noise (independent of the capture's streams).
PLAIN_NOISE_STREAM = 0x91A1
#: The plain renderer's fixed set-up (the second check): a Kinect v2 2.5 m from the subject's centre, 1.0 m
#: over the floor, looking level, a wall 0.8 m behind the subject, seen from the front and from 30°.
FIXED_SETUP = {"camera": "kinect-v2", "distance_m": 2.5, "height_m": 1.0, "wall_behind_m": 0.8,
               "azimuths_deg": (0.0, 30.0)}


@dataclass(frozen=True)
class RoomTestSettings:
    """Conditions of the held-out captures.

    Attributes
    ----------
    capture : CaptureSettings
        Its ``edge_pixels`` draw is not used: ``edge_pixels`` below applies to every image. The default is
        the benchmark's default: noise at Kinect v1's level (``noise_scale`` 1), no ideal captures. Both are
        drawn last, so ``noise_scale=(f, f)`` or ``ideal_share=1`` give the same captures at another noise
        level or with no sensor effects.
    wall_behind_m : (float, float)
        Gap between the subject and the wall behind, uniform.
    second_person : float
        Probability of a second person beside the subject.
    side_m : (float, float)
        Sideways offset of the second person (centre to centre), uniform, either side.
    pick : str
        How the estimator chooses among several people (the operator aims the camera at the subject).
    edge_pixels : {'kept', 'mixed', 'dropped'}
        What the camera returns for a pixel straddling a depth edge (:func:`wbsa.sensor.depth_edges.edge_pixels`):
        the render's depth (the benchmark's default), a time-of-flight mix of the two surfaces, or nothing.
    edge_share : float
        Share of the depth edges so affected.
    scene : {'room', 'alone'}
        ``alone``: the same captures of the subject with no floor, wall or second person, as a render of a
        3-D body scan would be.
    clothing_m : float
        A layer of everyday clothes 0–0.05 m thick over the subject's trunk, upper arms, legs and feet
        (:mod:`wbsa.bodies.clothing`; the shoe soles flattened onto the floor); the truth stays the bare
        skin's WBSA. The capture (camera, distance, view) is drawn from the bare body and aims at its centre;
        the room is placed around the clothed body (the wall's gap from its back, the second person, who stays
        bare, beside its centre), a few millimetres from where it stands around the bare one.
    clothing_stated : bool
        The estimator is told the layer, as a user states it (``clothing_m`` of :func:`~wbsa.estimation.estimate`);
        False: it is told nothing (taken as none and flagged ``clothes_unstated``), what a layer nobody states reads.
    renderer : {'project', 'plain', 'both'}
        Who draws each capture: the project's renderer, the plain one (:mod:`wbsa.testing.plain_render`:
        the same scene, camera and position, Open3D's ray casting and its own noise), or both (two rows per
        capture, the column ``renderer`` telling them apart).
    fixed_setup : bool
        Also draw each posed subject with the plain renderer in :data:`FIXED_SETUP` (rows ``plain-fixed-0``
        and ``plain-fixed-30``: the subject alone before its wall, no second person, no clothes).
    seed : int
    """

    capture: CaptureSettings = field(default_factory=lambda: CaptureSettings(
        edge_pixels=("kept",), noise_scale=(1.0, 1.0), grazing_dropout_scale=(1.0, 1.0), ideal_share=0.0))
    wall_behind_m: tuple[float, float] = (0.5, 1.5)
    second_person: float = 0.3
    side_m: tuple[float, float] = (0.9, 1.6)
    pick: str = "center"
    edge_pixels: EdgePixels = "kept"
    edge_share: float = 1.0
    scene: TestScene = "room"
    clothing_m: float = 0.0
    clothing_stated: bool = True
    renderer: TestRenderer = "project"
    fixed_setup: bool = False
    seed: int = 1000

    def __post_init__(self) -> None:
        check_types(self)
        if not 0.0 <= self.edge_share <= 1.0:
            raise WbsaError(f"edge_share {self.edge_share} must be a share of the depth edges in [0, 1]")
        if not 0.0 <= self.clothing_m <= MAX_CLOTHING_M:
            raise WbsaError(f"clothing_m {self.clothing_m} must be a layer of 0–{MAX_CLOTHING_M:g} m (0.01 for 1 cm "
                            "of clothes)")


#: Pixels this close (in the image) to the subject's make up the contact strip with the floor ...
CONTACT_REACH_PX = 3


def held_out_population(n: int, survey_share: float, seed: int) -> pd.DataFrame:
    """Held-out subjects: random (ages 3–80) and survey-matched (a ``survey_share`` of ``n``), excluding the
    survey people the default model was trained on; one row per subject with its truth (``wbsa_m2``, ...)."""
    import warnings

    from wbsa.bodies.random_population import RandomPopulationSettings, sample_random_parameters
    from wbsa.bodies.survey import build_survey_population
    from wbsa.bodies.survey_data import load_survey, select_people
    from wbsa.bodies.table import measure_population
    from wbsa.training.pipeline import TrainSettings

    n_survey = int(round(n * survey_share))
    params = sample_random_parameters(RandomPopulationSettings(n=n - n_survey, seed=seed, age_years=(3, 80),
                                                               age_sampling="years", weight=(0.0, 1.0)))
    parts = [measure_population(params, show_progress=False).assign(population="random")]
    if n_survey:
        train = TrainSettings()
        trained_ids = set(select_people(load_survey(None).people, train.n_survey, train.seed + 1)["survey_id"])
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            survey = build_survey_population(n_survey + 10, seed=seed + 1, show_progress=False)
        survey = survey[~survey["survey_id"].isin(trained_ids)].head(n_survey)
        parts.append(survey.assign(population="survey"))
    pop = pd.concat(parts, ignore_index=True)
    pop["subject_id"] = np.arange(len(pop))
    return pop


def contact_strip(truth: np.ndarray, surface_height_m: np.ndarray) -> np.ndarray:
    """(h, w) bool: the feet's contact strip, pixels no depth image tells between the subject and the floor.

    The pixels that see a surface lower than :data:`~wbsa.estimation.subject.cloud.FLOOR_CUT_M` over the floor (the
    subject's soles and toes, the floor) within :data:`CONTACT_REACH_PX` of such a pixel of the subject.
    The measures cut the subject's share of it only when a floor is found (by the segmentation, at run
    time and in the training renders in rooms): :func:`~wbsa.estimation.subject.measure.measure_subject` then
    drops the subject's returns within the floor's noise envelope (at least ``FLOOR_CUT_M`` over it,
    :func:`~wbsa.estimation.subject.cloud.above_floor`) and sparse low pixels beside them, reading heights from the
    measured depth over the found floor, not from the true surface, so the cut matches this strip only up
    to the depth noise and the floor's error. With no floor found (flag ``no_floor``; a body alone)
    nothing is cut and the soles are measured with the body. Segmentation benchmarks leave such a band out
    as "void" (the object boundaries of PASCAL VOC); the benchmark's figures count it, and both are reported.

    Parameters
    ----------
    truth : (h, w) bool
        The subject's pixels.
    surface_height_m : (h, w) float64
        Height over the floor of the surface each pixel sees, NaN where none (:meth:`RoomScene.surface_height_m`).

    Returns
    -------
    (h, w) bool
        The strip: subject and floor pixels alike.
    """
    from scipy import ndimage

    from wbsa.estimation.subject.cloud import FLOOR_CUT_M

    low = np.nan_to_num(surface_height_m, nan=np.inf) < FLOOR_CUT_M
    return low & ndimage.binary_dilation(truth & low, iterations=CONTACT_REACH_PX)


@dataclass(frozen=True)
class HeldOutCapture:
    """One held-out capture: the subject posed in its room, seen by its camera.

    Attributes
    ----------
    index : int
        The image's number (its seeds are ``SeedSequence([seed, index])``).
    posture : str
    capture : wbsa.training.capture.Capture
    room : wbsa.training.room.RoomScene
    frame : wbsa.core.DepthFrame
        The render (triangle ids for the truth).
    depth_m : (h, w) float64
        What the camera returns (metres, whole millimetres; depth edges as the settings say).
    truth : (h, w) bool
        The subject's pixels in the render.
    second_person : bool
    vertices : (n, 3) float64
        The posed body (before any clothes).
    """

    index: int
    posture: str
    capture: object
    room: object
    frame: object
    depth_m: np.ndarray
    truth: np.ndarray
    second_person: bool
    vertices: np.ndarray


def room_test_captures(population: pd.DataFrame, others: pd.DataFrame, first: int, settings: RoomTestSettings,
                       body_model, reshape=None):
    """Yield the :class:`HeldOutCapture` of every subject of ``population`` (``others``: the possible second people).

    ``reshape(vertices, index)``, if given, changes each posed body before it is captured (e.g. seeded bumps
    outside the body model's shapes); everything drawn is unchanged by it. One generator serves every
    benchmark, so their captures are the same images.
    """
    from wbsa.bodies.clothing import COVERED_BONES, dressed_vertices
    from wbsa.bodies.posture import RandomPosture
    from wbsa.training.room import capture_room, compose_room, with_edge_pixels

    poser = RandomPosture(body_model)
    covered = body_model.vertices_of_bones(COVERED_BONES)
    bodies = body_model.rest_bodies(population)
    extra = body_model.rest_bodies(others)
    for b in range(len(population)):
        index = first + b
        rng = np.random.default_rng(np.random.SeedSequence([settings.seed, index]))
        pose_rng, other_rng, capture_rng, room_rng, edge_rng = rng.spawn(5)
        vertices, posture = poser(bodies.vertices[b], bodies.bone_heads[b], pose_rng)
        if reshape is not None:
            vertices = reshape(vertices, index)
        cap = sample_capture(vertices, capture_rng, settings.capture)
        subject = body_model.skin_mesh(vertices)
        bare_center = subject.bbox_center
        if settings.clothing_m > 0.0:
            subject = body_model.skin_mesh(dressed_vertices(vertices, body_model.skin_faces, covered,
                                                            settings.clothing_m))
        people = ()
        if room_rng.random() < settings.second_person:
            v2, _ = poser(extra.vertices[b], extra.bone_heads[b], other_rng)
            side = room_rng.uniform(*settings.side_m) * room_rng.choice([-1.0, 1.0])
            people = ((body_model.skin_mesh(v2), float(side)),)
        wall_m = float(room_rng.uniform(*settings.wall_behind_m))
        if settings.scene == "alone":
            room = compose_room(subject, cap.view.azimuth_deg, wall_behind_m=None, floor=False)
            people = ()
        else:
            room = compose_room(subject, cap.view.azimuth_deg, wall_behind_m=wall_m, others=people)
        if settings.clothing_m > 0.0:  # the camera aims where it aimed at the bare body
            room = replace(room, subject_center=bare_center)
        frame, depth = capture_room(room, cap, seed=settings.seed, subject_id=index)
        truth = room.is_subject(frame.triangle_id) & (depth > 0)
        depth = with_edge_pixels(depth, settings.edge_pixels, settings.edge_share, edge_rng)
        yield HeldOutCapture(index, posture, cap, room, frame, depth, truth, bool(people), vertices)


def plain_capture(tc: HeldOutCapture, seed: int) -> tuple[np.ndarray, np.ndarray]:
    """The same capture drawn by the plain renderer (:mod:`wbsa.testing.plain_render`).

    The same room (subject, other people, floor, wall), intrinsics and camera centre and rotation as the
    project's render of ``tc``; the noise its own, from ``SeedSequence([seed, tc.index, PLAIN_NOISE_STREAM])``,
    or none for an ideal capture.

    Parameters
    ----------
    tc : HeldOutCapture
    seed : int
        The test set's seed.

    Returns
    -------
    depth_m : (h, w) float64
        Whole millimetres, 0 where nothing is seen.
    triangle_id : (h, w) int64
        The triangle of the room's mesh each pixel sees, −1 where none.
    """
    from wbsa.camera.extrinsics import pose_from_view
    from wbsa.testing.plain_render import plain_depth

    cam = tc.capture.camera
    pose = pose_from_view(tc.capture.view, tc.room.subject_center)
    rng = None if tc.capture.sensor.is_ideal else np.random.default_rng(
        np.random.SeedSequence([seed, tc.index, PLAIN_NOISE_STREAM]))
    depth, tri = plain_depth(tc.room.mesh.vertices, tc.room.mesh.faces, width=cam.width, height=cam.height,
                             fx=cam.fx, fy=cam.fy, cx=cam.cx, cy=cam.cy, rotation=pose.R,
                             center_m=pose.camera_center, rng=rng)
    return depth, tri


def fixed_setup_capture(tc: HeldOutCapture, body_model, azimuth_deg: float, seed: int):
    """The posed subject of ``tc`` drawn by the plain renderer in :data:`FIXED_SETUP` from ``azimuth_deg``.

    Returns
    -------
    camera : wbsa.camera.Intrinsics
    depth_m : (h, w) float64
    triangle_id : (h, w) int64
    room : wbsa.training.room.RoomScene
    """
    from wbsa.camera.presets import preset
    from wbsa.testing.plain_render import level_camera
    from wbsa.testing.plain_render import plain_depth
    from wbsa.training.room import compose_room

    cam = preset(FIXED_SETUP["camera"])
    room = compose_room(body_model.skin_mesh(tc.vertices), azimuth_deg, wall_behind_m=FIXED_SETUP["wall_behind_m"])
    th = np.radians(azimuth_deg)
    rotation, center = level_camera(room.subject_center, np.array([np.sin(th), -np.cos(th), 0.0]),
                                    FIXED_SETUP["distance_m"], FIXED_SETUP["height_m"])
    rng = np.random.default_rng(np.random.SeedSequence([seed, tc.index, PLAIN_NOISE_STREAM, int(azimuth_deg)]))
    depth, tri = plain_depth(room.mesh.vertices, room.mesh.faces, width=cam.width, height=cam.height, fx=cam.fx,
                             fy=cam.fy, cx=cam.cx, cy=cam.cy, rotation=rotation, center_m=center, rng=rng)
    return cam, depth, tri, room


def rendered(tc: HeldOutCapture, settings: RoomTestSettings, body_model=None):
    """Yield ``(renderer, camera, depth_m, truth, triangle_id, room, azimuth_deg)`` of one capture for every
    renderer ``settings.renderer`` names (and the fixed set-up's): its camera, depth (whole millimetres), the
    subject's pixels, the triangle each pixel sees, the scene and the camera's azimuth."""
    cam, az = tc.capture.camera, tc.capture.view.azimuth_deg
    if settings.renderer in ("project", "both"):
        yield "project", cam, tc.depth_m, tc.truth, tc.frame.triangle_id, tc.room, az
    if settings.renderer in ("plain", "both"):
        depth, tri = plain_capture(tc, settings.seed)
        yield "plain", cam, depth, tc.room.is_subject(tri) & (depth > 0), tri, tc.room, az
    if settings.fixed_setup:
        for azimuth in FIXED_SETUP["azimuths_deg"]:
            fcam, depth, tri, room = fixed_setup_capture(tc, body_model, azimuth, settings.seed)
            yield f"plain-fixed-{azimuth:g}", fcam, depth, room.is_subject(tri) & (depth > 0), tri, room, azimuth


def room_capture_chunk(population: pd.DataFrame, others: pd.DataFrame, first: int, settings: RoomTestSettings,
                       model_path: str | None) -> pd.DataFrame:
    """Capture and estimate every subject of ``population`` (``others``: the same number of possible second people).

    Returns one row per subject and renderer (``settings.renderer``): truth, capture, segmentation (``seg_kept``, ``seg_included``; and the same
    outside the feet's contact strip, ``seg_kept_off_strip``, ``seg_included_off_strip``: see
    :func:`contact_strip`), the estimate (``est_*``, ``flags``; ``error`` when it raised) and the estimate's
    wall time.
    """
    from wbsa.bodies.body_model import BodyModel
    from wbsa.estimation.methods.regression.default_model import load_model
    from wbsa.parallel import keep_large_allocations, single_threaded_math

    keep_large_allocations()
    rows = []
    with single_threaded_math():
        body_model = BodyModel()
        model = load_model(model_path)
        for tc in room_test_captures(population, others, first, settings, body_model):
            for drawn in rendered(tc, settings, body_model):
                rows.append(estimate_row(tc, *drawn, population.iloc[tc.index - first], settings, model))
    return pd.DataFrame(rows)


def estimate_row(tc: HeldOutCapture, renderer: str, camera, depth: np.ndarray, truth: np.ndarray,
                 triangle_id: np.ndarray, room, azimuth_deg: float, subject: pd.Series, settings: RoomTestSettings,
                 model) -> dict:
    """One row of :func:`room_capture_chunk`: the truth, the capture, the estimate and its segmentation.

    Parameters
    ----------
    tc : HeldOutCapture
    renderer : str
        Who drew ``depth``.
    camera : wbsa.camera.Intrinsics
        The camera it was drawn with.
    depth : (h, w) float64
        The capture's depth image, metres.
    truth : (h, w) bool
        The subject's pixels.
    triangle_id : (h, w) int
        The triangle each pixel sees (−1 where none), for the feet's contact strip.
    room : wbsa.training.room.RoomScene
        The scene drawn.
    azimuth_deg : float
        The camera's azimuth.
    subject : pandas.Series
        The subject's row of the population (its truth).
    settings : RoomTestSettings
    model : EstimatorModel
    """
    from wbsa.estimation.methods.view import fold_azimuth
    from wbsa.estimation.single_view import estimate
    from wbsa.estimation.subject.segment import SegmentSettings

    cap = tc.capture
    strip = contact_strip(truth, room.surface_height_m(triangle_id))
    row = {k: subject[k] for k in ("subject_id", "population", "sex", "age_years", "stature_m", "mass_kg", "wbsa_m2")
           if k in subject.index}
    fixed = renderer.startswith("plain-fixed")
    row.update(image=tc.index, renderer=renderer, posture=tc.posture, camera=camera.name, scene=settings.scene,
               noise_scale=cap.sensor.effective_noise_scale, posed_height_m=float(tc.vertices[:, 2].max()),
               ideal_sensor=cap.sensor.is_ideal, azimuth_deg=azimuth_deg,
               elevation_deg=cap.view.elevation_deg if not fixed else float(np.degrees(np.arctan2(
                   FIXED_SETUP["height_m"] - room.subject_center[2], FIXED_SETUP["distance_m"]))),
               distance_m=cap.view.distance_m if not fixed else FIXED_SETUP["distance_m"],
               camera_height_m=cap.camera_height_m if not fixed else FIXED_SETUP["height_m"], fits=cap.fits,
               second_person=tc.second_person and not fixed,
               clothing_m=0.0 if fixed else settings.clothing_m, clothing_stated=settings.clothing_stated,
               subject_pixels=int(truth.sum()))
    t0 = time.perf_counter()
    try:
        est = estimate(depth, camera, model, segment=SegmentSettings(pick=settings.pick),
                       clothing_m=(0.0 if fixed else settings.clothing_m) if settings.clothing_stated else None)
    except WbsaError as exc:
        row.update(error=str(exc), seconds=time.perf_counter() - t0)
        return row
    seconds = time.perf_counter() - t0
    mask = est.mask
    row.update(error="", seconds=seconds, est_wbsa_m2=est.wbsa_m2, est_lo_m2=est.wbsa_lo_m2,
               est_hi_m2=est.wbsa_hi_m2, est_azimuth_deg=est.view.azimuth_deg,
               est_azimuth_sd_deg=est.view.azimuth_sd_deg, est_elevation_deg=est.view.elevation_deg,
               est_stature_m=est.stature_m, est_vbsa_m2=est.vbsa_m2, flags=",".join(est.flags),
               seg_kept=float((mask & truth).sum() / max(truth.sum(), 1)),
               seg_included=float((mask & ~truth).sum() / max(mask.sum(), 1)),
               seg_kept_off_strip=float((mask & truth & ~strip).sum() / max((truth & ~strip).sum(), 1)),
               seg_included_off_strip=float((mask & ~truth & ~strip).sum() / max((mask & ~strip).sum(), 1)),
               azimuth_error_deg=float(abs(est.view.azimuth_deg - fold_azimuth(azimuth_deg))))
    return row


def run_room_tests(population: pd.DataFrame, settings: RoomTestSettings, model_path: str | None, *, workers: int = 1,
                   chunk: int = 10, show_progress: bool | None = None, rows_dir: str | None = None) -> pd.DataFrame:
    """:func:`room_capture_chunk` over a whole population (the second people are the population shifted by one).

    ``rows_dir``: a folder where each chunk's rows are written as it finishes (``chunk-<first>.parquet``, atomically),
    beside ``run.json`` (the settings, model and subjects); a run given the same folder again reads the
    chunks already there and captures only the others, so a long benchmark resumes after a stop. A folder
    written with other settings is refused (:mod:`wbsa.testing.rows`).
    """
    import dataclasses

    from wbsa.progress import progress
    from wbsa.testing.rows import map_resumable, run_record

    others = population.iloc[np.roll(np.arange(len(population)), 1)].reset_index(drop=True)
    starts = list(range(0, len(population), chunk))
    args = [(population.iloc[s:s + chunk].reset_index(drop=True), others.iloc[s:s + chunk].reset_index(drop=True),
             s, settings, model_path) for s in starts]
    record = run_record(population, chunk, settings=dataclasses.asdict(settings), model=str(model_path))
    bar = progress(total=len(population), desc="test captures", unit="image", enabled=show_progress)
    try:
        parts = map_resumable(room_capture_chunk, args, starts, rows_dir=rows_dir, record=record, workers=workers,
                              tag="estimator-test", on_result=lambda part: bar.update(part["image"].nunique() if len(part) else 0))
    finally:
        bar.close()
    table = pd.concat(parts, ignore_index=True)
    return table.sort_values(["image", "renderer"], kind="stable").reset_index(drop=True)
