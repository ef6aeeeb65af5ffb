"""How real the virtual bodies are: the virtual side of the comparison in ``docs/calibration.md``.

Pure functions of a population table (``wbsa population``), for the realism benchmark and the report:

* :func:`hw_law`: how well stature and mass alone predict the skin area, log WBSA = a + b·log H +
  c·log W (R², residual SD = the scatter of area at fixed H and W), the area difference between
  women and men at the same H and W, and how the mesh / Du Bois ratio moves with BMI;
* :func:`dubois_table`: mesh area / Du Bois by sex and BMI class, beside what the formulae fitted on
  real scans (Schlich 2010, Yu 2010) and on obese patients (Livingston & Lee 2001) give for the same
  statures and masses;
* :func:`dubois_bmi_slopes`: how fast mesh / Du Bois and those formulae / Du Bois rise with BMI;
* :func:`composition_table`: body density and fat fraction by sex and BMI class, beside what
  Deurenberg's equation and Siri's density give for the same subjects;
* :func:`group_counts`: subjects per group (all, adults, children, obese, underweight, small, tall,
  women, men), :func:`posture_mix` and :func:`posed_area_change` when the table has a ``posture`` column.

The published figures these are set beside are in :mod:`wbsa.analysis.calibration_refs`.

Adult BMI classes (WHO) are used for adults only (age > 15 y); children are one class of their own,
as a child's BMI is read against its age.
"""

from __future__ import annotations

from dataclasses import asdict, dataclass

import numpy as np
import pandas as pd

from wbsa.analysis.groups import GroupSpec, assign_groups
from wbsa.errors import WbsaError

#: WHO adult BMI classes ``(label, low, high)``, kg/m², low inclusive.
BMI_CLASSES = (("<18.5", 0.0, 18.5), ("18.5-25", 18.5, 25.0), ("25-30", 25.0, 30.0), ("30-35", 30.0, 35.0),
               ("35-40", 35.0, 40.0), (">=40", 40.0, np.inf))
#: Label of the children's class in the tables (age <= the kid limit, any BMI).
CHILDREN = "children"
#: Group names of :func:`group_counts`, in order.
REALISM_GROUPS = ("all", "adults", "children", "obese", "underweight", "small", "tall", "women", "men")
#: The analysis group (:data:`wbsa.typing.GROUP_NAMES`) of each plain name that differs.
_GROUP_OF = {"children": "kids", "women": "females", "men": "males"}
#: Formulae fitted on measured areas that :func:`dubois_table` sets beside the mesh (keys of
#: :data:`wbsa.formulae.FORMULAE`): 3-D scans (Schlich 2010, Yu 2010) and obese patients
#: (Livingston & Lee 2001).
MEASURED_FORMULAE = ("schlich", "yu", "livingston_lee")
_REQUIRED = ("sex", "age_years", "stature_m", "mass_kg", "bmi", "wbsa_m2", "volume_m3")


@dataclass(frozen=True)
class HWLaw:
    """The fit log WBSA = a + b·log H + c·log W over a population.

    Attributes
    ----------
    n : int
    a, b, c : float
        Coefficients (H in m, W in kg, WBSA in m²).
    r2 : float
        Coefficient of determination of log WBSA.
    residual_sd_percent : float
        Residual SD of log WBSA × 100 (≈ % scatter of area at fixed H and W), ``n − 3`` degrees of freedom.
    female_effect_percent : float
        Area of women relative to men at the same H and W, % (from the fit with a sex term).
    dubois_bmi_slope_percent : float
        Slope of 100·(mesh / Du Bois − 1) against BMI over the adults, % per kg/m² (NaN without adults).
    """

    n: int
    a: float
    b: float
    c: float
    r2: float
    residual_sd_percent: float
    female_effect_percent: float
    dubois_bmi_slope_percent: float

    def to_dict(self) -> dict[str, float]:
        return asdict(self)


def _check(table: pd.DataFrame) -> None:
    missing = [c for c in _REQUIRED if c not in table.columns]
    if missing:
        raise WbsaError(f"population table lacks column(s) {', '.join(missing)}; build it with wbsa population")
    if len(table) < 5:
        raise WbsaError(f"the realism summary needs at least 5 subjects, got {len(table)}")


def one_row_per_body(table: pd.DataFrame) -> pd.DataFrame:
    """Survey tables: the matched bodies only (variation 0); other tables as they are."""
    return table[table["variation"] == 0] if "variation" in table.columns else table


def dubois_m2(table: pd.DataFrame) -> np.ndarray:
    """Du Bois BSA (m²) of every subject, ``(n,) float64``."""
    from wbsa.formulae import bsa

    return np.asarray(bsa("dubois", 100 * table["stature_m"].to_numpy(), table["mass_kg"].to_numpy(), check=False))


def hw_law(table: pd.DataFrame, spec: GroupSpec = GroupSpec()) -> HWLaw:
    """Fit the log H/W law to ``table`` (see :class:`HWLaw`)."""
    _check(table)
    t = one_row_per_body(table)
    y = np.log(t["wbsa_m2"].to_numpy())
    x = np.column_stack([np.ones(len(t)), np.log(t["stature_m"].to_numpy()), np.log(t["mass_kg"].to_numpy())])
    coef, *_ = np.linalg.lstsq(x, y, rcond=None)
    resid = y - x @ coef
    female = (t["sex"] == "female").to_numpy(dtype=np.float64)
    xs = np.column_stack([x, female])
    coef_s, *_ = np.linalg.lstsq(xs, y, rcond=None)
    slope = _bmi_slope(t, t["wbsa_m2"].to_numpy() / dubois_m2(t), spec)
    return HWLaw(n=len(t), a=float(coef[0]), b=float(coef[1]), c=float(coef[2]),
                 r2=float(1 - resid.var() / y.var()),
                 residual_sd_percent=float(100 * np.sqrt((resid**2).sum() / (len(t) - 3))),
                 female_effect_percent=float(100 * np.expm1(coef_s[3])) if female.any() and (1 - female).any()
                 else float("nan"),
                 dubois_bmi_slope_percent=slope)


def _bmi_slope(table: pd.DataFrame, ratio: np.ndarray, spec: GroupSpec) -> float:
    """Slope of 100·(ratio − 1) against BMI over the adults, % per kg/m² (NaN with fewer than 3 adults)."""
    adults = table["age_years"].to_numpy() > spec.kid_max_age_years
    if adults.sum() < 3:
        return float("nan")
    return float(np.polyfit(table["bmi"].to_numpy()[adults], 100 * (ratio[adults] - 1), 1)[0])


def dubois_bmi_slopes(table: pd.DataFrame, spec: GroupSpec = GroupSpec()) -> dict[str, float]:
    """How fast mesh / Du Bois and each measured formula / Du Bois rise with BMI over the adults.

    Returns
    -------
    dict
        ``mesh`` and each key of :data:`MEASURED_FORMULAE` -> slope of 100·(x / Du Bois − 1) against
        BMI, % per kg/m², the formulae evaluated at the same subjects' stature and mass (NaN with
        fewer than 3 adults). ``mesh`` equals :attr:`HWLaw.dubois_bmi_slope_percent`.
    """
    from wbsa.formulae import bsa

    _check(table)
    t = one_row_per_body(table)
    dubois = dubois_m2(t)
    h, w = 100 * t["stature_m"].to_numpy(), t["mass_kg"].to_numpy()
    out = {"mesh": _bmi_slope(t, t["wbsa_m2"].to_numpy() / dubois, spec)}
    for key in MEASURED_FORMULAE:
        out[key] = _bmi_slope(t, np.asarray(bsa(key, h, w, t["sex"].to_numpy(), check=False)) / dubois, spec)
    return out


def bmi_class(table: pd.DataFrame, spec: GroupSpec = GroupSpec()) -> pd.Series:
    """Class label of every subject: :data:`CHILDREN`, or the adult's :data:`BMI_CLASSES` label."""
    bmi = table["bmi"].to_numpy()
    labels = np.full(len(table), "", dtype=object)
    for label, lo, hi in BMI_CLASSES:
        labels[(bmi >= lo) & (bmi < hi)] = label
    labels[table["age_years"].to_numpy() <= spec.kid_max_age_years] = CHILDREN
    order = [CHILDREN, *(c[0] for c in BMI_CLASSES)]
    return pd.Series(pd.Categorical(labels, categories=order, ordered=True), index=table.index, name="bmi_class")


def _by_sex_and_class(table: pd.DataFrame, values: dict[str, np.ndarray], spec: GroupSpec) -> pd.DataFrame:
    """Mean and SD of every ``values`` column per sex and class, with ``n``; empty cells left out."""
    frame = pd.DataFrame(values, index=table.index)
    frame["sex"] = table["sex"].to_numpy()
    frame["bmi_class"] = bmi_class(table, spec)
    groups = frame.groupby(["sex", "bmi_class"], observed=True)
    out = groups.size().rename("n").to_frame()
    for name in values:
        out[f"{name}_mean"] = groups[name].mean()
        out[f"{name}_sd"] = groups[name].std()
    return out.reset_index()


def dubois_table(table: pd.DataFrame, spec: GroupSpec = GroupSpec()) -> pd.DataFrame:
    """Mesh area / Du Bois per sex and BMI class, beside the measured-area formulae / Du Bois.

    Returns
    -------
    pandas.DataFrame
        ``sex, bmi_class, n``, then mean and SD of ``mesh_over_dubois`` and of
        ``<formula>_over_dubois`` for each of :data:`MEASURED_FORMULAE` evaluated at the same
        subjects' stature and mass (what bodies measured by 3-D scan or geometry would be, if those
        formulae hold for them).
    """
    from wbsa.formulae import bsa

    _check(table)
    t = one_row_per_body(table)
    h, w = 100 * t["stature_m"].to_numpy(), t["mass_kg"].to_numpy()
    dubois = dubois_m2(t)
    values = {"mesh_over_dubois": t["wbsa_m2"].to_numpy() / dubois}
    for key in MEASURED_FORMULAE:
        values[f"{key}_over_dubois"] = np.asarray(bsa(key, h, w, t["sex"].to_numpy(), check=False)) / dubois
    return _by_sex_and_class(t, values, spec)


def composition_table(table: pd.DataFrame, spec: GroupSpec = GroupSpec()) -> pd.DataFrame:
    """Body density (kg/m³, mass / volume) and fat fraction per sex and BMI class, beside Deurenberg's.

    The fat fraction is the table's ``fat_fraction`` column; a constant-density table has none,
    and gets the fat fraction its density means by Siri's equation (55 % at 980 kg/m³).

    Returns
    -------
    pandas.DataFrame
        ``sex, bmi_class, n``, then mean and SD of ``density_kg_m3``, ``fat_fraction`` and of
        ``deurenberg_density_kg_m3`` / ``deurenberg_fat_fraction``: what Deurenberg's body-fat
        equation (its mean, no residual) and Siri's density give at the same subjects' BMI, age and sex
        (:mod:`wbsa.analysis.calibration_refs`).
    """
    from wbsa.analysis.calibration_refs import deurenberg_fat_fraction
    from wbsa.bodies.composition import density_from_fat, fat_from_density

    _check(table)
    t = one_row_per_body(table)
    density = t["mass_kg"].to_numpy() / t["volume_m3"].to_numpy()
    fat = t["fat_fraction"].to_numpy() if "fat_fraction" in t.columns else fat_from_density(density)
    expected = deurenberg_fat_fraction(t["bmi"].to_numpy(), t["age_years"].to_numpy(),
                                       (t["sex"] == "male").to_numpy())
    return _by_sex_and_class(t, {"density_kg_m3": density, "fat_fraction": fat,
                                 "deurenberg_density_kg_m3": density_from_fat(expected, "siri"),
                                 "deurenberg_fat_fraction": expected}, spec)


def group_masks(table: pd.DataFrame, spec: GroupSpec = GroupSpec()) -> dict[str, np.ndarray]:
    """Membership ``(n,) bool`` of every :data:`REALISM_GROUPS` group: the analysis groups
    (:func:`wbsa.analysis.groups.assign_groups`, the same definitions as the fits and the claim) under the
    plain names (children = kids, women = females, men = males)."""
    members = assign_groups(table, spec)
    return {name: members[_GROUP_OF.get(name, name)].to_numpy(dtype=bool) for name in REALISM_GROUPS}


def group_counts(table: pd.DataFrame, spec: GroupSpec = GroupSpec()) -> dict[str, int]:
    """Subjects per :data:`REALISM_GROUPS` group (see :func:`group_masks`)."""
    _check(table)
    return {name: int(mask.sum()) for name, mask in group_masks(one_row_per_body(table), spec).items()}


def posture_mix(table: pd.DataFrame) -> dict[str, int]:
    """Subjects per named posture (``posture`` column); ``{}`` when the table has none."""
    if "posture" not in table.columns:
        return {}
    counts = one_row_per_body(table)["posture"].value_counts()
    return {str(k): int(v) for k, v in counts.sort_index().items()}


def posed_area_change(table: pd.DataFrame) -> pd.DataFrame:
    """How much posing changes the skin area: 100·(``wbsa_posed_m2`` / ``wbsa_m2`` − 1) per posture.

    Returns
    -------
    pandas.DataFrame
        ``posture`` (``all`` first, then each name), ``n``, ``mean_percent``, ``sd_percent``,
        ``min_percent``, ``max_percent``; empty when the table has no posture columns.
    """
    from wbsa.bodies.posture_table import POSED_AREA_COLUMN

    cols = ["posture", "n", "mean_percent", "sd_percent", "min_percent", "max_percent"]
    if "posture" not in table.columns or POSED_AREA_COLUMN not in table.columns:
        return pd.DataFrame(columns=cols)
    t = one_row_per_body(table)
    change = pd.Series(100 * (t[POSED_AREA_COLUMN].to_numpy() / t["wbsa_m2"].to_numpy() - 1), index=t.index)
    rows = [("all", change)] + [(str(k), change[t["posture"] == k]) for k in sorted(t["posture"].unique())]
    return pd.DataFrame([(name, len(c), c.mean(), c.std(), c.min(), c.max()) for name, c in rows], columns=cols)


def realism_summary(table: pd.DataFrame, spec: GroupSpec = GroupSpec()) -> dict[str, object]:
    """Everything above as plain data (JSON-able).

    Keys: ``hw_law`` (:class:`HWLaw` as a dict), ``dubois_bmi_slopes``, ``schlich_female_effect_percent``
    (Schlich's women / men at the adults' stature and mass, :mod:`wbsa.analysis.calibration_refs`),
    ``groups``, ``posture``, ``posed_area`` (list of row dicts, empty without postures),
    ``bmi_range_adults``, ``composition_columns`` (whether the table has its own fat fractions),
    ``dubois`` and ``composition`` (lists of row dicts).
    """
    from wbsa.analysis.calibration_refs import schlich_female_effect_percent

    _check(table)
    t = one_row_per_body(table)
    adults = t[t["age_years"] > spec.kid_max_age_years]
    return {
        "hw_law": hw_law(t, spec).to_dict(),
        "dubois_bmi_slopes": dubois_bmi_slopes(t, spec),
        "schlich_female_effect_percent": schlich_female_effect_percent(adults["stature_m"].to_numpy(),
                                                                       adults["mass_kg"].to_numpy()),
        "groups": group_counts(t, spec),
        "posture": posture_mix(t),
        "posed_area": posed_area_change(t).to_dict("records"),
        "bmi_range_adults": [float(adults["bmi"].min()), float(adults["bmi"].max())] if len(adults) else [],
        "composition_columns": "fat_fraction" in t.columns,
        "dubois": dubois_table(t, spec).to_dict("records"),
        "composition": composition_table(t, spec).to_dict("records"),
    }
