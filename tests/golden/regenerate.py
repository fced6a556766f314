"""Rewrite the golden copies of the golden-file tests, after a deliberate change of an output.

Run:  python tests/golden/regenerate.py [case ...]      (default: every case; commit the diff of tests/golden/data)
"""

from __future__ import annotations

import argparse
import sys
import tempfile
from pathlib import Path

HERE = Path(__file__).resolve().parent


def main(argv: list[str] | None = None) -> int:
    # as the test run has them: the cases and the benchmarks' scenarios importable at the top level
    for folder in (HERE, HERE.parents[1] / "benchmarks", HERE.parents[1]):
        if str(folder) not in sys.path:
            sys.path.insert(0, str(folder))
    from golden_cases import CASES, DIGESTED
    from golden_files import GOLDEN, members, write_case

    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("cases", nargs="*", choices=[[], *sorted(CASES)], metavar="case",
                        help=f"cases to regenerate (default all: {', '.join(sorted(CASES))})")
    names = parser.parse_args(argv).cases or sorted(CASES)
    for name in names:
        with tempfile.TemporaryDirectory() as work:
            produced = members(CASES[name](Path(work)), DIGESTED)
        write_case(name, produced)
        print(f"{name}: {len(produced)} golden file(s) in {GOLDEN.relative_to(HERE.parents[1])}/{name}/")
    return 0


if __name__ == "__main__":
    sys.exit(main())
