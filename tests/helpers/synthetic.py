"""Synthetic population and scan tables with a known WBSA–VBSA law, for tests and benchmarks of the analysis.

Nothing here is a body model: WBSA is Mosteller's formula times a small random factor, and the
view area is a view-dependent fraction of WBSA with view-dependent multiplicative noise,

    VBSA(θ, φ) = f(θ, φ) · WBSA · (1 + s(θ, φ) · ε),   ε ~ N(0, 1),

so WBSA ≈ VBSA / f with an error that grows with WBSA (heteroscedastic, as in paper section 4.2).
The tables follow the pinned population and scan schemas so the analysis runs on them unchanged.
"""

from __future__ import annotations

import numpy as np
import pandas as pd

#: Azimuths and elevations of the paper's 65 views (θ = 0 only at φ = ±90).
PAPER_AZIMUTHS_DEG = (0.0, 30.0, 45.0, 60.0, 90.0, 120.0, 135.0, 150.0, 180.0)
PAPER_ELEVATIONS_DEG = (-60.0, -45.0, -30.0, 0.0, 30.0, 45.0, 60.0)


def paper_view_angles() -> list[tuple[float, float]]:
    """The 65 (azimuth_deg, elevation_deg) pairs of the paper."""
    views = [(a, e) for e in PAPER_ELEVATIONS_DEG for a in PAPER_AZIMUTHS_DEG]
    return views + [(0.0, -90.0), (0.0, 90.0)]


def view_fraction(azimuth_deg: np.ndarray, elevation_deg: np.ndarray) -> np.ndarray:
    """f(θ, φ): the synthetic visible fraction of WBSA, (n,) float64 in about [0.2, 0.45]."""
    a, e = np.radians(azimuth_deg), np.radians(elevation_deg)
    return 0.22 + 0.2 * np.abs(np.cos(a)) * np.cos(e) + 0.05 * np.abs(np.sin(e))


def view_noise(azimuth_deg: np.ndarray, elevation_deg: np.ndarray) -> np.ndarray:
    """s(θ, φ): relative noise of the synthetic VBSA, (n,) float64 in about [0.005, 0.04]."""
    a, e = np.radians(azimuth_deg), np.radians(elevation_deg)
    return 0.005 + 0.02 * np.abs(np.sin(a)) + 0.015 * np.abs(np.sin(e))


def synthetic_population(n: int, seed: int = 0) -> pd.DataFrame:
    """A population table of ``n`` subjects (kids and adults, statures 0.9–2.3 m, BMI 15–42).

    Returns
    -------
    DataFrame
        Columns of the population schema that the analysis reads: ``subject_id``, ``sex``,
        ``age_years``, ``stature_m``, ``mass_kg``, ``bmi``, ``wbsa_m2``, the circumferences,
        ``front_chest_width_m`` and ``volume_m3``.
    """
    rng = np.random.default_rng(seed)
    sex = np.where(rng.random(n) < 0.5, "male", "female")
    age = rng.uniform(3.0, 80.0, n)
    kid = age <= 15
    stature = np.where(kid, 0.9 + (age - 3.0) / 12.0 * 0.8 + rng.normal(0, 0.05, n), rng.uniform(1.40, 2.30, n))
    bmi = np.where(kid, rng.uniform(14.0, 26.0, n), rng.uniform(17.0, 42.0, n))
    mass = bmi * stature**2
    wbsa = np.sqrt(stature * 100.0 * mass / 3600.0) * (1.0 + rng.normal(0.0, 0.01, n))
    girth = np.sqrt(mass / stature)  # ~ sqrt(kg/m)
    noise = lambda s: 1.0 + rng.normal(0.0, s, n)  # noqa: E731
    return pd.DataFrame({
        "subject_id": np.arange(n, dtype=np.int64),
        "sex": sex,
        "age_years": age,
        "stature_m": stature,
        "mass_kg": mass,
        "bmi": bmi,
        "wbsa_m2": wbsa,
        "waist_circ_m": 0.14 * girth * noise(0.05),
        "hip_circ_m": 0.16 * girth * noise(0.04),
        "bust_circ_m": 0.16 * girth * noise(0.04),
        "underbust_circ_m": 0.14 * girth * noise(0.04),
        "neck_circ_m": 0.06 * girth * noise(0.05),
        "upper_arm_circ_m": 0.05 * girth * noise(0.06),
        "thigh_circ_m": 0.09 * girth * noise(0.06),
        "front_chest_width_m": 0.05 * girth * noise(0.05),
        "volume_m3": mass / 1010.0,
    })


def synthetic_scan(population: pd.DataFrame, views: list[tuple[float, float]] | None = None, seed: int = 0,
                   distance_m: float = 4.3, camera: str = "kinect-v1",
                   frame_limit_m: float | None = 2.25) -> pd.DataFrame:
    """A scan table: one row per subject × view with the law of this module.

    Parameters
    ----------
    population : DataFrame
        From :func:`synthetic_population` (``subject_id``, ``wbsa_m2``, ``stature_m``).
    views : list of (azimuth_deg, elevation_deg)
        Default :func:`paper_view_angles`.
    frame_limit_m : float or None
        Subjects taller than this do not fit in the frame (``fits_in_frame`` False).
    """
    views = views if views is not None else paper_view_angles()
    rng = np.random.default_rng(np.random.SeedSequence([seed, 1]))
    n, m = len(population), len(views)
    az = np.repeat(np.array([v[0] for v in views], dtype=float)[None, :], n, 0).ravel()
    el = np.repeat(np.array([v[1] for v in views], dtype=float)[None, :], n, 0).ravel()
    wbsa = np.repeat(population["wbsa_m2"].to_numpy(float), m)
    stature = np.repeat(population["stature_m"].to_numpy(float), m)
    visible = view_fraction(az, el) * wbsa * (1.0 + view_noise(az, el) * rng.standard_normal(n * m))
    fits = np.ones(n * m, dtype=bool) if frame_limit_m is None else stature <= frame_limit_m
    return pd.DataFrame({
        "subject_id": np.repeat(population["subject_id"].to_numpy(), m),
        "azimuth_deg": az,
        "elevation_deg": el,
        "distance_m": np.full(n * m, float(distance_m)),
        "camera": camera,
        "vbsa_hit_m2": visible * 1.02,
        "vbsa_visible_m2": visible,
        "n_pixels": np.round(visible * 4000).astype(np.int64),
        "fits_in_frame": fits,
    })
