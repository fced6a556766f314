"""Where a figure goes: exactly one of a path to write or the caller's axes, checked before drawing; the figure made
for a path is matplotlib's object API, so no library module touches the backend or pyplot."""

from __future__ import annotations

import ast
from pathlib import Path

import numpy as np
import pytest
from matplotlib.figure import Figure

from terrain import InvalidParameterError
from terrawatt_base.atomic import save_figure
from terrawatt_base.plot_target import check_ax, check_axes, check_plot_target, new_figure

ROOT = Path(__file__).resolve().parents[2]


def test_a_path_is_checked_and_returned(tmp_path):
    assert check_plot_target(tmp_path / "a.png", None) == tmp_path / "a.png"
    assert check_plot_target(str(tmp_path / "a.png"), None) == tmp_path / "a.png"
    with pytest.raises(InvalidParameterError, match="is a directory"):
        check_plot_target(tmp_path, None)
    with pytest.raises(InvalidParameterError, match="path must be a file name, got 'int'"):
        check_plot_target(3, None)


def test_axes_mean_no_path(tmp_path):
    ax = Figure().subplots()
    assert check_plot_target(None, ax) is None
    assert list(tmp_path.iterdir()) == []


def test_both_or_neither_is_refused(tmp_path):
    ax = Figure().subplots()
    with pytest.raises(InvalidParameterError, match=r"either path .* or ax=.*got neither"):
        check_plot_target(None, None)
    with pytest.raises(InvalidParameterError, match="either path or ax=, not both"):
        check_plot_target(tmp_path / "a.png", [ax])


def test_one_axes():
    fig = Figure()
    ax = fig.subplots()
    assert check_ax(ax) is ax
    with pytest.raises(InvalidParameterError, match="ax must be a matplotlib Axes, got 'Figure'"):
        check_ax(fig)
    with pytest.raises(InvalidParameterError, match="ax must be a matplotlib Axes, got 'ndarray'"):
        check_ax(Figure().subplots(1, 2))


def test_several_axes_are_read_in_row_major_order():
    grid = Figure().subplots(2, 2)
    assert check_axes(grid, 4) == (grid[0, 0], grid[0, 1], grid[1, 0], grid[1, 1])
    assert check_axes([[grid[0, 0]], [grid[1, 1]]], 2) == (grid[0, 0], grid[1, 1])
    pair = Figure().subplots(1, 2)
    assert check_axes(list(pair), 2) == tuple(pair)
    with pytest.raises(InvalidParameterError, match=r"ax must hold 3 matplotlib Axes \(a, b, c\), got 2"):
        check_axes(pair, 3, what="a, b, c")
    with pytest.raises(InvalidParameterError, match="must be a sequence of 2 matplotlib Axes, got 'Axes'"):
        check_axes(pair[0], 2)
    with pytest.raises(InvalidParameterError, match=r"ax\[1\] must be a matplotlib Axes, got 'str'"):
        check_axes(np.array([pair[0], "x"], dtype=object), 2)


def test_new_figure_is_an_agg_figure_with_its_axes():
    from matplotlib.backends.backend_agg import FigureCanvasAgg

    fig, ax = new_figure((4.0, 3.0))
    assert isinstance(fig, Figure) and isinstance(fig.canvas, FigureCanvasAgg)
    assert fig.get_size_inches().tolist() == [4.0, 3.0] and fig.axes == [ax]
    fig, grid = new_figure((6.0, 4.0), 2, 3, sharex=True, squeeze=False)
    assert grid.shape == (2, 3) and grid[1, 2].get_shared_x_axes().joined(grid[0, 0], grid[1, 2])


def test_a_figure_written_to_a_path_leaves_the_backend_and_pyplot_alone(tmp_path):
    import matplotlib
    import matplotlib.pyplot as plt

    backend, open_before = matplotlib.get_backend(), plt.get_fignums()
    fig, ax = new_figure((3.0, 2.0))
    ax.plot([0, 1], [1, 0])
    assert save_figure(fig, tmp_path / "a.png", dpi=50).read_bytes()[:4] == b"\x89PNG"
    assert matplotlib.get_backend() == backend and plt.get_fignums() == open_before


# the library's source: every package but the tests, examples and benchmarks
LIBRARY = [ROOT / name for name in ("terrawatt_base", "terrain", "energy", "planner", "terrawatt_cli")]


def _backend_or_pyplot_uses(path: Path) -> list[str]:
    """``file:line: what`` for each ``matplotlib.use(...)`` call or pyplot / pylab import in ``path``."""
    found = []
    for node in ast.walk(ast.parse(path.read_text(encoding="utf-8"), str(path))):
        what = None
        if isinstance(node, ast.Import):
            names = [a.name for a in node.names if a.name in ("matplotlib.pyplot", "pylab")]
            what = f"import {names[0]}" if names else None
        elif isinstance(node, ast.ImportFrom):
            if node.module in ("matplotlib.pyplot", "pylab") or (
                    node.module == "matplotlib" and any(a.name in ("pyplot", "use") for a in node.names)):
                what = f"from {node.module} import {', '.join(a.name for a in node.names)}"
        elif (isinstance(node, ast.Call) and isinstance(node.func, ast.Attribute) and node.func.attr == "use"
              and isinstance(node.func.value, ast.Name) and node.func.value.id in ("matplotlib", "mpl")):
            what = f"{node.func.value.id}.use(...)"
        if what:
            found.append(f"{path.relative_to(ROOT)}:{node.lineno}: {what}")
    return found


def test_no_library_module_sets_the_backend_or_imports_pyplot():
    files = [p for package in LIBRARY for p in sorted(package.rglob("*.py"))]
    assert len(files) > 50  # the packages were found
    found = [hit for path in files for hit in _backend_or_pyplot_uses(path)]
    assert not found, "a library figure must use new_figure (matplotlib's object API), not pyplot:\n" + "\n".join(found)
