"""Real depth frames shipped as test fixtures (tests/fixtures/), read into depth images."""

from __future__ import annotations

from pathlib import Path

import numpy as np

FIXTURES = Path(__file__).resolve().parent.parent / "fixtures"
FIVE_PEOPLE = FIXTURES / "pcl" / "five_people.pcd"

#: The five people of five_people.pcd, left to right, as boxes (x0, y0, x1, y1) in pixels, read off the
#: colour and depth images by eye (tests/fixtures/pcl/README.md), and whether their feet are in the frame.
FIVE_PEOPLE_BOXES = (
    ((20, 65, 155, 476), True),    # green shirt, black trousers; shoes at the frame's bottom band
    ((140, 100, 245, 476), True),  # blue top, jeans, behind the first one's right arm
    ((276, 105, 378, 445), True),  # white T-shirt, shorts, black shoes on the floor
    ((362, 105, 470, 455), True),  # grey shirt, jeans; his left arm touches the white T-shirt's
    ((456, 50, 610, 476), False),  # dark shirt, nearest (2 m); the frame cuts him at the knees
)


def pcd_depth(path: Path = FIVE_PEOPLE) -> np.ndarray:
    """(h, w) float64 depth image (z in metres, 0 = no return) of an organised PCD file."""
    from wbsa.testing.frames import read_pcd_depth

    return read_pcd_depth(path)
