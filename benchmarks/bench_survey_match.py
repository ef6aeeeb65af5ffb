"""Survey matching: match quality on all seven NHANES measures, and its time against four-measure matching.

Draws ``--n`` NHANES people (default 500, the paper's number) and matches the same people twice in one run:
on the seven NHANES measures (stature, mass, waist, hip, arm circumference, upper arm and upper leg length:
the library default) and on the first four (the baseline). Prints, for the seven-measure match, the
within-tolerance rate of every measure and of all seven at once for adults 18+ with survey BMI <= 40 (the
target group) and per sex × age band × BMI class, the error quantiles, the people anny cannot reach with
the measures they miss, and the matching time (start table + fit) of both runs with their ratio.

    .venv/bin/python benchmarks/bench_survey_match.py --n 500 --seed 0 [--density-model deurenberg-siri]
        [--threads 1] [--out matches.parquet] [--only seven|four]
"""

from __future__ import annotations

import argparse
import os
import sys
import time
import warnings

#: Tolerances as printed (cm, kg), by error key.
TOLERANCE = {"stature": 1.0, "mass": 1.0, "waist": 3.0, "hip": 3.0, "mid_arm_circ": 2.0, "upper_arm_length": 1.5,
             "upper_leg_length": 1.5}


def _run(args, measures: str):
    from wbsa.bodies.composition import CompositionSettings
    from wbsa.bodies.survey import SurveyMatchWarning, SurveyPopulationSettings, build_survey_population
    from wbsa.bodies.survey_match import MatchSettings

    settings = SurveyPopulationSettings(match=MatchSettings(measures=measures, threads=args.threads or None))
    t0 = time.perf_counter()
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", SurveyMatchWarning)
        table = build_survey_population(args.n, variations=0, seed=args.seed, show_progress=False, settings=settings,
                                        composition=CompositionSettings(model=args.density_model, seed=args.seed))
    return table, time.perf_counter() - t0


def _within(table):
    """(n,) bool per measure key and all seven, for the matched bodies, NaN-safe (a measure the survey lacks passes)."""
    import numpy as np

    from wbsa.bodies.survey import MATCHED_MEASURES, error_key

    out = {}
    for measure, survey, err in MATCHED_MEASURES:
        key, scale, _ = error_key(err)
        e = (table[measure] - table[survey]).abs() * scale
        out[key] = (table[survey].isna() | (e <= TOLERANCE[key] + 1e-9)).to_numpy()
    out["all seven"] = np.logical_and.reduce([out[k] for k in TOLERANCE])
    return out


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--n", type=int, default=500, help="survey people (default 500)")
    parser.add_argument("--seed", type=int, default=0)
    parser.add_argument("--threads", type=int, default=1, help="torch threads while matching (default 1; 0 = torch's)")
    parser.add_argument("--density-model", default="deurenberg-siri",
                        choices=("constant", "deurenberg-siri", "deurenberg-brozek"),
                        help="body density (default deurenberg-siri, each person's own)")
    parser.add_argument("--only", choices=("seven", "four"), help="run one matching only (no speed ratio)")
    parser.add_argument("--out", help="write the seven-measure table here (.parquet)")
    args = parser.parse_args(argv)

    import numpy as np
    import pandas as pd

    from wbsa.bodies.survey import unmatched_people

    load0 = os.getloadavg()[0]
    runs = {}
    for measures in ("four", "seven"):
        if args.only in (None, measures):
            runs[measures] = _run(args, measures)
    print(f"survey match benchmark: n={args.n} seed={args.seed} density {args.density_model} "
          f"torch threads {args.threads or 'default'} cpus={os.cpu_count()} "
          f"load average {load0:.1f} -> {os.getloadavg()[0]:.1f}")
    print(f"\n{'matching':<8} {'start table s':>14} {'fit s':>8} {'matching s':>11} {'table measures s':>17} "
          f"{'total s':>8} {'fit iterations p50/max':>23}")
    match_s = {}
    for measures, (table, total) in runs.items():
        s = table.attrs["run_log"]["seconds"]
        summary = table.attrs["survey"]
        match_s[measures] = s["start_table"] + s["match"]
        print(f"{measures:<8} {s['start_table']:14.1f} {s['match']:8.1f} {match_s[measures]:11.1f} {s['measure']:17.1f} "
              f"{total:8.1f} {summary['fit_iterations_p50']:>15.0f} / {summary['fit_iterations_max']}")
    if len(match_s) == 2:
        print(f"seven-measure matching takes {match_s['seven'] / match_s['four']:.2f} x the four-measure matching's "
              f"time (start table + fit, same people, same run; target <= 3)")
    if "seven" not in runs:
        return 0
    table = runs["seven"][0]
    if args.out:
        table.to_parquet(args.out, index=False)
    first = table[table["variation"] == 0].reset_index(drop=True)
    within = _within(first)
    adults = (first["survey_age_years"] >= 18).to_numpy()
    target = adults & (first["survey_bmi"] <= 40).to_numpy()
    keys = [*TOLERANCE, "all seven"]
    print(f"\nwithin tolerance (stature 1 cm, mass 1 kg, waist/hip 3 cm, arm circumference 2 cm, arm/leg length "
          f"1.5 cm; a measure the survey lacks counts as within); targets >= 95 % each, >= 90 % all seven")
    print(f"{'group':<34} {'n':>4} " + " ".join(f"{k[:10]:>10}" for k in keys))

    def line(name, mask):
        if mask.sum() == 0:
            return
        print(f"{name:<34} {int(mask.sum()):4d} " + " ".join(f"{within[k][mask].mean():10.1%}" for k in keys))

    line("adults 18+, BMI <= 40 (target)", target)
    line("all people", np.ones(len(first), dtype=bool))
    line("adults 18+, BMI 40-50", adults & (first["survey_bmi"] > 40).to_numpy() & (first["survey_bmi"] <= 50).to_numpy())
    line("children 2-17", ~adults)
    print("\nadults 18+ with BMI <= 40 by sex x age band x BMI class:")
    bands = pd.cut(first["survey_age_years"], [17, 39, 59, 200], labels=["18-39", "40-59", "60+"])
    classes = pd.cut(first["survey_bmi"], [0, 25, 30, 35, 40], labels=["<25", "25-30", "30-35", "35-40"])
    for (sex, band, bmi), g in first[target].groupby([first["sex"], bands, classes], observed=True):
        line(f"  {sex:<6} {band:<5} BMI {bmi}", np.isin(np.arange(len(first)), g.index))
    print("\nerrors, adults 18+ with BMI <= 40 (|table - survey|: p50 / p95 / max; mean signed):")
    for measure_key in TOLERANCE:
        col = next(c for c in first.columns if c.startswith(f"match_{measure_key}_err"))
        scale = 1.0 if col.endswith("_kg") else 100.0
        e = first.loc[target, col].dropna() * scale
        unit = "kg" if col.endswith("_kg") else "cm"
        print(f"  {measure_key:<17} {e.abs().quantile(0.5):6.2f} / {e.abs().quantile(0.95):6.2f} / {e.abs().max():6.2f} "
              f"{unit}; mean {e.mean():+6.2f}")
    missed = unmatched_people(table)
    print(f"\npeople anny cannot reach (all ages and BMIs): {len(missed)} of {len(first)}, with the measures they miss")
    counts: dict[str, int] = {}
    for failing in missed["failing"]:
        for name in failing.split(", "):
            counts[name] = counts.get(name, 0) + 1
    print("  missed measure counts:", ", ".join(f"{k} {v}" for k, v in sorted(counts.items(), key=lambda kv: -kv[1])))
    with pd.option_context("display.width", 200, "display.max_rows", 200):
        print(missed[["survey_id", "sex", "survey_age_years", "survey_bmi", "failing"]].round(1).to_string(index=False))
    from wbsa.bodies.body_model import ALL_LOCAL_CHANGE_COLUMNS

    print("\nlocal changes of the matched bodies (quantiles 0 / 5 / 50 / 95 / 100 %):")
    for name in ALL_LOCAL_CHANGE_COLUMNS:
        q = first[name].quantile([0, 0.05, 0.5, 0.95, 1]).to_numpy()
        print(f"  {name:<20} " + " ".join(f"{x:6.2f}" for x in q))
    return 0


if __name__ == "__main__":
    sys.exit(main())
