"""The result of a body fit (:class:`BodyFit`): the measures of the fitted body, its view, its fit and its meshes."""

from __future__ import annotations

import os
from dataclasses import dataclass, field
from typing import Literal

import numpy as np

from wbsa.core.mesh import TriangleMesh


@dataclass(frozen=True)
class BodyFit:
    """One whole body fitted to one depth view, measured (SI units, angles in degrees).

    Attributes
    ----------
    wbsa_m2 : float
        Skin area of the fitted body at rest, measured as the population's ``wbsa_m2`` (anny's skin: the shell
        without eyeballs, tongue and the inner faces of eyes and mouth; fingers and toes included).
    wbsa_lo_m2, wbsa_hi_m2 : float
        The split-conformal interval of :mod:`wbsa.estimation.methods.body_fit.interval` (NaN when no calibration is stored).
    level : float
        Its coverage (NaN without one).
    stature_m, volume_m3, mass_kg, bmi : float
        Of the fitted body at rest; mass and BMI from the composition model of the settings
        (``BodyFitSettings.composition``; anny's constant 980 kg/m³ by default, as the population tables).
    tapes : dict of str to float
        The tape measures of :mod:`wbsa.bodies.anthropometry` (``waist_circ_m``, ``hip_circ_m`` ...), metres.
    sex : str
        ``male`` or ``female`` (anny's gender parameter below or above 0.5).
    age_years : float
        The fitted body's age (anny's age parameter read as years; a shape cue, not a birth date).
    parameters : dict of str to float
        The fitted anny parameters (``p_*`` phenotypes, ``l_*`` local changes), ready for a population table.
    posture_deg : dict of str to float
        The fitted posture (:data:`wbsa.bodies.posture.ANGLE_COLUMNS`), changes from the rest A-pose.
    azimuth_deg, elevation_deg, distance_m : float
        The view: azimuth in [0, 360) (0 = camera in front), elevation of the camera above the body's centre,
        camera centre to the fitted body's bounding-box centre.
    residual_m : float
        Robust RMS point-to-surface distance of the observed points to the fitted body (the RMS of the 90 %
        smallest point-to-plane distances).
    inlier_share : float
        Share of the observed points within 3 cm of the fitted surface.
    loss : float
        The fit's final objective (:mod:`wbsa.estimation.methods.body_fit.objective`).
    converged : bool
    flags : dict of str to str
        Named warnings (:data:`wbsa.estimation.flags.FLAGS`, route ``body-fit``); empty when every check passed.
    seconds : float
        Wall time of the fit (without loading anny, done once per process); in an estimate with named clothes,
        of both fits its route ran (as stated, and thicker by the clothes' uncertainty, which widens the interval
        given here).
    steps, restarts : int
    rest_vertices : (n, 3) float64
        The fitted body at rest (anny's frame: +Z up, facing −Y, standing on z = 0).
    posed_vertices : (n, 3) float64
        The fitted body as the camera saw it (camera frame: OpenCV axes, metres).
    faces : (m, 3) int32
        The skin triangles (both meshes).
    """

    wbsa_m2: float
    wbsa_lo_m2: float
    wbsa_hi_m2: float
    level: float
    stature_m: float
    volume_m3: float
    mass_kg: float
    bmi: float
    tapes: dict[str, float]
    sex: str
    age_years: float
    parameters: dict[str, float]
    posture_deg: dict[str, float]
    azimuth_deg: float
    elevation_deg: float
    distance_m: float
    residual_m: float
    inlier_share: float
    loss: float
    converged: bool
    flags: dict[str, str]
    seconds: float
    steps: int
    restarts: int
    rest_vertices: np.ndarray = field(repr=False, compare=False)
    posed_vertices: np.ndarray = field(repr=False, compare=False)
    faces: np.ndarray = field(repr=False, compare=False)

    def __repr__(self) -> str:
        flags = f", flags: {', '.join(self.flags)}" if self.flags else ""
        interval = (f" [{self.wbsa_lo_m2:.3f}–{self.wbsa_hi_m2:.3f}, {100 * self.level:.0f} %]"
                    if self.level == self.level else "")
        return (f"BodyFit(WBSA {self.wbsa_m2:.3f} m²{interval}, stature {self.stature_m:.3f} m, mass {self.mass_kg:.1f} kg, "
                f"{self.sex}, azimuth {self.azimuth_deg:.0f}°, residual {1000 * self.residual_m:.1f} mm, "
                f"{self.seconds:.1f} s{flags})")

    def mesh(self, pose: Literal["rest", "observed"] = "rest") -> TriangleMesh:
        """The fitted skin at rest (body frame) or in the observed pose (camera frame).

        Parameters
        ----------
        pose : {'rest', 'observed'}
        """
        from wbsa.errors import WbsaError

        if pose not in ("rest", "observed"):
            raise WbsaError(f"pose {pose!r} is unknown; use 'rest' or 'observed'")
        return TriangleMesh(self.rest_vertices if pose == "rest" else self.posed_vertices, self.faces)

    def write_ply(self, path: str | os.PathLike, pose: Literal["rest", "observed"] = "rest"):
        """Write :meth:`mesh` as a binary PLY (atomically, checked; :func:`wbsa.core.mesh_io.write_mesh`).

        Parameters
        ----------
        path : str or path
        pose : {'rest', 'observed'}
        """
        from wbsa.core.mesh_io import write_mesh

        return write_mesh(self.mesh(pose), path)

    def to_dict(self) -> dict:
        """JSON-ready measures, view, fit and flags (without the meshes)."""
        out = {k: getattr(self, k) for k in ("wbsa_m2", "wbsa_lo_m2", "wbsa_hi_m2", "level", "stature_m", "volume_m3", "mass_kg", "bmi", "sex", "age_years",
                                             "azimuth_deg", "elevation_deg", "distance_m", "residual_m", "inlier_share",
                                             "loss", "converged", "seconds", "steps", "restarts")}
        out = {k: (None if isinstance(v, float) and v != v else round(v, 6) if isinstance(v, float) else v)
               for k, v in out.items()}
        for name in ("tapes", "parameters", "posture_deg"):
            out[name] = {k: round(float(v), 6) for k, v in getattr(self, name).items()}
        out["flags"] = dict(self.flags)
        return out
