"""The ``planner`` backend: offline, deterministic text -> terrain tool calls (images: see ``image.py``).

A scene description is scanned for *cues* (beach, river, forest, stairs, snow, ...) and *modifiers*
(knee-deep, steep, rocky, slippery, strong current, ...). Each cue is a short recipe of tool calls on a
*slot* of the tile; the cues found are laid out in the order they are mentioned (one cue: the whole tile;
two: back then front half; three: back half, front-right, front-left; four: the quadrants). A modifier
changes the calls of the cue mentioned nearest to it ("knee-deep river", "a river, knee-deep"). Every call
is validated against the registry, so the recipes can only use real tools and parameters, and a modifier
that would push a value out of range is clamped with a warning.

Scale: depths like "knee-deep" refer to a robot of about 1 m height (knee at about 0.3 m), the biped this
project ships; change :data:`KNEE_HEIGHT` for other robots.
"""

from __future__ import annotations

import dataclasses
import math
import re
from typing import Any, Mapping

from legged_gente.generation.backends import GenerationResult
from legged_gente.generation.tools import named_regions
from legged_gente.generation.validation import ToolCall, ValidationError, validate_call
from legged_gente.terrain.registry import ATOMIC_TERRAINS, AtomicTerrain

KNEE_HEIGHT = 0.3
"""Knee height (m) of the ~1 m biped this project ships; "knee-deep" water is this deep."""

Frac = tuple[float, float, float, float]
FULL: Frac = (0.0, 0.0, 1.0, 1.0)


@dataclasses.dataclass(frozen=True)
class Step:
    """One tool call of a recipe, on the fraction ``where`` = (fx0, fy0, fx1, fy1) of the cue's slot."""

    tool: str
    params: Mapping[str, Any] = dataclasses.field(default_factory=dict)
    where: Frac = FULL
    mode: str = "set"


@dataclasses.dataclass(frozen=True)
class Cue:
    name: str
    keywords: tuple[str, ...]
    steps: tuple[Step, ...]
    note: str = ""
    weak: tuple[str, ...] = ()


@dataclasses.dataclass(frozen=True)
class Modifier:
    """Changes the steps of its cue: ``set`` values, ``scale`` factors (per tool, per parameter), ``extra`` steps."""

    name: str
    keywords: tuple[str, ...]
    set: Mapping[str, Mapping[str, Any]] = dataclasses.field(default_factory=dict)
    scale: Mapping[str, Mapping[str, float]] = dataclasses.field(default_factory=dict)
    extra: tuple[Step, ...] = ()


ACROSS = math.pi / 2  # a channel whose axis runs along y: the robot walking +x has to cross it
WATER_FRONT: Frac = (0.6, 0.0, 1.0, 1.0)

CUES: tuple[Cue, ...] = (
    Cue("beach", ("beach", "shore", "shoreline", "coast", "seaside", "sea", "ocean"), (
        Step("natural_ground", {"amplitude": 0.05, "wavelength": 4.0, "platform": 0.0}),
        Step("soil", {"preset": "dry_sand"}, (0.0, 0.0, 0.6, 1.0)),
        Step("soil", {"preset": "wet_sand"}, WATER_FRONT),
        Step("water", {"depth": 0.2, "flow": "tide", "speed": 0.3, "omega": 0.5, "direction": 0.0}, WATER_FRONT),
    )),
    Cue("river", ("river",), (
        Step("natural_ground", {"amplitude": 0.04, "wavelength": 3.0, "platform": 0.0}),
        Step("river", {"width": 4.0, "depth": 0.5, "bank_width": 0.8, "direction": ACROSS, "meander_amplitude": 0.5}, mode="add"),
        Step("soil", {"preset": "wet_sand"}, (0.3, 0.0, 0.7, 1.0)),
        Step("water", {"depth": 0.35, "flow": "current", "speed": 0.6, "direction": ACROSS}, (0.3, 0.0, 0.7, 1.0)),
    )),
    Cue("stream", ("stream", "creek", "brook"), (
        Step("natural_ground", {"amplitude": 0.05, "wavelength": 2.0, "platform": 0.0}),
        Step("river", {"width": 1.5, "depth": 0.2, "bank_width": 0.3, "direction": ACROSS, "meander_amplitude": 0.3}, mode="add"),
        Step("water", {"depth": 0.12, "flow": "current", "speed": 0.4, "direction": ACROSS}, (0.4, 0.0, 0.6, 1.0)),
    )),
    Cue("lake", ("lake", "pond", "pool", "puddle"), weak=("water",), steps=(
        Step("natural_ground", {"amplitude": 0.03, "wavelength": 3.0, "platform": 0.0}),
        Step("pit", {"depth": 0.4, "width": 6.0}, (0.2, 0.2, 0.8, 0.8), mode="add"),
        Step("soil", {"preset": "mud"}, (0.2, 0.2, 0.8, 0.8)),
        Step("water", {"depth": 0.3}, (0.2, 0.2, 0.8, 0.8)),
    )),
    Cue("dunes", ("dune", "desert"), weak=("sand", "sandy"), steps=(
        Step("hills", {"amplitude": 0.6, "wavelength": 7.0, "platform": 0.0}),
        Step("soil", {"preset": "dry_sand"}),
    )),
    Cue("forest", ("forest", "wood", "woods", "woodland", "jungle"), weak=("tree",), steps=(
        Step("natural_ground", {"amplitude": 0.1, "wavelength": 2.0, "platform": 0.0}),
        Step("pillars", {"height": 3.0, "min_radius": 0.1, "max_radius": 0.3, "density": 0.06}, mode="add"),
        Step("rocks", {"max_height": 0.08, "min_radius": 0.05, "max_radius": 0.2, "density": 0.3}, mode="add"),
        Step("soil", {"preset": "clay_loam"}),
    )),
    Cue("park", ("park", "meadow", "grass", "grassland", "lawn", "field"), (
        Step("natural_ground", {"amplitude": 0.04, "wavelength": 3.0, "platform": 0.0}),
        Step("pillars", {"height": 3.0, "min_radius": 0.15, "max_radius": 0.3, "density": 0.01}, mode="add"),
    )),
    Cue("street", ("city street", "street", "sidewalk", "road", "plaza", "city", "urban"), (
        Step("flat", {"height": 0.0}),
        Step("discrete_obstacles", {"max_height": 0.12, "min_size": 0.3, "max_size": 1.0, "density": 0.05, "platform": 1.0}, mode="add"),
        Step("pillars", {"height": 3.0, "min_radius": 0.05, "max_radius": 0.12, "density": 0.02}, mode="add"),
    )),
    Cue("stairs", ("stairs", "staircase", "stairway", "steps", "stair"), (
        Step("stairs", {"step_height": 0.12, "step_width": 0.35, "direction": "up"}),
    )),
    Cue("rubble", ("ruin", "ruins", "rubble", "debris", "collapsed"), (
        Step("discrete_obstacles", {"max_height": 0.2, "min_size": 0.2, "max_size": 1.0, "density": 0.8}),
        Step("rocks", {"max_height": 0.15, "min_radius": 0.1, "max_radius": 0.4, "density": 0.6}, mode="add"),
    )),
    Cue("construction", ("construction site", "construction", "building site"), (
        Step("discrete_obstacles", {"max_height": 0.25, "min_size": 0.3, "max_size": 1.5, "density": 0.2}),
        Step("pit", {"depth": 0.3, "width": 3.0}, (0.5, 0.0, 1.0, 0.5), mode="add"),
        Step("soil", {"preset": "clay_loam"}),
    )),
    Cue("snow", ("snow", "snowy", "snowfield"), (
        Step("natural_ground", {"amplitude": 0.12, "wavelength": 3.0, "platform": 0.0}),
        Step("soil", {"preset": "snow"}),
    )),
    Cue("ice", ("ice", "icy", "frozen"), (
        Step("flat", {"height": 0.0}),
        Step("low_friction", {"preset": "ice"}),
    )),
    Cue("mud", ("mud", "muddy", "dirt"), (
        Step("natural_ground", {"amplitude": 0.06, "wavelength": 1.5, "platform": 0.0}),
        Step("soil", {"preset": "mud"}),
    )),
    Cue("swamp", ("swamp", "marsh", "bog", "wetland"), (
        Step("natural_ground", {"amplitude": 0.12, "wavelength": 2.5, "platform": 0.0}),
        Step("soil", {"preset": "mud"}),
        Step("water", {"depth": 0.15}, (0.1, 0.1, 0.45, 0.9)),
        Step("water", {"depth": 0.15}, (0.55, 0.1, 0.9, 0.9)),
    )),
    Cue("hills", ("hill", "hills", "hilly", "slope", "incline"), (
        Step("hills", {"amplitude": 0.8, "wavelength": 8.0, "platform": 0.0}),
    )),
    Cue("mountain", ("mountain trail", "mountain", "alpine"), weak=("trail", "path"), steps=(
        Step("hills", {"amplitude": 1.2, "wavelength": 10.0, "platform": 0.0}),
        Step("natural_ground", {"amplitude": 0.08, "wavelength": 1.0, "platform": 0.0}, mode="add"),
        Step("rocks", {"max_height": 0.12, "density": 0.4}, mode="add"),
    )),
    Cue("cave", ("cave", "cavern", "tunnel"), (
        Step("natural_ground", {"amplitude": 0.15, "wavelength": 1.0, "platform": 0.0}),
        Step("rocks", {"max_height": 0.2, "min_radius": 0.1, "max_radius": 0.5, "density": 0.5}, mode="add"),
        Step("low_friction", {"preset": "wet_tiles"}),
    ), note="a heightfield has no ceiling: the cave is modelled by its uneven, wet rock floor"),
    Cue("stepping_stones", ("stepping stones", "stepping stone"), (
        Step("stepping_stones", {"stone_size": 0.6, "stone_distance": 0.25, "depth": 0.5}),
    )),
    Cue("gap", ("gap", "gaps", "trench", "ditch", "chasm"), (
        Step("gap", {"gap_width": 0.6, "depth": 1.0, "platform": 3.0}),
    )),
    Cue("obstacles", ("obstacle", "obstacles", "pillar", "pillars", "post", "posts", "pole", "poles"), (
        Step("pillars", {"height": 2.0, "min_radius": 0.1, "max_radius": 0.3, "density": 0.08}),
    )),
    Cue("rocks", ("rock", "rocks", "boulder", "boulders", "stones", "gravel"), (
        Step("rocks", {"max_height": 0.15, "density": 0.8}),
    )),
    Cue("bumps", ("bumps", "bumpy", "moguls", "wavy ground", "undulating"), (
        Step("waves", {"amplitude": 0.1, "wavelength": 2.0, "pattern": "grid"}),
    )),
)

_STEEPNESS = {
    "hills": ("amplitude",), "pyramid_slope": ("slope",), "stairs": ("step_height",),
    "pyramid_stairs": ("step_height",), "river": ("depth",), "pit": ("depth",),
}
_ROUGHNESS = {"natural_ground": ("amplitude",), "random_uniform": ("amplitude",), "rocks": ("max_height",),
              "discrete_obstacles": ("max_height",), "waves": ("amplitude",)}


def _per_tool(table: Mapping[str, tuple[str, ...]], value: float) -> dict[str, dict[str, float]]:
    return {tool: {p: value for p in params} for tool, params in table.items()}


MODIFIERS: tuple[Modifier, ...] = (
    Modifier("ankle-deep", ("ankle-deep", "ankle deep"), set={"water": {"depth": 0.4 * KNEE_HEIGHT}}),
    Modifier("shallow", ("shallow",), set={"water": {"depth": 0.5 * KNEE_HEIGHT}}),
    Modifier("knee-deep", ("knee-deep", "knee deep"), set={"water": {"depth": KNEE_HEIGHT}}),
    Modifier("deep", ("deep",), set={"water": {"depth": 2.0 * KNEE_HEIGHT}, "river": {"depth": 2.5 * KNEE_HEIGHT}}),
    Modifier("waist-deep", ("waist-deep", "waist deep"), set={"water": {"depth": 2.0 * KNEE_HEIGHT}}),
    Modifier("steep", ("steep", "steeper", "tall"), scale=_per_tool(_STEEPNESS, 1.8)),
    Modifier("gentle", ("gentle", "gently", "easy", "mild"), scale=_per_tool(_STEEPNESS, 0.5)),
    Modifier("rough", ("rough", "uneven", "broken"), scale=_per_tool(_ROUGHNESS, 2.0)),
    Modifier("smooth", ("smooth",), scale=_per_tool(_ROUGHNESS, 0.4)),
    Modifier("rocky", ("rocky", "stony"), extra=(Step("rocks", {"max_height": 0.15, "density": 0.6}, mode="add"),)),
    Modifier("slippery", ("slippery", "slick", "wet"), extra=(Step("low_friction", {"preset": "wet_tiles"}),)),
    Modifier("flooded", ("flooded", "flooding", "submerged"), extra=(Step("water", {"depth": 0.2}),)),
    Modifier("strong current", ("strong current", "fast-flowing", "fast flowing", "rapids", "torrent", "swift"),
             set={"water": {"flow": "current", "speed": 1.5}}),
    Modifier("calm", ("calm", "still", "stagnant"), set={"water": {"flow": "still", "speed": 0.0}}),
    Modifier("waves", ("waves", "wavy", "surf", "tide", "tidal"), set={"water": {"flow": "tide", "speed": 0.6, "omega": 0.8}}),
    Modifier("dense", ("dense", "thick", "crowded", "cluttered"),
             scale={"pillars": {"density": 2.0}, "rocks": {"density": 2.0}, "discrete_obstacles": {"density": 2.0}}),
    Modifier("sparse", ("sparse", "scattered"),
             scale={"pillars": {"density": 0.4}, "rocks": {"density": 0.4}, "discrete_obstacles": {"density": 0.4}}),
)

SLOT_LAYOUTS = {
    1: ("full",),
    2: ("back", "front"),
    3: ("back", "front_right", "front_left"),
    4: ("back_right", "back_left", "front_right", "front_left"),
}

_NEGATION = re.compile(r"\b(no|not|without|never|avoid)\s+(\w+\s+){0,2}$")


def _find(keywords: tuple[str, ...], text: str) -> tuple[int, int] | None:
    """Span of the first keyword (whole words, optional plural) not negated just before it; None if absent."""
    best = None
    for kw in keywords:
        for m in re.finditer(rf"(?<![\w-]){re.escape(kw)}(?:s|es)?(?![\w-])", text):
            if not _NEGATION.search(text[max(0, m.start() - 30):m.start()]):
                best = m.span() if best is None or m.start() < best[0] else best
                break
    return best


def _first_mentions(items, text: str, keys) -> list[tuple[int, Any]]:
    """Items whose keywords occur in ``text``, by first mention; a match inside a longer match is dropped."""
    spans = [(span, item) for item in items if (span := _find(keys(item), text)) is not None]
    keep = [(a, item) for (a, b), item in spans
            if not any(c <= a and b <= d and d - c > b - a for (c, d), _ in spans)]
    return sorted(keep, key=lambda pi: (pi[0], pi[1].name))


def find_cues(text: str) -> list[tuple[int, Cue]]:
    """Cues mentioned in ``text`` with the position of their first mention, in order of mention.

    Weak keywords ("water", "sand", "trees") count only when no cue is named by a strong keyword.
    """
    text = text.lower()
    return _first_mentions(CUES, text, lambda c: c.keywords) or _first_mentions(CUES, text, lambda c: c.weak)


def find_modifiers(text: str) -> list[tuple[int, Modifier]]:
    return _first_mentions(MODIFIERS, text.lower(), lambda m: m.keywords)


def _frac_rect(slot: tuple[float, float, float, float], where: Frac) -> tuple[float, float, float, float]:
    x0, y0, x1, y1 = slot
    fx0, fy0, fx1, fy1 = where
    r = (x0 + fx0 * (x1 - x0), y0 + fy0 * (y1 - y0), x0 + fx1 * (x1 - x0), y0 + fy1 * (y1 - y0))
    return tuple(round(v, 2) for v in r)  # type: ignore[return-value]


def _apply(step: Step, modifiers: list[Modifier], terrain: AtomicTerrain, warnings: list[str]) -> dict[str, Any]:
    """The step's parameters with its cue's modifiers applied; out-of-range results clamped with a warning."""
    params = dict(step.params)
    for mod in modifiers:
        params.update(mod.set.get(step.tool, {}))
        for name, factor in mod.scale.get(step.tool, {}).items():
            p = terrain.params[name]
            value = params.get(name, p.default) * factor
            lo = -math.inf if p.low is None else p.low
            hi = math.inf if p.high is None else p.high
            if not lo <= value <= hi:
                clamped = min(max(value, lo), hi)
                warnings.append(f"'{mod.name}' asks {step.tool}.{name}={value:.3g} {p.unit}, outside [{p.low}, {p.high}]; "
                                f"clamped to {clamped:.3g}.")
                value = clamped
            params[name] = round(value, 4)
    return params


def plan_text(
    text: str,
    size_x: float = 20.0,
    size_y: float = 20.0,
    registry: Mapping[str, AtomicTerrain] | None = None,
) -> GenerationResult:
    """Deterministic tool calls for a scene description (see the module docstring for the rules)."""
    registry = ATOMIC_TERRAINS if registry is None else registry
    warnings: list[str] = []
    cues = find_cues(text)
    if not cues:
        warnings.append(
            f"no scene cue recognised in {text!r}; built flat ground. Known cues: "
            f"{sorted(k for c in CUES for k in c.keywords[:1])}."
        )
        cues = [(0, Cue("flat", (), (Step("flat", {"height": 0.0}),)))]
    if len(cues) > 4:
        warnings.append(f"{len(cues)} scene cues found; the tile holds 4, dropped {[c.name for _, c in cues[4:]]}.")
        cues = cues[:4]
    mods = find_modifiers(text)
    per_cue: dict[int, list[Modifier]] = {i: [] for i in range(len(cues))}
    for mpos, mod in mods:  # nearest cue mention wins; ties go to the cue after the modifier ("steep stairs")
        i = min(range(len(cues)), key=lambda k: (abs(cues[k][0] - mpos), cues[k][0] < mpos))
        per_cue[i].append(mod)
    regions = named_regions(size_x, size_y)
    geometric_calls: list[ToolCall] = []
    physical_calls: list[ToolCall] = []
    notes = []
    for i, (_, cue) in enumerate(cues):
        slot_name = SLOT_LAYOUTS[len(cues)][i]
        slot = regions[slot_name]
        used = per_cue[i]
        notes.append(f"{cue.name} on {slot_name}" + (f" ({', '.join(m.name for m in used)})" if used else "")
                     + (f": {cue.note}" if cue.note else ""))
        touched = {s.tool for s in cue.steps}
        for mod in used:
            if not (touched & (set(mod.set) | set(mod.scale))) and not mod.extra:
                warnings.append(f"modifier '{mod.name}' does not apply to {cue.name}; ignored.")
        steps = list(cue.steps) + [s for m in used for s in m.extra]
        geometric = [s for s in steps if registry[s.tool].kind == "geometric"]
        physical = [s for s in steps if registry[s.tool].kind == "physical"]
        for step in geometric + physical:
            terrain = registry[step.tool]
            args = _apply(step, used, terrain, warnings)
            rect = _frac_rect(slot, step.where)
            name = next((n for n, r in regions.items() if r == rect), None)
            args["region"] = name or dict(zip(("x0", "y0", "x1", "y1"), rect))
            if terrain.kind == "geometric":
                args["mode"] = step.mode
            try:
                call = validate_call(step.tool, args, size_x, size_y, registry)
            except ValidationError as exc:  # a recipe bug: say which cue and step
                raise ValidationError([f"planner cue '{cue.name}': {m}" for m in exc.messages]) from None
            (geometric_calls if terrain.kind == "geometric" else physical_calls).append(call)
    # All geometry first, then materials: the order in which the terrain library applies them.
    return GenerationResult(geometric_calls + physical_calls, warnings, notes, model=None)
