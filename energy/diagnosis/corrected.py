"""The corrected model: the input current model plus the chosen effects with fitted values, a normal CurrentModel."""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

import numpy as np

from terrain.terrain_map import TerrainMap
from terrawatt_base.checks import real_array
from terrawatt_base.errors import InvalidParameterError

from ..logs import InteractionLog
from ..models.base import CurrentModel, ModelRecord
from ..models.baselines import PhysicsCurrentModel
from ..params import RobotParams
from .case import prepare_data
from .effect_base import Effect
from .effects import EFFECTS_CATALOGUE, effect_from_spec
from .fit import compose, fit_effect_set
from .model_currents import clamps_at_zero, physics_basis, unclipped_prediction

__all__ = ["CorrectedCurrentModel"]


def _robot_plain(robot: Any) -> Any:
    return {"__robot__": robot.to_plain()} if isinstance(robot, RobotParams) else robot


def _robot_unplain(value: Any) -> Any:
    return RobotParams.from_plain(value["__robot__"]) if isinstance(value, dict) else value


class CorrectedCurrentModel(CurrentModel):
    """A fitted current model with unmodelled effects added: ``predict`` composes them.

    ``fit(logs)`` fits the effects' parameters on the logs (the base model stays as it is);
    saving stores the base model inside the same file. The slope effect needs the map:
    pass ``terrain`` (it is not stored in the file; give it again after loading with
    :meth:`with_terrain`).

    Parameters
    ----------
    base : CurrentModel
        The fitted input model.
    effects : sequence of str or Effect
        Effects to add, by catalogue name (or Effect objects, which cannot be saved).
    robot : str or RobotParams, optional
        Robot of the reference physics for a base model that is not a physics model.
    terrain : TerrainMap, optional
        Map for the slope effect.

    Attributes
    ----------
    effects_ : tuple of Effect
        The effects bound to the fitting data.
    values_ : tuple of numpy.ndarray
        Fitted parameter values of each effect.
    """

    _param_names = ("base", "effects", "robot", "terrain")

    def __init__(self, base: CurrentModel, effects: Sequence[Any] = (), robot: Any = None,
                 terrain: TerrainMap | None = None) -> None:
        self.base = base
        self.effects = effects
        self.robot = robot
        self.terrain = terrain

    def _check_params(self) -> list[Effect]:
        if not isinstance(self.base, CurrentModel) or not self.base.is_fitted:
            raise InvalidParameterError(f"base must be a fitted CurrentModel, got {self.base!r:.80}")
        if self.terrain is not None and not isinstance(self.terrain, TerrainMap):
            raise InvalidParameterError(f"terrain must be a TerrainMap or None, got {type(self.terrain).__name__!r}")
        if isinstance(self.effects, (str, Effect)) or not isinstance(self.effects, Sequence):
            raise InvalidParameterError(f"effects must be a sequence of effect names or Effects, got {self.effects!r:.80}")
        out = []
        for e in self.effects:
            out.append(e if isinstance(e, Effect) else effect_from_spec(e if isinstance(e, dict) else {"name": e}))
        physics_basis(self.base, self.robot)  # validates robot
        return out

    def _fit(self, logs: list[InteractionLog]) -> None:
        effects = [e.bind(logs, self.terrain, self.robot) for e in self._check_params()]
        data = prepare_data(self.base, logs, effects, physics_basis(self.base, self.robot))
        self.effects_ = tuple(effects)
        self.values_ = tuple(np.asarray(v, dtype=np.float64) for v in fit_effect_set(effects, data))

    def fitted_parameters(self) -> dict[str, dict[str, float]]:
        """Fitted values by effect name and parameter name."""
        self._check_fitted()
        return {e.name: e.values_dict(v) for e, v in zip(self.effects_, self.values_)}

    def with_terrain(self, terrain: TerrainMap) -> CorrectedCurrentModel:
        """This fitted model with the map the slope effect reads (e.g. after loading); a physics base that drives
        the map's slope gets it too."""
        self._check_fitted()
        if not isinstance(terrain, TerrainMap):
            raise InvalidParameterError(f"terrain must be a TerrainMap, got {type(terrain).__name__!r}")
        base = self.base
        if isinstance(base, PhysicsCurrentModel) and base.is_fitted and base.on_map_:
            base = base.with_terrain(terrain)
        out = CorrectedCurrentModel(base, self.effects, self.robot, terrain)
        out.effects_ = tuple(e.bind([], terrain, self.robot) for e in self.effects_)
        out.values_ = self.values_
        return out

    def _predict(self, log: InteractionLog) -> np.ndarray:
        basis = physics_basis(self.base, self.robot)
        base = unclipped_prediction(self.base, log, basis)
        prepared = [e.prepare(self.base, log) for e in self.effects_]
        return compose(self.effects_, self.values_, base, prepared, clamps_at_zero(self.base))

    # ------------------------------------------------------------ persistence
    def _params_to_plain(self) -> dict[str, Any]:
        rec = self.base.to_record()
        names = []
        for e in self.effects_:
            if e.name not in EFFECTS_CATALOGUE:
                raise InvalidParameterError(f"effect {e.name!r} is not catalogued; a corrected model with it cannot be saved")
            names.append(e.spec())
        return {"base": {"model_class": rec.model_class, "params": rec.params, "state": rec.state},
                "effects": names, "robot": _robot_plain(self.robot), "terrain": None}

    @classmethod
    def _params_from_plain(cls, params: dict[str, Any]) -> dict[str, Any]:
        b = params["base"]
        if b["model_class"] == "VibrationCurrentEstimator" and CurrentModel.registered(b["model_class"]) is None:
            from ..models.estimator import VibrationCurrentEstimator  # noqa: F401  (registers the class; needs torch)
        base = CurrentModel.from_record(ModelRecord(b["model_class"], b["params"], b["state"]), "the corrected model's base")
        return {"base": base, "effects": [dict(e) for e in params["effects"]], "robot": _robot_unplain(params["robot"]),
                "terrain": None}

    def _state(self) -> dict[str, Any]:
        return {"effects": [e.spec() for e in self.effects_], "values": [v.tolist() for v in self.values_]}

    def _load_state(self, state: dict[str, Any]) -> None:
        effects = [effect_from_spec(s).bind([], None, self.robot) for s in state["effects"]]
        values = [real_array("values", v, ndim=1) for v in state["values"]]
        if len(values) != len(effects) or any(v.size != e.n_parameters for e, v in zip(effects, values)):
            raise ValueError("the effect values do not match the effects' parameters")
        self.effects_ = tuple(effects)
        self.values_ = tuple(values)
