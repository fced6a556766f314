"""Tests of energy.models.data: WindowDataset (inputs, targets, subsets, the validation tail of each run)."""

import numpy as np
import pytest
import torch

from energy.features import WindowSpec
from energy.models import WindowDataset
from terrawatt_base.errors import DataError, InvalidParameterError


def _two_runs(y: bool = True) -> WindowDataset:
    """Two runs of ten windows each, 2 samples long at stride 2: starts 0, 2, ..., 18."""
    start = np.tile(np.arange(10) * 2, 2)
    run = np.repeat([0, 1], 10)
    x = np.arange(20.0)[:, None]
    return WindowDataset(x, np.array([[1.0], [2.0]]), run, start, WindowSpec(2, 2, 10.0), y=x * 2.0 if y else None)


def test_inputs_and_targets_of_a_batch():
    ds = _two_runs()
    assert len(ds) == 20
    x, table, idx = ds.inputs(torch.tensor([0, 15]))
    assert x.tolist() == [[0.0], [15.0]] and table.tolist() == [[1.0], [2.0]] and idx.tolist() == [0, 1]
    assert ds.targets(slice(0, 2)).tolist() == [[0.0], [2.0]]
    assert x.dtype == torch.float32 and idx.dtype == torch.int64
    with pytest.raises(DataError, match="this WindowDataset has no targets"):
        _two_runs(y=False).targets(slice(0, 2))


def test_arrays_of_different_lengths_are_refused():
    with pytest.raises(InvalidParameterError, match="WindowDataset arrays disagree in length: x_window 3"):
        WindowDataset(np.zeros((3, 1)), np.zeros((1, 0)), np.zeros(2, int), np.arange(3), WindowSpec(1, 1, 1.0))
    with pytest.raises(InvalidParameterError, match="disagree in length"):
        WindowDataset(np.zeros((3, 1)), np.zeros((1, 0)), np.zeros(3, int), np.arange(3), WindowSpec(1, 1, 1.0),
                      y=np.zeros((2, 1)))


def test_subset_keeps_the_run_table():
    sub = _two_runs().subset(np.arange(20) % 5 == 0)
    assert sub.x_window[:, 0].tolist() == [0.0, 5.0, 10.0, 15.0]
    assert sub.start.tolist() == [0, 10, 0, 10] and sub.run_index.tolist() == [0, 0, 1, 1]
    assert sub.run_table.shape == (2, 1) and sub.y[:, 0].tolist() == [0.0, 10.0, 20.0, 30.0]


def test_split_tail_holds_out_the_end_of_every_run_without_overlap():
    ds = _two_runs()
    assert ds.split_tail(0.0) == (ds, None)
    train, val = ds.split_tail(0.2)  # each run spans samples 0-20: validation from sample 16
    assert val.start.tolist() == [16, 18, 16, 18] and val.run_index.tolist() == [0, 0, 1, 1]
    assert train.start.tolist() == list(range(0, 16, 2)) * 2  # windows ending at or before 16
    overlapping = WindowDataset(np.zeros((4, 1)), np.zeros((1, 0)), np.zeros(4, int), [0, 1, 2, 3], WindowSpec(2, 1, 1.0))
    train, val = overlapping.split_tail(0.4)  # samples 0-5: validation from sample 3
    assert val.start.tolist() == [3] and train.start.tolist() == [0, 1]  # window 2 (samples 2-3) overlaps it: dropped
