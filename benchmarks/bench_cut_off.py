"""People cut off by the frame above the floor, with their stature stated: does the answer account for the legs?

Held-out captures (seed 1000, the project's renderer), in a room and alone, each cut by blanking the image's
rows from the height of a cut drawn between mid-shin and mid-thigh (15–40 % of the stature) down; each
is estimated with its true stature stated and, beside it, the same capture uncut with nothing stated.
Prints MAPE, bias, the interval's coverage and its width for both, per scene::

    python benchmarks/bench_cut_off.py --subjects 24
"""

from __future__ import annotations

import argparse

import numpy as np
import pandas as pd

#: Heights of the cut, as shares of the stature: mid-shin to mid-thigh.
CUT_SHARES = (0.15, 0.40)


def cut_frame(depth_m: np.ndarray, truth: np.ndarray, surface_height_m: np.ndarray, cut_m: float) -> np.ndarray:
    """``depth_m`` with every row from the highest subject pixel that sees its body below ``cut_m`` down blanked.

    Parameters
    ----------
    depth_m : (h, w) float64
    truth : (h, w) bool
        The subject's pixels.
    surface_height_m : (h, w) float64
        Height over the floor of the surface each pixel sees.
    cut_m : float
    """
    low = truth & (surface_height_m < cut_m)
    out = np.array(depth_m, dtype=np.float64)
    if low.any():
        out[np.flatnonzero(low.any(axis=1))[0]:] = 0.0
    return out


def rows(n_subjects: int, seed: int, scene: str) -> list[dict]:
    """One row per capture: the uncut and the cut estimate against the truth."""
    import wbsa
    from wbsa.bodies.body_model import BodyModel
    from wbsa.errors import WbsaError
    from wbsa.estimation import SegmentSettings
    from wbsa.testing.testset import RoomTestSettings, held_out_population, room_test_captures

    pop = held_out_population(n_subjects, 0.4, seed)
    others = pop.iloc[np.roll(np.arange(len(pop)), 1)].reset_index(drop=True)
    settings = RoomTestSettings(seed=seed, scene=scene)
    out = []
    for tc in room_test_captures(pop, others, 0, settings, BodyModel()):
        truth_row = pop.iloc[tc.index]
        rng = np.random.default_rng(np.random.SeedSequence([seed, tc.index, 77]))
        share = float(rng.uniform(*CUT_SHARES))
        stature = float(truth_row["stature_m"])
        cut = cut_frame(tc.depth_m, tc.truth, tc.room.surface_height_m(tc.frame.triangle_id), share * stature)
        row = dict(image=tc.index, scene=scene, camera=tc.capture.camera.name, cut_share=share,
                   wbsa_m2=float(truth_row["wbsa_m2"]), stature_m=stature)
        seg = SegmentSettings(pick=settings.pick)
        for name, depth, stated in (("uncut", tc.depth_m, None), ("cut", cut, stature)):
            try:
                est = wbsa.estimate(depth, tc.capture.camera.name, segment=seg, stature_m=stated, clothing_m=0.0)
            except WbsaError as exc:
                row[f"{name}_error"] = str(exc)
                continue
            row.update({f"{name}_wbsa_m2": est.wbsa_m2, f"{name}_lo_m2": est.wbsa_lo_m2,
                        f"{name}_hi_m2": est.wbsa_hi_m2, f"{name}_flags": ",".join(est.flags)})
        out.append(row)
    return out


def summary(df: pd.DataFrame) -> pd.DataFrame:
    """MAPE, bias, coverage and mean interval width (% of the estimate) of the uncut and cut estimates."""
    lines = []
    for scene, part in [("all", df), *df.groupby("scene")]:
        for name in ("uncut", "cut"):
            ok = part.dropna(subset=[f"{name}_wbsa_m2"])
            err = 100 * (ok[f"{name}_wbsa_m2"] / ok["wbsa_m2"] - 1)
            covered = (ok[f"{name}_lo_m2"] <= ok["wbsa_m2"]) & (ok["wbsa_m2"] <= ok[f"{name}_hi_m2"])
            width = 100 * (ok[f"{name}_hi_m2"] - ok[f"{name}_lo_m2"]) / ok[f"{name}_wbsa_m2"]
            lines.append(dict(scene=scene, frame=name, n=len(ok), refused=len(part) - len(ok),
                              mape_pct=err.abs().mean(), bias_pct=err.mean(), coverage=covered.mean(),
                              width_pct=width.mean()))
    return pd.DataFrame(lines)


def calibration(df: pd.DataFrame) -> tuple[float, float]:
    """(mean, standard deviation) of the cut estimates' log error per unit of unseen area share, fitted through 0
    (:data:`wbsa.estimation.subject.unseen.CUT_LOG_ERROR_PER_SHARE`). Run it on a model without that correction
    (both 0) and a seed that is not held out."""
    from wbsa.bodies.area_profile import area_below_share

    ok = df.dropna(subset=["cut_wbsa_m2"])
    u = area_below_share(ok["cut_share"].to_numpy())[0]
    e = np.log(ok["cut_wbsa_m2"].to_numpy() / ok["wbsa_m2"].to_numpy())
    mean = float(np.sum(e * u) / np.sum(u * u))
    sd = float(np.sqrt(np.sum((e - mean * u) ** 2) / np.sum(u * u)))
    return mean, sd


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--subjects", type=int, default=24, help="held-out subjects per scene (default 24)")
    ap.add_argument("--seed", type=int, default=1000)
    ap.add_argument("--out", default=None, help="write the per-capture rows here (.csv)")
    ap.add_argument("--rows-from", default=None, metavar="CSV", help="read the rows of an earlier --out instead")
    ap.add_argument("--calibrate", action="store_true",
                    help="also print CUT_LOG_ERROR_PER_SHARE fitted on these captures (a seed not held out)")
    args = ap.parse_args()
    if args.rows_from:
        df = pd.read_csv(args.rows_from)
    else:
        df = pd.DataFrame([r for scene in ("room", "alone") for r in rows(args.subjects, args.seed, scene)])
    if args.out:
        df.to_csv(args.out, index=False)
    seed = "" if args.rows_from else f", seed {args.seed}"
    print(f"{len(df)} captures{seed}, cut at {CUT_SHARES[0]:.0%}–{CUT_SHARES[1]:.0%} of the stature, "
          "the true stature stated on the cut frames")
    print(summary(df).to_string(index=False, float_format=lambda v: f"{v:.3f}"))
    if args.calibrate:
        mean, sd = calibration(df)
        print(f"CUT_LOG_ERROR_PER_SHARE = ({mean:.3f}, {sd:.3f})")


if __name__ == "__main__":
    main()
