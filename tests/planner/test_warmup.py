"""Tests of planner.warmup: warm_up_kernels compiles (or loads) every kernel and says how long it took."""

from __future__ import annotations

import math

from planner.warmup import warm_up_kernels


def test_warm_up_runs_every_kernel_and_returns_its_seconds():
    seconds = warm_up_kernels()
    assert math.isfinite(seconds) and seconds >= 0.0
    assert warm_up_kernels() >= 0.0  # a second call finds everything compiled
