"""The biped's task: a gait clock in the observations and biped gait rewards on top of LeggedRobot."""

from __future__ import annotations

import math

import mujoco
import torch

from legged_gente.envs.base.legged_robot import LeggedRobot
from legged_gente.external_forces.field import geom_body_box
from legged_gente.sim.assembly import match_names


class GenteBiped(LeggedRobot):
    param_rules = {**LeggedRobot.param_rules,
                   "rewards.gait_period": (lambda v: v > 0, "a period > 0 s"),  # the gait clock divides by it
                   "rewards.stance_fraction": (lambda v: 0 <= v <= 1, "a fraction of the period, in [0, 1]")}

    def _init_buffers(self) -> None:
        super()._init_buffers()
        # the sole geoms of each foot (cfg.asset.sole_geoms), (num_feet, soles per foot), and their depths
        geoms = [self.mjm.geom(i).name for i in range(self.mjm.ngeom)]
        soles = [self.mjm.geom(name).id for name in match_names(self.cfg.asset.sole_geoms, geoms, "cfg.asset.sole_geoms", "geom")]
        off_feet = [geoms[g] for g in soles if self.mjm.geom_bodyid[g] not in self.layout.foot_bodies]
        if off_feet:
            raise ValueError(f"cfg.asset.sole_geoms={self.cfg.asset.sole_geoms} matches {off_feet}, not on a foot "
                             f"({self.cfg.asset.foot_bodies}); name only geoms of the feet.")
        per_foot = [[g for g in soles if self.mjm.geom_bodyid[g] == foot] for foot in self.layout.foot_bodies]
        if any(len(f) != len(per_foot[0]) or not f for f in per_foot):
            raise ValueError(f"cfg.asset.sole_geoms={self.cfg.asset.sole_geoms} gives {[len(f) for f in per_foot]} "
                             f"geoms on the feet {self.cfg.asset.foot_bodies}; name the same number (>= 1) on each.")
        self.sole_geoms = torch.tensor(per_foot, dtype=torch.long, device=self.device)
        depth = [[self._sole_depth(g) for g in foot] for foot in per_foot]
        self.sole_depth = torch.tensor(depth, dtype=torch.float32, device=self.device)

    def _sole_depth(self, geom: int) -> float:
        """How far a sole geom reaches below its centre while its foot is level (exact for a sphere at any tilt)."""
        kind = int(self.mjm.geom_type[geom])
        if kind not in (mujoco.mjtGeom.mjGEOM_SPHERE.value, mujoco.mjtGeom.mjGEOM_CAPSULE.value,
                        mujoco.mjtGeom.mjGEOM_BOX.value):
            shape = mujoco.mjtGeom(kind).name[len("mjGEOM_"):].lower()
            raise ValueError(f"cfg.asset.sole_geoms: {self.mjm.geom(geom).name} is of type {shape}; soles must be "
                             f"sphere, capsule or box geoms")
        centre, half = geom_body_box(self.mjm, geom)  # in the foot's frame: its z is the vertical of a level foot
        return float(self.mjm.geom_pos[geom, 2] - (centre[2] - half[2]))

    def _gait_phase(self) -> torch.Tensor:
        """Per-foot phase in [0, 1): the feet evenly spaced over the period."""
        t = self.episode_length_buf.float() * self.dt
        phase = torch.remainder(t / self.params.rewards.gait_period, 1.0)
        num_feet = self.feet.shape[0]
        offsets = torch.arange(num_feet, device=self.device) / num_feet
        return torch.remainder(phase[:, None] + offsets[None], 1.0)

    def sole_clearance(self) -> torch.Tensor:
        """(num_envs, num_feet) height of each foot's lowest sole point above the ground under it (m)."""
        pos = self.sim.geom_xpos[:, self.sole_geoms]  # (n, feet, soles, 3)
        height = pos[..., 2] - self.sole_depth - self._ground_height(pos[..., :2])
        return height.amin(dim=-1)

    def _obs_gait_clock(self):
        phase = self._gait_phase()[:, 0]
        return torch.stack([torch.sin(2 * math.pi * phase), torch.cos(2 * math.pi * phase)], dim=1)

    def _reward_alive(self):
        return torch.ones(self.num_envs, device=self.device)

    def _reward_gait_contact(self):
        """Each foot on the ground in its stance phase and in the air in its swing phase."""
        stance = self._gait_phase() < self.params.rewards.stance_fraction
        return torch.sum(~(self.foot_contacts() ^ stance), dim=1).float()

    def _reward_feet_swing_height(self):
        """Squared error of the sole's clearance from the target, for feet in swing."""
        swing = ~self.foot_contacts()
        error = self.sole_clearance() - self.params.rewards.swing_height_target
        return torch.sum(torch.square(error) * swing, dim=1)

    def _reward_hip_deviation(self):
        return torch.sum(torch.square(self.dof_pos[:, self.hip_ids] - self.default_dof_pos[:, self.hip_ids]), dim=1)

    def _reward_no_fly(self):
        """At least one foot on the ground: a walk, not a hop."""
        return self.foot_contacts().any(dim=1).float()

    def _reward_feet_slip(self):
        """Horizontal speed of feet that are on the ground."""
        speed = torch.norm(self._body_linear_velocity(self.feet)[..., :2], dim=-1)
        return torch.sum(torch.square(speed) * self.foot_contacts(), dim=1)
