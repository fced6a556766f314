"""Run evaluation tasks (one fold each) here, one after another, or on a dask cluster, results in task order."""

from __future__ import annotations

from collections.abc import Callable, Iterator, Sequence
from typing import Any

from terrain.errors import InvalidParameterError, OptionalDependencyError

__all__ = ["check_client", "run_tasks"]


def check_client(client: Any) -> None:
    """Raise unless ``client`` is None or a ``distributed.Client``.

    Raises
    ------
    InvalidParameterError
        Anything else.
    OptionalDependencyError
        A client is given but dask.distributed is not installed.
    """
    if client is None:
        return
    try:
        from distributed import Client
    except ImportError as exc:
        raise OptionalDependencyError(
            "evaluating on a cluster needs dask.distributed; install it with: pip install 'terrawatt[distributed]'"
        ) from exc
    if not isinstance(client, Client):
        raise InvalidParameterError(
            f"client must be None (run the folds here, one after another) or a distributed.Client, got {client!r:.80}"
        )


def run_tasks(tasks: Sequence[tuple[Callable[..., Any], tuple[Any, ...]]], *, client: Any = None,
              progress: bool = False, description: str = "tasks") -> Iterator[Any]:
    """Each task's ``fn(*args)``, yielded in the order of ``tasks``.

    With a dask ``client`` every task is submitted at once (``fn`` must be importable by
    the workers) and the results come back in task order, whichever finishes first; a
    task's exception is raised here and the other tasks are cancelled.
    """
    from tqdm.auto import tqdm

    if client is None:
        for fn, args in tqdm(tasks, desc=description, disable=not progress):
            yield fn(*args)
        return
    from distributed import wait

    futures = [client.submit(fn, *args, pure=False) for fn, args in tasks]
    try:
        with tqdm(total=len(futures), desc=description, disable=not progress) as bar:
            for fut in futures:
                wait(fut)
                bar.update()
                yield fut.result()  # re-raises the task's exception
    except BaseException:
        client.cancel(futures)
        raise
