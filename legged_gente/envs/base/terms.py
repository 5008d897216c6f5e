"""Observation terms: declared once, in nested config classes, one table per observation group.

``ObsTerm(fn="base_ang_vel", scale=0.25, noise=0.2)`` in ``cfg.observations.policy`` makes the env call its
method ``_obs_base_ang_vel()`` (a ``(num_envs, k)`` tensor) every step; the env builds the observation vector,
its noise vector and the observation names from the same table, so noise cannot drift out of step with the term
it belongs to. Terms keep their class order (a subclass's new terms come after its parent's; set a term to
``None`` to drop it).
"""

from __future__ import annotations

import inspect
from dataclasses import dataclass

WHEN = (None, "heightfield", "forces")  # the conditions a term may depend on
NEEDS = {"heightfield": "a heightfield terrain (a plane has no height scan)",
         "forces": "the terrain force fields (a heightfield terrain, and forces.foot_geom_names or leg_geom_names)"}
"""What a conditional term needs, for the errors that name a term an env leaves out."""


@dataclass
class ObsTerm:
    """One observation term.

    fn: the env method ``_obs_<fn>`` that returns the term, ``(num_envs, k)``.
    scale: multiplies the term (a number, or one per column).
    noise: half-width of the uniform noise added to the policy's copy, in the term's own units (it is scaled
        with the term and by ``cfg.noise.noise_level``, as legged_gym's noise scales are); the critic's copy is
        noise-free.
    clip: (low, high) applied to the term before scaling, or None.
    when: None (always), "heightfield" (only where the env has a height scan), "forces" (only where the env
        has terrain force fields' observations).

    Each config instance holds its own copies (``--set observations.policy.dof_vel.scale=0.1`` changes one run).
    """

    fn: str
    scale: float | tuple[float, ...] = 1.0
    noise: float = 0.0
    clip: tuple[float, float] | None = None
    when: str | None = None


def obs_terms(group: object, path: str) -> list[tuple[str, ObsTerm]]:
    """The ``(name, ObsTerm)`` entries of a config group instance, in declaration order (parents first)."""
    names: list[str] = []
    for cls in reversed(type(group).__mro__):
        names += [n for n in vars(cls) if not n.startswith("_") and n not in names]
    names += [n for n in vars(group) if not n.startswith("_") and n not in names]
    terms = []
    for name in names:
        value = getattr(group, name)
        if value is None or inspect.isroutine(value):
            continue
        if not isinstance(value, ObsTerm):
            raise ValueError(f"{path}.{name} = {value!r} is not an ObsTerm; write {name} = ObsTerm(fn=...) "
                             f"or None to drop it.")
        if value.when not in WHEN:
            raise ValueError(f"{path}.{name}.when = {value.when!r}; use one of {list(WHEN)}.")
        terms.append((name, value))
    return terms
