"""Ray-casting back ends: every view of one body measured behind one interface.

Modelled on trimesh's ``ray`` back ends: the same question (the rows of
:func:`wbsa.camera.measure.measure_view` for a list of views) answered by interchangeable engines.

``open3d``
    The reference (:mod:`.open3d_backend`): Open3D's Embree ``RaycastingScene`` per view and the numpy
    visible-area estimate. The default: its rows are the project's published numbers, bit for bit.
``warp``
    NVIDIA Warp kernels (:mod:`.warp_backend`), on a CUDA GPU when there is one, else on the CPU: all
    views of a body in a few compiled passes. Same rows as ``open3d`` within float32 rounding
    (docs/camera.md gives the measured differences).
``auto``
    ``warp`` when a CUDA device is present, otherwise ``open3d``.
"""

from __future__ import annotations

from functools import lru_cache
from typing import TYPE_CHECKING, Literal, Protocol

from wbsa.errors import WbsaError

if TYPE_CHECKING:  # pragma: no cover
    import numpy as np

    from wbsa.camera.frame import DepthFrame
    from wbsa.camera.intrinsics import Intrinsics
    from wbsa.camera.scene import MeshScene
    from wbsa.camera.views import View

BackendName = Literal["auto", "open3d", "warp"]
#: The names accepted by ``backend`` settings and ``--backend``.
BACKENDS: tuple[str, ...] = ("auto", "open3d", "warp")
#: The default back end (its rows, and hence the scan's settings hash, are those of earlier versions).
DEFAULT_BACKEND = "open3d"


class Backend(Protocol):
    """What a back end does: measure a list of views of one scene."""

    name: str

    def measure_views(self, scene: MeshScene, intrinsics: Intrinsics, views: list[View],
                      target: np.ndarray | None = None, *, return_frames: bool = True, grazing_cos: float = ...,
                      grazing_split_px: float | None = ...) -> list[tuple[dict, DepthFrame | None]]:
        """One ``(row, frame)`` per view, as :func:`wbsa.camera.measure.measure_view` returns them."""


def check_backend(name: str) -> str:
    """``name`` if it is a back end, else a one-line :class:`WbsaError`."""
    if name not in BACKENDS:
        raise WbsaError(f"unknown ray-casting backend {name!r}: backend must be one of {', '.join(BACKENDS)}")
    return name


def cuda_available() -> bool:
    """Whether Warp is installed and sees a CUDA device."""
    try:
        from wbsa.camera.backends.warp_backend import warp_module
    except ImportError:  # pragma: no cover - warp-lang is a dependency
        return False
    try:
        return warp_module().get_cuda_device_count() > 0
    except Exception:  # noqa: BLE001 - a broken driver means no GPU
        return False


def resolve_backend(name: str) -> str:
    """The concrete back end (``open3d`` or ``warp``) that ``name`` stands for on this machine."""
    check_backend(name)
    if name == "auto":
        return "warp" if cuda_available() else "open3d"
    return name


@lru_cache(maxsize=4)
def get_backend(name: str = DEFAULT_BACKEND) -> Backend:
    """The (process-wide) back end object of ``name`` (``auto`` resolved first)."""
    name = resolve_backend(name)
    if name == "warp":
        try:
            from wbsa.camera.backends.warp_backend import WarpBackend

            return WarpBackend()
        except ImportError as exc:
            raise WbsaError(f"the warp backend needs NVIDIA Warp ({exc}); pip install warp-lang, "
                            "or use backend open3d") from None
    from wbsa.camera.backends.open3d_backend import Open3DBackend

    return Open3DBackend()


__all__ = ["BACKENDS", "Backend", "BackendName", "DEFAULT_BACKEND", "check_backend", "cuda_available",
           "get_backend", "resolve_backend"]
