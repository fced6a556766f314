"""Tests of energy.diagnosis.model_currents: the physics basis, unclipped currents and the ParameterTable surrogate."""

import numpy as np


def test_parameter_table_is_exact_at_nodes_and_linear_between():
    from energy.diagnosis.model_currents import ParameterTable

    base = np.column_stack([np.linspace(0.0, 1.0, 5), np.linspace(1.0, 2.0, 5)])
    table = ParameterTable(lambda x: base * x ** 2, 0.0, 2.0, 0.7, n_nodes=5)
    assert 0.7 in table.nodes and table.n_computed == 0  # the nominal is a node; nothing computed yet
    np.testing.assert_allclose(table.at(0.7), base * 0.49)
    np.testing.assert_allclose(table.at(1.5), base * 2.25)
    np.testing.assert_allclose(table.at(1.75), base * (2.25 + 4.0) / 2.0)  # linear between 1.5 and 2.0
    per_sample = np.array([0.0, 0.7, 1.75, 2.0, 9.0])  # clipped to the bounds
    expected = base * np.array([0.0, 0.49, 3.125, 4.0, 4.0])[:, None]
    np.testing.assert_allclose(table.at(per_sample), expected)
    assert table.nodes.size == 6 and table.n_computed == 6
