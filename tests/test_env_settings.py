"""LeggedRobot's settings and terms: init_state, send_timeouts, heading mode, unlimited joints, set_const after
mass randomisation, feet air time state, the biped's sole clearance, run-time settings in device tensors and
the step's no-config-read rule, and a subclass adding a reward and an observation term."""

import math
from unittest.mock import patch

import pytest
import torch
import warp as wp

from legged_gente.envs.base.step_runner import StepRunner
from legged_gente.envs.base.terms import ObsTerm
from legged_gente.envs.gente_biped.gente_biped import GenteBiped
from legged_gente.envs.gente_biped.gente_biped_config import GenteBipedFlatCfg

N = 3


def cfg_of(cls=GenteBipedFlatCfg):
    cfg = cls()
    cfg.env.num_envs = N
    cfg.domain_rand.push_robots = False
    return cfg


def zeros(env):
    return torch.zeros(env.num_envs, env.num_actions)


@pytest.fixture(scope="module")
def env():
    torch.manual_seed(0)
    return GenteBiped(cfg_of(), device="cpu")


def test_init_state_is_honoured_and_its_randomisation_is_explicit():
    cfg = cfg_of()
    half = math.radians(30.0) / 2  # a 30 degree yaw
    cfg.init_state.rot = [math.cos(half), 0.0, 0.0, math.sin(half)]
    cfg.init_state.lin_vel = [0.3, -0.2, 0.1]
    cfg.init_state.ang_vel = [0.0, 0.1, 0.2]
    cfg.domain_rand.random_init_yaw = False
    cfg.domain_rand.init_lin_vel_xy_noise = 0.0
    env = GenteBiped(cfg, device="cpu")
    assert torch.allclose(env.sim.qpos[:, 3:7], torch.tensor(cfg.init_state.rot).expand(N, 4), atol=1e-6)
    assert torch.allclose(env.sim.qvel[:, 0:3], torch.tensor([0.3, -0.2, 0.1]).expand(N, 3))
    assert torch.allclose(env.sim.qvel[:, 3:6], torch.tensor([0.0, 0.1, 0.2]).expand(N, 3))
    # the randomisation on: yaw turned about world z (the tilt is kept), xy velocity within +-0.5 m/s
    cfg.init_state.rot = [math.cos(0.1), math.sin(0.1), 0.0, 0.0]  # 0.2 rad roll
    cfg.domain_rand.random_init_yaw = True
    cfg.domain_rand.init_lin_vel_xy_noise = 0.5
    env = GenteBiped(cfg, device="cpu")
    gravity_z = -math.cos(0.2)  # gravity's component on the base z axis under a 0.2 rad tilt
    assert torch.allclose(env.projected_gravity[:, 2], torch.full((N,), gravity_z), atol=1e-5)
    assert len({round(v, 4) for v in env.sim.qpos[:, 6].tolist()}) == N  # different yaws
    assert ((env.sim.qvel[:, 0:2] - torch.tensor([0.3, -0.2])).abs() <= 0.5).all()


def test_send_timeouts_decides_whether_the_runner_sees_time_outs():
    cfg = cfg_of()
    cfg.env.send_timeouts = False
    env = GenteBiped(cfg, device="cpu")
    _, _, _, extras = env.step(zeros(env))
    assert "time_outs" not in extras


def test_stand_still_commands_do_not_turn_in_heading_mode(env):
    from legged_gente.utils.torch_math import yaw_of

    env.commands[:, 3] = yaw_of(env.base_quat) + 1.0  # a heading 1 rad away
    env.standing_still[:] = torch.tensor([True, False, False])
    env._update_heading_commands()
    assert env.commands[0, 2] == 0.0
    assert env.commands[1, 2] == pytest.approx(env.cfg.commands.heading_stiffness * 1.0, abs=1e-5)


def test_resampled_stand_still_commands_are_flagged(env):
    env.set_param("commands.still_fraction", 1.0)
    try:
        env._resample_commands(torch.ones(N, dtype=torch.bool))
        assert env.standing_still.all() and (env.commands[:, :3] == 0).all()
    finally:
        env.set_param("commands.still_fraction", 0.1)


def test_unlimited_joints_have_no_limits(tmp_path):
    from legged_gente.sim.assembly import resolve_path

    source = resolve_path(GenteBipedFlatCfg.asset.file)
    text = source.read_text().replace('range="0 2.0"', 'range="0 2.0" limited="false"', 1)  # left knee: unlimited
    assert 'limited="false"' in text
    robot = tmp_path / "unlimited_knee.xml"  # the biped is primitive geoms only: no files to find beside it
    robot.write_text(text)
    cfg = cfg_of()
    cfg.asset.file = str(robot)
    env = GenteBiped(cfg, device="cpu")
    knee = env.layout.joint_names.index("left_knee")
    assert env.dof_limits[knee].tolist() == [-math.inf, math.inf]
    assert env.soft_dof_limits[knee].tolist() == [-math.inf, math.inf]
    env.sim.qpos[:, env.qpos_adr[knee]] = 3.0  # rad, beyond the other knee's 2.0 rad limit
    env._update_state()
    assert (env._reward_dof_pos_limits() == 0).all()
    env._reset_envs(torch.ones(N, dtype=torch.bool))
    assert torch.isfinite(env.sim.qpos).all()


def test_base_mass_randomisation_updates_the_derived_constants():
    cfg = cfg_of()
    cfg.domain_rand.randomize_base_mass = True
    cfg.domain_rand.added_mass_range = [1.0, 3.0]
    env = GenteBiped(cfg, device="cpu")
    total = float(env.mjm.body_mass.sum())  # kg, the nominal robot (the world body and terrain weigh nothing)
    subtree = wp.to_torch(env.sim.m.body_subtreemass)[:, env.root_body]
    # the root's subtree mass is the whole robot: nominal mass plus each world's added mass
    assert torch.allclose(subtree, total + env.added_base_mass[:, 0], atol=1e-4)
    # and the solver's inverse weights differ between worlds of different masses
    invweight = wp.to_torch(env.sim.m.body_invweight0)[:, env.base, 0]
    assert len({round(v, 6) for v in invweight.tolist()}) == N


def test_feet_air_time_is_kept_whatever_its_reward_scale():
    cfg = cfg_of()
    assert cfg.rewards.scales.feet_air_time == 0.0  # the biped does not use the reward
    cfg.init_state.pos = [0.0, 0.0, 1.5]  # m: the feet start half a metre in the air
    env = GenteBiped(cfg, device="cpu")
    for _ in range(3):
        env.step(zeros(env))
    # three policy steps of 4 x 5 ms in the air: 3 x 0.02 s
    assert torch.allclose(env.feet_air_time.air_time, torch.full((N, 2), 3 * 0.02), atol=1e-6)
    env._reset_envs(torch.tensor([True, False, False]))
    assert (env.feet_air_time.air_time[0] == 0).all() and (env.feet_air_time.air_time[1:] > 0).all()


def test_swing_height_is_measured_at_the_sole(env):
    """The sole spheres (radius 0.02 m) sit 0.05 m below the foot body's origin (gente_biped.xml): with the legs
    straight and the base upright, a sole's lowest point is 0.07 m below the foot origin."""
    qpos = env.sim.qpos
    qpos[:, 0:3] = torch.tensor([0.0, 0.0, 2.0])
    qpos[:, 3:7] = torch.tensor([1.0, 0.0, 0.0, 0.0])
    qpos[:, 7:] = 0.0
    env.sim.forward(torch.ones(N, dtype=torch.bool))
    env._update_state()
    foot_z = env.sim.xpos[:, env.feet, 2]
    assert torch.allclose(env.sole_clearance(), foot_z - 0.05 - 0.02, atol=1e-5)
    target = env.cfg.rewards.swing_height_target
    expected = ((foot_z - 0.07 - target) ** 2).sum(1)  # both feet in the air
    assert torch.allclose(env._reward_feet_swing_height(), expected, atol=1e-5)


def test_run_time_settings_live_in_device_tensors(env):
    """A legged_gym-style command curriculum: widen a command range during training."""
    env.set_param("commands.ranges.lin_vel_x", [2.0, 3.0])
    env.set_param("commands.still_fraction", 0.0)
    try:
        env._resample_commands(torch.ones(N, dtype=torch.bool))
        assert ((env.commands[:, 0] >= 2.0) & (env.commands[:, 0] <= 3.0)).all()
        assert env.cfg.commands.ranges.lin_vel_x == [2.0, 3.0]
    finally:
        env.set_param("commands.ranges.lin_vel_x", [-1.0, 1.0])
        env.set_param("commands.still_fraction", 0.1)
    alive, sigma = env.cfg.rewards.scales.alive, env.cfg.rewards.tracking_sigma
    env.set_param("rewards.scales.alive", 2.0)
    env.set_param("rewards.tracking_sigma", 0.5)
    try:
        i = [name for name, _ in env.reward_functions].index("alive")
        assert env.reward_scale_vec[i].item() == pytest.approx(2.0 * env.dt)
        assert env.params.rewards.tracking_sigma.item() == 0.5
    finally:  # the module's env is shared by the tests after this one
        env.set_param("rewards.scales.alive", alive)
        env.set_param("rewards.tracking_sigma", sigma)
    # the soft joint limits follow their setting: the left knee's 0..2 rad range shrunk to half is 0.5..1.5 rad,
    # so a knee at 1.7 rad (the other joints mid-range) is penalised 0.2
    knee = env.layout.joint_names.index("left_knee")
    env.set_param("rewards.soft_dof_pos_limit", 0.5)
    try:
        assert env.soft_dof_limits[knee].tolist() == pytest.approx([0.5, 1.5])
        env.sim.qpos[:, env.qpos_adr] = env.dof_mid
        env.sim.qpos[:, env.qpos_adr[knee]] = 1.7
        env._update_state()
        assert env._reward_dof_pos_limits() == pytest.approx(torch.full((N,), 0.2), abs=1e-5)
    finally:
        env.set_param("rewards.soft_dof_pos_limit", 0.9)
    with pytest.raises(ValueError, match="not a reward term of this env"):
        env.set_param("rewards.scales.feet_air_time", 1.0)
    with pytest.raises(ValueError, match="not a setting the step reads"):
        env.set_param("commands.resampling_time", 3.0)


def test_a_config_read_inside_the_step_is_an_error():
    """What the compiled step and the CUDA graph would freeze: the first step fails, on the CPU too."""

    class ReadsConfig(GenteBiped):
        def _reward_alive(self):
            return torch.ones(self.num_envs) * self.cfg.rewards.tracking_sigma

    env = ReadsConfig(cfg_of(), device="cpu")
    with pytest.raises(ValueError, match=r"reads \['cfg.rewards.tracking_sigma'\].*env.set_param"):
        env.step(zeros(env))


class Heading(GenteBiped):
    """A subclass as docs/new_robot.md shows it: a reward term and an observation term, plain torch."""

    def _reward_upright_heading(self):
        return torch.exp(-torch.square(self.base_quat[:, 3]) / self.params.rewards.heading_sigma)

    def _obs_base_height(self):
        return self.base_pos[:, 2:3] - self._ground_height(self.base_pos[:, :2])[:, None]


class HeadingCfg(GenteBipedFlatCfg):
    class observations(GenteBipedFlatCfg.observations):
        class policy(GenteBipedFlatCfg.observations.policy):
            base_height = ObsTerm(fn="base_height", scale=2.0, noise=0.01)

    class rewards(GenteBipedFlatCfg.rewards):
        heading_sigma = 0.1

        class scales(GenteBipedFlatCfg.rewards.scales):
            upright_heading = 0.5


def rollout(compiled: bool):
    torch.manual_seed(0)
    env = Heading(cfg_of(HeadingCfg), device="cpu")
    if compiled:
        env._runner = StepRunner(env, compile=True)
    generator = torch.Generator().manual_seed(1)
    out = []
    with torch.inference_mode():
        for _ in range(4):
            obs, rew, done, _ = env.step(torch.rand(N, env.num_actions, generator=generator) * 2 - 1)
            out.append((obs["policy"], obs["critic"], rew, done))
    return env, out


def test_a_subclass_adds_a_reward_and_an_observation_term():
    env, out = rollout(compiled=False)
    assert "upright_heading" in env.reward_scales
    assert env.observation_names["policy"][-1] == "base_height"
    assert env.observation_names["policy"][-3:-1] == ["gait_clock[0]", "gait_clock[1]"]
    obs = out[-1][0]
    assert obs.shape == (N, 45)
    height = env.base_pos[:, 2] - env._ground_height(env.base_pos[:, :2])
    assert torch.allclose(obs[:, -1], 2.0 * height, atol=2.0 * 0.01 + 1e-5)  # within the term's noise
    assert torch.isfinite(out[-1][2]).all()


def test_the_subclass_compiles_to_the_same_numbers():
    """The same subclass under the compiled step (cfg.sim.torch_compile's torch.compile, here on the CPU with
    eager random numbers): the same observations, rewards and resets."""
    import torch._inductor.config as inductor_config

    with patch.object(inductor_config, "fallback_random", True):
        (_, eager), (_, compiled) = rollout(False), rollout(True)
    for (p, c, r, d), (pc, cc, rc, dc) in zip(eager, compiled):
        assert torch.allclose(p, pc, atol=1e-4) and torch.allclose(c, cc, atol=1e-4)
        assert torch.allclose(r, rc, atol=1e-6) and torch.equal(d, dc)


def test_step_graph_keeps_rebound_state_in_its_tensors():
    """What StepGraph records at the end of a capture (the copy itself runs on the CPU too): a tensor attribute the
    step rebinds is copied back into the tensor it held before, so a replay reads this step's value next step."""
    from types import SimpleNamespace

    from legged_gente.utils.cuda_graph import StepGraph, rebound_attributes

    owner = SimpleNamespace(carried=torch.zeros(3), untouched=torch.ones(2), name="x")
    carried, before = owner.carried, dict(vars(owner))
    owner.carried = owner.carried + 1.0  # rebound, as plain torch code does
    graph = StepGraph.__new__(StepGraph)
    graph.owner = owner
    kept = graph._copy_back(rebound_attributes(owner, before), before)
    assert kept == {"carried": carried} and torch.equal(carried, torch.ones(3))
    owner.carried = torch.zeros(4)  # a shape change cannot be replayed
    with pytest.raises(RuntimeError, match=r"carried changes from \(3,\)"):
        graph._copy_back(rebound_attributes(owner, before), before)


def test_step_graph_binds_captured_attributes_back_after_every_replay():
    """Code run eagerly between replays (a reset, refreshed observations) may rebind a captured attribute; the
    next replay writes the captured tensor, so the attribute must point at it again afterwards."""
    from types import SimpleNamespace

    from legged_gente.utils.cuda_graph import StepGraph, rebound_attributes

    owner = SimpleNamespace(carried=torch.zeros(3), name="x")
    captured, before = owner.carried, dict(vars(owner))
    owner.carried, owner.name = owner.carried + 1.0, "y"  # what the captured body does
    graph = StepGraph.__new__(StepGraph)
    graph.owner = owner
    rebound = rebound_attributes(owner, before)
    graph._bind(rebound, graph._copy_back(rebound, before))
    graph.graph = SimpleNamespace(replay=lambda: captured.add_(1.0))  # a replay writes the captured tensor
    owner.carried = torch.full((3,), 7.0)  # an eager reset between replays rebinds it
    graph()
    assert owner.carried is captured and torch.equal(owner.carried, torch.full((3,), 2.0)) and owner.name == "y"


def test_observation_terms_are_per_config_instance():
    from legged_gente.utils.args import apply_overrides
    from legged_gente.envs.gente_biped.gente_biped_config import GenteBipedFlatCfgPPO

    cfg = cfg_of()
    apply_overrides(["observations.policy.dof_vel.scale=0.1"], cfg, GenteBipedFlatCfgPPO())
    assert cfg.observations.policy.dof_vel.scale == 0.1
    assert GenteBipedFlatCfg().observations.policy.dof_vel.scale == 0.05  # the class's table is unchanged
