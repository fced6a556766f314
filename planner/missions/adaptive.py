"""The adaptive mission in simulation: the truth simulator plays the robot of a :class:`~planner.Navigator`.

:func:`run_adaptive_mission` is one client of the navigator (:mod:`planner.missions.navigator`,
which holds the loop: compare per cell, update, repair the route, decide). It plans, then
drives the navigator's route leg by leg (``settings.leg_length_m``, rest to rest) in a
:class:`energy.TruthSimulator` (which knows the true grounds), hands each leg's log to
:meth:`Navigator.observe` with a checkpoint at its end, drives the excitation manoeuvres the
navigator requests on the spot (on the ground of the map's class there, as the simulator
knows it) and hands them to :meth:`Navigator.observe_manoeuvre`, until the navigator
arrives or stops. Everything it drove is kept on the robot's clock
(:attr:`AdaptiveResult.leg_logs`, :attr:`AdaptiveResult.manoeuvre_logs`): replayed through a
navigator of the same settings (:func:`planner.missions.replay.replay_drive`), the same logs
give the same flags, updates and route.

With ``settings.update_source="manoeuvre"`` (the default) a flagged region is learned from an
excitation manoeuvre (a straight run over speed levels and a pivot run, its energy and time
charged to the battery); with ``"driven"`` from what the robot drove there, a manoeuvre
only where that is too little. Before either, the models already held are tried
(``"reuse"``); a (ground class, model) pair validated once is not updated again (its later
flags come from transients: the evidence is reset). The loop stops at the goal, when the
forecast of the remaining route exceeds the energy above the battery's reserve
(``"budget_exceeded"``), when the reserve is crossed (``"reserve_violated"``), when no route is
found (``"no_route"``) or after ``max_legs`` legs (``"max_legs"``); the result says why and where.
"""

from __future__ import annotations

from dataclasses import replace

import numpy as np

from energy import InteractionLog, TruthSimulator
from terrain import InvalidParameterError
from terrawatt_base.checks import check_instance

from ..route import evaluate_route
from .adaptive_results import AdaptiveResult
from .legs import split_polyline
from .navigator import Navigator
from .options import MissionDrive
from .simulate import simulate_mission

__all__ = ["run_adaptive_mission"]


def run_adaptive_mission(
    navigator: Navigator,
    truth: TruthSimulator,
    start_xy_m: tuple[float, float],
) -> AdaptiveResult:
    """Drive a navigator's mission from ``start_xy_m`` in a truth simulator, updating per-cell current models and
    replanning.

    Parameters
    ----------
    navigator : Navigator
        A navigator that has not planned yet: its map (the truth simulator looks up its true
        grounds by the map's ground names), per-cell models (changed in place by accepted
        updates), robot (normally ``truth.robot``), battery, goal, settings and models.
    truth : TruthSimulator
        Drives the legs and the excitation manoeuvres.
    start_xy_m : (float, float)
        World coordinates (m).

    Returns
    -------
    AdaptiveResult

    Raises
    ------
    InvalidParameterError
        Wrong argument types; a navigator that has already planned; start equals goal (within
        ``settings.goal_tolerance_m``): nothing to drive.
    OutOfBoundsError, BlockedPositionError
        Start or goal outside the map or blocked.

    Examples
    --------
    Usage (drives a simulated mission, so not run as a doctest)::

        nav = Navigator(tmap, CellModelRegistry.from_terrain(tmap, prior), husky, Battery(20.0, 24.0), (37.5, 8.0))
        result = run_adaptive_mission(nav, truth, (2.5, 8.0))
    """
    nav = check_instance("navigator", navigator, Navigator)
    if not isinstance(truth, TruthSimulator):
        raise InvalidParameterError(f"truth must be a TruthSimulator, got {type(truth).__name__!r}")
    terrain, robot, battery = nav.terrain, nav.robot, nav.battery
    cfg = nav.settings
    decision = nav.plan(start_xy_m, time_s=0.0)
    dt = 1.0 / truth.current_rate_hz
    leg_logs: list[InteractionLog] = []
    manoeuvre_logs: list[tuple[int, InteractionLog]] = []
    while not nav.finished:
        if decision.action == "manoeuvre":  # driven on the spot, one run after another
            req = decision.manoeuvre
            seed = cfg.seed + 10_000 + 10 * req.request_id + 2
            xlogs = []
            for i, p in enumerate(req.profiles):
                xl = truth.simulate_commands(p.time_s, p.v_mps, p.omega_radps, ground=req.ground, seed=seed + i)
                t_next = (xlogs[-1].time_s[-1] if xlogs else nav.time_s) + dt
                xlogs.append(xl.shifted(t_next - float(xl.time_s[0])))
            manoeuvre_logs.extend((len(nav.legs) - 1, xl) for xl in xlogs)
            decision = nav.observe_manoeuvre(xlogs)
            continue
        head, _ = split_polyline(np.asarray(nav.route.waypoints_m), cfg.leg_length_m)
        leg_route = evaluate_route(nav.cost, head, status="exact", planner="leg")
        mr = simulate_mission(terrain, leg_route, robot, battery.replace(initial_soc=nav.soc), truth, nav.cost,
                              drive=MissionDrive(speed_mps=cfg.speed_mps, start_heading_rad=nav.heading_rad,
                                                 stop_at_reserve=True, seed=cfg.seed + 1000 + len(nav.legs)))
        log = mr.log.shifted(nav.time_s + dt - float(mr.log.time_s[0]))
        leg_logs.append(log)
        decision = nav.observe(log, checkpoint=True)
    return replace(nav.result(), leg_logs=tuple(leg_logs), manoeuvre_logs=tuple(manoeuvre_logs))
