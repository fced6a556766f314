"""Load any saved current model: :func:`load_current_model` reads the file and builds its class by name.

The baselines are imported here; the torch estimator only when a file names it, so loading a
baseline never imports torch.
"""

from __future__ import annotations

import os

from terrawatt_base.errors import FileFormatError

from .base import CurrentModel, read_model_file
from .baselines import ConstantCurrentModel, LinearCurrentModel, PhysicsCurrentModel

__all__ = ["MODEL_CLASSES", "model_class", "load_current_model"]

#: Names of the model classes a current-model file may hold (plus any imported subclass).
#: Model classes a file may hold. ``CorrectedCurrentModel`` (a model plus fitted effects, from
#: :func:`energy.diagnose`) registers itself when ``energy`` is imported.
MODEL_CLASSES = (
    "ConstantCurrentModel",
    "LinearCurrentModel",
    "PhysicsCurrentModel",
    "VibrationCurrentEstimator",
    "CorrectedCurrentModel",
    "AdaptedCurrentModel",
)

_BASELINES: dict[str, type[CurrentModel]] = {
    cls.__name__: cls for cls in (ConstantCurrentModel, LinearCurrentModel, PhysicsCurrentModel)
}


def model_class(name: str) -> type[CurrentModel] | None:
    """The :class:`CurrentModel` subclass called ``name`` (importing the estimator only for it), or None."""
    if not isinstance(name, str):
        return None
    if name in _BASELINES:
        return _BASELINES[name]
    if name == "VibrationCurrentEstimator":
        from .estimator import VibrationCurrentEstimator  # the one model that needs torch

        return VibrationCurrentEstimator
    return CurrentModel.registered(name)


def load_current_model(path: str | os.PathLike[str]) -> CurrentModel:
    """Read any current model written by :meth:`CurrentModel.save`.

    Parameters
    ----------
    path : str or os.PathLike
        A file written by ``save`` (this format version, or a version-1 torch checkpoint).

    Returns
    -------
    CurrentModel
        The fitted model, of the class stored in the file.

    Raises
    ------
    FileFormatError
        Missing, truncated, corrupt or foreign file; a class name that is not a current
        model; missing, forged or mistyped parameters or state.
    FormatVersionError
        A file of a format version this release cannot read.
    """
    record = read_model_file(path)
    where = repr(str(path))
    cls = model_class(record.model_class)
    if cls is None:
        raise FileFormatError(
            f"{where} holds an unknown model class {record.model_class!r:.80}; expected one of {list(MODEL_CLASSES)!r}"
        )
    return cls.from_record(record, where)
