"""The answer of ``wbsa serve``: an :class:`~wbsa.estimation.Estimate` as the page shows and offers it.

- :func:`run_estimate`: the page's options into :func:`wbsa.estimate` (the one estimation code path);
- :func:`answer_json`: the number first (WBSA, interval, method; with ``both`` each route's own and which
  leads), the flags with what to do (:mod:`wbsa.server.advice`, details in the page's words), the view, the meshes for the 3-D view, the BSA formulae when height and
  mass were typed, the downloads;
- :func:`downloads`: JSON (``Estimate.to_dict``), FHIR R4 (:func:`~wbsa.estimation.fhir.fhir_observation`),
  the mask PNG and the surface PLY, made by the writers ``wbsa estimate`` uses;
- :func:`depth_picture`: the depth image coloured by distance with the subject outlined.
"""

from __future__ import annotations

import io
import json
import re
from pathlib import Path

import numpy as np

from wbsa.errors import WbsaError

#: Depth shown as the nearest and farthest colour: these percentiles of the returns.
DEPTH_PERCENTILES = (1.0, 99.0)


def run_estimate(depth_m: np.ndarray, camera, model, options, progress=None):
    """The estimate of ``depth_m`` with the page's ``options`` (:class:`wbsa.server.jobs.Options`), its request
    built as :func:`wbsa.estimate` builds it (:class:`wbsa.estimation.request.EstimateRequest`), reporting to
    ``progress(stage, done, total)`` (or None)."""
    from wbsa.estimation.request import EstimateRequest
    from wbsa.estimation.single_view import estimate_request
    from wbsa.estimation.subject.settings import SegmentSettings

    model = None if options.method == "body-fit" else model  # the body fit has no estimator model
    request = EstimateRequest.build(
        camera, options.method, azimuth_deg=options.azimuth_deg, elevation_deg=options.elevation_deg,
        clothes=options.clothes, clothing_m=options.clothing_m,
        stature_m=None if options.height_cm is None else options.height_cm / 100.0,
        segment=SegmentSettings(pick=options.pick),
        body_fit=None if options.method == "regression" else options.body_fit)
    return estimate_request(request, depth_m, model, progress=progress)


def _stem(name: str) -> str:
    stem = re.sub(r"[^A-Za-z0-9._-]+", "-", Path(name or "depth").stem).strip("-.") or "depth"
    return stem[:60]


def downloads(est, folder: Path, name: str) -> dict[str, tuple[bytes, str, str]]:
    """The estimate's files: download key -> (content, media type, file name), written in ``folder``.

    The mask and the mesh are written by the writers of ``wbsa estimate --mask-out / --out-mesh``
    (atomic, verified) into ``folder`` and read back.
    """
    from wbsa.core.mesh_io import write_mesh
    from wbsa.core.depth_image import write_mask
    from wbsa.estimation.fhir import fhir_observation
    from wbsa.strict_json import json_text

    stem = _stem(name)
    files = {
        "estimate.json": (json_text(est.to_dict()).encode(), "application/json", f"{stem}-wbsa.json"),
        "fhir.json": (json_text(fhir_observation(est)).encode(), "application/fhir+json",
                      f"{stem}-wbsa-observation.fhir.json"),
    }
    write_mask(folder / "mask.png", est.mask)
    files["mask.png"] = ((folder / "mask.png").read_bytes(), "image/png", f"{stem}-mask.png")
    write_mesh(est.surface, folder / "surface.ply")
    files["surface.ply"] = ((folder / "surface.ply").read_bytes(), "application/octet-stream", f"{stem}-surface.ply")
    if est.body is not None:  # the body fit's body, as the camera saw it (beside the surface) and at rest
        for pose in ("observed", "rest"):
            est.body.write_ply(folder / f"body-{pose}.ply", pose)
            files[f"body-{pose}.ply"] = ((folder / f"body-{pose}.ply").read_bytes(), "application/octet-stream",
                                         f"{stem}-body-{pose}.ply")
    return files


#: Download key -> the label the page gives it.
DOWNLOAD_LABELS = {"estimate.json": "JSON", "fhir.json": "FHIR R4 Observation", "mask.png": "Mask PNG",
                   "surface.ply": "Surface PLY", "body-rest.ply": "Fitted body PLY (at rest)",
                   "body-observed.ply": "Fitted body PLY (as seen)"}


def meshes(est, result_id: str) -> list[dict]:
    """The meshes of the 3-D view: name, its words in the view's legend, and a PLY to load (or
    ``vertices``/``faces`` arrays).

    The visible surface (camera frame, metres) and, with the body fit, the fitted body as the camera saw it.
    """
    out = [{"name": "visible surface", "label": "the surface the camera saw (measured)",
            "url": f"api/result/{result_id}/surface.ply", "frame": "camera"}]
    if est.body is not None:
        out.append({"name": "fitted body", "label": "the body fitted to it (body fit), as the camera saw it",
                    "url": f"api/result/{result_id}/body-observed.ply", "frame": "camera"})
    return out


def formula_rows(height_cm: float | None, mass_kg: float | None, sex: str | None) -> dict | None:
    """BSA by every classical formula (:func:`wbsa.formulae.bsa_all`) for a typed height and mass.

    Returns
    -------
    dict or None
        ``{"rows": [{"key", "name", "bsa_m2"}, ...]}``, ``{"error": ...}`` for a height or mass the formulae
        refuse, None when either was not typed.
    """
    from wbsa.formulae import FORMULAE, bsa_all

    if height_cm is None or mass_kg is None:
        return None
    try:
        values = bsa_all(height_cm, mass_kg, sex)
    except WbsaError as exc:
        return {"error": str(exc)}
    rows = []
    for key, value in values.items():  # without sex: schlich_male and schlich_female in schlich's place
        name = FORMULAE[key].name if key in FORMULAE else f"{FORMULAE['schlich'].name} ({key.split('_')[-1]})"
        rows.append({"key": key, "name": name, "bsa_m2": round(float(value), 4)})
    return {"rows": rows, "height_cm": height_cm, "mass_kg": mass_kg, "sex": sex}


#: Each route's name on the page.
ROUTE_LABELS = {"regression": "Regression", "body-fit": "Body fit", "combined": "Both combined"}
#: Why the route that leads with method ``both`` does, in plain words (the measured comparison: docs/body_fit.md).
LEAD_REASONS = {
    "regression": "The number above is the regression's. With both methods the regression leads: on the test "
                  "pictures it came closer to the true area than the body fit, which is shown beside it as a second "
                  "opinion.",
    "body-fit": "The number above is the body fit's: the regression gave no answer for this picture.",
    "combined": "The number above combines the two methods' answers.",
}


def routes_json(est) -> dict | None:
    """With method ``both``: each route's number, interval and own flags, which one leads and why; None otherwise.

    The route whose number is the estimate's leads; an estimate whose number is neither route's is their
    combination (``combined``). A body fit that failed is a route with its reason (``failed``).
    """
    from wbsa.errors import page_text
    from wbsa.server.advice import flag_rows

    if not est.routes:
        return None
    whole = est.to_dict()
    shown = whole["routes"]
    rows = []
    for key, route in shown.items():
        same = all(route[k] == whole[k] for k in ("wbsa_m2", "wbsa_lo_m2", "wbsa_hi_m2"))  # both rounded alike
        rows.append({"name": key, "label": ROUTE_LABELS.get(key, key), "wbsa_m2": round(route["wbsa_m2"], 3),
                     "wbsa_lo_m2": round(route["wbsa_lo_m2"], 3), "wbsa_hi_m2": round(route["wbsa_hi_m2"], 3),
                     "model": route["model"], "flags": flag_rows(route["flags"]), "leads": same})
    if "body_fit_failed" in est.flags and "body-fit" not in shown:
        rows.append({"name": "body-fit", "label": ROUTE_LABELS["body-fit"], "leads": False, "flags": [],
                     "failed": page_text(est.flags["body_fit_failed"])})
    lead = next((r["name"] for r in rows if r["leads"]), "combined")
    combined = None
    if lead == "combined":
        combined = {"name": "combined", "label": ROUTE_LABELS["combined"], "wbsa_m2": round(est.wbsa_m2, 3),
                    "wbsa_lo_m2": round(est.wbsa_lo_m2, 3), "wbsa_hi_m2": round(est.wbsa_hi_m2, 3), "leads": True}
    return {"rows": rows, "combined": combined, "lead": lead, "lead_label": ROUTE_LABELS.get(lead, lead),
            "why": LEAD_REASONS.get(lead, "")}


def shared_flags(est) -> dict[str, str]:
    """The estimate's flags less those a route of ``both`` raised itself (shown with that route's number)."""
    own = [dict(p.flags) for p in est.routes.values()]
    return {k: v for k, v in est.flags.items() if not any(f.get(k) == v for f in own)}


def answer_json(est, result_id: str, name: str, options, files: dict) -> dict:
    """What the page shows of one estimate (JSON-ready)."""
    from wbsa.server.advice import flag_rows

    return {
        "id": result_id, "name": name,
        "wbsa_m2": round(est.wbsa_m2, 3), "wbsa_lo_m2": round(est.wbsa_lo_m2, 3),
        "wbsa_hi_m2": round(est.wbsa_hi_m2, 3), "level": est.level, "method": est.method,
        # the page shows two decimals of the estimate itself, never of a value already rounded to three
        "shown": {k: f"{getattr(est, k):.2f}" for k in ("wbsa_m2", "wbsa_lo_m2", "wbsa_hi_m2")},
        "method_text": est.method_text(), "model": est.model, "camera": est.camera,
        "estimate": est.to_dict(), "pick": list(options.pick) if isinstance(options.pick, tuple) else options.pick,
        "flags": flag_rows(est.flags), "image_flags": flag_rows(shared_flags(est)),
        "routes": routes_json(est),
        "view": {**est.view.to_dict(), "distance_m": round(est.distance_m, 3),
                 "azimuth_used_deg": est.view_used[0], "elevation_used_deg": est.view_used[1],
                 "uncertain": "uncertain_view" in est.flags},
        "meshes": meshes(est, result_id),
        "formulae": formula_rows(options.height_cm, options.mass_kg, options.sex),
        "downloads": [{"label": DOWNLOAD_LABELS[k], "url": f"api/result/{result_id}/{k}", "filename": f[2]}
                      for k, f in files.items() if k in DOWNLOAD_LABELS],
    }


def depth_range(depth_m: np.ndarray) -> tuple[float, float]:
    """The depths (m) shown as the nearest and farthest colour (:data:`DEPTH_PERCENTILES` of the returns)."""
    d = np.asarray(depth_m)
    valid = d[np.isfinite(d) & (d > 0)]
    if valid.size == 0:
        return 0.0, 1.0
    near, far = np.percentile(valid, DEPTH_PERCENTILES)
    return float(near), float(max(far, near + 1e-3))


def depth_info(depth_m: np.ndarray, result_id: str) -> dict:
    """The depth picture's address, size (pixels) and colour range (m) for the page."""
    near, far = depth_range(depth_m)
    return {"url": f"api/result/{result_id}/depth.png", "width": int(depth_m.shape[1]),
            "height": int(depth_m.shape[0]), "near_m": round(near, 3), "far_m": round(far, 3)}


def depth_picture(depth_m: np.ndarray, mask: np.ndarray | None) -> bytes:
    """The depth image coloured by distance (turbo: near blue, far red; no return grey), the mask outlined
    in white with a black rim, as PNG bytes."""
    from matplotlib import colormaps
    from PIL import Image
    from scipy import ndimage

    d = np.asarray(depth_m, dtype=np.float64)
    valid = np.isfinite(d) & (d > 0)
    near, far = depth_range(d)
    lut = (colormaps["turbo"](np.linspace(0.0, 1.0, 256))[:, :3] * 255).astype(np.uint8)
    t = np.clip((np.where(valid, d, near) - near) / (far - near), 0.0, 1.0)
    rgb = lut[np.rint(t * 255).astype(np.intp)]
    rgb[~valid] = (60, 60, 60)
    if mask is not None and mask.any():
        edge = mask & ~ndimage.binary_erosion(mask)
        rim = ndimage.binary_dilation(edge, iterations=2) & ~edge
        rgb[rim] = (0, 0, 0)
        rgb[ndimage.binary_dilation(edge)] = (255, 255, 255)
    buf = io.BytesIO()
    Image.fromarray(rgb).save(buf, format="PNG", optimize=False)
    return buf.getvalue()
