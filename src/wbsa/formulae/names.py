"""Formula names users already know, resolved to the keys of :data:`~wbsa.formulae.FORMULAE`.

Names are compared case-insensitively after every run of characters other than letters and
digits becomes one ``_`` (``"Gehan-George"``, ``"gehan george"`` and ``"GEHAN_GEORGE"`` are
the same name). Accepted, besides the keys themselves:

- each formula's cited name (``"Du Bois & Du Bois"``, ``"Shuter & Aslani"``, ...);
- the ``method`` values of R admiral's ``compute_bsa()``: ``"Mosteller"``, ``"DuBois-DuBois"``,
  ``"Haycock"``, ``"Gehan-George"``, ``"Boyd"``, ``"Fujimoto"``, ``"Takahira"``;
- the function names of R physiology: ``bsa_dubois_dubois``, ``bsa_mosteller``, ``bsa_haycock``,
  ``bsa_gehan_george``, ``bsa_boyd``, ``bsa_fujimoto``, ``bsa_takahira``, ``bsa_shuter_aslani``,
  ``bsa_schlich``, and ``bsa_adult`` (physiology's adult default, Mosteller);
- ``"DuBois"`` / ``"Du Bois"``.

    >>> formula_key("DuBois-DuBois"), formula_key("bsa_adult"), formula_key("Gehan-George")
    ('dubois', 'mosteller', 'gehan_george')
"""

from __future__ import annotations

import re
from types import MappingProxyType
from typing import Mapping

from wbsa.errors import WbsaError
from wbsa.formulae.catalogue import FORMULAE, SCHLICH_BY_SEX

#: Names that are neither a key nor a cited name, normalised (see :func:`normalise_name`), by key.
_EXTRA: dict[str, tuple[str, ...]] = {
    "dubois": ("du_bois", "dubois_dubois"),  # "DuBois", "Du Bois", admiral "DuBois-DuBois"
    "mosteller": ("bsa_adult",),  # physiology bsa_adult() uses bsa_mosteller(); plain "adult" is no name
}


def normalise_name(name: str) -> str:
    """Lower case, every run of non-alphanumeric characters one ``_``, no ``_`` at the ends.

    >>> normalise_name(" Du Bois & Du Bois ")
    'du_bois_du_bois'
    """
    return re.sub(r"[^a-z0-9]+", "_", name.strip().lower()).strip("_")


def _aliases() -> Mapping[str, str]:
    table: dict[str, str] = {}
    for key, formula in FORMULAE.items():
        for alias in (key, formula.name, *_EXTRA.get(key, ())):
            table[normalise_name(alias)] = key
    for key in SCHLICH_BY_SEX:
        table[key] = key
    return MappingProxyType(table)


#: Every accepted normalised name → key of :data:`FORMULAE` (or ``schlich_male`` / ``schlich_female``).
ALIASES: Mapping[str, str] = _aliases()


def formula_key(name: str) -> str:
    """The key of the formula a user's name stands for.

    Parameters
    ----------
    name : str
        A key (``"dubois"``), a cited name (``"Du Bois & Du Bois"``), an R admiral method
        (``"DuBois-DuBois"``) or an R physiology function name (``"bsa_dubois_dubois"``); any case.
        ``'schlich_male'`` / ``'schlich_female'`` name Schlich at a fixed sex.

    Returns
    -------
    str
        A key of :data:`~wbsa.formulae.FORMULAE` or of :data:`~wbsa.formulae.SCHLICH_BY_SEX`.

    Raises
    ------
    WbsaError
        Unknown name; the message lists the keys.
    """
    if isinstance(name, str):
        normal = normalise_name(name)
        key = ALIASES.get(normal) or (ALIASES.get(normal[len("bsa_"):]) if normal.startswith("bsa_") else None)
        if key is not None:
            return key
    known = ", ".join([*FORMULAE, *SCHLICH_BY_SEX])
    raise WbsaError(
        f"unknown BSA formula {name!r}; choose one of {known} (any case; the R admiral and physiology names, "
        "e.g. 'DuBois-DuBois' or 'bsa_gehan_george', also work)"
    )
