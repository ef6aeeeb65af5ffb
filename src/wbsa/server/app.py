"""The web application of ``wbsa serve``: the page, its static files and the JSON routes it calls.

=====================================  ===========================================================
``GET /``                              the page (``static/index.html``; JS and CSS under ``/static``)
``GET /api/info``                      camera presets, methods, limits (for the page's form)
``POST /api/estimate``                 one depth file (form: ``depth``, optional ``intrinsics``,
                                       ``camera``, ``clothes``, ``clothing_cm``, ``method``, ``height_cm``,
                                       ``mass_kg``, ``sex``, ``pick``, ``azimuth_deg``,
                                       ``elevation_deg``) -> the answer
``POST /api/result/{id}/pick?pick=x,y`` the same image, the person at pixel (x, y) -> a new answer
                                       (both: with ``Accept: application/x-ndjson``, the progress as
                                       JSON lines and the answer last: :mod:`wbsa.server.progress`)
``GET /api/result/{id}/{file}``         ``depth.png``, ``estimate.json``, ``fhir.json``, ``mask.png``,
                                       ``surface.ply``
``POST /api/batch``                    several ``depth`` files -> a batch id; ``GET /api/batch/{id}``
                                       its progress and rows, ``GET /api/batch/{id}.csv`` the table
=====================================  ===========================================================

Errors are JSON ``{"error": "<one line>"}`` with a 4xx status (503 when busy); a failure of wbsa itself is
a 500 with a message and no traceback. The server keeps running after any of them.
"""

from __future__ import annotations

import argparse
import dataclasses
import shutil
import tempfile
from contextlib import asynccontextmanager
from pathlib import Path

from wbsa.server.uploads import MAX_UPLOAD_BYTES, UploadError, check_depth_upload, check_fields, read_form

STATIC = Path(__file__).parent / "static"
#: Text fields of ``POST /api/estimate`` and ``POST /api/batch``.
FIELDS = {"camera", "clothes", "clothing_cm", "method", "height_cm", "mass_kg", "sex", "pick", "azimuth_deg",
          "elevation_deg"}
#: File fields.
FILES = {"depth", "intrinsics"}
#: Headers on every response: no script, style or image from anywhere but this server.
SECURITY_HEADERS = {
    "Content-Security-Policy": "default-src 'self'; img-src 'self' data: blob:; object-src 'none'; "
                               "base-uri 'none'; frame-ancestors 'none'",
    "X-Content-Type-Options": "nosniff",
    "Referrer-Policy": "no-referrer",
}


class SecurityHeaders:
    """ASGI middleware adding :data:`SECURITY_HEADERS` to every HTTP response (bodies pass through unread)."""

    def __init__(self, app) -> None:
        self.app = app

    async def __call__(self, scope, receive, send) -> None:
        if scope["type"] != "http":
            return await self.app(scope, receive, send)
        extra = [(k.lower().encode(), v.encode()) for k, v in SECURITY_HEADERS.items()]

        async def send_with_headers(message) -> None:
            if message["type"] == "http.response.start":
                message = {**message, "headers": list(message.get("headers", [])) + extra}
            await send(message)

        await self.app(scope, receive, send_with_headers)


def _number(fields: dict, name: str, low: float, high: float, what: str) -> float | None:
    """A form field as a number in [low, high] (None when empty), checked by :func:`wbsa.cli_types.number_in`."""
    from wbsa.cli_types import number_in

    text = fields.get(name, "").strip()
    if not text:
        return None
    try:
        return number_in(low, high, what=what)(text)
    except argparse.ArgumentTypeError as exc:
        raise UploadError(f"{name}: {exc}") from None


def options_from_form(form, presets, methods, body_fit=None) -> "Options":
    """The page's choices as :class:`~wbsa.server.jobs.Options`, every field checked (``body_fit``: the server's
    settings of the body fit)."""
    from wbsa.cli_types import pick as parse_pick
    from wbsa.estimation.clothes import CLOTHES, clothes_help
    from wbsa.estimation.limits import LIMITS
    from wbsa.server.jobs import Options, camera_from_upload

    check_fields(form, FIELDS, FILES)
    f = form.fields
    camera = f.get("camera", "auto").strip() or "auto"
    if camera != "auto" and camera not in presets:
        raise UploadError(f"camera {camera!r} is not a preset; choose one of auto, {', '.join(presets)}, or upload "
                          "the camera's intrinsics JSON")
    intrinsics = form.files.get("intrinsics", [])
    if len(intrinsics) > 1:
        raise UploadError("give one intrinsics JSON, not several")
    method = f.get("method", methods[0]).strip() or methods[0]
    if method not in methods:
        raise UploadError(f"method {method!r} is unknown; available: {', '.join(methods)}")
    sex = f.get("sex", "").strip() or None
    if sex not in (None, "male", "female"):
        raise UploadError(f"sex {sex!r} must be male or female (or left empty)")
    pick = None
    if f.get("pick", "").strip():
        try:
            pick = parse_pick(f["pick"].strip())
        except argparse.ArgumentTypeError as exc:
            raise UploadError(f"pick: {exc}") from None
    clothing_cm = _number(f, "clothing_cm", *LIMITS["clothing"].scaled(100), "a thickness of clothes in cm")
    clothes = f.get("clothes", "").strip() or None
    if clothes is not None and clothes not in CLOTHES:
        raise UploadError(f"clothes {clothes!r} is unknown; choose one of {clothes_help()}")
    return Options(camera=camera, intrinsics=camera_from_upload(intrinsics[0]) if intrinsics else None,
                   intrinsics_name=intrinsics[0].name if intrinsics else "", clothes=clothes,
                   clothing_m=None if clothing_cm is None else clothing_cm / 100.0,
                   pick=pick, method=method, height_cm=_number(f, "height_cm", *LIMITS["stature"].scaled(100), "a height in cm"),
                   mass_kg=_number(f, "mass_kg", 0.1, 700, "a mass in kg"), sex=sex,
                   azimuth_deg=_number(f, "azimuth_deg", -360, 360, "an azimuth in degrees"),
                   elevation_deg=_number(f, "elevation_deg", -90, 90, "an elevation in degrees"), body_fit=body_fit)


def create_app(model=None, *, workers: int = 2, max_pending: int = 32, max_upload_bytes: int = MAX_UPLOAD_BYTES,
               temp_dir: str | None = None, keep_results: int = 64, token: str | None = None, body_fit=None):
    """The ``wbsa serve`` application (Starlette, ASGI).

    Parameters
    ----------
    model : EstimatorModel, path or None
        As for :func:`wbsa.estimate`; a path is read (and refused if broken) here, once. None: the default
        model.
    workers : int
        Estimates run at once (threads).
    max_pending : int
        Estimates accepted (waiting or running) before uploads are refused as busy (503).
    max_upload_bytes : int
        Largest request body.
    temp_dir : str, optional
        Where the server's temporary folder is made (default: the system's); it is removed at shutdown.
    keep_results : int
        Answers kept in memory for downloads and picks.
    token : str, optional
        A token every request must carry (:class:`wbsa.server.access.TokenGate`; 403 without it). None: no
        token (loopback only: ``wbsa serve`` makes one for any other address).
    body_fit : BodyFitSettings, optional
        The settings of the body fit (methods ``body-fit`` and ``both``; None: the defaults). Its ``threads`` is
        torch's thread count for the whole server, set once when it starts (and restored when it stops): torch's
        count is the process's and the estimates run in threads, so no fit changes it.

    Returns
    -------
    starlette.applications.Starlette
        ``app.state`` holds ``root`` (the temporary folder), ``runner``, ``results``, ``batches``, ``model`` and
        ``body_fit`` (the fits' settings: ``threads`` None, the server's count).
    """
    from starlette.applications import Starlette
    from starlette.requests import ClientDisconnect, Request
    from starlette.responses import FileResponse, JSONResponse, Response, StreamingResponse
    from starlette.routing import Mount, Route
    from starlette.staticfiles import StaticFiles

    from wbsa.camera.presets import CAMERAS
    from wbsa.strict_json import finite_or_none
    from wbsa.typing import METHODS
    from wbsa.server.batch import Batch, run_batch
    from wbsa.server.jobs import BoundedStore, Runner, internal_error, measure, new_id
    from wbsa.estimation.clothes import CLOTHES
    from wbsa.estimation.limits import limits_json
    from wbsa.server.progress import STREAM, stream_answer, wants_stream

    from wbsa.estimation.methods.body_fit.settings import BodyFitSettings
    from wbsa.parallel import torch_threads

    fit_threads = (body_fit or BodyFitSettings()).threads
    body_fit = dataclasses.replace(body_fit or BodyFitSettings(), threads=None)  # the fits keep the server's count
    if model is not None and not hasattr(model, "predict"):
        from wbsa.estimation.methods.regression.default_model import load_model

        model = load_model(model)
    presets = list(CAMERAS)
    methods = list(METHODS)
    root = Path(tempfile.mkdtemp(prefix="wbsa-serve-", dir=temp_dir))
    runner = Runner(workers=workers, max_pending=max_pending)
    results = BoundedStore(keep_results, "this result is no longer kept (the server keeps the last "
                                         f"{keep_results}); upload the depth file again")
    batches = BoundedStore(16, "this batch is no longer kept; upload its files again")

    def error(exc: UploadError) -> JSONResponse:
        return JSONResponse({"error": exc.page_words()}, status_code=exc.status)

    async def page(request: Request) -> Response:
        return FileResponse(STATIC / "index.html", media_type="text/html")

    async def info(request: Request) -> Response:
        return JSONResponse({
            "presets": [{"name": k, "width": CAMERAS[k].intrinsics.width, "height": CAMERAS[k].intrinsics.height} for k in presets],
            "methods": methods, "max_upload_bytes": max_upload_bytes, "limits": limits_json(),
            "clothes": [{"name": c.name, "words": c.words, "layer_cm": round(100 * c.layer_m, 2),
                         "sd_cm": round(100 * c.sd_m, 2)} for c in CLOTHES.values()],
            "model": "default" if model is None else str(getattr(model, "meta", {}).get("name", "given"))})

    async def answered(request: Request, prepare) -> Response:
        """Check the request with ``prepare()`` (a coroutine giving ``job(progress) -> Result``), then run the job
        in one of the runner's places: one JSON answer, or with ``Accept: application/x-ndjson`` its progress
        and then the answer (:mod:`wbsa.server.progress`). A bad request gets its one-line message, a failure of
        wbsa itself a 500 with no traceback."""
        try:
            with runner.slot() as slot:
                job = await prepare()
                if wants_stream(request):
                    return StreamingResponse(stream_answer(runner, job, results.add, internal_error, slot.hand_on()),
                                             media_type=STREAM,
                                             headers={"Cache-Control": "no-store", "X-Accel-Buffering": "no"})
                result = await runner.run(job, None)
        except UploadError as exc:
            return error(exc)
        except ClientDisconnect:
            return Response(status_code=400)
        except Exception as exc:  # a failure of wbsa itself: the server answers and keeps running
            return JSONResponse({"error": internal_error(exc)}, status_code=500)
        results.add(result)
        return JSONResponse(finite_or_none(result.answer), status_code=422 if "error" in result.answer else 200)

    async def estimate_one(request: Request) -> Response:
        async def prepare():
            form = await read_form(request, max_upload_bytes)
            options = options_from_form(form, presets, methods, body_fit)
            depth = form.files.get("depth", [])
            if len(depth) != 1:
                raise UploadError("send one depth file in the field 'depth' (for several, use the batch)"
                                  if depth else "no depth file was sent; choose or drop a depth image")
            check_depth_upload(depth[0])
            return lambda progress: measure(depth[0], options, model, root, progress=progress)

        return await answered(request, prepare)

    async def pick(request: Request) -> Response:
        from wbsa.cli_types import pick as parse_pick

        async def prepare():
            before = results.get(request.path_params["rid"])
            if before.depth_m is None:
                raise UploadError("this upload holds no depth image to pick from; upload a depth file")
            try:
                at = parse_pick(request.query_params.get("pick", ""))
            except argparse.ArgumentTypeError as exc:
                raise UploadError(f"pick: {exc}") from None
            options = dataclasses.replace(before.options, pick=at)

            def job(progress):
                result = measure(None, options, model, root, depth_m=before.depth_m, progress=progress)
                result.name = before.name
                result.answer["name"] = before.name
                return result

            return job

        return await answered(request, prepare)

    async def result_file(request: Request) -> Response:
        try:
            result = results.get(request.path_params["rid"])
            name = request.path_params["name"]
            if name not in result.files:
                raise UploadError(f"this result has no file {name!r}", status=404)
        except UploadError as exc:
            return error(exc)
        content, media, filename = result.files[name]
        return Response(content, media_type=media,
                        headers={"Content-Disposition": f'attachment; filename="{filename}"'})

    async def batch_start(request: Request) -> Response:
        try:
            with runner.slot() as slot:
                form = await read_form(request, max_upload_bytes)
                options = options_from_form(form, presets, methods, body_fit)
                uploads = form.files.get("depth", [])
                if not uploads:
                    raise UploadError("no depth files were sent; choose or drop depth images")
                batch = Batch(new_id(), [u.name for u in uploads])
                batches.add(batch)
                runner.submit(run_batch, batch, uploads, options, model, root, results).add_done_callback(
                    slot.hand_on())
        except UploadError as exc:
            return error(exc)
        except ClientDisconnect:
            return Response(status_code=400)
        return JSONResponse(batch.progress())

    async def batch_progress(request: Request) -> Response:
        try:
            return JSONResponse(batches.get(request.path_params["bid"]).progress())
        except UploadError as exc:
            return error(exc)

    async def batch_csv(request: Request) -> Response:
        try:
            batch = batches.get(request.path_params["bid"])
        except UploadError as exc:
            return error(exc)
        return Response(batch.csv_bytes(), media_type="text/csv",
                        headers={"Content-Disposition": 'attachment; filename="wbsa-batch.csv"'})

    @asynccontextmanager
    async def lifespan(app):
        with torch_threads(fit_threads):  # once for the whole server
            try:
                yield
            finally:
                runner.close()
                shutil.rmtree(root, ignore_errors=True)

    from starlette.middleware import Middleware

    from wbsa.server.access import TokenGate

    app = Starlette(routes=[
        Route("/", page),
        Route("/api/info", info),
        Route("/api/estimate", estimate_one, methods=["POST"]),
        Route("/api/result/{rid}/pick", pick, methods=["POST"]),
        Route("/api/result/{rid}/{name}", result_file),
        Route("/api/batch", batch_start, methods=["POST"]),
        Route("/api/batch/{bid}.csv", batch_csv),
        Route("/api/batch/{bid}", batch_progress),
        Mount("/static", StaticFiles(directory=STATIC), name="static"),
    ], lifespan=lifespan, middleware=[Middleware(SecurityHeaders)]
        + ([Middleware(TokenGate, token=token)] if token is not None else []))
    app.state.root, app.state.runner, app.state.results, app.state.batches = root, runner, results, batches
    app.state.model = model
    app.state.body_fit = body_fit
    return app

