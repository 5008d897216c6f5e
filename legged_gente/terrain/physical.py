"""Physical atomic terrains: water, deformable soil and low friction, as :class:`MaterialPatch` es.

Every function takes ``(shape, resolution, rng, heights, **params)`` where ``heights`` are the region's ground
heights, and returns what the region's cells carry. They change no height, but for ``ice``, which fills a
depression with frozen water: combine them with a geometric terrain (water in a ``river``, ``soil`` on ``hills``
for dunes). Water painted over soil keeps the soil.
"""

from __future__ import annotations

import numpy as np

from .soil import SOIL_PRESETS

from .materials import FLOW_KINDS, NO_WATER, MaterialPatch
from .registry import Param, atomic_terrain


def _lerp(a: float, b: float, d: float) -> float:
    return a + (b - a) * d


def _level(heights: np.ndarray, depth: float) -> tuple[np.float32, np.ndarray]:
    """The surface (m) of water filling a region up to ``depth`` above its lowest ground, and the cells below it:
    where ``water`` stands and where ``ice``, frozen water, fills."""
    surface = np.float32(heights.min() + depth)
    return surface, heights < surface


def _water_rules(p) -> None:
    # a speed on still water would be dropped silently ("water:speed=0.5" is still water); a current or tide of
    # speed 0 is allowed: zero means none, as depth 0 is no water
    if p["flow"] == "still" and p["speed"] > 0.0:
        raise ValueError(f"water: speed={p['speed']!r} m/s has no effect on still water; set flow=current or "
                         f"flow=tide to make it flow, or speed=0.")


@atomic_terrain(
    "water",
    "physical",
    "Wading water filling the region up to a depth above its lowest ground, still or flowing (current, tide). "
    "It changes no height: lay it on a depression at least as deep (river, pit, basin), or it stands as a wall "
    "where the region ends.",
    {
        "depth": Param(0.3, "height of the water surface above the lowest ground of the region", "m", 0.0, 2.0),
        "flow": Param("still", "still water, a steady current, or a tide oscillating along direction",
                      choices=tuple(FLOW_KINDS)),
        "speed": Param(0.0, "flow speed (current) or its amplitude (tide)", "m/s", 0.0, 3.0),
        "direction": Param(0.0, "direction of the flow in the xy plane, from +x towards +y", "rad", -np.pi, np.pi),
        "omega": Param(0.5, "angular frequency of the tide", "rad/s", 0.0, 2.0),
        "phase": Param(0.0, "phase of the tide", "rad", -np.pi, np.pi),
    },
    difficulty=lambda d: {"depth": _lerp(0.05, 0.5, d)},
    rules=_water_rules,
)
def water(shape, resolution, rng, heights, depth, flow, speed, direction, omega, phase):
    surface, wet = _level(heights, depth)
    return MaterialPatch(
        shape=shape,
        water_surface=np.where(wet, surface, NO_WATER).astype(np.float32),
        flow_kind=FLOW_KINDS[flow],
        flow_speed=speed,
        flow_direction=direction,
        flow_omega=omega,
        flow_phase=phase,
    )


SOIL_CHOICES = tuple(SOIL_PRESETS) + ("custom",)
"""Built-in presets of ``legged_gente.terrain.soil`` plus "custom"; a soil registered there under any other name is a
choice too (``Param.registered``). Each custom one must be registered first: until then a model is not offered it."""

SOIL_PRESET = Param(
    "dry_sand",
    "soil preset; a custom one (any name) needs register_custom_soil(name, ...) from legged_gente.terrain.soil",
    choices=SOIL_CHOICES,
    registered=SOIL_PRESETS,
)


def _soil_rules(p) -> None:
    if p["preset"] not in SOIL_PRESETS:
        raise ValueError(
            f"soil: preset {p['preset']!r} is not registered; use one of {SOIL_PRESET.offered()}, or register it "
            f"from Python first: legged_gente.terrain.soil.register_custom_soil({p['preset']!r}, kc=..., kphi=..., "
            f"n=..., c=..., mu=..., K=..., bulldoze_c=..., bulldoze_g=...)."
        )


@atomic_terrain(
    "soil",
    "physical",
    "Deformable soil the feet sink into: sand, snow, mud or clay (Bekker pressure-sinkage, bulldozing, shear).",
    {"preset": SOIL_PRESET},
    rules=_soil_rules,
)
def soil(shape, resolution, rng, heights, preset):
    return MaterialPatch(shape=shape, soil=preset)


# Friction ranges (rubber-like foot sole): ice 0.05-0.10 (Persson, "Sliding Friction", 2nd ed. 2000, ch. on ice;
# tyre/rubber on wet ice), wet glazed tiles 0.30-0.40 (HSE/UK Slip Resistance Group pendulum guidance: wet
# smooth ceramic tiles fall in the 0.3-0.4 dynamic friction band). One value per region is drawn uniformly.
LOW_FRICTION_RANGES = {"ice": (0.05, 0.10), "wet_tiles": (0.30, 0.40)}


@atomic_terrain(
    "low_friction",
    "physical",
    "Slippery ground: ice, wet tiles, or a custom friction coefficient.",
    {
        "preset": Param("ice", "ice (mu 0.05-0.10), wet_tiles (mu 0.30-0.40), or custom (uses mu)",
                        choices=tuple(LOW_FRICTION_RANGES) + ("custom",)),
        "mu": Param(0.5, "Coulomb friction coefficient when preset is custom", "1", 0.01, 1.5),
    },
    # ice's 0.1 at difficulty 1; past it (terrain.max_difficulty > 1) the ground stays ice: lower friction
    # stops being a surface a legged robot meets outdoors (wet ice, 0.05, is the ice preset's floor)
    difficulty=lambda d: {"preset": "custom", "mu": max(_lerp(1.0, 0.1, d), 0.1)},
)
def low_friction(shape, resolution, rng, heights, preset, mu):
    value = mu if preset == "custom" else rng.uniform(*LOW_FRICTION_RANGES[preset])
    return MaterialPatch(shape=shape, friction=float(value))


@atomic_terrain(
    "ice",
    "physical",
    "Frozen water: level ice filling the region up to a depth above its lowest ground, as slippery as ice. Lay it "
    "on a depression (river, pit, basin) as you would water; it raises the ground there to the ice's surface.",
    {"depth": Param(0.3, "height of the ice surface above the lowest ground of the region", "m", 0.0, 2.0)},
)
def ice(shape, resolution, rng, heights, depth):
    # the water's level turned solid; its friction is the ice preset's (LOW_FRICTION_RANGES)
    surface, frozen = _level(heights, depth)
    return MaterialPatch(shape=shape, ice_surface=np.where(frozen, surface, NO_WATER).astype(np.float32),
                         friction=float(rng.uniform(*LOW_FRICTION_RANGES["ice"])), mask=frozen)
