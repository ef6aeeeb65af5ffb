"""Posture throughput and how much posing changes the skin area.

Usage: ``python benchmarks/bench_posture.py [--n 300] [--seed 0]``

Builds a random population of ``n`` subjects in one process and thread, then times (CPU seconds) in
the same run:
the bare anny forward pass (rest vertices), the population table (``measure_population``, A-pose),
and the mixed postures (``add_postures``: draw, settle each body so no limb sinks into it, measure the
posed skin area), and posing alone (``BodyModel.skin_meshes`` with and without posture columns, as
the scan does). Then prints, per posture, the posed/rest skin-area change (mean, SD, range, %) and
how many limbs had to be raised to keep them out of the body. The model build is excluded.
"""

from __future__ import annotations

import argparse
import os
import time

os.environ.setdefault("WBSA_PROGRESS", "0")


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--n", type=int, default=300)
    parser.add_argument("--seed", type=int, default=0)
    args = parser.parse_args()

    import numpy as np

    from wbsa.bodies.body_model import BodyModel
    from wbsa.bodies.posture import ANGLE_COLUMNS, PostureSettings, draw_postures
    from wbsa.bodies.posture_table import add_postures
    from wbsa.bodies.random_population import RandomPopulationSettings, sample_random_parameters
    from wbsa.bodies.table import measure_population

    model = BodyModel()
    params = sample_random_parameters(RandomPopulationSettings(n=args.n, seed=args.seed))
    add_postures(measure_population(params.iloc[:8], model=model), PostureSettings("mixed", args.seed),
                 model=model)  # warm-up (imports, rig)

    from wbsa.parallel import single_threaded_math

    def timed(fn):
        """Result and CPU seconds of ``fn()`` on one thread (the machine may be shared: CPU time, not wall)."""
        with single_threaded_math():
            t0 = time.process_time()
            out = fn()
            return out, time.process_time() - t0

    _, forward_s = timed(lambda: model.rest_bodies(params))
    table, table_s = timed(lambda: measure_population(params, model=model))
    posed, posture_s = timed(lambda: add_postures(table, PostureSettings("mixed", args.seed), model=model))
    _, rest_mesh_s = timed(lambda: model.skin_meshes(table))
    _, posed_mesh_s = timed(lambda: model.skin_meshes(posed))
    n = args.n
    print(f"subjects: {n}  seed: {args.seed}  (one process, one thread; rates in bodies per CPU second)")
    print(f"anny forward only              : {n / forward_s:8.1f} bodies/s")
    print(f"population table (A-pose)      : {n / table_s:8.1f} bodies/s  "
          f"({table_s / forward_s:.1f}x the forward pass)")
    print(f"mixed postures (draw+settle)   : {n / posture_s:8.1f} bodies/s  "
          f"({posture_s / forward_s:.1f}x the forward pass)")
    print(f"population table + postures    : {n / (table_s + posture_s):8.1f} bodies/s  "
          f"({(table_s + posture_s) / table_s:.2f}x the A-pose table's time)")
    print(f"skin meshes, rest (scan)       : {n / rest_mesh_s:8.1f} bodies/s")
    print(f"skin meshes, posed (scan)      : {n / posed_mesh_s:8.1f} bodies/s  "
          f"({posed_mesh_s / rest_mesh_s:.2f}x rest)")

    drawn = draw_postures(posed["subject_id"], PostureSettings("mixed", args.seed))
    settled, drawn = posed[list(ANGLE_COLUMNS)].to_numpy(), drawn[list(ANGLE_COLUMNS)].to_numpy()
    raised = (settled != drawn).any(axis=1)
    change = 100 * (posed["wbsa_posed_m2"] / posed["wbsa_m2"] - 1)
    print("\nposed skin area vs rest (wbsa_posed_m2 / wbsa_m2 - 1, %), and bodies with a limb raised by settling:")
    print(f"{'posture':15s} {'n':>4s} {'mean':>7s} {'SD':>6s} {'min':>7s} {'max':>7s} {'raised':>7s}")
    for name, group in [("all", posed.index), *posed.groupby("posture").groups.items()]:
        c = change[group]
        print(f"{name:15s} {len(c):4d} {c.mean():+7.2f} {c.std():6.2f} {c.min():+7.2f} {c.max():+7.2f} "
              f"{int(raised[np.asarray(group)].sum()):7d}")


if __name__ == "__main__":
    main()
