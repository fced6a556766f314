"""Tests of planner.missions.adaptive: flag -> update -> replan, rejection of worse models, budget stop."""

import dataclasses

import numpy as np
import pytest

from energy import (
    Battery,
    LinearCurrentModel,
    TruthSimulator,
    excitation_commands,
    ground_preset,
    robot_preset,
)
from planner import AdaptiveSettings, run_adaptive_mission
from planner.missions import Navigator, NavigatorModels
from planner.registry import CellModelRegistry
from terrain import InvalidParameterError, TerrainMap


def _world():
    robot = robot_preset("husky")
    grounds = {"asphalt": ground_preset("asphalt"), "sand": ground_preset("sand")}
    truth = TruthSimulator(robot, grounds, seed=0)
    ground = np.zeros((16, 40), int)
    ground[4:12, 12:34] = 1
    tmap = TerrainMap(np.zeros((16, 40)), 1.0, ground=ground, ground_names={0: "asphalt", 1: "sand"})
    a = excitation_commands(20.0, speed_levels_mps=(0.2, 0.5, 0.8), omega_levels_radps=(0.0,), rest_s=0.0, seed=1)
    b = excitation_commands(8.0, speed_levels_mps=(0.0,), omega_levels_radps=(0.5,), omega_sign="both",
                            hold_s=(2.0, 3.0), rest_s=0.0, seed=2)
    logs = [truth.simulate_commands(p.time_s, p.v_mps, p.omega_radps, ground="asphalt", seed=3 + i)
            for i, p in enumerate((a, b))]
    prior = LinearCurrentModel().fit(logs)
    return robot, truth, tmap, prior


SETTINGS = AdaptiveSettings(leg_length_m=8.0, seed=0, max_updates=2)
ASPHALT = NavigatorModels(physics_ground=ground_preset("asphalt"))


def test_unknown_region_flagged_updated_and_error_drops():
    robot, truth, tmap, prior = _world()
    reg = CellModelRegistry.from_terrain(tmap, prior)
    res = run_adaptive_mission(Navigator(tmap, reg, robot, Battery(20.0, 24.0), (37.5, 8.0), settings=SETTINGS,
                                         models=ASPHALT), truth, (2.5, 8.0))
    assert res.status == "completed" and res.distance_to_goal_m <= SETTINGS.goal_tolerance_m
    assert res.accepted_updates >= 1
    up = next(u for u in res.updates if u.accepted)
    assert up.ground == "sand" and up.validation_error_new < up.validation_error_old
    assert abs(up.region_error_pct) > SETTINGS.policy.threshold_pct
    assert abs(res.error_before_update_pct) > SETTINGS.policy.threshold_pct
    assert abs(res.error_after_update_pct) < SETTINGS.policy.threshold_pct
    assert len(reg.history) >= 1 and reg.history[-1].kind == "update"
    d = res.to_dict()
    assert d["status"] == "completed" and d["accepted_updates"] == res.accepted_updates


def test_worse_model_rejected_and_old_kept():
    robot, truth, tmap, prior = _world()
    reg = CellModelRegistry.from_terrain(tmap, prior)

    class Worse:
        """Fits a linear model but predicts three times its currents."""

        def fit(self, logs):
            self.inner_ = LinearCurrentModel().fit(logs)
            return self

        def predict(self, log):
            return 3.0 * self.inner_.predict(log)

    def bad_factory():
        return Worse()

    res = run_adaptive_mission(Navigator(tmap, reg, robot, Battery(20.0, 24.0), (37.5, 8.0), settings=SETTINGS,
                                         models=NavigatorModels(physics_ground=ground_preset("asphalt"),
                                                                model_factory=bad_factory)),
                               truth, (2.5, 8.0))
    assert len(res.updates) >= 1
    assert not any(u.accepted for u in res.updates)
    assert reg.model_ids == (0,) and np.all(np.asarray(reg.model_id_map) == 0)
    # the old model beat the refit on this ground's fresh excitation data: the same
    # (ground, model) pair is not excited again, however long the sand still shows an error
    assert [u.ground for u in res.updates] == ["sand"]


def test_budget_violation_stops_with_reason_and_position():
    robot, truth, tmap, prior = _world()
    reg = CellModelRegistry.from_terrain(tmap, prior)
    tiny = Battery(capacity_ah=0.05, voltage_v=24.0, min_reserve_pct=20.0)
    res = run_adaptive_mission(Navigator(tmap, reg, robot, tiny, (37.5, 8.0), settings=SETTINGS, models=ASPHALT),
                               truth, (2.5, 8.0))
    assert res.status == "budget_exceeded"
    assert "reserve" in res.reason and "Wh" in res.reason
    assert res.final_xy_m == (2.5, 8.0) and res.distance_to_goal_m == pytest.approx(35.0)
    assert res.legs == ()


def test_bad_input():
    robot, truth, tmap, prior = _world()
    reg = CellModelRegistry.from_terrain(tmap, prior)
    with pytest.raises(InvalidParameterError, match="battery"):
        run_adaptive_mission(Navigator(tmap, reg, robot, "battery", (37.5, 8.0), models=ASPHALT), truth, (2.5, 8.0))
    with pytest.raises(InvalidParameterError, match="update_scope"):
        AdaptiveSettings(update_scope="everywhere")


def _usable_wh_battery(usable_wh: float) -> Battery:
    """A 24 V battery with ``usable_wh`` above its 20 % reserve."""
    return Battery(capacity_ah=usable_wh / 24.0 / 0.8, voltage_v=24.0, min_reserve_pct=20.0)


def test_an_update_the_battery_cannot_afford_is_skipped_and_the_reserve_kept():
    # 2 Wh above the reserve: the route (~1.9 Wh driven) fits, the ~1 Wh sand manoeuvre does not
    robot, truth, tmap, prior = _world()
    reg = CellModelRegistry.from_terrain(tmap, prior)
    res = run_adaptive_mission(Navigator(tmap, reg, robot, _usable_wh_battery(2.0), (37.5, 8.0), settings=SETTINGS,
                                         models=ASPHALT), truth, (2.5, 8.0))
    assert res.status == "completed" and res.updates == ()
    assert res.skipped_updates and all("'sand'" in s and "reserve" in s for s in res.skipped_updates)
    assert res.excitation_energy_j == 0.0 and res.final_soc >= 0.2
    assert res.to_dict()["skipped_updates"] == list(res.skipped_updates)


def test_a_manoeuvre_that_crosses_the_reserve_stops_the_mission_where_it_stands():
    robot, truth, tmap, prior = _world()

    class HungryTruth(TruthSimulator):
        """Excitation manoeuvres (simulate_commands) draw five times the current."""

        def simulate_commands(self, *args, **kwargs):
            log = super().simulate_commands(*args, **kwargs)
            return dataclasses.replace(log, current_left_a=5.0 * log.current_left_a,
                                       current_right_a=5.0 * log.current_right_a)

    hungry = HungryTruth(robot, truth.grounds, seed=0)
    reg = CellModelRegistry.from_terrain(tmap, prior)
    res = run_adaptive_mission(Navigator(tmap, reg, robot, _usable_wh_battery(2.8), (37.5, 8.0), settings=SETTINGS,
                                         models=ASPHALT), hungry, (2.5, 8.0))
    assert res.status == "reserve_violated"
    assert "excitation manoeuvre" in res.reason and "'sand'" in res.reason and "no update" in res.reason
    assert f"{res.final_xy_m!r}" in res.reason  # where it stands (a leg end: the manoeuvre is made in place)
    # it stopped at the reserve: nothing below it is spent, and nothing is learned from the cut data
    assert res.final_soc == pytest.approx(0.2) and res.soc.min() >= 0.2 - 1e-12
    assert res.updates == () and reg.model_ids == (0,)
    assert res.excitation_energy_j > 0


def test_without_a_segmentation_a_learned_model_is_reused_instead_of_exciting_again():
    # update_scope="region": each update serves only the flagged cells, so the next sand cells
    # are flagged again; the sand model learned there explains them, no second manoeuvre
    robot, truth, tmap, prior = _world()
    reg = CellModelRegistry.from_terrain(tmap, prior)
    settings = dataclasses.replace(SETTINGS, update_scope="region")
    res = run_adaptive_mission(Navigator(tmap, reg, robot, Battery(20.0, 24.0), (37.5, 8.0), settings=settings,
                                         models=ASPHALT), truth, (2.5, 8.0))
    assert res.status == "completed"
    kinds = [u.kind for u in res.updates]
    assert kinds[0] == "excitation" and kinds.count("excitation") == 1 and "reuse" in kinds
    learned = res.updates[0].model_id
    for u in res.updates[1:]:
        assert u.model_id == learned and u.excitation_energy_j == 0.0 and u.excitation_duration_s == 0.0
        assert u.validation_error_new < min(settings.policy.threshold_pct / 100, u.validation_error_old)
    assert res.excitation_energy_j == res.updates[0].excitation_energy_j
    assert any(v.reason.startswith("reuse: model") for v in reg.history)
    # the reuse is a registry version like any other: rolling it back restores the cells
    before = np.asarray(reg.model_id_map).copy()
    reg.rollback()
    assert not np.array_equal(np.asarray(reg.model_id_map), before)


def test_start_equal_to_goal_is_refused():
    robot, truth, tmap, prior = _world()
    reg = CellModelRegistry.from_terrain(tmap, prior)
    with pytest.raises(InvalidParameterError, match="start equals goal"):
        run_adaptive_mission(Navigator(tmap, reg, robot, Battery(20.0, 24.0), (2.5, 8.0), settings=SETTINGS,
                                       models=ASPHALT), truth, (2.5, 8.0))


def test_the_budget_is_the_batterys_own_over_driving_and_manoeuvres():
    robot, truth, tmap, prior = _world()
    reg = CellModelRegistry.from_terrain(tmap, prior)
    battery = Battery(20.0, 24.0, internal_resistance_ohm=0.1, peukert_exponent=1.2)
    res = run_adaptive_mission(Navigator(tmap, reg, robot, battery, (37.5, 8.0), settings=SETTINGS, models=ASPHALT),
                               truth, (2.5, 8.0))
    assert res.status == "completed" and res.excitation_energy_j > 0
    b = res.budget
    assert b.battery == battery
    assert b.actual_energy_j == pytest.approx(res.driven_energy_j + res.excitation_energy_j, rel=1e-6)
    assert b.predicted_energy_j == pytest.approx(res.replans[0].predicted_energy_j)
    # state of charge only through energy.battery: the loop's running SoC (leg by leg and
    # manoeuvre by manoeuvre) is the one of the whole draw, with resistance and Peukert
    assert b.arrival_soc == pytest.approx(res.final_soc, abs=1e-6)
    naive = battery.initial_soc - (res.driven_energy_j + res.excitation_energy_j) / battery.energy_capacity_j
    assert res.final_soc < naive  # the pack's losses cost more than energy / capacity
    assert res.to_dict()["budget"] == b.to_json_dict()


def test_the_in_run_update_is_tried_and_proposed_when_it_validates_better(monkeypatch):
    """With in_run_update the loop also adapts the serving model on the excitation data; a
    stand-in update that fits the held-back data exactly must win over the refit."""
    import planner.missions.region_updates as adaptive_module

    robot, truth, tmap, prior = _world()
    calls = []

    class Oracle(LinearCurrentModel):
        def _predict(self, log):
            return np.column_stack([log.current_left_a, log.current_right_a])

    def fake_adapted(model, logs, **options):
        calls.append(sum(len(g) for g in logs))
        oracle = Oracle().fit(logs)
        return oracle

    monkeypatch.setattr(adaptive_module, "adapted_model", fake_adapted)
    reg = CellModelRegistry.from_terrain(tmap, prior)
    settings = dataclasses.replace(SETTINGS, in_run_update=True)
    res = run_adaptive_mission(Navigator(tmap, reg, robot, Battery(20.0, 24.0), (37.5, 8.0), settings=settings,
                                         models=ASPHALT), truth, (2.5, 8.0))
    assert calls and all(n > 0 for n in calls)
    up = next(u for u in res.updates if u.accepted)
    assert up.kind == "in_run" and up.validation_error_new == pytest.approx(0.0, abs=1e-12)
    # off by default: the loop refits only
    res_off = run_adaptive_mission(Navigator(tmap, CellModelRegistry.from_terrain(tmap, prior), robot,
                                             Battery(20.0, 24.0), (37.5, 8.0), settings=SETTINGS, models=ASPHALT),
                                   truth, (2.5, 8.0))
    assert all(u.kind != "in_run" for u in res_off.updates)
    with pytest.raises(InvalidParameterError, match="in_run_update"):
        AdaptiveSettings(in_run_update="yes")


def test_the_real_in_run_update_runs_in_the_loop():
    robot, truth, tmap, prior = _world()
    reg = CellModelRegistry.from_terrain(tmap, prior)
    settings = dataclasses.replace(SETTINGS, in_run_update=True)
    res = run_adaptive_mission(Navigator(tmap, reg, robot, Battery(20.0, 24.0), (37.5, 8.0), settings=settings,
                                         models=ASPHALT), truth, (2.5, 8.0))
    assert res.status == "completed" and res.accepted_updates >= 1
    assert {u.kind for u in res.updates} <= {"excitation", "in_run", "reuse"}
    assert abs(res.error_after_update_pct) < SETTINGS.policy.threshold_pct
