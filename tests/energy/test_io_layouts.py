"""Tests of energy.io.layouts: read_logs (every layout at one path), BagTopics, the commands that read through it."""

from __future__ import annotations

import json
import shutil
from pathlib import Path

import numpy as np
import pytest
from robot_bags import requires_rosbags, write_robot_bag

from energy import BagTopics, InteractionLog, LogMeta, new_current_model, read_borealtc, read_logs, write_csv_log
from energy.io import LOG_SUFFIXES
from terrain import DataError, InvalidParameterError, UnknownNameError
from terrawatt_cli import main

FIXTURES = Path(__file__).resolve().parents[1] / "fixtures" / "borealtc"
ODOM = BagTopics(cmd_vel_topic="/odometry/filtered")
HUSKY = BagTopics(cmd_vel_topic="/odometry/filtered", current_topics=("/status",),
                  current_fields=("left_driver_current", "right_driver_current"), voltage_field="battery_voltage")
HUSKY_FLAGS = ["--cmd-vel-topic", "/odometry/filtered", "--current-topics", "/status",
               "--current-fields", "left_driver_current", "right_driver_current", "--voltage-field", "battery_voltage"]


def csv_run(path: Path, ground: str | None = "sand", seed: int = 0, currents: bool = True) -> Path:
    rng = np.random.default_rng(seed)
    t, ta = np.arange(100) * 0.1, np.arange(1000) * 0.01
    cur = (np.full(100, 2.0) + 0.1 * rng.random(100), np.full(100, 2.5)) if currents else (None, None)
    log = InteractionLog(t, np.full(100, 0.5), 0.1 * np.sin(t), *cur, ta, 9.81 + 0.3 * rng.standard_normal(1000),
                         gyro_z_radps=0.1 * np.sin(ta), meta=LogMeta(robot="husky", ground_label=ground))
    return write_csv_log(log, path)


@pytest.fixture(scope="module")
def layouts(tmp_path_factory) -> dict[str, Path]:
    root = tmp_path_factory.mktemp("layouts")
    out = {"borealtc": FIXTURES}
    out["csv"] = csv_run(root / "one.csv")
    (root / "csvs").mkdir()
    for k in range(3):
        csv_run(root / "csvs" / f"run{k}.csv", seed=k)
    (root / "csvs" / "notes.txt").write_text("not a log")
    out["csvs"] = root / "csvs"
    out["constant_model"] = new_current_model("constant").fit(read_borealtc(FIXTURES)).save(root / "constant.zip")
    return out


@pytest.fixture(scope="module")
def bag_layouts(tmp_path_factory) -> dict[str, Path]:
    pytest.importorskip("rosbags", reason="rosbags (the 'ros' extra) is not installed")
    root = tmp_path_factory.mktemp("bag_layouts")
    out = {}
    write_robot_bag(root / "husky.bag", duration_s=20.0)
    out["ros1"] = root / "husky.bag"
    write_robot_bag(root / "ros2", kind="ros2", duration_s=20.0)
    out["ros2"] = root / "ros2"
    write_robot_bag(root / "mcap", kind="mcap", duration_s=20.0)
    out["mcap_file"] = next((root / "mcap").glob("*.mcap"))
    for ground in ("grass", "gravel"):
        (root / "grounds" / ground).mkdir(parents=True)
        for k in range(2):
            write_robot_bag(root / "grounds" / ground / f"run{k}.bag", duration_s=10.0, seed=k)
    out["grounds"] = root / "grounds"
    (root / "small").mkdir()
    for k in range(2):
        write_robot_bag(root / "small" / f"run{k}.bag", duration_s=6.0, seed=k)
    out["small"] = root / "small"
    (root / "mixed").mkdir()
    shutil.copy(root / "husky.bag", root / "mixed" / "a.bag")
    shutil.copytree(root / "ros2", root / "mixed" / "b_ros2")
    out["mixed"] = root / "mixed"
    write_robot_bag(root / "jackal.bag", imu_hz=50.0, status_hz=None, duration_s=20.0)
    out["jackal"] = root / "jackal.bag"
    return out


# ------------------------------------------------------------------ library
def test_borealtc_folder_is_read_like_read_borealtc(layouts):
    logs = read_logs(layouts["borealtc"])
    ref = read_borealtc(FIXTURES)
    assert [log.meta.source for log in logs] == [log.meta.source for log in ref]
    np.testing.assert_array_equal(logs[0].current_left_a, ref[0].current_left_a)
    assert [log.meta.ground_label for log in read_logs(layouts["borealtc"], ["SNOW"])] == ["snow"]


def test_csv_file_and_folder_of_csv_logs(layouts):
    (one,) = read_logs(layouts["csv"])
    assert one.meta.ground_label == "sand" and one.gyro_z_radps is not None and one.has_currents
    logs = read_logs(layouts["csvs"])
    assert [Path(log.meta.source).name for log in logs] == ["run0.csv", "run1.csv", "run2.csv"]
    (labelled,) = read_logs(layouts["csv"], ground_label="clay")
    assert labelled.meta.ground_label == "clay"
    assert len(read_logs(layouts["csvs"], ["SAND"])) == 3
    with pytest.raises(UnknownNameError, match=r"grounds \['snow'\]: no log at path .* the logs' labels: \['sand'\]"):
        read_logs(layouts["csvs"], ["snow"])


def test_csv_log_without_currents_is_read_and_refused_when_required(tmp_path):
    path = csv_run(tmp_path / "nocur.csv", currents=False)
    (log,) = read_logs(path)
    assert not log.has_currents and "no current columns" in log.meta.missing_currents
    with pytest.raises(DataError, match=r"needs measured drive currents, and this log has none \(no current columns"):
        read_logs(path, require_currents=True)


@requires_rosbags
@pytest.mark.parametrize("layout", ["ros1", "ros2", "mcap_file"])
def test_each_bag_layout_with_status_currents(bag_layouts, layout):
    (log,) = read_logs(bag_layouts[layout], bag=HUSKY, robot="husky", require_currents=True)
    assert log.has_currents and log.battery_voltage_v is not None and log.gyro_z_radps is not None
    assert log.meta.robot == "husky" and log.current_left_a.mean() == pytest.approx(3.0, abs=0.3)


@requires_rosbags
def test_ground_folders_and_a_mixed_folder_of_bags(bag_layouts):
    logs = read_logs(bag_layouts["grounds"], bag=HUSKY)
    assert [log.meta.ground_label for log in logs] == ["grass", "grass", "gravel", "gravel"]
    assert [log.meta.ground_label for log in read_logs(bag_layouts["grounds"], ["gravel"], bag=HUSKY)] == ["gravel"] * 2
    mixed = read_logs(bag_layouts["mixed"], bag=HUSKY, ground_label="lab")
    assert [Path(log.meta.source).name for log in mixed] == ["a.bag", "b_ros2"]
    assert {log.meta.ground_label for log in mixed} == {"lab"}


def test_bad_paths_and_arguments(tmp_path, layouts):
    with pytest.raises(DataError, match=r"^path '.*missing' does not exist") as err:
        read_logs(tmp_path / "missing")
    assert err.value.parameter == "path"  # the command line says it as its flag (--data)
    (tmp_path / "x.txt").write_text("x")
    with pytest.raises(DataError, match=r"unknown log file type '.txt'; expected one of \['.bag'"):
        read_logs(tmp_path / "x.txt")
    (tmp_path / "empty").mkdir()
    with pytest.raises(DataError, match="holds no logs"):
        read_logs(tmp_path / "empty")
    with pytest.raises(InvalidParameterError, match="bag must be a BagTopics"):
        read_logs(layouts["csv"], bag={"imu_topic": "/imu"})
    with pytest.raises(InvalidParameterError, match="grounds must be ground names"):
        read_logs(layouts["csv"], grounds=[3])
    assert set(LOG_SUFFIXES) == {".csv", ".bag", ".db3", ".mcap"}


@pytest.mark.parametrize(("kwargs", "match"), [
    (dict(current_topics=()), r"current_topics must be 1 or 2 non-empty name"),
    (dict(current_topics=("/a", "/b", "/c")), r"current_topics must be 1 or 2"),
    (dict(current_fields=("left",), current_topics=("/status",)), r"current_fields must be 2 non-empty name"),
    (dict(current_fields=("l", "r")), r"give one current topic"),
    (dict(voltage_field="battery_voltage", current_topics=("/status",)), r"name them too with current_fields"),
    (dict(imu_topic=""), r"imu_topic"),
])
def test_bag_topics_are_validated(kwargs, match):
    with pytest.raises(InvalidParameterError, match=match):
        BagTopics(**kwargs)
    with pytest.raises(UnknownNameError, match="current_unit"):
        BagTopics(current_unit="uA")


# ------------------------------------------------------------------ commands
def run_cli(capsys, *argv) -> tuple[int, str, str]:
    rc = main([str(a) for a in argv])
    out, err = capsys.readouterr()
    return rc, out, err


@requires_rosbags
@pytest.mark.filterwarnings("ignore::terrain.FigureWarning")  # the spectra figure stops at the 30 Hz IMU's Nyquist
def test_train_predict_evaluate_diagnose_accept_folders_of_bags(bag_layouts, tmp_path, capsys):
    data = bag_layouts["grounds"]
    rc, out, err = run_cli(capsys, "train", "--data", data, "--model", "physics", "--out", tmp_path / "m.zip", *HUSKY_FLAGS)
    assert rc == 0 and "on 4 runs" in out, err
    rc, out, err = run_cli(capsys, "predict", "--model", tmp_path / "m.zip", "--data", data, "--out", tmp_path / "p",
                           "--grounds", "grass", *HUSKY_FLAGS)
    assert rc == 0 and "grass/run0" in out and "gravel" not in out, err
    rc, out, err = run_cli(capsys, "evaluate", "--data", data, "--model", "constant", "--variants", "per_ground",
                           "--out", tmp_path / "e", *HUSKY_FLAGS)
    assert rc == 0 and "4 runs" in out, err
    assert json.loads((tmp_path / "e" / "evaluation.json").read_text())
    rc, out, err = run_cli(capsys, "diagnose", "--model", "physics", "--data", bag_layouts["small"], "--out",
                           tmp_path / "d", "--quiet", *HUSKY_FLAGS)
    assert rc == 0 and (tmp_path / "d" / "diagnosis.json").is_file(), err


@requires_rosbags
def test_predict_on_a_bag_without_currents_and_the_others_refuse_it(bag_layouts, tmp_path, capsys):
    rc, _, err = run_cli(capsys, "train", "--data", FIXTURES, "--model", "physics", "--out", tmp_path / "m.zip")
    assert rc == 0, err
    jackal = bag_layouts["jackal"]
    rc, out, err = run_cli(capsys, "predict", "--model", tmp_path / "m.zip", "--data", jackal, "--out", tmp_path / "p",
                           "--cmd-vel-topic", "/odometry/filtered")
    assert rc == 0 and "predictions only" in out, err
    (run,) = json.loads((tmp_path / "p" / "predictions.json").read_text())["runs"]
    assert run["charge_predicted_left_mah"] > 0 and run["charge_measured_left_mah"] is None
    for argv in (["train", "--model", "physics", "--out", tmp_path / "m2.zip"],
                 ["evaluate", "--model", "constant", "--out", tmp_path / "e"],
                 ["diagnose", "--model", "physics", "--out", tmp_path / "d"]):
        rc, _, err = run_cli(capsys, *argv, "--data", jackal, "--cmd-vel-topic", "/odometry/filtered")
        assert rc == 2 and err.count("\n") == 1, argv
        assert "needs measured drive currents" in err and "'/drive/current_left'" in err and "--current-topics" in err


@requires_rosbags
@pytest.mark.parametrize(("flags", "match"), [
    (["--current-topics", "/status", "--current-fields", "left_current", "right_driver_current"],
     "has no field 'left_current' (named by --current-fields)"),
    (["--current-topics", "/status"], "name its current fields with --current-fields (e.g. left_driver_current"),
    (["--current-topics", "/status", "--voltage-field", "battery_voltage"], "name them too with --current-fields"),
    (["--current-topics", "/status", "--current-fields", "left_driver_current", "right_driver_current",
      "--voltage-field", "volts"], "has no field 'volts' (named by --voltage-field)"),
    (["--imu-topic", "/imu/raw"], "topic(s) ['/imu/raw'] not in the bag"),
])
@pytest.mark.parametrize("command", ["train", "predict"])
def test_bad_bag_flags_exit_2_naming_the_option(layouts, bag_layouts, tmp_path, capsys, flags, match, command):
    argv = ["--data", bag_layouts["ros1"], "--cmd-vel-topic", "/odometry/filtered", *flags]
    if command == "train":
        argv = ["train", "--model", "constant", "--out", tmp_path / "m.zip", *argv]
    else:
        argv = ["predict", "--model", layouts["constant_model"], "--out", tmp_path / "p", *argv]
    rc, _, err = run_cli(capsys, *argv)
    assert rc == 2 and err.startswith("terrawatt: error: ") and err.count("\n") == 1
    assert match in err


@pytest.mark.parametrize("command", ["train", "evaluate", "predict", "diagnose"])
def test_every_command_accepts_a_csv_log_folder_and_refuses_a_missing_path(layouts, tmp_path, capsys, command):
    model = {"train": ["--model", "constant", "--out", tmp_path / "m.zip"],
             "evaluate": ["--model", "constant", "--variants", "per_ground", "--out", tmp_path / "e"],
             "predict": ["--model", layouts["constant_model"], "--out", tmp_path / "p"],
             "diagnose": ["--model", "physics", "--out", tmp_path / "d", "--quiet"]}[command]
    rc, _, err = run_cli(capsys, command, "--data", layouts["csvs"], *model)
    assert rc == 0, err
    rc, _, err = run_cli(capsys, command, "--data", tmp_path / "nowhere", *model)
    assert rc == 2 and "--data" in err and "does not exist" in err


# --------------------------------------------------------------------------- CSV logs of another layout
GENERIC = Path(__file__).resolve().parents[1] / "fixtures" / "generic_ma.csv"
GENERIC_LAYOUT = dict(columns={"time": "stamp_ms", "v": "cmd_v", "omega": "cmd_w", "current_left": "left_mA",
                               "current_right": "right_mA", "accel_z": "acc_z", "ground": "label"},
                      units={"time": "ms", "current_left": "mA", "current_right": "mA", "omega": "deg/s"})


def test_a_folder_of_csv_logs_of_another_layout_reads_as_read_csv_log_reads_each(tmp_path):
    from energy import read_csv_log
    from energy.io import CsvLayout

    for name in ("a.csv", "b.csv"):
        shutil.copy(GENERIC, tmp_path / name)
    logs = read_logs(tmp_path, csv=CsvLayout(**GENERIC_LAYOUT), require_currents=True)
    one = read_csv_log(GENERIC, CsvLayout(GENERIC_LAYOUT["columns"], GENERIC_LAYOUT["units"]))
    assert len(logs) == 2
    for log in logs:
        assert log.time_s.tolist() == one.time_s.tolist() and log.current_left_a.tolist() == one.current_left_a.tolist()
        assert log.omega_radps.tolist() == one.omega_radps.tolist() and log.ground.tolist() == one.ground.tolist()
    assert one.current_left_a[0] == pytest.approx(1.0)  # 1000 mA, declared


def test_a_csv_of_another_layout_without_its_map_says_how_to_give_one(tmp_path):
    with pytest.raises(DataError, match=r"missing column\(s\) \['time_s', .* of the layout terrawatt writes; the header "
                                        r"has \['stamp_ms'.*`columns` \(time=COLUMN v=COLUMN ...\) and `units` "
                                        r"\(time=ms ...\) of the CSV layout$") as raised:
        read_logs(GENERIC)
    assert raised.value.parameter == ("columns", "units")  # the command line says --csv-columns, --csv-units


@pytest.mark.parametrize(("kwargs", "error", "match"), [
    ({"columns": {"tim": "t"}}, UnknownNameError, r"unknown field\(s\) \['tim'\]"),
    ({"columns": {"time": ""}}, InvalidParameterError, "non-empty column names"),
    ({"columns": {"time": "t", "current_left": "i", "current_right": "i"}}, InvalidParameterError,
     r"several fields to one column: \{'i': \['current_left', 'current_right'\]\}"),
    ({"columns": {"time": "t"}, "units": {"v": "m/s"}}, UnknownNameError, r"field\(s\) \['v'\] that are not"),
    ({"columns": {"time": "t"}, "units": {"time": "fortnights"}}, UnknownNameError, "unit 'fortnights'"),
    ({"units": {"time": "fortnights"}}, UnknownNameError, "unit 'fortnights'"),  # units of the default columns
    ({"rates": "double"}, UnknownNameError, "rates must be one of"),
    ({"columns": "time=t"}, InvalidParameterError, "columns must be a mapping of field names, got 'str'"),
    ({"columns": {"time": "t"}, "units": "ms"}, InvalidParameterError, "units must be a mapping"),
    ({"track_width_m": -0.5}, InvalidParameterError, "track_width_m must be > 0"),
])
def test_a_csv_layout_is_checked_when_made(kwargs, error, match):
    from energy.io import CsvLayout

    with pytest.raises(error, match=match):
        CsvLayout(**kwargs)
    with pytest.raises(InvalidParameterError, match="csv must be a CsvLayout"):
        read_logs(GENERIC, csv=GENERIC_LAYOUT)


# --------------------------------------------------------------------------- a CSV layout where it cannot apply
@pytest.mark.parametrize(("kwargs", "given"), [
    ({"columns": GENERIC_LAYOUT["columns"]}, r"columns=\{'time': 'stamp_ms'"),
    ({"rates": "single"}, r"rates='single'"),
    ({"track_width_m": 0.5}, r"track_width_m=0\.5"),  # BorealTC logs are wheel speeds, but their own track width
])
def test_a_csv_layout_for_a_borealtc_folder_is_refused_not_ignored(kwargs, given):
    from energy.io import CsvLayout

    with pytest.raises(InvalidParameterError, match=(
            r"^`csv` applies to CSV logs only, and path "
            r"'.*borealtc' is read as a BorealTC folder \(GROUND/imu_NN\.csv \+ pro_NN\.csv\), whose columns, units "
            r"and track width \(0\.555 m\) are the format's own; give no CSV layout for them \(got " + given)) as raised:
        read_logs(FIXTURES, csv=CsvLayout(**kwargs))
    assert raised.value.parameter == ("path", "csv")
    assert len(read_logs(FIXTURES, csv=CsvLayout())) == len(read_borealtc(FIXTURES))  # the default layout: no layout


@requires_rosbags
def test_a_csv_layout_for_bags_only_is_refused_not_ignored(bag_layouts):
    from energy.io import CsvLayout

    for path in (bag_layouts["ros1"], bag_layouts["mixed"]):
        with pytest.raises(InvalidParameterError, match=r"applies to CSV logs only, and path '.*' holds no CSV log, "
                                                        r"only bags \(read with the bag options\)"):
            read_logs(path, bag=HUSKY, csv=CsvLayout(rates="single"))


def test_a_track_width_beside_v_and_omega_columns_is_refused_not_recorded(tmp_path):
    from energy.io import CsvLayout

    with pytest.raises(InvalidParameterError, match=(
            r"track_width_m 0\.5 derives omega from wheel speeds \(speed_left / speed_right "
            r"columns\), but the layout's velocities are v and omega \('cmd_v', 'cmd_w'\): there is no omega to "
            r"derive; drop the track width, or map the wheel speeds instead \(`columns` speed_left=COLUMN "
            r"speed_right=COLUMN\)")) as raised:
        CsvLayout(**GENERIC_LAYOUT, track_width_m=0.5)
    assert raised.value.parameter == ("track_width_m", "columns")
    default = CsvLayout(track_width_m=0.5)  # maybe meant for logs of another kind: refused when a CSV log is read
    with pytest.raises(InvalidParameterError, match=r"but the default layout's velocities are v and omega "
                                                    r"\('v_mps', 'omega_radps'\)"):
        read_logs(csv_run(tmp_path / "run.csv"), csv=default)
    wheels = tmp_path / "wheels.csv"
    wheels.write_text("t,wl,wr,il,ir,az\n0,0.1,0.3,1.5,2.5,9.8\n0.5,0.2,0.2,1.6,2.4,9.7\n1.0,0.4,0.0,1.7,2.3,9.9\n")
    layout = CsvLayout({"time": "t", "speed_left": "wl", "speed_right": "wr", "current_left": "il",
                        "current_right": "ir", "accel_z": "az"}, rates="single", track_width_m=0.5)
    (log,) = read_logs(wheels, csv=layout)
    assert log.meta.track_width_m == 0.5 and log.omega_radps[0] == pytest.approx(0.4)
