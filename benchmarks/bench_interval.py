"""Coverage of the estimator's interval rule on its own calibration captures, by random halves of the subjects.

The default model's calibration captures (subjects never fitted on) are rendered again, exactly as in
training; their conformal scores (``|log true − log predicted| / s(x)``) are split by subject, the quantile is
taken from one half with each rule and its coverage measured on the other half, over many random halves:

* ``subject rank`` (the estimator's rule): the ⌈(m + 1) L⌉-th of m subjects, as a level over the captures;
* ``plain``: the ⌈(n + 1) L⌉-th of the n captures, as if they were independent;
* ``90 % confidence`` (the rule up to session 11): the rank that covers L with probability 0.9 over the draw.

Coverage is also given by scene (a room with a noisy sensor, an ideal render in a room, the body alone) and,
in noisy rooms, by what the camera did at depth edges. Seeded: the same arguments print the same table.

    python benchmarks/bench_interval.py --workers 2 [--splits 400] [--level 0.95]

The render of the calibration captures takes about 7 minutes on 2 cores.
"""

from __future__ import annotations

import argparse
import time

import numpy as np
import pandas as pd


def rule_ranks(n: int, m: int, level: float) -> dict[str, int]:
    """1-based rank of the score each rule takes among ``n`` capture scores of ``m`` calibration subjects
    (:func:`~wbsa.estimation.methods.regression.model.conformal_rank`; past ``n`` where the rule asks for more scores than there
    are: :func:`quantile_at` takes the largest)."""
    from scipy.stats import binom

    from wbsa.estimation.methods.regression.model import conformal_rank

    confident = int(binom.ppf(0.9, m, level)) + 1  # of m + 1, as the subject rank's ⌈(m + 1) L⌉
    return {"subject rank": conformal_rank(n, m, level)[0], "plain": conformal_rank(n, n, level)[0],
            "90 % confidence": -(-(n + 1) * confident // (m + 1))}


def quantile_at(sorted_scores: np.ndarray, rank: int) -> float:
    """The ``rank``-th (1-based) of the sorted scores (the largest if that rank is past the end)."""
    return float(sorted_scores[min(rank, len(sorted_scores)) - 1])


def split_coverage(scores: np.ndarray, subject: np.ndarray, groups: dict[str, np.ndarray], level: float,
                   splits: int, seed: int) -> pd.DataFrame:
    """Mean coverage on the held-out half, per rule and group, over ``splits`` random halves of the subjects.

    Parameters
    ----------
    scores : (n,) float64
        Conformal scores of the calibration captures.
    subject : (n,) int
        Subject of each capture.
    groups : dict of str to (n,) bool
        Captures to report coverage on (besides all of them).
    """
    rng = np.random.default_rng(seed)
    ids = np.unique(subject)
    rows = []
    for _ in range(splits):
        half = np.isin(subject, rng.permutation(ids)[: len(ids) // 2])
        s = np.sort(scores[half])
        for rule, rank in rule_ranks(len(s), len(ids) // 2, level).items():
            inside = scores[~half] <= quantile_at(s, rank)
            row = {"rule": rule, "all": inside.mean()}
            row.update({g: inside[sel[~half]].mean() for g, sel in groups.items()})
            rows.append(row)
    return pd.DataFrame(rows)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--workers", type=int, default=2)
    ap.add_argument("--splits", type=int, default=400, help="random halves of the subjects (default 400)")
    ap.add_argument("--level", type=float, default=0.95, help="interval level (default 0.95)")
    ap.add_argument("--seed", type=int, default=0, help="seed of the halves")
    args = ap.parse_args()

    from wbsa.estimation.methods.regression.default_model import default_model, default_model_path
    from wbsa.training.pipeline import TrainSettings, calibration_scores, training_renders, usable

    model = default_model()
    t0 = time.perf_counter()
    cal = usable(training_renders(TrainSettings(), ("calibration",), workers=args.workers)["calibration"])
    _, scores, _, _ = calibration_scores(model, cal)
    if len(scores) != len(model.scores) or not np.allclose(np.sort(scores), model.scores):
        raise SystemExit(f"error: these renders do not give the model's calibration scores ({len(scores)} "
                         f"scores, the model has {len(model.scores)}); was the model trained with other "
                         "settings or another wbsa? delete it to retrain")
    t = cal.table
    noisy_room = ~t["alone"].to_numpy(bool) & ~t["ideal_sensor"].to_numpy(bool)
    groups = {"noisy room": noisy_room, "ideal room": ~t["alone"].to_numpy(bool) & t["ideal_sensor"].to_numpy(bool),
              "alone": t["alone"].to_numpy(bool)}
    groups.update({f"noisy room, edges {e}": noisy_room & (t["edge_pixels"] == e).to_numpy()
                   for e in ("kept", "mixed", "dropped")})
    res = split_coverage(scores, t["subject_id"].to_numpy(), groups, args.level, args.splits, args.seed)
    m = int(t["subject_id"].nunique())
    print(f"model {default_model_path()}; {len(scores)} calibration captures of {m} subjects "
          f"({time.perf_counter() - t0:.0f} s); level {args.level:g}; {args.splits} random halves "
          f"of {m // 2} subjects")
    print(f"quantile of the full calibration set: {model.quantile(args.level):.3f} (the estimator's rule)")
    summary = res.groupby("rule", sort=False).mean()
    summary.insert(1, "all, 5th pct", res.groupby("rule", sort=False)["all"].quantile(0.05))
    summary.insert(2, "all, 95th pct", res.groupby("rule", sort=False)["all"].quantile(0.95))
    pd.set_option("display.width", 200)
    print("\nmean coverage on the held-out half:")
    print(summary.round(3).to_string())
    print("\ncaptures per group:", {g: int(sel.sum()) for g, sel in groups.items()})


if __name__ == "__main__":
    main()
