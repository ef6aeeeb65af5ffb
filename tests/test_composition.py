"""Body composition: Deurenberg fat fraction, Siri/Brozek density, mass by fixed point."""

from __future__ import annotations

import numpy as np
import pandas as pd
import pytest

from wbsa.bodies.composition import (CompositionSettings, density_from_fat, fat_fraction, fat_from_density,
                                     predicted_fat_percent, residual_z, solve_composition)
from wbsa.errors import WbsaError


def test_deurenberg_equations_give_the_published_values():
    """Deurenberg 1991: adults 1.20 BMI + 0.23 age − 10.8 sex − 5.4; children 1.51 BMI − 0.70 age − 3.6 sex + 1.4"""
    got = predicted_fat_percent(np.array([25.0, 25.0, 18.0, 18.0]), np.array([40.0, 40.0, 10.0, 10.0]),
                                np.array([True, False, True, False]))
    np.testing.assert_allclose(got, [23.0, 33.8, 17.98, 21.58], atol=1e-12)
    # the child equation stops at 15 y: a 15-year-old is a child, 15.5 an adult
    child, adult = predicted_fat_percent(np.array([20.0, 20.0]), np.array([15.0, 15.5]), np.array([False, False]))
    assert child == pytest.approx(1.51 * 20 - 0.70 * 15 + 1.4)
    assert adult == pytest.approx(1.20 * 20 + 0.23 * 15.5 - 5.4)


def test_two_compartment_densities_and_their_inverse():
    """Siri: %BF = 495/D − 450; Brozek: %BF = 457/D − 414.2 (D in g/cm³); fat-free mass ≈ 1.100 g/cm³."""
    assert density_from_fat(np.array([0.25]))[0] == pytest.approx(1000 * 495 / 475)
    assert density_from_fat(np.array([0.25]), "brozek")[0] == pytest.approx(1000 * 457 / 439.2)
    assert density_from_fat(np.array([0.0]))[0] == pytest.approx(1100.0)
    fat = np.linspace(0.03, 0.6, 20)
    for eq in ("siri", "brozek"):
        np.testing.assert_allclose(fat_from_density(density_from_fat(fat, eq), eq), fat, atol=1e-13)
    # anny's 980 kg/m³ would be 55 % fat by Siri (Siri 1961; docs/references.md)
    assert fat_from_density(np.array([980.0]))[0] == pytest.approx(0.5510, abs=1e-4)


def test_fat_fraction_scatter_is_clipped_to_physiology():
    bmi, age = np.full(4, 22.0), np.array([30.0, 30.0, 10.0, 30.0])
    male = np.array([True, False, False, True])
    low = fat_fraction(bmi, age, male, np.full(4, -10.0))
    np.testing.assert_allclose(low, [0.03, 0.10, 0.03, 0.03])
    high = fat_fraction(np.full(4, 80.0), age, male, np.full(4, 10.0))
    np.testing.assert_allclose(high, 0.60)
    # no scatter: exactly the equation
    none = fat_fraction(bmi, age, male, np.full(4, 3.0), residual_scale=0.0)
    np.testing.assert_allclose(none, predicted_fat_percent(bmi, age, male) / 100)


def test_residual_deviates_are_seeded_per_subject_and_standard_normal():
    keys = np.arange(4000)[:, None]
    z = residual_z(5, keys)
    np.testing.assert_array_equal(residual_z(5, keys[1000:1010]), z[1000:1010])  # independent of who else
    assert not np.array_equal(residual_z(6, keys[:10]), z[:10])
    assert abs(z.mean()) < 0.06 and abs(z.std() - 1) < 0.05
    # survey keys (survey_id, variation) differ from a subject id alone
    assert residual_z(5, np.array([[3, 0]]))[0] != residual_z(5, np.array([[3]]))[0]


def test_mass_is_the_fixed_point_of_volume_times_density():
    """m = V · D(f(m / H²)): the returned fat fraction is the equation's at the returned BMI."""
    rng = np.random.default_rng(0)
    n = 200
    volume, stature = rng.uniform(0.02, 0.2, n), rng.uniform(1.2, 2.1, n)
    age, male, z = rng.uniform(7, 80, n), rng.random(n) < 0.5, rng.standard_normal(n)
    for model in ("deurenberg-siri", "deurenberg-brozek"):
        s = CompositionSettings(model=model)
        c = solve_composition(s, volume, stature, age, male, z)
        np.testing.assert_array_equal(c.mass_kg, volume * c.density_kg_m3)
        np.testing.assert_allclose(c.bmi, c.mass_kg / stature**2, rtol=1e-15)
        np.testing.assert_allclose(fat_fraction(c.bmi, age, male, z), c.fat_fraction, atol=1e-12)
        assert ((c.density_kg_m3 > 960) & (c.density_kg_m3 < 1100)).all()
        # one subject's result does not depend on the batch it is solved in
        part = solve_composition(s, volume[50:60], stature[50:60], age[50:60], male[50:60], z[50:60])
        np.testing.assert_array_equal(part.mass_kg, c.mass_kg[50:60])
    const = solve_composition(CompositionSettings(), volume, stature, age, male, z)
    np.testing.assert_array_equal(const.mass_kg, volume * 980.0)
    assert np.isnan(const.fat_fraction).all()


def test_settings_are_checked():
    with pytest.raises(WbsaError, match="model must be one of 'constant'.*got 'siri'"):
        CompositionSettings(model="siri")
    with pytest.raises(WbsaError, match="must be positive"):
        CompositionSettings(density_kg_m3=0.0)
    with pytest.raises(WbsaError, match="residual_scale"):
        CompositionSettings(residual_scale=-1)


def test_constant_density_tables_are_the_old_tables(body_model):
    """``constant`` gives exactly the table of mass = volume × 980 with no extra column (same bytes)."""
    from wbsa.bodies.anthropometry import Anthropometer
    from wbsa.bodies.body_model import ALL_LOCAL_CHANGE_COLUMNS
    from wbsa.bodies.build import build_population
    from wbsa.bodies.random_population import RandomPopulationSettings, sample_random_parameters
    from wbsa.bodies.table import TABLE_COLUMNS

    new = build_population("random", n=6, seed=3, density_model="constant", show_progress=False)
    params = sample_random_parameters(RandomPopulationSettings(n=6, seed=3))
    old = pd.concat([params, Anthropometer(body_model, 980.0).measure(body_model.rest_bodies(params))], axis=1)
    for name in ALL_LOCAL_CHANGE_COLUMNS:
        old[name] = 0.0
    assert list(new.columns) == list(TABLE_COLUMNS)
    assert new.to_csv(index=False) == old.to_csv(index=False)


def test_composition_population_has_real_densities_and_consistent_mass(body_model):
    from wbsa.bodies.build import build_population

    a = build_population("random", n=24, seed=2, density_model="deurenberg-siri", show_progress=False)
    b = build_population("random", n=24, seed=2, density_model="deurenberg-brozek", show_progress=False)
    c = build_population("random", n=24, seed=2, show_progress=False)
    assert list(a.columns[-3:]) == ["fat_fraction", "density_kg_m3", "fat_residual_z"]
    # a table carrying each subject's deviate rebuilds the same composition
    from wbsa.bodies.composition import CompositionSettings
    from wbsa.bodies.table import with_composition

    again = with_composition(a.assign(mass_kg=0.0), CompositionSettings("deurenberg-siri", seed=99))
    pd.testing.assert_frame_equal(again, a)
    np.testing.assert_allclose(a["mass_kg"], a["volume_m3"] * a["density_kg_m3"], rtol=1e-15)
    # same bodies, heavier than at 980 kg/m³: typical densities 1.00–1.09 g/cm³
    np.testing.assert_array_equal(a["wbsa_m2"], c["wbsa_m2"])
    assert (a["mass_kg"] > c["mass_kg"]).all()
    assert a["density_kg_m3"].between(990, 1090).all()
    # Brozek gives slightly lower densities than Siri at the same fat fraction above ~15 % fat
    assert (b["density_kg_m3"] - a["density_kg_m3"]).abs().max() < 15
    # women carry more fat than men at the same BMI (Deurenberg's −10.8 · sex)
    adults = a[a["age_years"] > 15]
    assert adults.groupby("sex")["fat_fraction"].mean()["female"] > adults.groupby("sex")["fat_fraction"].mean()["male"]


def test_a_population_table_given_as_parameters_rebuilds_itself(tmp_path, body_model):
    """``--kind table --params POPULATION`` measures the bodies again (no duplicate columns) with the same draws."""
    from wbsa.cli import main

    first, again = tmp_path / "a.csv", tmp_path / "b.csv"
    assert main(["population", "--kind", "random", "--n", "4", "--seed", "2", "--sampling", "varied",
                 "--density-model", "deurenberg-brozek", "--out", str(first)]) == 0
    assert main(["population", "--kind", "table", "--params", str(first), "--density-model", "deurenberg-brozek",
                 "--seed", "77", "--out", str(again)]) == 0
    pd.testing.assert_frame_equal(pd.read_csv(first), pd.read_csv(again))
