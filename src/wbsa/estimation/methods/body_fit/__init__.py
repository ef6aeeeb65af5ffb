"""Whole-body fit to one depth view (``method="body-fit"``): fit anny's shape, posture and placement to the
subject's points and silhouette, and measure the fitted body as the population is measured.

Entry point: :func:`fit_body`; result: :class:`BodyFit`; settings: :class:`BodyFitSettings`.
"""

from wbsa.estimation.methods.body_fit.fit import fit_body
from wbsa.estimation.methods.body_fit.result import BodyFit
from wbsa.estimation.methods.body_fit.settings import BodyFitSettings

__all__ = ["BodyFit", "BodyFitSettings", "fit_body"]
