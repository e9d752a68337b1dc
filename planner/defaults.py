"""The planner's default settings of a writing job, in one light module (no solver imports):
:class:`planner.options.PlanOptions` and a show file's ``planning`` section both default to
these, so a show, ``skyquill plan`` and ``skyquill fly`` plan alike."""

from __future__ import annotations

WRITE_HEIGHT_M = 0.335
"""Vehicle reference height above the board surface while the brush writes, [m] (the Airshow
brush: 0.35 m hanging free less its 0.015 m nominal press)."""
CLEARANCE_M = 0.05
"""Extra height with the pen up, [m]."""
MARGIN_M = 0.05
"""Free border kept inside the writing area when a glyph is laid out, [m]."""
SPLIT_THRESHOLD_M = 0.01
"""Split-and-merge threshold of the turning points, [m]."""
SAMPLE_RATE_HZ = 100.0
"""Rate at which the trajectory is sampled for the control loop, [Hz]."""

SOLVERS = ("piqp", "clarabel", "osqp")
"""QP solvers the planner can use (``planner.qp_solvers``), the default first."""
ONE_OFF_DENSE_QP_BUDGET_S = 0.2
"""``PlanOptions.dense_qp_budget_s`` of a process that plans once (``skyquill plan``), [s]: about
what importing ``scipy.sparse`` costs there (0.2 s on a 2-core machine), which the sparse QP
interface would need."""
