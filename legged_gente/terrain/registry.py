"""The one place atomic terrains are declared.

Every atomic terrain is a plain function registered with :func:`atomic_terrain`. Its parameters, their SI
units, ranges and docs live here, on the function's registration, and nowhere else: the curriculum, the
LLM tool schemas, the offline planner's vocabulary and the validator all read :data:`ATOMIC_TERRAINS`.
Rules that tie several parameters together (``min_radius <= max_radius``) are declared on the registration
too, as ``rules``; :meth:`AtomicTerrain.check_params` applies them, and both the validator and the tile
builder call it, so a call the validator accepts is one the builder can build.

Two kinds exist:

* ``"geometric"``: ``fn(shape, resolution, rng, **params) -> np.ndarray`` returns float32 heights in
  metres of ``shape == (nx, ny)`` cells of ``resolution`` metres (x along axis 0).
* ``"physical"``: ``fn(shape, resolution, rng, heights, **params) -> MaterialPatch`` returns the material
  properties for the region (water, soil, friction) given the region's current heights (and ice, which raises
  them to its surface).
"""

from __future__ import annotations

import dataclasses
import inspect
from typing import Any, Callable, Literal, Mapping

import numpy as np


@dataclasses.dataclass(frozen=True)
class Param:
    """One keyword parameter of an atomic terrain.

    ``low``/``high`` bound numeric values (inclusive); ``choices`` lists the allowed strings for a categorical
    parameter. ``unit`` is an SI unit string ("m", "rad", "m/s", "1" for dimensionless, "" for categorical).
    """

    default: Any
    doc: str
    unit: str = ""
    low: float | None = None
    high: float | None = None
    choices: tuple[str, ...] | None = None
    integer: bool = False
    registered: Mapping[str, Any] | None = dataclasses.field(default=None, compare=False, repr=False)
    """Where choices that name things registered at run time are kept (the soil presets): a choice must be there
    before it can be used, and any name registered there is a choice too. :meth:`offered` lists those usable now;
    the terrain's ``rules`` refuse a listed choice not registered yet, saying how to register it."""

    def offered(self) -> list[str]:
        """The choices usable now, in order: all of ``choices``, or those ``registered`` holds, then the names
        registered beyond them."""
        if self.registered is None:
            return list(self.choices)
        return [c for c in self.choices if c in self.registered] + [c for c in self.registered if c not in self.choices]

    def check(self, name: str, value: Any, terrain: str) -> Any:
        """Return ``value`` if valid, else raise ValueError naming the terrain, the parameter and the fix."""
        if self.choices is not None:
            if value not in self.choices and not (self.registered is not None and value in self.registered):
                more = "" if self.registered is None else f" ({self.doc})"  # the doc says how to register one
                raise ValueError(f"{terrain}: {name}={value!r} is not one of {self.offered()}; pick one of "
                                 f"those{more}.")
            return value
        if isinstance(value, bool) or not isinstance(value, (int, float, np.integer, np.floating)):
            raise ValueError(f"{terrain}: {name} must be a number ({self.unit}), got {type(value).__name__} {value!r}.")
        # Finite and in range before the whole-number test: int() of inf or nan, float() of a huge int, raise.
        if not isinstance(value, (int, np.integer)) and not np.isfinite(value):
            raise ValueError(f"{terrain}: {name}={value!r} is not a finite number; choose a value in "
                             f"[{self.low}, {self.high}] {self.unit}.")
        if (self.low is not None and value < self.low) or (self.high is not None and value > self.high):
            raise ValueError(
                f"{terrain}: {name}={value!r} {self.unit} is outside [{self.low}, {self.high}] {self.unit}; "
                f"choose a value in that range."
            )
        if self.integer and float(value) != int(value):
            raise ValueError(f"{terrain}: {name} must be a whole number, got {value!r}.")
        return int(value) if self.integer else float(value)


@dataclasses.dataclass(frozen=True)
class AtomicTerrain:
    """A registered atomic terrain: its function, kind, one-line description, parameters and curriculum map."""

    name: str
    kind: Literal["geometric", "physical"]
    description: str
    params: dict[str, Param]
    fn: Callable[..., Any]
    difficulty: Callable[[float], dict[str, Any]] | None = None
    bounds: Callable[[dict[str, Any], float, float], tuple[float, float]] | None = None
    rules: Callable[[dict[str, Any]], None] | None = None
    """Cross-field rules: ``rules(params)`` raises ValueError (naming the terrain and the fix) or returns None."""

    def height_bounds(self, params: dict[str, Any], size_x: float, size_y: float) -> tuple[float, float]:
        """Declared (min, max) height in metres of this terrain on a ``size_x`` x ``size_y`` m region.

        ``params`` must be complete (the output of :meth:`check_params`). Physical terrains declare none (ice
        fills a depression up to its depth above the region's lowest ground).
        """
        if self.bounds is None:
            return (0.0, 0.0)
        return self.bounds(params, size_x, size_y)

    def check_params(self, params: dict[str, Any]) -> dict[str, Any]:
        """Validate ``params`` (unknown or out-of-range keys, broken cross-field rules raise) and fill defaults."""
        unknown = sorted(set(params) - set(self.params))
        if unknown:
            raise ValueError(
                f"{self.name}: unknown parameter(s) {[str(k)[:40] for k in unknown[:10]]}; "
                f"valid parameters are {sorted(self.params)}."
            )
        checked = {k: p.check(k, params.get(k, p.default), self.name) for k, p in self.params.items()}
        if self.rules is not None:
            self.rules(checked)
        return checked

    def params_for_difficulty(self, difficulty: float, fixed: dict[str, Any] | None = None) -> dict[str, Any]:
        """Parameters for a curriculum difficulty (defaults where the terrain has no mapping; ``fixed`` params
        replace the mapped ones).

        0 is the easiest level and 1 the standard top level; up to ``MAX_DIFFICULTY`` the maps go on past it
        (``terrain.max_difficulty``), and a parameter pushed out of its declared range raises, naming it."""
        if not 0.0 <= difficulty <= MAX_DIFFICULTY:
            raise ValueError(f"difficulty must be in [0, {MAX_DIFFICULTY}], got {difficulty}.")
        mapped = self.difficulty(difficulty) if self.difficulty is not None else {}
        # a map that lands on a bound must pass it: 0.4 * 1.75 is 0.7000000000000001 in binary floating point
        mapped = {k: round(v, 12) if isinstance(v, float) else v for k, v in mapped.items()}
        try:
            return self.check_params({**mapped, **(fixed or {})})
        except ValueError as error:
            raise ValueError(f"at curriculum difficulty {difficulty:.3g}: {error} Lower terrain.max_difficulty, or "
                             f"fix the parameter in terrain_types ('{self.name}:<param>=<value>').") from None


ATOMIC_TERRAINS: dict[str, AtomicTerrain] = {}

MAX_DIFFICULTY = 2.0
"""Largest curriculum difficulty: twice the standard top level, where most linear maps are still physical."""


def atomic_terrain(
    name: str,
    kind: Literal["geometric", "physical"],
    description: str,
    params: dict[str, Param],
    difficulty: Callable[[float], dict[str, Any]] | None = None,
    bounds: Callable[[dict[str, Any], float, float], tuple[float, float]] | None = None,
    rules: Callable[[dict[str, Any]], None] | None = None,
) -> Callable[[Callable[..., Any]], Callable[..., Any]]:
    """Register ``fn`` as the atomic terrain ``name``; the function's keyword arguments must equal ``params``.

    ``bounds(params, size_x, size_y) -> (min, max)`` declares the heights (m) a geometric terrain can produce.
    ``rules(params)`` checks the rules between parameters (raises ValueError); see :func:`min_le_max`.
    """

    def register(fn: Callable[..., Any]) -> Callable[..., Any]:
        fixed = ("shape", "resolution", "rng") + (("heights",) if kind == "physical" else ())
        sig = [p for p in inspect.signature(fn).parameters if p not in fixed]
        if set(sig) != set(params):
            raise TypeError(f"atomic terrain {name!r}: function keywords {sig} differ from declared params {list(params)}")
        if name in ATOMIC_TERRAINS:
            raise ValueError(f"atomic terrain {name!r} is registered twice")
        ATOMIC_TERRAINS[name] = AtomicTerrain(name, kind, description, dict(params), fn, difficulty, bounds, rules)
        return fn

    return register


def min_le_max(terrain: str, low: str, high: str) -> Callable[[dict[str, Any]], None]:
    """A ``rules`` check that parameter ``low`` does not exceed parameter ``high``."""

    def rule(params: dict[str, Any]) -> None:
        if params[low] > params[high]:
            raise ValueError(f"{terrain}: {low}={params[low]!r} must not exceed {high}={params[high]!r}; swap or change them.")

    return rule
