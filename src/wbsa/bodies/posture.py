"""Standing postures: named poses with seeded joint jitter, applied to rest-pose bodies by skinning.

Every body is built in anny's rest A-pose (:mod:`wbsa.bodies.body_model`). A posture turns its arms
and legs about their joints and moves the skin with anny's own skinning weights (linear blend
skinning, LBS). anny's forward pass is not used for this: with an identity pose it does not return the
rest vertices (its pose parameters are relative to reference bone orientations, not the rest pose),
whereas here the rest pose *is* the identity, so the paper's A-pose stays bit-identical.

Joint angles are **changes from the rest A-pose**, in degrees, one set per side (``l`` = the subject's
left, at +X; ``r`` = right), about axes fixed in the rest pose (+Z up, the subject faces −Y):

=============================  ======================================================================
column                         rotation (positive direction)
=============================  ======================================================================
``shoulder_<s>_abduction_deg``  the whole arm about the forward axis through the shoulder joint (arm
                                raised sideways; negative brings it down towards the trunk)
``shoulder_<s>_flexion_deg``    the whole arm about the left–right axis through the shoulder (arm
                                forwards; negative: backwards)
``shoulder_<s>_rotation_deg``   the arm about its own rest shoulder–elbow axis (internal rotation:
                                the forearm swings towards the belly); anny's two upper-arm bones
                                share it, the upper one turning half as much (twist spread along
                                the arm, as real skin does, instead of wringing the shoulder)
``elbow_<s>_flexion_deg``       the forearm and hand about the elbow hinge (the normal of the rest
                                upper-arm/forearm plane; anny's rest elbow is bent about 43°;
                                negative straightens it)
``hip_<s>_abduction_deg``       the leg about the forward axis through the hip joint (foot outwards;
                                negative: feet together); the foot turns back by the same angle about
                                the ankle, so the sole stays flat on the floor
=============================  ======================================================================

The shoulder rotations compose as abduction ∘ flexion ∘ rotation (the arm is first turned about its
own axis, then raised forward, then sideways), the elbow after them (it rides on the upper arm). A
posed body is shifted to stand on z = 0 again.

A body's vertex moves with the blend Σ_k w_k T_k of the transforms of its bones; bones without a
rotation keep the identity, so a vertex weighted only to the trunk does not move at all.

Named postures (:data:`POSTURES`) give each angle a nominal value and a uniform jitter half-width;
:func:`draw_postures` draws every subject's angles from its own stream
``SeedSequence([seed, subject_id, POSTURE_STREAM])``. :func:`settle_posture` then keeps the limbs out
of the body: an arm that sinks into the trunk, head or legs is raised sideways in steps of
:data:`SETTLE_STEP_DEG` until it no longer does (the arm of a heavy body rests on its side instead of
passing through it), and legs that sink into each other are spread the same way.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Callable

import numpy as np
import pandas as pd

from wbsa.bodies.posing import JOINT_MOTIONS, SIDES, SinkTest, pose_vertices, segment_transforms
from wbsa.typing import PostureChoice
from wbsa.errors import WbsaError
from wbsa.settings_io import check_types

#: Angle columns of a postured population table, degrees, changes from the rest A-pose.
ANGLE_COLUMNS = tuple(f"{m.split('_')[0]}_{s}_{m.split('_')[1]}_deg" for s in SIDES for m in JOINT_MOTIONS)
#: Every posture column: the posture's name, then :data:`ANGLE_COLUMNS`.
POSTURE_COLUMNS = ("posture", *ANGLE_COLUMNS)
#: Random stream tag of the posture draw (``SeedSequence([seed, subject_id, POSTURE_STREAM])``).
POSTURE_STREAM = 0x9057E
#: Abduction step (degrees) by which :func:`settle_posture` raises a limb that sinks into the body.
SETTLE_STEP_DEG = 2.0
#: Largest depth (m) a forearm, hand or leg may sink into the rest of the body before it is raised.
SETTLE_TOLERANCE_M = 0.005


@dataclass(frozen=True)
class PostureSpec:
    """One named posture: nominal joint angles and their jitter, the same for both sides.

    Attributes
    ----------
    nominal_deg : dict of str to float
        Nominal change from the rest pose of each motion in :data:`JOINT_MOTIONS` (missing: 0).
    jitter_deg : dict of str to float
        Half-width of the uniform jitter added to each motion, drawn independently per side
        (missing: :data:`DEFAULT_JITTER_DEG`).
    """

    nominal_deg: dict[str, float] = field(default_factory=dict)
    jitter_deg: dict[str, float] = field(default_factory=dict)

    def nominal(self, motion: str) -> float:
        return float(self.nominal_deg.get(motion, 0.0))

    def jitter(self, motion: str) -> float:
        return float(self.jitter_deg.get(motion, DEFAULT_JITTER_DEG[motion]))


#: Jitter half-widths (degrees) of a motion a posture does not set itself.
DEFAULT_JITTER_DEG = {"shoulder_abduction": 4.0, "shoulder_flexion": 5.0, "shoulder_rotation": 6.0,
                      "elbow_flexion": 6.0, "hip_abduction": 1.5}

#: The named postures (nominal changes from anny's rest A-pose, degrees).
POSTURES: dict[str, PostureSpec] = {
    "a-pose": PostureSpec(),
    "arms-down": PostureSpec({"shoulder_abduction": -32.0, "elbow_flexion": -35.0},
                             {"shoulder_abduction": 4.0, "elbow_flexion": 8.0}),
    "arms-wide": PostureSpec({"shoulder_abduction": 18.0, "elbow_flexion": -10.0},
                             {"shoulder_abduction": 7.0, "elbow_flexion": 8.0}),
    "hands-on-hips": PostureSpec({"shoulder_flexion": -10.0, "shoulder_rotation": 85.0, "elbow_flexion": 30.0},
                                 {"shoulder_rotation": 8.0}),
    "elbows-bent": PostureSpec({"shoulder_abduction": -25.0, "shoulder_rotation": 10.0, "elbow_flexion": 45.0},
                               {"elbow_flexion": 10.0}),
    "feet-together": PostureSpec({"hip_abduction": -8.0}, {"hip_abduction": 1.5}),
    "feet-apart": PostureSpec({"hip_abduction": 6.0}, {"hip_abduction": 2.0}),
}


@dataclass(frozen=True)
class PostureSettings:
    """How a population stands.

    Attributes
    ----------
    posture : str
        ``"a-pose"``: every body in anny's rest A-pose exactly, no posture columns (the paper's study);
        ``"mixed"``: each subject draws one of ``mix`` with equal probability, plus jitter; or one name
        of :data:`POSTURES` for every subject, with jitter.
    seed : int
        Root seed; subject ``i`` draws from ``SeedSequence([seed, i, POSTURE_STREAM])``.
    mix : tuple of str
        The postures ``"mixed"`` draws from (default: all of :data:`POSTURES`).
    """

    posture: PostureChoice = "a-pose"
    seed: int = 0
    mix: tuple[str, ...] = tuple(POSTURES)

    def __post_init__(self) -> None:
        check_types(self)
        if self.seed < 0:
            raise WbsaError(f"posture seed must be an integer >= 0, got {self.seed!r}")
        unknown = [name for name in self.mix if name not in POSTURES]
        if unknown or not self.mix:
            raise WbsaError(f"posture mix {list(self.mix)} must name at least one of {', '.join(POSTURES)}")

    @property
    def varies(self) -> bool:
        """False for the paper's A-pose (no posture columns, bodies exactly at rest)."""
        return self.posture != "a-pose"


def draw_postures(subject_ids, settings: PostureSettings) -> pd.DataFrame:
    """Each subject's posture name and joint angles (nominal + uniform jitter).

    Parameters
    ----------
    subject_ids : (b,) int
    settings : PostureSettings
        With ``posture == "a-pose"`` every angle is 0 (no jitter): the rest pose.

    Returns
    -------
    pandas.DataFrame
        :data:`POSTURE_COLUMNS`, one row per subject, in the order of ``subject_ids``. Subject ``i``'s
        row depends only on ``settings`` and ``i``.
    """
    ids = np.asarray(subject_ids, dtype=np.int64)
    names: list[str] = []
    angles = np.zeros((len(ids), len(ANGLE_COLUMNS)))
    for row, sid in enumerate(ids):
        if settings.posture == "a-pose":
            names.append("a-pose")
            continue
        rng = np.random.default_rng(np.random.SeedSequence([int(settings.seed), int(sid), POSTURE_STREAM]))
        name = settings.mix[rng.integers(len(settings.mix))] if settings.posture == "mixed" else settings.posture
        names.append(name)
        angles[row] = draw_angles(name, rng)
    out = pd.DataFrame(angles, columns=list(ANGLE_COLUMNS))
    out.insert(0, "posture", names)
    return out


def draw_angles(name: str, rng: np.random.Generator) -> np.ndarray:
    """(10,) float64 joint angles of posture ``name`` (:data:`ANGLE_COLUMNS` order): nominal + uniform jitter."""
    spec = POSTURES[name]
    u = rng.uniform(-1.0, 1.0, size=len(ANGLE_COLUMNS))
    nominal = np.array([spec.nominal(m) for _ in SIDES for m in JOINT_MOTIONS])
    jitter = np.array([spec.jitter(m) for _ in SIDES for m in JOINT_MOTIONS])
    return nominal + u * jitter


#: ``(rest vertices (n, 3), bone heads (j, 3), rng) -> (posed vertices (n, 3), posture name)``: how the
#: estimator's training and test captures pose a body.
PoseBody = Callable[[np.ndarray, np.ndarray, np.random.Generator], tuple[np.ndarray, str]]


class RandomPosture:
    """A :data:`PoseBody`: a posture drawn uniformly from ``names``, jittered, settled and applied.

    The same postures, jitter and settling as a ``posture = "mixed"`` population
    (:func:`draw_postures`, :func:`settle_posture`), drawn from the caller's generator.

    Parameters
    ----------
    model : wbsa.bodies.body_model.BodyModel
    names : tuple of str, optional
        Names of :data:`POSTURES` to draw from (default: all).
    """

    def __init__(self, model, names: tuple[str, ...] | None = None) -> None:
        from wbsa.bodies.posing import Rig

        self.names = tuple(POSTURES) if names is None else tuple(names)
        unknown = [n for n in self.names if n not in POSTURES]
        if unknown or not self.names:
            raise WbsaError(f"postures {unknown or list(self.names)} are unknown; use some of {', '.join(POSTURES)}")
        self.rig = Rig.from_model(model)

    def __call__(self, vertices: np.ndarray, bone_heads: np.ndarray,
                 rng: np.random.Generator) -> tuple[np.ndarray, str]:
        """Posed vertices (n, 3) float64 standing on z = 0, and the posture's name."""
        name = self.names[int(rng.integers(len(self.names)))]
        _, posed = settle_posture(np.asarray(vertices, dtype=np.float64), np.asarray(bone_heads, dtype=np.float64),
                                  draw_angles(name, rng), self.rig)
        return posed, name


def has_posture(table: pd.DataFrame) -> bool:
    """True when ``table`` carries posture angle columns (:data:`ANGLE_COLUMNS`)."""
    return any(c in table.columns for c in ANGLE_COLUMNS)


def posture_angles(table: pd.DataFrame) -> np.ndarray | None:
    """The joint angles of every row, ``(b, 10)`` float64 degrees, or None for a table without posture.

    Raises
    ------
    WbsaError
        If only some angle columns are present, or an angle is not finite or beyond ±180°.
    """
    if not has_posture(table):
        return None
    missing = [c for c in ANGLE_COLUMNS if c not in table.columns]
    if missing:
        raise WbsaError(f"the table has posture columns but lacks {', '.join(missing)}; "
                        "rebuild it with wbsa population --posture")
    angles = table[list(ANGLE_COLUMNS)].to_numpy(dtype=np.float64)
    bad = ~np.isfinite(angles) | (np.abs(angles) > 180.0)
    if bad.any():
        row, col = np.argwhere(bad)[0]
        raise WbsaError(f"posture angle {ANGLE_COLUMNS[col]} = {float(angles[row, col])!r} in row {row} is not a "
                        "finite angle within ±180 degrees")
    return angles


#: Column indices of each side's shoulder and hip abduction in :data:`ANGLE_COLUMNS`.
_ABDUCTION = {side: ANGLE_COLUMNS.index(f"shoulder_{side}_abduction_deg") for side in SIDES}
_HIP = tuple(ANGLE_COLUMNS.index(f"hip_{side}_abduction_deg") for side in SIDES)
#: Most steps :func:`settle_posture` takes (a limb is raised by at most this × :data:`SETTLE_STEP_DEG`).
SETTLE_MAX_STEPS = 40


def settle_posture(rest_vertices: np.ndarray, bone_heads: np.ndarray, angles_deg: np.ndarray,
                   rig) -> tuple[np.ndarray, np.ndarray]:
    """Keep the limbs out of the body: spread the legs, then raise each arm, until none sinks in.

    Legs that sink into each other deeper than at rest plus :data:`SETTLE_TOLERANCE_M` both have their
    hip abduction raised by half of :data:`SETTLE_STEP_DEG`, until they do not; then an arm whose
    vertices lie deeper than :data:`SETTLE_TOLERANCE_M` inside the trunk, head or legs has its
    shoulder abduction raised by :data:`SETTLE_STEP_DEG`, until it does not. Each limb takes at most
    :data:`SETTLE_MAX_STEPS` steps. Only limbs the posture moves are checked (the rest pose is the
    reference), legs only when drawn together (negative hip abduction).

    Parameters
    ----------
    rest_vertices : (n, 3) float64
    bone_heads : (j, 3) float64
    angles_deg : (10,) float64
        Drawn joint angles (:data:`ANGLE_COLUMNS` order).
    rig : wbsa.bodies.posing.Rig

    Returns
    -------
    angles : (10,) float64
        The angles applied (``angles_deg`` where no limb sank in).
    vertices : (n, 3) float64
        The posed body standing on z = 0 (:func:`~wbsa.bodies.posing.pose_vertices` of ``angles``).
    """
    angles = np.array(angles_deg, dtype=np.float64)
    hips = list(_HIP)
    if angles[hips].min() < 0:
        allowed = None
        for _ in range(SETTLE_MAX_STEPS):
            v = pose_vertices(rest_vertices, bone_heads, angles, rig, floor=False)
            points = v[rig.leg_query["l"].vertices]
            depth = SinkTest(v, rig.leg_target["l"], points, 1.0).depth_m(points)
            if depth <= SETTLE_TOLERANCE_M:
                break
            if allowed is None:
                rest = rest_vertices[rig.leg_query["l"].vertices]
                allowed = SinkTest(rest_vertices, rig.leg_target["l"], rest, 1.0).depth_m(rest) + SETTLE_TOLERANCE_M
            if depth <= allowed:
                break
            angles[hips] += SETTLE_STEP_DEG / 2
    per_side = len(JOINT_MOTIONS)
    settled = angles.copy()
    v = pose_vertices(rest_vertices, bone_heads, angles, rig, floor=False)
    for si, side in enumerate(SIDES):
        if not angles[si * per_side:si * per_side + 4].any():
            continue
        query = rig.arm_query[side]
        test = SinkTest(v, rig.arm_target[side], v[query.vertices], 1.0 if side == "l" else -1.0)
        for _ in range(SETTLE_MAX_STEPS):
            points = query.blend(rest_vertices, segment_transforms(bone_heads, angles, rig))
            if test.depth_m(points) <= SETTLE_TOLERANCE_M:
                break
            angles[_ABDUCTION[side]] += SETTLE_STEP_DEG
    if not np.array_equal(angles, settled):
        v = pose_vertices(rest_vertices, bone_heads, angles, rig, floor=False)
    if angles.any():
        v[:, 2] -= v[:, 2].min()
    return angles, v
