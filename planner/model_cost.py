"""Edge costs from a saved current model: checked against the robot and the map, one registry model per ground class.

A user who trained a model on their robot's logs (``terrawatt train``) plans with it through
:func:`model_energy_cost`: the model prices every ground class of the map it was trained on,
through :class:`~planner.LearnedEnergyModel` (the physics model adds the slope term).

**One model id per ground.** The registry gets one model id per ground class present in the
map, all serving the same model object, because a vibration-conditioned model (the
:class:`energy.VibrationCurrentEstimator`, or a model adapted from one) predicts a ground from
its vibration: each id is fed the vertical acceleration recorded on its ground in training
(:meth:`energy.CurrentModel.ground_vibration`). A model that ignores vibration gets the same
table for every id.

**Compatibility** (checked before any table is built; each refusal names both sides):

- *robot*: every robot of the model's training summary must match the robot preset: the
  preset name contained in the log's robot name, case-insensitively ("husky" matches
  "husky", "Husky_A200", "clearpath_husky"). A log that did not name its robot
  (``"unknown"``) and a file without a training summary give a warning
  (:class:`ModelCompatibilityWarning`), not a refusal.
- *grounds*: every ground class of the map must be a ground the model drove (names compared
  case-insensitively). Cells of unknown ground (class -1, e.g. a DEM without classes) are
  priced as the model's only training ground, or refused when it knows several. With
  ``model_ground`` every cell is priced as that one training ground instead.
- *vibration*: a vibration-conditioned model (:func:`uses_vibration`, or one that holds a
  recorded vibration for some training ground) must hold the recorded vibration of every
  ground it prices (files saved before that was recorded do not). A model that returns a
  recording for a ground is fed it, whatever its class.
"""

from __future__ import annotations

import warnings
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any

import numpy as np

from energy import CurrentModel, GroundParams, RobotParams, ground_preset
from energy.logs import UNLABELLED, named_robots, robot_matches
from terrain import TerrainMap
from terrain.terrain_map import UNKNOWN_GROUND
from terrawatt_base.errors import DataError, InvalidParameterError, TerrawattWarning, UnknownNameError

from .edge_cost import DEFAULT_MAX_SLOPE_RAD, EnergyCost
from .learned_cost import LearnedEnergyModel
from .registry import CellModelRegistry

if TYPE_CHECKING:  # annotations only: energy does not export the summary's class at the top level
    from energy.models.base import TrainedOn

__all__ = [
    "ModelCompatibilityWarning",
    "ModelGrounds",
    "robot_matches",
    "check_model_robot",
    "model_grounds",
    "uses_vibration",
    "model_energy_model",
    "model_energy_cost",
    "parse_model_ground",
    "DEFAULT_MODEL_PHYSICS_GROUND",
]

#: Ground preset of the physics slope term when a saved model prices the map.
DEFAULT_MODEL_PHYSICS_GROUND = "asphalt"


class ModelCompatibilityWarning(TerrawattWarning):
    """A saved model could not be fully checked against the robot (unnamed robot, no training summary)."""


def check_model_robot(model: CurrentModel, robot: RobotParams | str) -> list[str]:
    """Check that ``model`` was trained on ``robot``; return the warnings (also issued) of what could not be checked.

    Parameters
    ----------
    model : CurrentModel
        A fitted model (e.g. from :func:`energy.load_current_model`).
    robot : RobotParams or str
        The robot preset (its ``name``) or a preset name.

    Returns
    -------
    list of str
        Warnings issued as :class:`ModelCompatibilityWarning` (empty when fully checked).

    Raises
    ------
    InvalidParameterError
        ``model`` is not a CurrentModel; a training robot that does not match the preset
        (the message lists the model's robots and the preset).
    """
    if not isinstance(model, CurrentModel):
        raise InvalidParameterError(f"model must be a fitted CurrentModel, got {type(model).__name__!r}")
    name = robot.name if isinstance(robot, RobotParams) else str(robot)
    summary = model.training_summary
    notes = []
    if summary is None:
        notes.append(f"the model file does not say which robot it was trained on (saved before that was "
                     f"recorded): assumed to be {name!r}")
    else:
        named = [r for r in summary.robots if named_robots([r])]
        other = [r for r in named if not robot_matches(name, r)]
        if other:
            raise InvalidParameterError(
                f"the model was trained on robot(s) {list(summary.robots)!r}, not on the robot preset {name!r} "
                f"({other!r} do not match): train a model on {name!r} logs, or give the model's robot as `robot`",
                parameter="robot"
            )
        if len(named) < len(summary.robots):
            notes.append(f"some training logs of the model do not name their robot ({list(summary.robots)!r}): "
                         f"assumed to be {name!r}")
    for note in notes:
        warnings.warn(note, ModelCompatibilityWarning, stacklevel=2)
    return notes


def uses_vibration(model: Any) -> bool:
    """Whether ``model`` is conditioned on the ground's vibration (the estimator, or a model adapted from one).

    Asks the model (``uses_vibration`` of :class:`energy.VibrationCurrentEstimator` and of a model
    adapted from one); anything else is not.
    """
    return bool(getattr(model, "uses_vibration", False))


@dataclass(frozen=True)
class ModelGrounds:
    """Which training ground of a saved model prices each ground class of a map.

    Attributes
    ----------
    by_class : dict of int to str
        Map ground class id (``-1`` for unknown cells) to the model's training ground name
        (as the model spells it).
    training_grounds : tuple of str
        The model's training grounds (empty for a file without a training summary).
    """

    by_class: dict[int, str]
    training_grounds: tuple[str, ...]

    @property
    def grounds(self) -> tuple[str, ...]:
        """The distinct training grounds used, in first-use order."""
        return tuple(dict.fromkeys(self.by_class.values()))


def _lookup(name: str, known: Sequence[str]) -> str | None:
    key = str(name).strip().lower()
    return next((k for k in known if k.lower() == key), None)


def model_grounds(terrain: TerrainMap, summary: TrainedOn | None, *,
                  model_ground: str | Mapping[str, str] | None = None) -> ModelGrounds:
    """Match the map's ground classes with the grounds a model was trained on (module docstring).

    Parameters
    ----------
    terrain : TerrainMap
        The map.
    summary : TrainedOn or None
        The model's :attr:`~energy.CurrentModel.training_summary`; ``None`` (an older file):
        the map's class names are taken as they are, and unknown cells need ``model_ground``.
    model_ground : str or mapping of str to str, optional
        A name: price every cell as this training ground. A mapping of map class names to
        training grounds: price those classes so (a class the model never drove, e.g.
        ``{"grass": "asphalt"}``), the others by their own names.

    Returns
    -------
    ModelGrounds

    Raises
    ------
    UnknownNameError
        ``model_ground`` or a ground class of the map that the model never drove (the
        message lists the model's grounds and the map's).
    InvalidParameterError
        Unknown cells when the model knows several grounds (or none is recorded) and no
        ``model_ground`` was given.
    """
    if not isinstance(terrain, TerrainMap):
        raise InvalidParameterError(f"terrain must be a TerrainMap, got {type(terrain).__name__!r}")
    known = tuple(g for g in (summary.grounds if summary is not None else {}) if g != UNLABELLED)
    present = [int(v) for v in np.unique(np.asarray(terrain.ground))]
    map_names = {gid: terrain.ground_names.get(gid, str(gid)) for gid in present if gid != UNKNOWN_GROUND}
    where = (f"the model was trained on grounds {list(known)!r}; the map has {sorted(map_names.values())!r}"
             + (" and cells of unknown ground" if UNKNOWN_GROUND in present else ""))
    if isinstance(model_ground, str):
        chosen = _lookup(model_ground, known) if summary is not None else str(model_ground)
        if chosen is None:
            raise UnknownNameError(f"model_ground {model_ground!r} is not a ground the model drove: {where}",
                                   parameter="model_ground")
        return ModelGrounds({gid: chosen for gid in present}, known)
    renamed = {} if model_ground is None else {str(k).strip().lower(): str(v) for k, v in dict(model_ground).items()}
    unused = sorted(set(renamed) - {n.lower() for n in map_names.values()})
    if unused:
        raise UnknownNameError(f"model_ground names map class(es) {unused!r} that the map does not have: {where}",
                               parameter="model_ground")
    by_class: dict[int, str] = {}
    missing = []
    for gid, name in map_names.items():
        target = renamed.get(name.lower(), name)
        chosen = _lookup(target, known) if summary is not None else target
        if chosen is None and name.lower() in renamed:
            raise UnknownNameError(f"model_ground {name}={target} names a ground the model never drove: {where}",
                                   parameter="model_ground")
        if chosen is None:
            missing.append(name)
        else:
            by_class[gid] = chosen
    if missing:
        raise UnknownNameError(
            f"the model never drove the map's ground(s) {sorted(missing)!r}: {where}; train it on them, give "
            "model_ground CLASS=NAME to price such a class as one of the model's grounds, or model_ground NAME "
            "to price every cell as one", parameter="model_ground"
        )
    if UNKNOWN_GROUND in present:
        if len(known) != 1:
            raise InvalidParameterError(
                f"the map has cells of unknown ground and {where.split(';')[0]}: give model_ground NAME to "
                "say which of its grounds prices them", parameter="model_ground"
            )
        by_class[UNKNOWN_GROUND] = known[0]
    return ModelGrounds(by_class, known)


def model_energy_model(
    terrain: TerrainMap,
    model: CurrentModel,
    robot: RobotParams,
    *,
    model_ground: str | Mapping[str, str] | None = None,
    physics_ground: GroundParams | None = None,
) -> tuple[LearnedEnergyModel, ModelGrounds]:
    """A :class:`LearnedEnergyModel` over ``terrain`` serving ``model`` per ground class, checked (module docstring).

    Parameters
    ----------
    terrain : TerrainMap
        The map.
    model : CurrentModel
        A fitted, saved-and-loaded (or fresh) current model.
    robot : RobotParams
        The robot preset planned for; the model must have been trained on it.
    model_ground : str or mapping of str to str, optional
        As :func:`model_grounds`: one training ground for every cell, or map class names to training grounds.
    physics_ground : GroundParams, optional
        Ground of the physics slope term (default the ``asphalt`` preset).

    Returns
    -------
    (LearnedEnergyModel, ModelGrounds)
        The adapter (its registry holds one model id per map class, named after the
        training ground) and the matching it used.

    Raises
    ------
    InvalidParameterError, UnknownNameError
        As :func:`check_model_robot` and :func:`model_grounds`.
    DataError
        A vibration-conditioned model without the recorded vibration of a ground it prices.
    """
    check_model_robot(model, robot)
    plan = model_grounds(terrain, model.training_summary, model_ground=model_ground)
    vibration = {}
    conditioned = uses_vibration(model) or any(model.ground_vibration(g) is not None for g in plan.training_grounds)
    for g in plan.grounds:
        rec = model.ground_vibration(g)
        if rec is not None:
            vibration[g] = rec
        elif conditioned:
            raise DataError(
                f"the model is conditioned on vibration but holds no recorded vibration of ground {g!r} (a file "
                f"saved before that was recorded, or a ground it did not drive): re-save the model with this "
                f"release (terrawatt train), or give model_ground NAME of a ground it holds", parameter="model_ground"
            )
    ground = np.asarray(terrain.ground)
    names = plan.grounds
    registry = CellModelRegistry.from_terrain(terrain, model, prior_name=names[0])
    ids = {names[0]: registry.prior_id}
    for g in names[1:]:
        ids[g] = registry.add_model(model, name=g)
    for gid, g in plan.by_class.items():
        if ids[g] != registry.prior_id:
            registry.assign(ground == gid, ids[g], reason=f"saved model, ground {g}")
    lem = LearnedEnergyModel(registry, robot,
                             physics_ground if physics_ground is not None else ground_preset(DEFAULT_MODEL_PHYSICS_GROUND))
    for g, (t, a) in vibration.items():
        lem.set_vibration(ids[g], t, a)
    # a class named as the training ground it is priced by is that ground: its own spread; a class the model
    # never drove, priced as one it did (model_ground {"grass": "asphalt"}), keeps the new-ground spread of the mapping
    class_names = getattr(terrain, "ground_names", None) or {}
    for g in names:
        mapped = [str(class_names.get(gid, "")).lower() for gid, tg in plan.by_class.items() if tg == g]
        if mapped and all(m == g.lower() for m in mapped):
            lem.set_ground(ids[g], g)
    return lem, plan


def model_energy_cost(
    terrain: TerrainMap,
    model: CurrentModel,
    robot: RobotParams,
    speed_mps: float,
    *,
    model_ground: str | Mapping[str, str] | None = None,
    physics_ground: GroundParams | None = None,
    max_slope_rad: float = DEFAULT_MAX_SLOPE_RAD,
) -> EnergyCost:
    """Edge costs of ``terrain`` priced by a saved current model (what planning with a saved model uses).

    :func:`model_energy_model` then :meth:`LearnedEnergyModel.energy_cost`; the cost's row
    labels are the model's training grounds, and it carries standard-deviation tables when
    the model gives an interval (:mod:`planner.route_price`).

    Raises
    ------
    InvalidParameterError, UnknownNameError, DataError
        As :func:`model_energy_model`; bad speed or slope.

    Examples
    --------
    Usage (needs a trained model file, so not run as a doctest; :meth:`planner.CostSpec.build` calls it)::

        model = load_current_model("husky.tw")
        cost = model_energy_cost(tmap, model, robot_preset("husky"), 0.5)
    """
    lem, _ = model_energy_model(terrain, model, robot, model_ground=model_ground, physics_ground=physics_ground)
    return lem.energy_cost(terrain, speed_mps, max_slope_rad=max_slope_rad)


def parse_model_ground(tokens: Sequence[str] | str, name: str = "model_ground") -> str | dict[str, str]:
    """``model_ground`` from words: one ``NAME`` (every cell priced as this training ground), or ``CLASS=NAME`` pairs.

    Parameters
    ----------
    tokens : str or sequence of str
        One training-ground name, or ``CLASS=NAME`` pairs (a map class priced as a training ground).
    name : str
        How messages name the setting: the caller's parameter (which the error carries).

    Returns
    -------
    str or dict
        The name, or the mapping of map class to training ground (:func:`model_energy_cost`'s ``model_ground``).

    Raises
    ------
    InvalidParameterError
        A pair without a class or a name, a class named twice, several words that are not pairs.

    Examples
    --------
    >>> parse_model_ground(["snow"]), parse_model_ground(["grass=asphalt", "sand=snow"])
    ('snow', {'grass': 'asphalt', 'sand': 'snow'})
    """
    items = [tokens] if isinstance(tokens, str) else list(tokens)
    if not items or not all(isinstance(t, str) for t in items):
        raise InvalidParameterError(f"{name} takes one NAME or CLASS=NAME pairs, got {tokens!r}")
    if len(items) == 1 and "=" not in items[0]:
        return items[0]
    mapping: dict[str, str] = {}
    for token in items:
        cls, sep, ground = token.partition("=")
        if not sep or not cls.strip() or not ground.strip():
            raise InvalidParameterError(f"{name} takes one NAME or CLASS=NAME pairs, got {token!r}")
        if cls.strip() in mapping:
            raise InvalidParameterError(f"{name} names map class {cls.strip()!r} twice")
        mapping[cls.strip()] = ground.strip()
    return mapping
