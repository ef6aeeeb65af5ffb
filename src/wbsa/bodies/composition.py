"""Body composition: fat fraction from BMI, age and sex; density from fat fraction; mass = volume × density.

anny gives a body's shape and volume, not its mass. A constant density (anny's 980 kg/m³) makes
mass a fixed multiple of volume, so body composition never varies. The composition models here
give each subject the body density a real person of its BMI, age and sex would have:

1. **fat fraction** from Deurenberg, Weststrate & Seidell (1991, Br J Nutr 65:105–114; 1,229 Dutch
   people aged 7–83 y, BMI 13.9–40.9, body fat by densitometry), ``sex`` = 1 male, 0 female:

   * adults (age > 15 y): %BF = 1.20·BMI + 0.23·age − 10.8·sex − 5.4 (R² 0.79, SEE 4.1 %BF);
   * children (age ≤ 15 y): %BF = 1.51·BMI − 0.70·age − 3.6·sex + 1.4 (R² 0.38, SEE 4.4 %BF);

   plus the equation's own residual scatter, SEE·z with z ~ N(0, 1) drawn per subject from its own
   stream (``SeedSequence([seed, STREAM, len(key), *key])``), then clipped to physiology
   (:data:`FAT_FRACTION_LIMITS`);
2. **density** from the fat fraction by a two-compartment equation: Siri (1961),
   %BF = 495/D − 450 (fat 0.900 g/cm³, fat-free mass 1.100 g/cm³), or Brozek et al. (1963),
   %BF = 457/D − 414.2;
3. **mass** = volume × density, and BMI = mass / stature².

The circularity (BMI needs the mass, which needs the density, which needs the BMI) is solved by
fixed-point iteration, m ← V·D(f(m/H²)). The map is a contraction: with Siri,
d ln D / d%BF = −1/(%BF + 450) and d%BF/dBMI = 1.2 (1.51 for children), so one step shrinks an
error in mass by the factor BMI · 1.2/(%BF + 450) ≈ 0.06 at BMI 25 and ≈ 0.12 at BMI 50 (0 where
the fat fraction is clipped). :data:`FIXED_POINT_ITERATIONS` steps from 1,000 kg/m³ therefore
reach machine precision; the count is fixed (not "until converged") so that every subject's
result depends on that subject alone, whatever the batch it is computed in.

``model = "constant"`` keeps a single density for everyone (anny's 980 kg/m³ by default) and adds
no columns, so its tables are the tables written before composition models existed.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Literal

import numpy as np

from wbsa.bodies.settings import DEFAULT_DENSITY_KG_M3 as ANNY_DENSITY_KG_M3
from wbsa.errors import WbsaError
from wbsa.typing import DensityModel
from wbsa.settings_io import check_types

#: Columns a composition model adds to a population table (absent with ``constant``): the fat
#: fraction, the density, and the subject's standard-normal residual deviate (drawn from its stream,
#: or fitted by the survey matcher), which with its BMI, age and sex gives the fat fraction.
COMPOSITION_COLUMNS = ("fat_fraction", "density_kg_m3", "fat_residual_z")

#: Deurenberg et al. 1991: ``(BMI, age, sex, intercept)`` coefficients of %BF and the SEE (%BF).
DEURENBERG_ADULT = (1.20, 0.23, -10.8, -5.4)
DEURENBERG_ADULT_SEE = 4.1
DEURENBERG_CHILD = (1.51, -0.70, -3.6, 1.4)
DEURENBERG_CHILD_SEE = 4.4
#: Deurenberg's child equation is for age ≤ 15 y, the adult one above.
CHILD_MAX_AGE_YEARS = 15.0
#: Two-compartment equations %BF = a/D − b (D in g/cm³): ``(a, b)``.
TWO_COMPARTMENT = {"siri": (495.0, 450.0), "brozek": (457.0, 414.2)}
#: Fat-fraction limits ``(low, high)``. Low: essential fat, about 3 % of body mass in men and 10 %
#: in women (American Council on Exercise ranges 2–5 % and 10–13 %); girls and boys up to 15 y take
#: the men's bound (the women's essential fat is sex-specific fat of adult women). High: 60 %,
#: where Deurenberg's linear equation, fitted up to BMI 40.9, is an extrapolation (at BMI 50 a
#: 40-year-old woman would get 64 %); 60 % fat is a Siri density of 0.971 g/cm³.
FAT_FRACTION_LIMITS = {"male": (0.03, 0.60), "female": (0.10, 0.60), "child": (0.03, 0.60)}
#: Fixed-point steps (see the module docstring; the contraction factor is below 0.15 up to BMI 60).
FIXED_POINT_ITERATIONS = 40
#: Tag of the per-subject residual streams (so they never coincide with the phenotype streams).
STREAM = 0xFA7


@dataclass(frozen=True)
class CompositionSettings:
    """How body density is assigned.

    Attributes
    ----------
    model : {'constant', 'deurenberg-siri', 'deurenberg-brozek'}
        ``constant``: one density for everyone (``density_kg_m3``); the others: Deurenberg's fat
        fraction with its residual scatter, turned into a density by Siri's or Brozek's equation.
    density_kg_m3 : float
        The constant model's density (anny's 980 kg/m³ by default); unused by the other models.
    seed : int
        Root of the per-subject residual streams (the population's seed).
    residual_scale : float
        Multiplies the published residual SD (1 = as published, 0 = every subject exactly on
        the equation).
    """

    model: DensityModel = "constant"
    density_kg_m3: float = ANNY_DENSITY_KG_M3
    seed: int = 0
    residual_scale: float = 1.0

    def __post_init__(self) -> None:
        check_types(self)
        if not (np.isfinite(self.density_kg_m3) and self.density_kg_m3 > 0):
            raise WbsaError(f"density {self.density_kg_m3} kg/m³ must be positive (human tissue is ~950–1100)")
        if not (np.isfinite(self.residual_scale) and self.residual_scale >= 0):
            raise WbsaError(f"residual_scale = {self.residual_scale} must be 0 or more (1 = the published scatter)")

    @property
    def constant(self) -> bool:
        """True for the constant-density model (mass = volume × ``density_kg_m3``, no extra columns)."""
        return self.model == "constant"


def predicted_fat_percent(bmi: np.ndarray, age_years: np.ndarray, male: np.ndarray) -> np.ndarray:
    """Deurenberg 1991 body fat (%) without residual, ``(n,) float64``.

    Parameters
    ----------
    bmi, age_years : (n,) float64
        kg/m² and years; the child equation applies up to :data:`CHILD_MAX_AGE_YEARS`.
    male : (n,) bool
    """
    bmi, age = np.asarray(bmi, dtype=np.float64), np.asarray(age_years, dtype=np.float64)
    sex = np.asarray(male, dtype=np.float64)
    child = age <= CHILD_MAX_AGE_YEARS
    a = np.where(child[None, :], np.array(DEURENBERG_CHILD)[:, None], np.array(DEURENBERG_ADULT)[:, None])
    return a[0] * bmi + a[1] * age + a[2] * sex + a[3]


def residual_sd_percent(age_years: np.ndarray) -> np.ndarray:
    """Deurenberg's standard error of estimate (%BF) for each age, ``(n,) float64``."""
    child = np.asarray(age_years, dtype=np.float64) <= CHILD_MAX_AGE_YEARS
    return np.where(child, DEURENBERG_CHILD_SEE, DEURENBERG_ADULT_SEE)


def fat_fraction_limits(age_years: np.ndarray, male: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Physiological ``(low, high)`` fat fractions, each ``(n,) float64`` (:data:`FAT_FRACTION_LIMITS`)."""
    child = np.asarray(age_years, dtype=np.float64) <= CHILD_MAX_AGE_YEARS
    male = np.asarray(male, dtype=bool)
    low = np.where(child, FAT_FRACTION_LIMITS["child"][0],
                   np.where(male, FAT_FRACTION_LIMITS["male"][0], FAT_FRACTION_LIMITS["female"][0]))
    high = np.where(child, FAT_FRACTION_LIMITS["child"][1],
                    np.where(male, FAT_FRACTION_LIMITS["male"][1], FAT_FRACTION_LIMITS["female"][1]))
    return low, high


def fat_fraction(bmi: np.ndarray, age_years: np.ndarray, male: np.ndarray, z: np.ndarray,
                 residual_scale: float = 1.0) -> np.ndarray:
    """Fat fraction (0–1) of each subject: Deurenberg's prediction + SEE·z, clipped; ``(n,) float64``.

    Parameters
    ----------
    z : (n,) float64
        The subject's standard-normal residual deviate (:func:`residual_z`).
    """
    percent = predicted_fat_percent(bmi, age_years, male) + residual_scale * residual_sd_percent(age_years) * z
    low, high = fat_fraction_limits(age_years, male)
    return np.clip(percent / 100.0, low, high)


def density_from_fat(fat: np.ndarray, equation: Literal["siri", "brozek"] = "siri") -> np.ndarray:
    """Body density (kg/m³) of fat fractions ``(n,)`` by a two-compartment equation, ``(n,) float64``."""
    a, b = TWO_COMPARTMENT[equation]
    return 1000.0 * a / (100.0 * np.asarray(fat, dtype=np.float64) + b)


def fat_from_density(density_kg_m3: np.ndarray, equation: Literal["siri", "brozek"] = "siri") -> np.ndarray:
    """Fat fraction of body densities (kg/m³) by a two-compartment equation (inverse of :func:`density_from_fat`)."""
    a, b = TWO_COMPARTMENT[equation]
    return (a / (np.asarray(density_kg_m3, dtype=np.float64) / 1000.0) - b) / 100.0


def residual_z(seed: int, keys: np.ndarray) -> np.ndarray:
    """Standard-normal residual deviate of each subject, ``(n,) float64``.

    Parameters
    ----------
    seed
        The population's seed.
    keys : (n, k) int
        What identifies a subject: ``subject_id`` (random and table populations) or
        ``(survey_id, variation)`` (survey population), so a subject's deviate does not depend on
        who else is in the population.
    """
    keys = np.asarray(keys, dtype=np.int64).reshape(len(keys), -1)
    # the key's length is part of the entropy: SeedSequence pads with zeros, so (3, 0) would be (3,)
    return np.array([np.random.default_rng(np.random.SeedSequence([int(seed), STREAM, len(k), *map(int, k)]))
                     .standard_normal() for k in keys], dtype=np.float64)


def equation_of(model: DensityModel) -> Literal["siri", "brozek"]:
    """The two-compartment equation of a (non-constant) density model."""
    if model == "constant":
        raise WbsaError("the constant density model has no two-compartment equation")
    return "brozek" if model.endswith("brozek") else "siri"


def density_at_bmi(settings: CompositionSettings, bmi: np.ndarray, age_years: np.ndarray, male: np.ndarray,
                   z: np.ndarray) -> np.ndarray:
    """Density (kg/m³) of subjects whose BMI is known, ``(n,) float64`` (the constant model: its density)."""
    if settings.constant:
        return np.full(len(np.atleast_1d(bmi)), settings.density_kg_m3)
    return density_from_fat(fat_fraction(bmi, age_years, male, z, settings.residual_scale),
                            equation_of(settings.model))


@dataclass(frozen=True)
class Composition:
    """Mass and composition of a batch of bodies.

    Attributes
    ----------
    mass_kg, bmi, fat_fraction, density_kg_m3 : (n,) float64
        ``density_kg_m3`` is exactly the density of ``fat_fraction`` and ``mass_kg`` exactly
        volume × density; ``fat_fraction`` is NaN for the constant model (no composition).
    """

    mass_kg: np.ndarray
    bmi: np.ndarray
    fat_fraction: np.ndarray
    density_kg_m3: np.ndarray


def solve_composition(settings: CompositionSettings, volume_m3: np.ndarray, stature_m: np.ndarray,
                      age_years: np.ndarray, male: np.ndarray, z: np.ndarray) -> Composition:
    """Mass, BMI, fat fraction and density of bodies of known volume and stature (fixed point).

    Parameters
    ----------
    volume_m3, stature_m, age_years : (n,) float64
    male : (n,) bool
    z : (n,) float64
        Residual deviates (:func:`residual_z`); ignored by the constant model.
    """
    volume = np.asarray(volume_m3, dtype=np.float64)
    h2 = np.asarray(stature_m, dtype=np.float64) ** 2
    if settings.constant:
        density = np.full(len(volume), settings.density_kg_m3)
        mass = volume * density
        return Composition(mass, mass / h2, np.full(len(volume), np.nan), density)
    equation = equation_of(settings.model)
    density = np.full(len(volume), 1000.0)
    fat = np.full(len(volume), np.nan)
    for _ in range(FIXED_POINT_ITERATIONS):
        fat = fat_fraction(volume * density / h2, age_years, male, z, settings.residual_scale)
        density = density_from_fat(fat, equation)
    mass = volume * density
    return Composition(mass, mass / h2, fat, density)
