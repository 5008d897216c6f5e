"""Bad settings of LeggedRobot are refused with the fix, at construction and at run time (set_param), instead of
being run as something else: a reversed command range, a randomised base mass that is not positive, a friction
range that is not one, an observation term whose scale does not fit its columns."""

import re

import pytest
import torch

from legged_gente.envs.base.terms import ObsTerm
from legged_gente.envs.gente_biped.gente_biped import GenteBiped
from legged_gente.envs.gente_biped.gente_biped_config import GenteBipedFlatCfg

N = 2


def cfg_of():
    cfg = GenteBipedFlatCfg()
    cfg.env.num_envs = N
    cfg.domain_rand.push_robots = False
    return cfg


@pytest.fixture(scope="module")
def env():
    return GenteBiped(cfg_of(), device="cpu")


def test_set_param_refuses_a_reversed_command_range_as_the_config_does(env):
    """cfg.commands.ranges.ang_vel_yaw = [1, -1] is refused at construction; set at run time it used to be taken,
    and the heading controller's clamp(yaw_rate, 1, -1) then commands -1 rad/s whatever the heading error."""
    with pytest.raises(ValueError, match=r"commands.ranges.ang_vel_yaw=\[1.0, -1.0\]; use \[low, high\], low <= high"):
        env.set_param("commands.ranges.ang_vel_yaw", [1.0, -1.0])
    assert env.params.commands.ang_vel_yaw.tolist() == [-1.0, 1.0]  # unchanged
    assert env.cfg.commands.ranges.ang_vel_yaw == [-1.0, 1.0]
    env.set_param("commands.ranges.ang_vel_yaw", [-0.5, 0.5])  # a valid range is taken
    try:
        assert env.params.commands.ang_vel_yaw.tolist() == [-0.5, 0.5]
    finally:
        env.set_param("commands.ranges.ang_vel_yaw", [-1.0, 1.0])


def test_a_randomised_base_mass_must_stay_positive():
    """A base of m0 kg with added_mass_range [-m0 - 1, ...] would get a negative mass: every world then diverges
    at every step (counted, reset, never trained)."""
    cfg = cfg_of()
    env = GenteBiped(cfg, device="cpu")
    mass0 = float(env.mjm.body_mass[env.base])
    cfg.domain_rand.randomize_base_mass = True
    cfg.domain_rand.added_mass_range = [-mass0 - 1.0, 1.0]
    with pytest.raises(ValueError, match=r"added_mass_range=.*base mass .* kg.*low > -"):
        GenteBiped(cfg, device="cpu")


@pytest.mark.parametrize("field, value", [("friction_range", [1.0, 0.5]), ("friction_range", [-0.2, 0.5]),
                                          ("added_mass_range", [2.0, 1.0])])
def test_randomisation_ranges_are_low_high_pairs(field, value):
    cfg = cfg_of()
    cfg.domain_rand.randomize_friction = field == "friction_range"
    cfg.domain_rand.randomize_base_mass = field == "added_mass_range"
    setattr(cfg.domain_rand, field, value)
    with pytest.raises(ValueError, match=rf"cfg.domain_rand.{field}=.*; use \[low, high\]"):
        GenteBiped(cfg, device="cpu")


def test_an_observation_scale_that_does_not_fit_its_term_names_the_term():
    cfg = cfg_of()
    cfg.observations.policy.commands = ObsTerm(fn="commands", scale=(2.0, 2.0))  # the term has 3 columns
    with pytest.raises(ValueError, match=r"cfg.observations.policy.commands.scale has 2 values; the term has 3 "
                                         r"columns"):
        GenteBiped(cfg, device="cpu")


@pytest.mark.parametrize("value, shape", [(lambda self: self.base_pos[:, 2], "(2,)"),
                                          (lambda self: self.base_pos[:1, 2:], "(1, 1)")])
def test_an_observation_term_of_the_wrong_shape_names_the_term(value, shape):
    """A new robot's term returning one value per robot without its column, or the wrong rows: named, with the
    shape it must have (it was an IndexError or a size mismatch deep in torch)."""
    class Heights(GenteBiped):
        def _obs_base_height(self):
            return value(self)

    cfg = cfg_of()
    cfg.observations.policy.base_height = ObsTerm(fn="base_height")
    with pytest.raises(ValueError, match=rf"^cfg.observations.policy.base_height: _obs_base_height returned shape "
                                         rf"{re.escape(shape)}; an observation term returns \(num_envs, k\) = \(2, k\)"):
        Heights(cfg, device="cpu")


@pytest.mark.parametrize("value, shape", [(lambda self: self.base_pos[:, 2:], "(2, 1)"),
                                          (lambda self: torch.tensor(1.0), "()")])
def test_a_reward_term_of_the_wrong_shape_names_the_term(value, shape):
    class Rewarded(GenteBiped):
        def _reward_height(self):
            return value(self)

    cfg = cfg_of()
    cfg.rewards.scales.height = 1.0
    env = Rewarded(cfg, device="cpu")
    with pytest.raises(ValueError, match=rf"^_reward_height returned shape {re.escape(shape)}; a reward term returns one value "
                                         rf"per robot, shape \(2,\)"):
        env.step(torch.zeros(N, env.num_actions))


@pytest.mark.parametrize("section, field", [("commands", "resampling_time"), ("domain_rand", "push_interval_s")])
def test_an_interval_under_half_a_policy_step_is_refused_not_rounded_up(section, field):
    """The biped's policy step is 0.005 s x 4 = 0.02 s; 0.005 s would round to no step at all (once made every step)."""
    cfg = cfg_of()
    cfg.domain_rand.push_robots = True
    setattr(getattr(cfg, section), field, 0.005)
    with pytest.raises(ValueError, match=rf"cfg.{section}.{field}=0.005 s is under half a policy step \(0.02 s\)"):
        GenteBiped(cfg, device="cpu")


@pytest.mark.parametrize("field, value", [("soft_dof_pos_limit", 0.0), ("soft_dof_pos_limit", 1.5),
                                          ("soft_dof_pos_limit", float("nan")), ("soft_torque_limit", 0.0),
                                          ("soft_torque_limit", -1.0)])
def test_soft_limits_are_shares_of_the_hard_ones(field, value):
    """A soft limit of 0 made the limit terms penalise everything, and with an unlimited joint or actuator 0 * inf
    = NaN, which the total then dropped for that world; above 1 the joint range grew past the model's."""
    cfg = cfg_of()
    setattr(cfg.rewards, field, value)
    with pytest.raises(ValueError, match=rf"cfg.rewards.{field}={value}; use a share of the hard limit"):
        GenteBiped(cfg, device="cpu")


def test_set_param_refuses_a_soft_limit_outside_its_share(env):
    with pytest.raises(ValueError, match=r"rewards.soft_torque_limit=0.0; use a share of the hard limit, in \(0, 1\]"):
        env.set_param("rewards.soft_torque_limit", 0.0)
    env.set_param("rewards.soft_torque_limit", 0.8)
    assert float(env.params.rewards.soft_torque_limit) == pytest.approx(0.8)
    env.set_param("rewards.soft_torque_limit", 1.0)


@pytest.mark.parametrize("field, value", [("clip_actions", 0.0), ("clip_actions", -1.0),
                                          ("clip_observations", 0.0), ("clip_observations", float("nan"))])
def test_clip_limits_are_positive(field, value):
    """A negative clip_actions crossed the clamp's bounds (every action became one constant); 0 zeroed them all."""
    cfg = cfg_of()
    setattr(cfg.normalization, field, value)
    with pytest.raises(ValueError, match=rf"cfg.normalization.{field}={value}; use a positive bound"):
        GenteBiped(cfg, device="cpu")
