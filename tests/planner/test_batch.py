"""plan_batch, BatchPairs / the pairs and sites CSVs, BatchResult, the dask client seam and ``terrawatt batch``."""

from __future__ import annotations

import dataclasses
import json
import math
import socket
import sys
import time

import numpy as np
import pytest
from batch_samples import EAST, EAST_LOW, ON_WALL, PAIRS, WEST, cost  # noqa: F401  (fixture)

import terrain
from planner import BatchPairs, plan_batch, plan_route, read_pairs_csv
from planner.batch_pairs import read_sites_csv
from planner.batch_result import BatchRow
from planner.cost_spec import CostSpec
from planner.planning import RouteSearch
from terrawatt_base.dask_client import Compute, dask_client
from terrawatt_base.errors import (
    DataError,
    FileFormatError,
    InvalidParameterError,
    OptionalDependencyError,
    UnknownNameError,
)
from terrawatt_cli import main

_NO_DASK = "planning on a cluster needs the distributed extra (dask[distributed])"


@pytest.fixture
def local_client():
    """An in-process dask cluster of two single-thread workers."""
    distributed = pytest.importorskip("distributed", reason=_NO_DASK)
    with distributed.LocalCluster(processes=False, n_workers=2, threads_per_worker=1,
                                  dashboard_address=":0") as cluster, distributed.Client(cluster) as client:
        yield client


def _outcome(row: BatchRow) -> dict:
    """A row without its planning time (the only field measured, not computed)."""
    d = dataclasses.asdict(row)
    d.pop("planning_time_s")
    return d


# ------------------------------------------------------------------ in process
def test_in_process_rows_are_plan_route_with_its_comparison_in_pair_order(cost, wall_map):
    res = plan_batch(cost, PAIRS)
    assert [r.name for r in res.rows] == ["0", "1", "2", "3"]
    assert res.where == "in process" and res.n_workers == 1 and res.planner == "lattice"
    for row, pair in zip(res.rows, PAIRS):
        route = plan_route(wall_map, pair[:2], pair[2:], cost=cost, planner="lattice", seed=0, compare=True)
        assert row.status == "exact" == route.status
        assert row.energy_j == route.energy_j and row.length_m == route.length_m
        assert row.energy_wh == pytest.approx(row.energy_j / 3600.0)
        assert row.duration_s == route.duration_s
        assert row.energy_saved_pct == route.energy_saved_pct
        assert (row.start_x_m, row.start_y_m, row.goal_x_m, row.goal_y_m) == tuple(pair)
    # through the gap in the wall: much longer than the straight line
    assert res.rows[0].length_m > 40.0
    assert res.n_found == 4 and res.n_errors == 0


def test_a_pair_that_raises_is_reported_and_the_others_are_planned(cost):
    pairs = [[*WEST, *EAST], [*ON_WALL, *EAST], [*EAST, *ON_WALL], [*EAST, *WEST]]
    res = plan_batch(cost, BatchPairs.from_array(pairs, ["ok1", "from-wall", "to-wall", "ok2"]))
    assert [r.status for r in res.rows] == ["exact", "error", "error", "exact"]
    assert res.rows[1].error.startswith("BlockedPositionError: start_xy_m (20.5, 10.5) m lies on an obstacle")
    assert res.rows[2].error.startswith("BlockedPositionError: goal_xy_m (20.5, 10.5) m lies on an obstacle")
    assert math.isnan(res.rows[1].energy_j) and res.rows[0].error == ""
    assert res.n_errors == 2 and res.count("exact") == 2
    assert "error in pair 'from-wall': BlockedPositionError" in res.summary()


def test_disconnected_pairs_are_infeasible_rows():
    closed = terrain.wall_map((40, 40), 1.0, wall_col=20, gap_rows=(0, 0), ground="asphalt")
    res = plan_batch(CostSpec().build(closed), [[*WEST, *EAST]])
    assert res.rows[0].status == "infeasible" and math.isnan(res.rows[0].energy_j) and res.n_found == 0


# ------------------------------------------------------------------ on a dask cluster
def test_a_local_cluster_plans_the_in_process_rows(cost, local_client):
    pairs = [*PAIRS, [*ON_WALL, *WEST]]
    here = plan_batch(cost, pairs)
    there = plan_batch(cost, pairs, compute=Compute(client=local_client, progress=True))
    assert there.where == "given client" and there.n_workers == 2
    assert [_outcome(r) for r in there.rows] == [_outcome(r) for r in here.rows]
    assert there.rows[-1].status == "error" and "BlockedPositionError" in there.rows[-1].error


def test_the_cost_goes_to_the_workers_once_without_its_caches(cost, local_client):
    plan_batch(cost, PAIRS)  # fills the caller's caches
    assert cost.lattices and len(cost.results)
    submitted = []
    original = local_client.submit

    def spy(fn, *args, **kwargs):
        submitted.append(args)
        return original(fn, *args, **kwargs)

    local_client.submit = spy
    try:
        plan_batch(cost, PAIRS, compute=Compute(client=local_client))
    finally:
        local_client.submit = original
    from distributed import Future

    (held,), tasks = submitted[0], submitted[1:]  # the cost as a task of its own, then the pairs' tasks
    assert not held.lattices and not len(held.results) and held.terrain is cost.terrain
    assert len(tasks) == 4 and len({a[0].key for a in tasks}) == 1  # one cost, referenced by every task
    assert all(isinstance(a[0], Future) for a in tasks)
    assert cost.lattices and len(cost.results)  # the caller's cost keeps its caches


def test_an_exception_outside_the_library_in_a_task_is_a_row_too(cost, local_client, monkeypatch):
    import planner.batch as batch_module

    def broken(*args, **kwargs):
        raise ZeroDivisionError("boom")

    monkeypatch.setattr(batch_module, "plan_pair", broken)  # the processes=False workers see the patch
    res = plan_batch(cost, PAIRS[:2], compute=Compute(client=local_client))
    assert [r.error for r in res.rows] == ["ZeroDivisionError: boom"] * 2
    here = plan_batch(cost, PAIRS[:2])
    assert [r.error for r in here.rows] == ["ZeroDivisionError: boom"] * 2


def test_a_task_that_fails_outside_planning_is_a_row_and_the_batch_goes_on(cost, local_client, monkeypatch):
    """A task whose future raises (a worker that dies, an argument that does not deserialise) is its pair's error
    row: the other pairs' rows are kept."""
    import planner.batch as batch_module

    real = batch_module._plan_pair_task

    def dies_on_the_second(cost, name, start_xy_m, *args):
        if tuple(start_xy_m) == tuple(EAST):  # PAIRS[1], the only one of the three starting there
            raise RuntimeError("worker lost")
        return real(cost, name, start_xy_m, *args)

    monkeypatch.setattr(batch_module, "_plan_pair_task", dies_on_the_second)
    for compute in (Compute(client=local_client), Compute()):
        res = plan_batch(cost, PAIRS[:3], compute=compute)
        assert [r.status for r in res.rows][1] == "error" and res.rows[1].error == "RuntimeError: worker lost"
        assert res.rows[0].status != "error" and res.rows[2].status != "error"


def test_a_pair_that_kills_its_workers_is_an_error_row_and_the_other_pairs_are_planned(cost):
    """The poison pair kills each worker dask retries it on (both, and their new ones): the cost they held is
    computed again, the other five pairs come back as in process, the poison pair is a KilledWorker row."""
    distributed = pytest.importorskip("distributed", reason=_NO_DASK)
    import dask
    from dask_samples import PoisonPair

    pairs = BatchPairs.from_array([*PAIRS, [*WEST, *EAST], [*EAST, *EAST_LOW]], ["a", "b", "poison", "d", "e", "f"])
    here = plan_batch(cost, pairs)
    with dask.config.set({"distributed.comm.timeouts.connect": "5s"}), distributed.LocalCluster(
        n_workers=2, processes=True, threads_per_worker=1, dashboard_address=":0"
    ) as cluster, distributed.Client(cluster) as client:
        client.register_plugin(PoisonPair("poison"))  # on the workers the nannies start too
        there = plan_batch(cost, pairs, compute=Compute(client=client))
    assert [r.status for r in there.rows] == ["exact", "exact", "error", "exact", "exact", "exact"]
    assert there.rows[2].error.startswith("KilledWorker") and there.n_errors == 1
    keep = [0, 1, 3, 4, 5]
    assert [_outcome(there.rows[i]) for i in keep] == [_outcome(here.rows[i]) for i in keep]


# ------------------------------------------------------------------ pairs and their files
def test_pairs_from_arrays_of_both_layouts_and_all_pairs_of_sites():
    a = BatchPairs.from_array(np.array(PAIRS))
    b = BatchPairs.from_array(np.array(PAIRS).reshape(-1, 2, 2), names=list("abcd"))
    assert np.array_equal(a.starts_xy_m, b.starts_xy_m) and np.array_equal(a.goals_xy_m, b.goals_xy_m)
    assert b.names == ("a", "b", "c", "d") and len(a) == 4
    assert not a.starts_xy_m.flags.writeable
    sites = BatchPairs.all_pairs([WEST, EAST, EAST_LOW], ["w", "e", "s"])
    assert len(sites) == 6 and sites.names[:2] == ("w->e", "w->s")
    assert np.array_equal(sites.starts_xy_m[2], EAST) and np.array_equal(sites.goals_xy_m[2], WEST)


@pytest.mark.parametrize(
    ("pairs", "kwargs", "error", "match"),
    [
        ([[1.0, 2.0, 3.0]], {}, InvalidParameterError, r"pairs must have shape \(N, 4\)"),
        ([[1.0, np.nan, 3.0, 4.0]], {}, InvalidParameterError, r"pairs row 0 has NaN/inf coordinates"),
        (np.empty((0, 4)), {}, InvalidParameterError, "at least one"),
        ([["a", "b", "c", "d"]], {}, InvalidParameterError, "must be a real number"),
        (PAIRS, {"names": ["x"]}, InvalidParameterError, "names must be 4 non-empty strings"),
        (PAIRS, {"names": ["x", "y", "x", "z"]}, InvalidParameterError, "'x' appears 2 times"),
    ],
)
def test_bad_pairs_are_refused(cost, pairs, kwargs, error, match):
    with pytest.raises(error, match=match):
        plan_batch(cost, BatchPairs.from_array(pairs, **kwargs))


def test_sites_need_two_and_unique_names():
    with pytest.raises(InvalidParameterError, match="at least 2 sites"):
        BatchPairs.all_pairs([WEST])
    with pytest.raises(InvalidParameterError, match="'a' appears 2 times"):
        BatchPairs.all_pairs([WEST, EAST], ["a", "a"])


def test_a_point_outside_the_map_is_an_error_row_like_any_failed_pair(cost):
    res = plan_batch(cost, [[*WEST, *EAST], [*WEST, 55.0, 5.0]])  # one rule for per-item failures
    assert [r.status for r in res.rows] == ["exact", "error"]
    assert res.rows[1].error.startswith("OutOfBoundsError") and "outside" in res.rows[1].error


def _write(path, text):
    path.write_text(text)
    return path


def test_a_pairs_csv_is_read_with_its_names(tmp_path, cost):
    f = _write(tmp_path / "p.csv", "name,start_x_m,start_y_m,goal_x_m,goal_y_m\nthere,5.5,10.5,35.5,10.5\nback,35.5,10.5,5.5,10.5\n")
    pairs = read_pairs_csv(f)
    assert pairs.names == ("there", "back")
    res = plan_batch(cost, pairs)
    assert res.rows[0].energy_j != res.rows[1].energy_j or res.rows[0].status == "exact"
    names, xy = read_sites_csv(_write(tmp_path / "s.csv", "x_m,y_m\n1,2\n3,4\n"))
    assert names == ("0", "1") and xy.tolist() == [[1.0, 2.0], [3.0, 4.0]]


@pytest.mark.parametrize(
    ("text", "error", "match"),
    [
        ("start_x_m,start_y_m,goal_x_m\n1,2,3\n", FileFormatError, r"lacks the column\(s\) \['goal_y_m'\]"),
        ("", FileFormatError, r"lacks the column"),
        ("start_x_m,start_y_m,goal_x_m,goal_y_m\n", DataError, "has a header but no rows"),
        ("start_x_m,start_y_m,goal_x_m,goal_y_m\n1,2,3,4\n1,nan,3,4\n", DataError, r"line 3: column 'start_y_m' is 'nan'"),
        ("start_x_m,start_y_m,goal_x_m,goal_y_m\n1,2,3,east\n", DataError, r"line 2: column 'goal_y_m' is 'east'"),
        ("start_x_m,start_y_m,goal_x_m,goal_y_m\n1,2,3\n", DataError, r"line 2: column 'goal_y_m' is ''"),
        ("name,start_x_m,start_y_m,goal_x_m,goal_y_m\na,1,2,3,4\na,1,2,3,5\n", DataError, "the name 'a' is used twice"),
        ("name,start_x_m,start_y_m,goal_x_m,goal_y_m\n,1,2,3,4\n", DataError, "line 2: the name is empty"),
    ],
)
def test_bad_pairs_files_are_refused_with_the_line_and_column(tmp_path, text, error, match):
    with pytest.raises(error, match=match):
        read_pairs_csv(_write(tmp_path / "p.csv", text))


def test_a_missing_pairs_file_is_a_file_not_found_error(tmp_path):
    with pytest.raises(FileNotFoundError):
        read_pairs_csv(tmp_path / "none.csv")


# ------------------------------------------------------------------ bad arguments
@pytest.mark.parametrize(
    ("kwargs", "error", "match"),
    [
        ({"planner": "Dijkstra"}, UnknownNameError, "planner must be one of"),
        ({"planner": "lattice", "seed": -1}, InvalidParameterError, "seed must be None or an integer"),
        ({"planner": "lattice", "settings": {"lattice_stride_cells": 2}}, InvalidParameterError,
         "settings must be a PlannerSettings"),
        ({"planner": "lattice", "time_limit_s": 0.0}, InvalidParameterError, "time_limit_s must be > 0"),
        ({"planner": "lattice", "max_cost_evaluations": 0}, InvalidParameterError, "max_cost_evaluations must be >= 1"),
        ({"planner": "RRTstar", "time_limit_s": None}, InvalidParameterError, "give at least one budget"),
    ],
)
def test_a_bad_search_is_refused_when_made(kwargs, error, match):
    with pytest.raises(error, match=match):
        RouteSearch(**kwargs)


@pytest.mark.parametrize(("kwargs", "match"), [
    ({"compute": "tcp://127.0.0.1:8786"}, "compute must be a Compute"),
    ({"search": "lattice"}, "search must be a RouteSearch"),
])
def test_bad_arguments_are_refused(cost, kwargs, match):
    with pytest.raises(InvalidParameterError, match=match):
        plan_batch(cost, PAIRS, **kwargs)


def test_a_cost_that_is_not_an_energy_cost_is_refused(wall_map):
    with pytest.raises(InvalidParameterError, match="cost must be an EnergyCost, got 'TerrainMap'"):
        plan_batch(wall_map, PAIRS)


@pytest.mark.parametrize(
    ("kwargs", "match"),
    [
        ({"client": "tcp://127.0.0.1:8786"}, r"client must be None .* or a distributed\.Client"),
        ({"workers": 0}, "workers must be a positive number of processes"),
        ({"progress": "yes"}, "progress must be True or False"),
        ({"where": "over there"}, "where names a given client"),
    ],
)
def test_a_bad_compute_is_refused_when_made(kwargs, match):
    with pytest.raises(InvalidParameterError, match=match):
        Compute(**kwargs)


def test_a_client_excludes_workers_and_scheduler(local_client):
    for extra in ({"workers": 2}, {"scheduler": "tcp://127.0.0.1:1"}):
        with pytest.raises(InvalidParameterError, match="client excludes workers and scheduler") as err:
            Compute(client=local_client, **extra)
        assert err.value.parameter == ("client", "workers", "scheduler")


def _free_port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


def test_an_unreachable_scheduler_is_a_clear_error_after_the_timeout():
    pytest.importorskip("distributed", reason=_NO_DASK)
    address = f"tcp://127.0.0.1:{_free_port()}"
    with pytest.raises(InvalidParameterError, match=rf"`scheduler` '{address}': cannot connect to a dask scheduler"):
        with dask_client(scheduler=address, timeout_s=0.5):
            pass
    with pytest.raises(InvalidParameterError, match=r"`scheduler` 'nowhere': cannot connect"):
        with dask_client(scheduler="nowhere", timeout_s=0.5):
            pass


class _Server:
    """A TCP server on a free local port that accepts and then says ``reply`` (nothing: b"") and keeps the line open."""

    def __init__(self, reply: bytes) -> None:
        import threading

        self.sock = socket.socket()
        self.sock.bind(("127.0.0.1", 0))
        self.sock.listen(4)
        self.address = f"tcp://127.0.0.1:{self.sock.getsockname()[1]}"
        self.reply, self.conns, self.stop = reply, [], threading.Event()
        self.thread = threading.Thread(target=self._serve, daemon=True)
        self.thread.start()

    def _serve(self) -> None:
        self.sock.settimeout(0.1)
        while not self.stop.is_set():
            try:
                conn, _ = self.sock.accept()
            except OSError:
                continue
            self.conns.append(conn)
            if self.reply:
                conn.sendall(self.reply)

    def close(self) -> None:
        self.stop.set()
        self.thread.join()
        for c in self.conns:
            c.close()
        self.sock.close()


@pytest.mark.parametrize("reply", [b"", b"\xff" * 64 + b"not dask at all"], ids=["silent", "junk"])
def test_a_scheduler_that_never_completes_the_handshake_is_a_clear_error_not_a_hang(reply):
    pytest.importorskip("distributed", reason=_NO_DASK)
    server = _Server(reply)
    try:
        with pytest.raises(InvalidParameterError, match=rf"`scheduler` '{server.address}': (no dask scheduler answered|"
                                                        "cannot connect)"):
            with dask_client(scheduler=server.address, timeout_s=0.5):
                pass
        # it did connect: the deadline covered the handshake. On a loaded machine the abandoned connect thread may
        # still be starting dask's client when the deadline passes; it connects afterwards: wait for it (bounded)
        deadline = time.monotonic() + 30.0
        while not server.conns and time.monotonic() < deadline:
            time.sleep(0.05)
        assert server.conns
    finally:
        server.close()


def test_dask_client_refuses_workers_with_a_scheduler_and_names_the_missing_extra(monkeypatch):
    with pytest.raises(InvalidParameterError, match="workers 2 and scheduler 'tcp://h:1' exclude each other") as err:
        with dask_client(2, "tcp://h:1"):
            pass
    assert err.value.parameter == ("workers", "scheduler")
    with pytest.raises(InvalidParameterError, match="workers must be >= 1"):
        with dask_client(0):
            pass
    monkeypatch.setitem(sys.modules, "distributed", None)  # `import distributed` now raises ImportError
    with pytest.raises(OptionalDependencyError, match=r"workers 3 needs dask.distributed; install it with"):
        with dask_client(3):
            pass


# ------------------------------------------------------------------ terrawatt batch
def _pairs_file(tmp_path, rows):
    lines = ["name,start_x_m,start_y_m,goal_x_m,goal_y_m", *(",".join(map(str, r)) for r in rows)]
    return _write(tmp_path / "pairs.csv", "\n".join(lines) + "\n")


def test_cli_batch_writes_its_files_and_exits_0_when_every_pair_has_a_route(tmp_path, capsys):
    f = _pairs_file(tmp_path, [("a", 10, 10, 150, 150), ("b", 150, 150, 10, 10)])
    rc = main(["batch", "--map", "example", "--pairs", str(f), "--out", str(tmp_path / "out"), "--no-progress"])
    out = capsys.readouterr().out
    assert rc == 0
    assert "2 pairs (2 exact) planned with lattice" in out and "median energy saved vs the shortest route" in out
    data = json.loads((tmp_path / "out" / "batch.json").read_text())
    assert [r["name"] for r in data["rows"]] == ["a", "b"] and data["where"] == "in process"
    assert (tmp_path / "out" / "batch.csv").read_text().startswith("name,start_x_m,")


def test_cli_batch_all_pairs_of_sites_with_a_blocked_site_exits_1(tmp_path, capsys):
    f = _write(tmp_path / "sites.csv", "name,x_m,y_m\na,10,10\nb,150,150\nrock,58.5,28.5\n")
    rc = main(["batch", "--map", "example", "--sites", str(f), "--all-pairs", "--out", str(tmp_path / "out"),
               "--no-progress"])
    out = capsys.readouterr().out
    assert rc == 1
    assert "6 pairs (2 exact, 4 error)" in out and "error in pair 'a->rock': BlockedPositionError" in out
    assert len(json.loads((tmp_path / "out" / "batch.json").read_text())["rows"]) == 6


def test_cli_batch_on_a_scheduler_address(tmp_path, capsys):
    distributed = pytest.importorskip("distributed", reason=_NO_DASK)
    f = _pairs_file(tmp_path, [("a", 10, 10, 150, 150), ("b", 20, 140, 140, 20)])
    rc0 = main(["batch", "--map", "example", "--pairs", str(f), "--out", str(tmp_path / "here"), "--no-progress"])
    # a worker process, as a real scheduler has: a second client on an in-process (processes=False)
    # cluster from the same process shares its event loop thread, and hung once in a full-suite run
    with distributed.LocalCluster(processes=True, n_workers=1, threads_per_worker=1,
                                  dashboard_address=":0") as cluster:
        rc = main(["batch", "--map", "example", "--pairs", str(f), "--scheduler", cluster.scheduler_address,
                   "--out", str(tmp_path / "there"), "--no-progress"])
    assert rc0 == rc == 0
    assert "(in process)" in capsys.readouterr().out
    here = json.loads((tmp_path / "here" / "batch.json").read_text())["rows"]
    there = json.loads((tmp_path / "there" / "batch.json").read_text())
    assert there["where"] == cluster.scheduler_address
    assert [{k: v for k, v in r.items() if k != "planning_time_s"} for r in there["rows"]] == [
        {k: v for k, v in r.items() if k != "planning_time_s"} for r in here
    ]


@pytest.mark.parametrize(
    ("extra", "message"),
    [
        (["--sites", "S"], "--sites needs --all-pairs"),
        (["--pairs", "P", "--all-pairs"], "--all-pairs needs --sites CSV"),
        (["--pairs", "P", "--workers", "0"], "--workers must be a positive number of processes, got 0"),
        (["--pairs", "P", "--workers", "2", "--scheduler", "tcp://127.0.0.1:1"], "exclude each other"),
        (["--pairs", "BADCOLS"], "lacks the column(s) ['goal_x_m', 'goal_y_m']"),
        (["--pairs", "P", "--speed", "0"], "--speed must be a number > 0"),
        (["--pairs", "P", "--max-evaluations", "0"], "--max-evaluations must be a number > 0"),
    ],
)
def test_cli_batch_bad_input_exits_2_with_one_line_and_writes_nothing(tmp_path, capsys, extra, message):
    good = _pairs_file(tmp_path, [("a", 10, 10, 150, 150)])
    bad = _write(tmp_path / "bad.csv", "start_x_m,start_y_m\n1,2\n")
    argv = [{"P": str(good), "S": str(good), "BADCOLS": str(bad)}.get(a, a) for a in extra]
    rc = main(["batch", "--map", "example", *argv, "--out", str(tmp_path / "out"), "--no-progress"])
    err = capsys.readouterr().err
    assert rc == 2 and message in err and len(err.strip().splitlines()) == 1
    assert not (tmp_path / "out").exists()


def test_cli_batch_checks_the_output_folder_before_reading_anything(tmp_path, capsys):
    (tmp_path / "out").write_text("a file")
    rc = main(["batch", "--map", "example", "--pairs", str(tmp_path / "missing.csv"), "--out", str(tmp_path / "out")])
    assert rc == 2 and "is a file; expected a folder" in capsys.readouterr().err


def test_an_ompl_planner_with_seed_and_work_bound_gives_the_same_rows_on_the_cluster(cost, local_client):
    search = RouteSearch("RRTstar", None, 3000, seed=1)
    here = plan_batch(cost, PAIRS, search=search)
    there = plan_batch(cost, PAIRS, compute=Compute(client=local_client), search=search)
    assert all(r.planning_time_s >= 0 for r in here.rows) and here.n_found == 4
    assert [_outcome(r) for r in there.rows] == [_outcome(r) for r in here.rows]


def test_workers_and_scheduler_open_a_client_through_the_seam(cost, local_client, monkeypatch):
    import contextlib

    import terrawatt_base.dask_client as seam

    calls = []

    @contextlib.contextmanager
    def fake_dask_client(workers, scheduler, quiet):
        calls.append((workers, scheduler))
        yield local_client

    monkeypatch.setattr(seam, "dask_client", fake_dask_client)
    on_local = plan_batch(cost, PAIRS[:2], compute=Compute(workers=2))
    on_scheduler = plan_batch(cost, PAIRS[:2], compute=Compute(scheduler="tcp://127.0.0.1:8786"))
    assert calls == [(2, None), (1, "tcp://127.0.0.1:8786")]
    assert on_local.where == "local cluster" and on_scheduler.where == "tcp://127.0.0.1:8786"
    assert on_local.n_workers == 2 and [r.status for r in on_scheduler.rows] == ["exact", "exact"]
