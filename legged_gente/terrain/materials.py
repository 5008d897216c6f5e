"""Per-cell physical properties of a terrain: water, soil and ground friction.

A :class:`MaterialMap` is aligned cell-for-cell with a heightfield (same shape, same resolution, same
origin). It is what the force kernels in ``legged_gente.external_forces`` read: one robot can stand with
one foot in water and the other on sand, because every property is looked up at each body's position.
"""

from __future__ import annotations

import dataclasses

import numpy as np

NO_WATER = np.float32(-1.0e9)
"""``water_surface`` value of a dry cell: far below any ground, so every submerged length is zero."""

FLOW_STILL, FLOW_CURRENT, FLOW_TIDE = 0, 1, 2
FLOW_KINDS = {"still": FLOW_STILL, "current": FLOW_CURRENT, "tide": FLOW_TIDE}

NO_SOIL = -1
"""``soil`` value of a cell without deformable soil (rigid ground)."""


@dataclasses.dataclass
class MaterialMap:
    """Arrays of shape ``(nx, ny)``, one value per heightfield cell.

    water_surface: absolute z of the water surface (m); ``NO_WATER`` where dry. Water may lie over soil.
    flow_kind: FLOW_STILL / FLOW_CURRENT / FLOW_TIDE (int8).
    flow_speed: amplitude of the flow velocity (m/s).
    flow_direction: direction of the flow in the xy plane (rad, from +x towards +y).
    flow_omega: angular frequency of a tide (rad/s).
    flow_phase: phase of a tide (rad).
    soil: index into ``soil_presets`` (int8), ``NO_SOIL`` for rigid ground.
    soil_presets: names of the soil presets (``legged_gente.external_forces.soil.SOIL_PRESETS`` keys, or
        custom names registered there) that ``soil`` indexes.
    friction: Coulomb friction coefficient of the ground surface (1).
    """

    water_surface: np.ndarray
    flow_kind: np.ndarray
    flow_speed: np.ndarray
    flow_direction: np.ndarray
    flow_omega: np.ndarray
    flow_phase: np.ndarray
    soil: np.ndarray
    friction: np.ndarray
    soil_presets: list[str] = dataclasses.field(default_factory=list)

    @classmethod
    def rigid(cls, shape: tuple[int, int], friction: float = 1.0) -> "MaterialMap":
        """A dry, rigid map of uniform ``friction``: the default ("none") material everywhere."""
        zeros = np.zeros(shape, np.float32)
        return cls(
            water_surface=np.full(shape, NO_WATER, np.float32),
            flow_kind=np.zeros(shape, np.int8),
            flow_speed=zeros.copy(),
            flow_direction=zeros.copy(),
            flow_omega=zeros.copy(),
            flow_phase=zeros.copy(),
            soil=np.full(shape, NO_SOIL, np.int8),
            friction=np.full(shape, friction, np.float32),
        )

    @property
    def shape(self) -> tuple[int, int]:
        return self.water_surface.shape

    def has_water(self) -> np.ndarray:
        return self.water_surface > NO_WATER / 2

    def has_soil(self) -> np.ndarray:
        return self.soil != NO_SOIL
