"""The paper's "Virtual NHANES" population: virtual bodies matched to real survey people.

``build_survey_population`` draws ``n`` people from the NHANES 2017–March 2020 body measures
(:mod:`~wbsa.bodies.survey_data`), fits each one's anny phenotypes and local changes to its
stature, mass, waist, hip, arm circumference, upper arm length and upper leg length (or the first
four, ``MatchSettings.measures``; :mod:`~wbsa.bodies.survey_match`), and adds ``variations`` bodies per person
that differ from the match in weight and muscle only (the paper's 500 × 25). Every body is then
measured exactly as the random population is (:func:`~wbsa.bodies.table.measure_population`),
and the match is checked on those final measures:

* ``matched`` is True when every matched measure the survey has is within its tolerance (stature
  1 cm, mass 1 kg, waist and hip 3 cm, arm circumference 2 cm, arm and leg length 1.5 cm);
  ``matched_stature_mass`` checks stature and mass only. People who miss are kept, flagged, and announced with a
  :class:`SurveyMatchWarning`, never dropped silently.
* ``match_*_err_*`` = table measure − survey measure, on the matched body's row (variation 0);
  NaN on variations.

Extra columns beyond :data:`~wbsa.bodies.table.TABLE_COLUMNS`: see :data:`SURVEY_COLUMNS`.
"""

from __future__ import annotations

import time
import warnings
from dataclasses import dataclass, field, replace

import numpy as np
import pandas as pd

from wbsa.io import RUN_LOG_ATTR
from wbsa.errors import WbsaError
from wbsa.bodies.age import years_to_param
from wbsa.bodies.anthropometry import DEFAULT_DENSITY_KG_M3
from wbsa.bodies.composition import COMPOSITION_COLUMNS, CompositionSettings
from wbsa.bodies.survey_match import MatchSettings
from wbsa.parallel import torch_threads
from wbsa.settings_io import check_types

#: Columns a survey population has beyond the random population's.
SURVEY_COLUMNS = (
    "survey_id", "variation", "survey_age_years", "survey_race", "survey_exam_weight",
    "survey_stature_m", "survey_mass_kg", "survey_bmi", "survey_waist_circ_m", "survey_hip_circ_m",
    "survey_mid_arm_circ_m", "survey_upper_arm_length_m", "survey_upper_leg_length_m",
    "match_stature_err_m", "match_mass_err_kg", "match_waist_err_m", "match_hip_err_m", "match_mid_arm_circ_err_m",
    "match_upper_arm_length_err_m", "match_upper_leg_length_err_m",
    "matched", "matched_stature_mass",
)

#: (population column, survey column, error column) of each matched measure.
MATCHED_MEASURES = (
    ("stature_m", "survey_stature_m", "match_stature_err_m"),
    ("mass_kg", "survey_mass_kg", "match_mass_err_kg"),
    ("waist_circ_m", "survey_waist_circ_m", "match_waist_err_m"),
    ("hip_circ_m", "survey_hip_circ_m", "match_hip_err_m"),
    ("mid_arm_circ_m", "survey_mid_arm_circ_m", "match_mid_arm_circ_err_m"),
    ("upper_arm_length_m", "survey_upper_arm_length_m", "match_upper_arm_length_err_m"),
    ("upper_leg_length_m", "survey_upper_leg_length_m", "match_upper_leg_length_err_m"),
)
#: Survey people columns of the matched measures, in :data:`MATCHED_MEASURES` order.
_PEOPLE_MEASURES = ("stature_m", "mass_kg", "waist_circ_m", "hip_circ_m", "mid_arm_circ_m", "upper_arm_length_m",
                    "upper_leg_length_m")
_VARIATION_STREAM = 0x7A21A7


#: Residual weights of the girth-rescue fit: the mass weighs no more than a girth.
RESCUE_WEIGHTS = (3.0, 0.1, 0.1, 0.1, 0.1, 0.1, 0.1)


class SurveyMatchWarning(UserWarning):
    """Some survey people could not be matched within the tolerances (they are flagged)."""


@dataclass(frozen=True)
class SurveyPopulationSettings:
    """How the survey population is built.

    Attributes
    ----------
    match
        Fit tolerances and limits.
    weight_spread, muscle_spread
        A variation draws ``p_weight`` and ``p_muscle`` uniformly within ± these of the matched
        body's values (the interval cut to [0, 1]); everything else stays the match's.
    survey_path
        Survey CSV; None = the copy shipped in the package.
    girth_rescue
        Refit the people matched in stature and mass but not in a girth with
        :data:`RESCUE_WEIGHTS` (:attr:`MatchSettings.rescue_weights`). None: on with a composition
        model, off at constant density, so that constant-density tables stay those of the
        matcher without it.
    """

    match: MatchSettings = field(default_factory=MatchSettings)
    weight_spread: float = 0.2
    muscle_spread: float = 0.3
    survey_path: str | None = None
    girth_rescue: bool | None = None

    def __post_init__(self) -> None:
        check_types(self)
        for name in ("weight_spread", "muscle_spread"):
            if not 0.0 <= getattr(self, name) <= 1.0:
                raise WbsaError(f"{name} = {getattr(self, name)} must lie in [0, 1]")


def build_survey_population(n: int, variations: int = 0, seed: int = 0, *,
                            density_kg_m3: float = DEFAULT_DENSITY_KG_M3, survey_weights: bool = False,
                            composition: CompositionSettings | None = None, show_progress: bool | None = None,
                            settings: SurveyPopulationSettings | None = None) -> pd.DataFrame:
    """Build the survey-matched population table.

    Parameters
    ----------
    n
        Survey people to draw (all ages with a standing height, 2–80 years).
    variations
        Extra bodies per person, varying weight and muscle around the match (0 = matches only).
    seed
        Seed of the draw and of the variations.
    density_kg_m3
        Body density for mass = volume × density, in the fit and in the table (when
        ``composition`` is None or ``constant``).
    composition
        Density model. Other than ``constant``, each person is fitted at the density its
        survey BMI, age and sex give (with the person's residual deviate), and the table's
        bodies get their own density by :func:`~wbsa.bodies.table.with_composition`.
    survey_weights
        Draw people with probability proportional to their exam weight (the survey's
        population weights) instead of uniformly.
    settings
        Tolerances, variation spreads and the survey file.

    Returns
    -------
    pandas.DataFrame
        ``n × (variations + 1)`` rows: :data:`~wbsa.bodies.table.TABLE_COLUMNS` then
        :data:`SURVEY_COLUMNS`. ``subject_id = person × (variations + 1) + variation``. The
        frame's ``attrs["survey"]`` holds the cleaning counts and the match summary
        (:func:`match_rates`), written into a Parquet file's metadata; ``attrs["run_log"]`` the wall and
        CPU seconds of each stage, which :func:`wbsa.io.write_table` keeps out of the file (same bytes
        on every run).
    """
    from wbsa.bodies.anthropometry import Anthropometer
    from wbsa.bodies.body_model import BodyModel
    from wbsa.bodies.survey_data import load_survey, select_people
    from wbsa.bodies.survey_match import DENSITY_COLUMN, match_bodies
    from wbsa.bodies.survey_measures import TorchMeasurer
    from wbsa.bodies.survey_start import StartTable
    from wbsa.bodies.table import measure_population

    s = settings or SurveyPopulationSettings()
    if composition is not None and composition.constant:
        density_kg_m3, composition = composition.density_kg_m3, None
    if not isinstance(variations, (int, np.integer)) or variations < 0:
        raise WbsaError(f"variations = {variations} must be a whole number >= 0 (the paper used 25)")
    clock = _Clock()
    data = load_survey(s.survey_path)
    people = select_people(data.people, n, seed, weighted=survey_weights)
    clock.lap("survey")

    model = BodyModel()
    meter = Anthropometer(model, density_kg_m3)
    measurer = TorchMeasurer(model, meter, s.match.measures)
    clock.lap("model")
    with torch_threads(s.match.threads):
        table = StartTable.build(measurer, s.match.start)
    clock.lap("start_table")
    targets = survey_targets(people)
    if composition is not None:
        targets[DENSITY_COLUMN] = person_density(people, composition)
    rescue = s.girth_rescue if s.girth_rescue is not None else composition is not None
    match = replace(s.match, rescue_weights=RESCUE_WEIGHTS) if rescue and s.match.rescue_weights is None else s.match
    fit = match_bodies(targets, measurer, match, table=table, show_progress=show_progress)
    clock.lap("match")

    params = _with_variations(people, fit, variations, seed, s)
    table = measure_population(params, density_kg_m3=density_kg_m3, composition=composition, model=model,
                               show_progress=show_progress)
    table = _add_match_columns(table, s.match)
    clock.lap("measure")
    summary = {
        "source": data.source,
        "rows": data.n_rows,
        "usable": len(data.people),
        "skipped": dict(data.skipped),
        "dropped": dict(data.dropped),
        "fit_iterations_p50": float(np.median(fit["fit_iterations"])),
        "fit_iterations_max": int(fit["fit_iterations"].max()),
        "measures": s.match.measures,
        **match_rates(table),
    }
    table.attrs["survey"] = summary
    # timings are run information, not data: wbsa.io.write_table keeps them out of the file
    table.attrs[RUN_LOG_ATTR] = {"seconds": clock.wall, "cpu_seconds": clock.cpu}
    _warn_unmatched(table, summary)
    return table


def survey_targets(people: pd.DataFrame) -> pd.DataFrame:
    """Fixed phenotypes and match targets of survey ``people`` (as from ``select_people``)."""
    return pd.DataFrame({
        "p_gender": (people["sex"] == "female").astype(np.float64).to_numpy(),
        "p_age": years_to_param(people["age_years"].to_numpy()),
        "p_african": people["p_african"].to_numpy(),
        "p_asian": people["p_asian"].to_numpy(),
        "p_caucasian": people["p_caucasian"].to_numpy(),
        "target_stature_m": people["stature_m"].to_numpy(),
        "target_mass_kg": people["mass_kg"].to_numpy(),
        **{f"target_{name}": people[name].to_numpy() if name in people.columns else np.full(len(people), np.nan)
           for name in _PEOPLE_MEASURES[2:]},
    })


def person_density(people: pd.DataFrame, composition: CompositionSettings) -> np.ndarray:
    """Density (kg/m³) of each survey person at its own BMI, age and sex, ``(n,) float64``.

    The residual deviate is the one the person's matched body (variation 0) gets in the table
    (:func:`~wbsa.bodies.table.residual_keys`), so fit and table use the same composition.
    """
    from wbsa.bodies.composition import density_at_bmi, residual_z

    keys = np.stack([people["survey_id"].to_numpy(dtype=np.int64), np.zeros(len(people), dtype=np.int64)], axis=1)
    return density_at_bmi(composition, people["bmi"].to_numpy(), people["age_years"].to_numpy(),
                          (people["sex"] == "male").to_numpy(), residual_z(composition.seed, keys))


def _with_variations(people: pd.DataFrame, fit: pd.DataFrame, k: int, seed: int,
                     s: SurveyPopulationSettings) -> pd.DataFrame:
    """Body-parameter rows of every matched body and its ``k`` variations, with the survey columns.

    Variations change weight and muscle only; they keep the person's local changes.
    """
    from wbsa.bodies.body_model import BODY_PARAMETER_COLUMNS

    n = len(people)
    rep = np.repeat(np.arange(n), k + 1)
    variation = np.tile(np.arange(k + 1), n)
    phen = fit[list(BODY_PARAMETER_COLUMNS)].to_numpy()[rep].copy()
    iw, im = BODY_PARAMETER_COLUMNS.index("p_weight"), BODY_PARAMETER_COLUMNS.index("p_muscle")
    ids = people["survey_id"].to_numpy()
    for row in np.flatnonzero(variation > 0):
        # the stream depends on the person and the variation only, not on who else was drawn
        rng = np.random.default_rng(np.random.SeedSequence([int(seed), _VARIATION_STREAM, int(ids[rep[row]]),
                                                            int(variation[row])]))
        u = rng.random(2)
        for col, spread, x in ((iw, s.weight_spread, u[0]), (im, s.muscle_spread, u[1])):
            lo, hi = max(0.0, phen[row, col] - spread), min(1.0, phen[row, col] + spread)
            phen[row, col] = lo + x * (hi - lo)
    out = pd.DataFrame({
        "subject_id": np.arange(len(rep), dtype=np.int64),
        "sex": people["sex"].to_numpy()[rep],
        "age_years": people["age_years"].to_numpy()[rep],
    })
    for j, name in enumerate(BODY_PARAMETER_COLUMNS):
        out[name] = phen[:, j]
    out["survey_id"] = ids[rep].astype(np.int64)
    out["variation"] = variation.astype(np.int64)
    out["survey_age_years"] = people["survey_age_years"].to_numpy()[rep].astype(np.int64)
    out["survey_race"] = people["survey_race"].to_numpy()[rep].astype(np.int64)
    out["survey_exam_weight"] = people["exam_weight"].to_numpy()[rep]
    for src, col in (("bmi", "survey_bmi"), *zip(_PEOPLE_MEASURES, (m[1] for m in MATCHED_MEASURES))):
        out[col] = people[src].to_numpy()[rep] if src in people.columns else np.nan
    return out


def _add_match_columns(table: pd.DataFrame, m: MatchSettings) -> pd.DataFrame:
    """Match errors on each matched body's row and the ``matched`` flags on every row."""
    from wbsa.bodies.table import TABLE_COLUMNS

    out = table.copy()
    first = out["variation"].to_numpy() == 0
    tol = m.tolerance_of
    within = {}
    for measure, survey, err in MATCHED_MEASURES:
        e = out[measure].to_numpy() - out[survey].to_numpy()
        # a measure the survey lacks is not matched and cannot fail; a body whose own girth is
        # undefined (NaN) where the survey has one fails
        within[measure] = np.isnan(out[survey].to_numpy()) | (np.abs(e) <= tol[measure])
        out[err] = np.where(first, e, np.nan)
    stature_mass = within["stature_m"] & within["mass_kg"]
    everything = np.logical_and.reduce([within[name] for name in m.names])
    person = out["survey_id"].to_numpy()
    for column, ok in (("matched", everything), ("matched_stature_mass", stature_mass)):
        # the matched body's flag, on all of its person's rows
        out[column] = pd.Series(np.where(first, ok, True)).groupby(person).transform("all").to_numpy()
    return out[[*TABLE_COLUMNS, *[c for c in COMPOSITION_COLUMNS if c in out.columns], *SURVEY_COLUMNS]]


def match_rates(table: pd.DataFrame) -> dict[str, object]:
    """Match rates and error quantiles of a survey population's matched bodies.

    Groups: all people, adults (18+) with survey BMI ≤ 40 (the target group), and adults with
    survey BMI in (40, 50] (beyond anny's reach for many women). Tables written before the limb
    measures (four measures only) give the four measures' figures.

    Returns
    -------
    dict
        ``{group: {"people", "matched", "matched_stature_mass", "<measure>_within",
        "<measure>_<unit>_p50" / "_p95" / "_max" / "_mean_signed"}}`` with rates as fractions and
        errors in cm / kg; ``<measure>`` is ``stature``, ``mass``, ``waist``, ``hip``, ``mid_arm_circ``,
        ``upper_arm_length``, ``upper_leg_length`` (those the table has).
    """
    first = table[table["variation"] == 0]
    groups = {
        "all": first,
        "adults_bmi_le_40": first[(first["survey_age_years"] >= 18) & (first["survey_bmi"] <= 40)],
        "adults_bmi_40_50": first[(first["survey_age_years"] >= 18) & (first["survey_bmi"] > 40)
                                  & (first["survey_bmi"] <= 50)],
    }
    tol = MatchSettings().tolerance_of
    out: dict[str, object] = {}
    for name, g in groups.items():
        row: dict[str, float] = {"people": int(len(g))}
        if len(g):
            row["matched"] = float(g["matched"].mean())
            row["matched_stature_mass"] = float(g["matched_stature_mass"].mean())
            for measure, _, err in MATCHED_MEASURES:
                if err not in g.columns:
                    continue
                key, scale, unit = error_key(err)
                e = (g[err].abs() * scale).dropna()
                if len(e):
                    row[f"{key}_within"] = float((e <= tol[measure] * scale + 1e-9).mean())
                    row[f"{key}_{unit}_p50"] = float(e.quantile(0.5))
                    row[f"{key}_{unit}_p95"] = float(e.quantile(0.95))
                    row[f"{key}_{unit}_max"] = float(e.max())
                    row[f"{key}_{unit}_mean_signed"] = float((g[err] * scale).mean())
        out[name] = row
    return out


def error_key(err: str) -> tuple[str, float, str]:
    """``(key, scale, unit)`` of an error column: ``match_waist_err_m`` → ``("waist", 100, "cm")``."""
    key = err.removeprefix("match_").removesuffix("_m").removesuffix("_kg").removesuffix("_err")
    return (key, 1.0, "kg") if err.endswith("_kg") else (key, 100.0, "cm")


def unmatched_people(table: pd.DataFrame) -> pd.DataFrame:
    """The people whose matched body misses a tolerance, with the measures it misses.

    Returns
    -------
    pandas.DataFrame
        One row per unmatched person: ``survey_id, sex, survey_age_years, survey_bmi, failing``
        (the missed measures, comma-separated, e.g. ``"mass, hip"``), and every error column.
    """
    first = table[(table["variation"] == 0) & ~table["matched"]]
    tol = MatchSettings().tolerance_of
    failing = []
    for _, row in first.iterrows():
        missed = [error_key(err)[0] for measure, survey, err in MATCHED_MEASURES
                  if err in row.index and np.isfinite(row[survey])
                  and not abs(row[measure] - row[survey]) <= tol[measure]]
        failing.append(", ".join(missed))
    errors = [err for _, _, err in MATCHED_MEASURES if err in first.columns]
    out = first[["survey_id", "sex", "survey_age_years", "survey_bmi", *errors]].copy()
    out.insert(4, "failing", failing)
    return out.reset_index(drop=True)


def _warn_unmatched(table: pd.DataFrame, summary: dict) -> None:
    first = table[table["variation"] == 0]
    bad = int((~first["matched"]).sum())
    skipped = sum(summary["skipped"].values())
    if bad:
        missed: dict[str, int] = {}
        for failing in unmatched_people(table)["failing"]:
            for name in failing.split(", "):
                missed[name] = missed.get(name, 0) + 1
        warnings.warn(
            f"{bad} of {len(first)} survey people are not matched within tolerance (anny cannot reach them; "
            f"missed measures: {_counts(missed)}); they are kept with matched=False. "
            f"{skipped} of {summary['rows']} survey rows were skipped ({_counts(summary['skipped'])})",
            SurveyMatchWarning, stacklevel=3)


def _counts(counts: dict[str, int]) -> str:
    return ", ".join(f"{k}: {v}" for k, v in counts.items()) or "none"


class _Clock:
    """Wall and CPU seconds of consecutive stages."""

    def __init__(self) -> None:
        self.wall: dict[str, float] = {}
        self.cpu: dict[str, float] = {}
        self._t, self._c = time.perf_counter(), time.process_time()

    def lap(self, name: str) -> None:
        t, c = time.perf_counter(), time.process_time()
        self.wall[name], self.cpu[name] = t - self._t, c - self._c
        self._t, self._c = t, c
