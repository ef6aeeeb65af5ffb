"""Which person a pick chooses among the people of a depth image (:mod:`~wbsa.estimation.subject.people`).

A pick (:func:`choose`) is ``nearest``, ``largest``, ``center`` (the object under the image's centre, else
the person whose middle is nearest to it) or an ``(x, y)`` pixel: the person under the pixel, else the
person with a pixel within :data:`PICK_REACH_PX`, else the person the object under it is seen past (the
wall between the legs); an object under the pixel that is not a person, or no person near, is refused in
one line that lists the people found.
"""

from __future__ import annotations

import numpy as np

from wbsa.errors import WbsaError
from wbsa.estimation.subject.people import Cluster, seen_past_object, why_not_a_person
from wbsa.estimation.subject.settings import is_pixel

#: A pixel pick chooses a person with a pixel this close (pixels) when no object lies under it.
PICK_REACH_PX = 5


def choose(people: list[Cluster], clusters: list[Cluster], pick, image_label: np.ndarray,
           limits: tuple[float, float, float]) -> Cluster:
    """The person a pick chooses (see the module doc), or a one-line :class:`~wbsa.errors.WbsaError`.

    Parameters
    ----------
    people : list of Cluster
        The persons (at least one).
    clusters : list of Cluster
        Every object described (people included).
    pick : None, str or (int, int)
    image_label : (h, w) int
        The object of every pixel (−1: none).
    limits : (float, float, float)
        Least and greatest height, greatest width of a person (m), for the refusal's reason.
    """
    h, w = image_label.shape
    if is_pixel(pick) and not (0 <= pick[0] < w and 0 <= pick[1] < h):  # refused with one person in view too
        where = f"({pick[0]}, {pick[1]}) lies outside the {w} x {h} depth image"
        raise WbsaError(f"pick pixel {where}; give x,y of a pixel on the subject", code="choose_person",
                        field="pick", value=pick,
                        page=f"the point clicked {where}; click on the person in the depth picture")
    if is_pixel(pick):
        return _at_pixel(people, clusters, (int(pick[0]), int(pick[1])), image_label, limits)
    if len(people) == 1:
        return people[0]
    if pick is None:
        ordered = sorted(people, key=lambda c: c.pixel_xy)
        listing = "; ".join(f"{i + 1}: {c.describe()}" for i, c in enumerate(ordered))
        shown = "; ".join(f"{i + 1}: {c.describe(page=True)}" for i, c in enumerate(ordered))
        raise WbsaError(f"{len(people)} people in the depth image ({listing}); "
                        "choose one with pick nearest, largest, center or x,y", code="choose_person", field="pick",
                        page=f"{len(people)} people in the depth image ({shown}): click on the person to measure "
                             "in the depth picture")
    if pick == "nearest":
        return min(people, key=lambda c: c.distance_m)
    if pick == "largest":
        return max(people, key=lambda c: c.n_pixels)
    x, y = (w - 1) / 2, (h - 1) / 2
    # the object under the centre (the operator aims at the subject), else the one whose middle is nearest
    hit = image_label[int(round(y)), int(round(x))]
    for c in people:
        if c.label == hit:
            return c
    return min(people, key=lambda c: (c.pixel_xy[0] - x) ** 2 + (c.pixel_xy[1] - y) ** 2)


def _at_pixel(people: list[Cluster], clusters: list[Cluster], xy: tuple[int, int], image_label: np.ndarray,
              limits: tuple[float, float, float]) -> Cluster:
    """The person a pixel pick ``xy`` chooses (see the module doc)."""
    x, y = xy
    by_label = {c.label: c for c in clusters}
    hit = int(image_label[y, x])
    person = next((c for c in people if c.label == hit), None)
    if person is not None:
        return person
    under = by_label.get(hit)
    if under is not None:
        behind = seen_past_object(under, clusters)
        if behind is not None and behind in people:
            return behind
        why = why_not_a_person(under, *limits) or "it is seen past a nearer object"
        raise WbsaError(f"pick pixel ({x}, {y}) lies on an object that is not a person ({under.describe()}: {why}); "
                        f"{_people_hint(people)}", code="choose_person", field="pick", value=xy,
                        page=f"the point clicked ({x}, {y}) lies on an object that is not a person "
                             f"({under.describe(page=True)}: {why}); {_people_hint(people, page=True)}")
    r = PICK_REACH_PX
    y0, x0 = max(y - r, 0), max(x - r, 0)
    window = image_label[y0:y + r + 1, x0:x + r + 1]
    wy, wx = np.nonzero(window >= 0)
    d2 = (wx + x0 - x) ** 2 + (wy + y0 - y) ** 2
    near = [(int(d2[window[wy, wx] == c.label].min()), c.label, c) for c in people if np.any(window == c.label)]
    if near:
        return min(near, key=lambda t: t[:2])[2]
    raise WbsaError(f"no person at pick pixel ({x}, {y}) or within {PICK_REACH_PX} pixels of it; "
                    f"{_people_hint(people)}", code="choose_person", field="pick", value=xy,
                    page=f"no person at the point clicked ({x}, {y}) or within {PICK_REACH_PX} pixels of it; "
                         f"{_people_hint(people, page=True)}")


def _people_hint(people: list[Cluster], page: bool = False) -> str:
    """``people found: 1.72 m tall at pixel (312, 240), 2.9 m away; ...; pick a pixel on one`` (``page``: in the
    page's words)."""
    found = "people found: " + "; ".join(c.describe(page) for c in sorted(people, key=lambda c: c.pixel_xy))
    return found + (": click on one of them" if page else "; pick a pixel on one")
