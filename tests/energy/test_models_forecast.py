"""Tests of energy.models.forecast: CurrentForecast and ChargeForecast (run spread, sample spread, intervals)."""

import numpy as np
import pytest
from interval_samples import interval_log

from energy.models import LinearCurrentModel
from energy.models.forecast import (
    CurrentForecast,
    central_level,
    combine_ground_sds,
    predictive_quantile,
)
from terrawatt_base.errors import InvalidParameterError


def test_run_spread_adds_linearly_and_sample_spread_in_quadrature():
    t = np.arange(0.0, 10.0 + 1e-9, 0.1)
    mean = np.full((t.size, 2), 2.0)
    run = np.column_stack([np.full(t.size, 0.5), np.full(t.size, 0.3)])
    white = np.full((t.size, 2), 1.0)
    q = CurrentForecast(t, mean, run, np.zeros_like(white)).charge()
    assert q.mean_as == pytest.approx([20.0, 20.0])
    assert q.sd_as == pytest.approx([5.0, 3.0])  # 0.5 A for 10 s, all of it shared
    assert q.total_sd_as == pytest.approx(8.0)  # the two sides' run parts add too
    qw = CurrentForecast(t, mean, np.zeros_like(run), white).charge()
    dt = np.gradient(t)
    assert qw.sd_as[0] == pytest.approx(np.sqrt(np.sum(dt**2)))  # ~ 1 A * sqrt(10 s * 0.1 s): averages out
    assert qw.sd_as[0] < 0.15 * 10.0  # the same 1 A shared by the run would give 10 A s
    lo, hi = q.interval(0.8)
    assert (hi - q.total_mean_as) == pytest.approx(predictive_quantile(0.9) * 8.0)
    assert q.quantile(0.5) == pytest.approx(40.0)


def test_forecast_refuses_bad_spreads_and_point_forecasts_have_none():
    t = np.arange(5.0)
    with pytest.raises(InvalidParameterError, match=">= 0"):
        CurrentForecast(t, np.zeros((5, 2)), -np.ones((5, 2)), np.zeros((5, 2)))
    with pytest.raises(InvalidParameterError, match="shape"):
        CurrentForecast(t, np.zeros((4, 2)), np.zeros((5, 2)), np.zeros((5, 2)))
    assert not CurrentForecast.point(t, np.ones((5, 2))).has_interval
    assert combine_ground_sds([3.0, 4.0]) == pytest.approx(5.0)


def test_models_without_an_interval_give_a_point_forecast():
    logs = [interval_log(s) for s in range(2)]
    lin = LinearCurrentModel().fit(logs)
    fc = lin.predict_distribution(logs[0])
    assert not lin.gives_interval and not fc.has_interval
    np.testing.assert_allclose(fc.mean_a, lin.predict(logs[0]))
    assert lin.training_summary.grounds == {"g": pytest.approx(2 * logs[0].duration_s)}
    assert lin.training_summary.robots == ("husky_a200",)



def test_a_forecast_with_few_degrees_of_freedom_has_heavier_tails_and_is_judged_by_its_own_quantiles():
    t = np.arange(0.0, 10.0, 0.1)
    mean = np.ones((t.size, 2))
    gauss = CurrentForecast(t, mean, np.full((t.size, 2), 0.2), np.zeros((t.size, 2)))
    heavy = CurrentForecast(t, mean, np.full((t.size, 2), 0.2), np.zeros((t.size, 2)), dof=3.0)
    g, h = gauss.charge(), heavy.charge()
    assert g.dof == np.inf and h.dof == 3.0 and h.total_sd_as == g.total_sd_as
    assert h.quantile(0.5) == pytest.approx(g.quantile(0.5))
    assert h.quantile(0.95) - h.total_mean_as == pytest.approx(predictive_quantile(0.95, 3.0) * h.total_sd_as)
    assert h.quantile(0.95) > g.quantile(0.95) and h.interval(0.8)[0] < g.interval(0.8)[0]
    assert predictive_quantile(0.9, 1e9) == pytest.approx(predictive_quantile(0.9), abs=1e-6)
    # drawn from the Student-t itself, its own central intervals hold at their nominal level
    z = np.random.default_rng(0).standard_t(3.0, 20000)
    need = central_level(z, 3.0)
    for level in (0.5, 0.8, 0.95):
        assert np.mean(need <= level) == pytest.approx(level, abs=0.01)
    assert np.mean(central_level(z) <= 0.95) < 0.93  # judged as Gaussian they are too narrow
    assert np.isnan(central_level(np.nan)) and central_level(0.0) == 0.0
    with pytest.raises(InvalidParameterError, match="dof"):
        CurrentForecast(t, mean, np.zeros((t.size, 2)), np.zeros((t.size, 2)), dof=0.0)
