"""Draw docs/img/camera_convention.png: the azimuth/elevation convention of wbsa's virtual camera.

Usage::

    python docs/make_camera_figure.py [--out docs/img/camera_convention.png]

Panel (a) looks down on the subject (world +Z towards the reader) and places the paper's azimuths;
panel (b) is the vertical plane through a camera at azimuth θ with the paper's elevations; panel (c)
is what the camera at azimuth 0, elevation 0 sees of the test figure (``body_like`` of ``tests/helpers/shapes.py``),
rendered by the ray caster itself, with the image axes.
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "src"))
sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "tests"))  # helpers.shapes: test meshes

from wbsa.camera import MeshScene, View, paper_views, pose_from_view, preset, render  # noqa: E402
from helpers.shapes import body_like  # noqa: E402
from wbsa.camera.views import PAPER_AZIMUTHS_DEG, PAPER_ELEVATIONS_DEG, view_direction  # noqa: E402


def draw(out: Path) -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    from matplotlib.patches import Arc, Ellipse, FancyArrowPatch, Polygon

    fig, axes = plt.subplots(1, 3, figsize=(15, 5.4), gridspec_kw={"width_ratios": [1, 1, 0.85]})

    # (a) top view: x to the right, y up on the page (world +Y), +Z towards the reader
    ax = axes[0]
    ax.add_patch(Ellipse((0, 0), 0.9, 0.5, color="0.8"))  # shoulders seen from above
    ax.add_patch(Polygon([[-0.08, -0.24], [0.08, -0.24], [0, -0.36]], color="0.55"))  # nose: the subject faces -Y
    ax.text(0.33, 0.0, "left\nside", ha="center", va="center", fontsize=8)
    ax.text(-0.33, 0.0, "right\nside", ha="center", va="center", fontsize=8)
    R = 1.6
    for az in PAPER_AZIMUTHS_DEG:
        d = view_direction(az, 0.0)
        ax.plot([0, R * d[0]], [0, R * d[1]], color="tab:blue", lw=0.6, alpha=0.5)
        ax.plot(R * d[0], R * d[1], "s", color="tab:blue", ms=7)
        ax.text(1.2 * R * d[0], 1.2 * R * d[1], f"{az:g}°", ha="center", va="center", fontsize=9)
    ax.add_patch(Arc((0, 0), 1.3, 1.3, theta1=-90, theta2=-45, color="tab:red", lw=1.5))
    ax.text(0.5, -0.62, "θ", color="tab:red", fontsize=13)
    for (dx, dy, label) in ((0.9, 0, "+X"), (0, 0.9, "+Y")):
        ax.add_patch(FancyArrowPatch((0, 0), (dx, dy), arrowstyle="-|>", mutation_scale=12, color="k"))
        ax.text(dx * 1.1, dy * 1.1 + (0.05 if dy else -0.08), label, fontsize=10)
    ax.text(-1.95, 1.85, "+Z (up) towards you", fontsize=9)
    ax.set_title("(a) azimuth θ about +Z, seen from above\n"
                 "0° = in front (−Y), 90° = subject's left (+X), 180° = behind",
                 fontsize=10)
    ax.set_xlim(-2.1, 2.1)
    ax.set_ylim(-2.2, 2.1)

    # (b) vertical plane through the camera: horizontal axis = distance along the azimuth direction
    ax = axes[1]
    ax.add_patch(Ellipse((0, 0), 0.45, 1.75, color="0.8"))
    for el in PAPER_ELEVATIONS_DEG + (90.0, -90.0):
        e = np.radians(el)
        p = (R * np.cos(e), R * np.sin(e))
        ax.plot([0, p[0]], [0, p[1]], color="tab:blue", lw=0.6, alpha=0.5)
        ax.plot(*p, "s", color="tab:blue", ms=7)
        ax.text(1.17 * p[0] + 0.05, 1.17 * p[1], f"{el:+g}°" if el else "0°", ha="center", va="center", fontsize=9)
    ax.add_patch(Arc((0, 0), 1.2, 1.2, theta1=0, theta2=45, color="tab:red", lw=1.5))
    ax.text(0.63, 0.22, "φ", color="tab:red", fontsize=13)
    ax.annotate("", xy=(R, 0), xytext=(0, 0), arrowprops=dict(arrowstyle="<->", color="tab:green"))
    ax.text(0.8, -0.12, "D (to the bbox centre)", color="tab:green", ha="center", fontsize=9)
    ax.text(0.1, -2.05, "subject's centre = centre of the mesh's bounding box", ha="center", fontsize=9)
    ax.add_patch(FancyArrowPatch((-1.3, -0.3), (-1.3, 0.4), arrowstyle="-|>", mutation_scale=12, color="k"))
    ax.text(-1.25, 0.35, "+Z", fontsize=10)
    ax.set_title("(b) elevation φ in the plane of the camera\n"
                 "+90° = above, looking down; −90° = below, looking up",
                 fontsize=10)
    ax.set_xlim(-2.1, 2.3)
    ax.set_ylim(-2.1, 2.2)

    for ax in axes[:2]:
        ax.set_aspect("equal")
        ax.axis("off")

    # (c) what the front camera sees, rendered by the ray caster
    ax = axes[2]
    k = preset("kinect-v1")
    scene = MeshScene(body_like())
    frame = render(scene, k, pose_from_view(View(0, 0, 2.6), scene.center))
    depth = np.where(frame.depth_m > 0, frame.depth_m, np.nan)
    ax.imshow(depth, cmap="viridis")
    ax.set_facecolor("black")
    ax.annotate("", xy=(140, 30), xytext=(30, 30), arrowprops=dict(arrowstyle="-|>", color="w"))
    ax.annotate("", xy=(30, 140), xytext=(30, 30), arrowprops=dict(arrowstyle="-|>", color="w"))
    ax.text(150, 34, "x (u)", color="w", va="center", fontsize=9)
    ax.text(34, 160, "y (v)", color="w", fontsize=9)
    ax.text(600, 440, "subject's left (+X)\nis on the image right", color="w", ha="right", fontsize=9)
    ax.set_xticks([])
    ax.set_yticks([])
    ax.set_title("(c) camera at θ = 0°, φ = 0°: OpenCV frame\nx right, y down, z forward (depth)", fontsize=10)
    fig.suptitle(f"wbsa virtual camera: the paper's Fig 1 convention ({len(paper_views())} paper views)", fontsize=12)
    fig.tight_layout(rect=(0, 0, 1, 0.93))
    out.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(out, dpi=110)
    plt.close(fig)
    print(f"wrote {out}")


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--out", default=str(Path(__file__).resolve().parent / "img" / "camera_convention.png"))
    draw(Path(parser.parse_args().out))


if __name__ == "__main__":
    main()
