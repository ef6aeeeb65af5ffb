"""The model file: round trip, intervals equal to statsmodels', ~95 % coverage on fresh data, lookup errors."""

import json

import numpy as np
import pandas as pd
import pytest

from wbsa.analysis.fit_views import FitSettings, fit_all
from wbsa.analysis.model_file import WbsaModel
from wbsa.errors import WbsaError

VIEWS = [(0.0, 0.0), (90.0, 30.0), (0.0, -90.0)]
C1, C0, B_STATURE = 2.4, 0.05, 0.3  # the law at view (0, 0)


def make_tables(n, seed, noise="additive"):
    """Population + scan with WBSA = C1*VBSA + C0 + B_STATURE*stature + e at view (0, 0).

    e ~ N(0, 0.02^2), or with an sd proportional to VBSA (``noise='proportional'``). The VBSA of the
    other views is unrelated to WBSA: those views only serve the lookups.
    """
    rng = np.random.default_rng(seed)
    stature = rng.uniform(1.0, 2.1, n)
    vbsa0 = rng.uniform(0.3, 0.9, n)
    eps = rng.normal(0, 0.02, n) * (vbsa0 / 0.6 if noise == "proportional" else 1.0)
    wbsa = C1 * vbsa0 + C0 + B_STATURE * stature + eps
    pop = pd.DataFrame({"subject_id": np.arange(n), "sex": np.where(rng.random(n) < 0.5, "male", "female"),
                        "age_years": rng.uniform(5, 80, n), "stature_m": stature, "mass_kg": 60.0, "bmi": 22.0,
                        "wbsa_m2": wbsa})
    rows = []
    for az, el in VIEWS:
        v = vbsa0 if (az, el) == VIEWS[0] else rng.uniform(0.2, 0.6, n)
        rows.append(pd.DataFrame({"subject_id": np.arange(n), "azimuth_deg": az, "elevation_deg": el,
                                  "distance_m": 4.3, "camera": "kinect-v1", "vbsa_hit_m2": v, "vbsa_visible_m2": v,
                                  "n_pixels": 1000, "fits_in_frame": True}))
    return pop, pd.concat(rows, ignore_index=True)


@pytest.fixture(scope="module")
def fitted():
    pop, scan = make_tables(1500, seed=21)
    out = fit_all(pop, scan, FitSettings(models=("linear", "wls", "loglog"), k=5, groups=("all", "adults")))
    return pop, scan, out


def test_round_trip_keeps_every_prediction(fitted, tmp_path):
    _, _, out = fitted
    path = out.model.save(tmp_path / "model.json")
    again = WbsaModel.load(path)
    assert again.meta["population_kind"] == "unknown"
    assert again.meta["cameras"] == ["kinect-v1"] and again.meta["distances_m"] == [4.3]
    assert len(again.entries) == len(out.fits)
    v = np.linspace(0.3, 0.9, 7)
    for model in ("linear", "wls", "loglog"):
        for kw in ({}, {"stature_m": 1.7}):
            a = out.model.predict(0, 0, v, group="adults", model=model, **kw)
            b = again.predict(0, 0, v, group="adults", model=model, **kw)
            for x, y in zip(a, b):
                np.testing.assert_array_equal(x, y)
    json.loads(path.read_text())  # strict JSON


def test_intervals_equal_statsmodels_get_prediction(fitted):
    import statsmodels.api as sm

    pop, scan, out = fitted
    rows = scan[(scan["azimuth_deg"] == 0) & (scan["elevation_deg"] == 0)].merge(pop, on="subject_id")
    X = sm.add_constant(rows[["vbsa_visible_m2", "stature_m"]].to_numpy())
    y = rows["wbsa_m2"].to_numpy()
    new_v, new_s = np.array([0.35, 0.5, 0.6, 0.85]), np.array([1.2, 1.4, 1.6, 2.0])
    Xn = sm.add_constant(np.column_stack([new_v, new_s]), has_constant="add")
    for model, res, w in (("linear", sm.OLS(y, X).fit(), None),
                          ("wls", sm.WLS(y, X, weights=1 / X[:, 1] ** 2).fit(), 1 / new_v**2)):
        frame = res.get_prediction(Xn, weights=w).summary_frame(alpha=0.10)
        mean, lo, hi = out.model.predict(0, 0, new_v, stature_m=new_s, model=model, level=0.90)
        np.testing.assert_allclose(mean, frame["mean"], rtol=1e-10)
        np.testing.assert_allclose(lo, frame["obs_ci_lower"], rtol=1e-10)
        np.testing.assert_allclose(hi, frame["obs_ci_upper"], rtol=1e-10)


@pytest.mark.parametrize("noise,model", [("additive", "linear"), ("proportional", "wls")])
def test_prediction_interval_covers_95_percent_of_fresh_points(noise, model):
    pop, scan = make_tables(1500, seed=22, noise=noise)
    out = fit_all(pop, scan, FitSettings(models=(model,), k=5, groups=("all",)))
    c = out.fits.query("azimuth_deg == 0 and elevation_deg == 0 and predictors == 'vbsa+stature_m'").iloc[0]
    assert abs(c["c1"] - C1) < 3 * c["c1_se"] and abs(c["c_stature_m"] - B_STATURE) < 3 * c["c_stature_m_se"]
    fresh_pop, fresh_scan = make_tables(4000, seed=99, noise=noise)
    v = fresh_scan.loc[(fresh_scan["azimuth_deg"] == 0) & (fresh_scan["elevation_deg"] == 0), "vbsa_visible_m2"]
    mean, lo, hi = out.model.predict(0.0, 0.0, v.to_numpy(), stature_m=fresh_pop["stature_m"].to_numpy(), model=model)
    truth = fresh_pop["wbsa_m2"].to_numpy()
    coverage = np.mean((truth >= lo) & (truth <= hi))
    assert 0.935 < coverage < 0.965  # 0.95 +- 4.4 binomial sd for 4000 points
    assert np.all(lo < mean) and np.all(mean < hi)


def test_loglog_interval_covers_a_lognormal_law():
    rng = np.random.default_rng(5)
    n = 5000
    v = rng.uniform(0.3, 1.2, n)
    w = 2.9 * v**0.9 * np.exp(rng.normal(0, 0.04, n))
    pop = pd.DataFrame({"subject_id": np.arange(n), "sex": "female", "age_years": 30.0, "stature_m": 1.7,
                        "mass_kg": 60.0, "bmi": 22.0, "wbsa_m2": w})
    scan = pd.DataFrame({"subject_id": np.arange(n), "azimuth_deg": 45.0, "elevation_deg": 0.0, "distance_m": 4.3,
                         "camera": "kinect-v1", "vbsa_hit_m2": v, "vbsa_visible_m2": v, "n_pixels": 1,
                         "fits_in_frame": True})
    train = scan["subject_id"] < 1000
    out = fit_all(pop[:1000], scan[train], FitSettings(models=("loglog",), predictor_sets=((),), k=5,
                                                       groups=("all",)))
    mean, lo, hi = out.model.predict(45, 0, v[1000:], model="loglog")
    assert 0.935 < np.mean((w[1000:] >= lo) & (w[1000:] <= hi)) < 0.965
    # the point prediction is the conditional median: about half the points lie above it
    assert 0.47 < np.mean(w[1000:] > mean) < 0.53


def test_lookup_errors_and_poles(fitted):
    _, _, out = fitted
    m = out.model
    with pytest.raises(WbsaError, match="nearest fitted view is azimuth 90, elevation 30"):
        m.predict(80, 30, 0.5)
    with pytest.raises(WbsaError, match="available sets"):
        m.predict(0, 0, 0.5, extras={"waist_circ_m": 0.8})
    with pytest.raises(WbsaError, match="no model for group 'kids'"):
        m.predict(0, 0, 0.5, group="kids")
    # at the pole the azimuth only spins the image: any azimuth maps to the one fitted there
    np.testing.assert_array_equal(m.predict(0, -90, 0.4)[0], m.predict(123, -90, 0.4)[0])
    # azimuth is periodic
    np.testing.assert_array_equal(m.predict(90, 30, 0.4)[0], m.predict(-270, 30, 0.4)[0])
    # vectorised over mixed views
    both = m.predict([0, 90], [0, 30], [0.5, 0.4])[0]
    assert both[0] == m.predict(0, 0, 0.5)[0][0] and both[1] == m.predict(90, 30, 0.4)[0][0]


def test_loading_a_wrong_file_is_a_user_error(tmp_path):
    p = tmp_path / "x.json"
    p.write_text('{"format": "something-else"}')
    with pytest.raises(WbsaError, match="not a wbsa model file"):
        WbsaModel.load(p)
    with pytest.raises(WbsaError, match="does not exist"):
        WbsaModel.load(tmp_path / "missing.json")


def test_model_and_fit_output_print_one_short_line(fitted):
    out = fitted[2]
    text = repr(out.model)
    entries = out.model.entries
    n_views = len({(e["azimuth_deg"], e["elevation_deg"]) for e in entries})
    assert "\n" not in text and len(text) < 400  # the default dataclass repr printed every coefficient
    assert text.startswith(f"WbsaModel({len(entries):,} entries, {n_views} views; kinds linear, wls, loglog; "
                           "groups all, adults; predictors vbsa, vbsa+stature_m; columns ")
    assert "cameras kinect-v1; distances 4.3 m)" in text
    summary = repr(out)
    assert "\n" not in summary and len(summary) < 600
    assert f"fits {len(out.fits):,}, skipped {len(out.skipped):,}, residuals {len(out.residuals):,}" in summary
    assert summary.endswith(f"model={text})")
