"""surface stage: reconstruct the visible surface of one depth view and measure its area.

``grid`` (organised pixel-grid mesh with a boundary skirt, vectorised numpy), ``ball-pivoting``
and ``poisson`` (Open3D, imported only when used); the frames it reads come from the camera or from a depth
image (:func:`wbsa.core.frame_from_depth_image`) (e.g. a real sensor's PNG) into a frame the same code can reconstruct.

Names are imported lazily, so ``from wbsa.surface.cli import add_reconstruct_arguments``
stays cheap for the CLI.
"""

from __future__ import annotations

from wbsa.lazy import lazy_exports

_EXPORTS = {
    "denoise_depth": "wbsa.surface.denoise",
    "grid_mesh": "wbsa.surface.grid",
    "add_reconstruct_arguments": "wbsa.surface.cli",
    "reconstruction_settings_from_args": "wbsa.surface.cli",
    "reconstruct": "wbsa.surface.reconstruction",
    "vbsa_recon_m2": "wbsa.surface.reconstruction",
    "BOUNDARY_MODELS": "wbsa.typing",
    "DENOISE_METHODS": "wbsa.typing",
    "RECONSTRUCTION_METHODS": "wbsa.typing",
    "ReconstructionSettings": "wbsa.surface.settings",
    "recon_column": "wbsa.surface.settings",
}
__all__ = sorted(_EXPORTS)
__getattr__, __dir__ = lazy_exports(__name__, _EXPORTS)
