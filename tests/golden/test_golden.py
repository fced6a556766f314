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


def test_printout_masking_hides_timings_only():
    from golden_files import MASK, mask_printed_text

    text = ("robot: husky, speed 0.5 m/s; map preparation 0.02 s\n\n"
            "route     energy J  plan s\n------------------------\nlattice     6759.9   0.037\n\n"
            "3 pairs planned in 0.11 s on 1 worker(s) (in process): 26.5 routes/s\nenergy 1.88 Wh\n")
    masked = mask_printed_text(text)
    assert masked.count(MASK) == 4
    assert "speed 0.5 m/s" in masked and "6759.9" in masked and "energy 1.88 Wh" in masked
    assert mask_printed_text(text.replace("1.88", "1.89")) != masked  # a printed number still counts
