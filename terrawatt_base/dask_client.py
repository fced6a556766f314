"""The dask seam: open a ``distributed.Client`` (local cluster or scheduler address) and check a given one.

Every part of terrawatt that runs tasks on dask (the evaluation folds, the diagnosis,
:func:`planner.plan_batch`, :func:`planner.simulate_missions_mc`, the tours' pricing) opens and checks its client
here, and runs its tasks through :func:`run_tasks` (shared inputs sent once, results in task order, a progress bar,
the rest cancelled on an error), so the optional extra, the timeout of an unreachable scheduler and the messages are
the same everywhere.
:class:`Compute` says in one value where a batch of independent tasks runs (here, a new local cluster, a
scheduler or a given client) and whether it shows a progress bar; ``Compute.session()`` opens what it names.
"""

from __future__ import annotations

import concurrent.futures
import contextlib
import logging
import threading
import warnings
from collections.abc import Callable, Iterator, Sequence
from dataclasses import dataclass
from typing import Any

from terrawatt_base.checks import check_bool, check_int, check_real, check_text, fmt_number
from terrawatt_base.errors import InvalidParameterError, OptionalDependencyError

__all__ = ["Compute", "dask_client", "check_dask_options", "check_client", "client_worker_count", "run_tasks", "DEFAULT_CONNECT_TIMEOUT_S"]

#: Seconds to wait for a dask scheduler to answer before giving up.
DEFAULT_CONNECT_TIMEOUT_S = 10.0

_INSTALL = "install it with: pip install 'terrawatt[distributed]'"


@contextlib.contextmanager
def dask_client(
    workers: int = 1,
    scheduler: str | None = None,
    *,
    quiet: bool = True,
    timeout_s: float = DEFAULT_CONNECT_TIMEOUT_S,
) -> Iterator[Any]:
    """A ``distributed.Client`` on ``scheduler``, or on a new local cluster of ``workers`` processes.

    Leaving the context closes the client and the local cluster it started. ``quiet``
    keeps dask's INFO messages (cluster start and stop) out of the log meanwhile.

    Parameters
    ----------
    workers : int
        Worker processes of the local cluster (>= 1, one thread each); not with ``scheduler``
        unless 1.
    scheduler : str, optional
        Address of a running scheduler, e.g. ``"tcp://host:8786"``.
    quiet : bool
        Silence dask's INFO log while the client is open.
    timeout_s : float
        Seconds to wait for ``scheduler`` to answer (> 0).

    Raises
    ------
    OptionalDependencyError
        dask.distributed is not installed.
    InvalidParameterError
        ``workers < 1``; both ``workers > 1`` and ``scheduler``; no dask scheduler answers at
        ``scheduler`` within ``timeout_s`` (the error names ``workers`` / ``scheduler`` as its
        parameters, :attr:`~terrawatt_base.errors.TerrawattError.parameter`).

    Examples
    --------
    Usage (starts worker processes, so not run as a doctest)::

        with dask_client(workers=2) as client:
            result = plan_batch(cost, pairs, client=client)
    """
    workers = check_int("workers", workers, low=1)
    quiet = check_bool("quiet", quiet)
    timeout_s = check_real("timeout_s", timeout_s, low=0.0, low_inclusive=False)
    if scheduler is not None:
        check_text("scheduler", scheduler)
    check_dask_options(workers, scheduler)
    try:
        from distributed import Client, LocalCluster
    except ImportError as exc:
        name, value = ("scheduler", scheduler) if scheduler is not None else ("workers", workers)
        raise OptionalDependencyError(f"{name} {value} needs dask.distributed; {_INSTALL}", parameter=name) from exc
    dask_log = logging.getLogger("distributed")  # configured by the import above
    old_level = dask_log.level
    if quiet:
        dask_log.setLevel(max(dask_log.getEffectiveLevel(), logging.WARNING))
    try:
        if scheduler is not None:
            client = _connect(Client, scheduler, timeout_s)
            with client:
                yield client
        else:
            with LocalCluster(n_workers=workers, threads_per_worker=1, processes=True,
                              dashboard_address=":0") as cluster, Client(cluster) as client:
                yield client
    finally:
        dask_log.setLevel(old_level)


def check_dask_options(workers: int = 1, scheduler: str | None = None) -> None:
    """Check where :func:`dask_client` would run, before any work: ``workers`` a positive int, not both ``workers > 1``
    and ``scheduler`` (the error names them as its parameters).

    Raises
    ------
    InvalidParameterError
        ``workers`` not an int >= 1; both ``workers > 1`` and ``scheduler``.

    Examples
    --------
    >>> check_dask_options(2)
    >>> check_dask_options(2, "tcp://host:8786")  # doctest: +ELLIPSIS
    Traceback (most recent call last):
    ...
    terrawatt_base.errors.InvalidParameterError: workers 2 and scheduler 'tcp://host:8786' exclude each other: ...
    """
    if isinstance(workers, bool) or not isinstance(workers, int) or workers < 1:
        raise InvalidParameterError(f"workers must be a positive number of processes, got {workers!r}",
                                    parameter="workers")
    if scheduler is not None and workers > 1:
        raise InvalidParameterError(
            f"workers {workers!r} and scheduler {scheduler!r} exclude each other: "
            f"give workers N for a local cluster or scheduler ADDRESS for an existing one",
            parameter=("workers", "scheduler"))


@dataclass(frozen=True)
class Compute:
    """Where a batch of independent tasks runs, and whether a progress bar shows.

    One value instead of the ``client`` / ``workers`` / ``scheduler`` / ``progress`` threads
    every batch entry point took: :func:`planner.plan_batch`, :func:`planner.simulate_missions_mc`,
    the Monte Carlo study, the tours' pricing. Checked when made.

    Parameters
    ----------
    workers : int
        Worker processes of a new local cluster (>= 1; 1 runs the tasks here, one after another).
    scheduler : str, optional
        Address of a running dask scheduler; not with ``workers > 1``.
    client : distributed.Client, optional
        A client the caller opened (and closes); not with ``workers > 1`` or ``scheduler``.
    progress : bool
        Show a progress bar (tqdm).
    quiet : bool
        Keep dask's INFO messages out of the log while a cluster this value opened runs.
    where : str, optional
        How results name where the tasks ran when ``client`` is given (default ``"given client"``;
        a command line that opened the client from its flags names the cluster it opened).

    Raises
    ------
    InvalidParameterError
        ``workers`` not an int >= 1; ``workers > 1`` with ``scheduler``; ``client`` not a
        ``distributed.Client``, or with ``workers > 1`` or ``scheduler``; ``where`` without ``client``.
    OptionalDependencyError
        A client is given but dask.distributed is not installed.

    Examples
    --------
    >>> with Compute().session() as (client, where):
    ...     client, where
    (None, 'in process')
    """

    workers: int = 1
    scheduler: str | None = None
    client: Any = None
    progress: bool = False
    quiet: bool = True
    where: str | None = None

    def __post_init__(self) -> None:
        check_dask_options(self.workers, self.scheduler)
        if self.scheduler is not None:
            check_text("scheduler", self.scheduler)
        check_client(self.client)
        if self.client is not None and (self.workers > 1 or self.scheduler is not None):
            raise InvalidParameterError(
                "client excludes workers and scheduler: give a distributed.Client, or workers=N for a local cluster, "
                "or scheduler=ADDRESS", parameter=("client", "workers", "scheduler"))
        check_bool("progress", self.progress)
        check_bool("quiet", self.quiet)
        if self.where is not None:
            check_text("where", self.where)
            if self.client is None:
                raise InvalidParameterError("where names a given client; give it with client", parameter="where")

    @property
    def here(self) -> bool:
        """Whether the tasks run in this process (no client, no cluster)."""
        return self.client is None and self.workers == 1 and self.scheduler is None

    @contextlib.contextmanager
    def session(self) -> Iterator[tuple[Any, str]]:
        """``(client, where)`` while the tasks run: ``(None, "in process")`` here; a new local cluster's or the
        scheduler's client (closed on leaving, as :func:`dask_client` opens it); or the given client, left open.

        Raises
        ------
        OptionalDependencyError, InvalidParameterError
            As :func:`dask_client`: no dask.distributed; an unreachable scheduler.
        """
        if self.client is not None:
            yield self.client, self.where or "given client"
        elif self.here:
            yield None, "in process"
        else:
            with dask_client(self.workers, self.scheduler, quiet=self.quiet) as client:
                yield client, ("local cluster" if self.scheduler is None else self.scheduler)


def _connect(client_class: Any, scheduler: str, timeout_s: float) -> Any:
    """``Client(scheduler)`` with one deadline over connect, handshake and first answer.

    dask's own ``timeout`` covers the TCP connect, not a server that accepts and never
    speaks (the handshake then waits forever) nor one that answers junk; the client is made
    in a helper thread and abandoned when the deadline passes (``timeout_s`` plus 2 s for
    dask's own start-up).
    """
    advice = "expected the address of a running dask scheduler, e.g. tcp://host:8786"
    future: concurrent.futures.Future = concurrent.futures.Future()

    def connect() -> None:
        if not future.set_running_or_notify_cancel():
            return
        try:
            future.set_result(client_class(scheduler, timeout=timeout_s))
        except BaseException as exc:  # handed to the waiting caller, never lost in the thread
            future.set_exception(exc)

    # a daemon thread, never a pool's worker: an executor's threads are joined at interpreter
    # exit, so a thread stuck in a handshake would keep the process alive after the error
    threading.Thread(target=connect, name="terrawatt-dask-connect", daemon=True).start()
    try:
        return future.result(timeout=timeout_s + 2.0)
    except concurrent.futures.TimeoutError as exc:
        future.add_done_callback(_close_late_client)
        raise InvalidParameterError(
            f"`scheduler` {scheduler!r}: no dask scheduler answered within {fmt_number(timeout_s)} s (a server that "
            f"accepts the connection but never completes dask's handshake?); {advice}", parameter="scheduler"
        ) from exc
    except Exception as exc:  # unreachable (TimeoutError is an OSError), malformed, junk answers (MemoryError...)
        raise InvalidParameterError(
            f"`scheduler` {scheduler!r}: cannot connect to a dask scheduler there ({type(exc).__name__}: "
            f"{str(exc)[:200]}); {advice}", parameter="scheduler"
        ) from exc


def _close_late_client(future: concurrent.futures.Future) -> None:
    """Close a client whose connection completed after its deadline (nobody else will)."""
    if not future.cancelled() and future.exception() is None:
        with contextlib.suppress(Exception):
            future.result().close()


def check_client(client: Any, what: str = "tasks") -> Any:
    """``client`` if it is ``None`` or a ``distributed.Client``; else a clear error.

    Raises
    ------
    InvalidParameterError
        Anything else (e.g. a scheduler address string or a cluster object).
    OptionalDependencyError
        A client is given but dask.distributed is not installed.
    """
    if client is None:
        return None
    try:
        from distributed import Client
    except ImportError as exc:
        raise OptionalDependencyError(f"running {what} on a cluster needs dask.distributed; {_INSTALL}") from exc
    if not isinstance(client, Client):
        raise InvalidParameterError(
            f"client must be None (run the {what} here, one after another) or a distributed.Client, got {client!r:.80}"
        )
    return client


def client_worker_count(client: Any) -> int:
    """Number of workers connected to ``client``'s scheduler now (at least 1 is assumed for None)."""
    return 1 if client is None else max(1, len(client.scheduler_info().get("workers", {})))


def run_tasks(tasks: Sequence[tuple[Callable[..., Any], tuple[Any, ...]]], *, client: Any = None,
              shared: Sequence[Any] = (), progress: bool = False, description: str = "tasks",
              sizes: Sequence[int] | None = None,
              on_error: Callable[[int, Exception], Any] | None = None) -> Iterator[Any]:
    """Each task's ``fn(*shared, *args)``, yielded in the order of ``tasks``.

    Without a ``client`` the tasks run here, one after another, when the results are asked
    for. With a dask ``client`` every task is submitted at once (``fn`` must be importable by
    the workers); each of ``shared`` (what every task takes first: a map, a cost, the logs)
    is sent once, never with a task, as a task of its own whose result is copied to every
    worker before the tasks are placed (the scheduler keeps the object in that task until the
    end, so dask computes it again on a live worker if every worker holding it dies), and
    released at the end. The results come back in task order, whichever finishes first; the
    first task's exception is raised here and the other tasks are cancelled — unless
    ``on_error`` turns it into that task's result (a batch whose one task fails keeps the others).

    A task whose worker process dies (a crash, ``os._exit``) is retried by dask on other
    workers (the scheduler's ``allowed-failures``, 3 by default) and kills them too; then its
    result is ``on_error(i, KilledWorker)`` and the other tasks still come back, once the
    cluster has started workers again (a ``LocalCluster``'s nannies do): the shared objects are
    computed again, and when more than one task fails with ``KilledWorker`` (tasks waiting on the
    dying workers beside the one that killed them), each runs once more, alone, after the
    others. On a 2-process local cluster, 6 tasks of which one calls ``os._exit``: the other 5
    came back in 20 of 20 runs (one run re-ran a bystander); with the shared object scattered
    as before, 3 to 6 of the 6 were lost in each of 6 runs (``FutureCancelledError``).

    Parameters
    ----------
    tasks : sequence of (callable, tuple)
        Each task's function and its own arguments.
    client : distributed.Client, optional
        Where the tasks run (default here).
    shared : sequence
        Leading arguments of every task.
    progress : bool
        Show a tqdm bar over the tasks (as they complete on a cluster).
    description : str
        The bar's label.
    sizes : sequence of int, optional
        How far each task moves the bar (e.g. the missions in a chunk; default 1 each).
    on_error : callable, optional
        ``on_error(i, exc)``: the result of task ``i`` that raised ``exc`` (an ``Exception``,
        dask's ``KilledWorker`` for a task whose workers died; an interrupt still stops every
        task). Default: raise (the first ``KilledWorker`` too, with no task run again).

    Raises
    ------
    InvalidParameterError
        ``sizes`` not one per task (when the results are first asked for).

    Examples
    --------
    >>> import operator
    >>> list(run_tasks([(operator.add, (1,)), (operator.mul, (3,))], shared=(2,)))
    [3, 6]
    """
    from tqdm.auto import tqdm

    steps = [1] * len(tasks) if sizes is None else list(sizes)
    if len(steps) != len(tasks):
        raise InvalidParameterError(f"sizes must give one size per task ({len(tasks)}), got {len(steps)}",
                                    parameter="sizes")
    with tqdm(total=sum(steps), desc=description, disable=not progress) as bar:
        if client is None:
            for i, ((fn, args), step) in enumerate(zip(tasks, steps)):
                try:
                    result = fn(*shared, *args)
                except Exception as exc:
                    if on_error is None:
                        raise
                    result = on_error(i, exc)
                bar.update(step)
                yield result
            return
        yield from _run_on_cluster(client, tasks, shared, steps, bar, on_error)


def _run_on_cluster(client: Any, tasks: Sequence[tuple[Callable[..., Any], tuple[Any, ...]]], shared: Sequence[Any],
                    steps: Sequence[int], bar: Any, on_error: Callable[[int, Exception], Any] | None) -> Iterator[Any]:
    """:func:`run_tasks` on a dask ``client``: every task submitted at once, the results yielded in task order."""
    from distributed import KilledWorker, as_completed, wait

    sent: list[Any] = []
    futures: list[Any] = []
    done: dict[int, Any] = {}  # finished, waiting for the tasks before them
    killed: dict[int, Exception] = {}  # lost with the workers that died running them
    first = 0  # the next result to yield
    try:
        # each shared object a task of its own whose spec keeps it on the scheduler, not scattered data: a worker
        # that dies loses what it held, and dask computes a lost result again on a live worker, where scattered
        # data is gone for good (and every task still to run with it); copied to every worker before the tasks
        # are placed, as a broadcast scatter was, or dask would place them all on the one worker that holds it
        sent = [_hold(client, obj) for obj in shared]
        if sent:
            wait(sent)
            for held in sent:
                if held.status == "error":
                    held.result()  # raises why the object does not load on the workers, before any task
            client.replicate(sent)
        futures = [client.submit(fn, *sent, *args, pure=False) for fn, args in tasks]
        position = {f.key: i for i, f in enumerate(futures)}
        for fut in as_completed(futures):
            i = position[fut.key]
            try:
                done[i] = fut.result()  # re-raises the task's exception (or the worker's death)
            except Exception as exc:
                if on_error is None:
                    raise
                if isinstance(exc, KilledWorker):
                    killed[i] = exc
                    continue
                done[i] = on_error(i, exc)
            bar.update(steps[i])
            while first in done:
                yield done.pop(first)
                first += 1
        # a task that kills its worker is retried on others by dask (``allowed-failures``) and kills them too: the
        # tasks waiting on those workers die with it, and more than one killed task means bystanders among them;
        # each runs once more, alone (its own death then counts only against itself)
        for i in sorted(killed):
            if len(killed) > 1:
                fn, args = tasks[i]
                futures.append(client.submit(fn, *sent, *args, pure=False))
                try:
                    done[i] = futures[-1].result()
                except Exception as exc:
                    done[i] = on_error(i, exc)
            else:
                done[i] = on_error(i, killed[i])
            bar.update(steps[i])
            while first in done:
                yield done.pop(first)
                first += 1
    except BaseException:
        client.cancel(futures)
        raise
    finally:
        client.cancel(sent)


def _held(obj: Any) -> Any:
    """``obj``: the task whose result is a shared input of :func:`run_tasks` (its spec keeps ``obj``)."""
    return obj


def _hold(client: Any, obj: Any) -> Any:
    """A future of ``obj`` that dask can recompute on a live worker when the workers holding it die."""
    with warnings.catch_warnings():
        # the graph is large on purpose (the map, the cost): it is sent once, and dask's advice is to scatter
        warnings.filterwarnings("ignore", message="Sending large graph", category=UserWarning)
        return client.submit(_held, obj, pure=False)
