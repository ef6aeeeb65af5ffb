"""Virtual bodies from anny phenotype parameters, skin-only, standing on z = 0.

anny (MakeHuman-based, PyTorch) turns phenotype parameters in [0, 1] into a mesh of
13,718 vertices and 27,420 triangles in its rest A-pose. That mesh holds more than skin:
two eyeballs, the tongue, and the eye sockets and mouth folded inward to close the shell.
WBSA is the *skin* area, so :class:`BodyModel` exposes two face masks:

* ``skin_face_mask``: the shell without eyeballs, tongue and the inner cavity faces
  (a triangle is a cavity face when its three vertices are listed in anny's
  ``template_mesh_internal_cavities.pth``); this is the surface that is measured and
  that the camera casts rays against;
* ``closed_face_mask``: skin plus cavities, a closed surface whose enclosed volume
  gives the body volume (and mass).

Besides the phenotypes, a body has seven anny *local changes* (MakeHuman's measure and
shape modifiers): four of the trunk (:data:`LOCAL_CHANGES`: waist, hips, belly, buttocks) and three
of the limbs (:data:`LIMB_CHANGES`: upper-arm girth and length, upper-leg length), stored in tables
as the ``l_*`` columns (:data:`ALL_LOCAL_CHANGE_COLUMNS`), each in [−1, 1] with 0 = no change (anny
applies the modifier's ``incr`` target for positive values and its ``decr`` target for negative
ones). The phenotypes alone cannot give real people's waist, hip and limbs at their stature and
mass; the survey matcher fits the local changes too (``docs/survey.md``). With every local change 0
a body is the phenotype-only body.

A body stands in anny's rest A-pose unless its table row has posture columns
(``wbsa population --posture``): then :meth:`BodyModel.skin_meshes` poses it by skinning
(:mod:`wbsa.bodies.posture`, :mod:`wbsa.bodies.posing`); every measure, WBSA included, is taken at rest.

The first ``anny.Anny()`` with this configuration in a fresh cache builds its data (60–120 s,
about 0.8 GB cached in ``ANNY_CACHE_DIR``, default ``~/.cache/anny``); later builds are fast.
"""

from __future__ import annotations

import functools
import warnings
from dataclasses import dataclass

import numpy as np
import pandas as pd

from wbsa.errors import WbsaError
from wbsa.core.mesh import TriangleMesh

#: Phenotype columns of a population table, in anny's order (``p_`` + anny label).
PHENOTYPE_COLUMNS = (
    "p_gender",
    "p_age",
    "p_muscle",
    "p_weight",
    "p_height",
    "p_proportions",
    "p_cupsize",
    "p_firmness",
    "p_african",
    "p_asian",
    "p_caucasian",
)
#: Columns that may be absent from a table; they default to 0.5 (anny's neutral value).
OPTIONAL_PHENOTYPES = ("p_cupsize", "p_firmness")
#: anny local changes the model is built with (MakeHuman modifiers, ``incr``/``decr`` target pairs).
LOCAL_CHANGES = ("measure-waist-circ-incr", "measure-hips-circ-incr", "stomach-pregnant-incr",
                 "buttocks-volume-incr")
#: Table columns of :data:`LOCAL_CHANGES`, same order; optional, in [-1, 1], default 0 (no change).
LOCAL_CHANGE_COLUMNS = ("l_waist_circ", "l_hips_circ", "l_stomach_pregnant", "l_buttocks_volume")
#: anny local changes of the limbs (symmetric MakeHuman measure modifiers): upper-arm girth and length,
#: upper-leg length. The survey matcher fits them to NHANES's arm and leg measures; 0 elsewhere.
LIMB_CHANGES = ("measure-upperarm-circ-incr", "measure-upperarm-length-incr", "measure-upperleg-height-incr")
#: Table columns of :data:`LIMB_CHANGES`, same order; optional, in [-1, 1], default 0 (no change).
LIMB_CHANGE_COLUMNS = ("l_upperarm_circ", "l_upperarm_length", "l_upperleg_height")
#: Every local-change column: the trunk's (:data:`LOCAL_CHANGE_COLUMNS`) then the limbs'.
ALL_LOCAL_CHANGE_COLUMNS = (*LOCAL_CHANGE_COLUMNS, *LIMB_CHANGE_COLUMNS)
_ALL_LOCAL_CHANGES = (*LOCAL_CHANGES, *LIMB_CHANGES)
#: Every body parameter: phenotypes then local changes (the columns of :func:`body_parameter_array`).
BODY_PARAMETER_COLUMNS = (*PHENOTYPE_COLUMNS, *ALL_LOCAL_CHANGE_COLUMNS)
_EYES_AND_TONGUE = ("eye_front.L", "eye_front.R", "eye_back.L", "eye_back.R", "tongue")
_ARM_BONE_PREFIXES = ("shoulder01", "upperarm", "lowerarm", "wrist", "finger", "metacarpal")


@functools.lru_cache(maxsize=1)
def load_anny():
    """The anny full-body model with all phenotypes, :data:`LOCAL_CHANGES` and :data:`LIMB_CHANGES`, built once.

    The local changes let a body's waist, hip, belly, buttocks, upper arms and thighs differ from
    what the phenotypes give (the survey matcher needs them to reach real people's measures);
    they add 14 blendshapes and cost nothing when 0.

    Returns
    -------
    anny.Anny
    """
    import torch  # noqa: F401  (anny needs it; import here so the CLI starts fast)

    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        import anny

        # plain LBS: wbsa uses only rest shapes, and this keeps NVIDIA Warp (and its banner) out
        return anny.Anny(phenotypes="all", skinning_method="lbs", local_changes=list(_ALL_LOCAL_CHANGES))


def phenotype_array(params: pd.DataFrame | dict) -> np.ndarray:
    """Phenotype parameters as a ``(b, 11)`` float64 array in anny's order (:data:`PHENOTYPE_COLUMNS`).

    Missing optional columns (``p_cupsize``, ``p_firmness``) take 0.5.

    Raises
    ------
    WbsaError
        If a required column is missing or a value is outside [0, 1] or not finite.
    """
    df = pd.DataFrame(params) if not isinstance(params, pd.DataFrame) else params
    cols = []
    for name in PHENOTYPE_COLUMNS:
        if name in df.columns:
            cols.append(df[name].to_numpy(dtype=np.float64))
        elif name in OPTIONAL_PHENOTYPES:
            cols.append(np.full(len(df), 0.5))
        else:
            raise WbsaError(f"phenotype column {name} is missing; a population table needs "
                            f"{', '.join(PHENOTYPE_COLUMNS[:6])}, ...")
    return _checked_range(np.stack(cols, axis=1), PHENOTYPE_COLUMNS, 0.0, "phenotype",
                          "anny parameters are normalised to [0, 1]")


def local_change_array(params: pd.DataFrame | dict) -> np.ndarray:
    """Local changes as a ``(b, 7)`` float64 array in :data:`ALL_LOCAL_CHANGE_COLUMNS` order.

    Missing columns take 0 (no change), so tables written before the local changes existed
    still give the same bodies.

    Raises
    ------
    WbsaError
        If a value is outside [-1, 1] or not finite.
    """
    df = pd.DataFrame(params) if not isinstance(params, pd.DataFrame) else params
    cols = [df[name].to_numpy(dtype=np.float64) if name in df.columns else np.zeros(len(df))
            for name in ALL_LOCAL_CHANGE_COLUMNS]
    return _checked_range(np.stack(cols, axis=1), ALL_LOCAL_CHANGE_COLUMNS, -1.0, "local change",
                          "local changes are -1 (decrease) to 1 (increase), 0 = no change")


def _checked_range(arr: np.ndarray, names: tuple[str, ...], low: float, what: str, why: str) -> np.ndarray:
    """``arr`` (b, k) unchanged if every value is finite and in [low, 1], else a one-line WbsaError."""
    bad = ~np.isfinite(arr) | (arr < low) | (arr > 1.0)
    if bad.any():
        row, col = np.argwhere(bad)[0]
        raise WbsaError(f"{what} {names[col]} = {float(arr[row, col])!r} in row {row} is outside "
                        f"[{low:g}, 1]; {why}")
    return arr


def body_parameter_array(params: pd.DataFrame | dict) -> np.ndarray:
    """Phenotypes and local changes, ``(b, 18)`` float64 in :data:`BODY_PARAMETER_COLUMNS` order.

    See :func:`phenotype_array` and :func:`local_change_array` (defaults and validation).
    """
    return np.concatenate([phenotype_array(params), local_change_array(params)], axis=1)


@dataclass(frozen=True)
class RestBodies:
    """A batch of bodies in rest pose, shifted to stand on z = 0.

    Attributes
    ----------
    vertices : (b, n, 3) float64
        Vertex positions in metres.
    bone_heads : (b, j, 3) float64
        Joint (bone head) positions in metres, same frame.
    """

    vertices: np.ndarray
    bone_heads: np.ndarray

    def __len__(self) -> int:
        return self.vertices.shape[0]

    def __repr__(self) -> str:
        b, n = self.vertices.shape[:2]
        return (f"RestBodies({b:,} {'body' if b == 1 else 'bodies'} × {n:,} vertices, "
                f"{self.bone_heads.shape[1]} bone heads, metres)")


class BodyModel:
    """Build skin meshes and their helpers from phenotype parameters.

    Parameters
    ----------
    batch_size
        Bodies per anny forward pass.
    """

    def __init__(self, batch_size: int = 64):
        import torch

        self._torch = torch
        self.batch_size = int(batch_size)
        self.anny = load_anny()
        self.faces = self.anny.faces.detach().cpu().numpy().astype(np.int32)
        self.phenotype_labels = tuple(self.anny.phenotype_labels)
        expected = tuple(c[2:] for c in PHENOTYPE_COLUMNS)
        if self.phenotype_labels != expected:
            raise WbsaError(f"unsupported anny phenotypes {self.phenotype_labels}; install anny==0.6.2")
        labels = tuple(self.anny.local_change_labels)
        if sorted(labels) != sorted(_ALL_LOCAL_CHANGES):
            raise WbsaError(f"unsupported anny local changes {labels}; install anny==0.6.2")
        #: anny's local-change order as indices into :data:`ALL_LOCAL_CHANGE_COLUMNS`
        self._local_order = [_ALL_LOCAL_CHANGES.index(label) for label in labels]
        self.bone_labels = tuple(self.anny.bone_labels)
        self.skin_face_mask, self.closed_face_mask = _face_masks(self.anny, self.faces)
        self.skin_faces = self.faces[self.skin_face_mask]
        self.closed_faces = self.faces[self.closed_face_mask]
        weights = self.anny.vertex_bone_weights.detach().cpu().numpy()
        indices = self.anny.vertex_bone_indices.detach().cpu().numpy()
        #: (n,) int: the bone that moves each vertex most (used to segment limbs and trunk)
        self.vertex_bone = indices[np.arange(len(indices)), weights.argmax(axis=1)]

    #: see :func:`phenotype_array`
    phenotype_array = staticmethod(phenotype_array)

    def __repr__(self) -> str:
        return (f"BodyModel(anny: {len(self.vertex_bone):,} vertices, {len(self.faces):,} faces "
                f"({len(self.skin_faces):,} skin), {len(self.phenotype_labels)} phenotypes, "
                f"{len(self._local_order)} local changes, {len(self.bone_labels)} bones; "
                f"batch_size {self.batch_size})")

    def coefficients(self, params):
        """anny blendshape coefficients ``(b, k)`` of body parameters (torch, differentiable).

        Parameters
        ----------
        params : (b, 11), (b, 15) or (b, 18) torch tensor
            Phenotypes in :data:`PHENOTYPE_COLUMNS` order, optionally followed by the trunk's local
            changes (:data:`LOCAL_CHANGE_COLUMNS`) and the limbs' (:data:`LIMB_CHANGE_COLUMNS`);
            absent ones are 0.
        """
        torch = self._torch
        model = self.anny
        n_ph = len(PHENOTYPE_COLUMNS)
        ph = params[:, :n_ph]
        local = params[:, n_ph:]
        missing = len(_ALL_LOCAL_CHANGES) - local.shape[1]
        if missing not in (0, len(LIMB_CHANGES), len(_ALL_LOCAL_CHANGES)):
            raise WbsaError(f"body parameters have {params.shape[1]} columns; expected {n_ph}, "
                            f"{n_ph + len(LOCAL_CHANGES)} or {n_ph + len(_ALL_LOCAL_CHANGES)}")
        if missing:
            local = torch.cat([local, torch.zeros((params.shape[0], missing), dtype=params.dtype)], dim=1)
        local = local[:, self._local_order]
        empty = torch.empty((params.shape[0], 0), dtype=params.dtype)
        return model._get_phenotype_blendshape_coefficients(ph, local, empty)

    # -- geometry -----------------------------------------------------------------------
    def rest_bodies(self, params: pd.DataFrame | dict) -> RestBodies:
        """Rest-pose vertices and joints of every body, standing on z = 0.

        Parameters
        ----------
        params
            Table with the ``p_*`` phenotype columns and optionally the ``l_*`` local
            changes (:data:`ALL_LOCAL_CHANGE_COLUMNS`, default 0), one row per body.
        """
        arr = body_parameter_array(params)
        torch = self._torch
        model = self.anny
        import anny.skinning.skinning as skinning

        verts, heads = [], []
        with torch.no_grad():
            for start in range(0, len(arr), self.batch_size):
                coeffs = self.coefficients(torch.as_tensor(arr[start:start + self.batch_size], dtype=model.dtype))
                verts.append(model.get_rest_vertices(coeffs).numpy())
                heads.append(skinning.apply_linear_blendshape(
                    model.template_bone_heads, model.bone_heads_blendshapes, coeffs).numpy())
        if not verts:
            n = model.template_vertices.shape[0]
            return RestBodies(np.zeros((0, n, 3)), np.zeros((0, len(self.bone_labels), 3)))
        v = np.concatenate(verts).astype(np.float64)
        h = np.concatenate(heads).astype(np.float64)
        floor = v[:, :, 2].min(axis=1)[:, None]
        v[:, :, 2] -= floor
        h[:, :, 2] -= floor
        return RestBodies(v, h)

    def skin_meshes(self, params: pd.DataFrame | dict) -> list[TriangleMesh]:
        """Skin-only triangle meshes, one per row of ``params``, as the rows stand (see :meth:`posed_vertices`)."""
        return [TriangleMesh(v, self.skin_faces) for v in self.posed_vertices(params)]

    def posed_vertices(self, params: pd.DataFrame | dict) -> np.ndarray:
        """Every body in its table row's posture, standing on z = 0.

        Parameters
        ----------
        params
            As for :meth:`rest_bodies`, optionally with the posture angle columns
            (:data:`wbsa.bodies.posture.ANGLE_COLUMNS`, written by ``wbsa population --posture``).

        Returns
        -------
        (b, n, 3) float64
            Without posture columns, or for a row whose angles are all 0: the rest vertices, bit for bit.
            Otherwise the body posed by :func:`wbsa.bodies.posing.pose_vertices` with the row's angles.
        """
        from wbsa.bodies.posing import pose_vertices
        from wbsa.bodies.posture import posture_angles

        table = params if isinstance(params, pd.DataFrame) else pd.DataFrame(params)
        angles = posture_angles(table)
        bodies = self.rest_bodies(table)
        if angles is None:
            return bodies.vertices
        return np.stack([pose_vertices(v, h, a, self.rig)
                         for v, h, a in zip(bodies.vertices, bodies.bone_heads, angles)]).reshape(bodies.vertices.shape)

    @functools.cached_property
    def rig(self):
        """The :class:`wbsa.bodies.posing.Rig` of this model (skeleton and skinning weights for posing)."""
        from wbsa.bodies.posing import Rig

        return Rig.from_model(self)

    def skin_mesh(self, vertices: np.ndarray) -> TriangleMesh:
        """The skin mesh over one body's ``(n, 3)`` vertices."""
        return TriangleMesh(vertices, self.skin_faces)

    def bone_index(self, label: str) -> int:
        """Index of the bone named ``label`` (e.g. ``"upperarm01.L"``)."""
        return self.bone_labels.index(label)

    def vertices_of_bones(self, prefixes: tuple[str, ...]) -> np.ndarray:
        """(n,) bool: vertices whose dominant bone name starts with one of ``prefixes``."""
        chosen = [i for i, b in enumerate(self.bone_labels) if b.startswith(prefixes)]
        return np.isin(self.vertex_bone, chosen)

    @property
    def trunk_vertex_mask(self) -> np.ndarray:
        """(n,) bool: vertices not moved mainly by an arm or hand bone."""
        return ~self.vertices_of_bones(_ARM_BONE_PREFIXES)


def _face_masks(model, faces: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Skin-only and closed-shell face masks, each ``(m,) bool``."""
    import anny
    import torch
    from anny.face_segmentation import get_face_segmentation_mask

    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        eyes_tongue = get_face_segmentation_mask(model, list(_EYES_AND_TONGUE))
    eyes_tongue = np.asarray(eyes_tongue.cpu().numpy() if hasattr(eyes_tongue, "cpu") else eyes_tongue, dtype=bool)
    path = f"{anny.__path__[0]}/data/template_mesh_internal_cavities.pth"
    cav = torch.load(path, weights_only=False)
    base = model.base_mesh_vertex_indices.detach().cpu().numpy()
    cavity_vertex = np.isin(base, np.asarray(cav["vertex_indices"]))
    cavity_face = cavity_vertex[faces].all(axis=1)
    closed = ~eyes_tongue
    skin = closed & ~cavity_face
    return skin, closed
