"""The segmentation's settings: how the subject is told apart from the room (:class:`SegmentSettings`)."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from wbsa.errors import check_field
from wbsa.estimation.limits import DEPTH_RANGE_M
from wbsa.typing import PICK_RULES, PickRule
from wbsa.settings_io import check_types


@dataclass(frozen=True)
class SegmentSettings:
    """How the subject is told apart from the room.

    Attributes
    ----------
    min_depth_m, max_depth_m : float
        Returns outside this z-range are background (default :data:`wbsa.estimation.limits.DEPTH_RANGE_M`).
    voxel_m : float
        Voxel size of the thinned cloud used for planes and clusters.
    max_planes : int
        Planes tried as room surfaces.
    min_plane_fraction : float
        A room surface holds at least this fraction of the thinned returns.
    behind_fraction : float
        A plane is a room surface if at most this fraction of the other returns lies behind it ...
        It must also run out of the image (reach its frame's border, :mod:`wbsa.estimation.subject.frame`): a floor
        or a wall does, a body alone in the image (no room), which a plane fits loosely, does not.
    cluster_gap_m : float
        Points closer than this (or three pixel pitches, if more) belong to one object.
    min_person_height_m, max_person_height_m, max_person_width_m : float
        What counts as a person-sized cluster.
    pick : {'nearest', 'largest', 'center'} or (int, int) or None
        Which person to take when there are several (None: refuse and list them); an ``(x, y)`` pixel is
        always used: the person under it or within 5 pixels, else refused
        (:func:`~wbsa.estimation.subject.pick.choose`).
    seed : int
        Seed of the RANSAC plane search (same seed, same mask).
    """

    min_depth_m: float = DEPTH_RANGE_M[0]
    max_depth_m: float = DEPTH_RANGE_M[1]
    voxel_m: float = 0.03
    max_planes: int = 5
    min_plane_fraction: float = 0.04
    behind_fraction: float = 0.01
    cluster_gap_m: float = 0.07
    min_person_height_m: float = 0.45
    max_person_height_m: float = 2.6
    max_person_width_m: float = 2.6
    pick: PickRule | tuple[int, int] | None = None
    seed: int = 0

    def __post_init__(self) -> None:
        check_types(self)
        check_field(0 <= self.min_depth_m < self.max_depth_m, "min_depth_m",
                    f"must be 0 or more and below max_depth_m (the depth range {self.min_depth_m}–"
                    f"{self.max_depth_m} m is empty)")
        check_field(self.voxel_m > 0, "voxel_m", f"must be a positive length in metres, got {self.voxel_m}")
        check_field(self.cluster_gap_m > 0, "cluster_gap_m",
                    f"must be a positive length in metres, got {self.cluster_gap_m}")
        check_field(self.pick is None or self.pick in PICK_RULES or is_pixel(self.pick), "pick",
                    f"must be one of {', '.join(PICK_RULES)} or an (x, y) pixel, got {self.pick!r}")


def is_pixel(pick: object) -> bool:
    """Whether a ``pick`` is an (x, y) pixel (two integers), not a rule.

    Parameters
    ----------
    pick : object
    """
    return isinstance(pick, tuple) and len(pick) == 2 and all(isinstance(v, (int, np.integer)) for v in pick)
