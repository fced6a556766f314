"""Reading a numeric CSV table: strict UTF-8 decoding, header scan, fast and exact parsers."""

from __future__ import annotations

import csv
import io
import math
import os
import warnings
from collections.abc import Sequence
from pathlib import Path
from typing import Any

import numpy as np

from terrawatt_base.containers import check_file_fits
from terrawatt_base.errors import DataError, FileFormatError

__all__ = ["MISSING_TOKENS", "CsvText", "read_csv_text", "read_table"]

#: Field values read as a missing number (NaN).
MISSING_TOKENS = frozenset({"", "nan", "NaN", "NAN", "NA", "null", "None"})


class CsvText:
    """A CSV file's decoded lines and where its header is.

    Attributes
    ----------
    source : str
        The path, for messages.
    lines : list of str
        Every line, newlines normalised to ``"\\n"``.
    header_line : int
        Index of the header line (the first line neither blank nor a ``#`` comment).
    names : list of str
        Column names of the header.
    comments : list of str
        Stripped comment lines above the header.
    """

    def __init__(self, source: str, lines: list[str], header_line: int, names: list[str], comments: list[str]):
        self.source = source
        self.lines = lines
        self.header_line = header_line
        self.names = names
        self.comments = comments


#: Memory of a CSV file being read, per byte of the file: its bytes, the decoded text, its
#: lines and the parsed columns are alive together (about 5x measured; 8x kept as a margin).
CSV_MEMORY_EXPANSION = 8.0


def _decode(path: Path) -> str:
    check_file_fits(path, repr(str(path)), CSV_MEMORY_EXPANSION, "reading this CSV file")
    try:
        raw = path.read_bytes()
    except OSError as exc:
        raise FileFormatError(f"cannot read {str(path)!r}: {exc.strerror or exc}") from exc
    try:
        return raw.decode("utf-8-sig")
    except UnicodeDecodeError as exc:
        line = raw.count(b"\n", 0, exc.start) + 1
        raise FileFormatError(
            f"{str(path)!r} is not a UTF-8 text CSV file: byte {exc.start} (line {line}) is "
            f"{raw[exc.start:exc.start + 1]!r}, which is not valid UTF-8 ({exc.reason})"
        ) from None


def read_csv_text(path: str | os.PathLike[str]) -> CsvText:
    """Decode a CSV file (strict UTF-8, an optional BOM) and find its header.

    Raises
    ------
    FileFormatError
        Missing path, not a file, unreadable, not UTF-8 (the message gives the byte offset
        and the line of the first bad byte), or a header the csv module cannot parse.
    DataError
        No header line.
    """
    path = Path(path)
    if not path.exists():
        raise FileFormatError(f"file {str(path)!r} does not exist")
    if not path.is_file():
        raise FileFormatError(f"{str(path)!r} is not a file")
    lines = io.StringIO(_decode(path), newline=None).readlines()
    comments: list[str] = []
    for lineno, line in enumerate(lines):
        stripped = line.strip()
        if not stripped:
            continue
        if stripped.startswith("#"):
            comments.append(stripped)
            continue
        try:
            names = [n.strip() for n in next(csv.reader([stripped]))]
        except csv.Error as exc:
            raise FileFormatError(f"{str(path)!r}, line {lineno + 1}: unreadable CSV header: {exc}") from None
        return CsvText(str(path), lines, lineno, names, comments)
    raise DataError(f"{str(path)!r} is empty: no header line and no data")


def read_table(
    text: CsvText, wanted: Sequence[str], optional: Sequence[str] = (), columns_text: Sequence[str] = ()
) -> dict[str, np.ndarray]:
    """Numeric columns ``wanted`` (+ ``optional`` when present) and text columns ``columns_text``.

    Missing numeric fields (empty, ``nan``, ``NA``) become NaN; text columns keep strings
    (missing -> ""). numpy's fast parser reads well-formed files; anything it refuses is
    re-read with the csv module for an exact message.

    Raises
    ------
    DataError
        A wanted column missing or duplicated in the header; no data rows.
    FileFormatError
        A ragged row or a field that is not a number (the message gives the line).
    """
    names, src = text.names, text.source
    dupes = sorted({n for n in names if names.count(n) > 1} & set(wanted))
    if dupes:
        raise DataError(f"{src!r}: column(s) {dupes!r} appear more than once in the header {names!r}")
    missing = [w for w in wanted if w not in names]
    if missing:
        raise DataError(f"{src!r}: missing column(s) {missing!r}; the header has {names!r}")
    numeric = list(wanted) + [o for o in optional if o in names and o not in wanted]
    text_cols = [c for c in columns_text if c in names]
    body = text.lines[text.header_line + 1 :]
    out: dict[str, np.ndarray] = {}
    try:
        with warnings.catch_warnings():
            warnings.simplefilter("error")  # numpy warns on an empty data section
            data = np.loadtxt(body, delimiter=",", usecols=[names.index(c) for c in numeric], ndmin=2,
                              comments="#", dtype=np.float64)
            tdata = [
                np.loadtxt(body, delimiter=",", usecols=[names.index(c)], ndmin=1, comments="#", dtype=str)
                for c in text_cols
            ]
        for j, c in enumerate(numeric):
            out[c] = np.ascontiguousarray(data[:, j])
        for c, arr in zip(text_cols, tdata):
            out[c] = np.char.strip(arr.astype(str))
    except (ValueError, UserWarning, IndexError):
        out = _read_table_slow(text, numeric, text_cols)
    n = next(iter(out.values())).size
    if n == 0:
        raise DataError(f"{src!r} is empty: a header {names!r} but no data rows")
    return out


def _read_table_slow(text: CsvText, numeric: list[str], text_cols: list[str]) -> dict[str, np.ndarray]:
    """csv-module parser: exact diagnostics for ragged rows and non-numbers, NaN for missing."""
    names, src = text.names, text.source
    idx = {c: names.index(c) for c in numeric + text_cols}
    need = max(idx.values()) + 1
    values: dict[str, list[Any]] = {c: [] for c in idx}
    first = text.header_line + 1
    for k, line in enumerate(text.lines[first:]):
        lineno = first + k + 1
        try:
            rows = list(csv.reader([line]))
        except csv.Error as exc:
            raise FileFormatError(f"{src!r}, line {lineno}: unreadable CSV row: {exc}") from None
        row = rows[0] if rows else []
        if not row or (len(row) == 1 and not row[0].strip()) or row[0].lstrip().startswith("#"):
            continue
        if len(row) < need:
            raise FileFormatError(f"{src!r}, line {lineno}: {len(row)} field(s), expected {len(names)} as in the header")
        for c in numeric:
            token = row[idx[c]].strip()
            if token in MISSING_TOKENS:
                values[c].append(math.nan)
                continue
            try:
                values[c].append(float(token))
            except ValueError:
                raise FileFormatError(f"{src!r}, line {lineno}, column {c!r}: {token[:40]!r} is not a number") from None
        for c in text_cols:
            values[c].append(row[idx[c]].strip())
    out = {c: np.asarray(values[c], dtype=np.float64) for c in numeric}
    out.update({c: np.asarray(values[c], dtype=str) for c in text_cols})
    return out
