"""The pack current of a log (battery_current_a): validation, resample/slice/shift/concatenate, CSV round trip, the truth simulator."""

from __future__ import annotations

import numpy as np
import pytest

from energy import Battery, InteractionLog, NoiseModel, TruthSimulator, robot_preset
from energy.io import CsvLayout, read_csv_log, write_csv_log
from energy.sim import PAPER_GROUNDS
from terrawatt_base.errors import DataError, InvalidParameterError


def _log(n: int = 20, **kw) -> InteractionLog:
    t = np.arange(n) * 0.1
    fields = dict(battery_voltage_v=np.linspace(25.0, 24.0, n), battery_current_a=np.linspace(1.0, 3.0, n))
    fields.update(kw)
    return InteractionLog(t, np.full(n, 0.5), np.zeros(n), np.full(n, 2.0), np.full(n, 2.1), t, np.full(n, 9.81),
                          **fields)


def test_battery_power_is_voltage_times_pack_current():
    log = _log()
    assert log.has_battery_power
    np.testing.assert_allclose(log.battery_power_w, log.battery_voltage_v * log.battery_current_a)
    plain = _log(battery_voltage_v=None, battery_current_a=None)
    assert not plain.has_battery_power and plain.battery_power_w is None
    assert not _log(battery_current_a=None).has_battery_power  # voltage alone is no power


def test_inputs_are_copied_not_modified():
    amps = np.linspace(1.0, 3.0, 20)
    log = _log(battery_current_a=amps)
    amps[0] = 99.0
    assert log.battery_current_a[0] == 1.0 and not log.battery_current_a.flags.writeable


@pytest.mark.parametrize(
    ("kw", "error", "match"),
    [
        ({"battery_voltage_v": None}, InvalidParameterError, "needs battery_voltage_v"),
        ({"battery_current_a": np.ones(19)}, InvalidParameterError, "battery_current_a must have the length"),
        ({"battery_current_a": np.r_[np.ones(19), np.nan]}, DataError, "battery_current_a must be finite"),
        ({"battery_current_a": np.ones((20, 2))}, InvalidParameterError, "battery_current_a"),
        ({"battery_current_a": ["a"] * 20}, InvalidParameterError, "battery_current_a"),
        ({"battery_voltage_v": np.r_[np.full(19, 24.0), -1.0]}, DataError, "battery_voltage_v must be >= 0"),
    ],
)
def test_bad_pack_current_or_voltage(kw, error, match):
    with pytest.raises(error, match=match):
        _log(**kw)


def test_carried_through_resample_slice_shift_and_concatenate():
    log = _log()
    r = log.resample(5.0)
    np.testing.assert_allclose(r.battery_current_a, np.interp(r.time_s, log.time_s, log.battery_current_a))
    held = log.resample(5.0, method="previous")
    np.testing.assert_array_equal(held.battery_current_a, log.battery_current_a[::2][: len(held)])
    s = log.slice(0.5, 1.0)
    np.testing.assert_array_equal(s.battery_current_a, log.battery_current_a[5:10])
    joined = InteractionLog.concatenate([log, log.shifted(10.0)])
    np.testing.assert_array_equal(joined.battery_current_a, np.r_[log.battery_current_a, log.battery_current_a])
    with pytest.raises(DataError, match="battery_current_a present in logs"):
        InteractionLog.concatenate([log, _log(battery_current_a=None).shifted(10.0)])


def test_csv_round_trip(tmp_path):
    log = _log()
    path = write_csv_log(log, tmp_path / "run.csv")
    header = path.read_text().splitlines()[1].split(",")
    assert "battery_current_a" in header and "battery_voltage_v" in header
    back = read_csv_log(path)
    np.testing.assert_array_equal(back.battery_current_a, log.battery_current_a)
    np.testing.assert_array_equal(back.battery_voltage_v, log.battery_voltage_v)
    plain = read_csv_log(write_csv_log(_log(battery_current_a=None), tmp_path / "plain.csv"))
    assert plain.battery_current_a is None and plain.battery_voltage_v is not None


def test_csv_pack_current_in_milliamps_and_without_voltage(tmp_path):
    log = _log()
    path = write_csv_log(log, tmp_path / "run.csv")
    text = path.read_text().splitlines()
    header = text[1].split(",")
    k = header.index("battery_current_a")
    rows = [r.split(",") for r in text[2:]]
    for r in rows:
        if r[k]:
            r[k] = repr(float(r[k]) * 1000.0)
    (tmp_path / "ma.csv").write_text("\n".join(text[:2] + [",".join(r) for r in rows]) + "\n")
    cols = {f: c for f, c in (("time", "time_s"), ("v", "v_mps"), ("omega", "omega_radps"), ("accel_z", "accel_z_mps2"),
                              ("battery_voltage", "battery_voltage_v"), ("battery_current", "battery_current_a"))}
    back = read_csv_log(tmp_path / "ma.csv", CsvLayout(columns=cols, units={"battery_current": "mA"}))
    np.testing.assert_allclose(back.battery_current_a, log.battery_current_a)
    del cols["battery_voltage"]
    with pytest.raises(InvalidParameterError, match="needs battery_voltage_v"):
        read_csv_log(tmp_path / "ma.csv", CsvLayout(columns=cols, units={"battery_current": "mA"}))


def _sim_run(battery, noise, seed=3):
    rb = robot_preset("husky")
    sim = TruthSimulator(rb, PAPER_GROUNDS, noise=noise, battery=battery)
    t = np.arange(600) * 0.01
    v = np.where(t > 1.0, 0.8, 0.0)
    w = np.where(t > 3.0, 0.6, 0.0)
    return sim.run_commands(t, v, w, ground="coated_wood", seed=seed)


def test_truth_simulator_pack_power_is_the_total_power():
    rb = robot_preset("husky")
    pack = Battery(20.0, rb.battery_voltage_v, internal_resistance_ohm=0.05)
    run = _sim_run(pack, NoiseModel.off())
    total = np.asarray(run.breakdown.total_power_w)
    np.testing.assert_allclose(run.log.battery_power_w, total, rtol=1e-12, atol=1e-9)
    # the terminal voltage sags with the current; the electronics draw power at standstill
    np.testing.assert_allclose(run.log.battery_voltage_v, rb.battery_voltage_v - 0.05 * run.log.battery_current_a)
    assert total[0] == pytest.approx(rb.sensor_power_w + rb.control_standby_power_w)
    assert total.max() > total[0] + 50.0


def test_truth_simulator_battery_noise_is_small_and_leaves_other_streams_alone():
    rb = robot_preset("husky")
    run = _sim_run(Battery(20.0, rb.battery_voltage_v), NoiseModel())
    rel = (run.log.battery_power_w - np.asarray(run.breakdown.total_power_w)) / np.asarray(run.breakdown.total_power_w)
    assert 0.002 < float(np.std(rel)) < 0.03
    plain = _sim_run(None, NoiseModel())
    assert plain.log.battery_current_a is None and plain.log.battery_voltage_v is None
    for name in ("current_left_a", "current_right_a", "accel_z_mps2"):
        np.testing.assert_array_equal(getattr(run.log, name), getattr(plain.log, name))
    with pytest.raises(InvalidParameterError, match="battery must be None or a Battery"):
        TruthSimulator(rb, PAPER_GROUNDS, battery=24.0)
    with pytest.raises(InvalidParameterError, match="battery_current_noise_rel"):
        NoiseModel(battery_current_noise_rel=-0.1)
