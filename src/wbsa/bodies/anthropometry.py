"""Anthropometric measures of virtual bodies: stature, mass, BMI, WBSA and tape measures.

Tape measures follow the paper's Table 2 (waist, hip, bust, underbust, neck, upper arm and
thigh circumferences, front chest width). A circumference is the perimeter of the convex
hull of a cross-section of one body part, exactly as a tape pulled around the body:

========================  ==========================================================================
measure                    plane (landmarks are template vertices or joints, so they follow every body)
========================  ==========================================================================
``waist_circ_m``          horizontal, at the mean height of anny's own waist vertex ring; trunk only
``hip_circ_m``            horizontal, at the most backward buttock vertex of a reference adult male
``bust_circ_m``           horizontal, at the most forward chest vertex (nipple) of a reference adult female
``underbust_circ_m``      horizontal, at the inframammary fold under that vertex (reference female)
``neck_circ_m``           perpendicular to the neck, 35 % of the way from the neck base to the head joint
``upper_arm_circ_m``      left arm, perpendicular to the upper arm at mid shoulder–elbow
``thigh_circ_m``          left leg, perpendicular to the thigh at mid hip–knee
``front_chest_width_m``   left–right extent of the front half of the trunk section half-way between
                          the bust and shoulder joint heights
``mid_arm_circ_m``        NHANES arm circumference (BMXARMC): right upper arm, perpendicular to the
                          acromion–olecranon line at its midpoint
``upper_arm_length_m``    NHANES upper arm length (BMXARML): acromion to olecranon, right arm
``upper_leg_length_m``    NHANES upper leg length (BMXLEG): inguinal crease to the proximal border of
                          the patella, right leg
========================  ==========================================================================

The last three follow the NHANES Anthropometry Procedures Manual (CDC/NCHS, 2017, sections on upper
leg length, upper arm length and arm circumference). Their landmarks are template vertices picked once
on the reference adult male (:class:`Landmarks`): the *acromion* is the highest skin vertex within
3 cm (horizontally) of the right shoulder joint; the *olecranon* the most backward arm vertex within
1.5 cm of the plane through the elbow joint perpendicular to the upper arm; the *inguinal crease* the
most forward skin vertex within 1.5 cm of the hip joint's left–right position and height (the mid-
inguinal point lies in front of the femoral head); the *patella* the most forward leg vertex within
1 cm of the plane through the knee joint perpendicular to the thigh and 4 cm of the knee's left–right
position. NHANES measures the arm length with the elbow bent at 90°: the olecranon tip, which lies behind
the elbow joint in the straight rest arm, then points down the arm's axis. :func:`nhanes_arm` places it
there (at the same distance from the elbow joint, along the shoulder → elbow joint line); the length is
the straight distance from the acromion to it, and the arm circumference is taken in the plane
perpendicular to that line through the midpoint of the two marks. The leg length (NHANES: seated, knee at
90°) is the straight distance between the inguinal and patella vertices of the standing body.

Trunk sections exclude arm and hand triangles (by each vertex's dominant skinning bone), so
the A-pose arms never enter a waist or hip tape. Limb tapes are perpendicular to the limb,
as a tape is applied, rather than horizontal: in the A-pose the upper arm hangs about 40°
from vertical and a horizontal cut would overstate its girth by ~30 %.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import pandas as pd

from wbsa.bodies.body_model import PHENOTYPE_COLUMNS, BodyModel, RestBodies
from wbsa.core.mesh import face_cross_products
from wbsa.bodies.sections import HorizontalSlicer, edge_plane_crossings, tape_perimeter_m, width_along_m
from wbsa.bodies.settings import DEFAULT_DENSITY_KG_M3  # noqa: F401 - re-exported (defined with the population settings)

#: Columns :func:`measure` returns, in order.
MEASURE_COLUMNS = (
    "stature_m",
    "volume_m3",
    "mass_kg",
    "bmi",
    "wbsa_m2",
    "waist_circ_m",
    "hip_circ_m",
    "bust_circ_m",
    "underbust_circ_m",
    "neck_circ_m",
    "upper_arm_circ_m",
    "thigh_circ_m",
    "front_chest_width_m",
    "mid_arm_circ_m",
    "upper_arm_length_m",
    "upper_leg_length_m",
)
#: The NHANES limb measures (BMXARMC, BMXARML, BMXLEG) among :data:`MEASURE_COLUMNS`; tables written
#: before they existed lack them (:data:`REQUIRED_MEASURE_COLUMNS` are the others).
NHANES_LIMB_COLUMNS = ("mid_arm_circ_m", "upper_arm_length_m", "upper_leg_length_m")
#: The measures every population table has.
REQUIRED_MEASURE_COLUMNS = tuple(c for c in MEASURE_COLUMNS if c not in NHANES_LIMB_COLUMNS)

_UP = np.array([0.0, 0.0, 1.0])
#: The mid-arm section keeps the crossings within this fraction of the upper arm length of its centre
#: (so no trunk edge enters the tape).
ARM_SECTION_RADIUS = 0.6


def reference_adult(gender: float) -> pd.DataFrame:
    """Phenotypes of a neutral ~33-year-old adult (gender 0 male, 1 female), one row."""
    row = {c: 0.5 for c in PHENOTYPE_COLUMNS}
    row.update(p_gender=gender, p_age=0.79, p_african=1 / 3, p_asian=1 / 3, p_caucasian=1 / 3)
    return pd.DataFrame([row])


@dataclass(frozen=True)
class Landmarks:
    """Template-defined landmarks and body-part edge sets, fixed for a :class:`BodyModel`.

    Attributes
    ----------
    waist_ring : (k,) int
        anny's waist vertex ring (model vertex indices).
    bust, underbust, hip : int
        Vertex indices whose height sets the horizontal bust / underbust / hip planes.
    trunk_edges, upper_arm_edges, thigh_edges : PartEdges
        Unique skin edges of each body part.
    neck_base, head, shoulder, elbow, hip_joint, knee : int
        Bone indices whose heads (joints) place the neck and limb planes.
    acromion, olecranon, inguinal, patella : int
        Vertex indices of the NHANES landmarks (right side, see the module docstring).
    right_shoulder, right_elbow : int
        Bone indices of the right upper arm's joints (the NHANES arm axis).
    right_upper_arm_edges : PartEdges
        Unique skin edges of the right upper arm (the NHANES arm circumference).
    """

    waist_ring: np.ndarray
    bust: int
    underbust: int
    hip: int
    trunk_edges: "PartEdges"
    upper_arm_edges: "PartEdges"
    thigh_edges: "PartEdges"
    neck_base: int
    head: int
    shoulder: int
    elbow: int
    hip_joint: int
    knee: int
    acromion: int
    olecranon: int
    inguinal: int
    patella: int
    right_shoulder: int
    right_elbow: int
    right_upper_arm_edges: "PartEdges"

    @classmethod
    def from_model(cls, model: BodyModel) -> "Landmarks":
        """Pick the landmarks once, on reference adult bodies of ``model``."""
        from anny.anthropometry import BASE_MESH_WAIST_VERTICES

        base = model.anny.base_mesh_vertex_indices.detach().cpu().numpy()
        lookup = {int(b): i for i, b in enumerate(base)}
        waist_ring = np.array([lookup[i] for i in BASE_MESH_WAIST_VERTICES])

        trunk = model.trunk_vertex_mask
        female = model.rest_bodies(reference_adult(1.0)).vertices[0]
        male = model.rest_bodies(reference_adult(0.0)).vertices[0]

        h = female[:, 2].max()
        band = trunk & (female[:, 0] > 0.02) & (female[:, 2] > 0.65 * h) & (female[:, 2] < 0.80 * h)
        bust = int(np.flatnonzero(band)[np.argmin(female[band, 1])])
        xb, zb = female[bust, 0], female[bust, 2]
        fold = (trunk & (np.abs(female[:, 0] - xb) < 0.015) & (female[:, 2] > zb - 0.10)
                & (female[:, 2] < zb - 0.03) & (female[:, 1] < female[trunk, 1].mean()))
        underbust = int(np.flatnonzero(fold)[np.argmax(female[fold, 1])])

        hm = male[:, 2].max()
        seat = trunk & (male[:, 2] > 0.42 * hm) & (male[:, 2] < 0.56 * hm)
        hip = int(np.flatnonzero(seat)[np.argmax(male[seat, 1])])

        faces = model.skin_faces
        nhanes = _nhanes_landmarks(model, male)
        return cls(
            waist_ring=waist_ring,
            bust=bust,
            underbust=underbust,
            hip=hip,
            trunk_edges=_part_edges(faces, trunk),
            upper_arm_edges=_part_edges(faces, model.vertices_of_bones(("upperarm01.L", "upperarm02.L"))),
            thigh_edges=_part_edges(faces, model.vertices_of_bones(("upperleg01.L", "upperleg02.L"))),
            neck_base=model.bone_index("neck01"),
            head=model.bone_index("head"),
            shoulder=model.bone_index("upperarm01.L"),
            elbow=model.bone_index("lowerarm01.L"),
            hip_joint=model.bone_index("upperleg01.L"),
            knee=model.bone_index("lowerleg01.L"),
            **nhanes,
            right_shoulder=model.bone_index("upperarm01.R"),
            right_elbow=model.bone_index("lowerarm01.R"),
            right_upper_arm_edges=_part_edges(faces, model.vertices_of_bones(("upperarm01.R", "upperarm02.R"))),
        )


def _nhanes_landmarks(model: BodyModel, male: np.ndarray) -> dict[str, int]:
    """Vertex indices of the NHANES landmarks, picked on the reference male's ``(n, 3)`` vertices."""
    joints = model.rest_bodies(reference_adult(0.0)).bone_heads[0]
    skin = np.zeros(len(male), dtype=bool)
    skin[np.unique(model.skin_faces)] = True
    v = male
    shoulder, elbow = joints[model.bone_index("upperarm01.R")], joints[model.bone_index("lowerarm01.R")]
    hip, knee = joints[model.bone_index("upperleg01.R")], joints[model.bone_index("lowerleg01.R")]

    def pick(mask: np.ndarray, score: np.ndarray) -> int:
        return int(np.flatnonzero(mask)[np.argmax(score[mask])])

    top = skin & (np.hypot(v[:, 0] - shoulder[0], v[:, 1] - shoulder[1]) < 0.03) & (v[:, 2] > shoulder[2])
    arm_axis = (elbow - shoulder) / np.linalg.norm(elbow - shoulder)
    arm = skin & model.vertices_of_bones(("upperarm", "lowerarm")) & (np.abs((v - elbow) @ arm_axis) < 0.015)
    groin = skin & (np.abs(v[:, 0] - hip[0]) < 0.015) & (np.abs(v[:, 2] - hip[2]) < 0.015)
    leg_axis = (knee - hip) / np.linalg.norm(knee - hip)
    front_knee = (skin & model.vertices_of_bones(("upperleg", "lowerleg")) & (np.abs((v - knee) @ leg_axis) < 0.01)
                  & (np.abs(v[:, 0] - knee[0]) < 0.04))
    # +y is backwards (anny faces −y)
    return {"acromion": pick(top, v[:, 2]), "olecranon": pick(arm, v[:, 1]),
            "inguinal": pick(groin, -v[:, 1]), "patella": pick(front_knee, -v[:, 1])}


@dataclass(frozen=True)
class PartEdges:
    """The unique skin edges of one body part, over the part's own vertices.

    Attributes
    ----------
    vertex_ids : (p,) int
        Model vertex indices of the part.
    edges : (e, 2) int
        Edges as indices into ``vertex_ids``.
    """

    vertex_ids: np.ndarray
    edges: np.ndarray


def nhanes_arm(olecranon, shoulder, elbow):
    """The olecranon tip of the elbow bent at 90° and the upper arm's unit axis (numpy or torch).

    Parameters
    ----------
    olecranon : (..., 3) float64
        The olecranon vertex of the straight rest arm.
    shoulder, elbow : (..., 3) float64
        The right shoulder and elbow joints.

    Returns
    -------
    tip : (..., 3) float64
        The elbow joint moved down the arm's axis by its distance to the olecranon vertex.
    axis : (..., 3) float64
        Unit vector from shoulder to elbow joint.
    """
    arm = elbow - shoulder
    axis = arm / ((arm**2).sum(axis=-1, keepdims=True)) ** 0.5
    r = (((olecranon - elbow) ** 2).sum(axis=-1, keepdims=True)) ** 0.5
    return elbow + r * axis, axis


def _part_edges(faces: np.ndarray, vertex_mask: np.ndarray) -> PartEdges:
    """Edges of the faces whose three vertices are all in ``vertex_mask`` (n,) bool."""
    part = faces[vertex_mask[faces].all(axis=1)]
    edges = np.unique(np.sort(np.concatenate([part[:, [0, 1]], part[:, [1, 2]], part[:, [2, 0]]]), axis=1), axis=0)
    ids, local = np.unique(edges, return_inverse=True)
    return PartEdges(ids, local.reshape(edges.shape))


def closed_volume_m3(vertices: np.ndarray, faces: np.ndarray) -> float:
    """Volume enclosed by a closed, consistently oriented triangle mesh (divergence theorem).

    Parameters
    ----------
    vertices : (n, 3) float64
    faces : (m, 3) int
    """
    cross, a = face_cross_products(vertices, faces)
    return _volume_from(cross, a)


def _volume_from(cross: np.ndarray, a: np.ndarray) -> float:
    """Σ a · ((b − a) × (c − a)) / 6 = Σ a · (b × c) / 6 over the triangles."""
    return float(abs((a * cross).sum()) / 6.0)


class Anthropometer:
    """Measures batches of bodies from one :class:`BodyModel`.

    Parameters
    ----------
    model
        The body model whose topology the landmarks refer to.
    density_kg_m3
        Body density used for mass = volume × density (default 980 kg/m³, as anny).
    """

    def __init__(self, model: BodyModel, density_kg_m3: float = DEFAULT_DENSITY_KG_M3):
        if not density_kg_m3 > 0:
            from wbsa.errors import WbsaError

            raise WbsaError(f"density {density_kg_m3} kg/m³ must be positive (human tissue is ~950–1100)")
        self.model = model
        self.density_kg_m3 = float(density_kg_m3)
        self.landmarks = Landmarks.from_model(model)
        #: (closed,) bool: which closed-shell triangles are skin (skin faces are the closed ones minus cavities)
        self._skin_in_closed = model.skin_face_mask[model.closed_face_mask]

    def __repr__(self) -> str:
        return f"Anthropometer(density {self.density_kg_m3:g} kg/m³, {self.model!r})"

    def measure(self, bodies: RestBodies) -> pd.DataFrame:
        """One row of :data:`MEASURE_COLUMNS` per body, SI units."""
        rows = [self.measure_one(v, j) for v, j in zip(bodies.vertices, bodies.bone_heads)]
        return pd.DataFrame(rows, columns=list(MEASURE_COLUMNS))

    def measure_one(self, v: np.ndarray, joints: np.ndarray) -> dict[str, float]:
        """Measures of one body from its ``(n, 3)`` vertices and ``(j, 3)`` joints."""
        lm = self.landmarks
        stature = float(v[:, 2].max() - v[:, 2].min())
        cross, corner = face_cross_products(v, self.model.closed_faces)  # skin faces are a subset
        volume = _volume_from(cross, corner)
        skin = cross[:, self._skin_in_closed]
        wbsa = float(0.5 * np.sqrt((skin * skin).sum(axis=0)).sum())
        mass = volume * self.density_kg_m3
        trunk_v = v[lm.trunk_edges.vertex_ids]  # gathered once for the five trunk tapes and the neck
        horizontal = HorizontalSlicer(trunk_v, lm.trunk_edges.edges).points

        def girth(z: float) -> float:
            return tape_perimeter_m(horizontal(z), _UP)

        def limb(edges: PartEdges, a: int, b: int, at: float = 0.5, min_radius_m: float = 0.0,
                 part_v: np.ndarray | None = None) -> float:
            # joints lie near the limb's axis (the neck's near the spine, at its back): keep
            # the section points within reach of the joint so no other part enters the tape
            direction = joints[b] - joints[a]
            middle = joints[a] + at * direction
            radius = max(0.6 * np.linalg.norm(direction), min_radius_m)
            pv = v[edges.vertex_ids] if part_v is None else part_v
            pts = edge_plane_crossings(pv, edges.edges, middle, direction)
            pts = pts[np.linalg.norm(pts - middle, axis=1) < radius]
            return tape_perimeter_m(pts, direction)

        acromion = v[lm.acromion]
        olecranon, arm_axis = nhanes_arm(v[lm.olecranon], joints[lm.right_shoulder], joints[lm.right_elbow])
        arm_length = float(np.linalg.norm(olecranon - acromion))
        mid = 0.5 * (acromion + olecranon)
        arm_pts = edge_plane_crossings(v[lm.right_upper_arm_edges.vertex_ids], lm.right_upper_arm_edges.edges, mid,
                                       arm_axis)
        arm_pts = arm_pts[np.linalg.norm(arm_pts - mid, axis=1) < ARM_SECTION_RADIUS * arm_length]
        z_chest = 0.5 * (v[lm.bust, 2] + joints[lm.shoulder, 2])
        chest = horizontal(z_chest)
        front = chest[chest[:, 1] < chest[:, 1].mean()] if len(chest) else chest
        return {
            "stature_m": stature,
            "volume_m3": volume,
            "mass_kg": mass,
            "bmi": mass / stature**2,
            "wbsa_m2": wbsa,
            "waist_circ_m": girth(v[lm.waist_ring, 2].mean()),
            "hip_circ_m": girth(v[lm.hip, 2]),
            "bust_circ_m": girth(v[lm.bust, 2]),
            "underbust_circ_m": girth(v[lm.underbust, 2]),
            "neck_circ_m": limb(lm.trunk_edges, lm.neck_base, lm.head, at=0.35, min_radius_m=0.12, part_v=trunk_v),
            "upper_arm_circ_m": limb(lm.upper_arm_edges, lm.shoulder, lm.elbow),
            "thigh_circ_m": limb(lm.thigh_edges, lm.hip_joint, lm.knee),
            "front_chest_width_m": width_along_m(front, np.array([1.0, 0.0, 0.0])),
            "mid_arm_circ_m": tape_perimeter_m(arm_pts, arm_axis),
            "upper_arm_length_m": arm_length,
            "upper_leg_length_m": float(np.linalg.norm(v[lm.inguinal] - v[lm.patella])),
        }
