"""Tests of the CLI's safety rules: no command replaces its own input, unwritable outputs fail first, exit codes."""

from __future__ import annotations

import shutil
from pathlib import Path

import numpy as np
import pytest

import terrawatt_cli.plan as plan_cli
from terrain.procedural import example_map
from terrawatt_cli import EXIT_BAD_INPUT, EXIT_CODES, EXIT_INTERNAL, build_parser, main

FIXTURES = Path(__file__).resolve().parents[1] / "fixtures"


def _err(capsys) -> str:
    err = capsys.readouterr().err
    assert "Traceback" not in err and err.count("\n") == 1, err
    return err


def test_reach_refuses_an_output_that_would_replace_its_map(tmp_path, capsys):
    out = tmp_path / "o"
    out.mkdir()
    src = example_map().save(out / "reach.npz")
    before = src.read_bytes()
    rc = main(["reach", "--map", str(src), "--depot", "10", "10", "--battery-ah", "5", "--out", str(out)])
    assert rc == EXIT_BAD_INPUT
    assert "would replace the input" in _err(capsys)
    assert src.read_bytes() == before


def test_batch_refuses_an_output_that_would_replace_its_pairs(tmp_path, capsys):
    out = tmp_path / "o"
    out.mkdir()
    pairs = out / "batch.csv"
    pairs.write_text("name,start_x_m,start_y_m,goal_x_m,goal_y_m\na,10,10,150,150\n")
    before = pairs.read_bytes()
    rc = main(["batch", "--map", "example", "--pairs", str(pairs), "--out", str(out), "--no-progress"])
    assert rc == EXIT_BAD_INPUT
    assert "would replace the input" in _err(capsys)
    assert pairs.read_bytes() == before


def test_train_refuses_to_write_its_model_over_its_data(tmp_path, capsys):
    log = tmp_path / "log.csv"
    shutil.copy(FIXTURES / "written_log.csv", log)
    before = log.read_bytes()
    rc = main(["train", "--data", str(log), "--model", "linear", "--out", str(log)])
    assert rc == EXIT_BAD_INPUT
    assert "would replace the input" in _err(capsys)
    assert log.read_bytes() == before


def test_diagnose_refuses_an_output_that_would_replace_its_model(tmp_path, capsys):
    out = tmp_path / "o"
    model = tmp_path / "m.zip"
    assert main(["train", "--data", str(FIXTURES / "borealtc"), "--model", "linear", "--interval-folds", "0",
                 "--out", str(model)]) == 0
    out.mkdir()
    inside = out / "corrected_model.zip"
    shutil.copy(model, inside)
    before = inside.read_bytes()
    capsys.readouterr()
    rc = main(["diagnose", "--model", str(inside), "--data", str(FIXTURES / "borealtc"), "--out", str(out)])
    assert rc == EXIT_BAD_INPUT
    assert "would replace the input" in _err(capsys)
    assert inside.read_bytes() == before


def test_an_unwritable_output_fails_before_any_work(tmp_path, capsys, monkeypatch):
    import terrawatt_base.atomic as atomic

    def no_write(*args, **kwargs):
        raise PermissionError(13, "Permission denied")

    planned = []
    monkeypatch.setattr(atomic.tempfile, "mkstemp", no_write)
    monkeypatch.setattr(plan_cli, "_run", lambda *a, **k: planned.append(1) or 0)
    rc = main(["demo", "--out", str(tmp_path / "o")])
    assert rc == EXIT_BAD_INPUT
    assert "is not writable: Permission denied" in _err(capsys)
    assert planned == []  # the planner never ran


def test_an_internal_error_exits_3_with_one_line_and_the_traceback_under_v(tmp_path, capsys, monkeypatch):
    def broken(*args, **kwargs):
        raise ZeroDivisionError("a bug")

    monkeypatch.setattr(plan_cli, "_run", broken)
    assert main(["demo", "--out", str(tmp_path / "o")]) == EXIT_INTERNAL
    err = _err(capsys)
    assert "internal error (a bug in terrawatt" in err and "ZeroDivisionError: a bug" in err and "-v" in err
    assert main(["-v", "demo", "--out", str(tmp_path / "o")]) == EXIT_INTERNAL
    assert "Traceback" in capsys.readouterr().err


def test_running_out_of_memory_is_said_as_such_not_as_a_bug(tmp_path, capsys, monkeypatch):
    def exhausted(*args, **kwargs):
        raise MemoryError

    monkeypatch.setattr(plan_cli, "_run", exhausted)
    assert main(["demo", "--out", str(tmp_path / "o")]) == EXIT_BAD_INPUT
    err = _err(capsys)
    assert "ran out of memory" in err and "internal error" not in err


def test_help_lists_the_exit_codes():
    text = build_parser().format_help()
    for code, meaning in EXIT_CODES.items():
        assert f"{code} {meaning.split()[0]}" in " ".join(text.split())
    assert np.array_equal(sorted(EXIT_CODES), [0, 1, 2, 3])


def test_the_writability_probe_leaves_nothing_behind(tmp_path):
    from terrawatt_base.atomic import probe_writable

    probe_writable(tmp_path / "a" / "b")
    assert list(tmp_path.iterdir()) == []
    (tmp_path / "kept").mkdir()
    probe_writable(tmp_path / "kept")
    assert list((tmp_path / "kept").iterdir()) == []


@pytest.mark.skipif(not hasattr(__import__("os"), "mkfifo"), reason="named pipes need a POSIX system")
def test_a_fifo_where_a_file_belongs_is_refused_not_a_hang(tmp_path, capsys):
    import os

    fifo = tmp_path / "log.csv"
    os.mkfifo(fifo)
    assert main(["batch", "--map", "example", "--pairs", str(fifo), "--out", str(tmp_path / "a"), "--no-progress"]) == 2
    assert "is not a regular file" in _err(capsys)
    assert main(["train", "--data", str(fifo), "--model", "linear", "--out", str(tmp_path / "m.zip")]) == 2
    assert "neither a regular file nor a folder" in _err(capsys)


def test_a_binary_pairs_file_is_bad_input_not_a_crash(tmp_path, capsys):
    pairs = tmp_path / "pairs.csv"
    pairs.write_bytes(bytes(range(256)) * 4)
    rc = main(["batch", "--map", "example", "--pairs", str(pairs), "--out", str(tmp_path / "o"), "--no-progress"])
    assert rc == EXIT_BAD_INPUT
    assert "is not a UTF-8 CSV table" in _err(capsys)


def test_messages_show_plain_numbers_not_numpy_reprs(tmp_path, capsys, monkeypatch):
    from terrain import Grid, InvalidParameterError, OutOfBoundsError
    from terrawatt_cli import plain_message

    assert plain_message("got np.float64(10.0) and np.int64(3), np.True_") == "got 10.0 and 3, np.True_"
    with pytest.raises(OutOfBoundsError) as info:
        Grid((4, 5), 1.0).rowcol(np.float64(10.0), np.float64(2.5))
    assert "np." not in str(info.value) and "(10, 2.5) m" in str(info.value)

    def bad(*args, **kwargs):
        raise InvalidParameterError(f"speed {np.float64(10.0)!r} too high")

    monkeypatch.setattr(plan_cli, "_run", bad)
    assert main(["demo", "--out", str(tmp_path / "o")]) == EXIT_BAD_INPUT
    assert "speed 10.0 too high" in _err(capsys)


def test_batch_against_a_server_that_never_speaks_fails_and_the_process_exits(tmp_path):
    """A scheduler address that accepts the connection and never answers: exit 2 with one line, and the process
    ends (the abandoned connect thread must not be joined at interpreter exit)."""
    import socket
    import subprocess
    import sys

    pairs = tmp_path / "pairs.csv"
    pairs.write_text("name,start_x_m,start_y_m,goal_x_m,goal_y_m\na,10,10,150,150\n")
    with socket.socket() as server:
        server.bind(("127.0.0.1", 0))
        server.listen(4)  # the kernel completes the TCP handshake; nobody ever reads or writes
        address = f"tcp://127.0.0.1:{server.getsockname()[1]}"
        # the CLI as a user runs it, with the connect deadline shortened from 10 s to keep the test fast
        code = (
            "import sys, terrawatt_base.dask_client as d; d.dask_client.__wrapped__.__kwdefaults__['timeout_s'] = 0.5; "
            "from terrawatt_cli import main; sys.exit(main(sys.argv[1:]))"
        )
        argv = ["batch", "--map", "example", "--pairs", str(pairs), "--out", str(tmp_path / "o"),
                "--no-progress", "--scheduler", address]
        try:
            done = subprocess.run([sys.executable, "-c", code, *argv], capture_output=True, text=True, timeout=60)
        except subprocess.TimeoutExpired:
            pytest.fail("the CLI process did not exit after failing to reach a silent scheduler")
    assert done.returncode == EXIT_BAD_INPUT, done.stderr
    assert "no dask scheduler answered within 0.5 s" in done.stderr
    assert "Traceback" not in done.stderr
