"""The update steps of the ride-along loop: for a flagged region, reuse a model, fit one on the driving, or ask for a manoeuvre.

:class:`RegionUpdates` is a mixin of :class:`~planner.Navigator` (it works on the navigator's
state: its map, registry, settings, records and battery account). For each region the
checkpoint flags, in order:

1. **reuse** — a model the registry already holds that explains what was measured in the
   region better than the serving one and under the policy's threshold is assigned to the
   update's scope (a registry version like any other: it rolls back);
2. **skip** — a (ground class, model) pair already validated on fresh data is not updated
   again (its later flags come from transients a small region over-represents): the evidence
   is reset;
3. **fit** — a new model on the driving kept inside the scope (``update_source="driven"``,
   when there is at least ``min_driven_s`` of it), or on the excitation manoeuvre the
   navigator asks for (its energy must fit above the reserve with the rest of the route);
   new and old models are validated on the held-back part, and the registry keeps the
   better (:meth:`planner.registry.CellModelRegistry.propose_update`).

The scope of an update is, with ``update_scope="ground_class"``, every cell of the map's
ground class at the region's representative cell that is served by the same model(s) (the
ground layer as a segmentation, never for its energy); with ``"region"`` the flagged cells.
"""

from __future__ import annotations

import time
from typing import Any

import numpy as np

from energy import InteractionLog
from terrain import DataError

from .adaptive_results import UpdateRecord
from .decisions import Decision, ManoeuvreRequest
from .manoeuvres import excitation_profiles
from .updates import adapted_model, best_other_model, charge_error, driven_runs, split_runs, validation_error

__all__ = ["RegionUpdates", "as_xy"]


class RegionUpdates:
    """The update steps of :class:`~planner.Navigator` (module docstring); a mixin over its state."""

    def _ground_name(self, region: Any) -> str:
        r, c = region.representative_row_col
        gid = int(self.terrain.ground[r, c])
        return self.terrain.ground_names.get(gid, str(gid))

    def _scope(self, region: Any) -> tuple[np.ndarray, int, str, int]:
        """The cells an update of ``region`` covers, its ground class id and name, the old model id."""
        r, c = region.representative_row_col
        gid = int(self.terrain.ground[r, c])
        ids = np.asarray(self.registry.model_id_map)
        if self.settings.update_scope == "ground_class":
            scope = (np.asarray(self.terrain.ground) == gid) & np.isin(ids, np.asarray(region.model_ids))
        else:
            scope = region.mask(self.registry.shape)
        return scope, gid, self.terrain.ground_names.get(gid, str(gid)), int(ids[r, c])

    def _update_region(self, region: Any) -> bool | Decision:
        """Reuse a model, skip, fit on driven data, or request a manoeuvre."""
        cfg, registry = self.settings, self.registry
        w0 = time.perf_counter()
        scope, gid, gname, old_id = self._scope(region)
        if self._reuse(region, scope, gname, w0):
            return True
        if (gid, old_id) in self.validated:  # proved itself on fresh data of this ground: transients
            registry.evidence.reset(region)
            return False
        if cfg.update_source == "driven":
            outcome = self._fit_driven(region, scope, gid, gname, old_id)
            if outcome is not None:
                return outcome
        x_e_est = self.leg_power_w * (cfg.excitation_duration_s + cfg.turn_excitation_duration_s)
        if x_e_est > self.charge.available_j() - sum(self.pending):
            self.skipped.append(f"after leg {len(self.legs) - 1}: no {gname!r} update, its ~{x_e_est / 3600:.2f} Wh "
                                "manoeuvre and the remaining route do not both fit above the reserve")
            registry.evidence.reset(region)
            return False
        seed = cfg.seed + 10_000 + 10 * len(self.updates)
        profiles = excitation_profiles(straight_s=cfg.excitation_duration_s, turn_s=cfg.turn_excitation_duration_s,
                                       speeds_mps=cfg.excitation_speeds_mps, omega_radps=cfg.excitation_omega_radps,
                                       seed=seed, dt_s=0.01)
        self.request = ManoeuvreRequest(
            request_id=len(self.updates), ground=gname, region_cells=int(region.cell_count),
            xy_m=as_xy(self.position_xy_m), profiles=profiles, duration_s=sum(p.duration_s for p in profiles),
            estimated_energy_j=x_e_est, purpose=(
                f"the {gname!r} region ({region.cell_count} cells) is off by {100 * region.relative_error:+.1f} % "
                "and the driven data cannot tell a new model apart: a straight run over speed levels and pivots"))
        self.phase = "manoeuvre"
        self._w0 = w0
        return self._decide("manoeuvre", self.request.purpose, len(self.legs) - 1, dict(self.checkpoint_evidence),
                            manoeuvre=self.request)

    def _reuse(self, region: Any, scope: np.ndarray, gname: str, w0: float) -> bool:
        """Assign a model learned elsewhere that already explains what was measured in the region."""
        cmp_ = self.comparison
        in_region = region.mask(self.registry.shape)[cmp_.rows, cmp_.cols]
        found = best_other_model(self.registry, cmp_.log, in_region, cmp_.meas, cmp_.dt, region.model_ids,
                                 self.settings.policy.min_samples)
        if found is None:
            return False
        mid, err = found
        err_now = charge_error(cmp_.pred, cmp_.meas, cmp_.dt, in_region)
        if not err < min(self.settings.policy.threshold_pct / 100.0, err_now):
            return False
        leg = len(self.legs) - 1
        self.registry.assign(scope, mid, reason=(
            f"reuse: model {mid} ({self.registry.model_record(mid).name!r}) explains the {gname!r} region "
            f"driven in leg {leg} to {100 * err:.1f} % (the serving model: {100 * err_now:.1f} %)"))
        wall = time.perf_counter() - w0
        self.update_wall += wall
        self.updates.append(UpdateRecord(leg, gname, region.cell_count, int(np.count_nonzero(scope)),
                                         100.0 * region.relative_error, True, mid, err, err_now,
                                         0.0, 0.0, wall, kind="reuse"))
        self._models_changed()
        return True

    def _fit_driven(self, region: Any, scope: np.ndarray, gid: int, gname: str, old_id: int) -> bool | None:
        """Fit and validate a new model on the driving kept inside the scope; None when it is too little."""
        cfg = self.settings
        w0 = time.perf_counter()
        runs = driven_runs(self.history, scope)
        if sum(float(r.duration_s) for r in runs) < cfg.min_driven_s:
            return None
        train, held = split_runs(runs, cfg.validation_fraction)
        if not train or not held:
            return None
        try:
            return self._propose(region, train, held, "driven", 0.0, 0.0, w0, runs[0])
        except DataError:  # the model cannot be fitted on these pieces: as if they were too few
            return None

    def _excite(self, xlogs: list[InteractionLog]) -> Decision:
        """Book the manoeuvre's energy, fit and validate on it, go on with the queue."""
        cfg = self.settings
        req, region = self.request, self.queue[0]
        self.phase, self.request = "driving", None
        e0, t_start = self.charge.excitation_j, self.time_s
        crossed = False
        for xl in xlogs:
            _, crossed = self._book(xl, None, None, driving=False)
            if crossed:
                break
        x_e, x_t = self.charge.excitation_j - e0, self.time_s - t_start
        if crossed:
            self.update_wall += time.perf_counter() - self._w0
            return self._finish("reserve_violated", (
                f"the battery reached its {self.battery.min_reserve_pct:g} % reserve in the {req.ground!r} "
                f"excitation manoeuvre at {as_xy(self.position_xy_m)!r} m after leg {len(self.legs) - 1}; "
                "no update was made from the incomplete data"), "stop")
        train, held = [], []
        for xl in xlogs:
            cut = xl.time_s[0] + (1.0 - cfg.validation_fraction) * (xl.time_s[-1] - xl.time_s[0])
            train.append(xl.slice(xl.time_s[0], cut))
            held.append(xl.slice(cut, xl.time_s[-1] + 1.0))
        self.changed |= self._propose(region, train, held, "excitation", x_e, x_t, self._w0, xlogs[0])
        self.queue.pop(0)
        return self._work_queue()

    def _propose(self, region: Any, train: list[InteractionLog], held: list[InteractionLog], kind: str, x_e: float,
                 x_t: float, w0: float, vibration: InteractionLog) -> bool:
        """Fit a new model on ``train``, validate new and old on ``held``; the registry keeps the better (over the
        region's scope, :meth:`_scope`, as it stands now)."""
        registry = self.registry
        scope, gid, gname, old_id = self._scope(region)
        new_model = self.model_factory().fit(train)
        err_new = validation_error(new_model, held)
        adapted = adapted_model(registry.model(old_id), train) if self.settings.in_run_update else None
        err_adapted = validation_error(adapted, held) if adapted is not None else np.inf
        if err_adapted < err_new:  # the serving model updated in-run validates better than a refit
            new_model, err_new, kind = adapted, err_adapted, "in_run"
        err_old = validation_error(registry.model(old_id), held)
        leg = len(self.legs) - 1
        decision = registry.propose_update(
            scope, new_model, err_new, err_old, name=f"update{len(registry.model_ids)}-{gname}",
            reason=f"region error {100 * region.relative_error:+.1f} % after leg {leg}",
            meta={"ground": gname, "after_leg": leg, "data": kind})
        if decision.accepted:
            self.vibrations[int(decision.model_id)] = (np.asarray(vibration.accel_time_s),
                                                       np.asarray(vibration.accel_z_mps2))
            self.learned.set_vibration(decision.model_id, vibration.accel_time_s, vibration.accel_z_mps2)
            self.validated.add((gid, int(decision.model_id)))
            self._models_changed()
        else:  # the old model stays: proved on a manoeuvre's fresh data, or on driving where it is itself
            # within the threshold (else more driving there may yet tell a better model apart: not locked out)
            if kind != "driven" or err_old <= self.settings.policy.threshold_pct / 100.0:
                self.validated.add((gid, old_id))
            registry.evidence.reset(region)
        wall = time.perf_counter() - w0
        self.update_wall += wall
        self.updates.append(UpdateRecord(leg, gname, region.cell_count, int(np.count_nonzero(scope)),
                                         100.0 * region.relative_error, bool(decision.accepted), decision.model_id,
                                         err_new, err_old, x_e, x_t, wall, kind))
        return bool(decision.accepted)

    def _models_changed(self) -> None:
        """The in-run gain starts again (the models it corrected are gone); the legs' spread about
        it is kept, pooled (:mod:`planner.missions.remaining`)."""
        obs = np.asarray([(a, b) for a, b in self.observed if a > 0 and b > 0], dtype=np.float64).reshape(-1, 2)
        if obs.shape[0] >= 2:
            r = np.log(obs[:, 1] / obs[:, 0])
            self.pooled = (self.pooled[0] + float(np.sum((r - r.mean()) ** 2)), self.pooled[1] + obs.shape[0] - 1)
        self.observed = []



def as_xy(p: Any) -> tuple[float, float]:
    """A point as a pair of plain floats (m)."""
    return float(p[0]), float(p[1])
