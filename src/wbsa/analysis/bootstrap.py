"""Paired bootstrap of two predictors' absolute percentage errors, and the verdict read from its interval.

Pure statistics on arrays, used by the claim test (:mod:`wbsa.analysis.claim`): the difference of mean
absolute percentage error (MAPE, in percentage points) between predictor A and one or more comparators B,
evaluated on the same resampled subjects. A *wins* when the whole interval of A − B lies below 0,
*loses* when it lies above 0, and *ties* otherwise.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Literal

import numpy as np

from wbsa.errors import WbsaError

Verdict = Literal["wins", "ties", "loses"]

#: Verdict of a group with fewer subjects than :attr:`wbsa.analysis.claim.ClaimSettings.min_subjects`.
TOO_FEW = "too few subjects"


@dataclass(frozen=True)
class BootstrapDiff:
    """Paired-bootstrap differences of mean APE, A − B, one entry per comparator B.

    Attributes
    ----------
    diff, lo, hi : (m,) float64
        Observed difference of MAPE (percentage points) and its percentile interval.
    """

    diff: np.ndarray
    lo: np.ndarray
    hi: np.ndarray

    @property
    def verdicts(self) -> list[str]:
        """:func:`verdict` of every interval."""
        return [verdict(lo, hi) for lo, hi in zip(self.lo, self.hi)]


def verdict(lo: float, hi: float) -> Verdict:
    """``wins`` if the interval of (A − B) lies below 0, ``loses`` if above 0, else ``ties``."""
    if hi < 0:
        return "wins"
    if lo > 0:
        return "loses"
    return "ties"


def paired_bootstrap(ape_a: np.ndarray, ape_b: np.ndarray, resamples: int = 2000, level: float = 0.95,
                     seed: int | list[int] | np.random.SeedSequence = 0) -> BootstrapDiff:
    """Percentile interval of mean(ape_a) − mean(ape_b), resampling subjects with replacement.

    Both predictors are evaluated on the same resampled subjects (paired), so what they share (a body
    that is hard for both) cancels. Every comparator uses the same resamples.

    Parameters
    ----------
    ape_a : (n,) float64
        Absolute percentage errors of predictor A (e.g. the single view), one per subject.
    ape_b : (n,) or (n, m) float64
        Those of one or ``m`` comparators, on the same subjects in the same order.
    resamples : int
        Bootstrap resamples.
    level : float
        Interval level.
    seed : int, list of int or SeedSequence
        Seed of ``numpy.random.default_rng``.

    Returns
    -------
    BootstrapDiff
        ``(m,)`` arrays (``m = 1`` for a 1-D ``ape_b``).
    """
    a = np.asarray(ape_a, dtype=float)
    b = np.asarray(ape_b, dtype=float)
    if b.ndim == 1:
        b = b[:, None]
    if a.ndim != 1 or b.shape[0] != a.shape[0]:
        raise WbsaError(f"paired bootstrap needs errors of the same subjects: got {a.shape} and {b.shape}")
    n = a.shape[0]
    if n < 2:
        raise WbsaError(f"paired bootstrap needs at least 2 subjects, got {n}")
    if not (np.isfinite(a).all() and np.isfinite(b).all()):
        raise WbsaError("paired bootstrap got non-finite errors; drop the subjects without a prediction first")
    d = a[:, None] - b  # (n, m)
    rng = np.random.default_rng(seed)
    means = np.empty((int(resamples), d.shape[1]))
    chunk = max(1, min(int(resamples), 4_000_000 // n))  # bounded memory: a (chunk, n) count matrix at a time
    p = np.full(n, 1.0 / n)
    for start in range(0, int(resamples), chunk):
        stop = min(int(resamples), start + chunk)
        counts = rng.multinomial(n, p, size=stop - start)  # same law as drawing n subjects with replacement
        means[start:stop] = counts @ d / n
    q = np.quantile(means, [(1 - level) / 2, (1 + level) / 2], axis=0)
    return BootstrapDiff(diff=d.mean(axis=0), lo=q[0], hi=q[1])


def ape_pct(pred_m2: np.ndarray, wbsa_m2: np.ndarray) -> np.ndarray:
    """Absolute percentage error 100·|pred − WBSA|/WBSA, shape of the inputs (broadcast)."""
    y = np.asarray(wbsa_m2, dtype=float)
    return 100.0 * np.abs(np.asarray(pred_m2, dtype=float) - y) / y

