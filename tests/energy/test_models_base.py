"""Tests of energy.models.base: checking logs, their currents, the training summary and the model file."""

import json
import zipfile

import numpy as np
import pytest

from energy import InteractionLog, LogMeta
from energy.models import (
    CURRENT_MODEL_FORMAT,
    CURRENT_MODEL_FORMAT_VERSION,
    ModelRecord,
    TrainedOn,
    check_logs,
    log_currents,
    read_model_file,
    write_model_file,
)
from energy.models.base import package_versions
from terrawatt_base.errors import DataError, FileFormatError, FormatVersionError, InvalidParameterError


def _log(robot: str = "husky", ground: str | None = "sand", duration_s: float = 10.0, currents: bool = True) -> InteractionLog:
    t = np.arange(0.0, duration_s, 0.5)
    ta = np.arange(0.0, t[-1] + 0.005, 0.01)
    left, right = (np.full(t.size, 1.0), np.full(t.size, 2.0)) if currents else (None, None)
    return InteractionLog(t, np.full(t.size, 0.5), np.zeros(t.size), left, right, ta, np.full(ta.size, 9.81),
                          meta=LogMeta(robot=robot, ground_label=ground))


def test_check_logs_takes_one_log_or_a_sequence():
    log = _log()
    assert check_logs(log) == [log] and check_logs((log, log)) == [log, log]
    with pytest.raises(InvalidParameterError, match="logs must be an InteractionLog or a sequence of them, got 'run.csv'"):
        check_logs("run.csv")
    with pytest.raises(InvalidParameterError, match="train must hold at least one InteractionLog, got an empty sequence"):
        check_logs([], "train")
    with pytest.raises(InvalidParameterError, match=r"logs\[1\] must be an InteractionLog, got 3"):
        check_logs([log, 3])


def test_log_currents_are_left_and_right_columns():
    cur = log_currents(_log())
    assert cur.shape == (20, 2) and cur[0].tolist() == [1.0, 2.0]
    with pytest.raises(DataError):
        log_currents(_log(currents=False))


def test_training_summary_counts_seconds_per_ground():
    s = TrainedOn.from_logs([_log(), _log(ground=None, robot="jackal"), _log(duration_s=4.0)])
    assert s.robots == ("husky", "jackal") and s.runs == 3
    assert s.grounds == {"sand": pytest.approx(9.5 + 3.5), "unlabelled": pytest.approx(9.5)}
    both = s.merged(TrainedOn(("husky",), {"sand": 1.0, "grass": 2.0}, 1))
    assert both.runs == 4 and both.grounds["grass"] == 2.0 and both.grounds["sand"] == pytest.approx(14.0)
    assert TrainedOn.from_plain(s.to_plain()) == s


@pytest.mark.parametrize(("plain", "match"), [
    ({"robots": []}, "must hold exactly 'robots', 'grounds' and 'runs'"),
    ({"robots": "husky", "grounds": {}, "runs": 1}, "robots must be a list of names"),
    ({"robots": [], "grounds": [1.0], "runs": 1}, "grounds must map names to seconds"),
    ({"robots": [], "grounds": {"a": -1.0}, "runs": 1}, "seconds on 'a'"),
    ({"robots": [], "grounds": {}, "runs": -1}, "runs"),
])
def test_training_summary_from_a_malformed_entry(plain, match):
    with pytest.raises(InvalidParameterError, match=match):
        TrainedOn.from_plain(plain)


def test_package_versions_name_terrawatt_numpy_python_and_extras():
    v = package_versions(torch="2.0")
    assert set(v) == {"terrawatt", "numpy", "python", "torch"} and v["numpy"] == np.__version__


def test_a_record_round_trips_through_the_file(tmp_path):
    rec = ModelRecord("LinearCurrentModel", {"alpha": 0.5, "names": ("a", "b")},
                      {"coef": np.arange(6.0).reshape(3, 2), "n": np.int64(3), "nested": {"k": [np.ones(2)]}},
                      versions={"numpy": "2"}, trained_on={"robots": ["husky"], "grounds": {"g": 1.0}, "runs": 1})
    path = write_model_file(tmp_path / "m.zip", rec)
    with zipfile.ZipFile(path) as archive:
        head = json.loads(archive.read("model.json"))
    assert head["format"] == CURRENT_MODEL_FORMAT and head["format_version"] == CURRENT_MODEL_FORMAT_VERSION
    back = read_model_file(path)
    assert back.model_class == "LinearCurrentModel" and back.params == {"alpha": 0.5, "names": ["a", "b"]}
    np.testing.assert_array_equal(back.state["coef"], rec.state["coef"])
    assert back.state["n"] == 3 and back.state["nested"]["k"][0].tolist() == [1.0, 1.0]
    assert back.trained_on == rec.trained_on and back.interval is None and back.versions == {"numpy": "2"}


def test_read_model_file_documented_errors(tmp_path):
    with pytest.raises(FileFormatError, match="current-model file .* does not exist or is not a file"):
        read_model_file(tmp_path / "nope.zip")
    path = write_model_file(tmp_path / "m.zip", ModelRecord("X", {}, {}))
    with zipfile.ZipFile(path) as archive:
        head = json.loads(archive.read("model.json"))
    for change, error, match in [
        ({"format_version": 7}, FormatVersionError, r"current-model format version 7; this release reads versions \[1, 2\]"),
        ({"format": "other"}, FileFormatError, "is not a terrawatt current-model file"),
        ({"params": [1]}, FileFormatError, "the 'params' entry must be a dict, got list"),
    ]:
        forged = tmp_path / "forged.zip"
        with zipfile.ZipFile(forged, "w") as archive:
            archive.writestr("model.json", json.dumps(head | change))
        with pytest.raises(error, match=match):
            read_model_file(forged)
    (tmp_path / "junk.zip").write_bytes(b"not a zip")
    with pytest.raises(FileFormatError, match="is not a readable terrawatt current-model file"):
        read_model_file(tmp_path / "junk.zip")
    with pytest.raises(InvalidParameterError):
        write_model_file(tmp_path, ModelRecord("X", {}, {}))  # a directory
