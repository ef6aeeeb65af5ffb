"""The estimator's model file: view model, WBSA regression continuous in view and distance, calibrated interval.

WBSA is predicted on the log scale from what :func:`~wbsa.estimation.subject.measure.measure_subject` measures and
the view: a ridge regression of log WBSA on the log seen area (the visible area of
:mod:`~wbsa.estimation.subject.seen_surface`), log stature (paper eq. 8), log silhouette area, width and thickness, each times a view basis (1, cos ψ, cos 2ψ, cos 3ψ, sin φ), plus distance, pixel
pitch, how the camera treated the outline (mixed returns, gaps: the area read through the outline
moves with them), the depth noise (a noisy surface reads a different area), whether a floor was seen and
the clothes the user states (a layer of clothes adds area the image cannot tell from skin);
boosted trees then correct its residual from the same measures, the body's band widths and thicknesses and
the view's uncertainty. The interval is split-conformal: residuals divided by a fitted
spread s(x) on held-out calibration renders (never used in fitting) give the quantile of any level, its
rank counted in calibration subjects (:meth:`EstimatorModel.quantile`, :func:`conformal_rank`).

File layout: one ``.npz`` of numbers (no pickle) with ``meta_json`` (format ``wbsa-estimator``, version
:data:`VERSION`, training settings, feature ranges, held-out metrics). Only files of this version are read:
the version changes whenever the design's terms do (:data:`DESIGN_TERMS`, :data:`SPREAD_TERMS`), and a file
of another version, or with another number of terms, is refused with a request to rebuild it.
"""

from __future__ import annotations

import json
import math
import os
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from wbsa.errors import WbsaError
from wbsa.estimation.methods.regression.design import (DESIGN_TERMS, RANGE_KEYS, SPREAD_TERMS, check_measures, design, range_values,
                                    spread_design, tree_features, with_clothing)
from wbsa.estimation.methods.regression.trees import TreeEnsemble
from wbsa.estimation.methods.regression.view_model import ViewModel

FORMAT = "wbsa-estimator"
VERSION = 6
def conformal_rank(n_scores: int, n_subjects: int, level: float) -> tuple[int, bool]:
    """Rank of the split-conformal quantile of ``level`` among capture scores, counted in subjects.

    With m calibration subjects, k = ⌈(m + 1) L⌉ and the level over the captures L′ = k / (m + 1); the
    rank is the ⌈(n + 1) L′⌉-th of the n capture scores (see :meth:`EstimatorModel.quantile`). With
    ``n_subjects == n_scores`` it is the plain split-conformal rank ⌈(n + 1) L⌉. ⌈(m + 1) L⌉ is taken
    10⁻⁹ below its float product, so a product that is a whole number in exact arithmetic but
    lands just above it in floating point (e.g. 100 × 0.55 = 55.00000000000001) is not rounded up to
    the next rank; the second step is exact integer arithmetic.

    Parameters
    ----------
    n_scores : int
        n, the calibration scores (captures), at least 1.
    n_subjects : int
        m, the calibration subjects behind them, at least 1.
    level : float
        L, the interval's level, in (0, 1).

    Returns
    -------
    rank : int
        1-based rank of the score to take, in [1, n]: the largest score when ``unsure``.
    unsure : bool
        True when the calibration cannot promise ``level``: k > m (or the rank would lie past the n
        scores, which happens only with more subjects than scores).

    Raises
    ------
    WbsaError
        ``level`` outside (0, 1), or fewer than one score or subject.
    """
    if not 0.0 < level < 1.0:
        raise WbsaError(f"interval level {level} must lie in (0, 1), e.g. 0.95")
    n, m = int(n_scores), int(n_subjects)
    if n < 1 or m < 1:
        raise WbsaError(f"a conformal rank needs at least one score and one subject, got {n} scores of "
                        f"{m} subjects; calibrate on more renders")
    k = math.ceil((m + 1) * level - 1e-9)
    if k > m:
        return n, True
    rank = -(-(n + 1) * k // (m + 1))
    return min(rank, n), rank > n


@dataclass
class EstimatorModel:
    """View model, WBSA regression and calibrated interval (see the module doc).

    Attributes
    ----------
    view : ViewModel
    mean, scale : (p,) float64
        Standardisation of :func:`design` columns.
    coef : (p,) float64
    intercept : float
    residual : TreeEnsemble or None
        Correction of the ridge prediction (log scale).
    spread_coef : (SPREAD_TERMS,) float64
        log s(x) = :func:`spread_design` · spread_coef, clipped to ``spread_range``.
    spread_range : (2,) float64
        Range of log s(x) over the out-of-fold predictions on the fit renders (no extrapolation beyond it).
    scores : (k,) float64
        Sorted calibration scores |log residual| / s(x).
    meta : dict
        Format, settings, training ranges, metrics.
    """

    view: ViewModel
    mean: np.ndarray
    scale: np.ndarray
    coef: np.ndarray
    intercept: float
    residual: TreeEnsemble | None
    spread_coef: np.ndarray
    spread_range: np.ndarray
    scores: np.ndarray
    meta: dict = field(default_factory=dict)

    def __repr__(self) -> str:
        trees = 0 if self.residual is None else len(self.residual.roots)
        cal = self.meta.get("calibration", {})
        mape = f", calibration MAPE {cal['wbsa_mape_pct']:.1f} %" if "wbsa_mape_pct" in cal else ""
        return (f"EstimatorModel({self.name!r}: {self.meta.get('n_fit', '?')} fit and {len(self.scores)} calibration "
                f"renders ({self.n_calibration_subjects} subjects), {len(self.coef)} regression terms, {trees} "
                f"residual trees{mape}; .meta for the settings and ranges)")

    @property
    def name(self) -> str:
        """Short identifier (the file name, or ``default``)."""
        return str(self.meta.get("name", "estimator"))

    @property
    def ranges(self) -> dict[str, tuple[float, float]]:
        """Training range of each of :data:`RANGE_KEYS`."""
        return {k: tuple(v) for k, v in self.meta.get("ranges", {}).items()}

    def log_wbsa(self, features: dict[str, np.ndarray], shape: np.ndarray, psi_deg, psi_sd_deg,
                 elevation_deg) -> np.ndarray:
        """Predicted log WBSA (n,).

        Parameters
        ----------
        features, shape, psi_deg, psi_sd_deg, elevation_deg
            As for :func:`~wbsa.estimation.methods.regression.design.tree_features`.
        """
        X = (design(features, psi_deg, elevation_deg) - self.mean) / self.scale
        out = X @ self.coef + self.intercept
        if self.residual is not None:
            out = out + self.residual.predict_raw(tree_features(features, shape, psi_deg, psi_sd_deg, elevation_deg))
        return out

    def quantile(self, level: float) -> float:
        """Calibrated multiplier of s(x) for a two-sided interval of ``level`` (split conformal, by subject).

        Split conformal takes the ⌈(m + 1) L⌉-th smallest of m exchangeable calibration scores: a new
        score falls below it with probability at least L (Vovk et al. 2005; Lei et al. 2018). A body's
        captures share that body and are not exchangeable one by one, so the rank is counted in calibration
        *subjects* (an approximation: the guarantee is for one score per subject): with m subjects
        (``meta["n_calibration_subjects"]``; older files: n over the captures per subject) the level
        L′ = ⌈(m + 1) L⌉ / (m + 1) is taken, and the ⌈(n + 1) L′⌉-th of the n capture scores
        (:func:`conformal_rank`). When ⌈(m + 1) L⌉ > m, no score promises L; the largest is taken and
        :meth:`quantile_is_sure` is False.

        Parameters
        ----------
        level : float
            The interval's coverage, in (0, 1).
        """
        return float(self.scores[self._rank(level)[0] - 1])

    @property
    def n_calibration_subjects(self) -> int:
        """Subjects behind the calibration scores (older files: scores over the captures per subject)."""
        per_subject = float(self.meta.get("settings", {}).get("views_per_subject", 1))
        return max(int(self.meta.get("n_calibration_subjects", round(len(self.scores) / per_subject))), 1)

    def quantile_is_sure(self, level: float) -> bool:
        """Whether the calibration has enough subjects for :meth:`quantile` to promise ``level``.

        Parameters
        ----------
        level : float
            The interval's coverage, in (0, 1).
        """
        return not self._rank(level)[1]

    def _rank(self, level: float) -> tuple[int, bool]:
        """:func:`conformal_rank` of this model's scores and subjects: (1-based rank, unsure). Raises when
        even the plain rank over the n captures, ⌈(n + 1) L⌉, lies past the n scores."""
        n = len(self.scores)
        if n < 1 or conformal_rank(n, n, level)[1]:
            raise WbsaError(f"the model was calibrated on {n} renders, too few for a {100 * level:g} % interval; "
                            f"use a lower level")
        return conformal_rank(n, self.n_calibration_subjects, level)

    def predict(self, features: dict[str, np.ndarray], shape: np.ndarray, psi_deg, psi_sd_deg, elevation_deg,
                level: float = 0.95) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """WBSA (n,) and the interval bounds (n,), m².

        Parameters
        ----------
        features, shape, psi_deg, psi_sd_deg, elevation_deg
            As for :func:`~wbsa.estimation.methods.regression.design.tree_features`.
        level : float
            The interval's coverage, in (0, 1).
        """
        mu = self.log_wbsa(features, shape, psi_deg, psi_sd_deg, elevation_deg)
        half = self.quantile(level) * self.spread(features, psi_deg, psi_sd_deg, mu)
        return np.exp(mu), np.exp(mu - half), np.exp(mu + half)

    def spread(self, features: dict[str, np.ndarray], psi_deg: np.ndarray, psi_sd_deg: np.ndarray,
               log_wbsa: np.ndarray) -> np.ndarray:
        """Fitted residual spread s(x) on the log scale.

        Parameters
        ----------
        features : dict of (n,) float64
        psi_deg, psi_sd_deg : (n,) float64
            Folded azimuth and its spread (degrees).
        log_wbsa : (n,) float64
            The predicted log WBSA (:meth:`log_wbsa`).

        Returns
        -------
        (n,) float64
        """
        z = spread_design(psi_deg, psi_sd_deg, features, log_wbsa) @ self.spread_coef
        return np.exp(np.clip(z, self.spread_range[0], self.spread_range[1]))

    # ------------------------------------------------------------------ file
    def save(self, path: str | os.PathLike) -> Path:
        """Write the model as one ``.npz`` of numbers, atomically; the same model gives the same bytes.

        Parameters
        ----------
        path : str or path
            The ``.npz`` file to write.
        """
        from wbsa.io import write_npz

        arrays = {**self.view.to_arrays(), "mean": self.mean, "scale": self.scale, "coef": self.coef,
                  "intercept": np.array([self.intercept]), "spread_coef": self.spread_coef,
                  "spread_range": self.spread_range, "scores": self.scores}
        if self.residual is not None:
            arrays.update(self.residual.to_arrays("residual_"))
        meta = {"format": FORMAT, "version": VERSION, **self.meta}
        arrays["meta_json"] = np.array(json.dumps(meta, default=_json_default))
        return write_npz(arrays, path)

    @classmethod
    def load(cls, path: str | os.PathLike) -> "EstimatorModel":
        """Read a model written by :meth:`save` (numbers only; no code is loaded).

        Parameters
        ----------
        path : str or path
            A ``.npz`` file :meth:`save` wrote.
        """
        from wbsa.estimation.subject.checks import check_finite_model

        import zipfile

        path = Path(path)
        if not path.is_file():
            raise WbsaError(f"model file {path} does not exist; omit it to use the default model")
        try:
            with np.load(path, allow_pickle=False) as z:
                arrays = {k: z[k] for k in z.files}
            meta_json = arrays.pop("meta_json")
            if meta_json.dtype.kind != "U" or meta_json.ndim != 0:
                raise ValueError("meta_json is not a text")
            meta = json.loads(str(meta_json))
        except (OSError, ValueError, KeyError, EOFError, zipfile.BadZipFile, json.JSONDecodeError) as exc:
            raise WbsaError(f"{path} is not a wbsa estimator model ({type(exc).__name__}: it is empty, truncated or "
                            "not a model file); rebuild it") from None
        if not isinstance(meta, dict) or meta.get("format") != FORMAT or meta.get("version") != VERSION:
            raise WbsaError(f"{path} is not a {FORMAT} version {VERSION} file; rebuild it with this wbsa")
        _check_members(arrays, meta, path)
        check_finite_model(arrays, str(path))
        for key in ("coef", "mean", "scale"):
            if arrays[key].shape != (DESIGN_TERMS,):
                raise WbsaError(f"{path} has {arrays[key].size} regression terms, not {DESIGN_TERMS}; rebuild it "
                                "with this wbsa")
        if arrays["spread_coef"].shape != (SPREAD_TERMS,):
            raise WbsaError(f"{path} has {arrays['spread_coef'].size} spread terms, not {SPREAD_TERMS}; rebuild it "
                            "with this wbsa")
        _check_values(arrays, meta, path)
        residual = (TreeEnsemble.from_arrays(arrays, "residual_", str(path))
                    if any(k.startswith("residual_") for k in arrays) else None)
        meta.setdefault("name", path.name)
        return cls(ViewModel.from_arrays(arrays, str(path)), arrays["mean"], arrays["scale"], arrays["coef"],
                   float(arrays["intercept"][0]), residual, arrays["spread_coef"], arrays["spread_range"],
                   np.sort(arrays["scores"]), meta)


#: The members of a model file besides the trees' (name: how many numbers, or None for any number ≥ 1).
_MEMBERS = {"mean": DESIGN_TERMS, "scale": DESIGN_TERMS, "coef": DESIGN_TERMS, "intercept": 1,
            "spread_coef": SPREAD_TERMS, "spread_range": 2, "scores": None}


def _check_members(arrays: dict, meta: dict, path: Path) -> None:
    """Every member there, a 1-D array of real numbers (not text, not an object); ``meta`` holds dicts where
    dicts belong."""
    for name in _MEMBERS:
        if name not in arrays:
            raise WbsaError(f"{path}: the member {name} is missing; the model file is damaged, rebuild it")
        a = arrays[name]
        if a.ndim != 1 or a.dtype.kind not in "iuf" or a.size == 0:
            raise WbsaError(f"{path}: {name} is a {a.dtype} array of shape {a.shape}, not a list of numbers; "
                            "the model file is damaged, rebuild it")
    for key in ("settings", "ranges", "calibration"):
        if key in meta and not isinstance(meta[key], dict):
            raise WbsaError(f"{path}: meta {key} is a {type(meta[key]).__name__}, not a table; the model file is "
                            "damaged, rebuild it")


def _check_values(arrays: dict, meta: dict, path: Path) -> None:
    """The numbers a prediction divides by or scales with are positive; the trained ranges are finite."""
    def bad(what: str) -> WbsaError:
        return WbsaError(f"{path}: {what}; the model file is damaged, rebuild it")

    if not np.all(arrays["scale"] > 0):
        raise bad(f"scale holds {int(np.sum(arrays['scale'] <= 0))} numbers that are not positive")
    if not arrays["spread_range"][0] <= arrays["spread_range"][1]:
        raise bad("spread_range is reversed")
    scores = arrays["scores"]
    if np.any(scores < 0) or not np.any(scores > 0):
        raise bad("the calibration scores must be positive (an interval's half-width per unit spread), got "
                  f"{int(np.sum(scores < 0))} negative and {int(np.sum(scores == 0))} zero of {scores.size}")
    for name, rng in meta.get("ranges", {}).items():
        try:
            lo, hi = (float(v) for v in rng)
            ok = np.isfinite(lo) and np.isfinite(hi) and lo <= hi
        except (TypeError, ValueError):
            ok = False
        if not ok:
            raise bad(f"the trained range of {name} is {rng!r}, not two finite numbers low to high")


def _json_default(o: object) -> object:
    if isinstance(o, np.generic):
        return o.item()
    if isinstance(o, np.ndarray):
        return o.tolist()
    if isinstance(o, (tuple, set)):
        return list(o)
    return str(o)
