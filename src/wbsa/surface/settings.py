"""Settings of surface reconstruction from one depth view (``[reconstruction]`` of a study)."""

from __future__ import annotations

import math
from dataclasses import asdict, dataclass

from wbsa.errors import check_field
from wbsa.typing import (BOUNDARY_MODELS, DENOISE_METHODS, RECONSTRUCTION_METHODS, SMOOTHING_METHODS, BoundaryModel,
                         DenoiseMethod, ReconstructionMethod, SmoothingMethod)
from wbsa.settings_io import check_types


@dataclass(frozen=True)
class ReconstructionSettings:
    """Which surfaces to reconstruct from one depth image, and how.

    Attributes
    ----------
    methods : tuple of {'grid', 'ball-pivoting', 'poisson'}
        Methods a scan or a view runs; each adds a ``vbsa_recon_<method>_m2`` column. Empty (the
        default): no reconstruction. (:func:`wbsa.surface.reconstruct` takes its method as an argument.)
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

    methods: tuple[ReconstructionMethod, ...] = ()
    denoise: DenoiseMethod = "quadratic"
    denoise_sigma_px: float = 2.5
    denoise_sigma_depth_m: float = 0.05
    max_angle_deg: float = 85.0
    boundary: BoundaryModel = "contour"
    hole_max_px: int = 16
    voxel_size_m: float = 0.0
    smoothing: SmoothingMethod = "none"
    neighbours: int = 20
    bpa_radii_px: tuple[float, ...] = (1.0, 2.0, 4.0)
    poisson_depth: int = 8
    poisson_trim_quantile: float = 0.0
    crop_distance_px: float = 1.5

    def __post_init__(self) -> None:
        check_types(self)
        object.__setattr__(self, "methods", tuple(self.methods))
        object.__setattr__(self, "bpa_radii_px", tuple(self.bpa_radii_px))
        for name, value, valid in (("denoise", self.denoise, DENOISE_METHODS),
                                   ("boundary", self.boundary, BOUNDARY_MODELS),
                                   ("smoothing", self.smoothing, SMOOTHING_METHODS)):
            check_field(value in valid, name, f"must be one of {', '.join(valid)}, got {value!r}")
        bad = [m for m in self.methods if m not in RECONSTRUCTION_METHODS]
        check_field(not bad, "methods", f"must be among {', '.join(RECONSTRUCTION_METHODS)}, got {', '.join(map(repr, bad))}")
        check_field(len(set(self.methods)) == len(self.methods), "methods", f"lists a method twice: {', '.join(self.methods)}")
        check_field(self.denoise_sigma_px > 0 and math.isfinite(self.denoise_sigma_px), "denoise_sigma_px",
                    f"must be positive pixels, got {self.denoise_sigma_px}")
        check_field(self.denoise_sigma_depth_m > 0, "denoise_sigma_depth_m", f"must be positive metres, got {self.denoise_sigma_depth_m}")
        check_field(0.0 < self.max_angle_deg < 90.0, "max_angle_deg", f"must be degrees in (0, 90), got {self.max_angle_deg}")
        check_field(self.hole_max_px >= 0, "hole_max_px", f"must be 0 or more pixels, got {self.hole_max_px}")
        check_field(self.voxel_size_m >= 0 and math.isfinite(self.voxel_size_m), "voxel_size_m",
                    f"must be 0 (off) or positive metres, got {self.voxel_size_m}")
        check_field(self.neighbours >= 3, "neighbours", f"must be at least 3, got {self.neighbours}")
        check_field(bool(self.bpa_radii_px) and all(r > 0 for r in self.bpa_radii_px), "bpa_radii_px",
                    f"must be positive numbers, got {list(self.bpa_radii_px)}")
        check_field(1 <= self.poisson_depth <= 12, "poisson_depth", f"must be in 1..12, got {self.poisson_depth}")
        check_field(0.0 <= self.poisson_trim_quantile < 1.0, "poisson_trim_quantile",
                    f"must be in [0, 1), got {self.poisson_trim_quantile}")
        check_field(self.crop_distance_px > 0, "crop_distance_px", f"must be positive, got {self.crop_distance_px}")

    def to_dict(self) -> dict:
        """Plain settings for recording in outputs."""
        d = asdict(self)
        d["methods"] = list(self.methods)
        d["bpa_radii_px"] = list(self.bpa_radii_px)
        return d


def recon_column(method: str) -> str:
    """Scan-table column of a method's reconstructed area: ``vbsa_recon_<method>_m2`` ('-' -> '_')."""
    return f"vbsa_recon_{method.replace('-', '_')}_m2"
