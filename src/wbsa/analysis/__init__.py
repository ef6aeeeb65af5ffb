"""analysis stage: per-view regression of WBSA on VBSA, cross-validation, groups, diagnostics, formulae comparison.

Modules (small, one job each):

- ``groups``: :class:`GroupSpec`, :func:`assign_groups` (all, males/females, kids/adults, small/normal/big, obese,
  underweight, tall)
- ``design``: model kinds (linear, quadratic, loglog, wls) and their design matrices
- ``cv``: seeded subject folds, out-of-fold predictions, CV RMSE / MSPE / MAPE
- ``regression``: :func:`fit_view`, :class:`ViewFit` (one view, one group, one model)
- ``data``: VBSA column selectors, predictor names, the population ⋈ scan join
- ``fit_views``: :class:`FitSettings`, :func:`fit_all`, :func:`fit_views` (every view × group × model)
- ``residuals``: residual and QQ tables
- ``model_file``: :class:`WbsaModel` (save / load / predict with a prediction interval)
- ``correlation``: Spearman matrix at one view (paper Table 2)
- ``formulae_comparison``: classical BSA formulae versus the single-view models
- ``claim``: the paper's central claim per group: one view vs every formula and a refitted H/W law (paired bootstrap)
- ``summary``: model kinds side by side (paper section 4.2)
- ``outputs``: :func:`run_fit` reads the tables and writes every output file
- ``command``: the ``wbsa fit`` subcommand
- ``realism``: how varied a population is (log H/W law, Du Bois ratios, composition by sex and BMI class)
- ``calibration_refs``: the published real-body figures (with citations) that ``realism`` is set beside

Names are imported lazily so that ``wbsa --help`` stays fast.
"""

from __future__ import annotations

from wbsa.lazy import lazy_exports

_EXPORTS = {
    "FitSettings": "wbsa.analysis.settings",
    "FitOutput": "wbsa.analysis.fit_views",
    "fit_all": "wbsa.analysis.fit_views",
    "fit_views": "wbsa.analysis.fit_views",
    "fit_view": "wbsa.analysis.regression",
    "ViewFit": "wbsa.analysis.regression",
    "GroupSpec": "wbsa.analysis.groups",
    "assign_groups": "wbsa.analysis.groups",
    "WbsaModel": "wbsa.analysis.model_file",
    "spearman_matrix": "wbsa.analysis.correlation",
    "compare_formulae": "wbsa.analysis.formulae_comparison",
    "evaluate_claim": "wbsa.analysis.claim",
    "ClaimSettings": "wbsa.analysis.claim",
    "run_fit": "wbsa.analysis.outputs",
    "realism_summary": "wbsa.analysis.realism",
}

__all__ = sorted(_EXPORTS)
__getattr__, __dir__ = lazy_exports(__name__, _EXPORTS)
