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
    soil_presets: names of the soil presets (``legged_gente.terrain.soil.SOIL_PRESETS`` keys, or
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

    def soil_index(self, name: str) -> int:
        """Index of soil preset ``name`` in ``soil_presets``, appending it the first time it is used."""
        if name not in self.soil_presets:
            if len(self.soil_presets) >= np.iinfo(np.int8).max:
                raise ValueError(f"too many distinct soil presets in one map (max {np.iinfo(np.int8).max}).")
            self.soil_presets.append(name)
        return self.soil_presets.index(name)

    def paint(self, patch: "MaterialPatch", i0: int, j0: int) -> None:
        """Apply ``patch`` to the window of cells starting at (i0, j0) with the patch's shape.

        Water is written where ``patch.water_surface`` is wet (flow fields with it); soil and friction where
        ``patch.mask`` is true (everywhere in the window if no mask). Properties the patch leaves ``None``
        keep their current values, so water painted over soil keeps the soil below it.
        """
        shape = patch.shape
        win = (slice(i0, i0 + shape[0]), slice(j0, j0 + shape[1]))
        if i0 < 0 or j0 < 0 or i0 + shape[0] > self.shape[0] or j0 + shape[1] > self.shape[1]:
            raise ValueError(f"patch of shape {shape} at ({i0}, {j0}) does not fit a map of shape {self.shape}.")
        if patch.water_surface is not None:
            wet = patch.water_surface > NO_WATER / 2
            self.water_surface[win][wet] = patch.water_surface[wet]
            for field, value in (
                ("flow_kind", patch.flow_kind),
                ("flow_speed", patch.flow_speed),
                ("flow_direction", patch.flow_direction),
                ("flow_omega", patch.flow_omega),
                ("flow_phase", patch.flow_phase),
            ):
                if value is not None:
                    getattr(self, field)[win][wet] = value
        mask = np.ones(shape, bool) if patch.mask is None else patch.mask
        if patch.soil is not None:
            self.soil[win][mask] = self.soil_index(patch.soil)
        if patch.friction is not None:
            self.friction[win][mask] = patch.friction

    def drain(self, window: tuple[slice, slice], cells: np.ndarray) -> None:
        """Make ``cells`` (bool, the window's shape) of ``window`` dry: no water surface, no flow."""
        self.water_surface[window][cells] = NO_WATER
        for field in ("flow_kind", "flow_speed", "flow_direction", "flow_omega", "flow_phase"):
            getattr(self, field)[window][cells] = 0

    def paste(self, other: "MaterialMap", i0: int, j0: int) -> None:
        """Copy every property of ``other`` into this map at cell offset (i0, j0), remapping soil indices."""
        win = (slice(i0, i0 + other.shape[0]), slice(j0, j0 + other.shape[1]))
        for field in ("water_surface", "flow_kind", "flow_speed", "flow_direction", "flow_omega", "flow_phase", "friction"):
            getattr(self, field)[win] = getattr(other, field)
        remap = np.array([self.soil_index(n) for n in other.soil_presets] + [NO_SOIL], np.int8)
        self.soil[win] = remap[other.soil]  # NO_SOIL == -1 picks the appended NO_SOIL


@dataclasses.dataclass
class MaterialPatch:
    """What a physical atomic terrain sets inside its region; ``None`` leaves a property unchanged.

    water_surface: (nx, ny) absolute z of the water surface (m), ``NO_WATER`` where the patch leaves a cell dry.
    flow_kind, flow_speed, flow_direction, flow_omega, flow_phase: the flow of that water (see MaterialMap).
    soil: name of a soil preset of ``legged_gente.terrain.soil.SOIL_PRESETS``.
    friction: Coulomb friction coefficient of the ground (1).
    mask: (nx, ny) bool, the cells soil and friction apply to (all cells of the region if None).
    ice_surface: (nx, ny) absolute z (m) up to which the patch raises the ground (frozen water), ``NO_WATER`` where
    it leaves a cell's height; water at or below it is frozen with it and soil under it is covered (the tile's
    builder applies all three).
    """

    shape: tuple[int, int]
    water_surface: np.ndarray | None = None
    flow_kind: int | None = None
    flow_speed: float | None = None
    flow_direction: float | None = None
    flow_omega: float | None = None
    flow_phase: float | None = None
    soil: str | None = None
    friction: float | None = None
    mask: np.ndarray | None = None
    ice_surface: np.ndarray | None = None
