"""The ground writer's climb tables for ``bench_ground.py``: the bound at the paper's friction, the
0.1 m step over seeds, the highest step, and how much each reading of the model decides them.

Paper and model sit side by side only where they measure the same thing: Table 2's slip and
rotation error ratios beside ours when both methods climbed the 0.1 m step in every run (a
stall's ratios measure a wheel spinning against a riser, not a climb); the prototype's highest
steps (section 3.3) beside the model's highest step with rubber rollers.
"""

from __future__ import annotations

from dataclasses import dataclass, replace

from vehicles.omni_wheel.climb import METHODS, TABLE_1, ClimbResult, Method, climb
from vehicles.omni_wheel.climb_study import SeededClimbs, highest_step_m, seeded_climbs
from vehicles.omni_wheel.floor_plan import RUBBER_ROLLERS
from vehicles.omni_wheel.geometry import OmniGeometry
from vehicles.omni_wheel.statics import riser_phases

PAPER_STEP_M = 0.1
"""The step of the paper's simulation (section 3.1) in [m]."""
PAPER_TABLE_2_AVERAGE = {"standard": (30.3, 16.5), "proposed": (13.9, 7.5)}
"""Table 2's averages in [%]: slip ratio, rotation error ratio (Working Model 2D, friction 0.3)."""
PAPER_HIGHEST_M = {"standard": 0.072, "proposed": 0.152}
"""Highest steps the prototype climbed in [m] (section 3.3)."""
OTHER_READING = replace(RUBBER_ROLLERS, rear_frame_com_x_m=-0.1075)
"""The rear mass centre read midway between the middle and rear axles (``geometry``)."""
SENSITIVITY: tuple[tuple[str, OmniGeometry], ...] = (
    ("as read (rubber rollers)", RUBBER_ROLLERS),
    ("rear mass centre -0.1075 m", OTHER_READING),
    ("rear mass centre -0.125 m", replace(RUBBER_ROLLERS, rear_frame_com_x_m=-0.125)),
    ("motor torque 3.0 N m", replace(RUBBER_ROLLERS, motor_torque_max_nm=3.0)),
    ("motor torque 6.0 N m", replace(RUBBER_ROLLERS, motor_torque_max_nm=6.0)),
    ("roller friction 0.8", replace(RUBBER_ROLLERS, friction_static=0.8, friction_dynamic=0.72)),
    ("roller friction 1.2", replace(RUBBER_ROLLERS, friction_static=1.2, friction_dynamic=1.08)),
    ("frame clearance 0.02 m", replace(RUBBER_ROLLERS, frame_clearance_m=0.02)),
)
"""Rows of the sensitivity table: one reading changed each."""


def paper_friction_bound() -> None:
    """Table 1's friction on the 0.1 m step: the quasi-static bound, then a run per method."""
    print(f"\n{PAPER_STEP_M} m step, Table 1's roller friction {TABLE_1.friction_static}")
    print("  quasi-static bound (statics.py): lift each axle needs on the riser, lift the")
    print("  friction can give (mu x push, push <= mu x load on the pushing wheels)")
    for phase in riser_phases(TABLE_1, TABLE_1.friction_static):
        verdict = "possible" if phase.possible else "impossible"
        print(
            f"    {phase.axle:6s} axle on the riser: needs {phase.lift_needed_n:5.1f} N,"
            f" friction gives at most {phase.lift_available_n:5.1f} N: {verdict}"
        )
    for method in METHODS:
        r = climb(method, PAPER_STEP_M, geometry=TABLE_1, time_limit_s=10.0)
        front_up = bool(r.log["joint_pitch_rad"].size) and r.log["joint_pitch_rad"].min() < -0.2
        print(f"  {method:8s} climbed {r.climbed!s:5s} (front wheels up the riser: {front_up!s})")
    print("  neither can: the front axle alone needs more lift than the riser's friction gives")


@dataclass(frozen=True)
class StepComparison:
    """Both methods on one step over the same seeds."""

    runs: dict[Method, SeededClimbs]
    """Per method."""

    def ratio(self, figure: str) -> float:
        """Proposed over standard of ``figure`` (``slip`` or ``rotation_error``)."""
        return self.runs["proposed"].mean(figure) / self.runs["standard"].mean(figure)

    @property
    def all_climbed(self) -> bool:
        """Every run of both methods climbed."""
        return all(s.climbed == len(s.runs) for s in self.runs.values())


def step_over_seeds(label: str, geometry: OmniGeometry, seeds: range) -> StepComparison:
    """The 0.1 m step, both methods, ``seeds``; Table 2 beside only when every run climbed."""
    print(f"\n{PAPER_STEP_M} m step, {label}, seeds {seeds.start}-{seeds.stop - 1}")
    print("                climbed   slip [%]   rot. err. [%]   (mean |ratio| in the climb)")
    comparison = StepComparison(
        {m: seeded_climbs(m, PAPER_STEP_M, geometry, seeds) for m in METHODS}
    )
    for method, s in comparison.runs.items():
        slip, rot = 100.0 * s.mean("slip"), 100.0 * s.mean("rotation_error")
        paper = PAPER_TABLE_2_AVERAGE[method]
        beside = f"   paper {paper[0]:4.1f} / {paper[1]:4.1f}" if comparison.all_climbed else ""
        print(
            f"  {method:8s}     {s.climbed}/{len(s.runs)}     {slip:6.1f}      {rot:6.1f}{beside}"
        )
    slip_ratio, rot_ratio = comparison.ratio("slip"), comparison.ratio("rotation_error")
    if comparison.all_climbed:
        print(
            f"  proposed / standard: slip {slip_ratio:.2f}x, rotation error {rot_ratio:.2f}x"
            "   (target <= 0.70x each; paper 0.46x / 0.45x)"
        )
    else:
        print(
            f"  proposed / standard: slip {slip_ratio:.2f}x, rotation error {rot_ratio:.2f}x of"
            " stalled runs: not a climb, no paper figure beside"
        )
    return comparison


def highest_steps(geometry: OmniGeometry) -> dict[Method, float]:
    """Highest step per method (bisection to 5 mm), printed beside the prototype's."""
    print("\nhighest step climbed, rubber rollers (bisection 40-200 mm to 5 mm)")
    out = {m: highest_step_m(m, geometry) for m in METHODS}
    for method, h in out.items():
        paper = 1e3 * PAPER_HIGHEST_M[method]
        print(f"  {method:8s} {1e3 * h:5.0f} mm   prototype {paper:.0f} mm (section 3.3)")
    print(f"  target: proposed >= 120 mm: {'met' if out['proposed'] >= 0.12 else 'not met'}")
    return out


FIGURES = ("slip", "rotation_error")
"""The two figures of Table 2."""


def _average(run: ClimbResult, figure: str) -> float:
    """Average over the wheel groups of ``figure`` in one run."""
    values = run.slip_per_wheel if figure == "slip" else run.rotation_error_per_wheel
    return run.by_group(values)["average"]


def sensitivity() -> dict[str, dict[Method, float]]:
    """One reading changed per row: the 0.1 m step (seed 0) per method, and proposed over
    standard of its slip and rotation error where both climbed; the highest step per method.
    Returns the highest steps per row."""
    print("\nsensitivity: one reading changed per row, rubber rollers otherwise as read")
    print("  reading                      0.1 m std/prop  slip x  rot. x  highest std/prop [mm]")
    table: dict[str, dict[Method, float]] = {}
    for label, geometry in SENSITIVITY:
        runs = {m: climb(m, PAPER_STEP_M, geometry=geometry) for m in METHODS}
        table[label] = {m: highest_step_m(m, geometry) for m in METHODS}
        marks = "/".join("yes" if r.climbed else "no" for r in runs.values())
        ratios = "     -       -"
        if all(r.climbed for r in runs.values()):
            slip, rot = (
                _average(runs["proposed"], f) / _average(runs["standard"], f) for f in FIGURES
            )
            ratios = f"  {slip:5.2f}   {rot:5.2f}"
        highs = " / ".join(f"{1e3 * table[label][m]:3.0f}" for m in METHODS)
        print(f"  {label:28s} {marks:>10s}    {ratios}      {highs}", flush=True)
    return table
