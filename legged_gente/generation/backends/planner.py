"""The ``planner`` backend: offline, deterministic text -> terrain tool calls (images: see ``image.py``).

A scene description is scanned for *cues* (beach, river, forest, stairs, buildings, benches, ...) and
*modifiers* (knee-deep, steep, tall, rocky, frozen, dry, calm, ...). Each cue is a short recipe of tool calls
on a *slot* of the tile; the cues found are laid out in the order they are mentioned (one cue: the whole tile;
two: back then front half; three: back half, front-right, front-left; four: the quadrants).

A modifier is bound to the noun it qualifies: first the cue named right after it in the same phrase ("tall
trees", "icy stone steps"), else the nearest cue before it in the same sentence ("a river, knee-deep"), else
the nearest cue it can change at all; a modifier that changes no cue is reported. Modifiers set or scale
parameters (depths, heights, speeds), add calls (rocky: rocks; snowy: snow) or remove them (frozen: the
water becomes ice; dry: no water). Negated words are honoured: "no river" drops the cue, "without sand" /
"no waves" / "no snow" remove that part of every recipe. Every call is validated against the registry, so the
recipes can only use real tools and parameters, and a modifier that would push a value out of range is
clamped with a warning.

Water stands in ground that holds it: a channel's water covers its whole slot (only the channel below the surface
is wet), open water lies in a ``basin``, and after the modifiers every depression holding a water step of the cue is
deepened to the water's depth plus :data:`FREEBOARD`.

Scale: depths like "knee-deep" refer to a robot of about 1 m height (knee at about 0.3 m), the biped this
project ships; change :data:`KNEE_HEIGHT` for other robots.
"""

from __future__ import annotations

import bisect
import dataclasses
import itertools
import math
import re
from typing import Any, Mapping

from legged_gente.generation.backends import GenerationResult
from legged_gente.generation.tools import named_regions
from legged_gente.generation.validation import ToolCall, ValidationError, validate_call
from legged_gente.terrain.composition import SEAM_BAND
from legged_gente.terrain.registry import ATOMIC_TERRAINS, AtomicTerrain

KNEE_HEIGHT = 0.3
"""Knee height (m) of the ~1 m biped this project ships; "knee-deep" water is this deep."""
FREEBOARD = 0.1
"""Height (m) by which the ground holding a recipe's water (its river, pit, basin or sunken floor) rises above the
water's surface after the modifiers: the water's depth plus this is the depression's least depth, so the
ground's few centimetres of relief (natural ground) never lift the waterline over the rim."""
WATER_MARGIN = 2.0 * SEAM_BAND + 0.2
"""Distance (m) by which the depression holding water keeps off a slot edge inside the tile. Its water reaches
``SEAM_BAND`` past it (over the band where the depression blends into the ground), and a neighbouring cue's part
blends into this slot over another ``SEAM_BAND``, which can pull a rim there down below the waterline (stairs
falling away, a quay); two more 0.1 m cells between the two bands keep the rim whole."""
STAIRS_END_DROP = 0.3
"""m: a flight of stairs whose end stands higher or lower than this beside the ground is warned of (the highest
step the terrain library's stairs have)."""
DEPRESSIONS = ("river", "pit", "basin")
"""Geometric terrains that hold water: their ``depth`` below the ground (a ``flat`` below 0 m on part of a slot,
a quay's floor, holds it too)."""

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


Drop = tuple[str, "str | None"]
"""A (tool, preset) pattern of recipe steps a modifier removes; preset None matches any."""


@dataclasses.dataclass(frozen=True)
class Modifier:
    """Changes the steps of its cue: ``set`` values, ``scale`` factors (per tool, per parameter), ``drop`` steps,
    ``extra`` steps (added after the drop, so "snowy" replaces the cue's soil by snow), ``turn`` tools into others
    once the values are set (frozen: water to ice; the step keeps its region and the parameters the new tool takes,
    so a deep frozen lake is deep ice), and ``fallback`` steps, added when it turns nothing in the cue (icy stairs:
    ice friction on the stairs)."""

    name: str
    keywords: tuple[str, ...]
    set: Mapping[str, Mapping[str, Any]] = dataclasses.field(default_factory=dict)
    scale: Mapping[str, Mapping[str, float]] = dataclasses.field(default_factory=dict)
    extra: tuple[Step, ...] = ()
    drop: tuple[Drop, ...] = ()
    turn: Mapping[str, str] = dataclasses.field(default_factory=dict)
    fallback: tuple[Step, ...] = ()

    def applies_to(self, cue: Cue) -> bool:
        """Whether this modifier changes anything in ``cue``."""
        tools = {s.tool for s in cue.steps}
        changed = set(self.set) | set(self.scale) | set(self.turn)
        return bool(self.extra or self.fallback or tools & changed) or any(_dropped(s, self.drop) for s in cue.steps)


def _dropped(step: Step, drop: tuple[Drop, ...]) -> bool:
    return any(step.tool == tool and (preset is None or step.params.get("preset") == preset) for tool, preset in drop)


ACROSS = math.pi / 2  # a channel whose axis runs along y: the robot walking +x has to cross it
WATER_FRONT: Frac = (0.6, 0.0, 1.0, 1.0)
BUILDING_HEIGHT = 2.0
"""Height (m) of a building, tower or cliff block (the top of `flat`'s range): a wall the robot walks around."""
WALL_HEIGHT = 1.2
"""Height (m) of a wall, fence or hedge."""

CUES: tuple[Cue, ...] = (
    # --- water
    Cue("beach", ("beach",), (
        Step("natural_ground", {"amplitude": 0.04, "wavelength": 4.0, "platform": 0.0}),
        Step("soil", {"preset": "dry_sand"}, (0.0, 0.0, 0.6, 1.0)),
        Step("soil", {"preset": "wet_sand"}, WATER_FRONT),
        Step("basin", {"depth": 0.3, "shore_width": 1.5}, WATER_FRONT, mode="add"),
        Step("water", {"depth": 0.2, "flow": "tide", "speed": 0.3, "omega": 0.5, "direction": 0.0}, WATER_FRONT),
    )),
    Cue("sea", ("sea", "ocean", "coast", "coastline", "seaside", "seashore"), (
        Step("natural_ground", {"amplitude": 0.05, "wavelength": 4.0, "platform": 0.0}),
        Step("basin", {"depth": 0.5, "shore_width": 2.0}, WATER_FRONT, mode="add"),
        Step("water", {"depth": 0.4, "flow": "tide", "speed": 0.4, "omega": 0.5, "direction": 0.0}, WATER_FRONT),
    )),
    Cue("tidal flat", ("tidal flat", "tidal flats", "mudflat", "mud flat", "mud flats"), (
        Step("natural_ground", {"amplitude": 0.03, "wavelength": 4.0, "platform": 0.0}),
        Step("soil", {"preset": "wet_sand"}),
        Step("basin", {"depth": 0.2, "shore_width": 1.0}, (0.5, 0.0, 1.0, 1.0), mode="add"),
        Step("water", {"depth": 0.1, "flow": "tide", "speed": 0.3, "omega": 0.5, "direction": 0.0}, (0.5, 0.0, 1.0, 1.0)),
    )),
    Cue("shore", ("shore", "shoreline", "lakeshore", "waterfront", "waterside"), (
        Step("natural_ground", {"amplitude": 0.04, "wavelength": 3.0, "platform": 0.0}),
        Step("basin", {"depth": 0.25, "shore_width": 1.5}, WATER_FRONT, mode="add"),
        Step("water", {"depth": 0.15}, WATER_FRONT),
    )),
    Cue("bank", ("bank", "riverbank", "embankment"), (
        Step("natural_ground", {"amplitude": 0.05, "wavelength": 3.0, "platform": 0.0}),
    ), note="the dry ground next to water"),
    Cue("river", ("river", "riverbed", "river bed"), (
        Step("natural_ground", {"amplitude": 0.04, "wavelength": 3.0, "platform": 0.0}),
        Step("river", {"width": 4.0, "depth": 0.5, "bank_width": 0.8, "direction": ACROSS, "meander_amplitude": 0.5}, mode="add"),
        Step("water", {"depth": 0.35, "flow": "current", "speed": 0.6, "direction": ACROSS}),
    )),
    Cue("rapids", ("rapids", "torrent", "whitewater", "white water"), (
        Step("natural_ground", {"amplitude": 0.05, "wavelength": 2.0, "platform": 0.0}),
        Step("river", {"width": 5.0, "depth": 0.6, "bank_width": 0.8, "direction": ACROSS}, mode="add"),
        Step("water", {"depth": 0.4, "flow": "current", "speed": 1.5, "direction": ACROSS}),
    )),
    Cue("waterfall", ("waterfall", "waterfalls", "cascade"), (
        Step("natural_ground", {"amplitude": 0.05, "wavelength": 2.0, "platform": 0.0}),
        Step("river", {"width": 2.0, "depth": 0.4, "bank_width": 0.4, "direction": 0.0}, mode="add"),
        Step("water", {"depth": 0.3, "flow": "current", "speed": 1.2, "direction": 0.0}),
    )),
    Cue("stream", ("stream", "creek", "brook"), (
        Step("natural_ground", {"amplitude": 0.04, "wavelength": 2.0, "platform": 0.0}),
        Step("river", {"width": 1.5, "depth": 0.2, "bank_width": 0.3, "direction": ACROSS, "meander_amplitude": 0.3}, mode="add"),
        Step("water", {"depth": 0.12, "flow": "current", "speed": 0.4, "direction": ACROSS}),
    )),
    Cue("lake", ("lake", "pond", "pool", "lagoon", "reservoir"), weak=("water",), steps=(
        Step("natural_ground", {"amplitude": 0.03, "wavelength": 3.0, "platform": 0.0}),
        Step("pit", {"depth": 0.4, "width": 6.0}, (0.2, 0.2, 0.8, 0.8), mode="add"),
        Step("water", {"depth": 0.3}, (0.2, 0.2, 0.8, 0.8)),
    )),
    Cue("harbour", ("harbour", "harbor", "marina", "canal", "pier", "jetty", "quay"), (
        Step("flat", {"height": 0.0}),
        Step("flat", {"height": -1.0}, WATER_FRONT),
        Step("water", {"depth": 1.0}, WATER_FRONT),
    )),
    Cue("puddles", ("puddle", "puddles"), (
        Step("natural_ground", {"amplitude": 0.03, "wavelength": 2.0, "platform": 0.0}),
        Step("basin", {"depth": 0.15, "shore_width": 0.5}, (0.2, 0.1, 0.4, 0.4), mode="add"),
        Step("basin", {"depth": 0.15, "shore_width": 0.5}, (0.6, 0.5, 0.8, 0.8), mode="add"),
        Step("water", {"depth": 0.05}, (0.2, 0.1, 0.4, 0.4)),
        Step("water", {"depth": 0.05}, (0.6, 0.5, 0.8, 0.8)),
    )),
    Cue("swamp", ("swamp", "marsh", "bog", "wetland", "wetlands"), (
        Step("natural_ground", {"amplitude": 0.06, "wavelength": 2.5, "platform": 0.0}),
        Step("soil", {"preset": "mud"}),
        Step("basin", {"depth": 0.25, "shore_width": 1.0}, (0.1, 0.1, 0.45, 0.9), mode="add"),
        Step("basin", {"depth": 0.25, "shore_width": 1.0}, (0.55, 0.1, 0.9, 0.9), mode="add"),
        Step("water", {"depth": 0.15}, (0.1, 0.1, 0.45, 0.9)),
        Step("water", {"depth": 0.15}, (0.55, 0.1, 0.9, 0.9)),
    )),
    # --- surfaces
    Cue("dunes", ("dune", "desert", "sand dune"), (
        Step("hills", {"amplitude": 0.6, "wavelength": 7.0, "platform": 0.0}),
        Step("soil", {"preset": "dry_sand"}),
    )),
    Cue("sand", ("sand",), (
        Step("natural_ground", {"amplitude": 0.03, "wavelength": 3.0, "platform": 0.0}),
        Step("soil", {"preset": "dry_sand"}),
    )),
    Cue("snow", ("snow", "snowfield", "powder", "snowdrift"), (
        Step("natural_ground", {"amplitude": 0.05, "wavelength": 3.0, "platform": 0.0}),
        Step("soil", {"preset": "snow"}),
    )),
    Cue("ice", ("ice", "glacier", "ice rink", "ice sheet"), (
        Step("flat", {"height": 0.0}),
        Step("low_friction", {"preset": "ice"}),
    )),
    Cue("mud", ("mud", "mire"), (
        Step("natural_ground", {"amplitude": 0.05, "wavelength": 1.5, "platform": 0.0}),
        Step("soil", {"preset": "mud"}),
    )),
    Cue("gravel", ("gravel", "pebble", "scree", "shingle"), (
        Step("natural_ground", {"amplitude": 0.03, "wavelength": 2.0, "platform": 0.0}),
        Step("random_uniform", {"amplitude": 0.04, "spacing": 0.1, "platform": 0.0}, mode="add"),
    )),
    Cue("grass", ("meadow", "grass", "grassland", "lawn", "field", "garden", "pasture", "farm"), (
        Step("natural_ground", {"amplitude": 0.04, "wavelength": 3.0, "platform": 0.0}),
    )),
    Cue("path", ("path", "trail", "track", "footpath", "dirt road", "dirt track", "dirt path"), (
        Step("natural_ground", {"amplitude": 0.04, "wavelength": 2.0, "platform": 0.0}),
    )),
    Cue("street", ("city street", "street", "sidewalk", "pavement", "road", "plaza", "square", "parking lot", "car park",
                   "city", "urban", "alley", "courtyard", "yard", "underpass"), (
        Step("flat", {"height": 0.0}),
    )),
    # --- relief
    Cue("hills", ("hill", "hilly", "hillside", "slope", "incline", "ramp", "ski slope"), (
        Step("hills", {"amplitude": 0.8, "wavelength": 8.0, "platform": 0.0}),
    )),
    Cue("mountain", ("mountain trail", "mountain", "alpine"), (
        Step("hills", {"amplitude": 1.2, "wavelength": 10.0, "platform": 0.0}),
        Step("natural_ground", {"amplitude": 0.05, "wavelength": 1.0, "platform": 0.0}, mode="add"),
    )),
    Cue("stairs", ("stairs", "staircase", "stairway", "steps", "stair", "stone stairs", "stone steps", "flight of steps"), (
        Step("stairs", {"step_height": 0.12, "step_width": 0.35, "direction": "up"}),
    )),
    Cue("cave", ("cave", "cavern", "tunnel"), (
        Step("natural_ground", {"amplitude": 0.15, "wavelength": 1.0, "platform": 0.0}),
        Step("rocks", {"max_height": 0.2, "min_radius": 0.1, "max_radius": 0.5, "density": 0.5}, mode="add"),
        Step("low_friction", {"preset": "wet_tiles"}),
    ), note="a heightfield has no ceiling: the cave is modelled by its uneven, wet rock floor"),
    Cue("stepping_stones", ("stepping stones", "stepping stone"), (
        Step("stepping_stones", {"stone_size": 0.6, "stone_distance": 0.25, "depth": 0.5}),
    )),
    Cue("gap", ("gap", "trench", "ditch", "chasm", "crevasse"), (
        Step("gap", {"gap_width": 0.6, "depth": 1.0, "platform": 3.0}),
    )),
    Cue("bumps", ("bumps", "bumpy", "moguls", "wavy ground", "undulating"), (
        Step("waves", {"amplitude": 0.1, "wavelength": 2.0, "pattern": "grid"}),
    )),
    # --- obstacles, natural
    Cue("forest", ("forest", "wood", "woods", "woodland", "jungle", "grove"), (
        Step("natural_ground", {"amplitude": 0.06, "wavelength": 2.0, "platform": 0.0}),
        Step("pillars", {"height": 3.0, "min_radius": 0.1, "max_radius": 0.3, "density": 0.06}, mode="add"),
        Step("soil", {"preset": "clay_loam"}),
    )),
    Cue("trees", ("tree", "pine", "palm", "bush", "shrub"), (
        Step("natural_ground", {"amplitude": 0.04, "wavelength": 3.0, "platform": 0.0}),
        Step("pillars", {"height": 3.0, "min_radius": 0.1, "max_radius": 0.3, "density": 0.03}, mode="add"),
    )),
    Cue("park", ("park",), (
        Step("natural_ground", {"amplitude": 0.04, "wavelength": 3.0, "platform": 0.0}),
        Step("pillars", {"height": 3.0, "min_radius": 0.15, "max_radius": 0.3, "density": 0.01}, mode="add"),
    )),
    Cue("rocks", ("rock", "rocks", "boulder", "stones"), (
        Step("rocks", {"max_height": 0.15, "density": 0.8}),
    )),
    Cue("cliff", ("cliff", "bluff", "rock face", "canyon", "gorge", "ravine", "escarpment"), (
        Step("natural_ground", {"amplitude": 0.05, "wavelength": 2.0, "platform": 0.0}),
        Step("flat", {"height": BUILDING_HEIGHT}, (0.75, 0.0, 1.0, 1.0)),
    ), note="the cliff is a 2 m face along the far edge of its part"),
    Cue("logs", ("log", "fallen tree", "root", "curb", "kerb", "stump"), (
        Step("discrete_obstacles", {"max_height": 0.2, "min_size": 0.3, "max_size": 1.5, "density": 0.15, "platform": 0.0}, mode="add"),
    )),
    Cue("rubble", ("ruin", "ruins", "rubble", "debris", "collapsed"), (
        Step("discrete_obstacles", {"max_height": 0.2, "min_size": 0.2, "max_size": 1.0, "density": 0.8}),
        Step("rocks", {"max_height": 0.15, "min_radius": 0.1, "max_radius": 0.4, "density": 0.6}, mode="add"),
        Step("random_uniform", {"amplitude": 0.03, "spacing": 0.1, "platform": 0.0}, mode="add"),
    )),
    # --- obstacles, built
    Cue("buildings", ("building", "house", "skyscraper", "apartment", "temple", "church", "barn", "shed", "hut",
                      "cabin", "factory", "warehouse", "shop", "storefront", "row of houses"), (
        Step("flat", {"height": 0.0}),
        Step("flat", {"height": BUILDING_HEIGHT}, (0.1, 0.0, 0.9, 0.15)),
        Step("flat", {"height": BUILDING_HEIGHT}, (0.1, 0.85, 0.9, 1.0)),
    ), note="buildings are 2 m blocks along both sides of their part"),
    Cue("wall", ("wall", "brick wall", "stone wall", "fence", "railing", "hedge", "barrier", "sandbag"), (
        Step("flat", {"height": WALL_HEIGHT}, (0.0, 0.9, 1.0, 0.96)),
    ), note="the wall runs along the left edge of its part"),
    Cue("tower", ("lighthouse", "tower", "chimney", "windmill", "silo", "obelisk"), (
        Step("flat", {"height": BUILDING_HEIGHT}, (0.45, 0.45, 0.6, 0.6)),
    )),
    Cue("fountain", ("fountain",), (
        Step("flat", {"height": 0.5}, (0.3, 0.3, 0.7, 0.7)),
        # the bowl is a basin cut into the rim (held water: its floor 0.4 m down, deeper for deeper water); its water
        # reaches SEAM_BAND past it, so the bowl keeps 0.1 of the part (0.5 m on a 5 m part) inside the rim's edge
        Step("basin", {"depth": 0.4, "shore_width": 0.1}, (0.4, 0.4, 0.6, 0.6), mode="add"),
        Step("flat", {"height": 1.2}, (0.47, 0.47, 0.55, 0.55)),
        Step("water", {"depth": 0.3}, (0.4, 0.4, 0.6, 0.6)),
    ), note="a basin with a 0.5 m rim, water inside and a central column"),
    Cue("furniture", ("bench", "car", "barrel", "bin", "trash can", "kiosk", "bus stop", "picnic table", "table",
                      "block", "concrete block", "crate", "container", "parked car"), (
        Step("discrete_obstacles", {"max_height": 0.5, "min_size": 0.5, "max_size": 1.5, "density": 0.08, "platform": 1.0}, mode="add"),
    ), note="street furniture as 0.5 m blocks"),
    Cue("obstacles", ("obstacle", "pillar", "post", "pole", "lamp post", "streetlight", "street light", "column",
                      "statue", "bollard", "sign", "signpost"), (
        Step("pillars", {"height": 2.0, "min_radius": 0.1, "max_radius": 0.3, "density": 0.05}, mode="add"),
    )),
    Cue("construction", ("construction site", "construction", "building site"), (
        Step("flat", {"height": 0.0}),
        Step("pit", {"depth": 0.3, "width": 3.0}, (0.5, 0.0, 1.0, 0.5), mode="add"),
        Step("soil", {"preset": "clay_loam"}),
    )),
)

_STEEPNESS = {
    "hills": ("amplitude",), "pyramid_slope": ("slope",), "stairs": ("step_height",),
    "pyramid_stairs": ("step_height",), "river": ("depth",), "pit": ("depth",),
}
_ROUGHNESS = {"natural_ground": ("amplitude",), "random_uniform": ("amplitude",), "rocks": ("max_height",),
              "discrete_obstacles": ("max_height",), "waves": ("amplitude",)}
_DENSITY = ("pillars", "rocks", "discrete_obstacles")
_ALL_SOIL: tuple[Drop, ...] = (("soil", None),)


def _per_tool(table: Mapping[str, tuple[str, ...]], value: float) -> dict[str, dict[str, float]]:
    return {tool: {p: value for p in params} for tool, params in table.items()}


MODIFIERS: tuple[Modifier, ...] = (
    Modifier("ankle-deep", ("ankle-deep", "ankle deep"), set={"water": {"depth": 0.4 * KNEE_HEIGHT}}),
    Modifier("shallow", ("shallow",), set={"water": {"depth": 0.5 * KNEE_HEIGHT}}),
    Modifier("knee-deep", ("knee-deep", "knee deep"), set={"water": {"depth": KNEE_HEIGHT}}),
    Modifier("deep", ("deep",), set={"water": {"depth": 2.0 * KNEE_HEIGHT}, "river": {"depth": 2.5 * KNEE_HEIGHT}}),
    Modifier("waist-deep", ("waist-deep", "waist deep"), set={"water": {"depth": 2.0 * KNEE_HEIGHT}}),
    Modifier("steep", ("steep", "steeper"), scale=_per_tool(_STEEPNESS, 1.8)),
    Modifier("gentle", ("gentle", "gently", "easy", "mild"), scale=_per_tool(_STEEPNESS, 0.5)),
    Modifier("tall", ("tall", "towering", "high"),
             scale={"pillars": {"height": 1.5}, "flat": {"height": 1.5}, "discrete_obstacles": {"max_height": 1.5}}),
    Modifier("rough", ("rough", "uneven", "broken"), scale=_per_tool(_ROUGHNESS, 2.0)),
    Modifier("smooth", ("smooth",), scale=_per_tool(_ROUGHNESS, 0.4)),
    Modifier("rocky", ("rocky", "stony"), extra=(Step("rocks", {"max_height": 0.15, "density": 0.6}, mode="add"),)),
    Modifier("slippery", ("slippery", "slick", "wet"), extra=(Step("low_friction", {"preset": "wet_tiles"}),)),
    Modifier("flooded", ("flooded", "flooding", "submerged"),
             extra=(Step("basin", {"depth": 0.3, "shore_width": 1.5}, mode="add"), Step("water", {"depth": 0.2}))),
    # frost hardens the soils that hold water (mud, wet sand, clay loam at 15-46 % moisture, Wong Table 2.3): frozen
    # ground to walk on, not a soil to sink into
    Modifier("frozen", ("frozen", "icy", "iced over", "ice-covered"), turn={"water": "ice"},
             drop=(("soil", "mud"), ("soil", "wet_sand"), ("soil", "clay_loam")),
             fallback=(Step("low_friction", {"preset": "ice"}),)),
    Modifier("dry", ("dry", "dried", "dried-up", "dried up"), drop=(("water", None),)),
    Modifier("snowy", ("snowy", "snow-covered", "snow covered", "snowbound"), drop=_ALL_SOIL,
             extra=(Step("soil", {"preset": "snow"}),)),
    Modifier("muddy", ("muddy",), drop=_ALL_SOIL, extra=(Step("soil", {"preset": "mud"}),)),
    Modifier("sandy", ("sandy",), drop=_ALL_SOIL, extra=(Step("soil", {"preset": "dry_sand"}),)),
    Modifier("strong current", ("strong current", "fast-flowing", "fast flowing", "swift", "fast", "raging"),
             set={"water": {"flow": "current", "speed": 1.5}}),
    Modifier("flowing", ("flowing", "slow-flowing", "slow flowing", "running"), set={"water": {"flow": "current", "speed": 0.4}}),
    Modifier("calm", ("calm", "still", "stagnant"), set={"water": {"flow": "still", "speed": 0.0}}),
    Modifier("waves", ("waves", "wavy", "surf", "tide", "tidal", "breakers"), set={"water": {"flow": "tide", "speed": 0.6, "omega": 0.8}}),
    Modifier("dense", ("dense", "thick", "crowded", "cluttered"), scale={t: {"density": 2.0} for t in _DENSITY}),
    Modifier("sparse", ("sparse", "scattered", "few"), scale={t: {"density": 0.4} for t in _DENSITY}),
)

NEGATED: dict[str, Modifier] = {
    "sand": Modifier("no sand", (), drop=(("soil", "dry_sand"), ("soil", "wet_sand"))),
    "snow": Modifier("no snow", (), drop=(("soil", "snow"),)),
    "water": Modifier("no water", (), drop=(("water", None),)),
    "waves": Modifier("no waves", (), set={"water": {"flow": "still", "speed": 0.0}}),
    "current": Modifier("no current", (), set={"water": {"flow": "still", "speed": 0.0}}),
    "trees": Modifier("no trees", (), drop=(("pillars", None),)),
    "vegetation": Modifier("no vegetation", (), drop=(("pillars", None),)),
    "rocks": Modifier("no rocks", (), drop=(("rocks", None),)),
}
"""Negated words ("without sand", "no waves") and what they remove from every recipe of the text."""

SLOT_LAYOUTS = {
    1: ("full",),
    2: ("back", "front"),
    3: ("back", "front_right", "front_left"),
    4: ("back_right", "back_left", "front_right", "front_left"),
}

_NEGATORS = "no|not|without|never|avoid"
"""Words that negate the cue or noun at most two words after them (one list for both)."""
_QUANTITY = re.compile(r"(?<![\w.])\d+(?:[.,]\d+)?\s*(?:cm|mm|km|m|metres?|meters?|deg(?:rees?)?|°|%|percent)(?!\w)")
"""A number with a unit ("20 cm", "2 m", "30 degrees"), which the planner does not read: it is said so."""
_NEGATION = re.compile(rf"\b({_NEGATORS})\s+(\w+\s+){{0,2}}$")
_SENTENCE_END = re.compile(r"[.;!?]")
_PHRASE_END = re.compile(r"[,.;:!?]")

Mention = tuple[int, int, Any]  # (start, end, Cue or Modifier)


def _mentions(items, text: str, keys) -> list[Mention]:
    """Every non-negated occurrence of an item's keywords (whole words, optional plural) in ``text``."""
    out = []
    for item in items:
        for kw in keys(item):
            for m in re.finditer(rf"(?<!\w){re.escape(kw)}(?:s|es)?(?!\w)", text):
                if not _NEGATION.search(text[max(0, m.start() - 30):m.start()]):
                    out.append((m.start(), m.end(), item))
    return out


def _outermost(mentions: list[Mention]) -> list[Mention]:
    """Drop mentions lying inside a longer one ("stepping stones" hides "stones", "knee-deep" hides "deep").

    One sweep over the distinct spans by start (longest first): a span ending within the reach of an earlier one
    lies inside it."""
    inner, reach = set(), -1
    for a, b in sorted({(a, b) for a, b, _ in mentions}, key=lambda span: (span[0], -span[1])):
        if b <= reach:
            inner.add((a, b))
        reach = max(reach, b)
    return [(a, b, x) for a, b, x in mentions if (a, b) not in inner]


def _scan(text: str) -> tuple[list[Mention], list[Mention]]:
    """Cue and modifier mentions of ``text`` (lower case), inner mentions dropped across both kinds.

    Weak cue keywords ("water") count only when no cue is named by a strong keyword.
    """
    mods = _mentions(MODIFIERS, text, lambda m: m.keywords)
    cues = _mentions(CUES, text, lambda c: c.keywords) or _mentions(CUES, text, lambda c: c.weak)
    both = _outermost(cues + mods)
    is_cue = lambda x: isinstance(x, Cue)  # noqa: E731
    return sorted(m for m in both if is_cue(m[2])), sorted((m for m in both if not is_cue(m[2])), key=lambda m: m[0])


def find_cues(text: str) -> list[tuple[int, Cue]]:
    """Cues mentioned in ``text`` with the position of their first mention, in order of first mention."""
    return _first_mentions(_scan(text.lower())[0])


def _first_mentions(cue_mentions: list[Mention]) -> list[tuple[int, Cue]]:
    """Each cue's first mention (position, cue), in order of first mention."""
    first: dict[str, tuple[int, Cue]] = {}
    for start, _, cue in cue_mentions:
        first.setdefault(cue.name, (start, cue))
    return sorted(first.values(), key=lambda pc: (pc[0], pc[1].name))


def _bind(text: str, mod: Mention, cue_mentions: list[Mention], sentence_ends: list[int]) -> tuple[Cue | None, Cue | None]:
    """(cue the modifier changes, cue it was aimed at) for one modifier mention (module docstring's rule).

    ``cue_mentions`` sorted by start, none inside another (so their ends are sorted too); ``sentence_ends``: the
    positions of ``text``'s sentence ends, sorted. The candidates are walked nearest first and the walk stops at
    the first that the modifier applies to, so a long text binds in about linear time."""
    start, end, modifier = mod
    following = []
    nxt = bisect.bisect_left(cue_mentions, end, key=lambda m: m[0])  # a later cue's gap holds this one's
    if nxt < len(cue_mentions):
        gap = text[end:cue_mentions[nxt][0]]
        if not _PHRASE_END.search(gap) and len(gap.split(None, 3)) <= 3:
            following = [cue_mentions[nxt]]
    k = bisect.bisect_left(sentence_ends, start)
    sentence_start = sentence_ends[k - 1] if k else -1  # a preceding cue must end after the sentence's last end
    lo = bisect.bisect_right(cue_mentions, sentence_start, key=lambda m: m[1])
    hi = bisect.bisect_right(cue_mentions, start, key=lambda m: m[1])

    def preceding():  # nearest end first; mentions of one span in their order
        i = hi
        while i > lo:
            j = i - 1
            while j > lo and cue_mentions[j - 1][1] == cue_mentions[i - 1][1]:
                j -= 1
            yield from cue_mentions[j:i]
            i = j

    distance = lambda m: min(abs(m[0] - end), abs(start - m[1]))  # noqa: E731
    nearest = itertools.chain(following, preceding())
    aimed = next(nearest, None)
    target = aimed if aimed and modifier.applies_to(aimed[2]) else next(
        (m for m in nearest if modifier.applies_to(m[2])), None)
    aimed = aimed or min(cue_mentions, key=distance, default=None)
    target = target or min((m for m in cue_mentions if modifier.applies_to(m[2])), key=distance, default=None)
    return (target[2] if target else None), (aimed[2] if aimed else None)


def _negations(text: str) -> list[Modifier]:
    found = []
    for word, mod in NEGATED.items():
        if re.search(rf"\b(?:{_NEGATORS})\s+(?:\w+\s+){{0,2}}{word}s?\b", text):
            found.append(mod)
    return found


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


def _inside(inner: Frac, outer: Frac) -> bool:
    return outer[0] <= inner[0] and outer[1] <= inner[1] and inner[2] <= outer[2] and inner[3] <= outer[3]


def _hold_water(steps: list[Step], params: list[dict[str, Any]]) -> set[int]:
    """Deepen every depression that holds a water step of the cue (its rectangle inside the depression's) to the
    water's depth plus ``FREEBOARD``, in ``params`` (the steps' parameters after the modifiers); the indices of the
    water steps and their depressions."""
    held: set[int] = set()
    for w, water in enumerate(steps):
        if water.tool != "water":
            continue
        need = round(float(params[w]["depth"]) + FREEBOARD, 4)
        for d, step in enumerate(steps):
            if not _inside(water.where, step.where):
                continue
            if step.tool in DEPRESSIONS:
                params[d]["depth"] = max(float(params[d].get("depth", ATOMIC_TERRAINS[step.tool].params["depth"].default)), need)
                held |= {w, d}
            elif step.tool == "flat" and step.where != FULL and float(params[d].get("height", 0.0)) < 0.0:
                params[d]["height"] = min(float(params[d]["height"]), -need)
                held |= {w, d}
    return held


def keep_off_seams(rect, slot, size_x: float, size_y: float, water: bool):
    """``rect`` of a depression kept ``WATER_MARGIN`` off each edge of its slot inside the tile (a side on or nearer
    to that edge is moved in); the rect of its water so moved and then widened by ``SEAM_BAND`` on every side inside
    the tile, over the band where the depression blends into the ground around it (a channel's end, a quay floor's
    edge): the water's surface there is the depression's, and no lowered cell of the band is left dry below it."""
    x0, y0, x1, y1 = rect
    slot = tuple(round(v, 2) for v in slot)
    x0 = max(x0, slot[0] + WATER_MARGIN) if slot[0] > 0.0 else x0
    y0 = max(y0, slot[1] + WATER_MARGIN) if slot[1] > 0.0 else y0
    x1 = min(x1, slot[2] - WATER_MARGIN) if slot[2] < size_x else x1
    y1 = min(y1, slot[3] - WATER_MARGIN) if slot[3] < size_y else y1
    if water:
        x0, y0, x1, y1 = max(x0 - SEAM_BAND, 0.0), max(y0 - SEAM_BAND, 0.0), min(x1 + SEAM_BAND, size_x), min(y1 + SEAM_BAND, size_y)
    return tuple(round(v, 2) for v in (x0, y0, x1, y1))


def _steps(cue: Cue, modifiers: list[Modifier]) -> list[Step]:
    """The cue's recipe after the modifiers' drops, then their extra steps and the fallback steps of those that
    turn nothing left in it (before their turns: :func:`_turned`)."""
    drops = tuple(d for m in modifiers for d in m.drop)
    kept = [s for s in cue.steps if not _dropped(s, drops)]
    extra = [s for m in modifiers for s in m.extra]
    fallback = [s for m in modifiers if not any(s.tool in m.turn for s in kept) for s in m.fallback]
    return kept + extra + fallback


def _turned(step: Step, params: dict[str, Any], modifiers: list[Modifier],
            registry: Mapping[str, AtomicTerrain]) -> tuple[Step, dict[str, Any]]:
    """``step`` and its ``params`` after the modifiers' turns: the new tool keeps the parameters it takes."""
    for mod in modifiers:
        if step.tool in mod.turn:
            step = dataclasses.replace(step, tool=mod.turn[step.tool])
            params = {k: v for k, v in params.items() if k in registry[step.tool].params}
    return step, params


def _bind_all(text: str, warnings: list[str]) -> tuple[list[tuple[int, Cue]], dict[str, list[Modifier]]]:
    """The cues laid out (at most 4, by first mention) and the modifiers bound to each (negations included)."""
    lower = text.lower()
    cue_mentions, mod_mentions = _scan(lower)
    cues = _first_mentions(cue_mentions)
    if not cues:
        warnings.append(
            f"no scene cue recognised in {text!r}; built flat ground. Known cues: "
            f"{sorted(k for c in CUES for k in c.keywords[:1])}."
        )
        flat = Cue("flat", (), (Step("flat", {"height": 0.0}),))
        cues = [(0, flat)]
        cue_mentions = [(0, 0, flat)]
    if len(cues) > 4:
        warnings.append(f"{len(cues)} scene cues found; the tile holds 4, dropped {[c.name for _, c in cues[4:]]}.")
        cues = cues[:4]
    kept = {c.name for _, c in cues}
    cue_mentions = [m for m in cue_mentions if m[2].name in kept]
    per_cue: dict[str, list[Modifier]] = {c.name: [] for _, c in cues}
    sentence_ends = [m.start() for m in _SENTENCE_END.finditer(lower)]
    quantities = [m.group(0) for m in _QUANTITY.finditer(lower)]
    if quantities:
        warnings.append(f"the planner reads words, not numbers: {', '.join(repr(q) for q in quantities[:6])} "
                        f"{'is' if len(quantities) == 1 else 'are'} not applied (it sets depths, heights and sizes from "
                        f"words: knee-deep, tall, steep, wide); check the spec's values, edit its spec.json, or use "
                        f"--backend openai.")
    for mention in mod_mentions:
        target, aimed = _bind(lower, mention, cue_mentions, sentence_ends)
        if target is None:
            written = lower[mention[0]:mention[1]]  # the word the user wrote, and the modifier it is a keyword of
            name = f"'{written}'" + (f" ({mention[2].name})" if written != mention[2].name else "")
            warnings.append(f"modifier {name} does not apply to {aimed.name if aimed else 'anything'}; ignored.")
        elif mention[2] not in per_cue[target.name]:
            per_cue[target.name].append(mention[2])
    for negation in _negations(lower):
        for _, cue in cues:
            if negation.applies_to(cue):
                per_cue[cue.name].append(negation)
    return cues, per_cue


def recipe_steps(text: str) -> list[Step]:
    """Every recipe step :func:`plan_text` builds for ``text`` (modifiers' drops and extra steps applied)."""
    cues, per_cue = _bind_all(text, [])
    return [_turned(step, {}, per_cue[cue.name], ATOMIC_TERRAINS)[0]
            for _, cue in cues for step in _steps(cue, per_cue[cue.name])]


def plan_text(
    text: str,
    size_x: float = 20.0,
    size_y: float = 20.0,
    registry: Mapping[str, AtomicTerrain] | None = None,
    resolution: float | None = None,
) -> GenerationResult:
    """Deterministic tool calls for a scene description (see the module docstring for the rules); with the tile's
    ``resolution`` (m), a recipe call whose features are finer than its cells is skipped with a warning."""
    registry = ATOMIC_TERRAINS if registry is None else registry
    warnings: list[str] = []
    cues, per_cue = _bind_all(text, warnings)
    regions = named_regions(size_x, size_y)
    geometric_calls: list[ToolCall] = []
    physical_calls: list[ToolCall] = []
    notes = []
    for i, (_, cue) in enumerate(cues):
        slot_name = SLOT_LAYOUTS[len(cues)][i]
        slot = regions[slot_name]
        used = per_cue[cue.name]
        notes.append(f"{cue.name} on {slot_name}" + (f" ({', '.join(m.name for m in used)})" if used else "")
                     + (f": {cue.note}" if cue.note else ""))
        steps = _steps(cue, used)
        params = [_apply(step, used, registry[step.tool], warnings) for step in steps]
        held = _hold_water(steps, params)
        steps, params = map(list, zip(*(_turned(step, args, used, registry) for step, args in zip(steps, params))))
        # geometry first, then materials, each in recipe order
        for k in sorted(range(len(steps)), key=lambda k: registry[steps[k].tool].kind != "geometric"):
            step, args, terrain = steps[k], params[k], registry[steps[k].tool]
            rect = _frac_rect(slot, step.where)
            if k in held:
                rect = keep_off_seams(rect, slot, size_x, size_y, step.tool in ("water", "ice"))
                if rect[2] <= rect[0] or rect[3] <= rect[1]:
                    raise ValidationError([f"planner cue '{cue.name}' does not fit on a {size_x:g} m x {size_y:g} m "
                                           f"tile: its water keeps {WATER_MARGIN:g} m off its part's edges and no room "
                                           f"is left; ask for a larger tile or fewer cues, or write the calls yourself "
                                           f"in a spec."])
            name = next((n for n, r in regions.items() if r == rect), None)
            if step.tool == "stairs":  # one flight across its part: its ends stand above and below the ground there
                low, high = terrain.bounds({**{k: p.default for k, p in terrain.params.items()}, **args},
                                           rect[2] - rect[0], rect[3] - rect[1])
                if max(-low, high) > STAIRS_END_DROP:
                    warnings.append(f"planner cue '{cue.name}' on {slot_name}: one flight of stairs across it, its "
                                    f"back end up to {-low:.2f} m below and its front end up to {high:.2f} m above "
                                    f"the ground beside it: drops a robot cannot step; more cues give it a shorter "
                                    f"part, or edit the spec.")
            args["region"] = name or dict(zip(("x0", "y0", "x1", "y1"), rect))
            if terrain.kind == "geometric":
                args["mode"] = step.mode
            try:
                call = validate_call(step.tool, args, size_x, size_y, registry)
            except ValidationError as exc:  # every recipe builds on a 20 m tile: a larger one can be too large
                raise ValidationError([f"planner cue '{cue.name}' does not fit on a {size_x:g} m x {size_y:g} m tile: "
                                       f"ask for a smaller tile, or write the calls yourself in a spec ({m.rstrip('.')})."
                                       for m in exc.messages]) from None
            if resolution is not None:
                try:
                    validate_call(step.tool, args, size_x, size_y, registry, resolution)
                except ValidationError as exc:  # finer than the grid (e.g. rocks at 0.2 m cells): keep the rest
                    warnings += [f"skipped: planner cue '{cue.name}': {m}" for m in exc.messages]
                    continue
            (geometric_calls if terrain.kind == "geometric" else physical_calls).append(call)
    # All geometry first, then materials: the order in which the terrain library applies them.
    return GenerationResult(geometric_calls + physical_calls, warnings, notes, model=None)
