"""Typed text from the public never crashes the planner: it plans, or it is a PlannerError."""

from __future__ import annotations

import contextlib

import numpy as np
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from planner.board import BoardFrame
from planner.errors import PlannerError
from planner.glyphs import fit_to_area, text_glyph
from planner.pipeline import PlanOptions, plan_strokes

BOARD = BoardFrame(center_m_enu=np.array([0.0, 0.0, 0.75]), yaw_rad=0.0)


def _plan(text: str) -> None:
    glyph = fit_to_area(text_glyph(text), width_m=1.2, height_m=1.2)
    plan_strokes(list(glyph.strokes), PlanOptions(board=BOARD))


def test_repeated_vertices_of_tiny_glyphs_plan() -> None:
    """Thirty i's and markup-like text once divided by zero on repeated points."""
    for text in ("i" * 30, "[link=x]y[/link]"):
        _plan(text)


@settings(max_examples=15, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(st.text(alphabet=st.characters(codec="ascii", exclude_categories=["Cc"]), max_size=24))
def test_any_ascii_text_plans_or_says_why(text: str) -> None:
    with contextlib.suppress(PlannerError):  # refusing with a reason is fine; anything else not
        _plan(text)
