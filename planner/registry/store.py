"""Saving and loading a registry directory atomically, and recovering one a killed save left aside.

A registry is one directory::

    registry.npz    format version, grid, cell map, evidence arrays, flag state,
                    the cells and previous ids of every history version
    history.json    format version, the model table (id, name, meta, file) and the
                    history versions (model, reason, validation errors)
    models/         one file per model, written by the caller's ``save_model``

It is written through :func:`terrawatt_base.atomic.atomic_directory`: built in a temporary folder
``.<name>.<pid>.<random>.tmp`` beside the target and renamed into place; an existing
registry is moved aside (into another such folder) only once the new one is complete, and
removed once the new one is in place. A save killed between those two renames leaves no
directory under the name and the previous registry in the aside folder:
:func:`recover_interrupted_save` moves it back (with a
:class:`~terrawatt_base.errors.RecoveryWarning`). Every save and load first recovers, then removes
the temporaries of dead saves of the same target, so leftovers never accumulate.
"""

from __future__ import annotations

import glob
import os
import re
import shutil
import warnings
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from terrain.grid import Grid
from terrawatt_base.atomic import atomic_directory, fsync_directory, remove_stale_temporaries, stale_temporaries
from terrawatt_base.checks import readonly
from terrawatt_base.errors import FileFormatError, FormatVersionError, InvalidParameterError, RecoveryWarning
from terrawatt_base.formats import read_result_json, read_versioned_npz, result_document, write_result_json

from .assignment import CellAssignment
from .cells import unflat
from .evidence import CellEvidence
from .records import CurrentModelProtocol, RegistryVersion
from .table import ModelTable

__all__ = [
    "REGISTRY_FORMAT_VERSION",
    "REGISTRY_FILE",
    "HISTORY_FILE",
    "MODELS_DIR",
    "RegistryParts",
    "save_registry",
    "load_registry",
    "recover_interrupted_save",
]

#: Version of the registry directory format written by :func:`save_registry`.
REGISTRY_FORMAT_VERSION = 1
#: The arrays of a registry directory.
REGISTRY_FILE = "registry.npz"
#: The model table and history of a registry directory.
HISTORY_FILE = "history.json"
#: The folder of model files in a registry directory.
MODELS_DIR = "models"

_MAGIC = "terrawatt-cell-model-registry"
_HISTORY_KIND = "cell-model-history"  # format "terrawatt-cell-model-history"
_MODEL_FILE_RE = re.compile(r"^models/model-[0-9]+[A-Za-z0-9._-]*$")
_SUFFIX_RE = re.compile(r"[A-Za-z0-9._-]+")


@dataclass(frozen=True, eq=False)
class RegistryParts:
    """Everything a :class:`~planner.registry.registry.CellModelRegistry` is made of.

    ``grid`` is ``None`` for a registry that knows only its ``shape``.
    """

    shape: tuple[int, int]
    grid: Grid | None
    table: ModelTable
    assignment: CellAssignment
    evidence: CellEvidence


# --------------------------------------------------------------------------- save
def _replaceable(target: Path) -> bool:
    """Whether ``target`` may be replaced by a save: a registry directory or an empty one."""
    if not target.is_dir():
        return False
    return (target / REGISTRY_FILE).is_file() or not any(target.iterdir())


def save_registry(
    directory: str | os.PathLike[str],
    parts: RegistryParts,
    save_model: Callable[[Any, Path], None],
    *,
    model_suffix: str = "",
) -> Path:
    """Write a registry directory atomically (see the module docstring); return its path.

    Raises
    ------
    InvalidParameterError
        The target exists and is not a registry directory; a bad suffix; ``save_model``
        wrote nothing at the path it was given.
    """
    target = Path(directory)
    if not isinstance(model_suffix, str) or (model_suffix and _SUFFIX_RE.fullmatch(model_suffix) is None):
        raise InvalidParameterError(f"model_suffix must be letters, digits, '.', '_' or '-', got {model_suffix!r}")
    recover_interrupted_save(target)
    if target.exists() and not _replaceable(target):
        raise InvalidParameterError(
            f"{str(target)!r} exists and is not a registry directory (no {REGISTRY_FILE}); refusing to replace it"
        )
    with atomic_directory(target) as tmp:
        _write_into(tmp, parts, save_model, model_suffix)
    return target


def _write_into(tmp: Path, parts: RegistryParts, save_model: Callable[[Any, Path], None], suffix: str) -> None:
    (tmp / MODELS_DIR).mkdir()
    model_entries = []
    for rec in parts.table:
        rel = f"{MODELS_DIR}/model-{rec.model_id:04d}{suffix}"
        path = tmp / rel
        save_model(parts.table.model(rec.model_id), path)
        if not path.exists():
            raise InvalidParameterError(
                f"save_model wrote nothing at {str(path)!r} for model {rec.model_id} ({rec.name!r}); "
                "it must write the model to exactly the path it is given"
            )
        model_entries.append({"model_id": rec.model_id, "name": rec.name, "meta": dict(rec.meta), "file": rel})
    grid, ev = parts.grid, parts.evidence
    payload: dict[str, np.ndarray] = {
        "__magic__": np.array(_MAGIC),
        "__version__": np.array(REGISTRY_FORMAT_VERSION),
        "shape": np.array(parts.shape, dtype=np.int64),
        "georeferenced": np.array(grid is not None),
        "cell_size_m": np.array(np.nan if grid is None else grid.cell_size_m),
        "origin_xy_m": np.array((np.nan, np.nan) if grid is None else grid.origin_xy_m),
        "model_id_map": parts.assignment.cell_model,
        "measured_charge_c": ev.measured_charge_c,
        "predicted_charge_c": ev.predicted_charge_c,
        "sample_count": ev.sample_count,
        "flag_state": ev.flag_state,
    }
    versions = []
    for v in parts.assignment.history:
        payload[f"version_{v.version}_cells"] = v.rows * parts.shape[1] + v.cols
        payload[f"version_{v.version}_previous"] = v.previous_model_ids
        versions.append({
            "version": v.version,
            "kind": v.kind,
            "model_id": v.model_id,
            "cell_count": v.cell_count,
            "reason": v.reason,
            "validation_error_new": v.validation_error_new,
            "validation_error_old": v.validation_error_old,
        })
    with open(tmp / REGISTRY_FILE, "wb") as fh:
        np.savez_compressed(fh, **payload)
        fh.flush()
        os.fsync(fh.fileno())
    write_result_json(tmp / HISTORY_FILE, result_document(_HISTORY_KIND, REGISTRY_FORMAT_VERSION, {
        "next_version": parts.assignment.next_version,
        "models": model_entries,
        "versions": versions,
    }))


# --------------------------------------------------------------------- recovery
def recover_interrupted_save(target: str | os.PathLike[str]) -> Path | None:
    """Move back the registry a save killed between its two renames left aside; return it.

    Only acts when nothing is under ``target``'s name. The newest registry found in an
    aside folder of a dead save (``.<name>.<pid>.<random>.tmp/old``, or the
    ``.<name>.<random>.old/<name>`` holders of earlier releases) is renamed back, with a
    :class:`~terrawatt_base.errors.RecoveryWarning`; its folder is removed. Returns ``None`` when
    there was nothing to recover.
    """
    target = Path(target)
    if target.exists() or not target.parent.is_dir():
        return None
    found: list[tuple[float, Path, Path]] = []
    for holder in stale_temporaries(target):
        if (holder / "old" / REGISTRY_FILE).is_file():
            found.append((holder.stat().st_mtime, holder, holder / "old"))
    for name in glob.glob(f".{glob.escape(target.name)}.*.old", root_dir=target.parent):
        holder = target.parent / name
        if (holder / target.name / REGISTRY_FILE).is_file():
            found.append((holder.stat().st_mtime, holder, holder / target.name))
    if not found:
        return None
    _, holder, old = max(found, key=lambda item: item[0])
    os.rename(old, target)
    fsync_directory(target.parent)
    shutil.rmtree(holder, ignore_errors=True)
    warnings.warn(
        f"registry {str(target)!r} was missing after an interrupted save; restored the previous "
        f"version from {str(holder)!r}",
        RecoveryWarning,
        stacklevel=3,
    )
    return target


# --------------------------------------------------------------------------- load
def load_registry(directory: str | os.PathLike[str], load_model: Callable[[Path], Any]) -> RegistryParts:
    """Read and check a registry directory written by :func:`save_registry`.

    Recovers an interrupted save first and removes temporaries of dead saves of the target.

    Raises
    ------
    FileFormatError
        Missing directory; a missing, corrupt or inconsistent ``registry.npz``,
        ``history.json`` or model file (the message names the piece); ``load_model``
        failing or returning something without fit/predict.
    FormatVersionError
        ``registry.npz`` or ``history.json`` of another format version, or
        ``load_model`` raising FormatVersionError.
    """
    root = Path(directory)
    recover_interrupted_save(root)
    remove_stale_temporaries(root)
    if not root.is_dir():
        raise FileFormatError(f"registry directory {str(root)!r} does not exist")
    arrays = read_versioned_npz(root / REGISTRY_FILE, magic=_MAGIC, version=REGISTRY_FORMAT_VERSION,
                                what="cell-model registry")
    history = read_result_json(root / HISTORY_FILE, _HISTORY_KIND, REGISTRY_FORMAT_VERSION, what="registry history")
    npz, hist = str(root / REGISTRY_FILE), str(root / HISTORY_FILE)
    try:
        shape = tuple(int(v) for v in arrays["shape"])
        georef = bool(arrays["georeferenced"])
        cell_size = float(arrays["cell_size_m"])
        origin = tuple(float(v) for v in arrays["origin_xy_m"])
        state = {key: np.asarray(arrays[key]) for key in
                 ("model_id_map", "measured_charge_c", "predicted_charge_c", "sample_count", "flag_state")}
    except KeyError as exc:
        raise FileFormatError(f"{npz!r} lacks entry {exc.args[0]!r}") from exc
    except (TypeError, ValueError) as exc:
        raise FileFormatError(f"{npz!r} has a malformed grid description: {exc}") from exc
    if len(shape) != 2 or min(shape) < 1:
        raise FileFormatError(f"{npz!r}: shape must be 2 positive integers, got {shape!r}")
    rows_cols: tuple[int, int] = (shape[0], shape[1])
    for key, kind in (("model_id_map", "i"), ("measured_charge_c", "f"), ("predicted_charge_c", "f"),
                      ("sample_count", "i"), ("flag_state", "b")):
        arr = state[key]
        if arr.shape != rows_cols or arr.dtype.kind != kind:
            raise FileFormatError(
                f"{npz!r}: {key} has shape {arr.shape!r} and dtype {arr.dtype}; expected {rows_cols!r} of kind {kind!r}"
            )
    measured, predicted, count = state["measured_charge_c"], state["predicted_charge_c"], state["sample_count"]
    if not (np.all(np.isfinite(measured)) and np.all(np.isfinite(predicted)) and np.all(count >= 0)):
        raise FileFormatError(f"{npz!r}: evidence arrays hold NaN/inf charges or negative counts")
    try:
        grid = Grid(rows_cols, cell_size, origin) if georef else None  # type: ignore[arg-type]
    except InvalidParameterError as exc:
        raise FileFormatError(f"{npz!r} holds an invalid grid: {exc}") from exc

    try:
        entries = history["models"]
        version_entries = history["versions"]
        next_version = int(history["next_version"])
        if not isinstance(entries, list) or not isinstance(version_entries, list):
            raise TypeError("'models' and 'versions' must be lists")
        ids = [int(e["model_id"]) for e in entries]
    except (KeyError, TypeError, ValueError) as exc:
        raise FileFormatError(f"{hist!r} is malformed: {exc!r}") from exc
    if ids != list(range(len(ids))) or not ids:
        raise FileFormatError(f"{hist!r}: model ids must be 0, 1, 2, ... with at least the prior, got {ids!r}")
    cell_model = state["model_id_map"]
    if cell_model.min() < 0 or cell_model.max() >= len(ids):
        raise FileFormatError(f"{npz!r}: model_id_map holds ids outside the model table 0..{len(ids) - 1}")

    table = ModelTable()
    for e in entries:
        model = _load_model_file(root, e, load_model, hist)
        try:
            table.add(model, name=e["name"], meta=e.get("meta") or None)
        except (KeyError, InvalidParameterError) as exc:
            raise FileFormatError(f"{hist!r} or {npz!r} holds an invalid registry: {exc}") from exc

    versions = _read_versions(version_entries, arrays, rows_cols, len(ids), next_version, f"{hist!r}/{npz!r}")
    assignment = CellAssignment(rows_cols)
    last = versions[-1].version if versions else 0
    assignment.restore(cell_model, versions, max(next_version, last + 1))
    evidence = CellEvidence(rows_cols, grid=grid, assignment=assignment)
    evidence.restore(measured, predicted, count, state["flag_state"])
    return RegistryParts(rows_cols, grid, table, assignment, evidence)


def _load_model_file(root: Path, entry: Any, load_model: Callable[[Path], Any], hist: str) -> Any:
    rel = entry.get("file") if isinstance(entry, dict) else None
    if not isinstance(rel, str) or not _MODEL_FILE_RE.match(rel):
        raise FileFormatError(f"{hist!r}: model entry {entry!r} has no valid 'file' inside {MODELS_DIR}/")
    path = root / rel
    if not path.exists():
        raise FileFormatError(f"model file {str(path)!r} (model {entry['model_id']}, {entry.get('name')!r}) is missing")
    try:
        model = load_model(path)
    except FormatVersionError as exc:
        raise FormatVersionError(f"model file {str(path)!r}: {exc}") from exc
    except Exception as exc:
        raise FileFormatError(f"model file {str(path)!r} could not be loaded: {exc!r}") from exc
    if not isinstance(model, CurrentModelProtocol):
        raise FileFormatError(
            f"load_model returned a {type(model).__name__} for {str(path)!r}; expected a model with fit/predict"
        )
    return model


def _read_versions(
    entries: Any, arrays: dict[str, np.ndarray], shape: tuple[int, int], n_models: int, next_version: int, where: str
) -> list[RegistryVersion]:
    n_cells = shape[0] * shape[1]
    versions: list[RegistryVersion] = []
    last = 0
    for ve in entries:
        try:
            vnum = int(ve["version"])
            cells = np.asarray(arrays[f"version_{vnum}_cells"])
            previous = np.asarray(arrays[f"version_{vnum}_previous"])
            if vnum <= last or vnum >= next_version:
                raise ValueError(f"version {vnum} out of order (previous {last}, next {next_version})")
            if cells.dtype.kind != "i" or previous.dtype.kind != "i" or cells.shape != previous.shape \
                    or cells.ndim != 1 or cells.size != int(ve["cell_count"]):
                raise ValueError(f"version {vnum} cell arrays do not match its cell_count")
            if cells.size and (cells.min() < 0 or cells.max() >= n_cells
                               or previous.min() < 0 or previous.max() >= n_models):
                raise ValueError(f"version {vnum} refers to cells or models that do not exist")
            model_id = int(ve["model_id"])
            if not 0 <= model_id < n_models:
                raise ValueError(f"version {vnum} refers to model {model_id} not in the table")
            rows, cols = unflat(shape, cells)
            err_new, err_old = ve.get("validation_error_new"), ve.get("validation_error_old")
            versions.append(RegistryVersion(
                version=vnum,
                kind=ve["kind"],
                model_id=model_id,
                rows=readonly(rows),
                cols=readonly(cols),
                previous_model_ids=readonly(previous.astype(np.int32)),
                cell_count=int(cells.size),
                reason=str(ve["reason"]),
                validation_error_new=None if err_new is None else float(err_new),
                validation_error_old=None if err_old is None else float(err_old),
            ))
            last = vnum
        except KeyError as exc:
            raise FileFormatError(f"{where}: a history version lacks {exc.args[0]!r}") from exc
        except (TypeError, ValueError, AttributeError, InvalidParameterError) as exc:
            raise FileFormatError(f"{where}: invalid history: {exc}") from exc
    return versions
