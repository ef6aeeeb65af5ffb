"""Measures of a fitted body, taken exactly as the population's (:mod:`wbsa.bodies.anthropometry`)."""

from __future__ import annotations

import numpy as np
import pandas as pd

from wbsa.bodies.body_model import BODY_PARAMETER_COLUMNS, PHENOTYPE_COLUMNS


def parameter_table(params: np.ndarray) -> pd.DataFrame:
    """One-row population table of ``(15,)`` body parameters, clipped to anny's ranges.

    Parameters
    ----------
    params : (15,) float64
        anny's phenotypes then local changes.
    """
    p = np.asarray(params, dtype=np.float64).copy()
    n = len(PHENOTYPE_COLUMNS)
    p[:n] = np.clip(p[:n], 0.0, 1.0)
    p[n:] = np.clip(p[n:], -1.0, 1.0)
    return pd.DataFrame([dict(zip(BODY_PARAMETER_COLUMNS, p))])


def measure_body(anthropometer, params: np.ndarray, composition) -> dict:
    """Rest vertices, joints and measures of one body.

    Parameters
    ----------
    anthropometer : wbsa.bodies.anthropometry.Anthropometer
    params : (15,) float64
    composition : wbsa.bodies.composition.CompositionSettings
        How mass follows from the volume (residual deviate 0: the equation's value).

    Returns
    -------
    dict
        ``rest`` (:class:`~wbsa.bodies.body_model.RestBodies` of one body), ``measures`` (the
        :data:`~wbsa.bodies.anthropometry.MEASURE_COLUMNS` with composition's mass and BMI), ``age_years``,
        ``male``, ``table`` (the one-row parameter table).
    """
    from wbsa.bodies.age import param_to_years
    from wbsa.bodies.composition import solve_composition

    table = parameter_table(params)
    rest = anthropometer.model.rest_bodies(table)
    m = anthropometer.measure_one(rest.vertices[0], rest.bone_heads[0])
    age = float(param_to_years(table["p_age"].iloc[0]))
    male = bool(table["p_gender"].iloc[0] < 0.5)
    comp = solve_composition(composition,
                             np.array([m["volume_m3"]]), np.array([m["stature_m"]]), np.array([age]),
                             np.array([male]), np.zeros(1))
    m["mass_kg"], m["bmi"] = float(comp.mass_kg[0]), float(comp.bmi[0])
    return {"rest": rest, "measures": m, "age_years": age, "male": male, "table": table}
