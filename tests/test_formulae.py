"""Classical BSA formulae: published values, vectorisation, input checks and the ``wbsa bsa`` command."""

from __future__ import annotations

import dataclasses
import json
import math
import re

import numpy as np
import pandas as pd
import pytest

from wbsa.cli import main
from wbsa.errors import WbsaError
from wbsa.formulae import FORMULAE, Formula, bsa, bsa_all, bsa_table, formula_key, parse_sex, validate_inputs

# Published values at 170 cm / 70 kg (m², 4 decimals), copied from the project's reference facts.
PUBLISHED_170_70 = {
    "dubois": 1.8097,
    "mosteller": 1.8181,
    "haycock": 1.8257,
    "gehan_george": 1.8313,
    "boyd": 1.8347,
    "fujimoto": 1.7643,
    "takahira": 1.8241,
    "shuter_aslani": 1.7861,
    "schlich_male": 1.6980,
    "schlich_female": 1.7654,
    "yu": 1.8109,
    "livingston_lee": 1.8295,
    "tikuisis": 1.8099,
}
PINNED_KEYS = [
    "dubois", "mosteller", "haycock", "gehan_george", "boyd", "fujimoto", "takahira",
    "shuter_aslani", "schlich", "yu", "livingston_lee", "tikuisis",
]
ALL_KEYS_NO_SEX = [k for k in PINNED_KEYS if k != "schlich"]
ALL_KEYS_NO_SEX.insert(PINNED_KEYS.index("schlich"), "schlich_female")
ALL_KEYS_NO_SEX.insert(PINNED_KEYS.index("schlich"), "schlich_male")


# --- catalogue -------------------------------------------------------------------------------------

def test_catalogue_keys_order_and_fields():
    assert list(FORMULAE) == PINNED_KEYS
    for key, formula in FORMULAE.items():
        assert isinstance(formula, Formula) and formula.key == key
        assert formula.name and formula.expression and str(formula.year) in formula.citation
        assert 1900 < formula.year < 2030
    assert [k for k, f in FORMULAE.items() if f.sex_specific] == ["schlich"]
    with pytest.raises(dataclasses.FrozenInstanceError):
        FORMULAE["dubois"].year = 2000
    with pytest.raises(TypeError):
        FORMULAE["new"] = FORMULAE["dubois"]


@pytest.mark.parametrize("key", [k for k in PUBLISHED_170_70 if not k.startswith("schlich")])
def test_published_value_170cm_70kg(key):
    assert bsa(key, 170, 70) == pytest.approx(PUBLISHED_170_70[key], abs=5e-5)


@pytest.mark.parametrize("sex", ["male", "female"])
def test_schlich_published_value_by_sex(sex):
    assert bsa("schlich", 170, 70, sex) == pytest.approx(PUBLISHED_170_70[f"schlich_{sex}"], abs=5e-5)
    assert bsa(f"schlich_{sex}", 170, 70) == pytest.approx(PUBLISHED_170_70[f"schlich_{sex}"], abs=5e-5)


def test_bsa_all_without_sex_matches_published_values():
    values = bsa_all(170.0, 70.0)
    assert list(values) == ALL_KEYS_NO_SEX
    for key, value in values.items():
        assert value.shape == ()
        assert float(value) == pytest.approx(PUBLISHED_170_70[key], abs=5e-5)


def test_bsa_all_with_sex_has_one_schlich():
    values = bsa_all(170.0, 70.0, "female")
    assert list(values) == PINNED_KEYS
    assert float(values["schlich"]) == pytest.approx(PUBLISHED_170_70["schlich_female"], abs=5e-5)


def test_closed_forms_at_other_points():
    # Mosteller is sqrt(H W / 3600); Takahira is Du Bois with a larger constant; Livingston & Lee
    # ignores height; Boyd takes weight in grams inside (a classic bug is to pass kilograms).
    h, w = np.array([50.0, 120.0, 185.0, 200.0]), np.array([3.5, 25.0, 90.0, 150.0])
    np.testing.assert_allclose(bsa("mosteller", h, w), np.sqrt(h * w / 3600.0), rtol=1e-12)
    np.testing.assert_allclose(bsa("takahira", h, w) / bsa("dubois", h, w), 0.007241 / 0.007184, rtol=1e-12)
    np.testing.assert_allclose(bsa("livingston_lee", h, w), bsa("livingston_lee", 170.0, w), rtol=1e-12)
    g = 1000.0 * w
    expected_boyd = 0.0003207 * h**0.3 * g ** (0.7285 - 0.0188 * np.log10(g))
    np.testing.assert_allclose(bsa("boyd", h, w), expected_boyd, rtol=1e-12)


def test_formulae_agree_and_grow_with_size():
    h = np.linspace(50.0, 210.0, 9)
    w = np.linspace(3.0, 140.0, 9)
    for sex in ("male", "female"):
        values = bsa_all(h, w, sex)
        for key, v in values.items():
            assert np.all(np.diff(v) > 0), key  # bigger bodies, bigger surface
            assert np.all(bsa(key, h, w + 5.0, sex) > v), key  # heavier at the same height
        # adult: every formula within 10 % of Du Bois
        adult = np.array([float(bsa(k, 175.0, 75.0, sex)) for k in FORMULAE])
        assert np.all(np.abs(adult / bsa("dubois", 175.0, 75.0) - 1.0) < 0.10)


# --- vectorisation ---------------------------------------------------------------------------------

def test_vectorised_equals_scalar_calls():
    rng = np.random.default_rng(7)
    h = rng.uniform(60.0, 200.0, 25)
    w = rng.uniform(6.0, 130.0, 25)
    sex = rng.choice(["male", "female"], 25)
    for key in PINNED_KEYS:
        vec = bsa(key, h, w, sex)
        assert isinstance(vec, np.ndarray) and vec.shape == (25,) and vec.dtype == np.float64
        scalars = [bsa(key, float(a), float(b), str(s)) for a, b, s in zip(h, w, sex)]
        assert all(isinstance(s, float) for s in scalars)
        np.testing.assert_allclose(vec, scalars, rtol=1e-13)


def test_broadcasting_and_2d_inputs():
    h = np.array([[150.0], [170.0], [190.0]])
    w = np.array([50.0, 70.0])
    out = bsa("dubois", h, w)
    assert out.shape == (3, 2)
    assert out[1, 1] == pytest.approx(PUBLISHED_170_70["dubois"], abs=5e-5)
    female = bsa("schlich", 170.0, [70.0, 70.0], "female")
    np.testing.assert_allclose(female, PUBLISHED_170_70["schlich_female"], atol=5e-5)
    with pytest.raises(WbsaError, match="shape"):
        bsa("dubois", [170.0, 180.0], [70.0, 80.0, 90.0])
    with pytest.raises(WbsaError, match="one sex per subject"):
        bsa("schlich", [170.0, 180.0], [70.0, 80.0], ["male", "female", "male"])


def test_bsa_table_columns_index_and_values():
    idx = pd.Index([101, 205, 309], name="subject_id")
    people = pd.DataFrame(
        {"stature_cm": [170.0, 160.0, 185.0], "mass_kg": [70.0, 55.0, 95.0], "sex": ["male", "female", "male"]},
        index=idx,
    )
    table = bsa_table(people["stature_cm"], people["mass_kg"], people["sex"])
    assert list(table.columns) == [f"bsa_{k}_m2" for k in PINNED_KEYS]
    assert table.index.equals(idx)
    assert table.loc[101, "bsa_dubois_m2"] == pytest.approx(PUBLISHED_170_70["dubois"], abs=5e-5)
    assert table.loc[101, "bsa_schlich_m2"] == pytest.approx(PUBLISHED_170_70["schlich_male"], abs=5e-5)
    np.testing.assert_allclose(
        table["bsa_schlich_m2"], bsa("schlich", people["stature_cm"], people["mass_kg"], people["sex"])
    )
    no_sex = bsa_table([170.0, 160.0], [70.0, 55.0])
    assert list(no_sex.columns) == [f"bsa_{k}_m2" for k in ALL_KEYS_NO_SEX]
    assert list(no_sex.index) == [0, 1]
    one = bsa_table(170.0, 70.0)
    assert len(one) == 1
    with pytest.raises(WbsaError, match="1-D"):
        bsa_table(np.full((2, 2), 170.0), 70.0)


def test_check_false_gives_nan_for_missing_or_impossible_rows():
    h = pd.Series([170.0, np.nan, 160.0, -1.0, 175.0])
    w = pd.Series([70.0, 60.0, np.nan, 50.0, 0.0])
    with pytest.raises(WbsaError, match="position 1"):
        bsa_table(h, w)
    table = bsa_table(h, w, check=False)
    assert table.loc[0, "bsa_mosteller_m2"] == pytest.approx(PUBLISHED_170_70["mosteller"], abs=5e-5)
    assert table.iloc[1:].isna().all().all()  # every formula, Livingston & Lee included
    assert math.isnan(bsa("dubois", -170.0, 70.0, check=False))


# --- sex and key handling --------------------------------------------------------------------------

def test_parse_sex():
    assert parse_sex(None) is None
    assert parse_sex("male").shape == () and not parse_sex("male")
    np.testing.assert_array_equal(parse_sex(["female", " Male", "FEMALE"]), [True, False, True])
    for bad in ("m", "other", ["male", 2]):
        with pytest.raises(WbsaError, match="is not understood; use 'male' or 'female'"):
            parse_sex(bad)
    for missing in (["male", None], pd.Series(["female", np.nan])):
        with pytest.raises(WbsaError, match="sex is missing"):
            parse_sex(missing)


def test_schlich_needs_sex_and_unknown_key():
    with pytest.raises(WbsaError, match="give the sex, male or female"):
        bsa("schlich", 170, 70)
    with pytest.raises(WbsaError, match="unknown BSA formula 'du_boys'.*dubois"):
        bsa("du_boys", 170, 70)
    assert bsa("dubois", 170, 70, "female") == bsa("dubois", 170, 70)


# --- input checks ----------------------------------------------------------------------------------

@pytest.mark.parametrize(
    ("height", "weight", "message"),
    [
        (0.0, 70.0, "height 0 must be positive"),
        (-170.0, 70.0, "height -170 must be positive"),
        (170.0, 0.0, "weight 0 must be positive"),
        (170.0, -3.0, "weight -3 must be positive"),
        (1.7, 70.0, "height 1.7 looks like metres; give the height in centimetres, e.g. 170"),
        (1700.0, 70.0, "height 1700 is above 272 cm and looks like millimetres"),
        (20.0, 70.0, "height 20 cm is outside the physiological range 30–272 cm"),
        (4000.0, 70.0, "height 4000 cm is outside the physiological range 30–272 cm"),
        (170.0, 70000.0, "weight 70000 is above 650 kg and looks like grams"),
        (170.0, 0.2, "weight 0.2 kg is outside the physiological range 0.5–650 kg"),
        (170.0, 1e7, "weight 1e+07 kg is outside the physiological range 0.5–650 kg"),
        (float("nan"), 70.0, "height nan is not a finite number"),
        (170.0, float("inf"), "weight inf is not a finite number"),
        ("tall", 70.0, "height must be a number"),
    ],
)
def test_validate_inputs_rejects(height, weight, message):
    with pytest.raises(WbsaError) as info:
        validate_inputs(height, weight)
    assert message in str(info.value)
    assert "\n" not in str(info.value)


def test_validate_inputs_accepts_the_bounds_and_real_people():
    validate_inputs(30.0, 0.5)
    validate_inputs(272.0, 650.0)
    validate_inputs([49.5, 120.0, 170.0, 201.0], [3.3, 22.0, 70.0, 180.0])


def test_validate_inputs_array_message_names_position_and_count():
    with pytest.raises(WbsaError) as info:
        validate_inputs([170.0, 1.62, 1.80, 150.0], 70.0)
    msg = str(info.value)
    assert "height 1.62 (at position 1; 2 of 4 values) looks like metres" in msg
    with pytest.raises(WbsaError, match=r"at position \(1, 0\)"):
        validate_inputs(np.array([[170.0, 160.0], [-1.0, 150.0]]), 60.0)


# --- command line ----------------------------------------------------------------------------------

def test_cli_table(capsys):
    assert main(["bsa", "--height-cm", "170", "--weight-kg", "70"]) == 0
    out = capsys.readouterr().out.splitlines()
    assert out[0] == "height 170 cm, weight 70 kg"
    assert out[1].split() == ["formula", "year", "BSA", "(m²)"]
    rows = out[2:]
    assert len(rows) == len(ALL_KEYS_NO_SEX)
    assert len({len(line) for line in out[1:]}) == 1  # aligned columns
    by_name = {name: [year, value] for name, year, value in (re.split(r"\s{2,}", line.strip()) for line in rows)}
    assert by_name["Du Bois & Du Bois"] == ["1916", "1.8097"]
    assert by_name["Schlich (male)"] == ["2010", "1.6980"]
    assert by_name["Schlich (female)"] == ["2010", "1.7654"]
    assert by_name["Tikuisis"] == ["2001", "1.8099"]


def test_cli_json(capsys):
    assert main(["bsa", "--height-cm", "170", "--weight-kg", "70", "--sex", "male", "--json"]) == 0
    payload = json.loads(capsys.readouterr().out)
    assert payload["height_cm"] == 170.0 and payload["weight_kg"] == 70.0 and payload["sex"] == "male"
    assert list(payload["bsa_m2"]) == PINNED_KEYS
    expected = dict(PUBLISHED_170_70, schlich=PUBLISHED_170_70["schlich_male"])
    for key, value in payload["bsa_m2"].items():
        assert value == pytest.approx(expected[key], abs=5e-5)


@pytest.mark.parametrize(
    ("height", "weight", "message"),
    [
        ("1.7", "70", "error: height 1.7 looks like metres; give the height in centimetres, e.g. 170"),
        ("0", "70", "error: height 0 must be positive"),
        ("170", "-70", "error: weight -70 must be positive"),
        ("170", "70000", "error: weight 70000 is above 650 kg and looks like grams"),
        ("nan", "70", "error: height nan is not a finite number"),
    ],
)
def test_cli_bad_input_exits_2(capsys, height, weight, message):
    assert main(["bsa", "--height-cm", height, "--weight-kg", weight]) == 2
    captured = capsys.readouterr()
    assert captured.out == ""
    assert captured.err.startswith(message)
    assert captured.err.count("\n") == 1


@pytest.mark.parametrize(
    "argv",
    [
        ["bsa", "--height-cm", "tall", "--weight-kg", "70"],
        ["bsa", "--height-cm", "170"],
        ["bsa", "--height-cm", "170", "--weight-kg", "70", "--sex", "other"],
    ],
)
def test_cli_usage_errors_exit_2(capsys, argv):
    assert main(argv) == 2
    err = capsys.readouterr().err
    assert err.startswith("error: ") and err.count("\n") == 1


# --- names users already know (R admiral, R physiology) ----------------------------------------------

# R admiral compute_bsa(method=...): the method names and admiral's own expected values at
# 170 cm / 75 kg and 185 cm / 90 kg, rounded to 3 decimals (admiral tests/testthat/test-compute_bsa.R).
ADMIRAL_170_75_185_90 = {
    "Mosteller": ("mosteller", (1.882, 2.151)),
    "DuBois-DuBois": ("dubois", (1.864, 2.141)),
    "Haycock": ("haycock", (1.895, 2.161)),
    "Gehan-George": ("gehan_george", (1.897, 2.160)),
    "Boyd": ("boyd", (1.905, 2.158)),
    "Fujimoto": ("fujimoto", (1.819, 2.086)),
    "Takahira": ("takahira", (1.878, 2.158)),
}


@pytest.mark.parametrize("method", list(ADMIRAL_170_75_185_90))
def test_admiral_methods_resolve_and_give_admirals_values(method):
    key, expected = ADMIRAL_170_75_185_90[method]
    assert formula_key(method) == key
    values = bsa(method, [170.0, 185.0], [75.0, 90.0])
    np.testing.assert_array_equal(values, bsa(key, [170.0, 185.0], [75.0, 90.0]))
    np.testing.assert_array_equal(np.round(values, 3), expected)


# R physiology: one function per formula, bsa_adult() is Mosteller.
PHYSIOLOGY_FUNCTIONS = {
    "bsa_adult": "mosteller",
    "bsa_dubois_dubois": "dubois",
    "bsa_mosteller": "mosteller",
    "bsa_haycock": "haycock",
    "bsa_gehan_george": "gehan_george",
    "bsa_boyd": "boyd",
    "bsa_fujimoto": "fujimoto",
    "bsa_takahira": "takahira",
    "bsa_shuter_aslani": "shuter_aslani",
    "bsa_schlich": "schlich",
}


@pytest.mark.parametrize("function", list(PHYSIOLOGY_FUNCTIONS))
def test_physiology_function_names_resolve(function):
    key = PHYSIOLOGY_FUNCTIONS[function]
    assert formula_key(function) == key
    assert bsa(function, 170.0, 70.0, "female") == bsa(key, 170.0, 70.0, "female")


@pytest.mark.parametrize(
    ("name", "key"),
    [
        ("Mosteller", "mosteller"), ("MOSTELLER", "mosteller"), (" mosteller ", "mosteller"),
        ("DuBois", "dubois"), ("dubois", "dubois"), ("Du Bois", "dubois"), ("du_bois", "dubois"),
        ("Du Bois & Du Bois", "dubois"), ("dubois_dubois", "dubois"),
        ("Gehan-George", "gehan_george"), ("gehan george", "gehan_george"), ("Gehan & George", "gehan_george"),
        ("Shuter & Aslani", "shuter_aslani"), ("Yu, Lin & Yang", "yu"), ("Livingston-Lee", "livingston_lee"),
        ("Schlich_Male", "schlich_male"),
    ],
)
def test_names_are_case_and_separator_insensitive(name, key):
    assert formula_key(name) == key


def test_every_key_and_cited_name_resolves_to_itself():
    for key, formula in FORMULAE.items():
        assert formula_key(key) == key
        assert formula_key(formula.name) == key
        assert formula_key(formula.name.upper()) == key


@pytest.mark.parametrize("name", ["du_boys", "", "bsa_", "bsa", "gehan", "adult", None, 3])
def test_unknown_name_is_one_line_listing_the_keys(name):
    with pytest.raises(WbsaError) as info:
        formula_key(name)
    message = str(info.value)
    assert "\n" not in message
    assert message.startswith(f"unknown BSA formula {name!r}; choose one of dubois, mosteller, haycock")
    assert all(key in message for key in FORMULAE)


def test_wbsa_error_is_a_value_error():
    assert issubclass(WbsaError, ValueError)
    with pytest.raises(ValueError, match="unknown BSA formula"):
        bsa("Mosteler", 170, 70)


def test_cli_formula_accepts_known_names(capsys):
    argv = ["bsa", "--height-cm", "170", "--weight-kg", "70", "--json"]
    assert main([*argv, "--formula", "Mosteller", "--formula", "DuBois-DuBois", "--formula", "dubois"]) == 0
    payload = json.loads(capsys.readouterr().out)
    assert payload["bsa_m2"] == pytest.approx({"mosteller": PUBLISHED_170_70["mosteller"],
                                               "dubois": PUBLISHED_170_70["dubois"]}, abs=5e-5)
    assert list(payload["bsa_m2"]) == ["mosteller", "dubois"]
    assert main([*argv, "--formula", "bsa_schlich"]) == 0  # no sex: both Schlich variants, as in the full table
    assert list(json.loads(capsys.readouterr().out)["bsa_m2"]) == ["schlich_male", "schlich_female"]
    assert main(["bsa", "--height-cm", "170", "--weight-kg", "70", "--sex", "male", "--formula", "Gehan-George"]) == 0
    out = capsys.readouterr().out.splitlines()
    assert len(out) == 3 and out[2].split() == ["Gehan", "&", "George", "1970", f"{PUBLISHED_170_70['gehan_george']:.4f}"]


def test_cli_unknown_formula_exits_2(capsys):
    assert main(["bsa", "--height-cm", "170", "--weight-kg", "70", "--formula", "Mosteler"]) == 2
    captured = capsys.readouterr()
    assert captured.out == ""
    assert captured.err.startswith("error: unknown BSA formula 'Mosteler'; choose one of dubois")
    assert captured.err.count("\n") == 1
