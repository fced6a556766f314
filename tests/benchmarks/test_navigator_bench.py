"""The navigator benchmark (benchmarks/navigator_bench.py) with --quick: a small map, a 2-minute drive; the table and
the JSON have their structure (never their times: the machine may be shared)."""

from __future__ import annotations

import json
import os
import subprocess
import sys
from pathlib import Path

import pytest

BENCH = Path(__file__).resolve().parents[2] / "benchmarks" / "navigator_bench.py"
CALL_KINDS = {"observe", "checkpoint_no_update", "checkpoint_update_rejected", "checkpoint_update_repair"}


@pytest.fixture(scope="module")
def quick(tmp_path_factory):
    tmp = tmp_path_factory.mktemp("navigator_bench")
    out = tmp / "nb.json"
    env = dict(os.environ, MPLBACKEND="Agg")
    run = subprocess.run([sys.executable, str(BENCH), "--quick", "--seed", "3", "--profile", "always", "--no-pin",
                          "--out", str(out), "--cache-dir", str(tmp / "cache")],
                         capture_output=True, text=True, env=env, timeout=240, cwd=tmp)
    assert run.returncode == 0, run.stderr[-3000:]
    return {"doc": json.loads(out.read_text()), "stdout": run.stdout, "cache": tmp / "cache"}


def test_the_table_has_its_four_parts_and_the_targets(quick):
    text = quick["stdout"]
    for head in ("1. replay_drive", "2. call latency", "3. beside the simulated loop", "4. save / load and memory",
                 "targets:", "benchmark wall time", "profile (replay_chunk_0.1s)", "profile (replay_chunk_1s)"):
        assert head in text, head


def test_the_drive_is_two_minutes_at_15_hz_with_the_imu_at_100_hz_and_is_cached(quick):
    doc = quick["doc"]
    d = doc["drive"]
    assert doc["map_cells"] == [96, 96] and doc["quick"] is True and doc["seed"] == 3
    assert d["duration_s"] == pytest.approx(120.0, abs=0.2)
    assert d["drive_rate_hz"] == pytest.approx(15.0, rel=1e-3) and d["imu_rate_hz"] == pytest.approx(100.0, rel=1e-3)
    assert d["cached"] is False and list(quick["cache"].glob("navigator_bench_drive_*.npz"))
    assert sum(d["ground_share"].values()) == pytest.approx(1.0)
    assert doc["machine"]["numba_threads"] in (1, None)
    assert doc["machine"]["threads_env"]["OMP_NUM_THREADS"] == "1"


def test_replays_calls_and_cutting_for_both_chunk_sizes(quick):
    doc = quick["doc"]
    for key in ("replay", "calls", "cutting"):
        assert [r["chunk_s"] for r in doc[key]] == [0.1, 1.0], key
    for r in doc["replay"]:
        assert r["chunks"] > 0 and r["wall_s"] > 0 and r["real_time_factor"] > 0
        assert r["drive_s"] == pytest.approx(doc["drive"]["duration_s"], abs=0.2)
        assert r["status"] in ("under_way", "completed") and r["checkpoints"] >= 1
    assert doc["replay_default_policy"]["min_samples"] == 50 and doc["replay"][0]["min_samples"] == 8
    for r in doc["calls"]:
        assert set(r["calls"]) == CALL_KINDS
        assert sum(s["n"] for s in r["calls"].values()) == r["chunks"]
        obs = r["calls"]["observe"]
        assert obs["n"] > 0 and obs["p50_ms"] <= obs["p99_ms"] <= obs["max_ms"]
        for e in r["update_repair_events"]:
            assert {"drive_s", "wall_ms", "grounds", "fit_validate_ms", "refresh_ms", "search_ms"} <= set(e)
        assert len(r["update_repair_events"]) == r["calls"]["checkpoint_update_repair"]["n"]
    for r in doc["cutting"]:
        assert r["chunks"] > 0 and r["replay_cut_s"] > 0 and r["index_cut_s"] > 0


def test_simulated_loop_ratios_targets_and_profile(quick):
    doc = quick["doc"]
    sim = doc["simulated"]
    assert sim["missions"] and sim["drive_s"] > 0 and sim["wall_s"] > 0
    assert sim["navigator_share"] + sim["simulator_share"] + sim["client_share"] == pytest.approx(1.0)
    assert 0.0 <= sim["navigator_share"] <= 1.0 and 0.0 <= sim["simulator_share"] <= 1.0
    assert {"chunk_0.1s", "chunk_1s", "simulated_navigator_over_simulator"} <= set(doc["ratios"])
    assert set(doc["targets_met"]) == {"replay_0.1s_real_time", "replay_1s_real_time", "observe_p99", "update_repair"}
    assert all(isinstance(v, bool) for v in doc["targets_met"].values())
    assert doc["targets"] == {"real_time_factor": 60.0, "observe_p99_ms": 5.0, "update_repair_ms": 100.0}
    prof = doc["profile"]
    assert set(prof) == {"replay_chunk_0.1s", "replay_chunk_1s"}
    for p in prof.values():
        assert p["by_own_time"] and p["by_cumulative"] and p["trees"]["replay_drive"]["found"]
    assert prof["replay_chunk_0.1s"]["trees"]["observe"]["found"]


def test_save_and_memory(quick):
    lat = quick["doc"]["calls"][0]
    assert [round(s["drive_s"]) for s in lat["saves"]] == [30, 120]
    for s in lat["saves"]:
        assert s["bytes"] > 0 and s["save_s"] > 0 and s["load_s"] > 0
        assert {"navigator.json", "state.npz", "registry"} <= set(s["parts_bytes"])
    assert lat["save_profile"]["found"]
    assert len(lat["rss"]) >= 2 and all(r["rss_mib"] > 0 for r in lat["rss"])
    h = lat["held"]
    assert h["series_samples"] > 0 and h["history_s"] <= 600.0 + 60.0
    assert quick["doc"]["peak_rss_mib"] >= lat["memory"]["peak_rss_after_loop_mib"] > 0
