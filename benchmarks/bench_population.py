"""Population throughput: bodies per second, including every anthropometric measure.

Usage: ``python benchmarks/bench_population.py [--n 512]``

Prints the rate of ``measure_population`` (anny forward pass + stature, volume, mass, BMI,
WBSA and eight tape measures) and, in the same run, of the bare anny forward pass (the floor),
with their ratio; the paper's figure (20,000 subjects in 2 h 30 min on a quad-core CPU,
≈ 2.2 subjects/s) is printed for reference. The model build (cached) is excluded.
"""

from __future__ import annotations

import argparse
import os
import time

os.environ.setdefault("WBSA_PROGRESS", "0")


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--n", type=int, default=4000)
    parser.add_argument("--workers", type=int, default=None, help="worker processes (default: all cores)")
    args = parser.parse_args()

    from wbsa.bodies.body_model import BodyModel
    from wbsa.bodies.random_population import RandomPopulationSettings, sample_random_parameters
    from wbsa.bodies.table import measure_population

    model = BodyModel()
    params = sample_random_parameters(RandomPopulationSettings(n=args.n, seed=0))
    measure_population(params.iloc[:64], model=model)  # warm-up

    t0 = time.perf_counter()
    model.rest_bodies(params)
    forward_s = time.perf_counter() - t0

    t0 = time.perf_counter()
    serial = measure_population(params, model=model)
    serial_s = time.perf_counter() - t0

    paper_rate = 20000 / (2.5 * 3600)
    print(f"subjects: {args.n}  cores: {os.cpu_count()}")
    print(f"anny forward only       : {args.n / forward_s:8.1f} bodies/s")
    print(f"population, 1 process   : {args.n / serial_s:8.1f} bodies/s  "
          f"({serial_s / forward_s:.1f}x the forward pass)")
    from wbsa.parallel import default_workers

    t0 = time.perf_counter()
    parallel = measure_population(params, workers=args.workers or default_workers())
    parallel_s = time.perf_counter() - t0
    same = serial.equals(parallel)
    print(f"population, all cores   : {args.n / parallel_s:8.1f} bodies/s  (incl. cluster start-up; "
          f"table identical to 1 process: {same})")
    print(f"paper (quad-core, 2017) : {paper_rate:8.1f} bodies/s  -> speed-up {args.n / parallel_s / paper_rate:.0f}x")


if __name__ == "__main__":
    main()
