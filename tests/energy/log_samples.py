"""A small interaction log with known values, shared by the tests of energy.logs."""

from __future__ import annotations

import numpy as np

from energy import InteractionLog, LogMeta


def make_log(n: int = 11, drive_dt: float = 0.1, m: int = 101, accel_dt: float = 0.01, **kw) -> InteractionLog:
    """Linear ramps with known values: v = t, omega = 2t, I_L = 1 + t, I_R = 3 - t, a_z = 9.81 + t."""
    t = np.arange(n) * drive_dt
    ta = np.arange(m) * accel_dt
    args = dict(
        time_s=t,
        v_mps=t.copy(),
        omega_radps=2 * t,
        current_left_a=1 + t,
        current_right_a=3 - t,
        accel_time_s=ta,
        accel_z_mps2=9.81 + ta,
        meta=LogMeta(robot="testbot", source="synthetic", ground_label="sand"),
    )
    args.update(kw)
    return InteractionLog(**args)
