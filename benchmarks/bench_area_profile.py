"""The share of the body's area below each height (:data:`wbsa.bodies.area_profile.AREA_BELOW`), measured again.

Prints the table as the constants of :mod:`wbsa.bodies.area_profile` (paste them there to rebuild it) and the
largest difference from the shipped table::

    python benchmarks/bench_area_profile.py --subjects 120
"""

from __future__ import annotations

import argparse

import numpy as np


def main() -> None:
    from wbsa.bodies.area_profile import AREA_BELOW, measure_area_profile
    from wbsa.testing.testset import held_out_population

    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--subjects", type=int, default=120, help="bodies (default 120)")
    ap.add_argument("--seed", type=int, default=2000, help="seed of the bodies and postures (default 2000, never the "
                                                            "held-out 1000)")
    args = ap.parse_args()
    table = measure_area_profile(held_out_population(args.subjects, 0.4, args.seed), args.seed)
    print("AREA_BELOW = np.array([")
    for mean, sd in table:
        print(f"    [{mean:.4f}, {sd:.4f}],")
    print("])")
    print(f"largest difference from the shipped table: {np.abs(table - AREA_BELOW).max():.4f}")


if __name__ == "__main__":
    main()
