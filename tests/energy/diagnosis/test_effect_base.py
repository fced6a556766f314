"""Tests of energy.diagnosis.effect_base: EffectParameter and the Effect / BasisEffect contract."""

import numpy as np
import pytest

from energy import robot_preset
from energy.diagnosis import Effect, EffectParameter
from energy.diagnosis.effect_base import EFFECT_KINDS, BasisEffect
from terrawatt_base.errors import InvalidParameterError


def test_effect_parameter_validates():
    with pytest.raises(InvalidParameterError, match="below high"):
        EffectParameter("g", 1.0, 2.0, 1.0, "1")
    with pytest.raises(InvalidParameterError, match="initial"):
        EffectParameter("g", 5.0, 0.0, 1.0, "1")


def test_an_effect_parameter_has_a_plausible_range_defaulting_to_its_bounds():
    p = EffectParameter("g", 1.0, 0.0, 3.0, "1")
    assert (p.plausible_low, p.plausible_high) == (0.0, 3.0)
    q = EffectParameter("mass_scale", 1.0, 0.25, 4.0, "1", None, 0.5, 2.5, "a payload")
    assert q.plausible(2.4) and not q.plausible(2.6) and not q.plausible(0.4)
    assert q.flags(1.8) == ()
    (outside,) = q.flags(3.0)
    assert "mass_scale = 3" in outside and "outside its plausible 0.5 … 2.5" in outside and "a payload" in outside
    pinned = q.flags(4.0)
    assert len(pinned) == 2 and "pinned at its fitting bound 4" in pinned[1]
    assert q.at_bound(0.25) == "low" and q.at_bound(1.0) is None
    with pytest.raises(InvalidParameterError, match="plausible_low 2.0 must be below plausible_high 1.0"):
        EffectParameter("g", 1.0, 0.0, 3.0, "1", None, 2.0, 1.0)
    with pytest.raises(InvalidParameterError, match="plausible_high"):
        EffectParameter("g", 1.0, 0.0, 3.0, "1", None, 0.5, float("nan"))


class _Offset(Effect):
    """A minimal effect: a constant added to both sides."""

    name = "offset"
    kind = "measurement"
    parameters = (EffectParameter("offset_a", 0.0, -5.0, 5.0, "A", plausible_low=-1.0, plausible_high=1.0),)

    def prepare(self, model, log):
        return None

    def apply(self, values, predicted_a, prepared):
        return predicted_a + values[0]


def test_the_effect_contract_defaults():
    e = _Offset()
    assert e.n_parameters == 1 and repr(e) == "_Offset(name='offset', kind='measurement', n_parameters=1)"
    assert e.initial.tolist() == [0.0] and [b.tolist() for b in e.bounds] == [[-5.0], [5.0]]
    assert [r.tolist() for r in e.plausible_ranges()] == [[-1.0], [1.0]]
    assert e.applies_to(object()) and e.unsupported([], None) is None and e.bind([]) is e
    assert e.spec() == {"name": "offset"} and e.priors().tolist() == [0.0] and not e.negligible(np.array([0.0]))
    assert e.penalty(np.array([1.0])).size == 0
    base = np.ones((3, 2))
    np.testing.assert_array_equal(e.apply_surrogate(np.array([0.5]), base, None), base + 0.5)
    assert e.describe([0.25]) == "offset (offset_a = 0.25 A)"
    assert e.values_dict([0.25]) == {"offset_a": 0.25} and e.values_dict([np.nan]) == {}
    assert e.plausibility_flags([0.5]) == () and "outside its plausible" in e.plausibility_flags([2.0])[0]
    with pytest.raises(InvalidParameterError, match="effect 'offset' has 1 parameters, got 2 values"):
        e.values_dict([1.0, 2.0])


def test_a_basis_effect_binds_a_robot_on_a_copy():
    e = BasisEffect()
    robot = robot_preset("husky")
    bound = e.bind([], robot=robot)
    assert bound is not e and bound.robot is robot and e.robot is None


@pytest.mark.parametrize(("kwargs", "match"), [
    (dict(name="", initial=0.0, low=0.0, high=1.0, unit="1"), "name"),
    (dict(name="g", initial=0.0, low=0.0, high=1.0, unit=1), "EffectParameter.unit must be a str, got 1"),
    (dict(name="g", initial=0.0, low=0.0, high=float("inf"), unit="1"), "high"),
    (dict(name="g", initial=0.0, low=0.0, high=1.0, unit="1", plausible_note=3), "plausible_note must be a str"),
])
def test_effect_parameter_documented_errors(kwargs, match):
    with pytest.raises(InvalidParameterError, match=match):
        EffectParameter(**kwargs)


def test_a_non_finite_value_is_flagged():
    assert EffectParameter("g", 1.0, 0.0, 3.0, "1").flags(float("nan")) == ("g is not finite (nan)",)
    assert EFFECT_KINDS == ("parameter", "physics", "learned", "measurement", "electrical")

