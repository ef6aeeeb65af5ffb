"""argparse ``type=`` checkers shared by the stage commands (each error becomes one usage line, exit 2)."""

from __future__ import annotations

import argparse
import math
from typing import Callable


def pick(text: str) -> str | tuple[int, int]:
    """An argparse type for ``--pick`` (and the page's pick field): ``nearest``, ``largest``, ``center`` or ``x,y``
    (a pixel of the subject).

    Parameters
    ----------
    text : str

    Returns
    -------
    str or (int, int)
        A :data:`wbsa.typing.PICK_RULES` name or the pixel (x, y).
    """
    from wbsa.typing import PICK_RULES

    if text in PICK_RULES:
        return text
    try:
        x, y = (int(v) for v in text.split(","))
    except ValueError:
        raise argparse.ArgumentTypeError(f"{text!r} is not nearest, largest, center or x,y") from None
    return (x, y)


def number_in(low: float = -math.inf, high: float = math.inf, *, low_open: bool = False, high_open: bool = False,
              what: str = "a number") -> Callable[[str], float]:
    """An argparse type that accepts a float in the interval [low, high] (ends open when asked).

    Examples
    --------
    ``type=number_in(0, 1, what="a fraction")``; ``type=number_in(0, low_open=True, what="a positive number")``.
    """
    if math.isinf(high):
        span = f"{'>' if low_open else '>='} {low:g}"
    else:
        span = f"{'(' if low_open else '['}{low:g}, {high:g}{')' if high_open else ']'}"

    def check(text: str) -> float:
        try:
            value = float(text)
        except ValueError:
            raise argparse.ArgumentTypeError(f"expected {what} {_phrase(span)}, got {text!r}") from None
        above = value > low if low_open else value >= low
        below = value < high if high_open else value <= high
        if not (above and below):
            raise argparse.ArgumentTypeError(f"expected {what} {_phrase(span)}, got {text}")
        return value

    return check


def _phrase(span: str) -> str:
    """``in [0, 1]`` for an interval, ``>= 0`` for a bound."""
    return span if span.startswith(">") else f"in {span}"


def range_of(low: float, high: float, *, unit: str) -> Callable[[str], tuple[float, float]]:
    """An argparse type for ``LOW,HIGH`` with ``low <= LOW <= HIGH <= high`` (e.g. a distance range in m)."""

    def check(text: str) -> tuple[float, float]:
        try:
            lo, hi = (float(v) for v in text.split(","))
        except ValueError:
            raise argparse.ArgumentTypeError(f"expected LOW,HIGH in {unit}, e.g. {low:g},{high:g}; got {text!r}") \
                from None
        if not (low <= lo <= hi <= high):
            raise argparse.ArgumentTypeError(f"expected {low:g} <= LOW <= HIGH <= {high:g} {unit}, got {text}")
        return lo, hi

    return check
