"""The one exception root of the planner, with where-and-what detail for the user."""

from __future__ import annotations


class PlannerError(ValueError):
    """Anything the planner cannot do with its input; says what was wrong and where.

    Subclasses ``ValueError`` so callers that only know the standard library can catch it.
    """

    code = "plan_failed"
    """Stable error code on the bus (``bus.rpc.error_info_from_exception``)."""

    def __init__(
        self,
        message: str,
        *,
        stroke_index: int | None = None,
        point_index: int | None = None,
        field: str | None = None,
    ) -> None:
        self.message = message
        self.stroke_index = stroke_index
        self.point_index = point_index
        self.field = field
        super().__init__(self._describe())

    def _describe(self) -> str:
        where = []
        if self.field is not None:
            where.append(f"field {self.field!r}")
        if self.stroke_index is not None:
            where.append(f"stroke {self.stroke_index}")
        if self.point_index is not None:
            where.append(f"point {self.point_index}")
        return f"{', '.join(where)}: {self.message}" if where else self.message


class InfeasibleTrajectoryError(PlannerError):
    """A requested trajectory would violate a vehicle limit.

    Attributes name the limit (``"a_max"``, ``"v_max"``, ``"thrust"``, ``"body_rate"``,
    ``"fit_error"``, ``"force_rate"`` or ``"h_max"``, the time step bound), the axis (``"x"``,
    ``"y"``, ``"z"`` or ``None`` for a norm), the time ``t_s`` in [s] where it is worst, the
    reached ``value`` and the ``bound`` in SI units.
    """

    def __init__(
        self,
        message: str,
        *,
        limit: str,
        axis: str | None,
        t_s: float,
        value: float,
        bound: float,
        stroke_index: int | None = None,
    ) -> None:
        self.limit = limit
        self.axis = axis
        self.t_s = t_s
        self.value = value
        self.bound = bound
        super().__init__(message, stroke_index=stroke_index)
