"""Reading terrawatt's versioned ``.npz`` files: magic string, format version, clear errors."""

from __future__ import annotations

import os
from pathlib import Path
from typing import Any

import numpy as np

from .containers import read_npz
from .errors import FileFormatError, FormatVersionError

__all__ = ["read_versioned_npz", "check_format_version"]


def check_format_version(found: Any, expected: int, what: str, path: str | os.PathLike[str]) -> int:
    """The integer format version ``found`` in ``path``; it must equal ``expected``.

    Raises
    ------
    FileFormatError
        ``found`` is missing or not an integer.
    FormatVersionError
        Another version.
    """
    try:
        version = int(found)
    except (TypeError, ValueError, OverflowError) as exc:  # missing, text, inf
        raise FileFormatError(f"{what} file {str(path)!r} has no valid format version (got {found!r})") from exc
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
