"""The ``terrawatt train`` command (terrawatt_cli.train): threads, loss display and refused outputs."""

from __future__ import annotations

import pytest
from cli_samples import FIXTURES, one_line_error

from terrawatt_cli import main


@pytest.fixture
def tiny_paper_preset(monkeypatch):
    """The ``paper`` preset shrunk to train in a second on the two short fixture runs."""
    from energy import estimator_preset
    from energy.models import ESTIMATOR_PRESETS

    small = estimator_preset("paper").replace(max_epochs=2, n_spectrum_bins=100, hidden_sizes=(8, 8, 8))
    monkeypatch.setitem(ESTIMATOR_PRESETS, "paper", small)


def test_train_passes_threads_and_shows_the_loss(tmp_path, capsys, monkeypatch, tiny_paper_preset):
    import torch

    from energy import load_current_model

    calls = []
    real = torch.set_num_threads
    monkeypatch.setattr(torch, "set_num_threads", lambda n: (calls.append(n), real(n))[1])
    before = torch.get_num_threads()
    model = tmp_path / "paper.pt"
    assert main(["train", "--data", str(FIXTURES), "--model", "paper", "--threads", "1", "--out", str(model)]) == 0
    loaded = load_current_model(model)
    assert (loaded.n_threads, loaded.progress) == (1, True)
    assert calls[0] == 1 and torch.get_num_threads() == before  # used while fitting, restored after
    assert "loss=" in capsys.readouterr().err  # the progress bar's postfix

    quiet = tmp_path / "quiet.pt"
    assert main(["train", "--data", str(FIXTURES), "--model", "paper", "--quiet", "--out", str(quiet)]) == 0
    loaded = load_current_model(quiet)
    assert (loaded.n_threads, loaded.progress) == (None, False)
    assert "loss=" not in capsys.readouterr().err


@pytest.mark.parametrize(
    "extra, message",
    [(["--model", "paper", "--threads", "0"], "--threads must be a positive number of threads, got 0"),
     (["--model", "linear", "--threads", "2"], "--threads applies to the estimator and paper models only")],
)
def test_train_bad_threads_is_an_error(tmp_path, capsys, extra, message):
    rc = main(["train", "--data", str(FIXTURES), *extra, "--out", str(tmp_path / "m.pt")])
    assert rc == 2
    assert message in capsys.readouterr().err
    assert not (tmp_path / "m.pt").exists()


def test_train_onto_a_directory_is_refused_before_training(tmp_path, capsys, monkeypatch):
    import terrawatt_cli.train as train_cli

    monkeypatch.setattr(train_cli, "logs_from_args", lambda *a, **k: pytest.fail("read the logs before checking --out"))
    rc = main(["train", "--data", str(FIXTURES), "--model", "linear", "--out", str(tmp_path)])
    assert rc == 2
    assert "--out" in one_line_error(capsys)
    blocker = tmp_path / "file"
    blocker.write_text("x")
    rc = main(["train", "--data", str(FIXTURES), "--model", "linear", "--out", str(blocker / "model.pt")])
    assert rc == 2
    assert "--out" in one_line_error(capsys)


def test_train_physics_on_a_robot_file_keeps_that_robot(tmp_path, capsys):
    from energy import load_current_model, robot_preset
    from energy.params import write_robot_file

    rover = robot_preset("jackal").replace(name="rover")
    write_robot_file(rover, tmp_path / "rover.json")
    rc = main(["train", "--data", str(FIXTURES), "--model", "physics", "--robot", str(tmp_path / "rover.json"),
               "--out", str(tmp_path / "m.zip")])
    assert rc == 0 and load_current_model(tmp_path / "m.zip").robot_ == rover
    capsys.readouterr()
    assert main(["train", "--data", str(FIXTURES), "--model", "linear", "--robot", "jackal",
                 "--out", str(tmp_path / "l.zip")]) == 2
    assert "--robot applies to the physics model only, got --model linear" in one_line_error(capsys)
    assert not (tmp_path / "l.zip").exists()
    robot_file = (tmp_path / "rover.json").read_bytes()
    assert main(["train", "--data", str(FIXTURES), "--model", "physics", "--robot", str(tmp_path / "rover.json"),
                 "--out", str(tmp_path / "rover.json")]) == 2  # the robot file is an input: never overwritten
    assert "would replace the input" in one_line_error(capsys)
    assert (tmp_path / "rover.json").read_bytes() == robot_file


def test_the_command_line_says_the_libraries_parameters_by_its_flags():
    from energy.models import ModelOptions, check_training_options
    from terrain import InvalidParameterError
    from terrawatt_cli import error_message
    from terrawatt_cli.train import _FLAGS

    with pytest.raises(InvalidParameterError) as raised:
        check_training_options("linear", n_threads=2)
    assert error_message(raised.value, _FLAGS) == ("--threads applies to the estimator and paper models only, got "
                                                   "--model 'linear'")
    assert check_training_options("estimator", n_threads=2, options=ModelOptions(band_hz=[0, 25])).band_hz == (0.0, 25.0)
