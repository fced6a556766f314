"""Shared samples of the fit, selection and runner tests: logs whose currents carry a per-side gain a linear model lacks."""

from __future__ import annotations

import numpy as np

from energy import InteractionLog, LinearCurrentModel, robot_preset

__all__ = ["REST_A", "gained_logs", "gained_logs_and_model"]

#: The reference Husky's rest current (A): the sensor offset the gain does not scale.
REST_A = robot_preset("husky").rest_current_a


def gained_logs(n_logs=4, n=300, gain=(1.3, 0.8), seed=0):
    """``n_logs`` runs of ``n`` samples at 20 Hz: ``1 + 2 v`` A, scaled by ``gain`` above the rest offset, 0.05 A noise."""
    rng = np.random.default_rng(seed)
    out = []
    for k in range(n_logs):
        t = np.arange(n) * 0.05
        v = 0.5 + 0.3 * np.sin(t + k)
        base = 1.0 + 2.0 * v
        # the gain scales what is drawn above the sensor's rest offset (the reference Husky's 0.59 A)
        cur = REST_A + (base[:, None] - REST_A) * np.array(gain) + 0.05 * rng.standard_normal((n, 2))
        out.append(InteractionLog(t, v, np.zeros(n), cur[:, 0], cur[:, 1], t, np.full(n, 9.81)))
    return out


def gained_logs_and_model() -> tuple[list[InteractionLog], LinearCurrentModel]:
    """The gained logs and a linear model fitted on the same runs without the gain."""
    logs = gained_logs()
    ungained = [InteractionLog(g.time_s, g.v_mps, g.omega_radps, 1 + 2 * g.v_mps, 1 + 2 * g.v_mps, g.time_s,
                               g.accel_z_mps2) for g in logs]
    model = LinearCurrentModel().fit(ungained)
    return logs, model
