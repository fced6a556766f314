"""Scoring many effect sets: one after another here, or as tasks on a dask.distributed client, with progress."""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

from terrawatt_base.dask_client import check_client, run_tasks

from .effect_base import Effect
from .fit import DiagnosisData, SetScore, score_effect_set
from .split import Split

__all__ = ["SetRunner"]


class SetRunner:
    """Scores effect sets on one :class:`DiagnosisData` and :class:`Split`, here or on ``client``.

    On a client the data and the split go to every worker once (``scatter(broadcast=True)``);
    each set is one task. Results come back in the order asked, equal to the serial ones
    (the fits are deterministic least squares). ``progress`` shows a tqdm bar per batch.
    """

    def __init__(self, data: DiagnosisData, split: Split, *, client: Any = None, progress: bool = False) -> None:
        self.data, self.split = data, split
        self.client = check_client(client, "candidate effect sets")
        self.progress = bool(progress)
        self._remote: tuple[Any, Any] | None = None

    def score(self, sets: Sequence[Sequence[Effect]], desc: str = "effect sets") -> list[SetScore]:
        """The held-out score of each set in ``sets``, in order."""
        if self.client is None or len(sets) < 2:
            data, split = self.data, self.split
        else:
            if self._remote is None:
                self._remote = tuple(self.client.scatter([self.data, self.split], broadcast=True, hash=False))
            data, split = self._remote
        tasks = [(score_effect_set, (list(s), data, split)) for s in sets]
        client = self.client if len(sets) >= 2 else None
        return list(run_tasks(tasks, client=client, progress=self.progress, description=desc))

    def close(self) -> None:
        """Release the scattered data on the cluster."""
        if self.client is not None and self._remote is not None:
            self.client.cancel(list(self._remote))
            self._remote = None
