"""A split-conformal interval for the body fit's WBSA, calibrated on renders of subjects outside the test set.

The calibration (``python benchmarks/bench_body_fit.py --calibrate``) fits held-out room captures of its own
subjects (seed 2000: not the benchmark's 1000, nor training's 0 and 1) and stores, numbers only, the
conformal quantiles of the relative error ``e = fit / truth − 1``: with ``n`` calibration errors sorted, the
lower bound is the ``⌊(n + 1)·α/2⌋``-th and the upper the ``⌈(n + 1)·(1 − α/2)⌉``-th (split conformal
prediction, Lei et al. 2018, with the two tails apart since the fit's error is not centred). The interval of a
new fit is then ``[wbsa / (1 + e_hi), wbsa / (1 + e_lo)]``: it covers the truth with probability at least
``1 − α`` if the new image is exchangeable with the calibration captures (the same kinds of subjects, cameras
and rooms), and says nothing for people or scenes unlike them.
"""

from __future__ import annotations

import json
import math
from dataclasses import dataclass
from importlib import resources
from pathlib import Path

import numpy as np

from wbsa.errors import WbsaError

#: Where the calibration is stored (package data, ``wbsa/data``; rebuilt by the command in its ``command`` field).
CALIBRATION_PATH = Path(str(resources.files("wbsa") / "data" / "bodyfit_interval.json"))


@dataclass(frozen=True)
class IntervalCalibration:
    """Conformal bounds of the relative WBSA error.

    Attributes
    ----------
    level : float
    error_lo, error_hi : float
        Bounds of ``fit / truth − 1``.
    n : int
        Calibration fits.
    command : str
        The command that rebuilds it.
    fit : dict or None
        The fit's settings it was calibrated with (:func:`fit_fingerprint`); None in a calibration stored without.
    """

    level: float
    error_lo: float
    error_hi: float
    n: int
    command: str
    fit: dict | None = None

    def interval(self, wbsa_m2: float) -> tuple[float, float]:
        """(lo, hi) m² of a fitted WBSA.

        Parameters
        ----------
        wbsa_m2 : float
            The fitted body's WBSA.
        """
        return wbsa_m2 / (1.0 + self.error_hi), wbsa_m2 / (1.0 + self.error_lo)


#: Settings that do not change the fitted body's WBSA (a safety stop, threads, the mass's composition).
_NOT_FIT = ("time_budget_s", "threads", "composition")


def fit_fingerprint(settings) -> dict:
    """The settings of a :class:`wbsa.estimation.methods.body_fit.BodyFitSettings` that shape the fitted body, as plain values:
    a calibration holds only for fits made with the same.

    Parameters
    ----------
    settings : BodyFitSettings

    Returns
    -------
    dict
        Every field but the safety stop, the threads and the composition (which do not change the WBSA).
    """
    from dataclasses import asdict

    return {k: v for k, v in asdict(settings).items() if k not in _NOT_FIT}


def calibrate(errors: np.ndarray, level: float, command: str, fit: dict | None = None) -> IntervalCalibration:
    """The split-conformal bounds of relative errors ``errors (n,)`` at ``level``.

    Parameters
    ----------
    errors : (n,) float64
        Relative errors ``fit / truth − 1`` of the calibration fits.
    level : float
        The interval's coverage, in (0, 1).
    command : str
        The command that rebuilds the calibration.

    Raises
    ------
    WbsaError
        Too few errors for the level (``n`` below ``2 / (1 − level) − 1``).
    """
    e = np.sort(np.asarray(errors, dtype=np.float64))
    n = len(e)
    alpha = 1.0 - level
    k_lo = math.floor((n + 1) * alpha / 2 + 1e-9)  # (the tolerance: 1 - 0.8 is 0.19999999999999996)
    k_hi = math.ceil((n + 1) * (1 - alpha / 2) - 1e-9)
    if k_lo < 1 or k_hi > n:
        raise WbsaError(f"{n} calibration fits are too few for a {100 * level:g} % interval; need at least "
                        f"{math.ceil(2 / alpha) - 1}")
    return IntervalCalibration(level, float(e[k_lo - 1]), float(e[k_hi - 1]), n, command, fit)


def save(cal: IntervalCalibration, path: Path = CALIBRATION_PATH) -> Path:
    """Write the calibration as JSON (numbers and the rebuild command only).

    Parameters
    ----------
    cal : IntervalCalibration
    path : Path
        Where to write it (package data by default).
    """
    from wbsa.io import write_json

    write_json({"level": cal.level, "error_lo": cal.error_lo, "error_hi": cal.error_hi, "n": cal.n,
                "command": cal.command, "fit": cal.fit}, path)
    return path


def load(path: Path = CALIBRATION_PATH) -> IntervalCalibration | None:
    """The stored calibration, or None when there is none.

    Parameters
    ----------
    path : Path
        The stored calibration (package data by default).
    """
    if not Path(path).exists():
        return None
    try:
        d = json.loads(Path(path).read_text())
        return IntervalCalibration(float(d["level"]), float(d["error_lo"]), float(d["error_hi"]), int(d["n"]),
                                   str(d["command"]), d.get("fit"))
    except (OSError, ValueError, KeyError, TypeError) as exc:
        raise WbsaError(f"the body-fit interval calibration {path} is unreadable ({exc}); rebuild it with "
                        "python benchmarks/bench_body_fit.py --calibrate") from None
