"""Posing rest-pose bodies by linear blend skinning on anny's skeleton (the geometry of :mod:`.posture`).

:class:`Rig` holds what posing needs from anny once per :class:`~wbsa.bodies.body_model.BodyModel`:
the vertices the posed bones move and their skinning weights, summed per rigid *segment* (upper arm,
lower upper arm, forearm and hand, leg, foot; per side), and the joints whose heads are the pivots.
:func:`pose_vertices` turns one body's rest vertices into the posed ones for a row of joint angles
(:data:`~wbsa.bodies.posture.ANGLE_COLUMNS`); all angles 0 returns the rest vertices unchanged, bit for
bit. :class:`SinkTest` and :func:`limb_sink_depths_m` measure how deep an arm lies inside the trunk,
head and legs, and a leg inside the other leg (the self-intersection check that
:func:`~wbsa.bodies.posture.settle_posture` uses).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np


#: The two sides: ``l`` is the subject's left (+X), ``r`` its right (−X).
SIDES = ("l", "r")
#: Joint motions of one side, in the order of a side's angles (``<joint>_<side>_<motion>_deg`` in tables).
JOINT_MOTIONS = ("shoulder_abduction", "shoulder_flexion", "shoulder_rotation", "elbow_flexion", "hip_abduction")
#: Segments of one side, in skinning-weight column order (:class:`SkinWeights`); a segment is a set of bones
#: moving rigidly.
SEGMENTS = ("upperarm01", "upperarm02", "forearm", "leg", "foot")
#: Bones whose heads are the joints of one side (anny names without the ``.L``/``.R`` suffix).
JOINT_BONES = {"shoulder": "upperarm01", "elbow": "lowerarm01", "wrist": "wrist", "hip": "upperleg01",
               "ankle": "foot"}
_SUFFIX = {"l": ".L", "r": ".R"}
#: Sign of each side's +X direction: the left side is at +X.
_SIDE_SIGN = {"l": 1.0, "r": -1.0}


@dataclass(frozen=True)
class SkinWeights:
    """Some vertices and their summed skinning weight on each segment, kept sparse.

    Attributes
    ----------
    vertices : (k,) intp
        Vertex indices into the body.
    rows : tuple of (r_s,) intp
        Per segment, the positions in ``vertices`` with a weight on it.
    weights : tuple of (r_s,) float64
        Per segment, those weights.
    """

    vertices: np.ndarray
    rows: tuple[np.ndarray, ...]
    weights: tuple[np.ndarray, ...]

    @classmethod
    def from_dense(cls, vertices: np.ndarray, dense: np.ndarray) -> "SkinWeights":
        """From the ``(k, s)`` weights of ``vertices`` on every segment."""
        rows = tuple(np.flatnonzero(dense[:, s] > 0) for s in range(dense.shape[1]))
        return cls(np.asarray(vertices, dtype=np.intp), rows, tuple(dense[r, s] for s, r in enumerate(rows)))

    def blend(self, rest_vertices: np.ndarray, transforms: list) -> np.ndarray:
        """Linear blend skinning of these vertices: ``p + Σ_s w_s (T_s p − p)``.

        Parameters
        ----------
        rest_vertices : (n, 3) float64
            The whole body at rest.
        transforms : list of (R, t) or None
            :func:`segment_transforms`; None entries (segments that do not move) add nothing.

        Returns
        -------
        (k, 3) float64
            The posed positions of :attr:`vertices`.
        """
        points = rest_vertices[self.vertices]
        out = points.copy()
        for rows, w, t in zip(self.rows, self.weights, transforms):
            if t is not None:
                p = points[rows]
                out[rows] += w[:, None] * (p @ t[0].T + t[1] - p)
        return out


@dataclass(frozen=True)
class Rig:
    """What posing needs from anny's skeleton, fixed for a body model.

    Attributes
    ----------
    skin : SkinWeights
        The vertices with a skinning weight on a posed bone (the others never move) and their weights
        on the segments: :data:`SEGMENTS` of the left side, then of the right.
    joints : dict of str to dict of str to int
        Per side (``l``, ``r``), the bone index whose head is each joint of :data:`JOINT_BONES`.
    arm_query, leg_query : dict of str to SkinWeights
        Per side, the vertices moved by that arm (or leg) alone (summed weight >= 0.999), whose
        depth inside the rest of the body is checked.
    arm_target, leg_target : dict of str to (t, 3) int32
        Per side, the closed-shell triangles an arm must stay out of (those neither arm moves: trunk,
        head, legs), and those of the other leg (every vertex weighted to it); each a closed surface
        but for the holes where the limbs join it, above the points tested.
    """

    skin: SkinWeights
    joints: dict[str, dict[str, int]]
    arm_query: dict[str, SkinWeights]
    leg_query: dict[str, SkinWeights]
    arm_target: dict[str, np.ndarray]
    leg_target: dict[str, np.ndarray]

    @classmethod
    def from_model(cls, model) -> "Rig":
        """The rig of a :class:`~wbsa.bodies.body_model.BodyModel` (anny's bones and skinning weights)."""
        anny = model.anny
        weights = anny.vertex_bone_weights.detach().cpu().numpy().astype(np.float64)
        indices = anny.vertex_bone_indices.detach().cpu().numpy().astype(np.intp)
        labels = list(model.bone_labels)
        parents = [int(p) for p in anny.bone_parents]
        n = weights.shape[0]
        return cls.from_arrays(labels, parents, weights, indices, model.closed_faces, n)

    @classmethod
    def from_arrays(cls, labels: list[str], parents: list[int], weights: np.ndarray, indices: np.ndarray,
                    closed_faces: np.ndarray, n_vertices: int) -> "Rig":
        """Build a rig from a skeleton (bone names and parents) and sparse skinning weights.

        Parameters
        ----------
        labels : list of str
            Bone names (anny's: ``upperarm01.L`` ...).
        parents : list of int
            Parent bone index of each bone (the root's negative).
        weights, indices : (n, w) float64, (n, w) int
            Each vertex's bone weights and bone indices.
        closed_faces : (m, 3) int
            The body's closed shell (:attr:`~wbsa.bodies.body_model.BodyModel.closed_faces`).
        n_vertices : int
        """
        children: dict[int, list[int]] = {i: [] for i in range(len(labels))}
        for bone, parent in enumerate(parents):
            if parent >= 0:
                children[parent].append(bone)

        def subtree(root: int) -> list[int]:
            out, stack = [], [root]
            while stack:
                bone = stack.pop()
                out.append(bone)
                stack.extend(children[bone])
            return out

        seg_weight = np.zeros((n_vertices, 2 * len(SEGMENTS)))
        joints = {}
        for si, side in enumerate(("l", "r")):
            idx = {name: labels.index(bone + _SUFFIX[side]) for name, bone in JOINT_BONES.items()}
            joints[side] = idx
            ua1, ua2, fore = idx["shoulder"], labels.index("upperarm02" + _SUFFIX[side]), idx["elbow"]
            leg_bones = [b for b in subtree(idx["hip"]) if b not in subtree(idx["ankle"])]
            bones = {"upperarm01": [ua1], "upperarm02": [ua2], "forearm": subtree(fore), "leg": leg_bones,
                     "foot": subtree(idx["ankle"])}
            assert set(subtree(ua1)) == {ua1, ua2, *subtree(fore)}, "unexpected anny arm skeleton"
            for j, seg in enumerate(SEGMENTS):
                seg_weight[:, si * len(SEGMENTS) + j] = np.where(np.isin(indices, bones[seg]), weights, 0.0).sum(1)
        moving = np.flatnonzero(seg_weight.sum(1) > 0)
        faces = np.asarray(closed_faces, dtype=np.int32)
        k = len(SEGMENTS)
        arm_query, leg_query, arm_target, leg_target = {}, {}, {}, {}
        both_arms = seg_weight[:, [0, 1, 2, k, k + 1, k + 2]].sum(1)
        leg_of = {side: seg_weight[:, si * k + 3:(si + 1) * k].sum(1) for si, side in enumerate(("l", "r"))}
        for si, side in enumerate(("l", "r")):
            w = seg_weight[:, si * k:(si + 1) * k]
            arm, leg = w[:, :3].sum(1), w[:, 3:].sum(1)
            arm_query[side] = np.flatnonzero(arm >= 0.999)
            arm_query[side] = SkinWeights.from_dense(arm_query[side], seg_weight[arm_query[side]])
            leg_query[side] = np.flatnonzero(leg >= 0.999)
            leg_query[side] = SkinWeights.from_dense(leg_query[side], seg_weight[leg_query[side]])
            arm_target[side] = faces[(both_arms[faces] == 0).all(axis=1)]
        for side, other in (("l", "r"), ("r", "l")):
            # the other leg alone: open only at the hip, above every point of this leg
            leg_target[side] = faces[(leg_of[other][faces] > 0).all(axis=1)]
        return cls(skin=SkinWeights.from_dense(moving, seg_weight[moving]), joints=joints, arm_query=arm_query,
                   leg_query=leg_query, arm_target=arm_target, leg_target=leg_target)


def rotation_matrix(axis: np.ndarray, angle_rad: float) -> np.ndarray:
    """``(3, 3)`` rotation by ``angle_rad`` about the unit ``axis`` (right-hand rule, Rodrigues)."""
    x, y, z = axis
    c, s = np.cos(angle_rad), np.sin(angle_rad)
    k = np.array([[0.0, -z, y], [z, 0.0, -x], [-y, x, 0.0]])
    return np.eye(3) + s * k + (1.0 - c) * (k @ k)


def _about(pivot: np.ndarray, rot: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The rigid transform ``x -> rot x + t`` that turns by ``rot`` about ``pivot``."""
    return rot, pivot - rot @ pivot


def _then(outer: tuple[np.ndarray, np.ndarray], inner: tuple[np.ndarray, np.ndarray]) -> tuple[np.ndarray, np.ndarray]:
    """``outer ∘ inner`` (inner applied first)."""
    return outer[0] @ inner[0], outer[0] @ inner[1] + outer[1]


def _unit(v: np.ndarray) -> np.ndarray:
    return v / np.linalg.norm(v)


def segment_transforms(bone_heads: np.ndarray, angles_deg: np.ndarray,
                       rig: Rig) -> list[tuple[np.ndarray, np.ndarray] | None]:
    """The rigid transform of every segment of one body (None where it does not move).

    Parameters
    ----------
    bone_heads : (j, 3) float64
        The body's rest joint positions.
    angles_deg : (10,) float64
        Joint angles: :data:`JOINT_MOTIONS` of the left side, then of the right
        (:data:`~wbsa.bodies.posture.ANGLE_COLUMNS` order).
    rig : Rig

    Returns
    -------
    list of (R, t) or None
        ``2 * len(SEGMENTS)`` entries (left side, then right): ``x -> R x + t``, ``R`` (3, 3), ``t`` (3,).
    """
    out: list[tuple[np.ndarray, np.ndarray] | None] = []
    a = np.radians(np.asarray(angles_deg, dtype=np.float64)).reshape(2, len(JOINT_MOTIONS))
    for si, side in enumerate(("l", "r")):
        abd, flex, rot, elbow, hip = a[si]
        sign = _SIDE_SIGN[side]
        j = {name: bone_heads[b] for name, b in rig.joints[side].items()}
        upper, fore = j["elbow"] - j["shoulder"], j["wrist"] - j["elbow"]
        forward_axis = np.array([0.0, -sign, 0.0])  # raises this side's limb sideways
        if abd or flex or rot or elbow:
            base = rotation_matrix(forward_axis, abd) @ rotation_matrix(np.array([-1.0, 0.0, 0.0]), flex)
            twist = sign * _unit(upper)
            ua1 = _about(j["shoulder"], base @ rotation_matrix(twist, rot / 2))
            ua2 = _about(j["shoulder"], base @ rotation_matrix(twist, rot))
            forearm = _then(ua2, _about(j["elbow"], rotation_matrix(_unit(np.cross(upper, fore)), elbow)))
            out += [ua1, ua2, forearm]
        else:
            out += [None, None, None]
        if hip:
            leg = _about(j["hip"], rotation_matrix(forward_axis, hip))
            out += [leg, _then(leg, _about(j["ankle"], rotation_matrix(forward_axis, -hip)))]
        else:
            out += [None, None]
    return out


def pose_vertices(rest_vertices: np.ndarray, bone_heads: np.ndarray, angles_deg: np.ndarray, rig: Rig, *,
                  floor: bool = True) -> np.ndarray:
    """One body's vertices in a posture, standing on z = 0.

    Parameters
    ----------
    rest_vertices : (n, 3) float64
        The body's rest-pose vertices (:attr:`~wbsa.bodies.body_model.RestBodies.vertices`), metres.
    bone_heads : (j, 3) float64
        Its rest joint positions, same frame (:attr:`~wbsa.bodies.body_model.RestBodies.bone_heads`).
    angles_deg : (10,) float64
        Joint angles in :data:`~wbsa.bodies.posture.ANGLE_COLUMNS` order (changes from the rest pose).
    rig : Rig
    floor : bool
        Shift the posed body so that its lowest vertex is at z = 0 (False: leave it where skinning put it).

    Returns
    -------
    (n, 3) float64
        The posed vertices (linear blend skinning with anny's weights). All angles 0: a copy of
        ``rest_vertices``, bit for bit.
    """
    v = np.array(rest_vertices, dtype=np.float64, copy=True)
    transforms = segment_transforms(bone_heads, angles_deg, rig)
    if all(t is None for t in transforms):
        return v
    v[rig.skin.vertices] = rig.skin.blend(v, transforms)
    if floor:
        v[:, 2] -= v[:, 2].min()
    return v


class SinkTest:
    """How deep points lie inside a fixed surface (the rest of a body a limb must stay out of).

    A point is inside when a ray from it straight down (−Z) crosses the surface an odd number of
    times; its depth is then its distance to the nearest triangle. The surface should be closed below
    the points (the hole above them, where the limb was cut off, does not matter).

    Only the triangles reaching the limb's side of a cut ``side * x >= cut`` are kept (``cut`` is
    ``margin`` inside the points' innermost ``side * x``): a downward ray from a point on that side
    meets no other triangle, and every triangle within ``margin`` of the points is kept, so depths up
    to ``margin`` are exact while the ray-casting structure is a fraction of the body.

    Parameters
    ----------
    vertices : (n, 3) float64
    faces : (m, 3) int
    points : (q, 3) float64
        The points that will be tested (their extent sets the cut).
    side : {1, -1}
        +1 for points at +X (the left side), −1 for the right.
    margin : float
        Metres.
    """

    def __init__(self, vertices: np.ndarray, faces: np.ndarray, points: np.ndarray, side: float,
                 margin: float = 0.05) -> None:
        import open3d as o3d

        self._o3d = o3d
        self.side = float(side)
        self.cut = float((side * points[:, 0]).min()) - margin
        faces = np.asarray(faces)
        x = side * vertices[:, 0]
        kept = faces[np.maximum(np.maximum(x[faces[:, 0]], x[faces[:, 1]]), x[faces[:, 2]]) >= self.cut]
        used = np.zeros(len(vertices), dtype=bool)
        used[kept] = True
        local = np.cumsum(used, dtype=np.uint32) - 1  # new index of each kept vertex
        self.scene = o3d.t.geometry.RaycastingScene()
        if len(kept):
            self.scene.add_triangles(o3d.core.Tensor(np.ascontiguousarray(vertices[used], dtype=np.float32)),
                                     o3d.core.Tensor(np.ascontiguousarray(local[kept])))

    def depth_m(self, points: np.ndarray) -> float:
        """The largest depth of ``points`` inside the surface, metres (0 when none is inside).

        Points beyond the cut (on the far side) count as outside.
        """
        o3c = self._o3d.core
        p = np.ascontiguousarray(points[self.side * points[:, 0] >= self.cut], dtype=np.float32)
        if not len(p):
            return 0.0
        rays = np.concatenate([p, np.broadcast_to(np.float32([0.0, 0.0, -1.0]), p.shape)], axis=1)
        inside = self.scene.count_intersections(o3c.Tensor(rays), nthreads=1).numpy() % 2 == 1
        if not inside.any():
            return 0.0
        return float(self.scene.compute_distance(o3c.Tensor(p[inside]), nthreads=1).numpy().max())


def limb_sink_depths_m(vertices: np.ndarray, rig: Rig) -> dict[str, float]:
    """How deep each arm lies inside the trunk, head and legs, and each leg inside the rest of the body.

    Parameters
    ----------
    vertices : (n, 3) float64
        A posed (or rest) body.
    rig : Rig

    Returns
    -------
    dict
        ``arm_l``, ``arm_r``, ``leg_l``, ``leg_r``: metres, exact up to 5 cm (see :class:`SinkTest`).
    """
    out = {}
    for limb, query, target in (("arm", rig.arm_query, rig.arm_target), ("leg", rig.leg_query, rig.leg_target)):
        for side in ("l", "r"):
            points = vertices[query[side].vertices]
            out[f"{limb}_{side}"] = SinkTest(vertices, target[side], points, _SIDE_SIGN[side]).depth_m(points)
    return out
