"""Settings of the report (``[report]`` of a study): which views the single-view figures show."""

from __future__ import annotations

import math
from dataclasses import dataclass

from wbsa.errors import check_field
from wbsa.settings_io import check_types


@dataclass(frozen=True)
class ReportSettings:
    """Which views the report's single-view figures show, and at what resolution.

    Attributes
    ----------
    scatter_view_deg : (float, float)
        View (azimuth, elevation) of the VBSA–WBSA scatter and the residual plots (paper Fig 10, S1, S2: 0, 0).
    nonlinear_view_deg : (float, float)
        View of the non-linearity figure (paper Fig 16: 60, 60).
    snapshot_view_deg : (float, float)
        View whose point cloud the snapshots show (paper Fig 8: 60, 60); the figure shows the scanned view
        nearest to it (the study's own views only).
    snapshot_subject : int or None
        Subject of the snapshots; None (in a study file: the key left out) picks the subject with the
        median WBSA.
    dpi : int
        Resolution of the figures, 30–600.
    """

    scatter_view_deg: tuple[float, float] = (0.0, 0.0)
    nonlinear_view_deg: tuple[float, float] = (60.0, 60.0)
    snapshot_view_deg: tuple[float, float] = (60.0, 60.0)
    snapshot_subject: int | None = None
    dpi: int = 100

    def __post_init__(self) -> None:
        check_types(self)
        for name in ("scatter_view_deg", "nonlinear_view_deg", "snapshot_view_deg"):
            view = getattr(self, name)
            check_field(len(view) == 2 and all(math.isfinite(a) for a in view), name,
                        f"must be (azimuth, elevation) in degrees, got {list(view)}")
        check_field(30 <= self.dpi <= 600, "dpi", f"must be in 30–600, got {self.dpi}")
        check_field(self.snapshot_subject is None or self.snapshot_subject >= 0, "snapshot_subject",
                    f"must be a subject id (0 or more; leave it out for the median subject), got {self.snapshot_subject}")
