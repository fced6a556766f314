"""Atomic file writes: a temporary file beside the target, fsync, then one rename.

Every file terrawatt saves (maps, models, logs, results, plots) goes through here, so a
crash or a full disk never leaves a half-written file under the target's name and never
destroys the previous version: the target is either the old file or the complete new one.
"""

from __future__ import annotations

import json
import math
import os
import tempfile
from collections.abc import Callable, Iterator
from contextlib import contextmanager
from pathlib import Path
from typing import IO, Any

__all__ = ["FILE_MODE", "atomic_path", "atomic_open", "write_bytes_atomic", "write_text_atomic", "write_json_atomic"]

#: Permissions of written files (``mkstemp`` alone would leave them owner-only, 0600).
FILE_MODE = 0o644


@contextmanager
def atomic_path(path: str | os.PathLike[str]) -> Iterator[Path]:
    """Yield a temporary path in ``path``'s directory; on success it replaces ``path``.

    For writers that want a file name (rasterio, matplotlib's ``savefig``). The parent
    directory is created if missing. If the block raises, the temporary file is removed,
    ``path`` is left as it was and the exception propagates.

    Parameters
    ----------
    path : str or os.PathLike
        The file to write.

    Yields
    ------
    pathlib.Path
        The temporary file to write (it exists, empty).

    Examples
    --------
    >>> import tempfile, pathlib
    >>> folder = tempfile.TemporaryDirectory()
    >>> target = pathlib.Path(folder.name) / "note.txt"
    >>> with atomic_path(target) as tmp:
    ...     _ = tmp.write_text("complete")
    >>> target.read_text()
    'complete'
    >>> folder.cleanup()
    """
    target = Path(path)
    target.parent.mkdir(parents=True, exist_ok=True)
    fd, name = tempfile.mkstemp(prefix=f".{target.name}.", suffix=".tmp", dir=target.parent)
    os.close(fd)
    tmp = Path(name)
    try:
        yield tmp
        with open(tmp, "rb") as fh:
            os.fsync(fh.fileno())
        os.chmod(tmp, FILE_MODE)
        os.replace(tmp, target)
    except BaseException:
        tmp.unlink(missing_ok=True)
        raise


@contextmanager
def atomic_open(path: str | os.PathLike[str], mode: str = "wb", **kwargs: Any) -> Iterator[IO[Any]]:
    """Open a temporary file for writing that replaces ``path`` when the block ends cleanly.

    ``mode`` must be a write mode (``"w"``, ``"wb"``, ...); ``kwargs`` go to :func:`open`
    (e.g. ``encoding``, ``newline``).
    """
    if not mode.startswith("w"):
        raise ValueError(f"atomic_open needs a write mode, got {mode!r}")
    with atomic_path(path) as tmp, open(tmp, mode, **kwargs) as fh:
        yield fh
        fh.flush()


def write_bytes_atomic(path: str | os.PathLike[str], data: bytes) -> Path:
    """Write ``data`` to ``path`` atomically; return the path."""
    with atomic_open(path, "wb") as fh:
        fh.write(data)
    return Path(path)


def write_text_atomic(path: str | os.PathLike[str], text: str) -> Path:
    """Write UTF-8 ``text`` to ``path`` atomically; return the path."""
    with atomic_open(path, "w", encoding="utf-8", newline="") as fh:
        fh.write(text)
    return Path(path)


def _json_default(obj: Any) -> Any:
    """numpy arrays and scalars as plain JSON values."""
    tolist = getattr(obj, "tolist", None)
    if callable(tolist):
        return tolist()
    raise TypeError(f"cannot serialise {type(obj).__name__} as JSON")


def _finite(obj: Any) -> Any:
    """NaN and infinities become ``None`` (JSON has no such numbers)."""
    if isinstance(obj, float):
        return obj if math.isfinite(obj) else None
    if isinstance(obj, dict):
        return {k: _finite(v) for k, v in obj.items()}
    if isinstance(obj, (list, tuple)):
        return [_finite(v) for v in obj]
    return obj


def write_json_atomic(
    path: str | os.PathLike[str], data: Any, *, indent: int | None = 2, default: Callable[[Any], Any] | None = None
) -> Path:
    """Write ``data`` as JSON to ``path`` atomically; return the path.

    numpy arrays and scalars are written as lists and numbers; non-finite floats
    (NaN, inf) are written as ``null`` so the file is strict JSON.
    """
    encoded = json.loads(json.dumps(data, default=default or _json_default))
    text = json.dumps(_finite(encoded), indent=indent, allow_nan=False) + "\n"
    return write_text_atomic(path, text)
