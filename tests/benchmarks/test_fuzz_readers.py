"""The readers' fuzz run (benchmarks/fuzz_readers.py), small: mutated real files under a 1 GiB address-space limit
give a library error or a correct result — no uncaught exception, no hang."""

from __future__ import annotations

import json
import os
import subprocess
import sys
from pathlib import Path

import pytest

FUZZ = Path(__file__).resolve().parents[2] / "benchmarks" / "fuzz_readers.py"


@pytest.mark.skipif(sys.platform != "linux", reason="the fuzz workers use fork, RLIMIT_AS and /proc (Linux)")
def test_mutated_files_give_library_errors_or_results_under_a_memory_limit(tmp_path):
    pytest.importorskip("rasterio", reason="the GeoTIFF seed needs the geo extra")
    pytest.importorskip("rosbags", reason="the bag seed needs the ros extra")
    out = tmp_path / "fuzz.json"
    env = dict(os.environ, MPLBACKEND="Agg")
    run = subprocess.run([sys.executable, str(FUZZ), "--n", "540", "--workers", "1", "--seed", "7", "--timeout-s", "60",
                          "--out", str(out)], capture_output=True, text=True, env=env, timeout=280)
    report = json.loads(out.read_text())
    assert run.returncode == 0, report["defects"][:5]
    assert report["n_defects"] == 0 and report["memory_gib"] == 1.0
    counts = report["counts"]
    assert sum(counts["all"].values()) == 540
    assert counts["all"].get("library error", 0) > 0 and counts["all"].get("ok", 0) > 0  # both answers occur
    assert set(counts) - {"all"} == {"model", "estimator_model", "map", "csv_log", "borealtc_pro", "geotiff", "rosbag",
                                     "pairs", "robot", "csv_layout", "landcover_classes", "interval_model"}
    assert all(counts[kind].get("library error", 0) > 0 for kind in set(counts) - {"all"})  # every reader is reached
