"""Settings of surface reconstruction from one depth view."""

from __future__ import annotations

import math
from dataclasses import asdict, dataclass
from typing import Literal

from wbsa.errors import WbsaError

Method = Literal["grid", "ball-pivoting", "poisson"]
METHODS: tuple[str, ...] = ("grid", "ball-pivoting", "poisson")
DenoiseMethod = Literal["quadratic", "none", "bilateral", "median"]
DENOISE_METHODS: tuple[str, ...] = ("quadratic", "none", "bilateral", "median")
BoundaryModel = Literal["none", "footprint", "contour"]
BOUNDARY_MODELS: tuple[str, ...] = ("none", "footprint", "contour")


@dataclass(frozen=True)
class ReconstructionSettings:
    """How to turn one depth image into a surface.

    Attributes
    ----------
    denoise : {'quadratic', 'none', 'bilateral', 'median'}
        Depth-image filter applied within the mask before any method (see
        :mod:`wbsa.surface.denoise`). The default robust quadratic filter is applied to ideal
        renderings too, so that noisy and noise-free views go through the same estimator; it is
        exact on locally quadratic surfaces and tames the contour skirt on sub-pixel structures.
    denoise_sigma_px : float
        Spatial scale of the filter in pixels (Gaussian σ; the median uses a 2·round(σ)+1 square).
    denoise_sigma_depth_m : float
        Range σ of the quadratic and bilateral filters: neighbours this much off the local
        median depth count e^-½ as much (keeps occlusion jumps sharp).
    max_angle_deg : float
        ``grid``: neighbouring pixels are joined unless the surface between them would be inclined
        more than this to the viewing ray (depth-jump test).
    boundary : {'none', 'footprint', 'contour'}
        ``grid``: skirt along the mesh boundary (see :mod:`wbsa.surface.grid`).
    hole_max_px : int
        ``grid``: enclosed regions without returns up to this size are holes, not background.
    voxel_size_m : float
        Point-cloud methods: voxel down-sampling before reconstruction (0 = off; the paper's clean-up).
    smoothing : {'none', 'mls'}
        Point-cloud methods: moving-least-squares smoothing (projection of each point on the plane
        fitted to its neighbours; the paper's "smoothing with least mean square").
    neighbours : int
        Point-cloud methods: neighbours for normal estimation and MLS.
    bpa_radii_px : tuple of float
        Ball-pivoting radii in units of the point spacing (the pixel pitch at the median depth, or
        the voxel size if larger).
    poisson_depth : int
        Octree depth of Poisson reconstruction.
    poisson_trim_quantile : float
        Drop Poisson vertices whose density is below this quantile (the extrapolated surface).
    crop_distance_px : float
        Poisson: keep triangles whose centroid lies within this many point spacings of the cloud
        (the closed surface is otherwise about twice the visible area).
    """

    denoise: DenoiseMethod = "quadratic"
    denoise_sigma_px: float = 2.5
    denoise_sigma_depth_m: float = 0.05
    max_angle_deg: float = 85.0
    boundary: BoundaryModel = "contour"
    hole_max_px: int = 16
    voxel_size_m: float = 0.0
    smoothing: Literal["none", "mls"] = "none"
    neighbours: int = 20
    bpa_radii_px: tuple[float, ...] = (1.0, 2.0, 4.0)
    poisson_depth: int = 8
    poisson_trim_quantile: float = 0.0
    crop_distance_px: float = 1.5

    def __post_init__(self) -> None:
        if self.denoise not in DENOISE_METHODS:
            raise WbsaError(f"unknown denoise filter {self.denoise!r}; use one of {', '.join(DENOISE_METHODS)}")
        if self.boundary not in BOUNDARY_MODELS:
            raise WbsaError(f"unknown boundary model {self.boundary!r}; use {', '.join(BOUNDARY_MODELS)}")
        if self.smoothing not in ("none", "mls"):
            raise WbsaError(f"unknown smoothing {self.smoothing!r}; use none or mls")
        if not (self.denoise_sigma_px > 0 and math.isfinite(self.denoise_sigma_px)):
            raise WbsaError(f"denoise_sigma_px must be positive, got {self.denoise_sigma_px}")
        if not (self.denoise_sigma_depth_m > 0):
            raise WbsaError(f"denoise_sigma_depth_m must be positive, got {self.denoise_sigma_depth_m}")
        if not (0.0 < self.max_angle_deg < 90.0):
            raise WbsaError(f"max_angle_deg must be in (0, 90), got {self.max_angle_deg}")
        if self.voxel_size_m < 0 or not math.isfinite(self.voxel_size_m):
            raise WbsaError(f"voxel_size_m must be >= 0, got {self.voxel_size_m}")
        if self.neighbours < 3:
            raise WbsaError(f"neighbours must be at least 3, got {self.neighbours}")
        if not self.bpa_radii_px or any(not (r > 0) for r in self.bpa_radii_px):
            raise WbsaError(f"bpa_radii_px must be positive numbers, got {self.bpa_radii_px}")
        if not (1 <= self.poisson_depth <= 12):
            raise WbsaError(f"poisson_depth must be in 1..12, got {self.poisson_depth}")
        if not (0.0 <= self.poisson_trim_quantile < 1.0):
            raise WbsaError(f"poisson_trim_quantile must be in [0, 1), got {self.poisson_trim_quantile}")
        if not (self.crop_distance_px > 0):
            raise WbsaError(f"crop_distance_px must be positive, got {self.crop_distance_px}")

    def to_dict(self) -> dict:
        """Plain settings for recording in outputs."""
        d = asdict(self)
        d["bpa_radii_px"] = list(self.bpa_radii_px)
        return d


def recon_column(method: str) -> str:
    """Scan-table column of a method's reconstructed area: ``vbsa_recon_<method>_m2`` ('-' -> '_')."""
    return f"vbsa_recon_{method.replace('-', '_')}_m2"
