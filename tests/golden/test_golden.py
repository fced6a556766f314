"""Golden-file tests: every versioned output, written by the CLI a user runs on small seeded inputs, is the
committed copy under ``tests/golden/data/`` (see ``golden_files`` for what is compared and masked).

They guard restructures that must change nothing (issue 34): a route (and its GeoJSON, ROS 2 bag, Nav2 maps,
costmap), batch, reach, mission, Monte Carlo, replay and navigator state, registry, diagnosis, evaluation,
adaptation, predictions, model file, robot file or map that comes out different fails here with the first
differing keys and lines. Wall-clock timings and package versions are masked (``golden_files.MASKED_KEYS``);
the cases and what each compares are listed in ``tests/golden/README.md``.

A deliberate change of an output: regenerate the copies and commit their diff with the change::

    TERRAWATT_REGEN_GOLDEN=1 python -m pytest tests/golden      # or
    python tests/golden/regenerate.py [case ...]
"""

from __future__ import annotations

import pytest
from golden_cases import CASES, DIGESTED, NEEDS
from golden_files import check_case, members, regenerating, write_case


@pytest.mark.parametrize("case", sorted(CASES))
def test_output_is_its_golden_copy(case, tmp_path):
    for module in NEEDS.get(case, ()):
        pytest.importorskip(module, reason=f"the {case} outputs need {module} (an optional extra)")
    produced = members(CASES[case](tmp_path), DIGESTED)
    if regenerating():
        write_case(case, produced)
        return
    check_case(case, produced)
