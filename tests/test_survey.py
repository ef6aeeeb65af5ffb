"""Survey population: NHANES cleaning and selection, differentiable measures, matching."""

from __future__ import annotations

import warnings

import numpy as np
import pandas as pd
import pytest

from wbsa.errors import WbsaError
from wbsa.bodies.body_model import ALL_LOCAL_CHANGE_COLUMNS, LOCAL_CHANGE_COLUMNS, body_parameter_array
from wbsa.bodies.survey_data import (
    ETHNIC_MIX,
    LIMB_SURVEY_COLUMNS,
    PEOPLE_COLUMNS,
    SURVEY_COLUMNS,
    clean_survey,
    load_survey,
    select_people,
)

# -- survey data (no body model needed) ---------------------------------------------------


def _raw(rows: list[dict]) -> pd.DataFrame:
    base = {"SEQN": "1", "RIAGENDR": "1", "RIDAGEYR": "40", "RIDRETH3": "3", "RIDEXPRG": "NA", "BMXWT": "80",
            "BMXHT": "175", "BMXWAIST": "95", "BMXHIP": "100", "BMXARMC": "33", "BMXARML": "38", "BMXLEG": "41",
            "WTMECPRP": "1000"}
    return pd.DataFrame([{**base, **r} for r in rows], columns=[*SURVEY_COLUMNS, *LIMB_SURVEY_COLUMNS])


def test_clean_survey_skips_and_counts_bad_values():
    raw = _raw([
        {"SEQN": "1"},
        {"SEQN": "2", "BMXHT": "NA"},  # no stature: skipped
        {"SEQN": "3", "BMXWT": "heavy"},  # not a number: skipped as missing mass
        {"SEQN": "4", "BMXHT": "17.5"},  # stature in the wrong unit: implausible, skipped
        {"SEQN": "5", "RIAGENDR": "9"},  # unknown sex: skipped
        {"SEQN": "6", "RIDEXPRG": "1", "RIAGENDR": "2"},  # pregnant: skipped
        {"SEQN": "7", "BMXWAIST": "NA", "BMXLEG": "NA"},  # measures missing: left out of the match, person kept
        {"SEQN": "8", "RIDRETH3": "NA", "WTMECPRP": "0"},  # unknown race, no weight: kept
        {"SEQN": "1"},  # duplicate id: skipped
        {"SEQN": "9", "BMXWAIST": "300"},  # a waist of 3 m: skipped, never matched
        {"SEQN": "10", "BMXARMC": "-33"},  # a negative arm: skipped
        {"SEQN": "11", "BMXHIP": "-3"},  # a negative hip: skipped
        {"SEQN": "12", "BMXARML": "380"},  # arm length in mm: skipped
    ])
    data = clean_survey(raw)
    assert list(data.people.columns) == list(PEOPLE_COLUMNS)
    assert data.people["survey_id"].tolist() == [1, 7, 8]
    assert data.skipped == {"sex missing": 1, "pregnant": 1, "stature implausible": 1, "stature missing": 1,
                            "mass missing": 1, "waist implausible": 1, "hip implausible": 1,
                            "arm circumference implausible": 1, "upper arm length implausible": 1,
                            "duplicate id": 1}
    assert data.dropped == {"waist missing": 1, "upper leg length missing": 1, "race unknown": 1,
                            "exam weight missing": 1}
    assert data.n_rows == len(raw)
    p = data.people.set_index("survey_id")
    assert np.isnan(p.loc[7, "waist_circ_m"]) and np.isnan(p.loc[7, "upper_leg_length_m"])
    assert p.loc[1, "stature_m"] == pytest.approx(1.75) and p.loc[1, "waist_circ_m"] == pytest.approx(0.95)
    assert p.loc[1, ["mid_arm_circ_m", "upper_arm_length_m", "upper_leg_length_m"]].tolist() == \
        pytest.approx([0.33, 0.38, 0.41])
    assert p.loc[1, "age_years"] == 40.5 and p.loc[1, "bmi"] == pytest.approx(80 / 1.75**2)
    assert p.loc[8, "survey_race"] == -1 and p.loc[8, ["p_african", "p_asian", "p_caucasian"]].tolist() == \
        pytest.approx([1 / 3] * 3)
    assert np.isnan(p.loc[8, "exam_weight"])


def test_a_survey_file_without_the_limb_columns_reads_for_four_measures():
    raw = _raw([{"SEQN": "1"}, {"SEQN": "2"}]).drop(columns=list(LIMB_SURVEY_COLUMNS))
    data = clean_survey(raw)
    assert data.people["survey_id"].tolist() == [1, 2]
    assert data.people[["mid_arm_circ_m", "upper_arm_length_m", "upper_leg_length_m"]].isna().all(axis=None)


def test_ethnic_mix_is_a_mix():
    for code, mix in ETHNIC_MIX.items():
        assert sum(mix) == pytest.approx(1.0) and min(mix) >= 0, code
    assert ETHNIC_MIX[3] == (0.0, 0.0, 1.0) and ETHNIC_MIX[6] == (0.0, 1.0, 0.0)


def test_packaged_survey_loads_and_equals_the_shared_file():
    data = load_survey()
    assert data.n_rows == 14300
    assert data.skipped["stature missing"] > 1000  # infants have no standing height
    assert len(data.people) == 14300 - sum(data.skipped.values())
    assert data.people["age_years"].between(2, 81).all()
    assert data.people["survey_id"].is_unique
    from pathlib import Path

    shared = Path(__file__).resolve().parents[2] / "shared" / "data" / "nhanes-2017-2020-bmx-demo.csv"
    if shared.exists():
        assert load_survey(shared).people.equals(data.people)


def test_missing_survey_file_is_a_user_error(tmp_path):
    with pytest.raises(WbsaError, match="cannot read survey file"):
        load_survey(tmp_path / "absent.csv")
    bad = tmp_path / "bad.csv"
    bad.write_text("a,b\n1,2\n")
    with pytest.raises(WbsaError, match="lacks the survey columns"):
        load_survey(bad)


def test_select_people_is_seeded_and_weighted():
    people = clean_survey(_raw([{"SEQN": str(i), "WTMECPRP": "0" if i < 5 else "1"} for i in range(20)])).people
    a = select_people(people, 6, seed=3)
    assert a.equals(select_people(people, 6, seed=3))
    assert not a["survey_id"].equals(select_people(people, 6, seed=4)["survey_id"])
    assert a["survey_id"].is_unique
    w = select_people(people, 15, seed=1, weighted=True)
    assert set(w["survey_id"]) == set(range(5, 20))  # zero exam weight is never drawn
    with pytest.raises(WbsaError, match="more than the 15"):
        select_people(people, 16, weighted=True)
    with pytest.raises(WbsaError, match="positive"):
        select_people(people, 0)


# -- body model ---------------------------------------------------------------------------


@pytest.fixture(scope="module")
def tools():
    from wbsa.bodies.anthropometry import Anthropometer
    from wbsa.bodies.body_model import BodyModel
    from wbsa.bodies.survey_measures import TorchMeasurer

    model = BodyModel()
    meter = Anthropometer(model)
    return model, meter, TorchMeasurer(model, meter)


def _bodies() -> pd.DataFrame:
    from wbsa.bodies.age import years_to_param

    rows = [
        dict(p_gender=0.0, p_age=years_to_param(35), p_muscle=0.3, p_weight=0.7, p_height=0.4, p_proportions=0.6,
             p_african=0.0, p_asian=0.0, p_caucasian=1.0, l_stomach_pregnant=0.4, l_hips_circ=-0.3),
        dict(p_gender=1.0, p_age=years_to_param(52), p_muscle=0.6, p_weight=0.35, p_height=0.55,
             p_proportions=0.4, p_cupsize=0.7, p_african=0.75, p_asian=0.0, p_caucasian=0.25,
             l_waist_circ=0.5, l_buttocks_volume=-0.4, l_upperarm_circ=0.6, l_upperarm_length=-0.3,
             l_upperleg_height=0.4),
        dict(p_gender=0.0, p_age=years_to_param(9), p_muscle=0.45, p_weight=0.6, p_height=0.5, p_proportions=0.5,
             p_african=0.05, p_asian=0.4, p_caucasian=0.55),
    ]
    return pd.DataFrame(rows).fillna({"p_cupsize": 0.5, **{c: 0.0 for c in ALL_LOCAL_CHANGE_COLUMNS}})


def test_torch_measures_equal_the_anthropometer(tools):
    model, meter, measurer = tools
    import torch

    params = _bodies()
    exact = meter.measure(model.rest_bodies(params))
    ph = torch.as_tensor(body_parameter_array(params))  # with local changes
    c = measurer.coefficients(ph)
    values = measurer.evaluate(measurer.vertices(c), coefficients=c).values.numpy()
    cols = ["stature_m", "mass_kg", "waist_circ_m", "hip_circ_m", "mid_arm_circ_m", "upper_arm_length_m",
            "upper_leg_length_m"]
    assert measurer.names == tuple(cols)
    np.testing.assert_allclose(values, exact[cols].to_numpy(), rtol=1e-9, atol=1e-9)


def test_torch_measure_gradients_match_finite_differences(tools):
    model, _, measurer = tools
    import torch

    ph = torch.as_tensor(body_parameter_array(_bodies()))
    c = measurer.coefficients(ph).detach()
    grad = measurer.evaluate(measurer.vertices(c), gradient=True, coefficients=c).grad
    assert grad.shape[1] == 7
    direction = torch.as_tensor(np.random.default_rng(0).normal(size=c.shape)) * 1e-6
    plus = measurer.evaluate(measurer.vertices(c + direction), coefficients=c + direction).values
    minus = measurer.evaluate(measurer.vertices(c - direction), coefficients=c - direction).values
    fd = (plus - minus) / 2
    analytic = (grad * direction[:, None, :]).sum(-1)
    np.testing.assert_allclose(analytic.numpy(), fd.numpy(), rtol=2e-3, atol=1e-9)


SEVEN = ("stature_m", "mass_kg", "waist_circ_m", "hip_circ_m", "mid_arm_circ_m", "upper_arm_length_m",
         "upper_leg_length_m")


def _small_settings(**kw):
    from wbsa.bodies.survey_match import MatchSettings
    from wbsa.bodies.survey_start import StartGrid

    grid = StartGrid(age_nodes_years=(6.0, 12.0, 30.0, 60.0), muscle=(0.0, 0.5, 1.0), weight=(0.2, 0.5, 0.8),
                     proportions=(0.5,), heights=(0.0, 0.5, 1.0))
    return MatchSettings(start=grid, **kw)


def test_known_bodies_are_matched_back_within_tolerance(tools):
    from wbsa.bodies.survey_match import match_bodies

    model, meter, measurer = tools
    params = _bodies()
    own = meter.measure(model.rest_bodies(params))
    targets = params[["p_gender", "p_age", "p_african", "p_asian", "p_caucasian"]].copy()
    for name in SEVEN:
        targets[f"target_{name}"] = own[name].to_numpy()
    targets.loc[2, "target_hip_circ_m"] = np.nan  # a child without a hip measure
    fit = match_bodies(targets, measurer, _small_settings(max_iterations=25), show_progress=False)
    # the fixed parameters are kept
    for col in ("p_gender", "p_age", "p_african", "p_asian", "p_caucasian"):
        np.testing.assert_allclose(fit[col], params[col])
    assert fit.loc[0, "p_cupsize"] == 0.5  # men keep the neutral cup size
    assert fit[list(LOCAL_CHANGE_COLUMNS)].abs().max(axis=None) <= 1.0
    back = meter.measure(model.rest_bodies(fit))
    assert np.all(np.abs(back["stature_m"] - own["stature_m"]) <= 0.01)
    assert np.all(np.abs(back["mass_kg"] - own["mass_kg"]) <= 1.0)
    assert np.all(np.abs(back["waist_circ_m"] - own["waist_circ_m"]) <= 0.03)
    assert np.all(np.abs(back["hip_circ_m"] - own["hip_circ_m"])[:2] <= 0.03)
    assert np.all(np.abs(back["mid_arm_circ_m"] - own["mid_arm_circ_m"]) <= 0.02)
    assert np.all(np.abs(back["upper_arm_length_m"] - own["upper_arm_length_m"]) <= 0.015)
    assert np.all(np.abs(back["upper_leg_length_m"] - own["upper_leg_length_m"]) <= 0.015)
    assert fit["fit_converged"].all()


def test_known_bodies_are_matched_back_at_their_own_density(tools):
    """With ``target_density_kg_m3`` each person's mass is volume × its own density in the fit."""
    from wbsa.bodies.survey_match import DENSITY_COLUMN, match_bodies

    model, meter, measurer = tools
    params = _bodies().iloc[:2]
    own = meter.measure(model.rest_bodies(params))
    density = np.array([1065.0, 1010.0])
    targets = params[["p_gender", "p_age", "p_african", "p_asian", "p_caucasian"]].copy()
    for name in SEVEN:
        targets[f"target_{name}"] = own[name].to_numpy()
    targets["target_mass_kg"] = own["volume_m3"].to_numpy() * density
    targets[DENSITY_COLUMN] = density
    fit = match_bodies(targets, measurer, _small_settings(max_iterations=25), show_progress=False)
    back = meter.measure(model.rest_bodies(fit))
    assert np.all(np.abs(back["volume_m3"].to_numpy() * density - targets["target_mass_kg"].to_numpy()) <= 1.0)
    np.testing.assert_allclose(fit["fit_mass_kg"], back["volume_m3"].to_numpy() * density, rtol=1e-9)
    assert np.all(np.abs(back["stature_m"] - own["stature_m"]) <= 0.01)
    targets[DENSITY_COLUMN] = [1000.0, -1.0]
    with pytest.raises(WbsaError, match=DENSITY_COLUMN):
        match_bodies(targets, measurer, _small_settings(max_iterations=1), show_progress=False)


def test_phenotype_only_match_keeps_local_changes_at_zero(tools):
    from wbsa.bodies.survey_match import match_bodies

    model, meter, measurer = tools
    params = _bodies().iloc[:1].assign(l_stomach_pregnant=0.0, l_hips_circ=0.0)
    own = meter.measure(model.rest_bodies(params))
    targets = params[["p_gender", "p_age", "p_african", "p_asian", "p_caucasian"]].copy()
    for name in SEVEN:
        targets[f"target_{name}"] = own[name].to_numpy()
    fit = match_bodies(targets, measurer, _small_settings(max_iterations=25, free_local_changes=False),
                       show_progress=False)
    assert (fit[list(ALL_LOCAL_CHANGE_COLUMNS)] == 0.0).all(axis=None)
    back = meter.measure(model.rest_bodies(fit))
    assert abs(back["stature_m"].iloc[0] - own["stature_m"].iloc[0]) <= 0.01
    assert abs(back["mass_kg"].iloc[0] - own["mass_kg"].iloc[0]) <= 1.0


def test_match_rejects_targets_without_stature(tools):
    from wbsa.bodies.survey_match import match_bodies

    _, _, measurer = tools
    bad = pd.DataFrame([dict(p_gender=0.0, p_age=0.8, p_african=0.0, p_asian=0.0, p_caucasian=1.0,
                             target_stature_m=np.nan, target_mass_kg=70.0,
                             **{f"target_{name}": np.nan for name in SEVEN[2:]})])
    with pytest.raises(WbsaError, match="stature and mass"):
        match_bodies(bad, measurer, _small_settings(max_iterations=1), show_progress=False)


@pytest.mark.slow
def test_survey_population_end_to_end(tmp_path):
    from wbsa.bodies.survey import SURVEY_COLUMNS as EXTRA
    from wbsa.bodies.survey import SurveyMatchWarning, SurveyPopulationSettings, build_survey_population
    from wbsa.bodies.subject import subject_mesh
    from wbsa.bodies.table import TABLE_COLUMNS

    # a small survey file with one bad row, so the run also counts what it skips
    with _packaged() as fh:
        raw = pd.read_csv(fh, comment="#", dtype=str, keep_default_na=False)
    raw = raw[raw["RIDAGEYR"].astype(int).between(20, 60) & (raw["RIDEXPRG"] != "1")].head(6).copy()
    raw.iloc[0, raw.columns.get_loc("BMXHT")] = "oops"
    path = tmp_path / "survey.csv"
    raw.to_csv(path, index=False)
    settings = SurveyPopulationSettings(match=_small_settings(max_iterations=15), survey_path=str(path))
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", SurveyMatchWarning)
        table = build_survey_population(2, variations=2, seed=5, settings=settings, show_progress=False)
        again = build_survey_population(2, variations=2, seed=5, settings=settings, show_progress=False)
    assert list(table.columns) == [*TABLE_COLUMNS, *EXTRA]
    assert len(table) == 6 and table["subject_id"].tolist() == list(range(6))
    assert table["variation"].tolist() == [0, 1, 2, 0, 1, 2]
    summary = table.attrs["survey"]
    assert summary["skipped"] == {"stature missing": 1} and summary["usable"] == 5
    for _, person in table.groupby("survey_id"):
        base = person.iloc[0]
        # variations change weight and muscle only, and keep the survey's values
        for col in ("p_gender", "p_age", "p_height", "p_proportions", "p_cupsize", "p_african", "survey_mass_kg",
                    *LOCAL_CHANGE_COLUMNS):
            assert (person[col] == base[col]).all()
        assert (person["p_weight"] - base["p_weight"]).abs().max() <= 0.2 + 1e-12
        assert (person["p_muscle"] - base["p_muscle"]).abs().max() <= 0.3 + 1e-12
        assert person["match_mass_err_kg"].iloc[1:].isna().all()
        err = base["stature_m"] - base["survey_stature_m"]
        assert base["match_stature_err_m"] == pytest.approx(err)
        ok = (abs(err) <= 0.01 and abs(base["match_mass_err_kg"]) <= 1.0
              and not abs(base["match_waist_err_m"]) > 0.03 and not abs(base["match_hip_err_m"]) > 0.03
              and not abs(base["match_mid_arm_circ_err_m"]) > 0.02
              and not abs(base["match_upper_arm_length_err_m"]) > 0.015
              and not abs(base["match_upper_leg_length_err_m"]) > 0.015)
        assert (person["matched"] == ok).all()
    pd.testing.assert_frame_equal(table, again)
    assert table[list(LOCAL_CHANGE_COLUMNS)].abs().max(axis=None) <= 1.0
    # later stages rebuild a subject from the table's columns: same skin area as measured
    path = tmp_path / "survey.parquet"
    table.to_parquet(path)
    from wbsa.bodies.table import read_population

    for sid in (0, 4):
        assert subject_mesh(read_population(path), sid).area_m2 == pytest.approx(table.loc[sid, "wbsa_m2"], rel=1e-12)

    # with a composition model: each body its own density, the person fitted at its own density
    from wbsa.bodies.composition import COMPOSITION_COLUMNS, CompositionSettings

    with warnings.catch_warnings():
        warnings.simplefilter("ignore", SurveyMatchWarning)
        dense = build_survey_population(2, variations=1, seed=5, settings=settings, show_progress=False,
                                        composition=CompositionSettings("deurenberg-siri", seed=5))
    assert list(dense.columns) == [*TABLE_COLUMNS, *COMPOSITION_COLUMNS, *EXTRA]
    np.testing.assert_allclose(dense["mass_kg"], dense["volume_m3"] * dense["density_kg_m3"], rtol=1e-15)
    assert dense["density_kg_m3"].between(960, 1100).all()
    first = dense[dense["variation"] == 0]
    assert (first["match_mass_err_kg"].abs() <= 1.0).sum() >= (table[table["variation"] == 0]["match_mass_err_kg"]
                                                               .abs() <= 1.0).sum() - 1


def test_tables_written_before_the_limb_measures_still_read(tmp_path, body_model):
    """A four-measure survey table of the earlier layout (no limb measures, no limb changes) reads back:
    the same bodies, its four match rates, its unmatched people."""
    from wbsa.bodies.anthropometry import NHANES_LIMB_COLUMNS
    from wbsa.bodies.body_model import LIMB_CHANGE_COLUMNS
    from wbsa.bodies.subject import subject_mesh
    from wbsa.bodies.survey import match_rates, unmatched_people
    from wbsa.bodies.table import measure_population, read_population

    params = _bodies().drop(columns=list(LIMB_CHANGE_COLUMNS))
    params.insert(0, "subject_id", np.arange(3))
    params.insert(1, "sex", np.where(params["p_gender"] >= 0.5, "female", "male"))
    params.insert(2, "age_years", [35.5, 52.5, 9.5])
    table = measure_population(params, model=body_model)
    old = table.drop(columns=[*NHANES_LIMB_COLUMNS, *LIMB_CHANGE_COLUMNS])
    old["survey_id"], old["variation"], old["survey_age_years"] = [11, 12, 13], 0, [35, 52, 9]
    old["survey_bmi"] = old["bmi"]
    offsets = {"stature_m": 0.0, "mass_kg": 0.5, "waist_circ_m": 0.01, "hip_circ_m": -0.05}  # hip 5 cm off
    for name, off in offsets.items():
        old[f"survey_{name}"] = old[name] - off
        old[f"match_{name.removesuffix('_m').removesuffix('_kg').removesuffix('_circ')}_err_"
            f"{'kg' if name == 'mass_kg' else 'm'}"] = off
    old["matched"] = False
    old["matched_stature_mass"] = True
    path = tmp_path / "old.parquet"
    old.to_parquet(path)
    back = read_population(path)
    assert (back[list(LIMB_CHANGE_COLUMNS)] == 0.0).all(axis=None)
    assert not set(NHANES_LIMB_COLUMNS) & set(back.columns)
    for sid in range(3):
        assert subject_mesh(back, sid).area_m2 == pytest.approx(table.loc[sid, "wbsa_m2"], rel=1e-12)
    rates = match_rates(back)["all"]
    assert rates["hip_within"] == 0.0 and rates["waist_within"] == 1.0 and rates["mass_within"] == 1.0
    assert "mid_arm_circ_within" not in rates
    assert unmatched_people(back)["failing"].tolist() == ["hip"] * 3


def _packaged():
    from importlib.resources import files

    return files("wbsa").joinpath("data/nhanes_bmx_demo.csv").open("r", encoding="utf-8")


def test_rescue_weights_are_checked():
    from wbsa.bodies.survey_match import MatchSettings

    with pytest.raises(WbsaError, match="rescue_weights"):
        MatchSettings(rescue_weights=(3.0, 0.0, 0.1, 0.1, 0.1, 0.1, 0.1))
    with pytest.raises(WbsaError, match="seven positive numbers"):
        MatchSettings(rescue_weights=(3.0, 0.1, 0.1, 0.1))
    w = (3.0, 0.1, 0.1, 0.1, 0.1, 0.1, 0.1)
    assert MatchSettings(rescue_weights=w).rescue_weights == w
    with pytest.raises(WbsaError, match="measures must be one of .*got 'five'"):
        MatchSettings(measures="five")
    assert MatchSettings(measures="four").names == ("stature_m", "mass_kg", "waist_circ_m", "hip_circ_m")


def test_survey_measures_is_a_checked_choice_of_the_population_and_the_cli():
    from helpers.cli import assert_one_line_error, run_cli

    from wbsa.bodies.settings import PopulationSettings

    assert PopulationSettings(kind="survey", n=5).survey_measures == "seven"
    with pytest.raises(WbsaError, match="survey_measures"):
        PopulationSettings(kind="survey", n=5, survey_measures="five")
    code, _, err = run_cli("population", "--kind", "survey", "--n", "5", "--survey-measures", "five", "--out", "x.csv")
    assert_one_line_error(code, err, "--survey-measures", "seven", "four")
