"""Tests of planner.warmup: warm_up_kernels compiles (or loads) every kernel and says how long it took."""

from __future__ import annotations

import importlib
import math
import pathlib
import pkgutil
import re

from numba.core.registry import CPUDispatcher

import planner
import planner.kernels
from planner.warmup import warm_up_kernels


def _python_sources() -> str:
    """The planner's Python code outside the kernels (what calls a kernel from Python)."""
    root = pathlib.Path(planner.__file__).parent
    return "\n".join(p.read_text() for p in root.rglob("*.py") if "kernels" not in p.parts)


def test_warm_up_compiles_every_kernel_python_calls_and_both_variants_of_each_parallel_one():
    seconds = warm_up_kernels()
    assert math.isfinite(seconds) and seconds >= 0.0
    python = _python_sources()
    cold = []
    for info in pkgutil.iter_modules(planner.kernels.__path__):
        module = importlib.import_module(f"planner.kernels.{info.name}")
        for name in getattr(module, "__all__", ()):
            kernel = getattr(module, name)
            if not isinstance(kernel, CPUDispatcher):
                continue
            # kernels called only from other kernels are compiled into their callers, not on their own
            called_from_python = re.search(rf"\b{name}\b", python) is not None
            if (called_from_python or name.endswith(("_serial", "_parallel"))) and not kernel.signatures:
                cold.append(f"{info.name}.{name}")
    assert cold == [], f"not compiled by warm_up_kernels: {cold}"
    assert warm_up_kernels() >= 0.0  # a second call finds everything compiled
