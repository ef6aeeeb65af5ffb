"""The realism summary (wbsa.analysis.realism) on tables with a known answer."""

from __future__ import annotations

import numpy as np
import pandas as pd
import pytest

from wbsa.analysis.realism import (composition_table, dubois_table, formula_bias_table, group_counts, hw_law,
                                   posture_mix, realism_summary)
from wbsa.errors import WbsaError


def _table(n: int = 4000, noise: float = 0.0, female_effect: float = 0.0, seed: int = 0) -> pd.DataFrame:
    """Bodies whose area follows 0.2·H^0.7·W^0.43, times (1 + female_effect) for women, times log-normal noise."""
    rng = np.random.default_rng(seed)
    stature = rng.uniform(1.2, 2.0, n)
    mass = rng.uniform(20, 140, n)
    female = rng.random(n) < 0.5
    area = (0.2 * stature**0.7 * mass**0.43 * np.where(female, 1 + female_effect, 1.0)
            * np.exp(noise * rng.standard_normal(n)))
    return pd.DataFrame({
        "subject_id": np.arange(n), "sex": np.where(female, "female", "male"), "age_years": rng.uniform(7, 80, n),
        "stature_m": stature, "mass_kg": mass, "bmi": mass / stature**2, "wbsa_m2": area, "volume_m3": mass / 980.0,
    })


def test_hw_law_recovers_a_known_law_and_its_scatter():
    exact = hw_law(_table())
    assert exact.r2 == pytest.approx(1.0, abs=1e-12) and exact.residual_sd_percent < 1e-9
    assert (exact.a, exact.b, exact.c) == pytest.approx((np.log(0.2), 0.7, 0.43), abs=1e-9)
    noisy = hw_law(_table(noise=0.02))
    assert noisy.residual_sd_percent == pytest.approx(2.0, abs=0.1)
    assert noisy.r2 < 0.999
    sexed = hw_law(_table(female_effect=0.03))
    assert sexed.female_effect_percent == pytest.approx(3.0, abs=1e-6)


def test_dubois_table_gives_the_ratio_of_the_mesh_and_of_the_measured_formulae():
    from wbsa.formulae import bsa

    t = _table(n=600)
    h, w = 100 * t["stature_m"], t["mass_kg"]
    t["wbsa_m2"] = bsa("dubois", h, w) * 1.05
    d = dubois_table(t)
    np.testing.assert_allclose(d["mesh_over_dubois_mean"], 1.05)
    assert d["n"].sum() == len(t)
    # Livingston & Lee's weight-only formula exceeds Du Bois more and more with BMI (their obese patients)
    men = d[(d["sex"] == "male") & (d["bmi_class"] != "children")].sort_values("bmi_class")
    assert men["livingston_lee_over_dubois_mean"].is_monotonic_increasing
    # a survey table counts its matched bodies (variation 0) only
    survey = pd.concat([t.assign(variation=0), t.assign(variation=1)], ignore_index=True)
    assert dubois_table(survey)["n"].sum() == len(t)


def test_formula_bias_table_is_the_formulae_against_the_mesh():
    from wbsa.formulae import bsa

    t = _table(n=600)
    h, w = 100 * t["stature_m"], t["mass_kg"]
    t["wbsa_m2"] = bsa("mosteller", h, w) * 1.04  # bodies 4 % larger than Mosteller says
    b = formula_bias_table(t)
    assert b["n"].sum() == len(t)
    np.testing.assert_allclose(b["mosteller_bias_percent_mean"], 100 * (1 / 1.04 - 1))
    np.testing.assert_allclose(b["mosteller_bias_percent_sd"], 0.0, atol=1e-9)
    # each cell is the mean over its own subjects (Schlich: the sex-specific formula of each)
    cell = t[(t["sex"] == "female") & (t["age_years"] > 15) & (t["bmi"] >= 25) & (t["bmi"] < 30)]
    expected = 100 * (bsa("schlich", 100 * cell["stature_m"], cell["mass_kg"], cell["sex"]) / cell["wbsa_m2"] - 1)
    row = b[(b["sex"] == "female") & (b["bmi_class"] == "25-30")].iloc[0]
    assert row["schlich_bias_percent_mean"] == pytest.approx(float(np.mean(expected)), rel=1e-12)
    summary = realism_summary(t)
    assert len(summary["formula_bias"]) == len(b)


def test_composition_table_reads_density_from_mass_and_volume():
    t = _table(n=300)
    c = composition_table(t)
    np.testing.assert_allclose(c["density_kg_m3_mean"], 980.0)
    np.testing.assert_allclose(c["fat_fraction_mean"], 495 / 0.98 / 100 - 4.5)  # Siri's fat at 980 kg/m³
    t["fat_fraction"] = 0.25
    assert (composition_table(t)["fat_fraction_mean"] == 0.25).all()


def test_group_counts_and_posture_mix():
    t = pd.DataFrame({"sex": ["female", "male", "male", "female", "male", "female"],
                      "age_years": [10, 30, 40, 50, 60, 70], "stature_m": [1.3, 1.8, 2.1, 1.6, 1.7, 1.5],
                      "bmi": [25.0, 17.0, 31.0, 22.0, 35.0, 30.0]})
    t["mass_kg"] = t["bmi"] * t["stature_m"] ** 2
    t["wbsa_m2"], t["volume_m3"] = 0.2 * t["stature_m"] ** 0.7 * t["mass_kg"] ** 0.43, t["mass_kg"] / 1000
    assert group_counts(t) == {"all": 6, "adults": 5, "children": 1, "obese": 3, "underweight": 1, "small": 1,
                               "tall": 1, "women": 3, "men": 3}
    assert posture_mix(t) == {}
    assert posture_mix(t.assign(posture=["a-pose", "arms-down", "a-pose", "a-pose", "hands-on-hips", "arms-down"])) \
        == {"a-pose": 3, "arms-down": 2, "hands-on-hips": 1}
    summary = realism_summary(t)
    assert summary["groups"]["obese"] == 3 and summary["bmi_range_adults"] == [17.0, 35.0]


def test_realism_needs_a_population_table():
    with pytest.raises(WbsaError, match="wbsa_m2"):
        hw_law(pd.DataFrame({"sex": ["male"] * 6}))
