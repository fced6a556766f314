"""Task functions and worker plugins the dask tests send to worker processes (importable there by name): some kill
the worker they run in, as a crash would, some fail as if their worker had died."""

from __future__ import annotations

import os
from types import SimpleNamespace

from distributed import KilledWorker
from distributed.diagnostics.plugin import WorkerPlugin

#: The argument at which :func:`add_or_die` kills the process it runs in.
POISON = -1

#: The worker a :class:`KilledWorker` of these samples names (dask's message reads its address).
GONE = SimpleNamespace(address="tcp://gone:1")

#: Keys :func:`killed_once` has seen (the workers of an in-process cluster share them).
SEEN: set[str] = set()


def add_or_die(base: float, x: float) -> float:
    """``base + x``; for ``x == POISON`` the worker process exits at once (``os._exit``)."""
    if x == POISON:
        os._exit(1)
    return base + x


def killed_once(base: float, key: str) -> str:
    """Fails with dask's ``KilledWorker`` the first time it runs for ``key`` (a bystander of a worker's death);
    ``base`` and ``key`` after that."""
    if key not in SEEN:
        SEEN.add(key)
        raise KilledWorker(key, GONE, 3)
    return f"{base} {key}"


def killed_always(base: float, key: str) -> str:
    """Always fails with dask's ``KilledWorker`` (the task that killed its workers)."""
    raise KilledWorker(key, GONE, 3)


class PoisonPair(WorkerPlugin):
    """On each worker (those started later too), the batch's pair named ``name`` kills the worker that plans it."""

    def __init__(self, name: str) -> None:
        self.name = name

    def setup(self, worker) -> None:
        import planner.batch as batch

        real = batch._plan_pair_task
        poison = self.name

        def plan_or_die(cost, name, *args):
            if name == poison:
                os._exit(1)
            return real(cost, name, *args)

        batch._plan_pair_task = plan_or_die


class PoisonSample(WorkerPlugin):
    """On each worker, the Monte Carlo task holding child seed ``sample`` kills the worker that runs it."""

    def __init__(self, sample: int) -> None:
        self.sample = sample

    def setup(self, worker) -> None:
        from planner.missions.monte_carlo import MissionSetup

        real = MissionSetup.run_chunk
        sample = self.sample

        def run_or_die(setup, seqs):
            if any(q.spawn_key == (sample,) for q in seqs):
                os._exit(1)
            return real(setup, seqs)

        MissionSetup.run_chunk = run_or_die
