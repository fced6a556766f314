"""Reading zip, ``.npz`` and ``.npy`` containers without trusting them.

A container's header says how big its content is; a hostile or corrupt file lies. Every
terrawatt reader of a zip archive (model files, map and registry ``.npz`` files) goes
through here:

- each entry's declared uncompressed size, and the sum over entries, must fit the memory
  budget (:data:`MEMORY_BUDGET_BYTES`, ``TERRAWATT_MEMORY_BUDGET_BYTES`` in the environment)
  before anything is inflated, and an entry is read with a hard cap at its declared size,
  so a header that lies about it is caught instead of inflating without end;
- an ``.npy`` entry's header (dtype and shape) must describe exactly the bytes that follow
  (a 2⁴⁰-element shape over a few bytes is refused before any allocation), and object
  dtypes (pickles) are refused;
- every decoding failure (zlib, a bad zip, unicode, overflow, memory) becomes a
  :class:`~terrawatt_base.errors.FileFormatError` naming the file and the entry.

The readers of other kinds check against the same budget: a text table
(:func:`check_file_fits`, its size times its expansion once parsed), a bag (the messages
of the topics read, :data:`energy.io.bag_messages.BAG_MESSAGE_BYTES` each) and a GeoTIFF
(its declared raster).
"""

from __future__ import annotations

import io
import math
import os
import zipfile
import zlib
from typing import IO, Any

import numpy as np

from .errors import FileFormatError, InvalidParameterError

__all__ = ["MEMORY_BUDGET_BYTES", "memory_budget_bytes", "memory_limit_bytes", "physical_memory_bytes", "check_zip_sizes", "check_file_fits", "read_zip_entry",
           "load_npy", "read_npz", "over_budget_message"]

#: Default memory budget of one container's content (bytes): 4 GiB.
MEMORY_BUDGET_BYTES = 4 * 1024**3
_DECODE_ERRORS = (zlib.error, zipfile.BadZipFile, zipfile.LargeZipFile, EOFError, UnicodeDecodeError, OverflowError,
                  MemoryError, ValueError, NotImplementedError, RuntimeError, OSError)  # OSError: bz2 / lzma streams


def memory_budget_bytes() -> int:
    """The budget in force: ``TERRAWATT_MEMORY_BUDGET_BYTES`` (a positive whole number of bytes) when set,
    else the default.

    Raises
    ------
    InvalidParameterError
        The variable is set to anything else (``0``, ``-5``, ``abc``, ``1e3``): never silently replaced.
    """
    raw = os.environ.get("TERRAWATT_MEMORY_BUDGET_BYTES")
    if raw is None or raw.strip() == "":
        return MEMORY_BUDGET_BYTES
    text = raw.strip().replace("_", "")
    if not text.isdigit() or int(text) <= 0:
        raise InvalidParameterError(
            f"TERRAWATT_MEMORY_BUDGET_BYTES must be a positive whole number of bytes (e.g. {MEMORY_BUDGET_BYTES} for "
            f"4 GiB), got {raw!r}; unset it for the default")
    return int(text)


def physical_memory_bytes() -> int | None:
    """This machine's physical memory (bytes), or ``None`` where the system does not say."""
    try:
        pages, page = os.sysconf("SC_PHYS_PAGES"), os.sysconf("SC_PAGE_SIZE")
    except (ValueError, OSError, AttributeError):  # not POSIX, or the names are unknown here
        return None
    return int(pages) * int(page) if pages > 0 and page > 0 else None


def memory_limit_bytes() -> int:
    """What one reading may take: the budget (:func:`memory_budget_bytes`), but never more than this
    machine's physical memory: a budget raised past it lets a 40 GiB raster through only to die in
    the middle of reading with MemoryError; the limit refuses it first (:func:`over_budget_message`
    then names the machine's memory).

    Raises
    ------
    InvalidParameterError
        The budget variable is set to something that is not a positive whole number of bytes.
    """
    budget = memory_budget_bytes()
    physical = physical_memory_bytes()
    return budget if physical is None else min(budget, physical)


def _gib(n: int) -> str:
    return f"{n / 1024**3:.3g} GiB" if n >= 1024**2 else f"{n} bytes"


def over_budget_message(where: str, what: str, need: int, limit: int | None = None, advice: str | None = None) -> str:
    """One message for every reader: what would not fit, the limit it passes and what to do.

    ``limit`` is the one that was checked (by default :func:`memory_limit_bytes`); where it is the
    machine's physical memory rather than the budget, the message says so, since raising the budget
    cannot help. ``advice`` replaces the default ("read a smaller file").
    """
    limit = memory_limit_bytes() if limit is None else limit
    physical = physical_memory_bytes()
    todo = advice or "read a smaller file"
    if physical is not None and limit >= physical:
        return (f"{where}: {what} would take about {_gib(need)} in memory, more than this machine has "
                f"({_gib(physical)}); {todo}")
    return (f"{where}: {what} would take about {_gib(need)} in memory, more than the memory budget of {_gib(limit)}; "
            f"{todo}, or raise the budget with the environment variable TERRAWATT_MEMORY_BUDGET_BYTES")


def check_file_fits(path: str | os.PathLike[str], where: str, expansion: float, what: str = "reading it") -> int:
    """The size of ``path`` (bytes), after checking that ``expansion`` times it fits the memory budget.

    Raises
    ------
    FileFormatError
        The file cannot be stat'ed, or its expanded size exceeds the budget.
    """
    try:
        size = os.stat(path).st_size
    except OSError as exc:
        raise FileFormatError(f"cannot read {where}: {exc.strerror or exc}") from exc
    limit = memory_limit_bytes()
    if size * expansion > limit:
        raise FileFormatError(over_budget_message(where, f"{what} ({_gib(size)} on disk)", int(size * expansion),
                                                  limit))
    return size


def check_zip_sizes(archive: zipfile.ZipFile, where: str, budget: int | None = None) -> None:
    """Refuse an archive whose declared content (any entry, or all together) exceeds the budget.

    Raises
    ------
    FileFormatError
        Naming the file, the entry and both sizes.
    """
    limit = memory_limit_bytes() if budget is None else budget
    total = 0
    for info in archive.infolist():
        if info.file_size > limit:
            raise FileFormatError(f"{where}: entry {info.filename!r} declares {_gib(info.file_size)} uncompressed, "
                                  f"more than the memory budget of {_gib(limit)}")
        total += info.file_size
    if total > limit:
        raise FileFormatError(f"{where}: its entries declare {_gib(total)} uncompressed together, more than the "
                              f"memory budget of {_gib(limit)}")


def read_zip_entry(archive: zipfile.ZipFile, name: str, where: str) -> bytes:
    """The bytes of entry ``name``, read with a hard cap at its declared size.

    Raises
    ------
    FileFormatError
        A missing entry, a stream that inflates past (or short of) its declared size, any
        decoding error.
    KeyError
        Never: a missing entry is a FileFormatError naming it.
    """
    try:
        info = archive.getinfo(name)
    except KeyError as exc:
        raise FileFormatError(f"{where} lacks the entry {name!r}") from exc
    try:
        fh: IO[bytes]
        with archive.open(info) as fh:
            data = fh.read(info.file_size + 1)
    except _DECODE_ERRORS as exc:
        raise FileFormatError(f"{where}: entry {name!r} is corrupt: {type(exc).__name__}: {exc}") from exc
    if len(data) != info.file_size:
        raise FileFormatError(f"{where}: entry {name!r} holds {len(data)} bytes, not the {info.file_size} its header "
                              "declares")
    return data


def load_npy(data: bytes, where: str, field: str, *, kinds: str | None = None) -> np.ndarray:
    """An ``.npy`` payload as an array, after checking that its header describes exactly its bytes.

    ``kinds`` (numpy dtype kind letters, e.g. ``"iuf"``) restricts the dtypes accepted.

    Raises
    ------
    FileFormatError
        Not an ``.npy`` payload, an object (pickled) dtype, a dtype outside ``kinds``, a shape
        whose size differs from the bytes present, any decoding error; the message names the
        file and ``field``.
    """
    buf = io.BytesIO(data)
    try:
        major, _ = np.lib.format.read_magic(buf)
        if major == 1:
            shape, _, dtype = np.lib.format.read_array_header_1_0(buf)
        else:
            shape, _, dtype = np.lib.format.read_array_header_2_0(buf)
    except _DECODE_ERRORS + (TypeError, SyntaxError) as exc:
        raise FileFormatError(f"{where}: {field} is not a readable .npy array: {exc}") from exc
    if dtype.hasobject:
        raise FileFormatError(f"{where}: {field} holds Python objects ({dtype}); terrawatt never loads pickles")
    if kinds is not None and dtype.kind not in kinds:
        names = {"b": "bool", "i": "integer", "u": "unsigned integer", "f": "real floating point", "c": "complex",
                 "U": "text", "S": "bytes", "V": "raw records", "M": "datetime", "m": "timedelta"}
        expected = " or ".join(names.get(k, k) for k in kinds)
        raise FileFormatError(f"{where}: {field} holds {names.get(dtype.kind, dtype.kind)} values ({dtype}); "
                              f"expected {expected}")
    count = math.prod(int(n) for n in shape)
    declared = count * dtype.itemsize
    present = len(data) - buf.tell()
    if declared != present:
        raise FileFormatError(f"{where}: {field} declares shape {tuple(shape)} of {dtype} ({declared} bytes) but "
                              f"holds {present} bytes")
    buf.seek(0)
    try:
        return np.load(buf, allow_pickle=False)
    except _DECODE_ERRORS + (TypeError,) as exc:
        raise FileFormatError(f"{where}: {field} cannot be decoded: {exc}") from exc


def read_npz(path: str | os.PathLike[str], what: str) -> dict[str, np.ndarray]:
    """Every array of a ``.npz`` file, each checked as above (``what`` names the file kind in messages).

    Raises
    ------
    FileFormatError
        Not a zip archive, content over the memory budget, an entry that is not a checked
        ``.npy`` array.
    """
    where = f"{what} file {str(path)!r}"
    try:
        archive = zipfile.ZipFile(path)
    except _DECODE_ERRORS as exc:  # incl. NotImplementedError: a zip version or compression it does not know
        raise FileFormatError(f"{where} is corrupt or not a .npz file: {exc}") from exc
    out: dict[str, Any] = {}
    with archive:
        check_zip_sizes(archive, where)
        for name in archive.namelist():
            key = name[:-4] if name.endswith(".npy") else name
            out[key] = load_npy(read_zip_entry(archive, name, where), where, f"entry {name!r}")
    return out
