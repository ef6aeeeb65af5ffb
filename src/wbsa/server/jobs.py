"""One estimate of ``wbsa serve``, run off the event loop, and the results kept for the page.

:class:`Runner` runs :func:`measure` (which calls :func:`wbsa.estimate`, the same code path as the library
and ``wbsa estimate``) in a pool of worker threads and refuses new work once :attr:`Runner.max_pending`
estimates are waiting, so a burst of uploads gets a clear "busy" message instead of exhausting memory.
Each estimate reads its upload from its own folder inside the server's temporary folder, removed as soon as
the answer is made; the answers (and the depth image, for a click on another person) stay in memory in a
bounded :class:`BoundedStore`.
"""

from __future__ import annotations

import asyncio
import json
import secrets
import shutil
import tempfile
import threading
from collections import OrderedDict
from concurrent.futures import ThreadPoolExecutor
from contextlib import contextmanager
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from wbsa.errors import WbsaError
from wbsa.server.uploads import Upload, UploadError, scrub


@dataclass(frozen=True)
class Options:
    """What the operator chose on the page besides the depth file (SI units).

    Attributes
    ----------
    camera : str
        A preset name or ``auto`` (the preset of the image's size); ignored when ``intrinsics`` is given.
    intrinsics : dict or None
        An uploaded Open3D intrinsics JSON, parsed.
    intrinsics_name : str
    clothes : str or None
        The clothes by name (:data:`wbsa.estimation.clothes.CLOTHES`), or None.
    clothing_m : float or None
        Or an explicit layer of clothes (m); neither: nothing stated (flagged ``clothes_unstated``).
    pick : tuple of (int, int) or str or None
    method : str
    height_cm, mass_kg : float or None
        Typed by the operator for the BSA formulae; the height is also the stated stature of the estimate
        (used where the subject's feet are not seen).
    sex : str or None
    azimuth_deg, elevation_deg : float or None
        A stated view (optional; it is estimated, and checked when given).
    body_fit : BodyFitSettings or None
        The server's settings of the body fit (``create_app(body_fit=...)``; None: the defaults), not the page's.
    """

    camera: str = "auto"
    intrinsics: dict | None = None
    intrinsics_name: str = ""
    clothes: str | None = None
    clothing_m: float | None = None
    pick: object = None
    method: str = "regression"
    height_cm: float | None = None
    mass_kg: float | None = None
    sex: str | None = None
    azimuth_deg: float | None = None
    elevation_deg: float | None = None
    body_fit: object = None


@dataclass
class Result:
    """One answer: the page's JSON, the downloads, and the depth image (for a pick of another person).

    Attributes
    ----------
    id : str
        Random, unguessable; the page's handle on the result.
    answer : dict
        What the page shows (:func:`wbsa.server.answer.answer_json`), or ``{"error": ...}`` with the depth
        picture when the image was read but could not be measured.
    files : dict of str to (bytes, str, str)
        Download name -> (content, media type, file name the browser saves).
    depth_m : (h, w) float32 or None
    options : Options
    estimate : wbsa.estimation.Estimate or None
    """

    id: str
    answer: dict
    files: dict = field(default_factory=dict)
    depth_m: np.ndarray | None = None
    options: Options = Options()
    name: str = ""
    estimate: object = None


class BoundedStore:
    """The last ``capacity`` items (results, batches), in memory, by their ``id`` (the oldest is dropped first).

    Parameters
    ----------
    capacity : int
        Items kept.
    missing : str
        The 404 message for an id not kept (dropped, or never given).
    """

    def __init__(self, capacity: int, missing: str) -> None:
        self.capacity = capacity
        self.missing = missing
        self._items: OrderedDict[str, object] = OrderedDict()
        self._lock = threading.Lock()

    def add(self, item) -> None:
        """Keep ``item`` under ``item.id``, dropping the oldest beyond the capacity."""
        with self._lock:
            self._items[item.id] = item
            while len(self._items) > self.capacity:
                self._items.popitem(last=False)

    def __len__(self) -> int:
        return len(self._items)

    def get(self, item_id: str):
        """The item of ``item_id``; an :class:`UploadError` (404) with :attr:`missing` if it is not kept."""
        with self._lock:
            try:
                return self._items[item_id]
            except KeyError:
                raise UploadError(self.missing, status=404) from None


def internal_error(exc: BaseException) -> str:
    """The page's message for a failure of wbsa itself (no traceback, no server path)."""
    return (f"the server failed on this file ({type(exc).__name__}); it is still running: try another file, "
            "and report this one to the wbsa developers")


def new_id() -> str:
    """A random result id."""
    return secrets.token_urlsafe(12)


def camera_from_upload(upload: Upload) -> dict:
    """An uploaded Open3D intrinsics JSON as a dict, checked by :meth:`Intrinsics.from_open3d_json`."""
    from wbsa.camera.intrinsics import Intrinsics

    try:
        source = json.loads(upload.data.decode("utf-8"))
    except (UnicodeDecodeError, json.JSONDecodeError) as exc:
        raise UploadError(f"{upload.name} is not an intrinsics JSON ({type(exc).__name__}); write it like "
                          "open3d.io.write_pinhole_camera_intrinsic, or choose a camera preset") from None
    try:
        Intrinsics.from_open3d_json(source)
    except WbsaError as exc:
        raise UploadError(f"{upload.name}: {exc.page_words()}") from None
    return source


def read_upload(upload: Upload, folder: Path) -> np.ndarray:
    """The depth image of ``upload`` in metres, read by :func:`wbsa.core.read_depth` from ``folder``."""
    from wbsa.core.depth_image import read_depth

    path = folder / f"depth{upload.suffix}"
    path.write_bytes(upload.data)
    return read_depth(path)


def camera_of(options: Options):
    """The camera argument of :func:`wbsa.estimate` for ``options``: the uploaded intrinsics, else the preset's
    name or ``auto``."""
    from wbsa.camera.intrinsics import Intrinsics

    if options.intrinsics is not None:
        return Intrinsics.from_open3d_json(options.intrinsics)
    return options.camera


def measure(upload: Upload | None, options: Options, model, root: Path, *, depth_m: np.ndarray | None = None,
            result_id: str | None = None, progress=None) -> Result:
    """Read an upload (or take ``depth_m``), estimate, and make the answer and its downloads.

    Runs in a worker thread. Every :class:`~wbsa.errors.WbsaError` becomes the answer's ``error``
    (one line, the server's paths replaced by the upload's name, in the page's words:
    :meth:`~wbsa.errors.WbsaError.page_words`; ``choose_person`` when its code asks for a click on a person); once
    the image is read, the answer keeps its depth picture, so the operator can click the person meant.

    Parameters
    ----------
    upload : Upload or None
    options : Options
    model : EstimatorModel, path or None
        As for :func:`wbsa.estimate`.
    root : Path
        The server's temporary folder; this estimate works in a new folder inside it, removed at the end.
    depth_m : (h, w) float, optional
        An image already read (a pick on an earlier result).
    result_id : str, optional
    progress : callable, optional
        ``progress(stage, done, total)``: ``reading`` the upload, the stages of :func:`wbsa.estimate`
        (``subject``, ``regression``, ``body-fit`` with its steps), ``answer`` (the downloads).

    Returns
    -------
    Result
    """
    from wbsa.server import answer

    def report(stage: str, done: int = 0, total: int = 1) -> None:
        if progress is not None:
            progress(stage, done, total)

    rid = result_id or new_id()
    name = upload.name if upload is not None else options.intrinsics_name
    folder = Path(tempfile.mkdtemp(prefix="r-", dir=root))
    result = Result(rid, {}, options=options, name=name)
    try:
        if depth_m is None:
            report("reading")
            depth_m = read_upload(upload, folder)
        result.depth_m = depth_m
        est = answer.run_estimate(depth_m, camera_of(options), model, options, progress)
        result.estimate = est
        report("answer")
        result.files = answer.downloads(est, folder, name)
        result.answer = answer.answer_json(est, rid, name, options, result.files)
    except WbsaError as exc:
        message = scrub(exc.page_words(), folder, name or "the upload")
        result.answer = {"id": rid, "name": name, "error": message, "choose_person": exc.code == "choose_person"}
    finally:
        shutil.rmtree(folder, ignore_errors=True)
    if result.depth_m is not None:
        result.files["depth.png"] = (answer.depth_picture(result.depth_m, None if result.estimate is None
                                                          else result.estimate.mask), "image/png", "depth.png")
        result.answer.setdefault("depth", answer.depth_info(result.depth_m, rid))
    return result


class Slot:
    """One reserved place of a :class:`Runner` (:meth:`Runner.slot`), given back once.

    Parameters
    ----------
    runner : Runner
    """

    def __init__(self, runner: Runner) -> None:
        self._runner = runner
        self._given_back = False
        self._lock = threading.Lock()
        self.handed_on = False

    def release(self, *_) -> None:
        """Give the place back (once; later calls do nothing). Takes and ignores any arguments, so it can be a
        future's done callback."""
        with self._lock:
            if self._given_back:
                return
            self._given_back = True
        self._runner.release()

    def hand_on(self):
        """The place now ends with the work it was reserved for: the block no longer gives it back; the returned
        :meth:`release` does (call it when the work ends)."""
        self.handed_on = True
        return self.release


class Runner:
    """Estimates in worker threads, at most ``max_pending`` waiting or running.

    Parameters
    ----------
    workers : int
        Threads that run estimates at once.
    max_pending : int
        Estimates accepted (waiting or running) before new ones are refused as busy.
    """

    def __init__(self, workers: int = 2, max_pending: int = 32) -> None:
        self.max_pending = max_pending
        self.pending = 0
        self._lock = threading.Lock()
        self._pool = ThreadPoolExecutor(max_workers=workers, thread_name_prefix="wbsa-estimate")

    def reserve(self, n: int = 1) -> None:
        """Count ``n`` estimates in, or refuse (503) when that would pass :attr:`max_pending`."""
        with self._lock:
            if self.pending + n > self.max_pending:
                raise UploadError(f"the server is busy with {self.pending} estimates (at most {self.max_pending} "
                                  "wait); send the file again in a few seconds", status=503)
            self.pending += n

    def release(self, n: int = 1) -> None:
        """Count ``n`` estimates out."""
        with self._lock:
            self.pending -= n

    @contextmanager
    def slot(self):
        """One estimate's place for the block (:meth:`reserve`, or the busy refusal): given back when the block
        ends, however it ends, unless the block hands it on (:meth:`Slot.hand_on`) to the work it started.

        Yields
        ------
        Slot
        """
        self.reserve()
        slot = Slot(self)
        try:
            yield slot
        finally:
            if not slot.handed_on:
                slot.release()

    async def run(self, fn, *args, **kwargs):
        """``fn(*args, **kwargs)`` in a worker thread, awaited without blocking the event loop."""
        loop = asyncio.get_running_loop()
        return await loop.run_in_executor(self._pool, lambda: fn(*args, **kwargs))

    def submit(self, fn, *args, **kwargs):
        """``fn(*args, **kwargs)`` in a worker thread; a :class:`concurrent.futures.Future`."""
        return self._pool.submit(fn, *args, **kwargs)

    def close(self) -> None:
        """Stop accepting work; running estimates finish."""
        self._pool.shutdown(wait=False, cancel_futures=True)
