"""The classical body surface area (BSA) formulae, as published.

Every formula takes stature ``H`` in centimetres and mass ``W`` in kilograms and gives BSA in m².
The functions here are the bare expressions: vectorised over numpy arrays, no unit or range
checks (those live in :mod:`wbsa.formulae.validate`; the checked entry points are in
:mod:`wbsa.formulae.compute`).
"""

from __future__ import annotations

from dataclasses import dataclass
from types import MappingProxyType
from typing import Callable, Mapping

import numpy as np

from wbsa.errors import WbsaError

#: Signature of :attr:`Formula.function`: ``(height_cm, weight_kg, female) -> bsa_m2``.
BsaFunction = Callable[[np.ndarray, np.ndarray, "np.ndarray | None"], np.ndarray]


@dataclass(frozen=True)
class Formula:
    """One published BSA formula.

    Attributes
    ----------
    key : str
        Short identifier (``"dubois"``), used in column names ``bsa_<key>_m2``.
    name : str
        Authors as usually cited (``"Du Bois & Du Bois"``).
    citation : str
        Full reference.
    expression : str
        The formula as text, W in kg, H in cm, result in m².
    function : callable
        ``function(height_cm, weight_kg, female=None) -> ndarray``: the bare expression on float
        arrays of one broadcast shape. ``female`` is a bool array (True = female) of the same shape;
        only sex-specific formulae use it and they raise :class:`WbsaError` when it is ``None``.
    year : int
        Publication year.
    sex_specific : bool
        True when the formula has separate coefficients for men and women.
    """

    key: str
    name: str
    citation: str
    expression: str
    function: BsaFunction
    year: int
    sex_specific: bool = False


def _power_law(c: float, w_exp: float, h_exp: float) -> BsaFunction:
    """``c · W^w_exp · H^h_exp`` as a :data:`BsaFunction` (ignores ``female``)."""

    def function(height_cm: np.ndarray, weight_kg: np.ndarray, female: np.ndarray | None = None) -> np.ndarray:
        return c * np.power(weight_kg, w_exp) * np.power(height_cm, h_exp)

    return function


def _mosteller(height_cm: np.ndarray, weight_kg: np.ndarray, female: np.ndarray | None = None) -> np.ndarray:
    return np.sqrt(height_cm * weight_kg / 3600.0)


def _boyd(height_cm: np.ndarray, weight_kg: np.ndarray, female: np.ndarray | None = None) -> np.ndarray:
    weight_g = 1000.0 * np.asarray(weight_kg, dtype=np.float64)  # Boyd's formula takes grams
    return 0.0003207 * np.power(height_cm, 0.3) * np.power(weight_g, 0.7285 - 0.0188 * np.log10(weight_g))


def _livingston_lee(height_cm: np.ndarray, weight_kg: np.ndarray, female: np.ndarray | None = None) -> np.ndarray:
    return 0.1173 * np.power(weight_kg, 0.6466) * np.ones_like(np.asarray(height_cm, dtype=np.float64))


_schlich_male = _power_law(0.000579479, 0.38, 1.24)
_schlich_female = _power_law(0.000975482, 0.46, 1.08)


def _schlich(height_cm: np.ndarray, weight_kg: np.ndarray, female: np.ndarray | None = None) -> np.ndarray:
    if female is None:
        raise WbsaError("the Schlich formula differs by sex; give the sex, male or female")
    return np.where(female, _schlich_female(height_cm, weight_kg), _schlich_male(height_cm, weight_kg))


_ALL = (
    Formula(
        "dubois", "Du Bois & Du Bois",
        "Du Bois D, Du Bois EF. A formula to estimate the approximate surface area if height and weight "
        "be known. Arch Intern Med. 1916;17(6):863-871.",
        "0.007184 · W^0.425 · H^0.725", _power_law(0.007184, 0.425, 0.725), 1916,
    ),
    Formula(
        "mosteller", "Mosteller",
        "Mosteller RD. Simplified calculation of body-surface area. N Engl J Med. 1987;317(17):1098.",
        "√(H · W / 3600)", _mosteller, 1987,
    ),
    Formula(
        "haycock", "Haycock",
        "Haycock GB, Schwartz GJ, Wisotsky DH. Geometric method for measuring body surface area: a "
        "height-weight formula validated in infants, children, and adults. J Pediatr. 1978;93(1):62-66.",
        "0.024265 · W^0.5378 · H^0.3964", _power_law(0.024265, 0.5378, 0.3964), 1978,
    ),
    Formula(
        "gehan_george", "Gehan & George",
        "Gehan EA, George SL. Estimation of human body surface area from height and weight. "
        "Cancer Chemother Rep. 1970;54(4):225-235.",
        "0.0235 · W^0.51456 · H^0.42246", _power_law(0.0235, 0.51456, 0.42246), 1970,
    ),
    Formula(
        "boyd", "Boyd",
        "Boyd E. The Growth of the Surface Area of the Human Body. Minneapolis: University of "
        "Minnesota Press; 1935.",
        "0.0003207 · H^0.3 · (1000·W)^(0.7285 − 0.0188 · log10(1000·W))", _boyd, 1935,
    ),
    Formula(
        "fujimoto", "Fujimoto",
        "Fujimoto S, Watanabe T, Sakamoto A, Yukawa K, Morimoto K. Studies on the physical surface area "
        "of Japanese. 18. Calculation formulas in three stages over all ages. Nihon Eiseigaku Zasshi. "
        "1968;23(5):443-450.",
        "0.008883 · W^0.444 · H^0.663", _power_law(0.008883, 0.444, 0.663), 1968,
    ),
    Formula(
        "takahira", "Takahira",
        "Takahira H. Metabolism. Report of the Imperial Government Institute for Nutrition, Tokyo. 1925;1:61.",
        "0.007241 · W^0.425 · H^0.725", _power_law(0.007241, 0.425, 0.725), 1925,
    ),
    Formula(
        "shuter_aslani", "Shuter & Aslani",
        "Shuter B, Aslani A. Body surface area: Du Bois and Du Bois revisited. Eur J Appl Physiol. "
        "2000;82(3):250-254.",
        "0.00949 · W^0.441 · H^0.655", _power_law(0.00949, 0.441, 0.655), 2000,
    ),
    Formula(
        "schlich", "Schlich",
        "Schlich E, Schumm M, Schlich M. 3-D-Body-Scan als anthropometrisches Verfahren zur Bestimmung "
        "der spezifischen Körperoberfläche. Ernährungs Umschau. 2010;57(4):178-183.",
        "male 0.000579479 · W^0.38 · H^1.24; female 0.000975482 · W^0.46 · H^1.08", _schlich, 2010,
        sex_specific=True,
    ),
    Formula(
        "yu", "Yu, Lin & Yang",
        "Yu CY, Lin CH, Yang YH. Human body surface area database and estimation formula. Burns. "
        "2010;36(5):616-629.",
        "71.3989 · H^0.7437 · W^0.4040 / 10⁴", _power_law(71.3989e-4, 0.4040, 0.7437), 2010,
    ),
    Formula(
        "livingston_lee", "Livingston & Lee",
        "Livingston EH, Lee S. Body surface area prediction in normal-weight and obese patients. "
        "Am J Physiol Endocrinol Metab. 2001;281(3):E586-E591.",
        "0.1173 · W^0.6466", _livingston_lee, 2001,
    ),
    Formula(
        "tikuisis", "Tikuisis",
        "Tikuisis P, Meunier P, Jubenville CE. Human body surface area: measurement and prediction using "
        "three dimensional body scans. Eur J Appl Physiol. 2001;85(3-4):264-271.",
        "128.1 · H^0.60 · W^0.44 / 10⁴", _power_law(128.1e-4, 0.44, 0.60), 2001,
    ),
)

#: Every formula by key, in a fixed order (read-only).
FORMULAE: Mapping[str, Formula] = MappingProxyType({f.key: f for f in _ALL})

#: The two fixed-sex variants of the Schlich formula, used when no sex is given.
SCHLICH_BY_SEX: Mapping[str, BsaFunction] = MappingProxyType(
    {"schlich_male": _schlich_male, "schlich_female": _schlich_female}
)
