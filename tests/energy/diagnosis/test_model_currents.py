"""Tests of energy.diagnosis.model_currents: the physics basis, unclipped currents and the ParameterTable surrogate."""

import numpy as np


def test_parameter_table_is_exact_at_nodes_and_linear_between():
    from energy.diagnosis.model_currents import ParameterTable

    base = np.column_stack([np.linspace(0.0, 1.0, 5), np.linspace(1.0, 2.0, 5)])
    table = ParameterTable(lambda x: base * x ** 2, 0.0, 2.0, 0.7, n_nodes=5)
    assert 0.7 in table.nodes and table.n_computed == 0  # the nominal is a node; nothing computed yet
    np.testing.assert_allclose(table.at(0.7), base * 0.49)
    np.testing.assert_allclose(table.at(1.5), base * 2.25)
    np.testing.assert_allclose(table.at(1.75), base * (2.25 + 4.0) / 2.0)  # linear between 1.5 and 2.0
    per_sample = np.array([0.0, 0.7, 1.75, 2.0, 9.0])  # clipped to the bounds
    expected = base * np.array([0.0, 0.49, 3.125, 4.0, 4.0])[:, None]
    np.testing.assert_allclose(table.at(per_sample), expected)
    assert table.nodes.size == 6 and table.n_computed == 6


def test_motoring_currents_hold_the_robot_standing_on_a_slope_and_nothing_on_level_ground():
    """Where the robot stands still the model predicts its rest level and, on a slope, the current of holding it
    there; so do the candidates' physics terms: 0 standing on level ground, the holding torque through the gear
    standing on a slope (m g sin(slope) r / 2 a side), scaled by a heavier robot."""
    from energy import InteractionLog, LogMeta
    from energy.diagnosis.model_currents import motoring_currents_a, physics_basis
    from energy.logs import rest_samples

    t = np.arange(0.0, 12.0, 0.1)
    v = np.where((t > 3.0) & (t < 8.0), 0.5, 0.0)
    ta = np.arange(0.0, 12.0, 0.01)
    log = InteractionLog(t, v, np.zeros_like(t), np.ones_like(t), np.ones_like(t), ta, np.full(ta.size, 9.81),
                         meta=LogMeta(robot="husky"))
    basis = physics_basis(object())  # the reference physics of the robot, every drive effect (gravity too)
    rest = rest_samples(log)
    assert rest.sum() > 40 and (~rest).sum() > 40
    cruising = (t > 3.5) & (t < 7.5)
    level = motoring_currents_a(basis, log, slope_rad=np.zeros(t.size))
    assert np.all(level[rest] == 0.0) and np.all(level[cruising] > 0.0)
    slope = 0.17
    cur = motoring_currents_a(basis, log, slope_rad=np.full(t.size, slope))
    robot, motor = basis.robot, basis.robot.motor
    torque = robot.mass_kg * 9.81 * np.sin(slope) / 2.0 * robot.wheel_radius_m
    expected = torque / (motor.gear_ratio * motor.gear_efficiency * motor.torque_constant_nm_per_a)
    np.testing.assert_allclose(cur[rest], expected, rtol=0.02)
    assert np.all(cur[cruising] > level[cruising])  # climbing draws more than cruising on the level
    heavy = motoring_currents_a(basis, log, robot=basis.robot.replace(mass_kg=2.0 * basis.robot.mass_kg),
                                slope_rad=np.full(t.size, slope))
    np.testing.assert_allclose(heavy[rest], 2.0 * cur[rest], rtol=1e-9)
    assert np.all(heavy[cruising] > cur[cruising])


def _stop_blip_start_log():
    """Cruise, stop, stand (one sample of odometry noise in it), start again: a 6.5 Hz-like log."""
    from energy import InteractionLog, LogMeta

    t = np.arange(0.0, 9.0, 0.15)
    v = np.interp(t, [0.0, 1.5, 2.4, 5.4, 6.3, 9.0], [0.6, 0.6, 0.0, 0.0, 0.6, 0.6])
    v[np.argmin(np.abs(t - 2.4))] = 0.0  # the stop's last instant: still, the central difference decelerating
    w = np.zeros_like(t)
    blip = int(np.argmin(np.abs(t - 3.9)))
    w[blip] = 0.012  # a yaw rate just above the rest threshold between still samples: the odometry's noise
    ta = np.arange(0.0, 9.0, 0.01)
    log = InteractionLog(t, v, w, np.ones_like(t), np.ones_like(t), ta, np.full(ta.size, 9.81),
                         meta=LogMeta(robot="husky"))
    return log, int(np.argmin(np.abs(t - 2.4))), blip


def test_where_the_log_stands_the_candidates_charge_no_breakaway_the_model_does():
    """At a stop's last instant the physics reads a start in reverse from the deceleration, and at a lone sample
    of noise-level yaw rate a full breakaway and turning moment: amperes a side the robot never draws. The
    candidates' physics terms are 0 there (a heavier robot would be charged a larger spike); at the still sample
    before a start too, unless asked for (the breakaway's own candidate); the model's own prediction keeps them."""
    from energy.diagnosis.model_currents import (
        basis_breakdown,
        motoring_currents_a,
        physics_basis,
        standing_samples,
        starting_samples,
    )

    log, stop, blip = _stop_blip_start_log()
    basis = physics_basis(object())
    res = basis_breakdown(basis, log)  # the physics everywhere: the current in the direction of rotation
    sign = np.sign(res.motor_speed_radps)
    raw = np.where(sign != 0, res.motor_current_a * sign, np.abs(res.motor_current_a))
    standing, starting = standing_samples(log), starting_samples(log)
    assert standing[stop] and standing[blip] and not standing[stop - 1]
    (start,) = np.nonzero(starting)[0]
    assert not standing[start] and log.v_mps[start + 1] > 0.0
    assert np.all(np.abs(raw[[stop, blip, start]]).max(axis=1) > 0.5)  # what the physics charges there
    cur = motoring_currents_a(basis, log)
    assert np.all(cur[[stop, blip, start]] == 0.0)
    assert np.all(motoring_currents_a(basis, log, starts=True)[start] == raw[start])
    moving = np.abs(log.v_mps) > 0.1
    np.testing.assert_array_equal(cur[moving], raw[moving])  # driving, nothing changes
    heavy = motoring_currents_a(basis, log, robot=basis.robot.replace(mass_kg=2.0 * basis.robot.mass_kg))
    assert np.all(heavy[[stop, blip, start]] == 0.0)
