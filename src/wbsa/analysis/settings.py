"""Settings of the per-view fit (``[fit]`` of a study, the flags of ``wbsa fit``) and of its groups.

Imports nothing heavy, so the ``wbsa fit`` parser takes its defaults from here.
"""

from __future__ import annotations

import math
from dataclasses import asdict, dataclass, field, fields

from wbsa.errors import SettingsError, WbsaError, check_field
from wbsa.typing import GROUP_NAMES, MODEL_KINDS, GroupName, ModelKind
from wbsa.settings_io import check_types

#: The groups of the paper (section 2.5): all, males/females, kids/adults, small/normal/big stature.
PAPER_GROUPS: tuple[str, ...] = ("all", "males", "females", "kids", "adults", "small", "normal", "big")

#: Thresholds used only by the claim groups; :meth:`GroupSpec.to_dict` records them only when changed, so fit
#: records written before these groups existed stay byte-identical.
_CLAIM_ONLY_FIELDS: tuple[str, ...] = ("underweight_max_bmi", "tall_min_stature_m")


def check_names(names: tuple[str, ...] | list[str], valid: tuple[str, ...], what: str,
                field: str | None = None) -> tuple[str, ...]:
    """``names`` without repeats, in order, if all are in ``valid``; else a WbsaError naming the valid ones.

    With ``field`` the error is a :class:`~wbsa.errors.SettingsError` of that settings field.
    """
    bad = [n for n in names if n not in valid]
    problem = (f"unknown {what}(s) {', '.join(bad)}; choose from {', '.join(valid)}" if bad
               else f"no {what} given; choose from {', '.join(valid)}" if not names else "")
    if problem:
        raise SettingsError(field, "has " + problem) if field else WbsaError(problem)
    return tuple(dict.fromkeys(names))


def check_group_names(names: tuple[str, ...] | list[str], field: str | None = None) -> tuple[str, ...]:
    """Validate group names; raise :class:`WbsaError` naming the valid ones (see :func:`check_names`)."""
    return check_names(names, GROUP_NAMES, "group", field)


def check_model_kinds(names: tuple[str, ...] | list[str], field: str | None = None) -> tuple[str, ...]:
    """Validate model kind names; raise :class:`WbsaError` naming the valid ones (see :func:`check_names`)."""
    return check_names(names, MODEL_KINDS, "model", field)


@dataclass(frozen=True)
class GroupSpec:
    """Thresholds that define the groups.

    Attributes
    ----------
    kid_max_age_years : float
        Kids are ``age_years <= kid_max_age_years`` (paper: 15); adults are older.
    small_max_stature_m : float
        Small stature is ``stature_m <= small_max_stature_m`` (paper: 1.40 m).
    big_min_stature_m : float
        Big stature is ``stature_m > big_min_stature_m`` (paper: 2.00 m); normal lies between.
    obese_min_bmi : float
        Obese is an adult with ``bmi >= obese_min_bmi`` (WHO: 30 kg/m²; children are left out because their
        BMI cut-offs depend on age and sex).
    underweight_max_bmi : float
        Underweight is an adult with ``bmi < underweight_max_bmi`` (WHO: 18.5 kg/m²; children are left out
        because their BMI cut-offs depend on age and sex).
    tall_min_stature_m : float
        Tall is ``stature_m >= tall_min_stature_m`` (default 1.85 m: the 90th percentile of US adult men,
        NHANES 2017–2020 weighted, 184.6 cm; 4.4 % of US adults). The paper's ``big`` (> 2.00 m) is too rare
        in real populations to test a claim on.
    """

    kid_max_age_years: float = 15.0
    small_max_stature_m: float = 1.40
    big_min_stature_m: float = 2.00
    obese_min_bmi: float = 30.0
    underweight_max_bmi: float = 18.5
    tall_min_stature_m: float = 1.85

    def __post_init__(self) -> None:
        check_types(self)
        check_field(0 < self.small_max_stature_m < self.big_min_stature_m, "small_max_stature_m",
                    f"must be positive and below big_min_stature_m (stature cuts 0 < small < big, e.g. 1.40 and "
                    f"2.00 m), got {self.small_max_stature_m:g} m and {self.big_min_stature_m:g} m")
        check_field(self.kid_max_age_years > 0, "kid_max_age_years",
                    f"must be a positive age in years, e.g. 15, got {self.kid_max_age_years:g}")
        check_field(self.obese_min_bmi > 0, "obese_min_bmi", f"must be a positive BMI, e.g. 30, got {self.obese_min_bmi:g}")
        check_field(0 < self.underweight_max_bmi < self.obese_min_bmi, "underweight_max_bmi",
                    f"must lie between 0 and obese_min_bmi ({self.obese_min_bmi:g}), e.g. 18.5 (WHO), "
                    f"got {self.underweight_max_bmi:g}")
        check_field(self.tall_min_stature_m > 0, "tall_min_stature_m",
                    f"must be a positive stature in metres, e.g. 1.85, got {self.tall_min_stature_m:g}")

    def to_dict(self) -> dict[str, float]:
        """The thresholds as plain JSON; the claim-only ones (underweight, tall) only when not at their defaults,
        so model files written before those groups existed stay byte-identical."""
        out = {}
        for f in fields(self):
            value = getattr(self, f.name)
            if f.name in _CLAIM_ONLY_FIELDS and value == f.default:
                continue
            out[f.name] = value
        return out

    def describe(self) -> dict[str, str]:
        """One human-readable definition per group name."""
        return {
            "all": "all subjects",
            "males": "sex == male",
            "females": "sex == female",
            "kids": f"age <= {self.kid_max_age_years:g} y",
            "adults": f"age > {self.kid_max_age_years:g} y",
            "small": f"stature <= {self.small_max_stature_m:g} m",
            "normal": f"{self.small_max_stature_m:g} m < stature <= {self.big_min_stature_m:g} m",
            "big": f"stature > {self.big_min_stature_m:g} m",
            "obese": f"adults with BMI >= {self.obese_min_bmi:g} kg/m2",
            "underweight": f"adults with BMI < {self.underweight_max_bmi:g} kg/m2",
            "tall": f"stature >= {self.tall_min_stature_m:g} m",
        }


@dataclass(frozen=True)
class FitSettings:
    """What :func:`wbsa.analysis.fit_views.fit_all` fits.

    Attributes
    ----------
    vbsa_columns : tuple of str
        VBSA selectors (``vbsa_hit_m2``, ``vbsa_visible_m2``, ``vbsa_recon_m2:<method>``), one fit each.
    predictor_sets : tuple of tuple of str
        Extra predictors besides VBSA, one fit per set; ``()`` is the VBSA-only model of eq. 5–7,
        ``('stature_m',)`` eq. 8 with stature. Aliases (``stature``, ``mass``, ``age``, ``sex``) are resolved.
        ``wbsa fit`` and a study always add ``()`` (:func:`with_vbsa_only`).
    models : tuple of {'linear', 'quadratic', 'loglog', 'wls'}
        Model kinds; the first is the model of the report's figures.
    groups : tuple of str
        Groups fitted, each on its own (:data:`wbsa.typing.GROUP_NAMES`).
    group_spec : GroupSpec
        Group thresholds (in a study file the sub-table ``[fit.group_spec]``).
    k : int
        Cross-validation folds (paper: 10).
    seed : int
        Seed of the fold assignment (folds are per group, by subject, the same at every view).
    require_in_frame : bool
        Drop scan rows whose body is cut by the image border (``fits_in_frame`` False).
    qq_points : int
        Quantiles per fit in the QQ table.
    residual_groups, residual_models : tuple of str
        Fits whose per-subject residuals are kept (the table grows as subjects × views).
    population_kind : str or None
        Label of the population (e.g. ``random``, ``survey``), recorded in the model file; None:
        ``unknown`` (a study sets its population's kind, ``wbsa fit`` the population file's name).
    correlation_view_deg : (float, float)
        Azimuth and elevation of the Spearman correlation matrix (paper Table 2: 0, 0).
    """

    vbsa_columns: tuple[str, ...] = ("vbsa_visible_m2",)
    predictor_sets: tuple[tuple[str, ...], ...] = ((), ("stature_m",))
    models: tuple[ModelKind, ...] = ("linear", "loglog", "wls")
    groups: tuple[GroupName, ...] = PAPER_GROUPS
    group_spec: GroupSpec = field(default_factory=GroupSpec)
    k: int = 10
    seed: int = 0
    require_in_frame: bool = True
    qq_points: int = 99
    residual_groups: tuple[GroupName, ...] = ("all",)
    residual_models: tuple[ModelKind, ...] = ("linear",)
    population_kind: str | None = None
    correlation_view_deg: tuple[float, float] = (0.0, 0.0)

    def __post_init__(self) -> None:
        check_types(self)
        from wbsa.analysis.data import resolve_vbsa_column

        check_field(int(self.k) >= 2, "k", f"must be at least 2 folds (paper: 10), got {self.k}")
        check_field(isinstance(self.seed, int) and self.seed >= 0, "seed", f"must be a whole number 0 or more, got {self.seed}")
        check_field(int(self.qq_points) >= 2, "qq_points", f"must be at least 2, got {self.qq_points}")
        check_model_kinds(self.models, "models")
        check_group_names(self.groups, "groups")
        check_field(len(self.vbsa_columns) >= 1, "vbsa_columns", "needs at least one VBSA column, e.g. vbsa_visible_m2")
        for col in self.vbsa_columns:
            try:
                resolve_vbsa_column(col)
            except WbsaError as exc:
                raise SettingsError("vbsa_columns", f"has {exc}") from None
        check_field(len(self.predictor_sets) >= 1, "predictor_sets", "needs at least one set; () is VBSA only")
        if self.residual_groups:
            check_group_names(self.residual_groups, "residual_groups")
        if self.residual_models:
            check_model_kinds(self.residual_models, "residual_models")
        check_field(all(math.isfinite(a) for a in self.correlation_view_deg), "correlation_view_deg",
                    f"must be finite angles in degrees, got {list(self.correlation_view_deg)}")

    def to_dict(self) -> dict:
        """The fitted models' settings as plain JSON (recorded in ``model.json`` and ``fit_info.json``).

        ``population_kind`` None is written as ``unknown``; the correlation view is not a setting of
        the models and is left out.
        """
        d = asdict(self)
        d["group_spec"] = self.group_spec.to_dict()
        d["predictor_sets"] = [list(s) for s in self.predictor_sets]
        d["population_kind"] = self.population_kind or "unknown"
        del d["correlation_view_deg"]
        return d


def with_vbsa_only(predictor_sets) -> tuple[tuple[str, ...], ...]:
    """``predictor_sets`` with the VBSA-only set ``()`` first and no set twice (what ``wbsa fit`` and a study fit)."""
    return tuple(dict.fromkeys([(), *(tuple(s) for s in predictor_sets)]))
