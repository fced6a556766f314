"""terrawatt's versioned files: ``.npz`` (magic string, format version) and result JSON documents, clear errors."""

from __future__ import annotations

import json
import os
import sys
from collections.abc import Mapping
from pathlib import Path
from typing import Any

import numpy as np

from .atomic import write_json_atomic
from .containers import check_file_fits, read_npz
from .errors import FileFormatError, FormatVersionError, InvalidParameterError

__all__ = [
    "FORMAT_PREFIX",
    "RESULT_JSON_INDENT",
    "format_name",
    "result_document",
    "write_result_json",
    "read_result_json",
    "read_versioned_npz",
    "check_format_version",
]

#: Every terrawatt file format's name starts with this (``"terrawatt-route"``, ``"terrawatt-batch"``).
FORMAT_PREFIX = "terrawatt-"
#: Indent of every result JSON file written by :func:`write_result_json`.
RESULT_JSON_INDENT = 2
#: The two keys every result document opens with.
_HEAD = ("format", "format_version")


def check_format_version(found: Any, expected: int, what: str, path: str | os.PathLike[str]) -> int:
    """The integer format version ``found`` in ``path``; it must equal ``expected``.

    Raises
    ------
    FileFormatError
        ``found`` is missing or not an integer.
    FormatVersionError
        Another version.
    """
    value = found.item() if isinstance(found, np.ndarray) and found.ndim == 0 else found  # a .npz entry
    if isinstance(value, (bool, np.bool_)) or not isinstance(value, (int, np.integer)):
        # 1.9, true, "1" or a missing entry are not version 1: never read a file as a version it does not name
        raise FileFormatError(f"{what} file {str(path)!r} has no valid format version (an integer; got {found!r})")
    version = int(value)
    if version != expected:
        raise FormatVersionError(
            f"{what} file {str(path)!r} has format version {version!r}; this terrawatt reads version {expected}"
        )
    return version


def read_versioned_npz(path: str | os.PathLike[str], *, magic: str, version: int, what: str) -> dict[str, np.ndarray]:
    """Every array of a terrawatt ``.npz`` file, after checking its magic string and format version.

    The file must hold a scalar ``__magic__`` equal to ``magic`` and a ``__version__`` equal
    to ``version``. Pickled objects are never loaded.

    Parameters
    ----------
    path : str or os.PathLike
    magic : str
        The file kind's magic string.
    version : int
        The format version this release reads.
    what : str
        What the file is, for messages (``"map"``, ``"registry"``).

    Returns
    -------
    dict of str to numpy.ndarray

    Raises
    ------
    FileFormatError
        Missing, corrupt (any failure to read the archive), content over the memory budget or
        an entry whose header lies (:mod:`terrawatt_base.containers`), not this kind of file, or
        without a valid version.
    FormatVersionError
        Another format version.
    """
    p = Path(path)
    if not p.is_file():
        raise FileFormatError(f"{what} file {str(p)!r} is missing (does not exist or is not a file)")
    content = read_npz(p, what)  # sizes checked against the file and the memory budget before inflating
    found = content.get("__magic__")
    if found is None or found.shape != () or str(found.item()) != magic:
        raise FileFormatError(f"{str(p)!r} is a .npz file but not a terrawatt {what}")
    check_format_version(content.get("__version__"), version, what, p)
    return content


def format_name(kind: str) -> str:
    """The format name of a kind of result file: ``"terrawatt-<kind>"``.

    Raises
    ------
    InvalidParameterError
        ``kind`` is not a non-empty string, or already carries the prefix.

    Examples
    --------
    >>> format_name("route")
    'terrawatt-route'
    """
    if not isinstance(kind, str) or not kind or kind.startswith(FORMAT_PREFIX) or kind != kind.strip():
        raise InvalidParameterError(
            f"kind must be a non-empty name without the {FORMAT_PREFIX!r} prefix (e.g. 'route'), got {kind!r}"
        )
    return FORMAT_PREFIX + kind


def _check_version(version: Any) -> int:
    if isinstance(version, bool) or not isinstance(version, (int, np.integer)) or version < 1:
        raise InvalidParameterError(f"version must be an int >= 1, got {version!r}")
    return int(version)


def result_document(kind: str, version: int, body: Mapping[str, Any]) -> dict[str, Any]:
    """A result document: ``{"format": "terrawatt-<kind>", "format_version": version, **body}``.

    What a result's ``to_dict()`` returns and :func:`write_result_json` writes; the body's
    values are left as they are (NaN, numpy values: the writer turns them into JSON).

    Parameters
    ----------
    kind : str
        The kind of file, without the prefix (``"route"``, ``"batch"``).
    version : int
        The layout's format version (>= 1).
    body : mapping of str to any
        The content; must not hold ``"format"`` or ``"format_version"``.

    Returns
    -------
    dict

    Raises
    ------
    InvalidParameterError
        A bad ``kind`` or ``version``, or a body that holds a head key.

    Examples
    --------
    >>> result_document("batch", 1, {"n_pairs": 3})
    {'format': 'terrawatt-batch', 'format_version': 1, 'n_pairs': 3}
    """
    name = format_name(kind)
    number = _check_version(version)
    clash = [k for k in _HEAD if k in body]
    if clash:
        raise InvalidParameterError(f"the body of a {name} document must not hold {clash!r}; they are the head's")
    return {"format": name, "format_version": number, **body}


def write_result_json(path: str | os.PathLike[str], document: Mapping[str, Any]) -> Path:
    """Write a result document (:func:`result_document`) as JSON to ``path`` atomically; return the path.

    One policy for every result file: numpy arrays and scalars are written as lists and
    numbers, NaN and infinities as ``null`` (the file is strict JSON), an indent of
    :data:`RESULT_JSON_INDENT`, a final newline (:func:`terrawatt_base.atomic.write_json_atomic`).

    Raises
    ------
    InvalidParameterError
        ``document`` does not open with a terrawatt ``format`` and an integer
        ``format_version``, or holds a value JSON cannot express.
    """
    if not isinstance(document, Mapping):
        raise InvalidParameterError(f"a result document must be a mapping, got {type(document).__name__}")
    found = document.get("format")
    if not isinstance(found, str) or not found.startswith(FORMAT_PREFIX) or found == FORMAT_PREFIX:
        raise InvalidParameterError(
            f"a result document needs a 'format' starting with {FORMAT_PREFIX!r} (see result_document), got {found!r}"
        )
    _check_version(document.get("format_version"))
    return write_json_atomic(path, dict(document), indent=RESULT_JSON_INDENT)


def read_result_json(
    path: str | os.PathLike[str], kind: str, version: int, *, what: str | None = None
) -> dict[str, Any]:
    """A result document read back from ``path``, after checking its format name and version.

    Parameters
    ----------
    path : str or os.PathLike
    kind : str
        The kind expected (``format`` must be ``"terrawatt-<kind>"``).
    version : int
        The format version this release reads.
    what : str, optional
        What the file is, for messages (default: ``kind``).

    Returns
    -------
    dict
        The whole document, head included; ``null`` comes back as ``None``.

    Raises
    ------
    FileFormatError
        Missing, unreadable, not JSON, not a JSON object, not this kind of file (a foreign
        file or another terrawatt kind), or without a valid version.
    FormatVersionError
        Another format version.
    """
    name = format_name(kind)
    expected = _check_version(version)
    what = kind if what is None else what
    p = Path(path)
    if not p.is_file():
        raise FileFormatError(f"{what} file {str(p)!r} is missing (does not exist or is not a file)")
    check_file_fits(p, f"{what} file {str(p)!r}", 8.0)  # parsed JSON takes several times its text
    try:
        data = json.loads(p.read_text(encoding="utf-8"))
    except (OSError, UnicodeDecodeError, json.JSONDecodeError, RecursionError) as exc:
        raise FileFormatError(f"{what} file {str(p)!r} is corrupt (not JSON): {exc}") from exc
    except ValueError:  # json reads an integer past Python's int() digit limit as a ValueError
        raise FileFormatError(f"{what} file {str(p)!r} is corrupt: it holds an integer of more than "
                              f"{sys.get_int_max_str_digits()} digits") from None
    found = data.get("format") if isinstance(data, dict) else None
    if found != name:
        raise FileFormatError(f"{str(p)!r} is not a terrawatt {what} (format {found!r}, expected {name!r})")
    check_format_version(data.get("format_version"), expected, what, p)
    return data
