"""NHANES 2017–March 2020 body measures: loading, cleaning and selecting survey people.

The package ships a trimmed copy of the survey file (``wbsa/data/nhanes_bmx_demo.csv``: all
14,300 people, only the columns used here, the CDC provenance header kept), so the survey
population needs nothing outside the package. Any file with the same columns (for example the
full ``nhanes-2017-2020-bmx-demo.csv``) can be given instead.

Cleaning never stops a run, and never matches a bad row silently: a person without a usable sex,
age, stature or mass, pregnant at the exam, or with any body measure outside its plausible range (a
waist of 3 m, a negative arm: an error in the row) is skipped and counted by reason; a *missing*
waist, hip, arm or leg measure only leaves that measure out of the match (and is counted).
"""

from __future__ import annotations

import os
from dataclasses import dataclass, field

import numpy as np
import pandas as pd

from wbsa.errors import WbsaError

#: Survey columns read (NHANES variable names).
SURVEY_COLUMNS = ("SEQN", "RIAGENDR", "RIDAGEYR", "RIDRETH3", "RIDEXPRG", "BMXWT", "BMXHT", "BMXWAIST",
                  "BMXHIP", "WTMECPRP")
#: The NHANES limb measures, read when the file has them (a file without them gives NaN: four-measure
#: matching only): arm circumference, upper arm length, upper leg length (cm).
LIMB_SURVEY_COLUMNS = ("BMXARMC", "BMXARML", "BMXLEG")
#: (NHANES column, people column, reason word) of the optional measures, in match order.
_OPTIONAL_MEASURES = (("BMXWAIST", "waist_circ_m", "waist"), ("BMXHIP", "hip_circ_m", "hip"),
                      ("BMXARMC", "mid_arm_circ_m", "arm circumference"),
                      ("BMXARML", "upper_arm_length_m", "upper arm length"),
                      ("BMXLEG", "upper_leg_length_m", "upper leg length"))
#: The packaged copy, inside the ``wbsa`` package.
PACKAGED_FILE = "data/nhanes_bmx_demo.csv"

#: RIDRETH3 code → (african, asian, caucasian) mix of anny's three ethnic blendshapes.
#: anny's three groups are appearance morphs, not ancestries; each survey group gets the rounded
#: average genetic ancestry reported for it in the US (e.g. Bryc et al., Am J Hum Genet 2015),
#: with Native American ancestry given to "asian", the closest of the three morphs.
ETHNIC_MIX = {
    1: (0.05, 0.40, 0.55),  # Mexican American
    2: (0.15, 0.20, 0.65),  # Other Hispanic
    3: (0.00, 0.00, 1.00),  # Non-Hispanic White
    4: (0.75, 0.00, 0.25),  # Non-Hispanic Black
    6: (0.00, 1.00, 0.00),  # Non-Hispanic Asian
    7: (1 / 3, 1 / 3, 1 / 3),  # Other race, including multi-racial
}
#: Mix for a missing or unknown RIDRETH3 code.
UNKNOWN_MIX = (1 / 3, 1 / 3, 1 / 3)

#: Plausible ranges (inclusive) of the cleaned measures; values outside are dropped and counted.
PLAUSIBLE = {
    "age_years": (0.0, 110.0),
    "stature_m": (0.5, 2.5),
    "mass_kg": (2.0, 350.0),
    "waist_circ_m": (0.3, 2.5),
    "hip_circ_m": (0.4, 2.5),
    "mid_arm_circ_m": (0.08, 0.9),
    "upper_arm_length_m": (0.08, 0.6),
    "upper_leg_length_m": (0.15, 0.8),
    "bmi": (8.0, 90.0),
}

#: Columns of :attr:`SurveyData.people`.
PEOPLE_COLUMNS = ("survey_id", "sex", "age_years", "survey_age_years", "survey_race", "p_african", "p_asian",
                  "p_caucasian", "stature_m", "mass_kg", "bmi", "waist_circ_m", "hip_circ_m", "mid_arm_circ_m",
                  "upper_arm_length_m", "upper_leg_length_m", "exam_weight")


@dataclass(frozen=True)
class SurveyData:
    """Cleaned survey people and what cleaning dropped.

    Attributes
    ----------
    people : pandas.DataFrame
        One row per usable person, columns :data:`PEOPLE_COLUMNS` (SI units; ``age_years`` is
        the middle of the completed year of age, ``survey_age_years`` the survey's integer,
        ``survey_race`` the RIDRETH3 code (−1 if missing);
        waist, hip and the limb measures NaN where not measured; ``exam_weight`` NaN where missing).
    skipped : dict[str, int]
        People skipped, by reason.
    dropped : dict[str, int]
        Measures missing (the person kept, the measure left out of the match), by reason, e.g.
        ``"waist missing"``; also ``"race unknown"`` and ``"exam weight missing"``.
    source : str
        Where the data came from.
    """

    people: pd.DataFrame
    skipped: dict[str, int] = field(default_factory=dict)
    dropped: dict[str, int] = field(default_factory=dict)
    source: str = ""

    @property
    def n_rows(self) -> int:
        """Rows in the source file."""
        return len(self.people) + sum(self.skipped.values())


def load_survey(path: str | os.PathLike | None = None) -> SurveyData:
    """Read and clean the survey file (the packaged copy when ``path`` is None).

    Raises
    ------
    WbsaError
        If the file cannot be read or lacks one of :data:`SURVEY_COLUMNS`.
    """
    if path is None:
        from importlib.resources import files

        resource = files("wbsa").joinpath(PACKAGED_FILE)
        with resource.open("r", encoding="utf-8") as fh:
            raw = _read_csv(fh, "the packaged survey file")
        source = f"wbsa/{PACKAGED_FILE}"
    else:
        try:
            with open(path, encoding="utf-8") as fh:
                raw = _read_csv(fh, str(path))
        except OSError as exc:
            raise WbsaError(f"cannot read survey file {path}: {exc.strerror}; give an NHANES BMX+DEMO CSV") from None
        source = str(path)
    return clean_survey(raw, source)


def _read_csv(fh, what: str) -> pd.DataFrame:
    try:
        raw = pd.read_csv(fh, comment="#", dtype=str, keep_default_na=False)
    except (pd.errors.ParserError, pd.errors.EmptyDataError, UnicodeDecodeError) as exc:
        raise WbsaError(f"{what} is not a readable CSV ({exc}); give an NHANES BMX+DEMO CSV") from None
    missing = [c for c in SURVEY_COLUMNS if c not in raw.columns]
    if missing:
        raise WbsaError(f"{what} lacks the survey columns {', '.join(missing)}; give an NHANES BMX+DEMO CSV")
    return raw


def clean_survey(raw: pd.DataFrame, source: str = "") -> SurveyData:
    """Turn raw survey rows (NHANES names, any cell types) into :class:`SurveyData`.

    Unreadable cells count as missing; nothing here raises for bad values.
    """
    skipped: dict[str, int] = {}
    dropped: dict[str, int] = {}

    def number(col: str) -> pd.Series:
        if col not in raw.columns:
            return pd.Series(np.nan, index=raw.index)
        return pd.to_numeric(raw[col].replace({"NA": np.nan, "": np.nan, ".": np.nan}), errors="coerce")

    def plausible(values: pd.Series, name: str) -> tuple[pd.Series, pd.Series]:
        lo, hi = PLAUSIBLE[name]
        missing = values.isna()
        bad = ~missing & ~values.between(lo, hi)
        return values.where(~bad), bad

    seqn = number("SEQN")
    sex_code = number("RIAGENDR")
    age_int = number("RIDAGEYR")
    race = number("RIDRETH3")
    pregnant = number("RIDEXPRG") == 1
    stature, bad_stature = plausible(number("BMXHT") / 100.0, "stature_m")
    mass, bad_mass = plausible(number("BMXWT"), "mass_kg")
    optional = {name: plausible(number(col) / 100.0, name) for col, name, _ in _OPTIONAL_MEASURES}
    weight = number("WTMECPRP")
    age, bad_age = plausible(age_int + 0.5, "age_years")
    bmi, bad_bmi = plausible(mass / stature**2, "bmi")

    reasons = [
        ("no usable id", seqn.isna()),
        ("sex missing", ~sex_code.isin([1, 2])),
        ("age missing or implausible", age.isna()),
        ("pregnant", pregnant),
        ("stature implausible", bad_stature),
        ("stature missing", stature.isna() & ~bad_stature),
        ("mass implausible", bad_mass),
        ("mass missing", mass.isna() & ~bad_mass),
        ("bmi implausible", bad_bmi),
        *[(f"{word} implausible", optional[name][1]) for _, name, word in _OPTIONAL_MEASURES],
    ]
    keep = pd.Series(True, index=raw.index)
    for reason, mask in reasons:
        hit = keep & mask.fillna(True)
        if hit.any():
            skipped[reason] = int(hit.sum())
        keep &= ~hit
    duplicated = keep & seqn.duplicated(keep="first")
    if duplicated.any():
        skipped["duplicate id"] = int(duplicated.sum())
        keep &= ~duplicated

    for reason, mask in [
        *[(f"{word} missing", optional[name][0].isna()) for _, name, word in _OPTIONAL_MEASURES],
        ("race unknown", ~race.isin(list(ETHNIC_MIX))),
        ("exam weight missing", ~(weight > 0)),
    ]:
        if (keep & mask).any():
            dropped[reason] = int((keep & mask).sum())

    mix = np.array([ETHNIC_MIX.get(int(r), UNKNOWN_MIX) if np.isfinite(r) else UNKNOWN_MIX
                    for r in race.fillna(-1)])
    people = pd.DataFrame({
        "survey_id": seqn.astype("Int64"),
        "sex": np.where(sex_code == 2, "female", "male"),
        "age_years": age,
        "survey_age_years": age_int,
        "survey_race": race.fillna(-1),
        "p_african": mix[:, 0],
        "p_asian": mix[:, 1],
        "p_caucasian": mix[:, 2],
        "stature_m": stature,
        "mass_kg": mass,
        "bmi": bmi,
        **{name: optional[name][0] for _, name, _ in _OPTIONAL_MEASURES},
        "exam_weight": weight.where(weight > 0),
    })[keep].reset_index(drop=True)
    for col in ("survey_id", "survey_age_years", "survey_race"):
        people[col] = people[col].astype(np.int64)
    return SurveyData(people=people, skipped=skipped, dropped=dropped, source=source)


def select_people(people: pd.DataFrame, n: int, seed: int = 0, *, weighted: bool = False) -> pd.DataFrame:
    """Draw ``n`` different people, uniformly or with probability proportional to exam weight.

    The draw depends only on ``seed``, ``weighted`` and the table. People without an exam
    weight cannot be drawn when ``weighted``.

    Returns
    -------
    pandas.DataFrame
        The drawn rows, in draw order, with a fresh index.

    Raises
    ------
    WbsaError
        If ``n`` is not positive or more than the people available.
    """
    if not isinstance(n, (int, np.integer)) or n <= 0:
        raise WbsaError(f"number of survey people n = {n} must be a positive integer; e.g. 500")
    pool = people
    if weighted:
        pool = people[people["exam_weight"] > 0]
    if n > len(pool):
        what = "survey people with an exam weight" if weighted else "usable survey people"
        raise WbsaError(f"n = {n} is more than the {len(pool)} {what}; use {len(pool)} or fewer")
    rng = np.random.default_rng(np.random.SeedSequence([int(seed), _SELECT_STREAM]))
    p = None
    if weighted:
        w = pool["exam_weight"].to_numpy(dtype=np.float64)
        p = w / w.sum()
    chosen = rng.choice(len(pool), size=n, replace=False, p=p)
    return pool.iloc[chosen].reset_index(drop=True)


#: Seed-stream tag of the selection (so it never shares a stream with other random steps).
_SELECT_STREAM = 0x5E1EC7
