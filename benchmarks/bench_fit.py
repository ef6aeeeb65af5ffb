"""Time `fit_all` on synthetic paper-scale tables (20,000 subjects x 65 views) with the default settings."""
import resource, sys, time
from pathlib import Path
t0 = time.perf_counter()
sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "tests"))  # helpers.synthetic: test-only tables
import statsmodels.api, statsmodels.stats.diagnostic, scipy.stats  # noqa: F401  (import time not counted)
from wbsa.analysis.fit_views import FitSettings, fit_all
from helpers.synthetic import paper_view_angles, synthetic_population, synthetic_scan

n = int(sys.argv[1]) if len(sys.argv) > 1 else 20000
n_views = int(sys.argv[2]) if len(sys.argv) > 2 else 65
pop = synthetic_population(n, seed=0)
scan = synthetic_scan(pop, paper_view_angles()[:n_views], seed=0)
settings = FitSettings()
c0, w0 = time.process_time(), time.perf_counter()
out = fit_all(pop, scan, settings)
cpu, wall = time.process_time() - c0, time.perf_counter() - w0
print(f"{n} subjects x {n_views} views, groups {len(settings.groups)}, models {settings.models}, "
      f"predictor sets {len(settings.predictor_sets)}, k {settings.k}: {out.info['n_fits']} fits "
      f"({out.info['n_skipped']} skipped), wall {wall:.1f} s, cpu {cpu:.1f} s, "
      f"{1e3 * cpu / out.info['n_fits']:.1f} ms cpu per fit (incl. its {settings.k} CV refits)")
print(f"residual rows {len(out.residuals)}, qq rows {len(out.qq)}, "
      f"peak RSS {resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1e6:.2f} GB")
