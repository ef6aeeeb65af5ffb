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


def write_organised_pcd(path: Path, points_m: np.ndarray) -> Path:
    """Write an organised binary PCD (``WIDTH`` × ``HEIGHT``, x y z float32) of (h, w, 3) points (NaN: no return)."""
    height, width = points_m.shape[:2]
    header = (f"VERSION 0.7\nFIELDS x y z\nSIZE 4 4 4\nTYPE F F F\nCOUNT 1 1 1\nWIDTH {width}\nHEIGHT {height}\n"
              f"VIEWPOINT 0 0 0 1 0 0 0\nPOINTS {width * height}\nDATA binary\n")
    path.write_bytes(header.encode("ascii") + np.ascontiguousarray(points_m, dtype="<f4").tobytes())
    return path


def grid_points(depth_m: np.ndarray, camera) -> np.ndarray:
    """(h, w, 3) float64 points of a depth image seen by ``camera`` (pixel centres; NaN where no return)."""
    v, u = np.mgrid[:depth_m.shape[0], :depth_m.shape[1]].astype(np.float64)
    z = np.where(depth_m > 0, depth_m, np.nan)
    return np.stack([(u - camera.cx) * z / camera.fx, (v - camera.cy) * z / camera.fy, z], axis=-1)
