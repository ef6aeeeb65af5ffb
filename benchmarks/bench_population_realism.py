"""Population realism: how varied the virtual bodies are, and what building them costs.

Usage: ``python benchmarks/bench_population_realism.py [--n 300] [--survey-n 200] [--seed 0] [--posture mixed]
[--survey-only] [--survey-measures seven|four|both]``

Builds, with the same seed, four populations and prints for each (:mod:`wbsa.analysis.realism`):

* ``random paper``: the paper's Virtual Random as the default study builds it (uniform macro
  parameters, no local change, constant 980 kg/m³) — the "before";
* ``random varied``: local changes, anny's whole range, an obese half of the adults, density from each
  body's fat fraction (``--sampling varied --density-model deurenberg-siri``) and a posture per subject
  (``--posture``, default ``mixed``: a random named posture with joint jitter; ``a-pose`` for none) —
  the "after";
* ``survey constant`` / ``survey deurenberg-siri``: NHANES people matched at 980 kg/m³ and at their own
  density, on the seven NHANES measures (``--survey-n`` people; ``--survey-n 0`` skips them;
  ``--survey-measures four`` or ``both`` also the four-measure match; ``--survey-only`` skips the random
  populations and the throughput);

the R² and residual SD of the law log WBSA = a + b·log H + c·log W (the scatter of area at fixed
stature and mass), the women–men area difference at the same H and W beside Schlich's scan-fitted
formulae at the same adults, the slope of mesh / Du Bois with BMI beside those of the formulae fitted
on measured areas, subjects per group (all, adults, children, obese, underweight, small, tall, women,
men), the posture mix and the posed − rest skin area per posture (from the ``posture`` and
``wbsa_posed_m2`` columns, when the table has them), adult BMI range, density and fat fraction by sex
and BMI class beside Deurenberg + Siri at the same subjects, and mesh / Du Bois by sex and BMI class
beside the formulae fitted on measured areas, and the bias of Du Bois, Mosteller and Schlich against the
mesh area by sex and BMI class. The published figures come from :mod:`wbsa.analysis.calibration_refs`.

Throughput: bodies per second of the varied population (anny forward pass, every measure, the
composition fixed point) against the bare anny forward pass of the same bodies in the same run (the
floor), and whether the table is identical with ``--workers`` processes (forced parallel) and with one.
Everything is seeded; the numbers are the same on every run except the timings.
"""

from __future__ import annotations

import argparse
import os
import sys
import time
import warnings

os.environ.setdefault("WBSA_PROGRESS", "0")


def _print_population(name: str, table) -> None:
    import pandas as pd

    from wbsa.analysis.calibration_refs import cite, schlich_female_effect_percent
    from wbsa.analysis.realism import (composition_table, dubois_bmi_slopes, dubois_table, formula_bias_table,
                                       group_counts, hw_law, posed_area_change, posture_mix)

    law = hw_law(table)
    adults = table[(table["age_years"] > 15) & ((table["variation"] == 0) if "variation" in table else True)]
    print(f"\n=== {name}: {law.n} bodies ===")
    print(f"log H/W law: R² = {law.r2:.5f}, residual SD = {law.residual_sd_percent:.2f} %, "
          f"coefficients a={law.a:.4f} b={law.b:.4f} c={law.c:.4f}")
    print(f"  published scatter at fixed H and W: {cite('area_scatter_at_fixed_hw_percent')}")
    print(f"women vs men at the same H and W: {law.female_effect_percent:+.2f} % "
          f"(Schlich 2010 at these adults' H and W: "
          f"{schlich_female_effect_percent(adults['stature_m'].to_numpy(), adults['mass_kg'].to_numpy()):+.2f} %)")
    slopes = dubois_bmi_slopes(table)
    print("slope of area / Du Bois with BMI (adults, % per kg/m²): "
          + ", ".join(f"{k} {v:+.3f}" for k, v in slopes.items())
          + f"; Du Bois under in obese patients: {cite('dubois_obese_underestimate_max_percent')}")
    print("subjects per group: " + ", ".join(f"{k} {v}" for k, v in group_counts(table).items()))
    mix = posture_mix(table)
    print("posture mix: " + (", ".join(f"{k} {v}" for k, v in mix.items()) if mix else "no posture column (A-pose)"))
    posed = posed_area_change(table)
    if not posed.empty:
        print("posed − rest skin area, % of WBSA (wbsa_posed_m2 / wbsa_m2 − 1):")
        for r in posed.itertuples():
            print(f"  {r.posture:<14} n {r.n:4d}  mean {r.mean_percent:+.2f}  SD {r.sd_percent:.2f}  "
                  f"min {r.min_percent:+.2f}  max {r.max_percent:+.2f}")
    if len(adults):
        print(f"adult BMI range: {adults['bmi'].min():.1f}–{adults['bmi'].max():.1f} kg/m²; "
              f"stature range (all): {table['stature_m'].min():.2f}–{table['stature_m'].max():.2f} m")
    comp = composition_table(table)
    dub = dubois_table(table)
    both = comp.merge(dub, on=["sex", "bmi_class", "n"])
    print("(D+S: density by Deurenberg 1991 + Siri 1961 at the same BMI, age and sex; D fat: Deurenberg's fat %)")
    print(f"{'sex':<7} {'BMI class':<9} {'n':>4} {'density kg/m³':>15} {'D+S':>5} {'fat %':>11} {'D fat':>6} "
          f"{'mesh/DuBois':>13} {'Schlich/DB':>11} {'Yu/DB':>7} {'L&L/DB':>7}")
    def sd(v: float, fmt: str = ".0f") -> str:
        return "" if pd.isna(v) else "±" + format(v, fmt)

    for _, r in both.iterrows():
        print(f"{r['sex']:<7} {r['bmi_class']:<9} {r['n']:4d} {r['density_kg_m3_mean']:8.0f}"
              f"{sd(r['density_kg_m3_sd']):>7} {r['deurenberg_density_kg_m3_mean']:5.0f} "
              f"{100 * r['fat_fraction_mean']:6.1f}{sd(100 * r['fat_fraction_sd']):>5} "
              f"{100 * r['deurenberg_fat_fraction_mean']:6.1f} "
              f"{r['mesh_over_dubois_mean']:7.3f}{sd(r['mesh_over_dubois_sd'], '.3f'):>7} "
              f"{r['schlich_over_dubois_mean']:11.3f} {r['yu_over_dubois_mean']:7.3f} "
              f"{r['livingston_lee_over_dubois_mean']:7.3f}")
    bias = formula_bias_table(table)
    print("formula bias against the mesh area, 100·(formula / mesh − 1), mean ± SD "
          f"(published: Du Bois under in obese patients {cite('dubois_obese_underestimate_max_percent')}; "
          f"Du Bois − scan by sex and BMI class: {cite('dubois_bias_by_class')})")
    print(f"{'sex':<7} {'BMI class':<9} {'n':>4} {'Du Bois %':>13} {'Mosteller %':>13} {'Schlich %':>13}")
    for _, r in bias.iterrows():
        print(f"{r['sex']:<7} {r['bmi_class']:<9} {r['n']:4d} "
              + " ".join(f"{r[f'{k}_bias_percent_mean']:+6.2f}{sd(r[f'{k}_bias_percent_sd'], '.2f'):>7}"
                         for k in ("dubois", "mosteller", "schlich")))


def main(argv: list[str] | None = None) -> int:
    from wbsa.typing import POSTURE_CHOICES

    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--n", type=int, default=300, help="random subjects (default 300, the demo study's)")
    parser.add_argument("--survey-n", type=int, default=200, help="survey people (default 200; 0 = skip)")
    parser.add_argument("--seed", type=int, default=0)
    parser.add_argument("--workers", type=int, default=2, help="worker processes of the identity check (default 2)")
    parser.add_argument("--posture", choices=POSTURE_CHOICES, default="mixed",
                        help="posture of the varied random population (default mixed; a-pose: none)")
    parser.add_argument("--survey-only", action="store_true",
                        help="only the survey populations (no random population, no throughput)")
    parser.add_argument("--survey-measures", choices=("seven", "four", "both"), default="seven",
                        help="measures the survey people are matched on (default seven; both: each)")
    parser.add_argument("--density-models", default="constant,deurenberg-siri",
                        help="survey density models, comma-separated (default constant,deurenberg-siri)")
    args = parser.parse_args(argv)

    from wbsa.bodies import table as table_module
    from wbsa.bodies.body_model import BodyModel
    from wbsa.bodies.build import build_population
    from wbsa.bodies.composition import CompositionSettings
    from wbsa.bodies.random_population import RandomPopulationSettings, sample_random_parameters
    from wbsa.bodies.survey import SurveyMatchWarning
    from wbsa.bodies.table import measure_population

    print(f"population realism benchmark: n={args.n} survey n={args.survey_n} seed={args.seed} "
          f"posture={args.posture} cpus={os.cpu_count()} load average {os.getloadavg()[0]:.1f}")
    populations = {}
    if not args.survey_only:
        populations = {
            "random paper (default study: uniform, no local change, 980 kg/m³)":
                build_population("random", n=args.n, seed=args.seed, show_progress=False),
                f"random varied (local changes, obese half, deurenberg-siri, posture {args.posture})":
                build_population("random", n=args.n, seed=args.seed, sampling="varied",
                                 density_model="deurenberg-siri", posture=args.posture, show_progress=False),
        }
    measures = ("seven", "four") if args.survey_measures == "both" else (args.survey_measures,)
    if args.survey_n:
        for model in args.density_models.split(","):
            for m in measures:
                with warnings.catch_warnings():
                    warnings.simplefilter("ignore", SurveyMatchWarning)
                    t = build_population("survey", n=args.survey_n, seed=args.seed, density_model=model,
                                         survey_measures=m, show_progress=False)
                populations[f"survey {model}, {m} measures"] = t
                rates = t.attrs["survey"]
                for group in ("adults_bmi_le_40", "adults_bmi_40_50"):
                    g = rates[group]
                    if g["people"]:
                        print(f"survey {model}, {m} measures: {group}: {g['people']} people, all {m} matched "
                              f"{g['matched']:.1%}, stature & mass {g['matched_stature_mass']:.1%}")
    for name, table in populations.items():
        _print_population(name, table)
    if args.survey_only:
        return 0

    # -- throughput: the varied population against the bare anny forward pass, same bodies, same run
    model = BodyModel()
    params = sample_random_parameters(RandomPopulationSettings.varied(n=args.n, seed=args.seed))
    composition = CompositionSettings(model="deurenberg-siri", seed=args.seed)
    measure_population(params.iloc[:64], model=model, composition=composition)  # warm-up
    t0 = time.perf_counter()
    model.rest_bodies(params)
    forward_s = time.perf_counter() - t0
    t0 = time.perf_counter()
    serial = measure_population(params, model=model, composition=composition)
    serial_s = time.perf_counter() - t0
    print(f"\nthroughput ({args.n} varied bodies without postures, 1 process): "
          f"anny forward only {args.n / forward_s:8.1f} bodies/s; "
          f"population (forward + measures + composition) {args.n / serial_s:8.1f} bodies/s "
          f"= {serial_s / forward_s:.1f}x the forward pass")
    # the same table with worker processes (parallel forced below PARALLEL_MIN_BODIES)
    saved = table_module.PARALLEL_MIN_BODIES
    table_module.PARALLEL_MIN_BODIES = 0
    try:
        t0 = time.perf_counter()
        parallel = measure_population(params, composition=composition, workers=args.workers)
        parallel_s = time.perf_counter() - t0
    finally:
        table_module.PARALLEL_MIN_BODIES = saved
    print(f"population, {args.workers} workers: {args.n / parallel_s:8.1f} bodies/s (incl. cluster start-up); "
          f"table identical to 1 process: {serial.equals(parallel)}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
