"""Withheld-effect scenarios: the experiment scaffolding of the diagnosis benchmarks (not part of the library).

Truth-simulator logs that excite one catalogued effect and a physics model that lacks it
(:mod:`.scenarios`), the manoeuvres that excite each effect (:mod:`.manoeuvres`) and the
battery-power logs of the electrical effects (:mod:`.power`). Used by
``benchmarks/diagnosis_bench.py`` and by the diagnosis tests as known-answer cases; import
it with ``benchmarks/`` on ``sys.path`` (a script in ``benchmarks/`` has it; the tests' conftest
adds it).
"""

from .manoeuvres import MANOEUVRES, manoeuvre_commands
from .power import PowerGap, battery_streams, power_gap
from .scenarios import (
    MEASUREMENT_EFFECTS,
    PARAMETER_EFFECTS,
    POWER_ONLY_EFFECTS,
    SCENARIOS,
    Scenario,
    WithheldGap,
    null_scenario,
    pair_scenario,
    scenario,
    withheld_gap,
    withheld_gap_ratio,
)

__all__ = [
    "MANOEUVRES",
    "manoeuvre_commands",
    "PowerGap",
    "battery_streams",
    "power_gap",
    "MEASUREMENT_EFFECTS",
    "PARAMETER_EFFECTS",
    "POWER_ONLY_EFFECTS",
    "SCENARIOS",
    "Scenario",
    "WithheldGap",
    "null_scenario",
    "pair_scenario",
    "scenario",
    "withheld_gap",
    "withheld_gap_ratio",
]
