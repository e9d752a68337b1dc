"""docs/strokes.schema.json and the parser agree; docs/formats.md's example parses.

``jsonschema`` is not a dependency, so a small validator for exactly the keywords the schema uses
is written here; a test makes sure the schema uses no other keyword (which would be ignored).
"""

from __future__ import annotations

import json
import re
from pathlib import Path
from typing import Any

import pytest

from planner.errors import PlannerError
from planner.glyphs import parse_strokes_json

DOCS = Path(__file__).parents[1] / "docs"
SCHEMA: dict[str, Any] = json.loads((DOCS / "strokes.schema.json").read_text(encoding="utf-8"))

ANNOTATIONS = {"$schema", "$id", "title", "description", "$defs"}
ASSERTIONS = {
    "$ref", "type", "enum", "required", "properties", "additionalProperties", "items",
    "prefixItems", "minItems", "maxItems", "minimum", "maximum", "exclusiveMinimum", "maxLength",
    "oneOf", "dependentRequired",
}  # fmt: skip
TYPES = {
    "object": lambda v: isinstance(v, dict),
    "array": lambda v: isinstance(v, list),
    "string": lambda v: isinstance(v, str),
    "number": lambda v: isinstance(v, int | float) and not isinstance(v, bool),
}


def schema_errors(value: Any, schema: dict[str, Any], path: str = "$") -> list[str]:
    """Violations of ``schema`` by ``value`` (draft 2020-12 semantics for the keywords above)."""
    if "$ref" in schema:
        name = schema["$ref"].removeprefix("#/$defs/")
        return schema_errors(value, SCHEMA["$defs"][name], path)
    if "oneOf" in schema:
        passing = sum(not schema_errors(value, sub, path) for sub in schema["oneOf"])
        if passing != 1:
            return [f"{path}: matches {passing} of oneOf"]
    if "type" in schema and not TYPES[schema["type"]](value):
        return [f"{path}: not {schema['type']}"]
    errors = []
    if "enum" in schema and not any(value == e and type(value) is type(e) for e in schema["enum"]):
        errors.append(f"{path}: not in enum")
    if isinstance(value, dict):
        errors += [f"{path}: missing {k}" for k in schema.get("required", []) if k not in value]
        for key, needs in schema.get("dependentRequired", {}).items():
            if key in value:
                errors += [f"{path}: {key} without {n}" for n in needs if n not in value]
        for key, sub in schema.get("properties", {}).items():
            if key in value:
                errors += schema_errors(value[key], sub, f"{path}.{key}")
        if schema.get("additionalProperties", True) is False:
            errors += [f"{path}: extra {k}" for k in value if k not in schema["properties"]]
    if isinstance(value, list):
        if len(value) < schema.get("minItems", 0) or len(value) > schema.get("maxItems", 1e18):
            errors.append(f"{path}: wrong length")
        prefix = schema.get("prefixItems", [])
        for i, item in enumerate(value):
            sub = prefix[i] if i < len(prefix) else schema.get("items")
            if sub is not None:
                errors += schema_errors(item, sub, f"{path}[{i}]")
    if isinstance(value, str) and len(value) > schema.get("maxLength", 1e18):
        errors.append(f"{path}: too long")
    if TYPES["number"](value):
        if value < schema.get("minimum", -1e308):
            errors.append(f"{path}: below minimum")
        if value > schema.get("maximum", 1e308):
            errors.append(f"{path}: above maximum")
        if "exclusiveMinimum" in schema and value <= schema["exclusiveMinimum"]:
            errors.append(f"{path}: not above exclusiveMinimum")
    return errors


def keywords(schema: Any) -> set[str]:
    found: set[str] = set()
    if isinstance(schema, dict):
        for key, sub in schema.items():
            found.add(key)
            if key in ("properties", "$defs"):
                for s in sub.values():
                    found |= keywords(s)
            elif key in ("items", "additionalProperties"):
                found |= keywords(sub)
            elif key in ("prefixItems", "oneOf"):
                for s in sub:
                    found |= keywords(s)
    return found


def test_schema_uses_only_checked_keywords() -> None:
    assert SCHEMA["$schema"] == "https://json-schema.org/draft/2020-12/schema"
    assert keywords(SCHEMA) <= ANNOTATIONS | ASSERTIONS


def base(**changes: Any) -> dict[str, Any]:
    doc: dict[str, Any] = {"units": "px", "y_axis": "down", "strokes": [[[0, 0], [10, 5]]]}
    doc.update(changes)
    return {k: v for k, v in doc.items() if v is not None}


SCHEMA_VALID = [
    base(),
    base(units="m", y_axis="up"),
    base(strokes=[[[0, 0, 0.0], [1, 1, 0.1]], [[2, 2, 0.3], [3, 3.5, 0.4, 0.9]]]),
    base(label="马", device="phone", canvas={"width": 300, "height": 200.5}, extra={"any": 1}),
    base(strokes=[[[0, 0], [1, 1]]] * 200),
    base(strokes=[[[0, 0], [0, 0], [1, 1]]]),
    base(strokes=[[[-1e6, 1e6], [1e6, -1e6]]], canvas={"width": 1e6, "height": 1}),
    base(strokes=[[{"x": 0, "y": 0, "w": 0.01}, {"x": 1, "y": 1, "w": 1}]]),
    base(strokes=[[{"x": 0, "y": 0, "t": 0, "pressure": 0.2}, {"x": 1, "y": 1, "t": 1}]]),
]
SCHEMA_INVALID = [
    base(strokes=None),
    base(units=None),
    base(y_axis=None),
    base(units="mm"),
    base(y_axis="left"),
    base(strokes=[]),
    base(strokes=[[[0, 0], [1, 1]]] * 201),
    base(strokes=[[[0, 0]]]),
    base(strokes=[[[0, 0], [1]]]),
    base(strokes=[[[0, 0], [1, 1, 2, 3, 4]]]),
    base(strokes=[[[0, 0], ["1", 1]]]),
    base(strokes=[[[0, 0], [True, 1]]]),
    base(strokes=[[[0, 0, 0, 0.5], [1, 1, 1, -0.5]]]),
    base(strokes=[[[0, 0], [1, 1]], "x"]),
    base(strokes={"0": [[0, 0], [1, 1]]}),
    base(label=5),
    base(device=["a"]),
    base(label="x" * 201),
    base(canvas={"width": 0, "height": 3}),
    base(canvas={"width": 10}),
    base(canvas="10x10"),
    base(strokes=[[[0, 0], [1e308, 1]]]),
    base(strokes=[[[0, 0], [1, -1_000_001]]]),
    base(canvas={"width": 1e7, "height": 3}),
    base(strokes=[[{"x": 0, "y": 0, "w": 0}, {"x": 1, "y": 1, "w": 0.01}]]),
    base(strokes=[[{"x": 0, "y": 0, "w": 0.01}, {"x": 1, "y": 1, "w": 1.5}]]),
    base(strokes=[[{"x": 0, "y": 0, "w": 0.01}, {"x": 1, "w": 0.01}]]),
    base(strokes=[[{"x": 0, "y": 0, "w": 0.01}, {"x": 1, "y": 1, "q": 0.01}]]),
    base(strokes=[[{"x": 0, "y": 0, "pressure": 1}, {"x": 1, "y": 1}]]),
]
# valid by the schema, rejected by rules the schema cannot express (see docs/formats.md)
SEMANTICALLY_INVALID = [
    base(strokes=[[[1, 1], [1, 1]]]),
    base(strokes=[[[0, 0, 1.0], [1, 1, 0.5]]]),
    base(strokes=[[[0, 0, 1.0], [1, 1]]]),
    base(strokes=[[[0, 0, 5.0], [1, 1, 6.0]], [[2, 2, 1.0], [3, 3, 2.0]]]),
    base(strokes=[[[float(i), 0.0] for i in range(10_001)]] * 2),
    base(strokes=[[{"x": 0, "y": 0, "w": 0.01}, {"x": 1, "y": 1}]]),
]


def parser_accepts(doc: dict[str, Any]) -> bool:
    try:
        parse_strokes_json(json.dumps(doc))
    except PlannerError:
        return False
    return True


@pytest.mark.parametrize("doc", SCHEMA_VALID)
def test_valid_examples_pass_both(doc: dict[str, Any]) -> None:
    assert schema_errors(doc, SCHEMA) == []
    assert parser_accepts(doc)


@pytest.mark.parametrize("doc", SCHEMA_INVALID)
def test_invalid_examples_fail_both(doc: dict[str, Any]) -> None:
    assert schema_errors(doc, SCHEMA) != []
    assert not parser_accepts(doc)


@pytest.mark.parametrize("doc", SEMANTICALLY_INVALID)
def test_rules_beyond_the_schema(doc: dict[str, Any]) -> None:
    assert schema_errors(doc, SCHEMA) == []
    assert not parser_accepts(doc)


@pytest.mark.parametrize(
    "name", sorted(p.name for p in (DOCS.parent / "tests" / "data").glob("*.json"))
)
def test_sample_files_are_schema_valid(name: str) -> None:
    text = (DOCS.parent / "tests" / "data" / name).read_text(encoding="utf-8")
    assert schema_errors(json.loads(text), SCHEMA) == []
    parse_strokes_json(text, source_name=name)


def test_formats_md_example_parses() -> None:
    text = (DOCS / "formats.md").read_text(encoding="utf-8")
    example = re.search(r"```json\n(.*?)```", text, re.DOTALL)
    assert example is not None
    doc = json.loads(example.group(1))
    assert schema_errors(doc, SCHEMA) == []
    glyph = parse_strokes_json(doc)
    assert len(glyph.strokes) == 3
