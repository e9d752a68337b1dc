"""A show's ``controller.overrides``: the brush quadrotor flies the gains it names."""

from __future__ import annotations

import dataclasses

import pytest

from planner.glyphs import text_glyph
from showfile import ShowFileError, parse_show
from vehicles.jobs import job_setup
from vehicles.quadrotor_brush.control.rpt import DEFAULT_GAINS, RptAxisGains
from vehicles.quadrotor_brush.gain_names import GAIN_NAMES, PARAMETERS

SOLO = """\
show_id: t
boards:
  - {id: b1, center_m_enu: [0, 0, 0.75], size_m: [1.4, 1.4], writing_area_m: [1.2, 1.2]}
vehicles:
  - {id: uav1, board: b1, home_m_enu: [0, -1.2, 0]}
controller:
  overrides: OVERRIDES
"""


def _show(overrides: str) -> str:
    return SOLO.replace("OVERRIDES", overrides)


def test_the_names_are_the_rpt_design_parameters_of_each_axis() -> None:
    assert tuple(f.name for f in dataclasses.fields(RptAxisGains)) == PARAMETERS
    assert len(GAIN_NAMES) == 12 and "z.ki_radps" in GAIN_NAMES


def test_the_vehicle_flies_the_gains_the_show_names_and_the_presets_for_the_rest() -> None:
    show = parse_show(_show("{x.eps: 0.8, z.zeta: 0.7}"))
    gains = job_setup(show, "uav1").settings.flight.controller.gains
    assert gains.x == dataclasses.replace(DEFAULT_GAINS.x, eps=0.8)
    assert gains.y == DEFAULT_GAINS.y
    assert gains.z == dataclasses.replace(DEFAULT_GAINS.z, zeta=0.7)
    assert gains.name == "default with x.eps, z.zeta"


@pytest.mark.parametrize(
    ("overrides", "message"),
    [
        ("{x.gain: 2.0}", "unknown gain 'x.gain'; the gains are: x.eps, x.wn_radps"),
        ("{z.eps: 0}", "gain 'z.eps' must be positive and finite, got 0.0"),
        ("{z.eps: .nan}", "gain 'z.eps' must be positive and finite, got nan"),
    ],
)
def test_a_gain_that_is_not_one_or_not_positive_is_refused_at_its_line(
    overrides: str, message: str
) -> None:
    with pytest.raises(ShowFileError) as info:
        parse_show(_show(overrides), file="bad.yaml")
    (problem,) = info.value.problems
    assert problem.field.startswith("controller.overrides") and problem.line in (7, 8)
    assert problem.message.startswith(message)


def test_slower_gains_track_the_same_plan_worse() -> None:
    """Closed loop: the overrides reach the flown controller (a test that fails if they are
    only stored)."""
    errors = []
    for overrides in ("{}", "{x.eps: 2.0, y.eps: 2.0}"):
        setup = job_setup(parse_show(_show(overrides)), "uav1")
        job = setup.plan(text_glyph("一"))
        flown = setup.kind.fly(job.plan, setup.settings)
        errors.append(setup.kind.score(job.plan, flown, setup.settings).rmse_m)
    assert errors[1] > 1.5 * errors[0]
