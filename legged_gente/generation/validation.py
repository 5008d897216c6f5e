"""Validation of tool calls and spec documents with jsonschema, against the registry-derived schemas.

One path serves the model loop (a model's tool call, arguments as a JSON string) and spec loading (a call
stored in a spec JSON). Every rejection is a :class:`ValidationError` whose message names the tool, the
argument, the value and what is allowed, so it can be shown to a user or sent back to a model as the tool
result. Overlapping regions are allowed on purpose: calls apply in order, later "set" calls replace earlier
heights in the overlap and "add" calls stack, which is how a scene is layered.

Every accepted call builds: the terrain's own parameter rules (``AtomicTerrain.check_params``, the same check
the tile builder runs), a region that holds at least one cell, and stacked heights within the builder's bound
(:func:`check_height_stack`, a worst-case bound; a spec beyond it is built once to decide). Where the resolution
is known, a call is also refused if its feature is finer than the cells can hold (:data:`GRID_RULES`). Input is
bounded before it is parsed (lengths, nesting, counts, finite numbers, integers a float can hold), and only
:class:`ValidationError` leaves this module, its messages truncated.
"""

from __future__ import annotations

import dataclasses
import json
import math
import numbers
from typing import Any, Callable, Iterable, Mapping

import jsonschema
import numpy as np
from jsonschema import Draft202012Validator

from legged_gente.generation.tools import LAYOUT_ARGS, arguments_schema, named_regions
from legged_gente.terrain import atomic
from legged_gente.terrain.composition import (
    MAX_ABS_HEIGHT,
    SPEC_SCHEMA,
    Operation,
    Part,
    Region,
    SEAM_BAND,
    TileSpec,
    clip_text,
    document_region,
    height_advice,
    heightmap_ground,
    params_layout_problem,
    schema_size_problem,
    spec_document_problems,
    stacked_height_bounds,
    tile_spec_from_document,
)
from legged_gente.terrain.registry import ATOMIC_TERRAINS, AtomicTerrain

Rect = tuple[float, float, float, float]

# Input limits: everything a model or a spec file sends is bounded before it is parsed or built.
MAX_CELLS = 4_000_000
"""Most heightfield cells of one tile: 200 m x 200 m at 0.1 m, or 40 m x 40 m at 0.02 m (~1 s to build)."""
MAX_ARGUMENT_CHARS = 16_000
"""Longest JSON text of one tool call's arguments."""
MAX_SPEC_BYTES = 1_000_000
"""Largest spec file."""
MAX_STRING_CHARS = 10_000
"""Longest string anywhere in a call or a spec (a prompt kept as provenance included)."""
MAX_DEPTH = 8
"""Deepest nesting of objects and arrays (a spec needs 5)."""
MAX_INT = 2**53
"""Largest |integer| accepted: beyond it a float no longer holds every integer."""
MAX_MESSAGES = 20
MAX_MESSAGE_CHARS = 400


def printable(text: str) -> str:
    """``text`` with each non-printable character (newline, ESC, other controls, bidi overrides) escaped as in a
    repr: one line that cannot move a terminal's cursor or restyle it, for model and server text."""
    return "".join(c if c.isprintable() else c.encode("unicode_escape").decode("ascii") for c in text)


class ValidationError(ValueError):
    """A rejected tool call or spec; ``messages`` holds one precise sentence per problem.

    Messages are cut to :data:`MAX_MESSAGE_CHARS` characters and at most :data:`MAX_MESSAGES` are kept, so a
    huge input is never echoed whole to a user or back to a model.
    """

    def __init__(self, messages: Iterable[str]):
        messages = [clip_text(str(m), MAX_MESSAGE_CHARS) for m in messages]
        if len(messages) > MAX_MESSAGES:
            messages = messages[:MAX_MESSAGES] + [f"... and {len(messages) - MAX_MESSAGES} more problem(s)."]
        self.messages = messages
        super().__init__("\n".join(self.messages))


def _reject_constant(name: str):
    raise ValueError(f"{name} is not a number JSON allows; send a finite number")


def parse_json(text: str | bytes, what: str, limit: int) -> Any:
    """``json.loads`` with bounds: at most ``limit`` characters, no NaN/Infinity; errors are ValidationError."""
    if len(text) > limit:
        raise ValidationError([f"{what} are {len(text)} characters long; the limit is {limit}."])
    try:
        return json.loads(text, parse_constant=_reject_constant)
    except RecursionError:
        raise ValidationError([f"{what} are nested too deeply to parse; the limit is {MAX_DEPTH} levels."]) from None
    except ValueError as exc:  # JSONDecodeError, NaN/Infinity, integers with too many digits, bad UTF-8
        if "integer string conversion" in str(exc):  # Python's own advice (sys.set_int_max_str_digits) is not theirs
            raise ValidationError([f"{what} hold an integer of more than 4300 digits; use a number below 2**53."]) \
                from None
        raise ValidationError([f"{what} are not valid JSON ({clip_text(str(exc), 160)}); send a JSON object."]) from None


def plain_json_problem(value: Any, max_depth: int = MAX_DEPTH) -> str | None:
    """Why ``value`` is not plain, bounded JSON data (None if it is): nesting, types, finiteness, sizes.

    The answer names the place, e.g. "step_height must be finite, got nan; send a finite number".

    Iterative, so a deeply nested input cannot exhaust the stack; ``jsonschema`` only sees what passes.
    """
    stack = [(value, "", 0)]
    count = 0
    while stack:
        node, where, depth = stack.pop()
        count += 1
        if count > 100_000:
            return "the data hold more than 100000 values; send less"
        at = where or "the data"
        if isinstance(node, dict):
            if depth >= max_depth:
                return f"{at} is nested more than {max_depth} levels deep"
            for k, v in node.items():
                if not isinstance(k, str):
                    return f"{at} has a non-string key {clip_text(repr(k), 40)}"
                stack.append((v, f"{where}.{k[:40]}" if where else k[:40], depth + 1))
        elif isinstance(node, (list, tuple)):
            if depth >= max_depth:
                return f"{at} is nested more than {max_depth} levels deep"
            stack.extend((v, f"{where}[{i}]", depth + 1) for i, v in enumerate(node))
        elif isinstance(node, str):
            if len(node) > MAX_STRING_CHARS:
                return f"{at} is a string of {len(node)} characters; the limit is {MAX_STRING_CHARS}"
        elif isinstance(node, bool) or node is None:
            pass
        elif isinstance(node, numbers.Integral):
            if abs(int(node)) > MAX_INT:
                return f"{at} is an integer of {len(str(abs(int(node))))} digits; use a number below 2**53"
        elif isinstance(node, numbers.Real):
            if not math.isfinite(float(node)):
                return f"{at} must be finite, got {float(node)!r}; send a finite number"
        else:
            return f"{at} is a {type(node).__name__}, which is not JSON data"
    return None


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
    for name, param in terrain.params.items():
        if param.registered is not None:  # the terrain's own check refuses an unregistered choice, saying what to do
            del schema["properties"][name]["enum"]
    return schema


_TYPE_NAMES = {"number": "a number", "integer": "a whole number", "string": "a string", "object": "an object"}


def _fmt(value: Any) -> str:
    """A short JSON-ish rendering of a value for a message (never the whole of a huge or odd value)."""
    if isinstance(value, str):
        value = value[:100]
    try:
        text = json.dumps(value) if not isinstance(value, float) else repr(value)
    except (TypeError, ValueError, RecursionError):
        text = f"<{type(value).__name__}>"
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


@dataclasses.dataclass(frozen=True)
class GridRule:
    """``param`` (m) of a terrain must reach ``cells`` cells (exceed them with ``strict``; 0 passes with ``zero_ok``).

    The builder samples heights at the cell points ``i * resolution``: a feature below the rule's span can hold no
    point and vanish, as ``why`` says. ``span`` names the span for the message, with ``{r}`` for the resolution and
    ``{bound}`` for the span in metres ("one {r} m cell").
    """

    param: str
    cells: float
    span: str
    why: str
    strict: bool = False
    zero_ok: bool = False

    def problem(self, tool: str, value: float, resolution: float) -> str | None:
        """Why ``value`` is finer than cells of ``resolution`` m can hold (one line with the fix), or None."""
        bound = self.cells * resolution
        holds = value > bound * (1 + 1e-9) if self.strict else value >= bound * (1 - 1e-9)  # 1e-9: float rounding
        if holds or (self.zero_ok and value == 0.0):
            return None
        up = math.ceil(bound * 1e4 - 1e-6) / 1e4  # the bound in 0.1 mm, rounded the safe way
        allowed = ("0 or " if self.zero_ok else "") + (f"> {bound:g}" if self.strict else f">= {up:g}")
        coarsest = value / self.cells  # the coarsest resolution that holds the feature (exclusive when strict)
        finer = math.floor(coarsest * 1e4 + 1e-6) / 1e4
        finest = SPEC_SCHEMA["properties"]["resolution"]["minimum"]
        if self.strict:
            fix = f", or a --resolution below {coarsest:g} m" if coarsest > finest else ""
        else:
            fix = f", or --resolution {finer:g} m or finer" if finer >= finest else ""
        span = self.span.format(r=f"{resolution:g}", bound=f"{bound:.4g}")
        return (f"{tool}: {self.param}={value:g} m is {'not more than' if self.strict else 'under'} {span}, so "
                f"{self.why}; use {self.param} {allowed} m{fix}.")


_ONE = "one {r} m cell"
_BETWEEN = "can fall between the cell points"
_TREAD = GridRule("step_width", 1.0, _ONE, "two risers can fall between neighbouring cells and merge steps")
GRID_RULES: dict[Callable[..., Any], tuple[GridRule, ...]] = {
    # Each rule follows from the terrain function's own test of a cell point (terrain/atomic.py): a closed or
    # half-open interval of width w >= resolution always holds a cell point; an open one needs w > resolution.
    atomic.stairs: (_TREAD,),
    atomic.pyramid_stairs: (_TREAD,),
    atomic.stepping_stones: (
        GridRule("stone_size", 1.0, _ONE, f"a stone {_BETWEEN}"),
        GridRule("stone_distance", 1.0, _ONE, f"a gap {_BETWEEN} and join two stones", zero_ok=True),
    ),
    atomic.gap: (
        GridRule("gap_width", 1.0, _ONE, f"the trench {_BETWEEN}", zero_ok=True),
        GridRule("platform", 1.0, _ONE, f"the platform {_BETWEEN}"),
    ),
    atomic.pit: (GridRule("width", 1.0, _ONE, f"the pit {_BETWEEN}", strict=True),),
    atomic.discrete_obstacles: (GridRule("min_size", 1.0, _ONE, f"a block {_BETWEEN}"),),
    # a rock shows where a cell point lies inside its radius; a cell's centre is resolution / sqrt(2) from them all
    atomic.rocks: (GridRule("min_radius", 1.0 / math.sqrt(2.0), "half the diagonal of a {r} m cell ({bound} m)",
                            f"a rock {_BETWEEN}"),),
    atomic.river: (GridRule("width", 1.0, _ONE, f"the channel {_BETWEEN}", strict=True),),
    # Nyquist: at two cells per wavelength the cell points can all sit on the zero crossings
    atomic.waves: (GridRule("wavelength", 2.0, "two {r} m cells", f"the crests and troughs {_BETWEEN}", strict=True),),
}
"""Resolution rules of the built-in terrains, by function. Not ruled: pillars (the builder fills the cell nearest a
thin pillar's axis), the spacing and octaves of random roughness (random_uniform, natural_ground, hills: a sub-cell
wavelength is sampled, not lost, and GenTe's own specs use it), and the spawn ``platform`` (0 means none)."""


def grid_problems(terrain: AtomicTerrain, params: Mapping[str, Any], resolution: float) -> list[str]:
    """Why the checked ``params`` of ``terrain`` describe features finer than cells of ``resolution`` m can hold."""
    found = (rule.problem(terrain.name, params[rule.param], resolution) for rule in GRID_RULES.get(terrain.fn, ()))
    return [p for p in found if p is not None]


def validate_call(
    tool: str,
    arguments: Mapping[str, Any] | str,
    size_x: float = 20.0,
    size_y: float = 20.0,
    registry: Mapping[str, AtomicTerrain] | None = None,
    resolution: float | None = None,
) -> ToolCall:
    """Validate one tool call (``arguments`` a dict or the model's JSON string); return it normalised.

    With ``resolution`` (m) the region must also hold at least one cell and the features must not be finer than
    the cells (:data:`GRID_RULES`). Raises :class:`ValidationError` listing every problem found, and nothing else.
    """
    registry = ATOMIC_TERRAINS if registry is None else registry
    if not isinstance(tool, str) or tool not in registry:
        raise ValidationError([f"unknown tool {_fmt(tool)}; available tools are {sorted(registry)}."])
    if isinstance(arguments, str):
        arguments = parse_json(arguments, f"{tool}: arguments", MAX_ARGUMENT_CHARS) if arguments.strip() else {}
    problem = plain_json_problem(arguments)
    if problem:
        raise ValidationError([f"{tool}: {problem}."])
    terrain = registry[tool]
    schema = _validation_schema(terrain, size_x, size_y)
    errors = sorted(_Validator(schema).iter_errors(arguments), key=lambda e: (list(map(str, e.absolute_path)), e.validator))
    if errors:
        raise ValidationError([m for e in errors[:MAX_MESSAGES] for m in _describe(tool, e, schema)])
    params = {k: v for k, v in arguments.items() if k not in LAYOUT_ARGS}
    try:
        params = terrain.check_params(params)  # the builder's own check: ranges, whole numbers, cross-field rules
    except ValueError as exc:
        raise ValidationError([str(exc)]) from None
    region = arguments["region"]
    if isinstance(region, dict):
        region = tuple(float(region[k]) for k in ("x0", "y0", "x1", "y1"))
    mode = arguments.get("mode", "set") if terrain.kind == "geometric" else None
    call = ToolCall(tool, params, region, mode)
    if terrain.fn is atomic.river:  # a channel beside its region carves nothing
        x0, y0, x1, y1 = call.rect(size_x, size_y)
        problem = atomic.river_outside(params, x1 - x0, y1 - y0)
        if problem:
            raise ValidationError([problem + "."])
    check_height_stack([call], size_x, size_y, registry)  # a call that alone exceeds the bound never builds
    if resolution is not None:
        problems = grid_problems(terrain, params, resolution)
        try:
            Region(*call.rect(size_x, size_y)).cells(resolution)
        except ValueError as exc:
            problems.append(f"{tool}: {exc}")
        if problems:
            raise ValidationError(problems)
    return call


def check_height_stack(
    calls: list[ToolCall], size_x: float, size_y: float, registry: Mapping[str, AtomicTerrain] | None = None,
    base: np.ndarray | None = None,
) -> None:
    """Raise ValidationError if the calls, in order, on ``base`` (a heightmap, None: flat 0 m) can make |height|
    exceed the builder's ``MAX_ABS_HEIGHT``: the terrain's own worst-case bound (:func:`stacked_height_bounds`)."""
    bounds = stacked_height_bounds(calls_tile(calls, size_x, size_y, base=base), registry)
    if bounds.first_beyond is not None:
        call = calls[bounds.first_beyond]
        if call.mode == "set":  # it replaces what lies below, so its own heights reach beyond the bound
            x0, y0, x1, y1 = call.rect(size_x, size_y)
            terrain = (ATOMIC_TERRAINS if registry is None else registry)[call.tool]
            advice = height_advice(terrain, dict(call.params), x1 - x0 + 2 * SEAM_BAND, y1 - y0 + 2 * SEAM_BAND)
            raise ValidationError([
                f"calls[{bounds.first_beyond}] ({call.tool}) can make |height| reach {bounds.peak:.2f} m > "
                f"{MAX_ABS_HEIGHT} m on its own region; {advice + '; or ' if advice else ''}give it a smaller region."
            ])
        if call.mode is None:  # ice: it raises the ground below its surface
            raise ValidationError([
                f"calls[{bounds.first_beyond}] ({call.tool}) can raise the ground to {bounds.peak:.2f} m > "
                f"{MAX_ABS_HEIGHT} m; lower its depth or lay it on lower ground."
            ])
        raise ValidationError([
            f"calls[{bounds.first_beyond}] ({call.tool} with mode {call.mode!r}) can make |height| reach "
            f"{bounds.peak:.2f} m > {MAX_ABS_HEIGHT} m where regions stack; lower its heights, use mode 'set', or move it."
        ])


def calls_tile(calls: list[ToolCall], size_x: float, size_y: float, resolution: float = 0.1, seed: int = 0,
               base: np.ndarray | None = None) -> TileSpec:
    """Validated calls as the terrain library's ``TileSpec``: one part per call, in order (as the builder reads them)."""
    parts = [Part(Region(*c.rect(size_x, size_y)), [Operation(c.tool, dict(c.params), c.mode or "set")]) for c in calls]
    return TileSpec(size_x, size_y, resolution, seed, parts, base)


def tile_problem(size_x: float, size_y: float, resolution: float) -> str | None:
    """Why the builder cannot make a tile of this size and resolution (None if it can)."""
    n = (size_x / resolution, size_y / resolution)
    if any(abs(v - round(v)) > 1e-6 for v in n):
        return (f"the {size_x:g} m x {size_y:g} m tile is not a whole number of {resolution:g} m cells; "
                f"pick sizes that are multiples of the resolution")
    cells = round(n[0]) * round(n[1])
    if cells > MAX_CELLS:
        return (f"the {size_x:g} m x {size_y:g} m tile at {resolution:g} m has {cells} cells; the limit is {MAX_CELLS} "
                f"(e.g. 200 m x 200 m at 0.1 m): use a coarser resolution or a smaller tile")
    return None


def spec_field_problem(field: str, value: Any) -> str | None:
    """Why ``value`` cannot be the spec's ``field`` (None if it can), by that field's rule in :data:`SPEC_SCHEMA`;
    lets a caller refuse a value before generating (the value itself is not repeated)."""
    rule = SPEC_SCHEMA["properties"][field]
    error = next(Draft202012Validator(rule).iter_errors(value), None)
    if error is None:
        return None
    too_long = schema_size_problem(error)
    if too_long:
        return too_long
    if error.validator in ("minimum", "maximum"):
        return f"must be in [{rule['minimum']:g}, {rule['maximum']:g}]"
    return f"must be {rule['description']}"


def validate_spec_dict(
    data: Any, registry: Mapping[str, AtomicTerrain] | None = None, base_dir: Any = None
) -> tuple[dict[str, Any], list[ToolCall]]:
    """Validate a spec document (see :class:`legged_gente.generation.spec.TerrainSpec`); return it and its calls.

    Accepts only what builds: the document's schema and limits, its heightmap (read from ``base_dir``, the spec
    file's folder), every call, the tile's cell grid and the stacked heights. Raises :class:`ValidationError`,
    and nothing else.
    """
    problem = plain_json_problem(data)
    if problem:
        raise ValidationError([f"spec: {problem}."])
    problems = spec_document_problems(data, most=MAX_MESSAGES)
    if problems:
        raise ValidationError(problems)
    problem = tile_problem(data["size_x"], data["size_y"], data["resolution"])
    if problem:
        raise ValidationError([f"spec: {problem}."])
    base = None
    if "heightmap" in data:
        try:
            base = heightmap_ground(data["heightmap"], data["size_x"], data["size_y"], data["resolution"], base_dir)
        except ValueError as exc:
            raise ValidationError([f"spec: {exc}."]) from None
    calls, messages = [], []
    for i, c in enumerate(data["calls"]):
        problem = params_layout_problem(c["params"])
        if problem:  # training passes params to the terrain as they are: layout there would not build
            messages.append(f"spec: calls[{i}]: {problem}.")
            continue
        args = {**c["params"], "region": c["region"]}
        if "mode" in c:
            args["mode"] = c["mode"]
        try:
            calls.append(validate_call(c["tool"], args, data["size_x"], data["size_y"], registry, data["resolution"]))
        except ValidationError as exc:
            messages += [f"spec: calls[{i}]: {m}" for m in exc.messages]
    regions = named_regions(data["size_x"], data["size_y"])
    for i, f in enumerate(data.get("smoothing", [])):
        try:
            region = document_region(f["region"], regions)
            region.check(data["size_x"], data["size_y"])
            region.cells(data["resolution"])
        except ValueError as exc:
            messages.append(f"spec: smoothing[{i}]: {exc}")
    if messages:
        raise ValidationError(messages)
    try:
        check_height_stack(calls, data["size_x"], data["size_y"], registry, base)
    except ValidationError as exc:
        # The interval bound is a worst case; this spec's own seed may stay within the bound: build to know.
        try:
            tile_spec_from_document(data, base_dir).build()
        except ValueError as build_exc:
            raise ValidationError([f"spec: {build_exc}"] + [f"spec: {m}" for m in exc.messages]) from None
    return data, calls
