"""OpenAI ``tools`` schemas derived from the atomic terrain registry.

Every registered atomic terrain is one tool: its name, description, parameters, units, ranges and choices
come from :data:`legged_gente.terrain.registry.ATOMIC_TERRAINS` and nowhere else, so registering a terrain
function adds a tool. Each tool also takes layout arguments: ``region`` (a named part of the tile or a
rectangle in metres) and, for geometric terrains, ``mode`` ("set" replaces the region's heights, "add" adds
to them).

Layout convention (the heightfield's): +x is the front of the tile, +y its left; a rectangle
``{x0, y0, x1, y1}`` is in metres from the tile's back-right corner (cell (0, 0)).
"""

from __future__ import annotations

import copy
from typing import Any, Mapping

from legged_gente.terrain.composition import LAYOUT_ARGS, named_regions
from legged_gente.terrain.registry import ATOMIC_TERRAINS, AtomicTerrain, Param


MODES = ("set", "add")


def param_schema(param: Param) -> dict[str, Any]:
    """JSON schema of one terrain parameter, with its unit, range, default and doc in the description; a categorical
    parameter offers the choices usable when the schema is built (a soil preset once registered)."""
    if param.choices is not None:
        return {
            "type": "string",
            "enum": param.offered(),
            "default": param.default,
            "description": f"{param.doc} One of {param.offered()}; default {param.default!r}.",
        }
    schema: dict[str, Any] = {"type": "integer" if param.integer else "number"}
    if param.low is not None:
        schema["minimum"] = param.low
    if param.high is not None:
        schema["maximum"] = param.high
    unit = f" [{param.unit}]" if param.unit and param.unit != "1" else ""
    schema["default"] = param.default
    schema["description"] = f"{param.doc}{unit} Range [{param.low}, {param.high}]; default {param.default}."
    return schema


def region_schema(size_x: float, size_y: float) -> dict[str, Any]:
    """``region``: a named part of the tile, or a rectangle in metres inside it."""
    names = list(named_regions(size_x, size_y))
    coord = lambda axis, hi, what: {  # noqa: E731 - tiny local factory
        "type": "number",
        "minimum": 0.0,
        "maximum": hi,
        "description": f"{what} {axis} of the rectangle in metres, 0..{hi} (+x front, +y left).",
    }
    return {
        "description": (
            f"Where on the {size_x:g} m x {size_y:g} m tile the terrain goes: one of {names} "
            f"(+x is front, +y is left), or a rectangle {{x0, y0, x1, y1}} in metres with x0 < x1 <= {size_x:g} "
            f"and y0 < y1 <= {size_y:g}."
        ),
        "oneOf": [
            {"type": "string", "enum": names},
            {
                "type": "object",
                "properties": {
                    "x0": coord("x", size_x, "lower"),
                    "y0": coord("y", size_y, "lower"),
                    "x1": coord("x", size_x, "upper"),
                    "y1": coord("y", size_y, "upper"),
                },
                "required": ["x0", "y0", "x1", "y1"],
                "additionalProperties": False,
            },
        ],
    }


def arguments_schema(terrain: AtomicTerrain, size_x: float = 20.0, size_y: float = 20.0) -> dict[str, Any]:
    """JSON schema of a tool's ``arguments`` object: the terrain's parameters plus the layout arguments."""
    clash = sorted(set(terrain.params) & set(LAYOUT_ARGS))
    if clash:
        raise ValueError(
            f"atomic terrain {terrain.name!r} declares parameter(s) {clash}, which are reserved for layout; "
            f"rename them in its registration."
        )
    props: dict[str, Any] = {name: param_schema(p) for name, p in terrain.params.items()}
    props["region"] = region_schema(size_x, size_y)
    if terrain.kind == "geometric":
        props["mode"] = {
            "type": "string",
            "enum": list(MODES),
            "default": "set",
            "description": "'set' replaces the region's heights with this terrain; 'add' adds it on top.",
        }
    return {"type": "object", "properties": props, "required": ["region"], "additionalProperties": False}


def tool_schema(terrain: AtomicTerrain, size_x: float = 20.0, size_y: float = 20.0) -> dict[str, Any]:
    """One OpenAI ``tools`` entry (``{"type": "function", "function": {...}}``) for ``terrain``."""
    if terrain.kind == "physical":
        role = "Physical terrain (materials: water, soil, friction over the region's current ground; call it after the geometry)"
    else:
        role = "Geometric terrain (heights)"
    return {
        "type": "function",
        "function": {
            "name": terrain.name,
            "description": f"{role}: {terrain.description}",
            "parameters": arguments_schema(terrain, size_x, size_y),
        },
    }


def tool_schemas(
    size_x: float = 20.0, size_y: float = 20.0, registry: Mapping[str, AtomicTerrain] | None = None
) -> list[dict[str, Any]]:
    """The ``tools`` list for every atomic terrain in ``registry`` (default: the global registry), sorted."""
    registry = ATOMIC_TERRAINS if registry is None else registry
    return [copy.deepcopy(tool_schema(registry[name], size_x, size_y)) for name in sorted(registry)]
