"""Validation of tool calls and spec documents with jsonschema, against the registry-derived schemas.

One path serves the model loop (a model's tool call, arguments as a JSON string) and spec loading (a call
stored in a spec JSON). Every rejection is a :class:`ValidationError` whose message names the tool, the
argument, the value and what is allowed, so it can be shown to a user or sent back to a model as the tool
result. Overlapping regions are allowed on purpose: calls apply in order, later "set" calls replace earlier
heights in the overlap and "add" calls stack, which is how a scene is layered.
"""

from __future__ import annotations

import dataclasses
import json
from typing import Any, Iterable, Mapping

import jsonschema
from jsonschema import Draft202012Validator

from legged_gente.generation.tools import LAYOUT_ARGS, arguments_schema, named_regions
from legged_gente.terrain.registry import ATOMIC_TERRAINS, AtomicTerrain

SPEC_VERSION = 1

Rect = tuple[float, float, float, float]


class ValidationError(ValueError):
    """A rejected tool call or spec; ``messages`` holds one precise sentence per problem."""

    def __init__(self, messages: Iterable[str]):
        self.messages = list(messages)
        super().__init__("\n".join(self.messages))


@dataclasses.dataclass(frozen=True)
class ToolCall:
    """A validated call: terrain ``tool`` with all its ``params`` (defaults filled) on ``region`` with ``mode``.

    ``region`` is a named region (see :func:`legged_gente.generation.tools.named_regions`) or a rectangle
    ``(x0, y0, x1, y1)`` in metres. ``mode`` is "set" or "add" for geometric terrains, None for physical ones.
    """

    tool: str
    params: dict[str, Any]
    region: str | Rect
    mode: str | None = "set"

    def rect(self, size_x: float, size_y: float) -> Rect:
        """The region as ``(x0, y0, x1, y1)`` metres on a ``size_x`` x ``size_y`` tile."""
        if isinstance(self.region, str):
            return named_regions(size_x, size_y)[self.region]
        return self.region

    def region_json(self) -> str | dict[str, float]:
        if isinstance(self.region, str):
            return self.region
        return dict(zip(("x0", "y0", "x1", "y1"), self.region))

    def arguments(self) -> dict[str, Any]:
        """The flat tool-call arguments (parameters + layout), as a model would send them."""
        layout = {"region": self.region_json()} | ({"mode": self.mode} if self.mode is not None else {})
        return {**self.params, **layout}

    def to_dict(self) -> dict[str, Any]:
        out = {"tool": self.tool, "region": self.region_json(), "params": dict(self.params)}
        return out | ({"mode": self.mode} if self.mode is not None else {})


def _positive_area(validator: Any, enabled: bool, instance: Any, schema: Mapping[str, Any]):
    """Custom keyword ``positiveArea``: a rectangle must have x0 < x1 and y0 < y1 (non-zero area)."""
    if not enabled or not isinstance(instance, dict):
        return
    for lo, hi in (("x0", "x1"), ("y0", "y1")):
        a, b = instance.get(lo), instance.get(hi)
        if isinstance(a, (int, float)) and isinstance(b, (int, float)) and not a < b:
            yield jsonschema.ValidationError(
                f"rectangle has {lo}={a!r} >= {hi}={b!r}, so it has zero area; make {lo} < {hi}."
            )


_Validator = jsonschema.validators.extend(Draft202012Validator, {"positiveArea": _positive_area})


def _validation_schema(terrain: AtomicTerrain, size_x: float, size_y: float) -> dict[str, Any]:
    schema = arguments_schema(terrain, size_x, size_y)
    schema["properties"]["region"]["oneOf"][1]["positiveArea"] = True
    return schema


_TYPE_NAMES = {"number": "a number", "integer": "a whole number", "string": "a string", "object": "an object"}


def _fmt(value: Any) -> str:
    text = json.dumps(value) if not isinstance(value, float) else repr(value)
    return text if len(text) <= 80 else text[:77] + "..."


def _describe(tool: str, err: jsonschema.ValidationError, schema: Mapping[str, Any]) -> list[str]:
    """Turn one jsonschema error into sentences naming the tool, argument, value and what is allowed."""
    path = ".".join(str(p) for p in err.absolute_path)
    arg = f"argument {path!r}" if path else "arguments"
    props = schema.get("properties", {})
    kind = err.validator
    if kind == "additionalProperties":
        extra = sorted(set(err.instance) - set(err.schema.get("properties", {})))
        allowed = sorted(err.schema.get("properties", {}))
        return [f"{tool}: unexpected {arg if path else 'argument(s)'} {extra}; allowed arguments are {allowed}."]
    if kind == "required":
        missing = err.message.split("'")[1]
        where = f"{path}.{missing}" if path else missing
        desc = props.get(missing, {}).get("description", "") if not path else ""
        return [f"{tool}: missing required argument {where!r}. {desc}".strip()]
    if kind == "type":
        if not path:
            return [f"{tool}: arguments must be a JSON object, got {_fmt(err.instance)}."]
        return [f"{tool}: {arg}={_fmt(err.instance)} has the wrong type; expected {_TYPE_NAMES.get(err.validator_value, err.validator_value)}. "
                f"{err.schema.get('description', '')}".strip()]
    if kind in ("minimum", "maximum"):
        lo, hi = err.schema.get("minimum"), err.schema.get("maximum")
        return [f"{tool}: {arg}={_fmt(err.instance)} is outside the allowed range [{lo}, {hi}]. "
                f"{err.schema.get('description', '')}".strip()]
    if kind == "enum":
        return [f"{tool}: {arg}={_fmt(err.instance)} is not one of {err.validator_value}."]
    if kind == "oneOf":  # the region: pick the branch that matches the value's JSON type
        branch = 1 if isinstance(err.instance, dict) else 0 if isinstance(err.instance, str) else None
        sub = [e for e in err.context if branch is not None and e.relative_schema_path[0] == branch]
        if sub:
            return [m for e in sub for m in _describe(tool, e, schema)]
        return [f"{tool}: {arg}={_fmt(err.instance)} is neither a region name nor a rectangle. "
                f"{err.schema.get('description', '')}".strip()]
    if kind == "positiveArea":
        return [f"{tool}: {arg} {err.message}"]
    return [f"{tool}: {arg}={_fmt(err.instance)}: {err.message}."]


def validate_call(
    tool: str,
    arguments: Mapping[str, Any] | str,
    size_x: float = 20.0,
    size_y: float = 20.0,
    registry: Mapping[str, AtomicTerrain] | None = None,
) -> ToolCall:
    """Validate one tool call (``arguments`` a dict or the model's JSON string); return it normalised.

    Raises :class:`ValidationError` listing every problem found.
    """
    registry = ATOMIC_TERRAINS if registry is None else registry
    if not isinstance(tool, str) or tool not in registry:
        raise ValidationError([f"unknown tool {_fmt(tool)}; available tools are {sorted(registry)}."])
    if isinstance(arguments, str):
        try:
            arguments = json.loads(arguments) if arguments.strip() else {}
        except json.JSONDecodeError as exc:
            raise ValidationError([f"{tool}: arguments are not valid JSON ({exc}); send a JSON object."]) from None
    terrain = registry[tool]
    schema = _validation_schema(terrain, size_x, size_y)
    errors = sorted(_Validator(schema).iter_errors(arguments), key=lambda e: (list(map(str, e.absolute_path)), e.validator))
    if errors:
        raise ValidationError([m for e in errors for m in _describe(tool, e, schema)])
    params = {k: v for k, v in arguments.items() if k not in LAYOUT_ARGS}
    try:
        params = terrain.check_params(params)  # the registry has the last word (finiteness, whole numbers)
    except ValueError as exc:
        raise ValidationError([str(exc)]) from None
    region = arguments["region"]
    if isinstance(region, dict):
        region = tuple(float(region[k]) for k in ("x0", "y0", "x1", "y1"))
    mode = arguments.get("mode", "set") if terrain.kind == "geometric" else None
    return ToolCall(tool, params, region, mode)


SPEC_SCHEMA: dict[str, Any] = {
    "type": "object",
    "properties": {
        "version": {"const": SPEC_VERSION, "description": f"spec format version; this code reads {SPEC_VERSION}"},
        "name": {"type": "string", "pattern": "^[A-Za-z][A-Za-z0-9_]*$"},
        "size_x": {"type": "number", "minimum": 1.0, "maximum": 200.0, "description": "tile length along x [m]"},
        "size_y": {"type": "number", "minimum": 1.0, "maximum": 200.0, "description": "tile width along y [m]"},
        "resolution": {"type": "number", "minimum": 0.02, "maximum": 1.0, "description": "cell size [m]"},
        "seed": {"type": "integer", "minimum": 0, "maximum": 2**32 - 1},
        "calls": {
            "type": "array",
            "items": {
                "type": "object",
                "properties": {
                    "tool": {"type": "string"},
                    "region": {},
                    "mode": {"type": "string"},
                    "params": {"type": "object"},
                },
                "required": ["tool", "region", "params"],
                "additionalProperties": False,
            },
        },
        "source": {"type": "object"},
        "backend": {"type": "string"},
        "model": {"type": ["string", "null"]},
    },
    "required": ["version", "name", "size_x", "size_y", "resolution", "seed", "calls", "source", "backend", "model"],
    "additionalProperties": False,
}


def validate_spec_dict(
    data: Any, registry: Mapping[str, AtomicTerrain] | None = None
) -> tuple[dict[str, Any], list[ToolCall]]:
    """Validate a spec document (see :class:`legged_gente.generation.spec.TerrainSpec`); return it and its calls."""
    errors = sorted(Draft202012Validator(SPEC_SCHEMA).iter_errors(data), key=lambda e: list(map(str, e.absolute_path)))
    if errors:
        raise ValidationError(
            [f"spec: field {'.'.join(map(str, e.absolute_path)) or '(document)'!r}: {e.message}." for e in errors]
        )
    calls, messages = [], []
    for i, c in enumerate(data["calls"]):
        args = {**c["params"], "region": c["region"]}
        if "mode" in c:
            args["mode"] = c["mode"]
        try:
            calls.append(validate_call(c["tool"], args, data["size_x"], data["size_y"], registry))
        except ValidationError as exc:
            messages += [f"spec: calls[{i}]: {m}" for m in exc.messages]
    if messages:
        raise ValidationError(messages)
    return data, calls
