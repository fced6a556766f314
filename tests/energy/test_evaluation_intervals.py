"""Tests of energy.evaluation.intervals: charge records of a forecast, their coverage, the reliability plot."""

import pytest
from interval_samples import fit_two_ground_estimator

from energy.evaluation.intervals import IntervalRecord, charge_record, coverage, plot_reliability
from energy.models.forecast import predictive_quantile


@pytest.fixture(scope="module")
def two_ground_estimator():
    return fit_two_ground_estimator()


def test_coverage_counts_records_inside_each_central_interval():
    z90 = predictive_quantile(0.9)
    recs = [IntervalRecord("g", "x", f"r{i}", true_as=10.0 + z, mean_as=10.0, sd_as=1.0)
            for i, z in enumerate([0.1, -0.5, 1.0, -z90 + 0.01, 3.0])]
    cov = coverage(recs)["g"]
    assert cov["50 %"] == pytest.approx(2 / 5)  # |z| <= 0.674
    assert cov["80 %"] == pytest.approx(4 / 5)
    assert cov["95 %"] == pytest.approx(4 / 5)
    ax = plot_reliability(recs)
    assert len(ax.lines) == 2


def test_reliability_plot_without_axes_makes_a_figure_outside_pyplot():
    import matplotlib
    import matplotlib.pyplot as plt
    from matplotlib.backends.backend_agg import FigureCanvasAgg

    backend, open_before = matplotlib.get_backend(), plt.get_fignums()
    ax = plot_reliability([IntervalRecord("g", "x", "r0", true_as=10.5, mean_as=10.0, sd_as=1.0)])
    assert isinstance(ax.figure.canvas, FigureCanvasAgg) and ax.figure.get_size_inches().tolist() == [4.8, 4.4]
    assert matplotlib.get_backend() == backend and plt.get_fignums() == open_before



def test_charge_record_scores_a_model_forecast(two_ground_estimator):
    est, logs = two_ground_estimator
    rec = charge_record(est, logs[1], group="known", run="r1")
    assert rec.sd_as > 0 and rec.true_as > 0
    assert abs(rec.z) < 5

