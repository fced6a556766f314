"""Tests of energy.io.csv_table: strict UTF-8 decoding, the header scan, the numeric table parsers."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from energy import InteractionLog, LogMeta, read_csv_log, write_csv_log
from energy.io import CsvLayout, LogCleaning
from energy.io.csv_table import MISSING_TOKENS, CsvText, read_csv_text, read_table
from terrain import DataError, FileFormatError


def _long_log_file(tmp_path: Path) -> Path:
    """A generic CSV log of 1000 rows (well past 8 KiB)."""
    t = np.arange(500) * 0.1
    ta = np.arange(2000) * 0.025
    log = InteractionLog(t, np.full(500, 0.5), np.zeros(500), np.full(500, 2.0), np.full(500, 2.5), ta,
                         np.full(2000, 9.81), meta=LogMeta(robot="r", notes="long"))
    return write_csv_log(log, tmp_path / "long.csv")


def test_csv_invalid_utf8_byte_beyond_8_kib(tmp_path):
    path = _long_log_file(tmp_path)
    data = bytearray(path.read_bytes())
    at = data.index(b"\n", 20_000) + 2
    data[at : at + 2] = b"\xc3("  # a lead byte without its continuation
    path.write_bytes(bytes(data))
    line = data.count(b"\n", 0, at) + 1
    with pytest.raises(FileFormatError, match=rf"long\.csv' is not a UTF-8 text CSV file: byte {at} \(line {line}\) is "
                                              r"b'\\xc3', which is not valid UTF-8"):
        read_csv_log(path)
    with pytest.raises(FileFormatError, match=rf"byte {at} \(line {line}\)"):
        read_csv_log(path, CsvLayout(rates="single"), cleaning=LogCleaning(repair=("interpolate_nans",)))


# ------------------------------------------------------------------ read_csv_text
def test_read_csv_text_skips_comments_and_blank_lines_to_the_header(tmp_path):
    path = tmp_path / "t.csv"
    path.write_bytes("\ufeff# a note\n\n# another\r\n time , a,b\r\n1,2,3\n".encode())  # a BOM, CRLF lines
    text = read_csv_text(path)
    assert text.source == str(path)
    assert text.header_line == 3
    assert text.names == ["time", "a", "b"]
    assert text.comments == ["# a note", "# another"]
    assert text.lines[-1] == "1,2,3\n" and all("\r" not in line for line in text.lines)


def test_read_csv_text_refuses_a_missing_path_a_folder_and_an_empty_file(tmp_path):
    with pytest.raises(FileFormatError, match=r"file '.*nope\.csv' does not exist"):
        read_csv_text(tmp_path / "nope.csv")
    with pytest.raises(FileFormatError, match="is not a file"):
        read_csv_text(tmp_path)
    (tmp_path / "e.csv").write_text("# only a comment\n\n")
    with pytest.raises(DataError, match=r"e\.csv' is empty: no header line and no data"):
        read_csv_text(tmp_path / "e.csv")


def test_read_csv_text_names_the_first_byte_that_is_not_utf8(tmp_path):
    path = tmp_path / "b.csv"
    path.write_bytes(b"t,a\n1,2\n3,\xff\n")
    with pytest.raises(FileFormatError, match=r"b\.csv' is not a UTF-8 text CSV file: byte 10 \(line 3\) is b'\\xff'"):
        read_csv_text(path)


# --------------------------------------------------------------------- read_table
def _table(tmp_path: Path, body: str) -> CsvText:
    path = tmp_path / "t.csv"
    path.write_text(body)
    return read_csv_text(path)


def test_read_table_reads_wanted_optional_and_text_columns(tmp_path):
    text = _table(tmp_path, "t,a,label,extra\n0,1.5,sand,9\n1,NA, grass ,9\n2,2.5,,9\n")
    out = read_table(text, ("t", "a"), optional=("gone", "extra"), columns_text=("label",))
    assert sorted(out) == ["a", "extra", "label", "t"]
    assert out["t"].tolist() == [0.0, 1.0, 2.0]
    assert out["a"][0] == 1.5 and np.isnan(out["a"][1]) and out["a"][2] == 2.5  # NA is a missing number
    assert out["label"].tolist() == ["sand", "grass", ""]
    assert out["t"].dtype == np.float64


def test_every_missing_token_is_nan(tmp_path):
    tokens = sorted(MISSING_TOKENS - {""})
    text = _table(tmp_path, "t,a\n" + "".join(f"{k},{tok}\n" for k, tok in enumerate(tokens)) + f"{len(tokens)},\n")
    out = read_table(text, ("t", "a"))
    assert out["t"].tolist() == list(range(len(tokens) + 1))
    assert np.isnan(out["a"]).all()


def test_read_table_documented_errors(tmp_path):
    with pytest.raises(DataError, match=r"missing column\(s\) \['b'\]; the header has \['t', 'a'\]"):
        read_table(_table(tmp_path, "t,a\n0,1\n"), ("t", "b"))
    with pytest.raises(DataError, match=r"column\(s\) \['a'\] appear more than once"):
        read_table(_table(tmp_path, "t,a,a\n0,1,2\n"), ("t", "a"))
    with pytest.raises(DataError, match="a header .* but no data rows"):
        read_table(_table(tmp_path, "t,a\n"), ("t", "a"))
    with pytest.raises(FileFormatError, match=r"line 3: 1 field\(s\), expected 2 as in the header"):
        read_table(_table(tmp_path, "t,a\n0,1\n2\n"), ("t", "a"))
    with pytest.raises(FileFormatError, match=r"line 2, column 'a': 'x1' is not a number"):
        read_table(_table(tmp_path, "t,a\n0,x1\n"), ("t", "a"))
