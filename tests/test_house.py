"""Invariants of the house: public APIs, the exception hierarchy and the import graph.

The import graph is read from the source with :mod:`ast` (nothing is imported for it), lazy
imports inside functions included: a lazy import hides a cycle, it does not remove it.
"""

from __future__ import annotations

import ast
import importlib
import inspect
import pkgutil
import re
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
#: The floors of the house: the groundwork (errors, checks, files) under the three library
#: packages, the command line on top; a package imports only from its own floor or below.
LAYERS = {"terrawatt_base": 0, "terrain": 1, "energy": 2, "planner": 3, "terrawatt_cli": 4}
PACKAGES = tuple(LAYERS)


def _modules(root: Path = ROOT) -> dict[str, Path]:
    out: dict[str, Path] = {}
    for pkg in PACKAGES:
        for path in sorted((root / pkg).rglob("*.py")):
            parts = list(path.relative_to(root).with_suffix("").parts)
            if parts[-1] == "__init__":
                parts = parts[:-1]
            out[".".join(parts)] = path
    return out


MODULES = _modules()


def _resolve(module: str, is_package: bool, level: int, target: str | None) -> str:
    if level == 0:
        return target or ""
    base = module.split(".") if is_package else module.split(".")[:-1]
    if level > 1:
        base = base[: len(base) - (level - 1)]
    return ".".join(base + ([target] if target else []))


def _owner(name: str, modules: dict[str, Path]) -> str | None:
    """The library module a dotted name refers to (the longest known prefix)."""
    parts = name.split(".")
    for i in range(len(parts), 0, -1):
        candidate = ".".join(parts[:i])
        if candidate in modules:
            return candidate
    return None


def _edges(modules: dict[str, Path]) -> list[tuple[str, str, tuple[str, ...], int]]:
    """(importing module, imported module, names imported from it, line) for every import."""
    edges = []
    for module, path in modules.items():
        is_package = path.name == "__init__.py"
        tree = ast.parse(path.read_text(encoding="utf-8"))
        for node in ast.walk(tree):
            if isinstance(node, ast.Import):
                for alias in node.names:
                    target = _owner(alias.name, modules)
                    if target:
                        edges.append((module, target, (), node.lineno))
            elif isinstance(node, ast.ImportFrom):
                base = _resolve(module, is_package, node.level, node.module)
                for alias in node.names:
                    sub = _owner(f"{base}.{alias.name}", modules)
                    if sub and sub != _owner(base, modules):  # "from pkg import submodule"
                        edges.append((module, sub, (), node.lineno))
                    else:
                        target = _owner(base, modules)
                        if target:
                            edges.append((module, target, (alias.name,), node.lineno))
    return edges


EDGES = _edges(MODULES)


def _public_modules() -> list[str]:
    names = []
    for pkg in PACKAGES:
        package = importlib.import_module(pkg)
        names.append(pkg)
        for info in pkgutil.walk_packages(package.__path__, prefix=f"{pkg}."):
            names.append(info.name)
    return names


def _upward(edges: list[tuple[str, str, tuple[str, ...], int]]) -> list[str]:
    return [
        f"{src} imports {dst} (line {line})"
        for src, dst, _, line in edges
        if LAYERS[dst.split(".")[0]] > LAYERS[src.split(".")[0]]
    ]


def _cycles(modules: dict[str, Path], edges: list[tuple[str, str, tuple[str, ...], int]]) -> list[list[str]]:
    """Strongly connected components of more than one module (Tarjan's algorithm).

    A package's ``__init__`` importing its own submodules is how it names its API, not a
    dependency of those submodules on it, so those edges are left out; an import of a package
    from one of its own submodules is kept (that one would be a real cycle).
    """
    graph: dict[str, set[str]] = {m: set() for m in modules}
    for src, dst, _, _ in edges:
        if src != dst and not (modules[src].name == "__init__.py" and dst.startswith(src + ".")):
            graph[src].add(dst)
    index: dict[str, int] = {}
    low: dict[str, int] = {}
    stack: list[str] = []
    on_stack: set[str] = set()
    cycles: list[list[str]] = []

    def visit(v: str) -> None:
        index[v] = low[v] = len(index)
        stack.append(v)
        on_stack.add(v)
        for w in graph[v]:
            if w not in index:
                visit(w)
                low[v] = min(low[v], low[w])
            elif w in on_stack:
                low[v] = min(low[v], index[w])
        if low[v] == index[v]:
            component = []
            while True:
                w = stack.pop()
                on_stack.discard(w)
                component.append(w)
                if w == v:
                    break
            if len(component) > 1:
                cycles.append(sorted(component))

    for v in graph:
        if v not in index:
            visit(v)
    return cycles


def _private_imports(edges: list[tuple[str, str, tuple[str, ...], int]]) -> list[str]:
    return [
        f"{src} imports {name} from {dst} (line {line})"
        for src, dst, names, line in edges
        for name in names
        if name.startswith("_") and not name.startswith("__") and src != dst
    ]


def test_the_packages_are_found() -> None:
    assert set(PACKAGES) <= set(MODULES)
    assert len(MODULES) > 20 and len(EDGES) > 50


def test_no_upward_import() -> None:
    assert _upward(EDGES) == []


def test_no_import_cycle() -> None:
    assert _cycles(MODULES, EDGES) == []


def test_no_module_imports_another_modules_private_names() -> None:
    assert _private_imports(EDGES) == []


def test_the_scan_finds_planted_faults(tmp_path: Path) -> None:
    """The checks above can fail: a tree with a lazy cycle, an upward and a private import."""
    files = {
        "terrain/__init__.py": '"""t."""\nfrom .a import A\n',
        "terrain/a.py": '"""a."""\nA = 1\n\n\ndef f():\n    from .b import _hidden\n    from planner import P\n',
        "terrain/b.py": '"""b."""\nfrom .a import A\n_hidden = 2\n',
        "energy/__init__.py": '"""e."""\n',
        "terrawatt_base/__init__.py": '"""b."""\n',
        "terrawatt_cli/__init__.py": '"""c."""\n',
        "planner/__init__.py": '"""p."""\nP = 3\n',
    }
    for rel, text in files.items():
        (tmp_path / rel).parent.mkdir(parents=True, exist_ok=True)
        (tmp_path / rel).write_text(text)
    modules = _modules(tmp_path)
    edges = _edges(modules)
    assert _cycles(modules, edges) == [["terrain.a", "terrain.b"]]
    assert _upward(edges) == ["terrain.a imports planner (line 7)"]
    assert _private_imports(edges) == ["terrain.a imports _hidden from terrain.b (line 6)"]


#: The library's floors: they speak in parameters; only ``terrawatt_cli`` speaks in flags (STYLE.md, line 20).
LIBRARY = ("terrawatt_base", "terrain", "energy", "planner")
#: A command-line flag spelled out: two dashes then a letter, not inside a word (``x--y``) nor a longer rule.
_FLAG = re.compile(r"(?<![\w-])--[A-Za-z]")


def _flag_faults(source: str, where: str) -> list[str]:
    """Where a module speaks a command line's language: a string literal (a message, a docstring, a default) that
    spells a flag, or a parameter whose job is to rename parameters for a front end (a ``flag`` / ``flags`` /
    ``..._flag`` of strings, or ``names`` given as a ``Mapping[str, str]`` of parameter to word)."""
    faults = []
    for node in ast.walk(ast.parse(source)):
        if isinstance(node, ast.Constant) and isinstance(node.value, str) and _FLAG.search(node.value):
            faults.append(f"{where}:{node.lineno}: {node.value.strip()[:70]!r} spells a flag")
        elif isinstance(node, (ast.FunctionDef, ast.AsyncFunctionDef)):
            args = node.args
            for arg in (*args.posonlyargs, *args.args, *args.kwonlyargs):
                note = ast.unparse(arg.annotation) if arg.annotation is not None else ""
                flag_like = arg.arg in ("flag", "flags") or arg.arg.endswith(("_flag", "_flags"))
                if (flag_like and "str" in note) or (arg.arg.endswith("names") and "Mapping[str, str]" in note):
                    faults.append(f"{where}:{node.lineno}: {node.name}({arg.arg}) renames parameters for a front end")
    return faults


def test_the_library_names_no_flag_and_takes_no_renaming_argument() -> None:
    """Errors carry the parameter (:attr:`terrain.TerrawattError.parameter`); ``terrawatt_cli`` says it by its flag."""
    paths = [path for name, path in MODULES.items() if name.split(".")[0] in LIBRARY]
    assert len(paths) > 150  # the whole library was read, not an empty or moved tree
    faults = [fault for path in paths for fault in _flag_faults(path.read_text(), str(path.relative_to(ROOT)))]
    assert faults == []


def test_the_flag_scan_finds_planted_faults() -> None:
    """The scan above can fail: a flag in a message, in a docstring and as a default; a renaming argument."""
    planted = (
        '"""Reads a map (the command line passes --map)."""\n'
        "from collections.abc import Mapping\n\n\n"
        "def read(path, cell_size_m, names: Mapping[str, str] | None = None, name: str = '--out'):\n"
        "    raise ValueError(f'{path}: give --cell-size ' f'{cell_size_m}')\n\n\n"
        "def write(path, flag: str):\n"
        "    return path\n"
    )
    faults = _flag_faults(planted, "m.py")
    assert sorted(int(f.split(":")[1]) for f in faults) == [1, 5, 5, 6, 9], faults
    assert any("read(names)" in f for f in faults) and any("write(flag)" in f for f in faults)
    clean = (
        "def read(path, names: tuple[str, str] = ('xy_m', 'lonlat'), ground_names: Mapping[int, str] = None,\n"
        "         flag: np.ndarray = None):\n"
        "    raise ValueError(f'{path}: x--y, a -- b, ---- rule, give cell_size_m', 'see `model`')\n"
    )
    assert _flag_faults(clean, "m.py") == []


@pytest.mark.parametrize("pkg", PACKAGES)
def test_all_is_unique_and_importable(pkg: str) -> None:
    package = importlib.import_module(pkg)
    names = list(package.__all__)
    duplicates = sorted({n for n in names if names.count(n) > 1})
    assert duplicates == []
    missing = [n for n in names if not hasattr(package, n)]
    assert missing == []


def test_every_module_names_its_api_and_has_a_docstring() -> None:
    for name in _public_modules():
        module = importlib.import_module(name)
        assert (module.__doc__ or "").strip(), f"{name} has no docstring"
        exported = getattr(module, "__all__", None)
        assert exported is not None, f"{name} has no __all__"
        assert len(set(exported)) == len(exported), f"{name}.__all__ repeats a name"
        assert all(hasattr(module, n) for n in exported), f"{name}.__all__ names what it lacks"


def test_every_exception_derives_from_the_root_and_a_builtin() -> None:
    from terrain import TerrawattError, TerrawattWarning

    seen = 0
    for name in _public_modules():
        module = importlib.import_module(name)
        for _, obj in inspect.getmembers(module, inspect.isclass):
            if not obj.__module__.startswith(PACKAGES):
                continue
            if issubclass(obj, Warning):
                assert issubclass(obj, TerrawattWarning), obj
                seen += 1
            elif issubclass(obj, BaseException):
                seen += 1
                assert issubclass(obj, TerrawattError), obj
                if obj is not TerrawattError:
                    builtins = [b for b in obj.__mro__ if b.__module__ == "builtins" and b not in (Exception, BaseException, object)]
                    assert builtins, f"{obj.__qualname__} inherits no builtin besides Exception"
    assert seen >= 10


def test_the_errors_have_one_home_and_terrain_names_them() -> None:
    """The hierarchy lives in terrawatt_base.errors; terrain, the package every user imports first,
    names all of it; energy and planner keep their surfaces for their own ideas."""
    import terrain
    import terrawatt_base.errors as errors

    classes = {n for n, v in vars(errors).items() if isinstance(v, type) and v.__module__ == errors.__name__}
    assert set(errors.__all__) == classes  # the module names every class it defines
    for name in errors.__all__:
        assert name in terrain.__all__ and getattr(terrain, name) is getattr(errors, name)
    for pkg in ("energy", "planner"):
        assert not set(errors.__all__) & set(importlib.import_module(pkg).__all__), pkg


def test_the_public_surfaces_are_deliberate() -> None:
    """The package APIs stay small (issue 22; planner grew by the Navigator, issue 28, and by CostSpec, the one
    pricing spec of issue 34): the rest is public in the packages' own modules."""
    import energy
    import planner

    assert len(energy.__all__) <= 50 and len(planner.__all__) <= 37
