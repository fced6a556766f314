"""energy.logs.rest: which drive samples stand still."""

from __future__ import annotations

import numpy as np
from log_samples import make_log

from energy.logs.rest import (
    REST_ACCEL_MPS2,
    REST_ALPHA_RADPS2,
    REST_OMEGA_RADPS,
    REST_SPEED_MPS,
    at_rest,
    rest_samples,
)


def test_thresholds():
    assert (REST_SPEED_MPS, REST_OMEGA_RADPS, REST_ACCEL_MPS2, REST_ALPHA_RADPS2) == (0.005, 0.01, 0.05, 0.1)


def test_still_driving_and_pivoting_samples():
    rest = at_rest([0.0, 0.004, -0.004, 0.3, 0.0, 0.005], [0.0, 0.0, -0.009, 0.0, 0.5, 0.0])
    assert rest.dtype == bool
    assert rest.tolist() == [True, True, True, False, False, False]  # the bound itself is not rest


def test_starting_or_stopping_is_not_rest():
    v = np.zeros(4)
    w = np.zeros(4)
    assert at_rest(v, w, [0.0, 0.06, -0.06, 0.0], [0.0, 0.0, 0.0, 0.2]).tolist() == [True, False, False, False]


def test_arguments_broadcast():
    assert at_rest(0.0, [0.0, 1.0]).tolist() == [True, False]
    assert at_rest(0.0, 0.0).shape == ()


def test_rest_samples_of_a_log_use_its_accelerations():
    t = np.arange(6) * 0.1
    v = np.array([0.0, 0.0, 0.0, 0.0, 0.2, 0.4])  # starts at t = 0.3 s
    log = make_log(n=6, time_s=t, v_mps=v, omega_radps=np.zeros(6), current_left_a=np.ones(6),
                   current_right_a=np.ones(6))
    # sample 3 has v = 0 but numpy.gradient gives dv/dt = 1 m/s^2 there
    assert rest_samples(log).tolist() == [True, True, True, False, False, False]


def test_rest_samples_of_a_one_sample_log():
    log = make_log(n=1, m=1, time_s=[0.0], v_mps=[0.0], omega_radps=[0.0], current_left_a=[1.0],
                   current_right_a=[1.0])
    assert rest_samples(log).tolist() == [True]
