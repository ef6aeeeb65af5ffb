"""Results built by hand (a fitted body, an estimate) for the code that prints and assembles them, without a fit."""

from __future__ import annotations

import numpy as np


def fitted_body(wbsa_m2: float = 1.80, lo: float = 1.70, hi: float = 1.90, seconds: float = 10.0,
                flags: dict[str, str] | None = None):
    """A :class:`~wbsa.estimation.methods.body_fit.BodyFit` of one triangle with the given area, interval, time
    and flags (every other measure a plausible adult's)."""
    from wbsa.estimation.methods.body_fit.result import BodyFit

    triangle = np.array([[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]])
    return BodyFit(wbsa_m2=wbsa_m2, wbsa_lo_m2=lo, wbsa_hi_m2=hi, level=0.95, stature_m=1.75, volume_m3=0.072,
                   mass_kg=70.6, bmi=23.0, tapes={"waist_circ_m": 0.85}, sex="male", age_years=40.0,
                   parameters={"p_muscle": 0.5}, posture_deg={"elbow_l_flexion_deg": 5.0}, azimuth_deg=10.0,
                   elevation_deg=8.0, distance_m=2.5, residual_m=0.012, inlier_share=0.93, loss=0.1, converged=True,
                   flags=dict(flags or {}), seconds=seconds, steps=120, restarts=3, rest_vertices=triangle,
                   posed_vertices=triangle, faces=np.array([[0, 1, 2]], dtype=np.int32))


def route(wbsa_m2: float, lo: float, hi: float, name: str = "regression", flags: dict[str, str] | None = None,
          body=None):
    """A route's :class:`~wbsa.estimation.methods.base.Prediction` seen from the front at 8° (``name``: its
    model's name)."""
    from wbsa.estimation.methods.base import Prediction
    from wbsa.estimation.methods.view import ViewEstimate

    return Prediction(wbsa_m2, lo, hi, ViewEstimate(10.0, 5.0, 8.0, 2.0, 0.9), (10.0, 8.0), name, dict(flags or {}),
                      body=body)


def estimate_of(lead, flags: dict[str, str], routes: dict | None = None, method: str = "regression"):
    """An :class:`~wbsa.estimation.single_view.Estimate` of a 512 x 424 frame whose numbers are ``lead``'s (a
    route), with ``flags``, ``routes`` and the first fitted body among them."""
    from wbsa.estimation.single_view import Estimate

    routes = dict(routes or {})
    body = next((p.body for p in (lead, *routes.values()) if p.body is not None), None)
    mask = np.zeros((424, 512), dtype=bool)
    return Estimate(wbsa_m2=lead.wbsa_m2, wbsa_lo_m2=lead.wbsa_lo_m2, wbsa_hi_m2=lead.wbsa_hi_m2, level=0.95,
                    vbsa_m2=0.7, stature_m=1.75, distance_m=2.5, n_pixels=20000, view=lead.view,
                    view_used=lead.view_used, flags=dict(flags), method=method, model=lead.model_name,
                    camera="kinect-v2", clothing_m=0.0, mask=mask, surface=None, measured_mask=mask, body=body,
                    routes=routes)
