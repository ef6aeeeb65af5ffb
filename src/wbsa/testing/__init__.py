"""The estimator's held-out benchmark: test captures of virtual people in rooms (:mod:`.testset`).

Used by ``benchmarks/bench_estimate.py`` and the tests; never by training (its seeds are the benchmark's).
"""
