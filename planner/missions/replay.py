"""A recorded drive fed through a :class:`~planner.Navigator` in time order: what it learned and decided.

:func:`replay_drive` takes what a robot recorded — the legs of a mission (an adaptive mission's ``logs``:
``leg_NNN.csv`` and the manoeuvres it drove, ``manoeuvre_NNN_K.csv``), or one long drive
(a bag, an MCAP, a CSV log) — and feeds it to a navigator as the robot would have: a folder
of legs leg by leg with a checkpoint at each leg's end; a long drive in chunks of
``chunk_s`` seconds (checkpoints every ``settings.leg_length_m`` driven). Where the
navigator asks for a manoeuvre, the recording's next manoeuvre runs answer it; a
recording without one declines it (the navigator then learns from the driven data, or
leaves the model as it is).

With ``feed.state_path`` the navigator's state is saved every ``feed.save_every`` checkpoints
(:meth:`Navigator.save`, atomic); a replay started again from the navigator saved there
(:meth:`Navigator.load`; :func:`~planner.missions.replay_report.replay_recording` does this when
``feed.resumes``) resumes from the last save, skipping the data it had already seen, and makes
the same decisions as one that ran through.

The :class:`ReplayResult` holds the navigator, the per-cell model map before and after,
every logged decision and the forecast of the remaining energy at each checkpoint against
what the robot then actually drew; ``write(out_dir)`` writes ``replay.json`` (format
``terrawatt-replay``), ``replay.png`` and ``replay.mcap`` (each replan a ``nav_msgs/Path``,
forecasts and decisions on topics: :func:`planner.replay_bag.write_replay_bag`).
"""

from __future__ import annotations

import logging
import math
import os
import re
import time
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from energy import InteractionLog
from terrain import DataError, InvalidParameterError
from terrawatt_base.answer import write_answer
from terrawatt_base.atomic import json_finite
from terrawatt_base.checks import check_instance
from terrawatt_base.formats import result_document, write_result_json

from ..replay_bag import write_replay_bag
from .navigator import Navigator
from .replay_figure import plot_replay
from .settings import ReplayFeed

__all__ = ["REPLAY_FORMAT_VERSION", "MANOEUVRE_FILE", "drive_items", "drive_chunks", "replay_drive", "ReplayResult"]

_LOG = logging.getLogger(__name__)

REPLAY_FORMAT_VERSION = 1
#: File names of manoeuvre runs in a folder of legs: ``manoeuvre_<after leg>_<run>.csv``.
MANOEUVRE_FILE = re.compile(r"manoeuvre_(\d{3,})_(\d+)\.csv")


def drive_items(logs: Sequence[Any]) -> list[tuple[str, InteractionLog]]:
    """Each log of a recording with its kind, sorted in time order: a ``(kind, log)`` pair keeps
    its kind; a log is a ``"manoeuvre"`` run by its file name (:data:`MANOEUVRE_FILE`), else a
    ``"drive"`` log.

    Raises
    ------
    DataError
        Logs that overlap in time (two drives mixed in one folder).
    """
    items = []
    for i, entry in enumerate(logs):
        if isinstance(entry, tuple) and len(entry) == 2 and entry[0] in ("drive", "manoeuvre"):
            kind, log = entry
        else:
            log = entry
            kind = "manoeuvre" if MANOEUVRE_FILE.fullmatch(Path(str(getattr(log, "meta", None) and log.meta.source)
                                                                 ).name) else "drive"
        if not isinstance(log, InteractionLog):
            raise InvalidParameterError(f"logs[{i}] must be an InteractionLog or a (kind, log) pair, got {entry!r:.80}")
        items.append((kind, log))
    items.sort(key=lambda kv: float(kv[1].time_s[0]))
    for (_, a), (_, b) in zip(items, items[1:]):
        if not float(b.time_s[0]) > float(a.time_s[-1]):
            raise DataError(f"the recording's logs overlap in time: {a.meta.source!r} ends at "
                            f"{float(a.time_s[-1]):.6g} s, {b.meta.source!r} starts at {float(b.time_s[0]):.6g} s")
    return items


def drive_chunks(log: InteractionLog, chunk_s: float, after_s: float) -> list[InteractionLog]:
    """The log's samples after ``after_s`` cut on a grid of ``chunk_s`` from its first sample; a window
    without a drive or an IMU sample is joined to the next one (nothing is dropped)."""
    t, ta = log.time_s, log.accel_time_s
    t0 = float(t[0])
    if not float(t[-1]) > after_s:
        return []
    start = after_s + 1e-12 if after_s >= t0 else t0
    first = float(t[np.searchsorted(t, start, side="left")])
    edges = t0 + chunk_s * np.arange(math.floor((first - t0) / chunk_s) + 1, math.floor((float(t[-1]) - t0) / chunk_s) + 1)
    edges = np.concatenate(([start], edges[edges > start], [float(t[-1]) + 1.0]))
    nd = np.diff(np.searchsorted(t, edges, side="left"))
    na = np.diff(np.searchsorted(ta, edges, side="left"))
    out, lo = [], edges[0]
    for k in range(len(edges) - 1):
        if (nd[k] == 0 or na[k] == 0) and k < len(edges) - 2:
            continue  # joined to the next window (lo stays)
        if nd[k] > 0 or out == []:
            try:
                out.append(log.slice(lo, float(edges[k + 1])))
            except DataError:  # the recording's end holds no IMU sample: the drive samples go with the last chunk
                if out:
                    out[-1] = log.slice(float(out[-1].time_s[0]), float(edges[k + 1]))
        lo = float(edges[k + 1])
    return out


@dataclass(frozen=True, eq=False)
class ReplayResult:
    """What a replay learned and decided (see the module docstring).

    Attributes
    ----------
    navigator : Navigator
        At the end of the replay (its registry holds the learned models).
    model_map_before, model_map_after : ndarray of int
        The model serving each cell before and after.
    decisions : tuple of dict
        Every logged decision (:meth:`Decision.to_dict`).
    forecast : dict of ndarray
        At each checkpoint: ``time_s``, ``energy_j``, ``low_j``, ``high_j`` (the remaining
        energy's forecast and interval), ``actual_j`` (what the robot then drew to the end of
        the recording) and ``soc``.
    mode : {"legs", "drive"}
        A folder of legs, or one drive in chunks.
    chunks : int
        Chunks fed to the navigator (this run; a resumed run counts from its restart).
    unused_s : float
        Seconds of recorded driving left after the mission ended.
    resumed : bool
        Whether the replay resumed from a saved state.
    wall_time_s, drive_time_s : float
        The replay's computing time and the recording's duration.
    map_label : str
        The map's name in :meth:`summary` (``terrawatt replay``: the map file's).
    """

    navigator: Navigator
    model_map_before: np.ndarray
    model_map_after: np.ndarray
    decisions: tuple[dict[str, Any], ...]
    forecast: dict[str, np.ndarray]
    mode: str
    chunks: int
    unused_s: float
    resumed: bool
    wall_time_s: float
    drive_time_s: float
    map_label: str = "map"

    @property
    def replans(self) -> list[tuple[float, np.ndarray]]:
        """Each route the navigator gave (the first plan, new routes, the way back): (time, waypoints)."""
        return [(float(d["time_s"]), np.asarray(d["route"]["waypoints_m"], dtype=np.float64))
                for d in self.decisions if d.get("route")]

    @property
    def updates(self) -> tuple[Any, ...]:
        """The update attempts (:class:`~planner.missions.adaptive_results.UpdateRecord`)."""
        return tuple(self.navigator.updates)

    def summary(self) -> str:
        """What ``terrawatt replay`` prints after the decisions: the map, the pace, the status, the updates and how
        the remaining-energy forecast did."""
        nav = self.navigator
        changed = int(np.count_nonzero(self.model_map_before != self.model_map_after))
        acc = sum(u.accepted for u in nav.updates)
        lines = [
            f"map: {self.map_label}",
            f"replay ({self.mode}): {len(nav.legs)} checkpoints, {self.drive_time_s:.1f} s of driving replayed in "
            f"{self.wall_time_s:.2f} s ({self.drive_time_s / max(self.wall_time_s, 1e-9):.0f}x real time)"
            + (" (resumed from a saved state)" if self.resumed else ""),
            f"status: {nav.status if nav.finished else 'under way at the end of the recording'}"
            + (f" ({nav.reason})" if nav.finished else ""),
            f"updates: {len(nav.updates)} tried, {acc} accepted; {changed} cells changed model; "
            f"{len(self.replans) - 1 if self.replans else 0} new routes",
        ]
        for u in nav.updates:
            lines.append(f"  after leg {u.after_leg}: {u.kind} update of {u.ground!r} ({u.region_cells} cells, "
                         f"error {u.region_error_pct:+.1f} %) {'accepted' if u.accepted else 'rejected'}, validation "
                         f"error new {100 * u.validation_error_new:.1f} % vs old {100 * u.validation_error_old:.1f} %")
        fc = self.forecast
        if fc["time_s"].size:
            ok = np.isfinite(fc["actual_j"]) & (fc["actual_j"] > 0)
            if ok.any():
                err = 100.0 * (fc["energy_j"][ok] - fc["actual_j"][ok]) / fc["actual_j"][ok]
                inside = (fc["low_j"][ok] <= fc["actual_j"][ok]) & (fc["actual_j"][ok] <= fc["high_j"][ok])
                lines.append(f"remaining-energy forecast vs what was then drawn: median |error| "
                             f"{np.median(np.abs(err)):.1f} %, inside its {100 * nav.settings.interval_level:.0f} % "
                             f"interval at {100 * inside.mean():.0f} % of {int(ok.sum())} checkpoints")
        if self.unused_s > 0:
            lines.append(f"{self.unused_s:.1f} s of the recording came after the mission ended (not fed)")
        return "\n".join(lines)

    def to_dict(self) -> dict[str, Any]:
        """The content of ``replay.json``."""
        nav = self.navigator
        return result_document("replay", REPLAY_FORMAT_VERSION, {
            "mode": self.mode, "status": nav.status if nav.finished else "under_way",
            "reason": nav.reason if nav.finished else "", "resumed": self.resumed,
            "chunks": self.chunks, "unused_s": self.unused_s, "wall_time_s": self.wall_time_s,
            "drive_time_s": self.drive_time_s,
            "adaptive": nav.result().to_dict(series_every=10),
            "model_map_before": self.model_map_before.tolist(), "model_map_after": self.model_map_after.tolist(),
            "decisions": list(self.decisions),
            "forecast": {k: json_finite(v) for k, v in self.forecast.items()},
        })

    def plot(self, path: str | os.PathLike[str] | None = None, *, ax: Any = None) -> Any:
        """Model map before / after with the routes, the remaining energy's forecast against the
        actual, the state of charge (:func:`~planner.missions.replay_figure.plot_replay`)."""
        return plot_replay(self, path, ax=ax)

    def write(self, out_dir: str | os.PathLike[str], *, mcap: bool = True, on_figure_error: str = "warn") -> list[Path]:
        """Write ``replay.json``, ``replay.png`` (a failing figure warns) and ``replay.mcap``; the files written."""
        out = Path(out_dir)
        written = write_answer(out, {"replay.json": lambda p: write_result_json(p, self.to_dict())},
                               {"replay.png": self.plot}, on_figure_error=on_figure_error)
        if mcap:
            fc = self.forecast
            written.append(write_replay_bag(
                out / "replay.mcap", self.navigator.terrain, replans=self.replans,
                forecasts={"time_s": fc["time_s"], "energy_j": fc["energy_j"], "low_j": fc["low_j"],
                           "high_j": fc["high_j"], "actual_j": fc["actual_j"], "soc": fc["soc"]},
                decisions=[(float(d["time_s"]), d) for d in self.decisions],
                start_time_ns=self.navigator.start_time_ns or 0))
        return written


def _forecast_series(nav: Navigator) -> dict[str, np.ndarray]:
    """The forecast at each checkpoint decision against the energy the legs after it then drew
    (driving only: a manoeuvre is not part of any route's forecast); NaN unless the mission completed."""
    rows = [d for d in nav.decisions if d.get("forecast") is not None and d.get("checkpoint") is not None]
    t = np.array([float(d["time_s"]) for d in rows])

    def get(k: str) -> np.ndarray:
        return np.array([np.nan if d["forecast"][k] is None else float(d["forecast"][k]) for d in rows])

    if nav.finished and nav.status == "completed":  # the driving energy of the legs after each checkpoint
        legs = np.array([leg.actual_energy_j for leg in nav.legs])
        after = np.concatenate((np.cumsum(legs[::-1])[::-1], [0.0]))
        actual = np.array([after[int(d["checkpoint"]) + 1] for d in rows])
    else:
        actual = np.full(t.size, np.nan)
    return {"time_s": t, "energy_j": get("energy_j"), "low_j": get("low_j"), "high_j": get("high_j"),
            "actual_j": actual, "soc": get("soc")}


def replay_drive(
    navigator: Navigator,
    logs: Sequence[InteractionLog],
    *,
    feed: ReplayFeed | None = None,
) -> ReplayResult:
    """Feed a recorded drive through a navigator in time order (see the module docstring).

    Parameters
    ----------
    navigator : Navigator
        A navigator that has not planned yet (it plans from the recording's first pose), or one
        restored from a saved state (:meth:`Navigator.load`): it resumes, skipping the data it
        had already seen.
    logs : sequence of InteractionLog
        The recording (:func:`energy.io.read_logs` of a folder, a bag, an MCAP or a CSV log);
        every drive log needs poses.
    feed : ReplayFeed, optional
        Legs or chunks, the pace, where the navigator's state is saved and who hears its
        decisions (:class:`~planner.missions.settings.ReplayFeed`; default ``ReplayFeed()``).

    Returns
    -------
    ReplayResult

    Raises
    ------
    InvalidParameterError
        Not a navigator or a feed; no logs.
    DataError
        A drive log without poses, overlapping logs, data refused by the navigator (named).
    """
    nav = check_instance("navigator", navigator, Navigator)
    feed = ReplayFeed() if feed is None else check_instance("feed", feed, ReplayFeed)
    items = drive_items(list(logs))
    if not items:
        raise InvalidParameterError("the recording holds no logs")
    n_drive = sum(kind == "drive" for kind, _ in items)
    if n_drive == 0:
        raise InvalidParameterError("the recording holds only manoeuvre runs: nothing was driven")
    mode, chunk_s, speed_up, on_decision = feed.mode, feed.chunk_s, feed.speed_up, feed.on_decision
    mode = ("legs" if len(items) > 1 else "drive") if mode == "auto" else mode
    state, save_every = feed.state_path, feed.save_every
    resumed = nav.phase != "idle"
    if resumed:
        before = np.asarray(nav.model_map_at_start).copy()
    else:
        before = np.asarray(nav.registry.model_id_map).copy()
        first = next(log for kind, log in items if kind == "drive")
        if first.pose_xyh is None:
            raise DataError(f"{first.meta.source!r} holds no poses: a replay needs to know where the robot was")
        t = first.time_s
        period = float(t[1] - t[0]) if t.size > 1 else 0.01
        nav.start_time_ns = first.meta.start_time_ns
        d = nav.plan(tuple(first.pose_xyh[0, :2]), time_s=float(t[0]) - period)
        if on_decision is not None:
            on_decision(d)
    w0 = time.perf_counter()
    t_first = float(items[0][1].time_s[0])
    chunks, saves_due, unused = 0, 0, 0.0
    i = 0
    def report(d: Any) -> None:
        nonlocal saves_due
        if d.action != "continue" and on_decision is not None:
            on_decision(d)
        if d.checkpoint is not None or d.action != "continue":
            saves_due += 1
            if state is not None and saves_due >= save_every and nav.pending_manoeuvre is None and not nav.finished:
                nav.save(state)
                saves_due = 0

    def answer(next_index: int) -> int:
        """Answer the waiting manoeuvre with the recording's manoeuvre runs at ``next_index`` (or decline it);
        the index after them."""
        while nav.pending_manoeuvre is not None:
            runs = []
            while next_index < len(items) and items[next_index][0] == "manoeuvre":
                runs.append(items[next_index][1])
                next_index += 1
            report(nav.observe_manoeuvre(runs) if runs else nav.decline_manoeuvre("not in the recording"))
        return next_index

    i = 0
    while i < len(items):
        kind, log = items[i]
        if nav.finished:
            unused += sum(float(lg.duration_s) for k, lg in items[i:] if k == "drive" and lg.time_s[-1] > nav.time_s)
            break
        if nav.pending_manoeuvre is not None:  # waiting since a checkpoint at the end of the last drive log
            i = answer(i)
            continue
        if kind == "manoeuvre" or float(log.time_s[-1]) <= nav.time_s:  # not asked for here, or seen before a restart
            i += 1
            continue
        if mode == "legs":
            rest = log if float(log.time_s[0]) > nav.time_s else log.slice(nav.time_s + 1e-12, float(log.time_s[-1]) + 1.0)
            pieces = [rest]
        else:
            pieces = drive_chunks(log, chunk_s, nav.time_s)
        i += 1
        for n, piece in enumerate(pieces):
            if nav.finished:
                break
            if speed_up is not None:
                ahead = (float(piece.time_s[-1]) - t_first) / speed_up - (time.perf_counter() - w0)
                if ahead > 0:
                    time.sleep(ahead)
            report(nav.observe(piece, checkpoint=True if mode == "legs" else None))
            chunks += 1
            if nav.pending_manoeuvre is not None:  # runs recorded after this log answer it; mid-log: declined
                i = answer(i) if n == len(pieces) - 1 else answer(len(items))
    if state is not None:
        nav.save(state)
    drive_s = float(max(float(lg.time_s[-1]) for _, lg in items) - t_first)
    return ReplayResult(navigator=nav, model_map_before=before, model_map_after=np.asarray(nav.registry.model_id_map).copy(),
                        decisions=tuple(nav.decisions), forecast=_forecast_series(nav), mode=mode, chunks=chunks,
                        unused_s=unused, resumed=resumed, wall_time_s=time.perf_counter() - w0, drive_time_s=drive_s)
