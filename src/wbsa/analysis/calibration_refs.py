"""What real bodies are published to do: the reference side of ``docs/calibration.md``, with citations.

One place for the published figures that the virtual populations are set beside (the report's
calibration section, ``benchmarks/bench_population_realism.py`` and the doc): :data:`SOURCES` (who
measured what, on how many bodies) and :data:`FIGURES` (each number, its unit, its source and the
quote or the reason it is missing). A figure the stored sources do not give has ``value=None`` and
says so: nothing here is quoted from memory.

The published *equations* live where they are used: the BSA formulae fitted on measured areas in
:data:`wbsa.formulae.FORMULAE` (``schlich``, ``yu``, ``livingston_lee``), Deurenberg's body-fat
equation and the two-compartment density equations in :mod:`wbsa.bodies.composition`. The functions
below evaluate them at a virtual population's own statures, masses, ages and sexes ("what real bodies
of this size would give, if the equation holds"), which is how the reference side of a comparison is
made when a source gives an equation rather than a table.
"""

from __future__ import annotations

from dataclasses import dataclass
from types import MappingProxyType
from typing import Mapping

import numpy as np

from wbsa.bodies.composition import DEURENBERG_ADULT_SEE, DEURENBERG_CHILD_SEE, density_from_fat, fat_fraction
from wbsa.formulae import FORMULAE


@dataclass(frozen=True)
class Source:
    """One published study.

    Attributes
    ----------
    key : str
        Short name used by :class:`PublishedFigure` (``"deurenberg_1991"``).
    label : str
        Authors and year as cited in text (``"Deurenberg et al. 1991"``).
    citation : str
        Full reference.
    bodies : str
        Who was measured.
    measured : str
        What was measured, and how.
    """

    key: str
    label: str
    citation: str
    bodies: str
    measured: str


@dataclass(frozen=True)
class PublishedFigure:
    """One published number (or range) with its source.

    Attributes
    ----------
    key : str
    what : str
        The quantity, in words.
    value : float, (float, float) or None
        The number, a ``(low, high)`` range, or ``None`` when the stored sources do not give it.
    unit : str
    source : str
        Key of :data:`SOURCES`.
    note : str
        The quote the number comes from, or why it is missing.
    """

    key: str
    what: str
    value: float | tuple[float, float] | None
    unit: str
    source: str
    note: str = ""

    @property
    def found(self) -> bool:
        """False when the stored sources do not give this figure."""
        return self.value is not None

    def text(self) -> str:
        """The value as printed (``"4.1 %BF"``, ``"13.9–40.9 kg/m²"``, ``"not found"``)."""
        if self.value is None:
                     return "not found"
        if isinstance(self.value, tuple):
                     lo, hi = self.value
                     return f"{lo:,g}–{hi:,g} {self.unit}".strip()
        return f"{self.value:,g} {self.unit}".strip()


_SOURCES = (
    Source("deurenberg_1991", "Deurenberg et al. 1991",
           "Deurenberg P, Weststrate JA, Seidell JC. Body mass index as a measure of body fatness: age- and "
           "sex-specific prediction formulas. Br J Nutr. 1991;65(2):105-114.",
           "1,229 Dutch people (521 men), 7–83 y, BMI 13.9–40.9",
           "body fat by underwater weighing (densitometry); fat % predicted from BMI, age and sex"),
    Source("siri_1961", "Siri 1961",
           "Siri WE. Body composition from fluid spaces and density: analysis of methods. In: Brozek J, "
           "Henschel A, eds. Techniques for Measuring Body Composition. Washington DC: National Academy of "
           "Sciences; 1961:223-244.",
           "—", "two-compartment model: fat 0.900 g/cm³, fat-free mass 1.100 g/cm³; %BF = 495/D − 450"),
    Source("brozek_1963", "Brozek et al. 1963",
           "Brozek J, Grande F, Anderson JT, Keys A. Densitometric analysis of body composition: revision of "
           "some quantitative assumptions. Ann N Y Acad Sci. 1963;110:113-140.",
           "—", "two-compartment model: %BF = 457/D − 414.2"),
    Source("livingston_lee_2001", "Livingston & Lee 2001", FORMULAE["livingston_lee"].citation,
           "45 patients of 51.3–248.6 kg, with published series",
           "BSA by a geometric method; BSA = 0.1173·W^0.6466 fitted on them"),
    Source("schlich_2010", "Schlich et al. 2010", FORMULAE["schlich"].citation,
           "adults measured by 3-D body scanner", "BSA from the scans; sex-specific power laws fitted on them"),
    Source("yu_2010", "Yu, Lin & Yang 2010", FORMULAE["yu"].citation,
           "3-D scan database", "BSA from the scans; a power law fitted on them"),
    Source("kuehnapfel_2017", "Kuehnapfel et al. 2017",
           "Kuehnapfel A, Ahnert P, Loeffler M, Scholz M. Body surface assessment with 3D laser-based "
           "anthropometry: reliability, validation, and improvement of empirical surface formulae. "
           "Eur J Appl Physiol. 2017;117(2):371-380.",
           "1,435 adults (LIFE-Adult, Leipzig)",
           "BSA by 3-D laser scan; 18 formulae validated by sex and BMI; new coefficients"),
    Source("verbraecken_2006", "Verbraecken et al. 2006",
           "Verbraecken J, Van de Heyning P, De Backer W, Van Gaal L. Body surface area in normal-weight, "
           "overweight, and obese adults. A comparison study. Metabolism. 2006;55(4):515-524.",
           "adults > 18 y by BMI class (20–24.9, 25–29.9, ≥ 30)",
           "formulae compared with each other; no measured area"),
)

#: Every source by key (read-only).
SOURCES: Mapping[str, Source] = MappingProxyType({s.key: s for s in _SOURCES})

_NOT_IN_ABSTRACT = ("the stored copies of Kuehnapfel 2017 and Verbraecken 2006 hold only the first part of "
                    "their abstracts, and no other stored source gives it")
_F = PublishedFigure
_FIGURES = (
    _F("area_scatter_at_fixed_hw_percent", "scatter of measured area at fixed stature and mass (residual SD)",
       None, "%", "kuehnapfel_2017", _NOT_IN_ABSTRACT),
    _F("dubois_bias_by_class", "Du Bois − scan by sex and BMI class", None, "%", "kuehnapfel_2017",
       _NOT_IN_ABSTRACT),
    _F("dubois_obese_underestimate_max_percent", "Du Bois under-estimate of BSA in obese patients, at most",
       20.0, "%", "livingston_lee_2001", "“Du Bois underestimated BSA in obese patients by as much as 20 %”"),
    _F("livingston_lee_mass_range_kg", "mass of the patients measured", (51.3, 248.6), "kg",
       "livingston_lee_2001"),
    _F("kuehnapfel_scans", "adults scanned", 1435.0, "", "kuehnapfel_2017"),
    _F("kuehnapfel_occc", "scan reliability (overall concordance correlation)", 0.998, "", "kuehnapfel_2017"),
    _F("fat_see_adult_percent", "standard error of estimate of body fat, adults", DEURENBERG_ADULT_SEE, "%BF",
       "deurenberg_1991"),
    _F("fat_see_child_percent", "standard error of estimate of body fat, children", DEURENBERG_CHILD_SEE, "%BF",
       "deurenberg_1991"),
    _F("fat_r2_adult", "R² of the body-fat equation, adults", 0.79, "", "deurenberg_1991"),
    _F("fat_r2_child", "R² of the body-fat equation, children", 0.38, "", "deurenberg_1991"),
    _F("deurenberg_bmi_range", "BMI of the people measured", (13.9, 40.9), "kg/m²", "deurenberg_1991",
       "“slightly overestimated” body fat in the obese; beyond BMI 40.9 the equation is an extrapolation"),
    _F("deurenberg_age_range_years", "age of the people measured", (7.0, 83.0), "y", "deurenberg_1991"),
    _F("deurenberg_people", "people measured", 1229.0, "", "deurenberg_1991"),
    _F("density_range_kg_m3", "body density from all fat to all fat-free mass",
       tuple(float(x) for x in np.round(density_from_fat(np.array([1.0, 0.0]), "siri"), 1)), "kg/m³",
       "siri_1961", "the two compartments' densities, 495/(100 + 450) and 495/450 g/cm³"),
)
del _F

#: Every published figure by key (read-only), in the order of :data:`_FIGURES`.
FIGURES: Mapping[str, PublishedFigure] = MappingProxyType({f.key: f for f in _FIGURES})

#: Keys of :data:`wbsa.formulae.FORMULAE` fitted on measured areas, with their :data:`SOURCES` key.
MEASURED_FORMULA_SOURCES: Mapping[str, str] = MappingProxyType(
    {"schlich": "schlich_2010", "yu": "yu_2010", "livingston_lee": "livingston_lee_2001"})


def cite(key: str) -> str:
    """``"<what>: <value> (<source label>)"`` of one figure, e.g. for a table cell or a sentence."""
    f = FIGURES[key]
    return f"{f.text()} ({SOURCES[f.source].label})"


def schlich_female_effect_percent(stature_m: np.ndarray, mass_kg: np.ndarray) -> float:
    """Area of women relative to men at the same stature and mass by Schlich's scan-fitted formulae, %.

    The mean over the given statures and masses (each ``(n,) float64``) of 100·(female / male − 1):
    Schlich's women have +3.7 % at 160 cm / 60 kg and +7.5 % at 165 cm / 100 kg. NaN for no subject.
    """
    h, w = 100 * np.asarray(stature_m, dtype=np.float64), np.asarray(mass_kg, dtype=np.float64)
    if h.size == 0:
        return float("nan")
    f, m = (FORMULAE["schlich"].function(h, w, np.full(h.shape, flag)) for flag in (True, False))
    return float(np.mean(100 * (f / m - 1)))


def deurenberg_siri_density_kg_m3(bmi: np.ndarray, age_years: np.ndarray, male: np.ndarray) -> np.ndarray:
    """Body density (kg/m³) that Deurenberg's body-fat equation and Siri's density give at a BMI, age and sex.

    The equation's mean (no residual), clipped to the physiological fat limits of
    :mod:`wbsa.bodies.composition`; each argument ``(n,)``, result ``(n,) float64``.
    """
    z = np.zeros(len(np.atleast_1d(bmi)))
    return density_from_fat(fat_fraction(bmi, age_years, male, z), "siri")


def deurenberg_fat_fraction(bmi: np.ndarray, age_years: np.ndarray, male: np.ndarray) -> np.ndarray:
    """Deurenberg's mean fat fraction (0–1) at a BMI, age and sex, clipped as above; ``(n,) float64``."""
    return fat_fraction(bmi, age_years, male, np.zeros(len(np.atleast_1d(bmi))))


__all__ = ["PublishedFigure", "Source", "FIGURES", "SOURCES", "MEASURED_FORMULA_SOURCES", "cite",
                    "schlich_female_effect_percent", "deurenberg_siri_density_kg_m3", "deurenberg_fat_fraction"]
