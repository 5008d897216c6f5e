"""The biped's task: a gait clock in the observations and biped gait rewards on top of LeggedRobot."""

from __future__ import annotations

import math

import torch

from legged_gente.envs.base.legged_robot import LeggedRobot


class GenteBiped(LeggedRobot):
    def _gait_phase(self) -> torch.Tensor:
        """Per-foot phase in [0, 1): the two feet half a period apart."""
        t = self.episode_length_buf.float() * self.dt
        phase = torch.remainder(t / self.cfg.rewards.gait_period, 1.0)
        num_feet = self.feet.shape[0]
        offsets = torch.arange(num_feet, device=self.device) / num_feet
        return torch.remainder(phase[:, None] + offsets[None], 1.0)

    def _task_observations(self) -> torch.Tensor:
        phase = self._gait_phase()[:, 0]
        return torch.stack([torch.sin(2 * math.pi * phase), torch.cos(2 * math.pi * phase)], dim=1)

    def _reward_alive(self):
        return torch.ones(self.num_envs, device=self.device)

    def _reward_gait_contact(self):
        """Each foot on the ground in its stance phase and in the air in its swing phase."""
        stance = self._gait_phase() < self.cfg.rewards.stance_fraction
        return torch.sum(~(self.foot_contacts() ^ stance), dim=1).float()

    def _reward_feet_swing_height(self):
        clearance = self.feet_pos[..., 2] - self._ground_height(self.feet_pos[..., :2])
        swing = ~self.foot_contacts()
        return torch.sum(torch.square(clearance - self.cfg.rewards.swing_height_target) * swing, dim=1)

    def _reward_hip_deviation(self):
        return torch.sum(torch.square(self.dof_pos[:, self.hip_ids] - self.default_dof_pos[:, self.hip_ids]), dim=1)

    def _reward_no_fly(self):
        """At least one foot on the ground: a walk, not a hop."""
        return self.foot_contacts().any(dim=1).float()

    def _reward_feet_slip(self):
        """Horizontal speed of feet that are on the ground."""
        speed = torch.norm(self._body_linear_velocity(self.feet)[..., :2], dim=-1)
        return torch.sum(torch.square(speed) * self.foot_contacts(), dim=1)
