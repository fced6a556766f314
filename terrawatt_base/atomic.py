"""Atomic file writes: a temporary file beside the target, fsync, one rename, fsync the folder.

Every file terrawatt saves (maps, models, logs, results, plots) goes through here, so a
crash or a full disk never leaves a half-written file under the target's name and never
destroys the previous version: the target is either the old file or the complete new one.

Temporaries are named ``.<target name>.<pid>.<random>.tmp`` beside the target. A process
killed mid-save (SIGKILL, power loss) cannot remove its own; the next save of the same
target removes every temporary of that target whose writing process is gone
(:func:`remove_stale_temporaries`), so leftovers never accumulate, and a save running at
the same time in another live process is never disturbed.
"""

from __future__ import annotations

import json
import math
import os
import re
import shutil
import tempfile
from collections.abc import Callable, Iterable, Iterator
from contextlib import contextmanager
from pathlib import Path
from typing import IO, Any

import numpy as np

__all__ = [
    "FILE_MODE",
    "DIR_MODE",
    "atomic_path",
    "atomic_open",
    "atomic_directory",
    "write_bytes_atomic",
    "json_finite",
    "write_text_atomic",
    "write_json_atomic",
    "save_figure",
    "fsync_directory",
    "stale_temporaries",
    "remove_stale_temporaries",
    "check_output_path",
    "refuse_overwriting_inputs",
    "probe_writable",
]

#: Permissions of written files (``mkstemp`` alone would leave them owner-only, 0600).
FILE_MODE = 0o644
#: Permissions of written directories (``mkdtemp`` alone would leave them owner-only, 0700).
DIR_MODE = 0o755


def _temp_prefix(target: Path) -> str:
    return f".{target.name}.{os.getpid()}."


def _pid_alive(pid: int) -> bool:
    if pid == os.getpid():
        return True
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    except PermissionError:  # alive, owned by someone else
        return True
    except OSError:
        return False
    return True


def stale_temporaries(path: str | os.PathLike[str]) -> list[Path]:
    """Temporaries of ``path`` left by saves whose process is gone (nothing is removed).

    Only names of the form ``.<target name>.<pid>.<random>.tmp`` (files or folders) beside
    ``path`` are considered, and only those whose ``pid`` is not a running process; they are
    listed oldest first (by modification time). For writers that may recover something from
    a dead save before :func:`remove_stale_temporaries` removes it (e.g. a folder moved
    aside by :func:`atomic_directory`).
    """
    target = Path(path)
    parent = target.parent
    if not parent.is_dir():
        return []
    # exactly one random part (no dot) between pid and suffix, so that the temporaries of
    # a target named e.g. "a.123" are never taken for those of "a" written by pid 123
    pattern = re.compile(rf"\.{re.escape(target.name)}\.([0-9]+)\.[A-Za-z0-9_]+\.tmp")
    found: list[tuple[float, Path]] = []
    for entry in parent.iterdir():
        match = pattern.fullmatch(entry.name)
        if match is None or _pid_alive(int(match.group(1))):
            continue
        try:
            found.append((entry.lstat().st_mtime, entry))
        except FileNotFoundError:  # removed meanwhile by another cleaner
            continue
    return [entry for _, entry in sorted(found)]


def remove_stale_temporaries(path: str | os.PathLike[str]) -> list[Path]:
    """Remove temporaries of ``path`` left by saves whose process is gone; return them.

    Only names of the form ``.<target name>.<pid>.<random>.tmp`` (files or folders) beside
    ``path`` are considered, and only those whose ``pid`` is not a running process. A save
    of another target, or one still running, is never touched.
    """
    removed: list[Path] = []
    for entry in stale_temporaries(path):
        try:
            if entry.is_dir() and not entry.is_symlink():
                shutil.rmtree(entry)
            else:
                entry.unlink()
        except FileNotFoundError:  # removed meanwhile by another cleaner
            continue
        removed.append(entry)
    return removed


def fsync_directory(path: str | os.PathLike[str]) -> None:
    """Flush a directory's entries (a rename into it) to disk; a no-op where unsupported."""
    try:
        fd = os.open(path, os.O_RDONLY)
    except OSError:  # pragma: no cover - platforms without directory descriptors
        return
    try:
        os.fsync(fd)
    except OSError:  # pragma: no cover - file systems that refuse fsync on directories
        pass
    finally:
        os.close(fd)


def check_output_path(path: str | os.PathLike[str], name: str = "path", *, directory: bool = False) -> Path:
    """Check, before any work is done, that ``path`` can be written as a file (or a folder).

    A file target must not be an existing directory and its parent must not be an existing
    file; a folder target must not be an existing file. Missing parents are fine (writers
    create them).

    ``name`` is how the message names the path: the caller's parameter (in backticks where the word is also
    prose, ```bag```), which the error carries without them (:attr:`~terrawatt_base.errors.TerrawattError.parameter`).

    Raises
    ------
    InvalidParameterError
        The target or one of its parents is of the wrong kind.
    """
    from .errors import InvalidParameterError

    target = Path(path)
    if directory:
        if target.exists() and not target.is_dir():
            raise InvalidParameterError(f"{name} {str(target)!r} is a file; expected a folder (or a new name)",
                                        parameter=name.strip("`"))
    elif target.is_dir():
        raise InvalidParameterError(f"{name} {str(target)!r} is a directory; expected a file name",
                                    parameter=name.strip("`"))
    for parent in target.parents:
        if parent.exists():
            if not parent.is_dir():
                raise InvalidParameterError(f"{name} {str(target)!r} lies under {str(parent)!r}, which is a file",
                                            parameter=name.strip("`"))
            break
    return target


def _resolved(path: Path) -> Path:
    try:
        return path.resolve()
    except (OSError, RuntimeError):  # a loop of symlinks: compare as given
        return path.absolute()


def refuse_overwriting_inputs(outputs: Iterable[str | os.PathLike[str]],
                              inputs: Iterable[str | os.PathLike[str] | None], name: str = "outputs") -> None:
    """Refuse, before any work, an output that is (or would replace) one of the command's inputs.

    An output file equal to an input file (the same path once resolved, or the same file on
    disk through another link) and an output folder that is an input folder are refused;
    ``None`` inputs (not given) are skipped.

    ``name`` is how the message names the path: the caller's parameter (in backticks where the word is also
    prose, ```bag```), which the error carries without them (:attr:`~terrawatt_base.errors.TerrawattError.parameter`).

    Raises
    ------
    InvalidParameterError
        Naming both paths.
    """
    from .errors import InvalidParameterError

    ins = [Path(p) for p in inputs if p is not None]
    for out in (Path(o) for o in outputs):
        r_out = _resolved(out)
        for inp in ins:
            same = r_out == _resolved(inp)
            if not same and out.exists() and inp.exists():
                try:
                    same = os.path.samefile(out, inp)
                except OSError:
                    same = False
            if same:
                raise InvalidParameterError(
                    f"{name}: writing {str(out)!r} would replace the input {str(inp)!r}; give another output",
                    parameter=name.strip("`"))


def probe_writable(directory: str | os.PathLike[str], name: str = "directory") -> Path:
    """Write and remove a probe file in ``directory``: an unwritable output fails now, not after the work.

    Folders missing on the way are created for the probe and removed again, so a command that
    fails later leaves nothing behind.

    ``name`` is how the message names the path: the caller's parameter (in backticks where the word is also
    prose, ```bag```), which the error carries without them (:attr:`~terrawatt_base.errors.TerrawattError.parameter`).

    Raises
    ------
    InvalidParameterError
        The folder cannot be created or written, naming it and the reason.
    """
    from .errors import InvalidParameterError

    target = Path(directory)
    created = [p for p in (target, *target.parents) if not p.exists()]
    try:
        target.mkdir(parents=True, exist_ok=True)
        fd, probe = tempfile.mkstemp(prefix=".terrawatt-probe-", dir=target)
        os.close(fd)
        os.unlink(probe)
    except OSError as exc:
        raise InvalidParameterError(f"{name} {str(target)!r} is not writable: {exc.strerror or exc}",
                                    parameter=name.strip("`")) from exc
    finally:
        for folder in created:  # deepest first
            try:
                folder.rmdir()
            except OSError:
                break
    return target


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
    target = check_output_path(path)
    target.parent.mkdir(parents=True, exist_ok=True)
    remove_stale_temporaries(target)
    fd, name = tempfile.mkstemp(prefix=_temp_prefix(target), suffix=".tmp", dir=target.parent)
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
    fsync_directory(target.parent)


@contextmanager
def atomic_directory(path: str | os.PathLike[str]) -> Iterator[Path]:
    """Yield a new empty temporary folder beside ``path`` to fill; on success it becomes ``path``.

    The folder must not exist yet, or be a folder that the caller means to replace: it is
    moved aside first and removed only once the new one is in place (if the rename fails it
    is put back). Files written inside should be fsynced by the writer; the folder itself
    and its parent are fsynced here. If the block raises, the temporary folder is removed.
    """
    target = check_output_path(path, directory=True)
    target.parent.mkdir(parents=True, exist_ok=True)
    remove_stale_temporaries(target)
    tmp = Path(tempfile.mkdtemp(prefix=_temp_prefix(target), suffix=".tmp", dir=target.parent))
    try:
        yield tmp
        os.chmod(tmp, DIR_MODE)
        fsync_directory(tmp)
        if target.exists():
            aside = Path(tempfile.mkdtemp(prefix=_temp_prefix(target), suffix=".tmp", dir=target.parent))
            old = aside / "old"
            os.rename(target, old)
            try:
                os.rename(tmp, target)
            except BaseException:
                os.rename(old, target)
                raise
            shutil.rmtree(aside, ignore_errors=True)
        else:
            os.rename(tmp, target)
    except BaseException:
        shutil.rmtree(tmp, ignore_errors=True)
        raise
    fsync_directory(target.parent)


@contextmanager
def atomic_open(path: str | os.PathLike[str], mode: str = "wb", **kwargs: Any) -> Iterator[IO[Any]]:
    """Open a temporary file for writing that replaces ``path`` when the block ends cleanly.

    ``mode`` must be a write mode (``"w"``, ``"wb"``, ...); ``kwargs`` go to :func:`open`
    (e.g. ``encoding``, ``newline``).
    """
    if not mode.startswith("w"):
        from .errors import InvalidParameterError

        raise InvalidParameterError(f"atomic_open needs a write mode, got {mode!r}")
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


def json_finite(obj: Any) -> Any:
    """``obj`` ready for JSON: NaN and infinities as ``None`` (JSON has no such numbers), tuples and numpy
    arrays as lists, numpy scalars as plain numbers and booleans."""
    if isinstance(obj, (bool, np.bool_)):
        return bool(obj)
    if isinstance(obj, np.integer):
        return int(obj)
    if isinstance(obj, (float, np.floating)):
        return float(obj) if math.isfinite(obj) else None
    if isinstance(obj, dict):
        return {k: json_finite(v) for k, v in obj.items()}
    if isinstance(obj, np.ndarray):
        return json_finite(obj.tolist())
    if isinstance(obj, (list, tuple)):
        return [json_finite(v) for v in obj]
    return obj


def write_json_atomic(
    path: str | os.PathLike[str], data: Any, *, indent: int | None = 2, default: Callable[[Any], Any] | None = None
) -> Path:
    """Write ``data`` as JSON to ``path`` atomically; return the path.

    numpy arrays and scalars are written as lists and numbers; non-finite floats
    (NaN, inf) are written as ``null`` so the file is strict JSON.
    """
    try:
        encoded = json.loads(json.dumps(data, default=default or _json_default))
    except (TypeError, ValueError, RecursionError) as exc:
        from .errors import InvalidParameterError

        raise InvalidParameterError(f"data cannot be written as JSON to {str(path)!r}: {exc}") from exc
    text = json.dumps(json_finite(encoded), indent=indent, allow_nan=False) + "\n"
    return write_text_atomic(path, text)


def save_figure(fig: Any, path: str | os.PathLike[str], *, dpi: int = 150, **savefig_kwargs: Any) -> Path:
    """Write a matplotlib figure atomically; return the path.

    The format comes from ``path``'s suffix (PNG when it has none); ``savefig_kwargs`` go to
    ``Figure.savefig``. The figure is left as it is: the caller owns it (a figure made by
    :func:`terrawatt_base.plot_target.new_figure` needs no closing; a pyplot figure is the
    caller's to close).
    """
    target = Path(path)
    savefig_kwargs.setdefault("format", target.suffix.lstrip(".").lower() or "png")
    with atomic_path(target) as tmp:
        fig.savefig(tmp, dpi=dpi, **savefig_kwargs)
    return target
