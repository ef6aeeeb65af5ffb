"""Classical body surface area (BSA) formulae, vectorised and unit-checked.

Height in centimetres, weight in kilograms, BSA in m²::

    >>> from wbsa.formulae import bsa, bsa_all
    >>> round(bsa("dubois", 170, 70), 4)
    1.8097
    >>> round(float(bsa_all(170, 70, "female")["schlich"]), 4)
    1.7654
    >>> bsa("DuBois-DuBois", 170, 70) == bsa("dubois", 170, 70)  # R admiral / physiology names work
    True

Modules: ``catalogue`` (the published expressions, :data:`FORMULAE`), ``validate`` (unit and
range checks), ``compute`` (:func:`bsa`, :func:`bsa_all`, :func:`bsa_table`), ``command``
(the ``wbsa bsa`` subcommand), ``names`` (:func:`formula_key`: the names users already know,
e.g. those of the R packages admiral and physiology).
"""

from wbsa.formulae.catalogue import FORMULAE, SCHLICH_BY_SEX, Formula
from wbsa.formulae.compute import bsa, bsa_all, bsa_table, parse_sex
from wbsa.formulae.names import formula_key
from wbsa.formulae.validate import HEIGHT_RANGE_CM, WEIGHT_RANGE_KG, validate_inputs

__all__ = [
    "FORMULAE",
    "HEIGHT_RANGE_CM",
    "SCHLICH_BY_SEX",
    "WEIGHT_RANGE_KG",
    "Formula",
    "bsa",
    "bsa_all",
    "bsa_table",
    "formula_key",
    "parse_sex",
    "validate_inputs",
]
