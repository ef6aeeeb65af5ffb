"""Survey matching: time and match quality of ``wbsa population --kind survey``.

Draws ``--n`` NHANES people (default 500, the paper's number), matches each (no variations), and
prints the wall and CPU seconds of every stage, the match rates and error quantiles for all
people and for the target group (adults 18+ with BMI <= 40), and the matching time as a ratio
to the baseline measured in the same run: measuring the same bodies exactly (the table stage,
``measure_population``).

    .venv/bin/python benchmarks/bench_survey_match.py --n 500 --seed 0 [--threads 1] [--out matches.parquet]
        [--phenotypes-only] [--density-model deurenberg-siri] [--girth-rescue auto|on|off]

``--phenotypes-only`` keeps the body model's local changes at 0 (the matcher before they were
fitted), for comparison.
"""

from __future__ import annotations

import argparse
import json
import os
import sys
import time
import warnings


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--n", type=int, default=500, help="survey people (default 500)")
    parser.add_argument("--seed", type=int, default=0)
    parser.add_argument("--weighted", action="store_true", help="draw by exam weight")
    parser.add_argument("--threads", type=int, default=1,
                        help="torch threads while matching (default 1, the library default; 0 = torch's own)")
    parser.add_argument("--phenotypes-only", action="store_true",
                        help="fit phenotypes only (local changes stay 0), for comparison")
    parser.add_argument("--density-model", default="constant",
                        choices=("constant", "deurenberg-siri", "deurenberg-brozek"),
                        help="body density: constant 980 kg/m³ (default) or from each person's fat fraction")
    parser.add_argument("--girth-rescue", choices=("auto", "on", "off"), default="auto",
                        help="refit people matched in stature and mass but not in a girth, mass weighted like a "
                             "girth (auto: with a composition model only, the library default)")
    parser.add_argument("--out", help="write the matched table here (.parquet)")
    args = parser.parse_args(argv)

    import torch

    from wbsa.bodies.survey import SurveyMatchWarning, SurveyPopulationSettings, build_survey_population
    from wbsa.bodies.composition import CompositionSettings
    from wbsa.bodies.survey_match import MatchSettings

    settings = SurveyPopulationSettings(match=MatchSettings(threads=args.threads or None,
                                                            free_local_changes=not args.phenotypes_only),
                                        girth_rescue={"auto": None, "on": True, "off": False}[args.girth_rescue])
    threads = args.threads or torch.get_num_threads()
    load0 = os.getloadavg()[0]
    t0, c0 = time.perf_counter(), time.process_time()
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", SurveyMatchWarning)
        table = build_survey_population(args.n, variations=0, seed=args.seed, survey_weights=args.weighted,
                                        show_progress=False, settings=settings,
                                        composition=CompositionSettings(model=args.density_model, seed=args.seed))
    wall, cpu = time.perf_counter() - t0, time.process_time() - c0
    s = {**table.attrs["survey"], **table.attrs["run_log"]}
    if args.out:
        table.to_parquet(args.out, index=False)

    print(f"survey match benchmark: n={args.n} seed={args.seed} weighted={args.weighted} "
          f"local changes {'fixed at 0' if args.phenotypes_only else 'fitted'} density {args.density_model} "
          f"girth rescue {args.girth_rescue} "
          f"torch threads while matching={threads} cpus={os.cpu_count()} "
          f"load average {load0:.1f} -> {os.getloadavg()[0]:.1f}")
    print(f"{'stage':<12} {'wall s':>8} {'cpu s':>8}")
    for stage, w in s["seconds"].items():
        print(f"{stage:<12} {w:8.1f} {s['cpu_seconds'][stage]:8.1f}")
    print(f"{'total':<12} {wall:8.1f} {cpu:8.1f}")
    match = s["seconds"]["start_table"] + s["seconds"]["match"]
    print(f"matching (start table + fit): {match:.1f} s wall = {match / args.n * 1000:.0f} ms per person = "
          f"{match / s['seconds']['measure']:.1f} x the exact measuring of the same bodies (baseline, "
          f"{s['seconds']['measure']:.1f} s)")
    print(f"fit iterations: median {s['fit_iterations_p50']:.0f}, max {s['fit_iterations_max']}")
    for group in ("all", "adults_bmi_le_40", "adults_bmi_40_50"):
        g = s[group]
        print(f"\n{group}: {g['people']} people")
        if not g["people"]:
            continue
        print(f"  matched (all four within 1 cm / 1 kg / 3 cm / 3 cm): {g['matched']:.1%}")
        print(f"  matched stature and mass:                           {g['matched_stature_mass']:.1%}")
        print(f"  {'error':<8} {'within':>7} {'p50':>7} {'p95':>7} {'max':>7} {'mean signed':>12}")
        for key, unit in (("stature_err", "cm"), ("mass_err", "kg"), ("waist_err", "cm"), ("hip_err", "cm")):
            if f"{key}_within" in g:
                print(f"  {key[:-4] + ' ' + unit:<8} {g[key + '_within']:7.1%} {g[f'{key}_{unit}_p50']:7.2f} "
                      f"{g[f'{key}_{unit}_p95']:7.2f} {g[f'{key}_{unit}_max']:7.2f} "
                      f"{g[f'{key}_{unit}_mean_signed']:12.2f}")
    import pandas as pd

    first = table[(table["variation"] == 0) & (table["survey_age_years"] >= 18)]
    classes = pd.cut(first["survey_bmi"], [0, 30, 35, 40, 50, 200], labels=["<=30", "30-35", "35-40", "40-50", ">50"])
    print("\nadults 18+ by sex and survey BMI: people, all four matched, stature & mass matched")
    for (sex, bmi), g in first.groupby([first["sex"], classes], observed=True):
        print(f"  {sex:<7} BMI {bmi:<6} {len(g):4d}  {g['matched'].mean():6.1%}  {g['matched_stature_mass'].mean():6.1%}")
    from wbsa.bodies.body_model import LOCAL_CHANGE_COLUMNS

    print("\nlocal changes of the matched bodies (quantiles 0 / 5 / 50 / 95 / 100 %):")
    for name in LOCAL_CHANGE_COLUMNS:
        q = table[name].quantile([0, 0.05, 0.5, 0.95, 1]).to_numpy()
        print(f"  {name:<20} " + " ".join(f"{x:6.2f}" for x in q))
    print("\nskipped survey rows:", json.dumps(s["skipped"]), " dropped values:", json.dumps(s["dropped"]))
    return 0


if __name__ == "__main__":
    sys.exit(main())
