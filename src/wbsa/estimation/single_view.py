"""WBSA from one depth image: segment, reconstruct, measure VBSA, predict with a model file."""

from __future__ import annotations

from dataclasses import asdict, dataclass

import numpy as np

from wbsa.errors import WbsaError
from wbsa.estimation.segment import SegmentSettings, segment_subject


@dataclass(frozen=True)
class Estimate:
    """One single-view WBSA estimate (SI units)."""

    vbsa_m2: float
    wbsa_m2: float
    wbsa_lo_m2: float
    wbsa_hi_m2: float
    level: float
    n_pixels: int
    method: str
    vbsa_column: str
    group: str
    model: str
    azimuth_deg: float
    elevation_deg: float
    stature_m: float | None

    def to_dict(self) -> dict:
        """Plain dict for JSON output."""
        return asdict(self)


def recon_method_for(vbsa_column: str) -> str:
    """The reconstruction that measures a model's VBSA column from a depth image.

    ``vbsa_recon_<method>_m2`` → that method; ``vbsa_visible_m2`` → ``grid`` (which reproduces the
    visible area within 2 % on noise-free views, see docs/sensor_and_surface.md).

    Raises
    ------
    WbsaError
        For ``vbsa_hit_m2``, which depends on the mesh behind the image and cannot be measured.
    """
    if vbsa_column == "vbsa_visible_m2":
        return "grid"
    if vbsa_column.startswith("vbsa_recon_") and vbsa_column.endswith("_m2"):
        return vbsa_column[len("vbsa_recon_"):-len("_m2")].replace("_", "-")
    raise WbsaError(f"a model fitted on {vbsa_column} cannot be applied to a depth image; "
                    "refit with --vbsa vbsa_visible_m2 or vbsa_recon_m2:grid")


def estimate_wbsa(depth_m: np.ndarray, intrinsics, model, azimuth_deg: float, elevation_deg: float, *,
                  stature_m: float | None = None, group: str = "all", kind: str = "linear", level: float = 0.95,
                  segment: SegmentSettings | None = SegmentSettings(), vbsa_column: str | None = None,
                  distance_m: float | None = None, seed: int = 0) -> tuple[Estimate, object]:
    """Estimate WBSA from one depth image.

    Parameters
    ----------
    depth_m : (h, w) float
        z-depth in metres (0 = no return), e.g. from :func:`wbsa.core.read_depth_png`.
    intrinsics : wbsa.camera.Intrinsics
        The sensor's intrinsics; the image size must match.
    model : wbsa.analysis.model_file.WbsaModel
        A model file from ``wbsa fit`` (its camera should match the sensor).
    azimuth_deg, elevation_deg : float
        The view, in the paper's convention (0, 0 = camera in front at body height).
    stature_m : float, optional
        Given, the model with stature as extra predictor is used.
    segment : SegmentSettings or None
        None: every return belongs to the subject (e.g. a rendered view).

    Returns
    -------
    Estimate, TriangleMesh
        The estimate and the reconstructed visible surface (camera frame, metres).
    """
    from wbsa.core.backproject import frame_from_depth_image
    from wbsa.surface import reconstruct

    column = vbsa_column or _single_vbsa_column(model)
    method = recon_method_for(column)
    depth = np.asarray(depth_m, dtype=np.float64)
    mask = segment_subject(depth, intrinsics, segment, seed) if segment is not None else depth > 0
    n_pixels = int(mask.sum())
    if n_pixels == 0:
        raise WbsaError("no subject found in the depth image; check --min-depth/--max-depth and the camera")
    frame = frame_from_depth_image(np.where(mask, depth, 0.0), intrinsics)
    surface = reconstruct(frame, method)
    vbsa = surface.area_m2
    wbsa, lo, hi = model.predict(azimuth_deg, elevation_deg, vbsa, stature_m, group, model=kind, level=level,
                                 vbsa_column=column, distance_m=distance_m)
    est = Estimate(vbsa_m2=vbsa, wbsa_m2=float(wbsa[0]), wbsa_lo_m2=float(lo[0]), wbsa_hi_m2=float(hi[0]),
                   level=level, n_pixels=n_pixels, method=method, vbsa_column=column, group=group, model=kind,
                   azimuth_deg=float(azimuth_deg), elevation_deg=float(elevation_deg), stature_m=stature_m)
    return est, surface


def _single_vbsa_column(model) -> str:
    columns = sorted({e["vbsa_column"] for e in model.entries})
    usable = [c for c in columns if c != "vbsa_hit_m2"]
    if len(usable) == 1:
        return usable[0]
    if not usable:
        raise WbsaError("the model holds only vbsa_hit_m2 fits, which a depth image cannot measure; "
                        "refit with --vbsa vbsa_visible_m2")
    raise WbsaError(f"the model holds several VBSA columns ({', '.join(usable)}); choose one with --vbsa")
