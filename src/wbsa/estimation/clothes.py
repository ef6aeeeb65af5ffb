"""Clothes, as the user states them: a named layer with its own uncertainty, or an explicit thickness.

The camera sees the outside of the clothes, which encloses more area than the skin; nothing in a depth
image tells cloth from skin, so the clothes are stated, never assumed. :data:`CLOTHES` is the one table of
the layers a user can name (``--clothes NAME``, ``clothes="NAME"``): how far their outside stands off the
skin over the trunk, upper arms, legs and feet, on average, and how uncertain that is. The thicknesses are
starting values, not measured: no published figure of clothing ease (the gap between a garment and the
body) was found in the repository's references.

:func:`stated_clothes` resolves what was stated (an explicit thickness checked by :func:`check_clothing`
against the one table of limits, :data:`wbsa.estimation.limits.LIMITS`); :func:`widened` adds a layer's uncertainty to a
prediction interval: the change of the estimate when the layer is thicker by its uncertainty, taken off
the lower bound and added to the upper one.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

from wbsa.errors import WbsaError
from wbsa.estimation.limits import MAX_CLOTHING_M


@dataclass(frozen=True)
class Clothes:
    """A layer of clothes (m) and its uncertainty (m; 0 for a thickness stated as measured).

    ``name`` is the table's key, or ``""`` for an explicit thickness; ``words`` describes it plainly;
    ``stated`` is False when nothing was stated (then the layer is 0, as the paper's bare subjects).
    """

    name: str
    layer_m: float
    sd_m: float
    words: str
    stated: bool = True

    def to_dict(self) -> dict:
        """JSON-ready ``{"clothes": ..., "clothing_m": ..., "clothing_sd_m": ..., "clothing_stated": ...}``."""
        return {"clothes": self.name or None, "clothing_m": round(self.layer_m, 5),
                "clothing_sd_m": round(self.sd_m, 5), "clothing_stated": self.stated}

    def text(self) -> str:
        """One clause for FHIR and reports: what was stated, or that nothing was."""
        if not self.stated:
            return ("clothes not stated (taken as none or tight-fitting; clothes that were worn read high, "
                    "about 9 % per cm)")
        if self.name:
            return (f"clothes stated: {self.words} ({self.name}, a {100 * self.layer_m:.1f} ± "
                    f"{100 * self.sd_m:.1f} cm layer over the trunk, upper arms, legs and feet)")
        return f"clothes stated as a {100 * self.layer_m:.1f} cm layer over the trunk, upper arms, legs and feet"


#: The layers a user can name, thinnest first (starting values; see the module doc).
CLOTHES: dict[str, Clothes] = {c.name: c for c in (
    Clothes("underwear", 0.000, 0.002, "underwear or tight-fitting clothes"),
    Clothes("thin-gown", 0.004, 0.003, "a thin hospital gown"),
    Clothes("light", 0.008, 0.004, "light clothes: a T-shirt and thin trousers"),
    Clothes("street", 0.015, 0.007, "street clothes: a shirt or jumper and jeans"),
)}

#: What is used when nothing is stated: no layer, no uncertainty, flagged ``clothes_unstated``.
UNSTATED = Clothes("", 0.0, 0.0, "not stated", stated=False)


def clothes_help() -> str:
    """``underwear (0 ± 0.2 cm), thin-gown (...), ...`` for the command line's help."""
    return ", ".join(f"{c.name} ({100 * c.layer_m:g} ± {100 * c.sd_m:g} cm)" for c in CLOTHES.values())


def check_clothing(clothing_m: float) -> None:
    """Raise if a stated layer of clothes is not a thickness of 0 to :data:`MAX_CLOTHING_M` metres.

    Parameters
    ----------
    clothing_m : float
        The stated layer (m).
    """
    from wbsa.estimation.subject.checks import is_real_number

    ok = is_real_number(clothing_m) and math.isfinite(float(clothing_m)) and 0.0 <= float(clothing_m) <= MAX_CLOTHING_M
    if not ok:
        said = (f"the clothes' layer {clothing_m!r} m must be a thickness of 0 to {MAX_CLOTHING_M:g} m (0 for none or "
                "tight-fitting, 0.01 for 1 cm")
        raise WbsaError(f"{said}; on the command line --clothing-cm 1)", code="out_of_range", field="clothing_m",
                        value=clothing_m, page=f"{said})")


def stated_clothes(clothes: str | None = None, clothing_m: float | None = None) -> Clothes:
    """The clothes stated by name (:data:`CLOTHES`) or as an explicit thickness (m), or :data:`UNSTATED`.

    Parameters
    ----------
    clothes : str, optional
        A name of :data:`CLOTHES`.
    clothing_m : float, optional
        Or an explicit layer (m), 0 to :data:`MAX_CLOTHING_M` (:func:`check_clothing`).

    Returns
    -------
    Clothes

    Raises
    ------
    WbsaError
        An unknown name, both a name and a thickness, or a thickness that is not 0 to 0.05 m.
    """
    if clothes is not None and clothing_m is not None:
        raise WbsaError("give the clothes by name (clothes, --clothes) or as a thickness (clothing_m, "
                        "--clothing-cm), not both", field="clothes",
                        page="choose the clothes by name or give their thickness, not both")
    if clothes is not None:
        if not isinstance(clothes, str) or clothes not in CLOTHES:
            raise WbsaError(f"unknown clothes {clothes!r}; give one of {clothes_help()}", field="clothes",
                            value=clothes)
        return CLOTHES[clothes]
    if clothing_m is not None:
        check_clothing(clothing_m)
        return Clothes("", float(clothing_m), 0.0, "an explicit layer")
    return UNSTATED


def widened(lo_m2: float, hi_m2: float, wbsa_m2: float, thicker_wbsa_m2: float) -> tuple[float, float]:
    """A prediction interval widened by a layer's uncertainty.

    Parameters
    ----------
    lo_m2, hi_m2, wbsa_m2 : float
        The interval and the estimate at the stated layer.
    thicker_wbsa_m2 : float
        The estimate with the layer thicker by its uncertainty.

    Returns
    -------
    (float, float)
        ``lo − |Δ|`` and ``hi + |Δ|``, Δ the change of the estimate.
    """
    delta = abs(wbsa_m2 - thicker_wbsa_m2)
    if not math.isfinite(delta):
        return lo_m2, hi_m2
    return lo_m2 - delta, hi_m2 + delta
