"""The share of the whole body surface area below each height: what a frame that cuts off the legs leaves unseen.

A person cut off by the frame (or hidden by a desk) above the floor shows only the body above some height
h; given the stature S, the share of the skin below h is read from :data:`AREA_BELOW` at h / S, with its
spread over people. :func:`wbsa.estimation.subject.unseen.unseen_legs` uses it to complete the unseen
legs and to widen the interval by that spread.

The table is measured on anny bodies of the held-out benchmark's mix (random and survey-matched adults
and children, seed 2000, never the held-out seed 1000), each standing in a drawn posture: the area of the
skin's triangles whose centroid lies below h, over the body's whole skin. Rebuilt, printed as the
constants below, by::

    python benchmarks/bench_area_profile.py --subjects 120
"""

from __future__ import annotations

import numpy as np

#: Height over the floor as a share of the stature at which :data:`AREA_BELOW` is tabulated.
HEIGHT_SHARES = np.linspace(0.0, 0.6, 25)
#: Mean and standard deviation over people of the share of the WBSA below each of :data:`HEIGHT_SHARES`
#: (``python benchmarks/bench_area_profile.py --subjects 120``).
AREA_BELOW = np.array([
    [0.0000, 0.0000],
    [0.0491, 0.0049],
    [0.0686, 0.0071],
    [0.0811, 0.0078],
    [0.0921, 0.0082],
    [0.1051, 0.0083],
    [0.1192, 0.0086],
    [0.1343, 0.0084],
    [0.1519, 0.0084],
    [0.1702, 0.0085],
    [0.1886, 0.0085],
    [0.2074, 0.0085],
    [0.2261, 0.0084],
    [0.2455, 0.0083],
    [0.2665, 0.0083],
    [0.2894, 0.0083],
    [0.3142, 0.0089],
    [0.3412, 0.0105],
    [0.3706, 0.0140],
    [0.4010, 0.0177],
    [0.4312, 0.0204],
    [0.4605, 0.0237],
    [0.4905, 0.0271],
    [0.5234, 0.0296],
    [0.5575, 0.0312],
])


def area_below_share(height_share) -> tuple[np.ndarray, np.ndarray]:
    """Share of the WBSA below a height (a share of the stature): its mean and spread over people.

    Parameters
    ----------
    height_share : float or (n,) float64
        Height over the floor over the stature; clipped to [0, 0.6] (the table's range).

    Returns
    -------
    mean, sd : (n,) float64 (0-d for a scalar)
    """
    h = np.clip(np.asarray(height_share, dtype=np.float64), HEIGHT_SHARES[0], HEIGHT_SHARES[-1])
    return np.interp(h, HEIGHT_SHARES, AREA_BELOW[:, 0]), np.interp(h, HEIGHT_SHARES, AREA_BELOW[:, 1])


def skin_share_below(vertices: np.ndarray, faces: np.ndarray, height_shares: np.ndarray = HEIGHT_SHARES) -> np.ndarray:
    """Share of a standing body's skin area whose triangles' centroids lie below each height.

    Parameters
    ----------
    vertices : (n, 3) float64
        The posed body standing on z = 0 (metres).
    faces : (m, 3) int
        The skin's triangles.
    height_shares : (k,) float64
        Heights as shares of the body's height (its highest vertex).

    Returns
    -------
    (k,) float64
    """
    from wbsa.core.mesh import triangle_areas_m2

    area = triangle_areas_m2(vertices, faces)
    z = vertices[faces, 2].mean(axis=1) / float(vertices[:, 2].max())
    order = np.argsort(z)
    cumulative = np.concatenate([[0.0], np.cumsum(area[order])]) / area.sum()
    return cumulative[np.searchsorted(z[order], np.asarray(height_shares, dtype=np.float64), side="right")]


def measure_area_profile(population, seed: int = 2000) -> np.ndarray:
    """(len(HEIGHT_SHARES), 2) float64: mean and standard deviation of :func:`skin_share_below` over the bodies
    of ``population`` (a table of anny parameters), each in a standing posture drawn from ``seed``."""
    from wbsa.bodies.body_model import BodyModel
    from wbsa.bodies.posture import RandomPosture

    body_model = BodyModel()
    bodies = body_model.rest_bodies(population)
    poser = RandomPosture(body_model)
    shares = []
    for b in range(len(population)):
        rng = np.random.default_rng(np.random.SeedSequence([seed, b]))
        vertices, _ = poser(bodies.vertices[b], bodies.bone_heads[b], rng)
        shares.append(skin_share_below(vertices, body_model.skin_faces))
    shares = np.array(shares)
    return np.column_stack([shares.mean(axis=0), shares.std(axis=0, ddof=1)])
