"""The excitation manoeuvre (a straight run over speed levels, then pivots) and the prior model it trains."""

from __future__ import annotations

from collections.abc import Sequence

from energy import CommandProfile, InteractionLog, LinearCurrentModel, TruthSimulator, excitation_commands
from terrawatt_base.checks import SEED_LIMIT, check_int
from terrawatt_base.errors import InvalidParameterError

__all__ = ["excitation_profiles", "excitation_manoeuvre", "fit_prior_model"]


def excitation_profiles(
    *,
    straight_s: float,
    turn_s: float,
    speeds_mps: Sequence[float],
    omega_radps: float,
    seed: int,
    dt_s: float = 0.01,
) -> tuple[CommandProfile, CommandProfile]:
    """The excitation manoeuvre's commands: a straight run over ``speeds_mps`` (``straight_s``
    seconds, no turning) and a pivot run at ``±omega_radps`` held 2-3 s (``turn_s`` seconds),
    both without rests (:func:`energy.excitation_commands`, seeded ``seed`` and ``seed + 1``).

    What :class:`~planner.Navigator` asks a robot to drive where its data cannot tell a model
    apart; :func:`excitation_manoeuvre` drives it in the truth simulator.

    Raises
    ------
    InvalidParameterError
        Bad durations, levels or seed.
    """
    seed = check_int("seed", seed, low=0, high=SEED_LIMIT - 2)
    straight = excitation_commands(straight_s, dt_s, speed_levels_mps=tuple(speeds_mps), omega_levels_radps=(0.0,),
                                   rest_s=0.0, seed=seed)
    turn = excitation_commands(turn_s, dt_s, speed_levels_mps=(0.0,), omega_levels_radps=(omega_radps,),
                               omega_sign="both", hold_s=(2.0, 3.0), rest_s=0.0, seed=seed + 1)
    return straight, turn


def excitation_manoeuvre(
    truth: TruthSimulator,
    ground: str,
    profiles: Sequence[CommandProfile],
    *,
    sim_seed: int,
) -> list[InteractionLog]:
    """Drive the excitation manoeuvre's commands (:func:`excitation_profiles`) on ``ground`` in the truth
    simulator: one log per profile, simulated with seeds ``sim_seed``, ``sim_seed + 1``, ...

    Raises
    ------
    InvalidParameterError
        A bad seed; not command profiles.
    UnknownNameError
        ``truth`` does not know ``ground``.
    """
    profiles = list(profiles)
    sim_seed = check_int("sim_seed", sim_seed, low=0, high=SEED_LIMIT - len(profiles))
    if not all(isinstance(p, CommandProfile) for p in profiles):
        raise InvalidParameterError(f"profiles must be CommandProfiles (excitation_profiles), got {profiles!r:.80}",
                                    parameter="profiles")
    return [truth.simulate_commands(p.time_s, p.v_mps, p.omega_radps, ground=ground, seed=sim_seed + i)
            for i, p in enumerate(profiles)]


def fit_prior_model(truth: TruthSimulator, ground: str, seed: int = 1) -> LinearCurrentModel:
    """A prior current model: a :class:`energy.LinearCurrentModel` fitted on one ground.

    It drives the excitation manoeuvre on ``ground`` in the truth simulator — straight runs
    at 0.2–0.8 m/s (30 s) and pivot turns at ±0.5 rad/s (12 s) — and fits the linear model
    to both, which is what a robot commissioned on that one ground would know.

    Parameters
    ----------
    truth : TruthSimulator
        Simulator that knows ``ground``.
    ground : str
        Ground name the prior is trained on (a key of ``truth``'s grounds).
    seed : int
        Seed of the manoeuvres and the simulated noise.

    Returns
    -------
    LinearCurrentModel
        The fitted prior.

    Raises
    ------
    UnknownNameError
        If ``truth`` does not know ``ground``.
    """
    seed = check_int("seed", seed, low=0, high=SEED_LIMIT - 12)
    profiles = excitation_profiles(straight_s=30.0, turn_s=12.0, speeds_mps=(0.2, 0.35, 0.5, 0.65, 0.8),
                                   omega_radps=0.5, seed=seed)
    logs = excitation_manoeuvre(truth, ground, profiles, sim_seed=seed + 10)
    return LinearCurrentModel().fit(logs)
