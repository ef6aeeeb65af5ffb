"""Rendered and measured training samples: one table row and one descriptor per capture."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import pandas as pd


@dataclass(frozen=True)
class Samples:
    """Rendered and measured samples.

    Attributes
    ----------
    table : pandas.DataFrame
        One row per capture: :data:`TRUTH_COLUMNS`, ``posture, camera, azimuth_deg, elevation_deg,
        distance_m, camera_height_m, fits, holes_fraction, pixel_dropout, noise_scale`` (0 without noise),
        ``ideal_sensor, edge_pixels, edge_share, clothing_m`` (0: bare), in a room ``alone`` (no floor or wall), without a room
        the render's ``vbsa_visible_m2`` and
        ``vbsa_recon_grid_m2``, and the measures (``m_`` + :meth:`SubjectMeasures.features`,
        ``m_touches_border``; ``m_ok`` False where the render had almost no returns or no subject was found).
    descriptors : (n, d) float32
        View descriptor then shape bands of each sample (:class:`SubjectMeasures` ``descriptor``, ``shape``).
    """

    table: pd.DataFrame
    descriptors: np.ndarray

    def __len__(self) -> int:
        return len(self.table)

    @staticmethod
    def concat(parts: list["Samples"]) -> "Samples":
        """One :class:`Samples` from several, in order."""
        return Samples(pd.concat([p.table for p in parts], ignore_index=True),
                       np.concatenate([p.descriptors for p in parts]))
