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
from typing import TYPE_CHECKING, Protocol

from wbsa.camera.area import GRAZING_COS, GRAZING_SPLIT_PX
from wbsa.errors import WbsaError
from wbsa.typing import RAYCAST_BACKENDS, RaycastBackend

if TYPE_CHECKING:  # pragma: no cover
    import numpy as np

    from wbsa.core.frame import DepthFrame
    from wbsa.camera.intrinsics import Intrinsics
    from wbsa.camera.scene import MeshScene
    from wbsa.camera.views import View

BackendName = RaycastBackend
#: The names accepted by ``backend`` settings and ``--backend``.
BACKENDS: tuple[str, ...] = RAYCAST_BACKENDS
#: The default back end: the reference path, whose rows (and hence the scans' settings hashes) existing scan
#: folders hold.
DEFAULT_BACKEND = "open3d"


class Backend(Protocol):
    """What a back end does: measure a list of views of one scene."""

    name: str

    def measure_views(self, scene: MeshScene, intrinsics: Intrinsics, views: list[View],
                      target: np.ndarray | None = None, *, return_frames: bool = True, grazing_cos: float = ...,
                      grazing_split_px: float | None = ...) -> list[tuple[dict, DepthFrame | None]]:
        """One ``(row, frame)`` per view, as :func:`wbsa.camera.measure.measure_view` returns them.

        Parameters
        ----------
        scene, intrinsics, views, target, return_frames, grazing_cos, grazing_split_px
            As for :func:`measure_views` (without its ``backend``).
        """


def check_backend(name: str) -> str:
    """``name`` if it is a back end, else a one-line :class:`WbsaError`.

    Parameters
    ----------
    name : str
    """
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
    """The concrete back end (``open3d`` or ``warp``) that ``name`` stands for on this machine.

    Parameters
    ----------
    name : {'auto', 'open3d', 'warp'}
    """
    check_backend(name)
    if name == "auto":
        return "warp" if cuda_available() else "open3d"
    return name


@lru_cache(maxsize=4)
def get_backend(name: str = DEFAULT_BACKEND) -> Backend:
    """The (process-wide) back end object of ``name`` (``auto`` resolved first).

    Parameters
    ----------
    name : {'auto', 'open3d', 'warp'}
    """
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
           "get_backend", "iter_measure_views", "measure_views", "resolve_backend"]


def measure_views(scene: MeshScene, intrinsics: Intrinsics, views, target: np.ndarray | None = None, *,
                  backend: str = DEFAULT_BACKEND, return_frames: bool = True,
                  grazing_cos: float = GRAZING_COS,
                  grazing_split_px: float | None = GRAZING_SPLIT_PX) -> list[tuple[dict, DepthFrame | None]]:
    """Measure several views of one scene with a ray-casting back end (:mod:`wbsa.camera.backends`).

    Parameters
    ----------
    scene : MeshScene
    intrinsics : Intrinsics
    views : sequence of View
    target : (3,) float, optional
        Point the camera aims at; default the mesh's bounding-box centre.
    backend : {'open3d', 'warp', 'auto'}
        ``open3d`` is :func:`wbsa.camera.measure_view` view by view (the reference); ``warp`` measures the views in a
        few compiled passes on a GPU or the CPU, with the same rows within float32 rounding.
    return_frames, grazing_cos, grazing_split_px
        As :func:`wbsa.camera.measure_view`.

    Returns
    -------
    list of (row, frame)
        One per view, in order, as :func:`measure_view` returns them.
    """
    return get_backend(backend).measure_views(scene, intrinsics, list(views), target, return_frames=return_frames,
                                              grazing_cos=grazing_cos, grazing_split_px=grazing_split_px)


#: Views per :func:`measure_views` call in :func:`iter_measure_views` when frames are kept (a 640 × 480
#: frame takes about 11 MB).
FRAMES_PER_CALL = 8


def iter_measure_views(scene: MeshScene, intrinsics: Intrinsics, views, target: np.ndarray | None = None, *,
                       backend: str = DEFAULT_BACKEND, return_frames: bool = True):
    """:func:`measure_views`, one ``(row, frame)`` at a time, in view order.

    Without frames all views go to the back end in one call; with frames, ``FRAMES_PER_CALL`` views per
    call, so that a long view list does not hold all its frames at once.

    Parameters
    ----------
    scene, intrinsics, views, target, backend, return_frames
        As for :func:`measure_views`.
    """
    views = list(views)
    step = FRAMES_PER_CALL if return_frames else max(1, len(views))
    for start in range(0, len(views), step):
        yield from measure_views(scene, intrinsics, views[start:start + step], target, backend=backend,
                                 return_frames=return_frames)
