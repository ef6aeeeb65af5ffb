"""The image's frame: its border, moved in past bands without returns along its edges.

A depth camera registered to its colour camera (a Kinect v1 through OpenNI, a TUM or PCL frame) leaves
bands a few tens of pixels wide without returns along the image's edges, and a frame can be blanked
below some row. What lies at the edge of such a band is at the edge of what the camera saw, as much as
what lies on the image's border: a floor running into the band reaches the border; a person whose
lowest returns end at it may be cut off there.

An edge band is the run of rows (columns) from an edge that hold (almost) no returns (under
:data:`BAND_MAX_SHARE` of their pixels), when the rows (columns) just inside it are seen across: within
:data:`BAND_EDGE_PX` of the band, one holds returns in at least :data:`BAND_FULL_SHARE` of its pixels (a
registered Kinect v1 frame's ragged band edge reaches that within 4 rows or columns). A subject alone in
the image (no room) leaves empty rows above and below it, but its own rows are narrow, so they make no
band; nor does the empty space over a wall's top with a head in it, unless the head stands less than
:data:`BAND_EDGE_PX` rows over the wall's top. A band along the left or right edge is at most
:data:`SIDE_BAND_MAX` of the image's width: a column through a standing body near the camera is most of
the image's height.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

#: Rows (columns) holding returns in less than this share of their pixels can be part of an edge band ...
BAND_MAX_SHARE = 0.005
#: ... which ends where, within this many pixels, a row (column) holds returns in this share of its pixels.
BAND_EDGE_PX = 5
BAND_FULL_SHARE = 0.4
#: Widest band along the left or right edge, as a share of the image's width.
SIDE_BAND_MAX = 0.1
#: Within this many pixels of the frame's edge is on the frame's border.
BORDER_PX = 3


@dataclass(frozen=True)
class Frame:
    """The part of an image that holds returns: rows ``top``–``bottom`` and columns ``left``–``right``
    (inclusive; the whole image when it has no edge bands)."""

    top: int
    bottom: int
    left: int
    right: int

    def at_border(self, rows: np.ndarray, cols: np.ndarray, margin_px: int = BORDER_PX) -> np.ndarray:
        """Pixels within ``margin_px`` of the frame's edge (or beyond it).

        Parameters
        ----------
        rows, cols : (n,) float or int
            The pixels' rows and columns.
        margin_px : int

        Returns
        -------
        (n,) bool
        """
        rows, cols = np.asarray(rows), np.asarray(cols)
        return ((rows < self.top + margin_px) | (rows > self.bottom - margin_px)
                | (cols < self.left + margin_px) | (cols > self.right - margin_px))

    def at_top(self, rows: np.ndarray, margin_px: int = BORDER_PX) -> np.ndarray:
        """Rows within ``margin_px`` of the frame's top edge (or above it).

        Parameters
        ----------
        rows : (n,) float or int
        margin_px : int

        Returns
        -------
        (n,) bool
        """
        return np.asarray(rows) < self.top + margin_px

    def at_bottom(self, rows: np.ndarray, margin_px: int = BORDER_PX) -> np.ndarray:
        """Rows within ``margin_px`` of the frame's bottom edge (or below it).

        Parameters
        ----------
        rows : (n,) float or int
        margin_px : int

        Returns
        -------
        (n,) bool
        """
        return np.asarray(rows) > self.bottom - margin_px


def _band(share: np.ndarray, max_px: int) -> int:
    """Width of the band at the start of ``share`` (the share of returns of each row or column from an edge)."""
    n = 0
    while n < min(len(share), max_px) and share[n] < BAND_MAX_SHARE:
        n += 1
    if n == 0 or n >= len(share) or not np.any(share[n:n + BAND_EDGE_PX] >= BAND_FULL_SHARE):
        return 0
    return n


def image_frame(returns: np.ndarray) -> Frame:
    """The frame of an image (see the module doc).

    Parameters
    ----------
    returns : (h, w) bool
        Pixels with a return.

    Returns
    -------
    Frame
    """
    h, w = returns.shape
    rows, cols = returns.mean(axis=1), returns.mean(axis=0)
    side = int(SIDE_BAND_MAX * w)
    return Frame(top=_band(rows, h), bottom=h - 1 - _band(rows[::-1], h),
                 left=_band(cols, side), right=w - 1 - _band(cols[::-1], side))
