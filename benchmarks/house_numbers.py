"""The house's numbers that issue 34 (one way to price a map, one way to price a route, one result per answer) counts.

Read from the library's source alone (nothing is imported or run): its lines outside tests, the
functions that take more than 8 parameters (``self`` / ``cls`` not counted; the compiled kernels
listed apart, since numba takes arrays one by one), the ``*Report`` / ``*Result`` / ``*Summary``
classes, and the public ways to build an ``EnergyCost``. Prints a table and writes JSON::

    python benchmarks/house_numbers.py --out house_numbers.json
"""

from __future__ import annotations

import argparse
import ast
import json
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
#: The library's packages, bottom to top.
PACKAGES = ("terrawatt_base", "terrain", "energy", "planner", "terrawatt_cli")
#: Where numba kernels live (their many array parameters are the price of compiling them).
KERNELS = ("planner/kernels/",)
#: The suffixes of the result-object classes counted.
RESULT_SUFFIXES = ("Report", "Result", "Summary")


def _sources() -> list[Path]:
    return sorted(p for pkg in PACKAGES for p in (ROOT / pkg).rglob("*.py"))


def _n_params(node: ast.FunctionDef | ast.AsyncFunctionDef) -> int:
    a = node.args
    n = len(a.posonlyargs) + len(a.args) + len(a.kwonlyargs) + (a.vararg is not None) + (a.kwarg is not None)
    first = (a.posonlyargs + a.args)[:1]
    return n - (1 if first and first[0].arg in ("self", "cls") else 0)


def house_numbers() -> dict:
    """The counts, with the names behind them."""
    lines = 0
    wide: list[tuple[int, str]] = []
    results: list[str] = []
    for path in _sources():
        text = path.read_text()
        lines += len(text.splitlines())
        rel = path.relative_to(ROOT).as_posix()
        for node in ast.walk(ast.parse(text)):
            if isinstance(node, (ast.FunctionDef, ast.AsyncFunctionDef)) and _n_params(node) > 8:
                wide.append((_n_params(node), f"{rel}:{node.name}"))
            if isinstance(node, ast.ClassDef) and node.name.endswith(RESULT_SUFFIXES):
                results.append(f"{rel}:{node.name}")
    kernels = [w for w in wide if w[1].startswith(KERNELS)]
    library = sorted((w for w in wide if w not in kernels), reverse=True)
    return {
        "library_lines": lines,
        "functions_over_8_parameters": len(library),
        "functions_over_8_parameters_public": sum(1 for _, name in library if not name.split(":")[1].startswith("_")),
        "kernels_over_8_parameters": len(kernels),
        "widest": [{"parameters": n, "function": name} for n, name in library[:15]],
        "result_classes": len(results),
        "result_class_names": results,
    }


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--out", type=Path, default=None, help="write the numbers as JSON here")
    args = ap.parse_args(argv)
    numbers = house_numbers()
    rows = [("library lines (outside tests)", numbers["library_lines"]),
            ("functions over 8 parameters (kernels apart)", numbers["functions_over_8_parameters"]),
            ("  of them public", numbers["functions_over_8_parameters_public"]),
            ("compiled kernels over 8 parameters", numbers["kernels_over_8_parameters"]),
            ("*Report / *Result / *Summary classes", numbers["result_classes"])]
    width = max(len(name) for name, _ in rows)
    for name, value in rows:
        print(f"{name:<{width}}  {value:>7}")
    print("widest: " + ", ".join(f"{w['function']} ({w['parameters']})" for w in numbers["widest"][:6]))
    if args.out is not None:
        args.out.write_text(json.dumps(numbers, indent=1) + "\n")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
