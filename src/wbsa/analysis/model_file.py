"""The fitted per-view models as a JSON file that predicts WBSA with a prediction interval.

File layout (``format: wbsa-model``, ``version: 1``)::

    {"format": "wbsa-model", "version": 1,
     "meta": {"population_kind": ..., "cameras": [...], "distances_m": [...], "vbsa_columns": [...],
              "groups": {name: definition}, "models": {kind: description}, "settings": {...}},
     "entries": [{"group", "vbsa_column", "camera", "distance_m", "azimuth_deg", "elevation_deg",
                  "model", "predictors", "terms", "coef", "cov_unscaled", "scale", "df_resid", "n"}, ...]}

Each entry holds what a prediction interval needs: coefficients, (X'WX)^-1 (``cov_unscaled``),
the residual variance on the model scale (``scale``) and its degrees of freedom. For a new row x
(design of :func:`wbsa.analysis.design.design_matrix`) the interval is
``x·b ± t_{df}((1+level)/2) · sqrt(scale · (x' C x + 1/w))`` on the model scale (w the ``wls``
weight 1/VBSA², else 1), mapped back to m² (exp for ``loglog``).
"""

from __future__ import annotations

import json
import os
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
import pandas as pd

from wbsa.analysis.design import design_matrix, from_model_scale, weights
from wbsa.errors import WbsaError
from wbsa.io import write_text

FORMAT = "wbsa-model"
VERSION = 1

#: Keys of an entry that say where it applies (the rest is the fitted model).
ENTRY_KEYS: tuple[str, ...] = ("group", "vbsa_column", "camera", "distance_m", "azimuth_deg", "elevation_deg",
                               "model", "predictors")
_ENTRY_FIELDS = ENTRY_KEYS + ("terms", "coef", "cov_unscaled", "scale", "df_resid", "n")


def _angle_key(x: float) -> float:
    return round(float(x), 6) + 0.0


def _az_key(az: float) -> float:
    return _angle_key(float(az) % 360.0) % 360.0


@dataclass
class WbsaModel:
    """Per-view, per-group WBSA models; built by :func:`wbsa.analysis.fit_views.fit_all`, saved as JSON.

    Attributes
    ----------
    entries : list of dict
        One fitted model per (group, VBSA column, camera, distance, view, model kind, predictor set).
    meta : dict
        Population kind, cameras, distances, group definitions, fit settings.
    """

    entries: list[dict]
    meta: dict = field(default_factory=dict)

    def __post_init__(self) -> None:
        self._index: dict[tuple, dict] = {}
        for e in self.entries:
            missing = [f for f in _ENTRY_FIELDS if f not in e]
            if missing:
                raise WbsaError(f"model entry lacks {', '.join(missing)}; refit with wbsa fit")
            self._index[self._key(e)] = e

    def __repr__(self) -> str:
        """One line: entries, views and the values of each key (``print`` of the entries is megabytes)."""
        def few(values, unit: str = "") -> str:
            values = list(dict.fromkeys(values))
            shown = ", ".join(f"{v:g}" if isinstance(v, float) else str(v) for v in values[:8])
            return shown + unit + (f", … ({len(values)})" if len(values) > 8 else "")

        e = self.entries
        views = {(_az_key(x["azimuth_deg"]), _angle_key(x["elevation_deg"])) for x in e}
        return (f"WbsaModel({len(e):,} entries, {len(views)} views; kinds {few(x['model'] for x in e)}; "
                f"groups {few(x['group'] for x in e)}; "
                f"predictors {few('+'.join(['vbsa', *x['predictors']]) for x in e)}; "
                f"columns {few(x['vbsa_column'] for x in e)}; cameras {few(str(x['camera']) for x in e)}; "
                f"distances {few((float(x['distance_m']) for x in e), ' m')})")

    @staticmethod
    def _key(e: dict) -> tuple:
        return (e["group"], e["model"], frozenset(e["predictors"]), e["vbsa_column"], str(e["camera"]),
                _angle_key(e["distance_m"]), _az_key(e["azimuth_deg"]), _angle_key(e["elevation_deg"]))

    # ------------------------------------------------------------------ I/O
    def save(self, path: str | os.PathLike) -> Path:
        """Write the model atomically as JSON (one entry per line)."""
        head = json.dumps({"format": FORMAT, "version": VERSION, "meta": self.meta}, indent=2, default=_json_default)
        lines = [json.dumps({f: e[f] for f in _ENTRY_FIELDS}, default=_json_default) for e in self.entries]
        text = head[:-2] + ',\n  "entries": [\n    ' + ",\n    ".join(lines) + "\n  ]\n}\n"
        write_text(text, path)
        return Path(path)

    @classmethod
    def load(cls, path: str | os.PathLike) -> "WbsaModel":
        """Read a model file written by :meth:`save`, checking every number in it.

        Raises
        ------
        WbsaError
            Missing or unreadable file, another format or version, or an entry with a missing field,
            a non-finite or out-of-range number (NaN coefficients, negative variance, ...).
        """
        path = Path(path)
        if not path.is_file():
            raise WbsaError(f"model file {path} does not exist; run wbsa fit first")
        try:
            obj = json.loads(path.read_text())
        except (json.JSONDecodeError, UnicodeDecodeError) as exc:
            raise WbsaError(f"{path} is not valid JSON ({exc.__class__.__name__}); "
                            "regenerate it with wbsa fit") from None
        except OSError as exc:
            from wbsa.io import os_error_message

            raise WbsaError(os_error_message(exc, path, "read")) from None
        if not isinstance(obj, dict) or obj.get("format") != FORMAT:
            raise WbsaError(f"{path} is not a wbsa model file; regenerate it with wbsa fit")
        if obj.get("version") != VERSION:
            raise WbsaError(f"{path} has model format version {obj.get('version')}, this wbsa reads {VERSION}; refit")
        entries, meta = obj.get("entries", []), obj.get("meta", {})
        if not isinstance(entries, list) or not isinstance(meta, dict):
            raise WbsaError(f"{path}: entries must be a list and meta an object; regenerate it with wbsa fit")
        for i, e in enumerate(entries):
            problem = entry_problem(e)
            if problem:
                raise WbsaError(f"{path}: entry {i} {problem}; regenerate the file with wbsa fit")
        return cls(entries=list(entries), meta=dict(meta))

    # ------------------------------------------------------------ queries
    def table(self) -> pd.DataFrame:
        """One row per entry with its keys, ``n``, ``df_resid``, ``scale`` and coefficients by term."""
        rows = []
        for e in self.entries:
            row = {k: e[k] for k in ENTRY_KEYS}
            row["predictors"] = "+".join(["vbsa", *e["predictors"]])
            row.update(n=e["n"], df_resid=e["df_resid"], scale=e["scale"])
            row.update({f"coef_{t}": b for t, b in zip(e["terms"], e["coef"])})
            rows.append(row)
        return pd.DataFrame(rows)

    def _select(self, group: str, model: str, predictors: frozenset, vbsa_column: str | None, camera: str | None,
                distance_m: float | None) -> dict[tuple[float, float], dict]:
        cands = [e for k, e in self._index.items() if k[0] == group and k[1] == model]
        if not cands:
            have = sorted({(k[0], k[1]) for k in self._index})
            raise WbsaError(f"no model for group {group!r} and kind {model!r}; available: "
                            + ", ".join(f"{g}/{m}" for g, m in have))
        sets = sorted({tuple(sorted(e["predictors"])) for e in cands})
        cands = [e for e in cands if frozenset(e["predictors"]) == predictors]
        if not cands:
            raise WbsaError(f"no {model} model for group {group!r} with extra predictors "
                            f"{sorted(predictors) or 'none'}; available sets: "
                            f"{', '.join('+'.join(s) or 'none' for s in sets)}")
        for name, want, key in (("vbsa_column", vbsa_column, lambda e: e["vbsa_column"]),
                                ("camera", camera, lambda e: str(e["camera"])),
                                ("distance_m", distance_m, lambda e: _angle_key(e["distance_m"]))):
            have = sorted({key(e) for e in cands})
            if want is None:
                if len(have) > 1:
                    raise WbsaError(f"the model holds several {name} values "
                                    f"({', '.join(map(str, have))}); pass {name}=")
                continue
            want_k = _angle_key(want) if name == "distance_m" else str(want)
            cands = [e for e in cands if key(e) == want_k]
            if not cands:
                raise WbsaError(f"no model for {name} = {want}; available: {', '.join(map(str, have))}")
        return {(_az_key(e["azimuth_deg"]), _angle_key(e["elevation_deg"])): e for e in cands}

    @staticmethod
    def _entry_for_view(views: dict[tuple[float, float], dict], az: float, el: float) -> dict:
        key = (_az_key(az), _angle_key(el))
        if key in views:
            return views[key]
        if abs(key[1]) == 90.0:  # at the poles the azimuth only spins the image
            at_pole = [e for (a, e_), e in views.items() if e_ == key[1]]
            if len(at_pole) == 1:
                return at_pole[0]
        near = min(views, key=lambda v: (abs((v[0] - key[0] + 180) % 360 - 180) + abs(v[1] - key[1])))
        raise WbsaError(f"no fit for view azimuth {az:g}, elevation {el:g}; nearest fitted view is "
                        f"azimuth {near[0]:g}, elevation {near[1]:g}")

    def predict(self, azimuth_deg, elevation_deg, vbsa_m2, stature_m=None, group: str = "all", *,
                model: str = "linear", extras: dict | None = None, level: float = 0.95, vbsa_column: str | None = None,
                camera: str | None = None, distance_m: float | None = None
                ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Predict WBSA with a prediction interval.

        Parameters
        ----------
        azimuth_deg, elevation_deg : float or (m,) float64
            View of each input (must be a fitted view; azimuth taken modulo 360).
        vbsa_m2 : float or (m,) float64
            Measured view body surface area, m².
        stature_m : float or (m,) float64, optional
            Stature; given, the model with stature as extra predictor is used, else the VBSA-only one.
        group : str
            Group whose model to use (default ``all``).
        model : str
            Model kind (default ``linear``).
        extras : dict name -> float or (m,) float64, optional
            Further predictors, for models fitted with them.
        level : float
            Coverage of the prediction interval, in (0, 1).
        vbsa_column, camera, distance_m : optional
            Needed only if the model file holds several.

        Returns
        -------
        wbsa_m2, lo_m2, hi_m2 : (m,) float64
            Prediction (the conditional median for ``loglog``) and interval bounds; NaN where an
            input lies outside the model's domain (e.g. VBSA <= 0 for ``loglog``).
        """
        from scipy import stats

        if not 0 < level < 1:
            raise WbsaError(f"prediction level {level} must lie in (0, 1), e.g. 0.95")
        named = dict(extras or {})
        if stature_m is not None:
            named["stature_m"] = stature_m
        views = self._select(group, model, frozenset(named), vbsa_column, camera, distance_m)
        arrays = np.broadcast_arrays(*(np.atleast_1d(np.asarray(a, dtype=float))
                                       for a in (azimuth_deg, elevation_deg, vbsa_m2, *named.values())))
        az, el, vbsa = (a.ravel() for a in arrays[:3])
        extra_vals = dict(zip(named, (a.ravel() for a in arrays[3:])))
        out = np.full((3, az.size), np.nan)
        keys = np.column_stack([np.mod(np.round(az, 6), 360.0), np.round(el, 6)])
        uniq, inverse = np.unique(keys, axis=0, return_inverse=True)
        inverse = inverse.ravel()
        for i, (a, e) in enumerate(uniq):
            entry = self._entry_for_view(views, a, e)
            rows = inverse == i
            X = design_matrix(entry["model"], vbsa[rows], {p: extra_vals[p][rows] for p in entry["predictors"]})
            coef = np.asarray(entry["coef"], dtype=float)
            cov = np.asarray(entry["cov_unscaled"], dtype=float)
            w = weights(entry["model"], vbsa[rows])
            with np.errstate(all="ignore"):
                mu = X @ coef
                var = entry["scale"] * (np.einsum("ij,jk,ik->i", X, cov, X) + (1.0 if w is None else 1.0 / w))
                half = stats.t.ppf(0.5 + level / 2.0, entry["df_resid"]) * np.sqrt(var)
                out[:, rows] = [from_model_scale(entry["model"], v) for v in (mu, mu - half, mu + half)]
        shape = arrays[0].shape
        return tuple(o.reshape(shape) for o in out)  # type: ignore[return-value]


def entry_problem(e: object) -> str:
    """What is wrong with one model-file entry, or ``''`` when nothing is.

    Checks the fields' presence and types, that coefficients, their (X'X)^-1 and the residual
    variance are finite, that the variance is >= 0 and the degrees of freedom and ``n`` positive,
    and that the view and distance are finite numbers.
    """
    import math

    if not isinstance(e, dict):
        return "is not an object"
    missing = [f for f in _ENTRY_FIELDS if f not in e]
    if missing:
        return f"lacks {', '.join(missing)}"
    if not isinstance(e["predictors"], list) or not all(isinstance(p, str) for p in e["predictors"]):
        return "has predictors that are not a list of names"
    for key in ("group", "model", "vbsa_column"):
        if not isinstance(e[key], str):
            return f"has a {key} that is not a name"
    for key in ("distance_m", "azimuth_deg", "elevation_deg", "scale"):
        v = e[key]
        if isinstance(v, bool) or not isinstance(v, (int, float)) or not math.isfinite(v):
            return f"has a non-finite or non-numeric {key} ({v!r})"
    if e["scale"] < 0 or e["distance_m"] <= 0:
        return f"has a negative residual variance or a non-positive distance ({e['scale']!r}, {e['distance_m']!r})"
    for key in ("df_resid", "n"):
        v = e[key]
        if isinstance(v, bool) or not isinstance(v, (int, float)) or not v >= 1 or v != int(v):
            return f"has {key} = {v!r}, not a whole number >= 1"
    try:
        coef = np.asarray(e["coef"], dtype=float)
        cov = np.asarray(e["cov_unscaled"], dtype=float)
    except (TypeError, ValueError):
        return "has coefficients or a covariance that are not numbers"
    p = len(e["terms"]) if isinstance(e["terms"], list) else -1
    if coef.shape != (p,) or cov.shape != (p, p):
        return f"has {coef.size} coefficients and a {cov.shape} covariance for {p} terms"
    if not (np.isfinite(coef).all() and np.isfinite(cov).all()):
        return "has non-finite (NaN or infinite) coefficients or covariance"
    return ""


def _json_default(o: object) -> object:
    if isinstance(o, np.generic):
        return o.item()
    if isinstance(o, np.ndarray):
        return o.tolist()
    if isinstance(o, (set, frozenset, tuple)):
        return list(o)
    if isinstance(o, Path):
        return str(o)
    raise TypeError(f"not JSON serialisable: {type(o).__name__}")
