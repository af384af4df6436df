"""Every summary a run can give is the documented `Summary`: no field missing, none unknown."""

import pytest

import percussim
from percussim.solver.summary import Summary
from percussim.testing import at_default_accuracy


@pytest.mark.parametrize(
    "how",
    [
        pytest.param(lambda: percussim.simulate(percussim.load_preset("fig5")), id="fixed grid"),
        pytest.param(lambda: percussim.simulate(at_default_accuracy("fig3")), id="default accuracy"),
        pytest.param(lambda: percussim.simulate(percussim.load_preset("fig3"), model="lumped"), id="lumped"),
        pytest.param(lambda: percussim.simulate(at_default_accuracy("fig6")), id="tolerance not met"),
    ],
)
def test_a_summary_is_the_documented_model(how):
    summary = how().summary
    parsed = Summary.model_validate(summary)
    assert parsed.model_dump(mode="json") == summary


def test_an_unknown_or_missing_field_is_refused():
    summary = percussim.simulate(percussim.load_preset("fig9")).summary
    with pytest.raises(ValueError, match="extra"):
        Summary.model_validate(summary | {"surprise": 1})
    with pytest.raises(ValueError, match="why"):
        Summary.model_validate({k: v for k, v in summary.items() if k != "why"})
