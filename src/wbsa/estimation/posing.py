"""Everyday postures for the estimator's training and benchmark bodies (an adapter, to be swapped).

Until the population stage poses bodies itself (``wbsa.bodies.posture``), the estimator poses anny's
rest (A-pose) bodies here: bone chains are rotated rigidly about their rest bone heads and the skin
follows by anny's skinning weights (linear blend skinning), a route the reference facts record as
working. Everything the estimator needs from a posture goes through one callable,
:data:`PoseBody`: ``(vertices, bone_heads, rng) -> (posed vertices, posture name)``, so a better posing
function drops in without touching the training or the benchmark.

Angles are relative to the rest A-pose (upper arms about 43° from vertical), in degrees:
``shoulder_abduction_deg`` > 0 spreads the arms, < 0 brings them to the body (about −38° hangs them
straight down); ``elbow_flexion_deg`` swings the forearms forward; ``elbow_inward_deg`` bends them
towards the hips in the frontal plane; ``hip_abduction_deg`` spreads the legs. WBSA stays the rest
body's area (the posed skin differs from it by blend-skinning distortion only).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Callable

import numpy as np

from wbsa.errors import WbsaError

#: ``(vertices (n, 3), bone_heads (j, 3), rng) -> (posed vertices (n, 3), posture name)``.
PoseBody = Callable[[np.ndarray, np.ndarray, np.random.Generator], tuple[np.ndarray, str]]


@dataclass(frozen=True)
class Posture:
    """Joint angles relative to the rest A-pose (degrees); see the module doc for the conventions."""

    name: str
    shoulder_abduction_deg: float = 0.0
    elbow_flexion_deg: float = 0.0
    elbow_inward_deg: float = 0.0
    hip_abduction_deg: float = 0.0


#: Named postures people stand in (issue 11, point 5). Pockets are arms down with bent elbows.
POSTURES: dict[str, Posture] = {
    "a-pose": Posture("a-pose"),
    "arms-down": Posture("arms-down", shoulder_abduction_deg=-36.0),
    "arms-wide": Posture("arms-wide", shoulder_abduction_deg=17.0),
    "hands-on-hips": Posture("hands-on-hips", shoulder_abduction_deg=-12.0, elbow_inward_deg=80.0),
    "elbows-bent": Posture("elbows-bent", shoulder_abduction_deg=-30.0, elbow_flexion_deg=70.0),
    "feet-together": Posture("feet-together", shoulder_abduction_deg=-20.0, hip_abduction_deg=-3.0),
    "feet-apart": Posture("feet-apart", shoulder_abduction_deg=-10.0, hip_abduction_deg=8.0),
}
#: Standard deviation of the random jitter added to every angle, each side separately (degrees).
JITTER_DEG = 5.0


def _rot_x(deg: float) -> np.ndarray:
    c, s = np.cos(np.radians(deg)), np.sin(np.radians(deg))
    return np.array([[1.0, 0.0, 0.0], [0.0, c, -s], [0.0, s, c]])


def _rot_y(deg: float) -> np.ndarray:
    c, s = np.cos(np.radians(deg)), np.sin(np.radians(deg))
    return np.array([[c, 0.0, s], [0.0, 1.0, 0.0], [-s, 0.0, c]])


class Poser:
    """Poses rest bodies of one :class:`wbsa.bodies.body_model.BodyModel` by linear blend skinning.

    Parameters
    ----------
    model : wbsa.bodies.body_model.BodyModel
    names : tuple of str
        The postures :meth:`__call__` draws from (uniformly); default all of :data:`POSTURES`.
    jitter_deg : float
        Random jitter of every angle, per side.
    """

    def __init__(self, model, names: tuple[str, ...] | None = None, jitter_deg: float = JITTER_DEG) -> None:
        names = tuple(POSTURES) if names is None else tuple(names)
        unknown = [n for n in names if n not in POSTURES]
        if unknown or not names:
            raise WbsaError(f"unknown posture {unknown or names}; use some of {', '.join(POSTURES)}")
        self.names = names
        self.jitter_deg = float(jitter_deg)
        self.parents = [int(p) for p in model.anny.bone_parents]
        labels = model.bone_labels
        self._bone = {b: labels.index(b) for b in ("upperarm01.L", "upperarm01.R", "lowerarm01.L", "lowerarm01.R",
                                                     "upperleg01.L", "upperleg01.R")}
        self.weights = model.anny.vertex_bone_weights.detach().cpu().numpy().astype(np.float64)
        self.indices = model.anny.vertex_bone_indices.detach().cpu().numpy().astype(np.int64)

    def __call__(self, vertices: np.ndarray, bone_heads: np.ndarray,
                 rng: np.random.Generator) -> tuple[np.ndarray, str]:
        """A random posture (uniform over ``names``, jittered) applied to one body: a :data:`PoseBody`."""
        base = POSTURES[self.names[int(rng.integers(len(self.names)))]]
        j = rng.normal(0.0, self.jitter_deg, size=(2, 4)) if self.jitter_deg > 0 else np.zeros((2, 4))
        sides = [Posture(base.name, base.shoulder_abduction_deg + j[s, 0], base.elbow_flexion_deg + j[s, 1],
                         base.elbow_inward_deg + j[s, 2] * (base.elbow_inward_deg != 0),
                         base.hip_abduction_deg + 0.4 * j[s, 3]) for s in range(2)]
        return self.pose(vertices, bone_heads, sides[0], sides[1]), base.name

    def pose(self, vertices: np.ndarray, bone_heads: np.ndarray, left: Posture,
             right: Posture | None = None) -> np.ndarray:
        """Posed vertices of one rest body.

        Parameters
        ----------
        vertices : (n, 3) float
            Rest vertices (anny's frame standing on z = 0).
        bone_heads : (j, 3) float
            Rest bone heads, same frame.
        left, right : Posture
            Angles of the body's left (+X) and right side (``right`` defaults to ``left``).

        Returns
        -------
        (n, 3) float64
            Lowered or raised so the lowest vertex stays on z = 0.
        """
        right = left if right is None else right
        local: dict[int, np.ndarray] = {}
        for side, p, sign in (("L", left, 1.0), ("R", right, -1.0)):
            # about +Y a positive angle turns a hanging limb (0, 0, -1) towards -X: outward is -sign
            local[self._bone[f"upperarm01.{side}"]] = _rot_y(-sign * p.shoulder_abduction_deg)
            local[self._bone[f"lowerarm01.{side}"]] = _rot_y(sign * p.elbow_inward_deg) @ _rot_x(-p.elbow_flexion_deg)
            local[self._bone[f"upperleg01.{side}"]] = _rot_y(-sign * p.hip_abduction_deg)
        heads = np.asarray(bone_heads, dtype=np.float64)
        n_bones = len(self.parents)
        rot = np.tile(np.eye(3), (n_bones, 1, 1))
        shift = np.zeros((n_bones, 3))
        for b in range(n_bones):  # parents come before their children in anny's bone list
            r_b = local.get(b)
            par = self.parents[b]
            pr, pt = (rot[par], shift[par]) if par >= 0 else (np.eye(3), np.zeros(3))
            if r_b is None:
                rot[b], shift[b] = pr, pt
            else:  # G_b(x) = G_parent(R_b (x - h_b) + h_b)
                rot[b] = pr @ r_b
                shift[b] = pr @ (heads[b] - r_b @ heads[b]) + pt
        v = np.asarray(vertices, dtype=np.float64)
        moved = np.einsum("nkij,nj->nki", rot[self.indices], v) + shift[self.indices]
        out = np.einsum("nk,nki->ni", self.weights, moved)
        out[:, 2] -= out[:, 2].min()
        return out


def rest_pose(vertices: np.ndarray, bone_heads: np.ndarray, rng: np.random.Generator) -> tuple[np.ndarray, str]:
    """The :data:`PoseBody` that leaves the body in its rest A-pose."""
    return np.asarray(vertices, dtype=np.float64), "a-pose"
