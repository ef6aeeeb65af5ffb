"""Camera viewpoints on a sphere around the subject: the paper's grid, custom lists, dense grids.

Convention (paper Fig 1, world = +Z up, subject facing −Y, left side at +X):
azimuth θ about +Z, 0 = camera in front (on −Y), 90 = at the subject's left (+X), 180 = behind;
elevation φ, +90 = camera above looking straight down, −90 = below looking straight up;
distance D from the camera centre to the subject's centre (bounding-box centre).
"""

from __future__ import annotations

import math
import re
from dataclasses import dataclass
from typing import Iterable, Sequence

import numpy as np

from wbsa.errors import SettingsError, WbsaError

#: The paper's azimuths and elevations (degrees); ±90 elevation only at azimuth 0 (65 views).
PAPER_AZIMUTHS_DEG = (0.0, 30.0, 45.0, 60.0, 90.0, 120.0, 135.0, 150.0, 180.0)
PAPER_ELEVATIONS_DEG = (0.0, 30.0, -30.0, 45.0, -45.0, 60.0, -60.0)
#: The paper's camera distance (m), chosen to fit its tallest subject (eq. 9).
PAPER_DISTANCE_M = 4.3

VIEW_SPECS = ("paper", "sphere:N", "grid:STEP", "front")

#: The range of a view angle a user gives (degrees): an azimuth within a full turn either way (−30 is 330, at the
#: subject's right), an elevation from straight below to straight above. Angles computed inside wbsa (the
#: Fibonacci sphere, random captures) may lie outside and are normalised by :class:`View`.
ANGLE_RANGES_DEG = {"azimuth": (-360.0, 360.0), "elevation": (-90.0, 90.0)}
_ANGLE_MEANING = {"azimuth": "0 = in front, 90 = at the subject's left, 180 = behind",
                  "elevation": "+90 = straight above, -90 = straight below"}


def check_angle(value: float, kind: str, name: str | None = None) -> float:
    """A view angle a user gave, refused outside its range (:data:`ANGLE_RANGES_DEG`) instead of wrapped.

    Parameters
    ----------
    value : float
        Degrees.
    kind : {'azimuth', 'elevation'}
    name : str, optional
        What the message calls it (a flag, a settings field); default ``kind``.

    Returns
    -------
    float
        ``value`` as a float.

    Raises
    ------
    SettingsError
        If ``value`` is not a finite number in range; the message starts with ``name`` and names the range.

    Examples
    --------
    >>> check_angle(-30, "azimuth")
    -30.0
    >>> check_angle(95, "elevation", "--elevation")
    Traceback (most recent call last):
    ...
    wbsa.errors.SettingsError: --elevation must be -90 to 90 degrees (+90 = straight above, -90 = straight below), got 95
    """
    lo, hi = ANGLE_RANGES_DEG[kind]
    try:
        v = float(value)
    except (TypeError, ValueError):
        v = math.nan
    if not (math.isfinite(v) and lo <= v <= hi):
        raise SettingsError(name or kind, f"must be {lo:g} to {hi:g} degrees ({_ANGLE_MEANING[kind]}), got {value!r}"
                            if not isinstance(value, (int, float)) else
                            f"must be {lo:g} to {hi:g} degrees ({_ANGLE_MEANING[kind]}), got {value:g}")
    return v


def normalise_angles(azimuth_deg: float, elevation_deg: float) -> tuple[float, float]:
    """Bring any (azimuth, elevation) pair to azimuth in [0, 360) and elevation in [−90, 90].

    An elevation past a pole continues over it: (θ, 120°) is the same camera as (θ + 180°, 60°).

    Parameters
    ----------
    azimuth_deg, elevation_deg : float
    """
    az, el = float(azimuth_deg), float(elevation_deg)
    if not (math.isfinite(az) and math.isfinite(el)):
        raise WbsaError(f"view angles must be finite numbers, got azimuth {azimuth_deg!r}, elevation {elevation_deg!r}")
    el = (el + 180.0) % 360.0 - 180.0  # (-180, 180]
    if el > 90.0:
        el, az = 180.0 - el, az + 180.0
    elif el < -90.0:
        el, az = -180.0 - el, az + 180.0
    az = az % 360.0
    if az >= 360.0:  # -1e-17 % 360 == 360.0 in floating point
        az = 0.0
    return az + 0.0, el + 0.0  # + 0.0 turns -0.0 into 0.0


@dataclass(frozen=True)
class View:
    """One camera placement relative to the subject's centre.

    Attributes
    ----------
    azimuth_deg : float
        Normalised to [0, 360).
    elevation_deg : float
        Normalised to [−90, 90].
    distance_m : float
        Camera centre to subject centre, metres (> 0).
    """

    azimuth_deg: float
    elevation_deg: float
    distance_m: float = PAPER_DISTANCE_M

    def __post_init__(self) -> None:
        az, el = normalise_angles(self.azimuth_deg, self.elevation_deg)
        object.__setattr__(self, "azimuth_deg", az)
        object.__setattr__(self, "elevation_deg", el)
        try:
            d = float(self.distance_m)
        except (TypeError, ValueError):
            raise WbsaError(f"camera distance must be a number of metres, got {self.distance_m!r}") from None
        if not (math.isfinite(d) and d > 0):
            raise WbsaError(f"camera distance must be positive and finite, got {d:g} m; e.g. 4.3")
        object.__setattr__(self, "distance_m", d)

    @property
    def direction(self) -> np.ndarray:
        """(3,) float64 unit vector from the subject's centre towards the camera (world frame)."""
        return view_direction(self.azimuth_deg, self.elevation_deg)

    @property
    def label(self) -> str:
        """Short name such as ``az30_el-45`` for file names."""
        return f"az{self.azimuth_deg:g}_el{self.elevation_deg:+g}".replace(".", "p")


def view_direction(azimuth_deg: float, elevation_deg: float) -> np.ndarray:
    """(3,) unit vector from the subject towards the camera: (sin θ cos φ, −cos θ cos φ, sin φ).

    Parameters
    ----------
    azimuth_deg, elevation_deg : float
        The camera's azimuth θ and elevation φ (degrees).
    """
    th, ph = math.radians(azimuth_deg), math.radians(elevation_deg)
    return np.array([math.sin(th) * math.cos(ph), -math.cos(th) * math.cos(ph), math.sin(ph)])


def paper_views(distance_m: float = PAPER_DISTANCE_M) -> list[View]:
    """The paper's 65 views: 9 azimuths × 7 elevations, plus straight down and straight up at azimuth 0.

    Parameters
    ----------
    distance_m : float
        Camera distance of every view.
    """
    views = [View(az, el, distance_m) for el in PAPER_ELEVATIONS_DEG for az in PAPER_AZIMUTHS_DEG]
    views += [View(0.0, 90.0, distance_m), View(0.0, -90.0, distance_m)]
    return views


def sphere_views(n: int, distance_m: float = PAPER_DISTANCE_M) -> list[View]:
    """``n`` nearly uniform views over the whole sphere (Fibonacci lattice), the first one nearest the top.

    Parameters
    ----------
    n : int
        Number of views.
    distance_m : float
        Camera distance of every view.
    """
    if n < 1:
        raise WbsaError(f"sphere:N needs N >= 1, got {n}")
    i = np.arange(n, dtype=np.float64) + 0.5
    z = 1.0 - 2.0 * i / n
    azimuth = np.degrees(i * math.pi * (3.0 - math.sqrt(5.0)))
    elevation = np.degrees(np.arcsin(z))
    return [View(float(a), float(e), distance_m) for a, e in zip(azimuth, elevation)]


def grid_views(step_deg: float, distance_m: float = PAPER_DISTANCE_M) -> list[View]:
    """A regular grid: azimuths 0, step, … < 360 at elevations −90 < k·step < 90, plus both poles once.

    Parameters
    ----------
    step_deg : float
        Angular step of both azimuth and elevation (degrees).
    distance_m : float
        Camera distance of every view.
    """
    if not (math.isfinite(step_deg) and 0 < step_deg <= 180):
        raise WbsaError(f"grid:STEP needs 0 < STEP <= 180 degrees, got {step_deg:g}")
    azimuths = np.arange(0.0, 360.0 - 1e-9, step_deg)
    k = int(math.floor(90.0 / step_deg - 1e-9))
    elevations = [j * step_deg for j in range(-k, k + 1)]
    views = [View(float(a), float(e), distance_m) for e in elevations for a in azimuths]
    return views + [View(0.0, 90.0, distance_m), View(0.0, -90.0, distance_m)]


def parse_angles(text: str | Iterable[float], what: str = "angles") -> list[float]:
    """Degrees from ``'0,30,90'`` or ``'0:180:30'`` (start:stop:step, stop included) or a sequence.

    ``what`` ``'azimuths'`` or ``'elevations'``: each angle is range-checked (:func:`check_angle`).

    Parameters
    ----------
    text : str or iterable of float
    what : str
        ``azimuths``, ``elevations`` (range-checked) or another name for the messages.
    """
    out = _parse_angles(text, what)
    kind = {"azimuths": "azimuth", "elevations": "elevation"}.get(what)
    if kind is not None:
        for a in out:
            check_angle(a, kind, what)
    return out


def _parse_angles(text: str | Iterable[float], what: str) -> list[float]:
    if not isinstance(text, str):
        return [float(x) for x in text]
    out: list[float] = []
    for part in (p.strip() for p in text.split(",")):
        if not part:
            continue
        try:
            if ":" in part:
                start, stop, step = (float(x) for x in part.split(":"))
                if step <= 0 or not math.isfinite(start + stop + step):
                    raise ValueError
                n = int(math.floor((stop - start) / step + 1e-9))
                out += [start + j * step for j in range(n + 1)]
            else:
                value = float(part)
                if not math.isfinite(value):
                    raise ValueError
                out.append(value)
        except ValueError:
            raise WbsaError(f"cannot read {what} {text!r}: use degrees like '0,30,90' or '0:180:30'") from None
    if not out:
        raise WbsaError(f"no {what} in {text!r}; use degrees like '0,30,90'")
    return out


def parse_views(spec: str | None = None, *, azimuths: str | Sequence[float] | None = None,
                elevations: str | Sequence[float] | None = None,
                distance_m: float = PAPER_DISTANCE_M) -> list[View]:
    """A list of views from a named grid or from azimuth × elevation lists.

    Parameters
    ----------
    spec : {'paper', 'front', 'sphere:N', 'grid:STEP'} or None
        ``paper``: the paper's 65 views; ``front``: azimuth 0, elevation 0; ``sphere:N``: N Fibonacci
        views over the sphere; ``grid:STEP``: azimuth and elevation every STEP degrees.
    azimuths, elevations : str or sequence of float, optional
        Degrees (``'0,30,90'``, ``'0:180:30'``); their product is taken, a missing one defaults to 0.
        Azimuths in −360…360, elevations in −90…90 (:func:`check_angle`); they are normalised (azimuth in
        [0, 360)) and exact duplicates after normalisation are dropped.
    distance_m : float
        Camera distance of every view.

    Raises
    ------
    WbsaError
        For an unknown view name, a bad number, or a named grid combined with angle lists.
    """
    if spec is not None and (azimuths is not None or elevations is not None):
        raise WbsaError("give either a named view set or azimuth/elevation lists, not both")
    if spec is None:
        az = parse_angles(azimuths if azimuths is not None else "0", "azimuths")
        el = parse_angles(elevations if elevations is not None else "0", "elevations")
        views = [View(a, e, distance_m) for e in el for a in az]
    else:
        name = spec.strip().lower()
        match = re.fullmatch(r"(sphere|grid):\s*([0-9.eE+-]+)", name)
        if name == "paper":
            views = paper_views(distance_m)
        elif name == "front":
            views = [View(0.0, 0.0, distance_m)]
        elif match and match.group(1) == "sphere":
            try:
                n = int(match.group(2))
            except ValueError:
                raise WbsaError(f"sphere:N needs a whole number of views, got {match.group(2)!r}") from None
            views = sphere_views(n, distance_m)
        elif match:
            try:
                step = float(match.group(2))
            except ValueError:
                raise WbsaError(f"grid:STEP needs a number of degrees, got {match.group(2)!r}") from None
            views = grid_views(step, distance_m)
        else:
            raise WbsaError(f"unknown view set {spec!r}; use one of {', '.join(VIEW_SPECS)} or azimuth/elevation lists")
    seen: set[tuple[float, float]] = set()
    unique = []
    for v in views:
        key = (v.azimuth_deg, v.elevation_deg)
        if key not in seen:
            seen.add(key)
            unique.append(v)
    return unique
