"""The shared CLI helpers (terrawatt_cli.common): map reading errors, output checks."""

from __future__ import annotations

from cli_samples import one_line_error

from terrawatt_cli import main


def test_a_missing_map_file_is_one_line_and_exit_2(tmp_path, capsys):
    rc = main(["plan", "--map", str(tmp_path / "nowhere.npz"), "--start", "1", "1", "--goal", "2", "2",
               "--out", str(tmp_path / "out")])
    assert rc == 2
    assert "nowhere.npz" in one_line_error(capsys)
