"""docs/showfile.md is generated from the show file's models and must say what they say."""

from __future__ import annotations

from pathlib import Path

from module_by_path import load_module
from pydantic import Field, field_validator, model_validator

from showfile.model_base import ShowModel
from showfile.models import Show

ROOT = Path(__file__).resolve().parent.parent
reference = load_module("showfile_reference", ROOT / "scripts" / "docs" / "showfile_reference.py")


class _Nozzle(ShowModel):
    """A toy section."""

    gap_m: float = Field(default=0.5, gt=0.0, le=2.0)
    """Gap to the wall, in [m]."""
    mode: str = "spray"
    """How it paints."""
    spare_m_enu: tuple[float, float, float] | None = None
    """Where the spare waits, in [m]."""

    @field_validator("mode")
    @classmethod
    def _known_mode(cls, value: str) -> str:
        if value not in ("spray", "drip"):
            raise ValueError(f"unknown mode {value!r}")
        return value

    @model_validator(mode="after")
    def _gap_fits(self) -> _Nozzle:
        if self.gap_m > 1.0 and self.mode == "drip":
            raise ValueError("a drip needs a gap of 1 m at most")
        return self


def test_committed_reference_is_up_to_date_with_the_models() -> None:
    committed = (ROOT / "docs" / "showfile.md").read_text(encoding="utf-8")
    assert committed == reference.render(), (
        "docs/showfile.md is out of date: run .venv/bin/python scripts/docs/showfile_reference.py"
    )


def test_every_field_of_every_section_is_documented() -> None:
    text = reference.render()
    assert "**undocumented**" not in text
    for path, model in reference.sections(Show):
        heading = f"## `{path}` (`{model.__name__}`)" if path else "## Top level (`Show`)"
        section = text.split(heading, 1)[1].split("\n## ", 1)[0]
        for name, info in model.model_fields.items():
            if not info.exclude:
                assert f"**`{name}`**" in section, (path, name)


def test_a_section_shows_type_unit_default_bounds_and_validator_messages() -> None:
    text = reference.render_section("nozzle", _Nozzle, {})
    assert "- **`gap_m`** · number · m · default `0.5` · > 0.0 · ≤ 2.0  \n  Gap to the wall" in text
    assert "**`mode`** · text · default `spray` · refused: “unknown mode {value}”" in text
    assert "**`spare_m_enu`** · [3 × number] or null · m, world ENU · default `null`" in text
    assert "- “a drip needs a gap of 1 m at most”" in text


def test_units_come_from_the_longest_suffix() -> None:
    assert reference.unit_of("center_m_enu") == "m, world ENU"
    assert reference.unit_of("a_max_mps2") == "m/s²"
    assert reference.unit_of("v_max_mps") == "m/s"
    assert reference.unit_of("dry_s") == "s"
    assert reference.unit_of("max_points") is None


def test_section_links_point_at_headings_that_exist() -> None:
    text = reference.render()
    for path, model in reference.sections(Show):
        if path:  # every section but the top is linked from the field that holds it
            assert f"](#{reference.anchor(path, model)})" in text, path
    assert "[`zenoh`](#zenoh-zenohsettings)" in text
    assert "[`boards[]`](#boards-board)" in text


def test_text_outside_code_spans_is_shown_as_written() -> None:
    assert reference.plain("FENCE_*, GF_*; ``a*b`` <x>") == "FENCE_\\*, GF_\\*; ``a*b`` &lt;x>"
    assert reference.plain("`<name>` and <name>") == "`<name>` and &lt;name>"
