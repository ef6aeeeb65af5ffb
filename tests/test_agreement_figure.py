"""The Bland–Altman figure: the limits of agreement are bias ± 1.96 SD, and the figure draws them."""

import numpy as np
import pytest


def test_limits_of_agreement_are_bias_plus_minus_1_96_sd():
    from wbsa.report.figures.agreement import limits_of_agreement

    d = np.array([-2.0, 0.0, 1.0, 3.0, np.nan])  # the NaN is ignored
    bias, lower, upper = limits_of_agreement(d)
    sd = np.sqrt(((np.array([-2.0, 0.0, 1.0, 3.0]) - 0.5) ** 2).sum() / 3)  # sample SD, ddof 1
    assert bias == pytest.approx(0.5)
    assert (lower, upper) == pytest.approx((0.5 - 1.96 * sd, 0.5 + 1.96 * sd))
    # a normal sample: about 95 % of the differences fall inside
    z = np.random.default_rng(0).normal(1.0, 2.0, 20000)
    bias, lower, upper = limits_of_agreement(z)
    assert np.mean((z > lower) & (z < upper)) == pytest.approx(0.95, abs=0.01)


def test_agreement_figure_draws_the_limits_and_a_box_per_group():
    from wbsa.report.figures.agreement import agreement_figure, limits_of_agreement
    from wbsa.report.figures.style import FigureUnavailable

    rng = np.random.default_rng(1)
    truth = rng.uniform(0.6, 2.4, 60)
    est = truth * (1 + rng.normal(0.0, 0.03, 60))
    groups = np.where(truth < 1.2, "child", "adult")
    fig = agreement_figure(truth, est, est * 0.95, est * 1.05, groups, order=["child", "adult"])
    ax, ax_g = fig.axes[:2]
    diff_pct = 100 * (est - truth) / (0.5 * (est + truth))
    drawn = sorted(line.get_ydata()[0] for line in ax.lines if line.get_linestyle() in ("-", "--")
                   and line.get_color() == "black")
    assert drawn == pytest.approx(sorted(limits_of_agreement(diff_pct)))
    labels = [t.get_text() for t in ax_g.get_xticklabels()]
    assert len(labels) == 2 and labels[0].startswith("child") and "n=" in labels[1]
    with pytest.raises(FigureUnavailable, match="at least two"):
        agreement_figure(truth[:1], est[:1], est[:1], est[:1], groups[:1])
