"""Tests of energy.io.csv_header: the '# terrawatt-log {json}' header line (format version, typed metadata)."""

from __future__ import annotations

import json
import re

import pytest
from energy_io_samples import FUZZ_WRITTEN, GENERIC, GENERIC_COLUMNS, GENERIC_UNITS, edit_lines, fuzz_settings
from hypothesis import given
from hypothesis import strategies as st

from energy import LogMeta, read_csv_log, write_csv_log
from energy.io import CsvLayout
from energy.io.csv_header import (
    CSV_LOG_FORMAT_VERSION,
    LOG_HEADER_PREFIX,
    MAX_LOG_HEADER_CHARS,
    format_log_header,
    parse_log_header,
)
from terrain import FileFormatError, FormatVersionError, TerrawattError


def test_csv_format_version_and_corrupt_header(tmp_path):
    log = read_csv_log(GENERIC, CsvLayout(GENERIC_COLUMNS, GENERIC_UNITS))
    path = write_csv_log(log, tmp_path / "v.csv")
    edit_lines(path, lambda ls: [ls[0].replace('"format_version": 1', '"format_version": 2')] + ls[1:])
    with pytest.raises(FormatVersionError, match="format version 2"):
        read_csv_log(path)
    edit_lines(path, lambda ls: ["# terrawatt-log {not json"] + ls[1:])
    with pytest.raises(FileFormatError, match="corrupt terrawatt-log header"):
        read_csv_log(path)



def test_csv_header_notes_not_a_string(tmp_path):
    path = write_csv_log(read_csv_log(GENERIC, CsvLayout(GENERIC_COLUMNS, GENERIC_UNITS)), tmp_path / "n.csv")
    edit_lines(path, lambda ls: [re.sub(r'"notes": "[^"]*"', '"notes": 5', ls[0])] + ls[1:])
    with pytest.raises(FileFormatError, match=r"n\.csv: terrawatt-log header: 'notes' must be a string or null, got 5"):
        read_csv_log(path)


def test_csv_header_nested_100000_deep(tmp_path):
    path = write_csv_log(read_csv_log(GENERIC, CsvLayout(GENERIC_COLUMNS, GENERIC_UNITS)), tmp_path / "deep.csv")
    edit_lines(path, lambda ls: ["# terrawatt-log " + "[" * 100_000] + ls[1:])
    with pytest.raises(FileFormatError, match=r"deep\.csv: corrupt terrawatt-log header line .*nested too deeply"):
        read_csv_log(path)
    edit_lines(path, lambda ls: ["# terrawatt-log " + '{"a": ' * 100_000] + ls[1:])
    with pytest.raises(FileFormatError, match="corrupt terrawatt-log header"):
        read_csv_log(path)


@pytest.mark.parametrize(("key", "value", "expected"), [
    ("robot", "[1, 2]", "a string or null"),
    ("source", "{}", "a string or null"),
    ("ground_label", '""', "a non-empty string or null"),
    ("velocity_source", '"guessed"', r"one of \['commanded', 'measured'\] or null"),
    ("track_width_m", '"wide"', "a finite number > 0 or null"),
    ("track_width_m", "-0.5", "a finite number > 0 or null"),
    ("track_width_m", "1e999", "a finite number > 0 or null"),
    ("start_time_ns", "1.5", "a 64-bit integer or null"),
    ("start_time_ns", "true", "a 64-bit integer or null"),
    ("start_time_ns", str(2**70), "a 64-bit integer or null"),
])
def test_csv_header_values_of_the_wrong_type(tmp_path, key, value, expected):
    path = write_csv_log(read_csv_log(GENERIC, CsvLayout(GENERIC_COLUMNS, GENERIC_UNITS)), tmp_path / "t.csv")
    edit_lines(path, lambda ls: [re.sub(rf'"{key}": ([^,}}]*)', f'"{key}": {value}', ls[0])] + ls[1:])
    with pytest.raises(FileFormatError, match=rf"terrawatt-log header: '{key}' must be {expected}"):
        read_csv_log(path)


def test_csv_header_format_version_true_is_not_1(tmp_path):
    path = write_csv_log(read_csv_log(GENERIC, CsvLayout(GENERIC_COLUMNS, GENERIC_UNITS)), tmp_path / "v.csv")
    edit_lines(path, lambda ls: [ls[0].replace('"format_version": 1', '"format_version": true')] + ls[1:])
    with pytest.raises(FormatVersionError, match="format version True"):
        read_csv_log(path)



JSON = st.recursive(
    st.none() | st.booleans() | st.integers() | st.floats() | st.text(max_size=8),
    lambda inner: st.lists(inner, max_size=3) | st.dictionaries(st.text(max_size=6), inner, max_size=3),
    max_leaves=8,
)
HEADER_KEYS = ["format_version", "robot", "source", "ground_label", "velocity_source", "track_width_m", "notes",
               "start_time_ns"]


@fuzz_settings(80)
@given(changes=st.dictionaries(st.sampled_from(HEADER_KEYS), JSON, max_size=4), raw=st.one_of(st.none(), st.text(max_size=60)))
def test_fuzz_csv_log_header(tmp_path, changes, raw):
    """Any header line (random JSON values for its keys, or random text) reads or raises a
    TerrawattError; a read log's metadata are of the documented types.

    Long run: ``TERRAWATT_FUZZ_EXAMPLES=20 python -m pytest -q tests/energy -k fuzz``.
    """
    lines = FUZZ_WRITTEN.read_text().splitlines()
    head = json.loads(lines[0][len("# terrawatt-log "):])
    head.update(changes)
    first = "# terrawatt-log " + (json.dumps(head) if raw is None else raw)
    path = tmp_path / "h.csv"
    path.write_text("\n".join([first.replace("\n", " ").replace("\r", " ")] + lines[1:]) + "\n")
    try:
        log = read_csv_log(path)
    except TerrawattError:
        return
    assert isinstance(log.meta.notes, str) and isinstance(log.meta.robot, str)
    assert log.meta.start_time_ns is None or isinstance(log.meta.start_time_ns, int)


# ------------------------------------------------------------- format / parse directly
def test_format_then_parse_gives_the_metadata_back():
    meta = LogMeta(robot="husky", source="run.bag", ground_label="sand", velocity_source="measured",
                   track_width_m=0.55, notes="n", start_time_ns=1_700_000_000_000_000_000)
    line = format_log_header(meta)
    assert line.startswith(LOG_HEADER_PREFIX + ' {"format_version": 1, "robot": "husky"')
    assert "gravity_removed" not in line and "missing_currents" not in line  # written only when set
    head = parse_log_header(line, "run.csv")
    assert head == {"format_version": CSV_LOG_FORMAT_VERSION, "robot": "husky", "source": "run.bag", "notes": "n",
                    "missing_currents": None, "ground_label": "sand", "velocity_source": "measured",
                    "track_width_m": 0.55, "start_time_ns": 1_700_000_000_000_000_000, "gravity_removed": None}


def test_parse_ignores_unknown_keys_and_reads_an_integer_track_width_as_float():
    head = parse_log_header(LOG_HEADER_PREFIX + ' {"format_version": 1, "track_width_m": 1, "colour": "red"}', "r.csv")
    assert head["track_width_m"] == 1.0 and isinstance(head["track_width_m"], float)
    assert "colour" not in head and head["robot"] is None


def test_parse_documented_errors():
    with pytest.raises(FileFormatError, match=r"r\.csv: corrupt terrawatt-log header line .*: not a JSON object"):
        parse_log_header(LOG_HEADER_PREFIX + " [1, 2]", "r.csv")
    with pytest.raises(FileFormatError, match=rf"more than {MAX_LOG_HEADER_CHARS}"):
        parse_log_header(LOG_HEADER_PREFIX + " " + " " * 10 + "x" * (MAX_LOG_HEADER_CHARS + 1), "r.csv")
    with pytest.raises(FormatVersionError, match="r.csv has terrawatt-log format version None; this terrawatt reads version 1"):
        parse_log_header(LOG_HEADER_PREFIX + " {}", "r.csv")
    with pytest.raises(FileFormatError, match="'gravity_removed' must be true, false or null, got 'yes'"):
        parse_log_header(LOG_HEADER_PREFIX + ' {"format_version": 1, "gravity_removed": "yes"}', "r.csv")
