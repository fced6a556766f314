"""The dask seam: argument checks, client checks and the task runner (here, on an in-process cluster, and on worker
processes that a task kills)."""

from __future__ import annotations

import contextlib
import operator
import re
import time
import warnings

import numpy as np
import pytest

from terrawatt_base.dask_client import (
    DEFAULT_CONNECT_TIMEOUT_S,
    check_client,
    check_dask_options,
    client_worker_count,
    dask_client,
    run_tasks,
)
from terrawatt_base.errors import InvalidParameterError


def test_default_connect_timeout_is_positive_seconds():
    assert DEFAULT_CONNECT_TIMEOUT_S == 10.0


def test_zero_workers_is_refused_naming_the_flag():
    with pytest.raises(InvalidParameterError, match="workers"), dask_client(workers=0):
        pass


def test_several_workers_and_a_scheduler_exclude_each_other():
    with pytest.raises(InvalidParameterError, match="exclude each other"), dask_client(
        workers=2, scheduler="tcp://127.0.0.1:8786"
    ):
        pass


def test_messages_name_the_parameters_and_the_error_carries_them():
    with pytest.raises(InvalidParameterError, match="workers 3 and scheduler 'tcp://h:1' exclude each other") as err:
        with dask_client(workers=3, scheduler="tcp://h:1"):
            pass
    assert err.value.parameter == ("workers", "scheduler")  # the command line says them as --workers, --scheduler


@pytest.mark.parametrize("timeout_s", [0.0, -1.0])
def test_a_non_positive_timeout_is_refused(timeout_s):
    with pytest.raises(InvalidParameterError, match="timeout_s"), dask_client(timeout_s=timeout_s):
        pass


def test_an_unreachable_scheduler_is_an_invalid_parameter():
    # port 1 on the loopback: nothing listens, the connection is refused at once
    with pytest.raises(InvalidParameterError, match="tcp://127.0.0.1:1"), dask_client(
        scheduler="tcp://127.0.0.1:1", timeout_s=0.5
    ):
        pass


def test_check_client_passes_none_through():
    assert check_client(None) is None


@pytest.mark.parametrize("bad", ["tcp://127.0.0.1:8786", 4, object()])
def test_check_client_refuses_what_is_not_a_client(bad):
    with pytest.raises(InvalidParameterError, match="client must be None .* or a distributed.Client"):
        check_client(bad, "folds")


def test_check_client_names_what_would_run():
    with pytest.raises(InvalidParameterError, match="run the folds here"):
        check_client("tcp://x:1", "folds")


def test_no_client_counts_as_one_worker():
    assert client_worker_count(None) == 1


def test_run_tasks_without_a_client_yields_results_in_task_order():
    tasks = [(operator.add, (1, 2)), (operator.mul, (3, 4)), (pow, (2, 10))]
    assert list(run_tasks(tasks)) == [3, 12, 1024]


def test_run_tasks_is_lazy_and_raises_a_tasks_exception_when_reached():
    tasks = [(operator.add, (1, 2)), (operator.truediv, (1, 0))]
    results = run_tasks(tasks, progress=False, description="division")
    assert next(results) == 3
    with pytest.raises(ZeroDivisionError):
        next(results)


def test_run_tasks_of_nothing_yields_nothing():
    assert list(run_tasks([])) == []


def test_run_tasks_puts_the_shared_arguments_first():
    assert list(run_tasks([(operator.sub, (1,)), (operator.truediv, (4,))], shared=(8,), sizes=[3, 1])) == [7, 2.0]


def test_run_tasks_wants_one_size_per_task():
    with pytest.raises(InvalidParameterError, match=r"sizes must give one size per task \(2\), got 1"):
        list(run_tasks([(operator.neg, (1,)), (operator.neg, (2,))], sizes=[1]))


@pytest.fixture
def local_client():
    """An in-process dask cluster of two single-thread workers."""
    distributed = pytest.importorskip("distributed", reason="the cluster path needs dask.distributed")
    with distributed.LocalCluster(processes=False, n_workers=2, threads_per_worker=1,
                                  dashboard_address=":0") as cluster, distributed.Client(cluster) as client:
        yield client


def _late_sum(base: int, delay_s: float, x: int) -> int:
    time.sleep(delay_s)  # lets a later task finish first
    return base + x


def test_run_tasks_on_a_cluster_yields_in_task_order_whichever_finishes_first():
    distributed = pytest.importorskip("distributed", reason="the cluster path needs dask.distributed")
    tasks = [(_late_sum, (0.5, 1)), (_late_sum, (0.0, 3)), (_late_sum, (0.0, 2))]
    with distributed.LocalCluster(processes=False, n_workers=2, threads_per_worker=1,
                                  dashboard_address=":0") as cluster, distributed.Client(cluster) as client:
        there = list(run_tasks(tasks, client=client, shared=(10,), sizes=[2, 1, 1]))
        with pytest.raises(ZeroDivisionError):
            list(run_tasks([(operator.truediv, (0,)), (operator.add, (1,))], client=client, shared=(1,)))
    assert there == [11, 13, 12] == list(run_tasks(tasks, shared=(10,)))


def test_run_tasks_on_error_turns_a_failed_task_into_its_result_here_and_on_a_cluster():
    distributed = pytest.importorskip("distributed", reason="the cluster path needs dask.distributed")
    tasks = [(operator.truediv, (2,)), (operator.truediv, (0,)), (operator.add, (5,))]

    def as_row(i, exc):
        return f"task {i}: {type(exc).__name__}"

    here = list(run_tasks(tasks, shared=(4,), on_error=as_row))
    with distributed.LocalCluster(processes=False, n_workers=2, threads_per_worker=1,
                                  dashboard_address=":0") as cluster, distributed.Client(cluster) as client:
        there = list(run_tasks(tasks, client=client, shared=(4,), on_error=as_row))
    assert here == there == [2.0, "task 1: ZeroDivisionError", 9]


def test_a_large_shared_object_goes_once_without_dasks_large_graph_warning(local_client):
    big = np.ones(12 * 2**20 // 8)  # 12 MiB: over dask's 10 MB "Sending large graph" threshold
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        there = list(run_tasks([(np.sum, ()), (np.size, ())], client=local_client, shared=(big,)))
    assert there == [big.size, big.size]


@contextlib.contextmanager
def dying_cluster():
    """A client of two worker processes of one thread (which a task may kill: their nannies start new ones); a dead
    worker's address refused for 5 s, not dask's 30, before its results are computed again."""
    distributed = pytest.importorskip("distributed", reason="the cluster path needs dask.distributed")
    import dask

    with dask.config.set({"distributed.comm.timeouts.connect": "5s"}), distributed.LocalCluster(
        n_workers=2, processes=True, threads_per_worker=1, dashboard_address=":0"
    ) as cluster, distributed.Client(cluster) as client:
        yield client


def _as_row(i, exc):
    return f"task {i}: {type(exc).__name__}"


def test_a_task_that_kills_its_workers_fails_alone_and_the_shared_data_survives():
    """dask retries a task whose worker died on the other workers (``allowed-failures``, 3), so it kills them all:
    the shared data they held is computed again, the other tasks come back, the poison task is its error row."""
    with dying_cluster() as client:
        from dask_samples import POISON, add_or_die

        xs = [1, 2, POISON, 4, 5, 6]
        there = list(run_tasks([(add_or_die, (x,)) for x in xs], client=client, shared=(np.float64(10.0),),
                               on_error=_as_row))
        assert there == [11.0, 12.0, "task 2: KilledWorker", 14.0, 15.0, 16.0]
        # and the cluster is whole again for the next run
        assert list(run_tasks([(operator.add, (1,))], client=client, shared=(2,))) == [3]


def test_tasks_killed_beside_the_one_that_killed_their_workers_run_again_alone(local_client):
    """More than one ``KilledWorker`` means bystanders among them: each runs once more, alone; one alone is the task
    that killed its workers, not run again."""
    import dask_samples

    dask_samples.SEEN.clear()
    tasks = [(operator.add, (1,)), (dask_samples.killed_once, ("a",)), (dask_samples.killed_always, ("b",)),
             (dask_samples.killed_once, ("c",)), (operator.add, (2,))]
    there = list(run_tasks(tasks, client=local_client, shared=(10,), on_error=_as_row))
    assert there == [11, "10 a", "task 2: KilledWorker", "10 c", 12]
    assert dask_samples.SEEN == {"a", "c"}
    only = list(run_tasks([(dask_samples.killed_once, ("d",)), (operator.add, (2,))], client=local_client,
                          shared=(10,), on_error=_as_row))
    assert only == ["task 0: KilledWorker", 12]
    with pytest.raises(dask_samples.KilledWorker):
        list(run_tasks(tasks, client=local_client, shared=(10,)))  # without on_error, raised as any error


@pytest.mark.parametrize(
    ("workers", "scheduler", "message"),
    [(0, None, "workers must be a positive number of processes, got 0"),
     (1.5, None, "workers must be a positive number of processes, got 1.5"),
     (True, None, "workers must be a positive number of processes, got True"),
     (2, "tcp://h:1", "workers 2 and scheduler 'tcp://h:1' exclude each other: give workers N for a local "
                      "cluster or scheduler ADDRESS for an existing one")],
)
def test_dask_options_are_checked_without_starting_anything(workers, scheduler, message):
    with pytest.raises(InvalidParameterError, match=re.escape(message)) as err:
        check_dask_options(workers, scheduler)
    assert "workers" in np.atleast_1d(err.value.parameter)  # the command line says it as --workers


def test_dask_options_that_go_together_pass():
    for workers, scheduler in ((1, None), (4, None), (1, "tcp://h:1")):
        assert check_dask_options(workers, scheduler) is None
    with pytest.raises(InvalidParameterError, match="^workers must be"):
        check_dask_options(-1)  # named as the parameter by default
