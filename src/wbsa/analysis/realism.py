"""How real the virtual bodies are: the virtual side of the comparison in ``docs/calibration.md``.

Pure functions of a population table (``wbsa population``), for the realism benchmark and the report:

* :func:`hw_law`: how well stature and mass alone predict the skin area, log WBSA = a + b·log H +
  c·log W (R², residual SD = the scatter of area at fixed H and W), the area difference between
  women and men at the same H and W, and how the mesh / Du Bois ratio moves with BMI;
* :func:`dubois_table`: mesh area / Du Bois by sex and BMI class, beside what the formulae fitted on
  real scans (Schlich 2010, Yu 2010) and on obese patients (Livingston & Lee 2001) give for the same
  statures and masses;
* :func:`composition_table`: body density and fat fraction by sex and BMI class;
* :func:`group_counts`: subjects per group (all, adults, children, obese, underweight, small, tall,
  women, men) and the posture mix when the table has a ``posture`` column.

Adult BMI classes (WHO) are used for adults only (age > 15 y); children are one class of their own,
as a child's BMI is read against its age.
"""

from __future__ import annotations

from dataclasses import asdict, dataclass

import numpy as np
import pandas as pd

from wbsa.analysis.groups import GroupSpec
from wbsa.errors import WbsaError

#: WHO adult BMI classes ``(label, low, high)``, kg/m², low inclusive.
BMI_CLASSES = (("<18.5", 0.0, 18.5), ("18.5-25", 18.5, 25.0), ("25-30", 25.0, 30.0), ("30-35", 30.0, 35.0),
               ("35-40", 35.0, 40.0), (">=40", 40.0, np.inf))
#: Label of the children's class in the tables (age <= the kid limit, any BMI).
CHILDREN = "children"
#: Group names of :func:`group_counts`, in order.
REALISM_GROUPS = ("all", "adults", "children", "obese", "underweight", "small", "tall", "women", "men")
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


def _one_row_per_body(table: pd.DataFrame) -> pd.DataFrame:
    """Survey tables: the matched bodies only (variation 0); other tables as they are."""
    return table[table["variation"] == 0] if "variation" in table.columns else table


def dubois_m2(table: pd.DataFrame) -> np.ndarray:
    """Du Bois BSA (m²) of every subject, ``(n,) float64``."""
    from wbsa.formulae import bsa

    return np.asarray(bsa("dubois", 100 * table["stature_m"].to_numpy(), table["mass_kg"].to_numpy(), check=False))


def hw_law(table: pd.DataFrame, spec: GroupSpec = GroupSpec()) -> HWLaw:
    """Fit the log H/W law to ``table`` (see :class:`HWLaw`)."""
    _check(table)
    t = _one_row_per_body(table)
    y = np.log(t["wbsa_m2"].to_numpy())
    x = np.column_stack([np.ones(len(t)), np.log(t["stature_m"].to_numpy()), np.log(t["mass_kg"].to_numpy())])
    coef, *_ = np.linalg.lstsq(x, y, rcond=None)
    resid = y - x @ coef
    female = (t["sex"] == "female").to_numpy(dtype=np.float64)
    xs = np.column_stack([x, female])
    coef_s, *_ = np.linalg.lstsq(xs, y, rcond=None)
    adults = t["age_years"].to_numpy() > spec.kid_max_age_years
    slope = np.nan
    if adults.sum() >= 3:
        ratio = 100 * (t["wbsa_m2"].to_numpy()[adults] / dubois_m2(t)[adults] - 1)
        slope = float(np.polyfit(t["bmi"].to_numpy()[adults], ratio, 1)[0])
    return HWLaw(n=len(t), a=float(coef[0]), b=float(coef[1]), c=float(coef[2]),
                 r2=float(1 - resid.var() / y.var()),
                 residual_sd_percent=float(100 * np.sqrt((resid**2).sum() / (len(t) - 3))),
                 female_effect_percent=float(100 * np.expm1(coef_s[3])) if female.any() and (1 - female).any()
                 else float("nan"),
                 dubois_bmi_slope_percent=slope)


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
    t = _one_row_per_body(table)
    h, w = 100 * t["stature_m"].to_numpy(), t["mass_kg"].to_numpy()
    dubois = dubois_m2(t)
    values = {"mesh_over_dubois": t["wbsa_m2"].to_numpy() / dubois}
    for key in MEASURED_FORMULAE:
        values[f"{key}_over_dubois"] = np.asarray(bsa(key, h, w, t["sex"].to_numpy(), check=False)) / dubois
    return _by_sex_and_class(t, values, spec)


def composition_table(table: pd.DataFrame, spec: GroupSpec = GroupSpec()) -> pd.DataFrame:
    """Body density (kg/m³, mass / volume) and fat fraction per sex and BMI class.

    The fat fraction is the table's ``fat_fraction`` column; a constant-density table has none,
    and gets the fat fraction its density means by Siri's equation (55 % at 980 kg/m³).
    """
    from wbsa.bodies.composition import fat_from_density

    _check(table)
    t = _one_row_per_body(table)
    density = t["mass_kg"].to_numpy() / t["volume_m3"].to_numpy()
    fat = t["fat_fraction"].to_numpy() if "fat_fraction" in t.columns else fat_from_density(density)
    return _by_sex_and_class(t, {"density_kg_m3": density, "fat_fraction": fat}, spec)


def group_masks(table: pd.DataFrame, spec: GroupSpec = GroupSpec()) -> dict[str, np.ndarray]:
    """Membership ``(n,) bool`` of every :data:`REALISM_GROUPS` group.

    Obese (BMI ≥ ``spec.obese_min_bmi``) and underweight (BMI < 18.5) are adult cut-offs and count
    adults only; small is stature ≤ ``spec.small_max_stature_m``, tall > ``spec.big_min_stature_m``.
    """
    age, bmi, stature = (table[c].to_numpy(dtype=float) for c in ("age_years", "bmi", "stature_m"))
    adults = age > spec.kid_max_age_years
    return {
        "all": np.ones(len(table), dtype=bool),
        "adults": adults,
        "children": ~adults,
        "obese": adults & (bmi >= spec.obese_min_bmi),
        "underweight": adults & (bmi < 18.5),
        "small": stature <= spec.small_max_stature_m,
        "tall": stature > spec.big_min_stature_m,
        "women": (table["sex"] == "female").to_numpy(),
        "men": (table["sex"] == "male").to_numpy(),
    }


def group_counts(table: pd.DataFrame, spec: GroupSpec = GroupSpec()) -> dict[str, int]:
    """Subjects per :data:`REALISM_GROUPS` group (see :func:`group_masks`)."""
    _check(table)
    return {name: int(mask.sum()) for name, mask in group_masks(_one_row_per_body(table), spec).items()}


def posture_mix(table: pd.DataFrame) -> dict[str, int]:
    """Subjects per named posture (``posture`` column); ``{}`` when the table has none."""
    if "posture" not in table.columns:
        return {}
    counts = _one_row_per_body(table)["posture"].value_counts()
    return {str(k): int(v) for k, v in counts.sort_index().items()}


def realism_summary(table: pd.DataFrame, spec: GroupSpec = GroupSpec()) -> dict[str, object]:
    """Everything above as plain data (JSON-able): ``hw_law``, ``groups``, ``posture``,
    ``dubois`` and ``composition`` (lists of row dicts), and ``bmi_range_adults``."""
    _check(table)
    t = _one_row_per_body(table)
    adults = t[t["age_years"] > spec.kid_max_age_years]["bmi"]
    return {
        "hw_law": hw_law(t, spec).to_dict(),
        "groups": group_counts(t, spec),
        "posture": posture_mix(t),
        "bmi_range_adults": [float(adults.min()), float(adults.max())] if len(adults) else [],
        "dubois": dubois_table(t, spec).to_dict("records"),
        "composition": composition_table(t, spec).to_dict("records"),
    }
