"""The env on a heightfield: MuJoCo's hfield equals the numpy heights, curriculum levels move, forces act."""

from unittest.mock import patch

import mujoco
import mujoco_warp as mjw
import numpy as np
import pytest
import torch
import warp as wp

from legged_gente.envs.base.step_runner import StepRunner
from legged_gente.envs.gente_biped.gente_biped import GenteBiped
from legged_gente.envs.gente_biped.gente_biped_config import GenteBipedCfg
from legged_gente.sim.backend import Simulation
from legged_gente.sim.assembly import build_model
from legged_gente.terrain.terrain import Terrain

TYPES = ["random_uniform", "pyramid_stairs", "river+water", "hills+soil:preset=dry_sand", "low_friction"]


class SmallCurriculum(GenteBipedCfg):
    class env(GenteBipedCfg.env):
        num_envs = 5

    class domain_rand(GenteBipedCfg.domain_rand):
        randomize_friction = False
        push_robots = False

    class terrain(GenteBipedCfg.terrain):
        num_rows = 3
        num_cols = 5
        border_size = 2.0
        terrain_types = TYPES
        terrain_proportions = [0.2] * 5
        max_init_terrain_level = 1


@pytest.fixture(scope="module")
def env():
    return GenteBiped(SmallCurriculum(), device="cpu")


def test_mujoco_hfield_matches_numpy_heights():
    cfg = SmallCurriculum()
    cfg.terrain.hfield_piece_size = 10.0  # the 28 m x 44 m terrain in 3 x 5 pieces
    terrain = Terrain(cfg.terrain, 5)
    mjm, layout = build_model(cfg, terrain)
    assert len(layout.terrain_geoms) == 15 and mjm.nhfield == 15
    data = mujoco.MjData(mjm)
    mujoco.mj_forward(mjm, data)
    rng = np.random.default_rng(0)
    nx, ny = terrain.height_field.shape
    ox, oy = terrain.origin_xy
    # random vertices of the grid (MuJoCo triangulates each cell, numpy interpolates bilinearly: the two agree
    # exactly at vertices, which is where the data is)
    i = rng.integers(0, nx, 400)
    j = rng.integers(0, ny, 400)
    geomid = np.zeros(1, np.int32)
    measured = []
    centre = np.array([ox + (nx - 1) * terrain.resolution / 2, oy + (ny - 1) * terrain.resolution / 2])
    for a, b in zip(ox + i * terrain.resolution, oy + j * terrain.resolution):
        # a vertex on the seam of two pieces lies on both their borders, where a ray may miss: 10 um inwards
        at = np.array([a, b]) + 1e-5 * np.sign(centre - np.array([a, b]))
        dist = mujoco.mj_ray(mjm, data, np.array([*at, 20.0]), np.array([0.0, 0.0, -1.0]), None, 1, -1, geomid)
        assert geomid[0] in layout.terrain_geoms
        measured.append(20.0 - dist)
    assert np.ptp(terrain.height_field[i, j]) > 0.1  # the sample is not all flat ground
    np.testing.assert_allclose(measured, terrain.height_field[i, j], atol=1e-3)


@pytest.mark.parametrize("piece_size, deep_everywhere", [(20.0, True), (1000.0, False)])
def test_a_contact_far_from_the_terrain_centre_keeps_its_depth(piece_size, deep_everywhere):
    """A capsule (r = 4 cm) lying 6 cm deep in flat ground has a contact 6 cm deep wherever it lies (by hand:
    the axis is at z = r - 0.06). In one 100 m MuJoCo-Warp heightfield the depth comes out in metres 30 m from its
    centre (the launch of the quadruped's diverged robots on GenTe's 200 x 400 m benchmark grid); laid down in
    pieces of 20 m it is right everywhere."""
    import mujoco_warp as mjw
    from types import SimpleNamespace

    from legged_gente.sim.assembly import _add_terrain

    terrain = SimpleNamespace(height_field=np.zeros((1001, 1001)), resolution=0.1, origin_xy=(-50.0, -50.0))
    spec = mujoco.MjSpec()
    _add_terrain(spec, SimpleNamespace(static_friction=1.0, hfield_piece_size=piece_size), terrain)
    body = spec.worldbody.add_body()
    body.add_freejoint()
    body.add_geom(type=mujoco.mjtGeom.mjGEOM_CAPSULE, fromto=[-0.15, 0, 0, 0.15, 0, 0], size=[0.04, 0, 0],
                  contype=2, conaffinity=1)
    mjm = spec.compile()
    places = [(0.03, 0.0), (10.03, 5.0), (30.03, 30.0), (-45.03, 20.0), (40.03, -35.0), (-30.03, -47.0)]
    with wp.ScopedDevice("cpu"):
        m, d = mjw.put_model(mjm), mjw.make_data(mjm, nworld=len(places), nconmax=16, njmax=64)
        d.qpos.assign(np.array([[x, y, 0.04 - 0.06, 1, 0, 0, 0] for x, y in places], dtype=np.float32))
        mjw.kinematics(m, d)
        mjw.collision(m, d)
        n = int(d.nacon.numpy()[0])
        world, dist = d.contact.worldid.numpy()[:n], d.contact.dist.numpy()[:n]
    deepest = np.array([dist[world == w].min() for w in range(len(places))])
    assert np.allclose(deepest, -0.06, atol=1e-3) == deep_everywhere, deepest


def test_a_ball_on_a_seam_of_the_pieces_rests_as_inside_one():
    """Balls (r = 3 cm, 2 kg) dropped on flat ground inside a piece, on the seam of two pieces and on the corner of
    four come to rest at z = r less MuJoCo's soft-contact depth (below 1 mm) without drifting sideways: a seam
    adds contacts (the ball touches two pieces), it does not make a step or a slope."""
    import mujoco_warp as mjw
    from types import SimpleNamespace

    from legged_gente.sim.assembly import _add_terrain

    terrain = SimpleNamespace(height_field=np.zeros((201, 201)), resolution=0.1, origin_xy=(0.0, 0.0))
    spec = mujoco.MjSpec()
    _add_terrain(spec, SimpleNamespace(static_friction=1.0, hfield_piece_size=10.0), terrain)
    places = [(5.03, 5.07), (10.0, 5.07), (10.0, 10.0)]  # inside, on a seam, on the corner of the 2 x 2 pieces
    for x, y in places:
        body = spec.worldbody.add_body(pos=[x, y, 0.035])
        body.add_freejoint()
        body.add_geom(type=mujoco.mjtGeom.mjGEOM_SPHERE, size=[0.03, 0, 0], mass=2.0, contype=2, conaffinity=1)
    mjm = spec.compile()
    assert mjm.nhfield == 4
    with wp.ScopedDevice("cpu"):
        m, d = mjw.put_model(mjm), mjw.make_data(mjm, nworld=1, nconmax=64, njmax=256)
        for _ in range(500):
            mjw.step(m, d)
        q = d.qpos.numpy()[0].reshape(-1, 7)
    depth = 0.03 - q[:, 2]
    assert ((depth > 0.0) & (depth < 1e-3)).all(), depth
    assert np.ptp(depth) < 5e-4, depth
    assert np.allclose(q[:, :2], places, atol=1e-5)


def test_robots_start_on_their_tiles(env):
    ground = env._ground_height(env.base_pos[:, :2])
    clearance = env.base_pos[:, 2] - ground
    assert (clearance > 0.8).all() and (clearance < 1.2).all()
    assert env.terrain_levels.max() <= 1
    assert env.terrain_columns.tolist() == [0, 1, 2, 3, 4]


def test_curriculum_moves_levels_as_specified(env):
    env.terrain_levels[:] = torch.tensor([1, 1, 1, 2, 1])
    env.env_origins[:] = env.terrain_origins[env.terrain_levels, env.terrain_columns]
    env.commands[:, :2] = torch.tensor([0.5, 0.0])
    far = env.env_origins[:, :2] + torch.tensor([0.6 * env.cfg.terrain.terrain_length, 0.0])
    near = env.env_origins[:, :2]
    # robots 0 and 3 walked far (up; 3 was on the top level -> random level), 1 stayed (down), 2 is not done
    env.sim.qpos[:, :2] = torch.stack([far[0], near[1], near[2], far[3], far[4]])
    env._update_state()
    done = torch.tensor([True, True, False, True, False])
    torch.manual_seed(0)
    env._update_terrain_curriculum(done)
    assert env.terrain_levels[0] == 2
    assert env.terrain_levels[1] == 0
    assert env.terrain_levels[2] == 1 and env.terrain_levels[4] == 1
    assert 0 <= env.terrain_levels[3] < env.max_terrain_level
    assert torch.equal(env.env_origins, env.terrain_origins[env.terrain_levels, env.terrain_columns])
    # with solved_top_level = "stay", robots that solve the top level keep it; the others move as before
    env.terrain_levels[:] = torch.tensor([1, 1, 1, 2, 1])
    env.env_origins[:] = env.terrain_origins[env.terrain_levels, env.terrain_columns]
    env.solved_top_level = "stay"  # (read from cfg.terrain at construction)
    try:
        for _ in range(3):  # never random
            env.sim.qpos[:, :2] = torch.stack([far[0], near[1], near[2], far[3], far[4]])
            env._update_state()
            env._update_terrain_curriculum(done)
            assert env.terrain_levels[3] == env.max_terrain_level - 1
    finally:
        env.solved_top_level = "random"


def test_terrain_level_statistic_is_the_mean_over_all_robots(env):
    env.terrain_levels[:] = torch.tensor([0, 1, 2, 2, 0])
    assert env._episode_statistics()["terrain_level"].item() == pytest.approx(1.0)


def test_unknown_solved_top_level_is_rejected():
    cfg = SmallCurriculum()
    cfg.terrain.solved_top_level = "stya"
    with pytest.raises(ValueError, match="solved_top_level='stya'; use 'random'"):
        GenteBiped(cfg, device="cpu")


def test_forces_act_in_water_and_soil_only(env):
    assert env.forces is not None
    assert env.get_observations()["critic"].shape[1] == env.get_observations()["policy"].shape[1] + 2 + 6 + 24
    env.reset()
    for _ in range(5):
        env.step(torch.zeros(env.num_envs, env.num_actions))
    obs = env.forces.privileged_obs().reshape(env.num_envs, 2, 12)
    on_soil = obs[..., 3]
    assert on_soil[3].all() and not on_soil[[0, 1, 2, 4]].any()
    xfrc = wp.to_torch(env.sim.d.xfrc_applied).abs().sum(dim=(1, 2))
    assert xfrc[0] == 0 and xfrc[1] == 0  # rigid, dry tiles feel nothing
    # soil acts through the feet's contacts (their rut, their friction limit), not as an applied force
    sinkage = wp.to_torch(env.forces.foot_sinkage)
    assert xfrc[3] == 0 and (sinkage[3] > 0).any() and not sinkage[[0, 1, 2, 4]].any()


def test_low_friction_tiles_lower_contact_friction(env):
    """The solver sees the cell's friction in the contacts of the robot on the low-friction tile."""
    slippery = TYPES.index("low_friction")
    # on the hardest row (then a reset): the start levels are random, and the easiest row's tile keeps the ground's
    # friction
    levels = env.terrain_levels.clone()
    levels[slippery] = env.max_terrain_level - 1
    assert env.load_curriculum_state({"terrain_levels": levels}).startswith("terrain curriculum restored")
    for _ in range(10):  # 0.2 s: the robots, spawned 3 cm above their stand, have landed
        env.step(torch.zeros(env.num_envs, env.num_actions))
    env.sim.step(1)  # a substep's contacts
    d = env.sim.d
    n = int(d.nacon.numpy()[0])
    world = d.contact.worldid.numpy()[:n]
    mu = d.contact.friction.numpy()[:n, 0]
    x, y = env.base_pos[slippery, :2].tolist()
    i = int(round((x - env.terrain.origin_xy[0]) / env.terrain.resolution))
    j = int(round((y - env.terrain.origin_xy[1]) / env.terrain.resolution))
    cell_mu = env.terrain.material.friction[i, j]
    assert cell_mu < env.cfg.terrain.static_friction
    assert (world == slippery).any() and (world == 0).any()
    np.testing.assert_allclose(mu[world == slippery], cell_mu, rtol=1e-5)
    np.testing.assert_allclose(mu[world == 0], env.cfg.terrain.static_friction, rtol=1e-5)


def test_checkpoints_keep_the_terrain_curriculum(env, tmp_path):
    """A resumed run climbs on from the saved levels instead of starting over at max_init_terrain_level."""
    from legged_gente.envs.base.legged_robot_config import rsl_rl_train_cfg
    from legged_gente.envs.gente_biped.gente_biped_config import GenteBipedCfgPPO
    from legged_gente.utils.distributed import GenteOnPolicyRunner

    train_cfg = GenteBipedCfgPPO()
    train_cfg.actor.hidden_dims = [8]
    train_cfg.critic.hidden_dims = [8]
    runner = GenteOnPolicyRunner(env, rsl_rl_train_cfg(train_cfg), log_dir=None, device="cpu")
    runner.task_name = "gente_biped"  # as the task registry sets it
    saved = torch.tensor([2, 0, 1, 2, 1])
    env.terrain_levels = saved.clone()
    runner.save(str(tmp_path / "model_0.pt"))
    env.terrain_levels = torch.zeros_like(saved)
    runner.load(str(tmp_path / "model_0.pt"))
    assert torch.equal(env.terrain_levels, saved) and "restored" in runner.curriculum_message
    assert torch.equal(env.env_origins, env.terrain_origins[saved, env.terrain_columns])
    # the robots start their episodes at the restored origins: an episode that ends at once (standing still)
    # walked nowhere, so no robot is promoted (it was, by the distance from its old spawn, before)
    torch.testing.assert_close(env.base_pos[:, :2], env.env_origins[:, :2] + env.init_base_state[:2], atol=1e-4,
                               rtol=0)
    env.commands[:] = 0.0
    env.episode_length_buf[:] = env.max_episode_length - 1
    env.step(torch.zeros(env.num_envs, env.num_actions))
    assert torch.equal(env.terrain_levels, saved)
    # levels saved for another number of robots leave the curriculum as it is, and say so
    message = env.load_curriculum_state({"terrain_levels": torch.zeros(7, dtype=torch.long)})
    assert "restarts" in message and torch.equal(env.terrain_levels, saved)
    # a checkpoint of another task whose networks fit (a task subclassed from this one): its weights load, its
    # levels (another grid's) do not, and the message names both tasks; before, it loaded silently, levels too
    runner.task_name = "mud_biped"
    env.terrain_levels = torch.zeros_like(saved)
    runner.load(str(tmp_path / "model_0.pt"))
    assert torch.equal(env.terrain_levels, torch.zeros_like(saved))
    assert runner.curriculum_message == ("the checkpoint is of task gente_biped, this task is mud_biped: its weights "
                                         "are loaded (the networks fit), the terrain curriculum restarts")


def test_critic_keeps_its_width_on_a_terrain_without_materials(env):
    """A policy trained with water and soil must load on any terrain: without materials the force fields'
    observation is there as zeros."""

    class Dry(SmallCurriculum):
        class terrain(SmallCurriculum.terrain):
            terrain_types = ["random_uniform"]
            terrain_proportions = [1.0]

    dry = GenteBiped(Dry(), device="cpu")
    assert dry.forces is not None  # installed for the analytic sole contacts alone
    critic = dry.get_observations()["critic"]
    assert critic.shape[1] == env.get_observations()["critic"].shape[1]
    per_foot = critic[:, -24:].reshape(-1, 2, 12)
    # no water, no soil: all zero but the feet's normal force (column 5)
    assert (per_foot[..., [0, 1, 2, 3, 4, 6, 7, 8, 9, 10, 11]] == 0).all()


def test_unknown_cuda_graph_mode_is_rejected():
    cfg = SmallCurriculum()
    cfg.sim.cuda_graph = "yes"
    with pytest.raises(ValueError, match="cuda_graph"):
        GenteBiped(cfg, device="cpu")


def test_torch_compile_must_be_a_bool():
    cfg = SmallCurriculum()
    cfg.sim.torch_compile = "yes"
    with pytest.raises(ValueError, match=r"cfg.sim.torch_compile='yes'; use True"):
        GenteBiped(cfg, device="cpu")


def test_the_step_logic_compiles_to_the_same_numbers():
    """torch.compile of the step's torch logic (what cfg.sim.torch_compile turns on on GPU), here on the CPU with
    the eager random numbers (inductor's fallback_random): the same observations, rewards and resets as eager."""
    import torch._inductor.config as inductor_config

    def rollout(compiled: bool):
        cfg = SmallCurriculum()
        torch.manual_seed(0)
        env = GenteBiped(cfg, device="cpu")
        if compiled:  # what cfg.sim.torch_compile does on a GPU
            env._runner = StepRunner(env, compile=True)
        generator = torch.Generator().manual_seed(1)
        out = []
        with torch.inference_mode():
            for _ in range(8):
                obs, rew, done, _ = env.step(torch.rand(env.num_envs, env.num_actions, generator=generator) * 2 - 1)
                out.append((obs["policy"], obs["critic"], rew, done))
        return out

    with patch.object(inductor_config, "fallback_random", True):
        eager, compiled = rollout(False), rollout(True)
    for (p, c, r, d), (pc, cc, rc, dc) in zip(eager, compiled):
        assert torch.allclose(p, pc, atol=1e-4) and torch.allclose(c, cc, atol=1e-4)
        assert torch.allclose(r, rc, atol=1e-6) and torch.equal(d, dc)


def test_a_reset_leaves_the_critics_force_observation_fresh(env):
    """Robot 3 stands on the soil tile (dry sand), then times out and is reset onto the rigid, dry tile of
    column 0: the force fields' observation of its feet that the critic sees right after the reset must be that
    tile's (no water: depth 0; no soil: flag 0, sinkage 0, soil parameters 0), not the soil it stood on."""
    soil = TYPES.index("hills+soil:preset=dry_sand")
    assert soil == 3 and env.terrain_columns[3] == soil
    env.reset()
    for _ in range(10):
        env.step(torch.zeros(env.num_envs, env.num_actions))
    feet = env.forces.privileged_obs().reshape(env.num_envs, 2, 12)
    assert feet[3, :, 3].any()  # on soil before the reset
    try:
        env.terrain_columns[3] = 0  # its next episode is on column 0's tile (random_uniform: rigid, dry)
        env.episode_length_buf[3] = env.max_episode_length - 1
        obs, _, done, _ = env.step(torch.zeros(env.num_envs, env.num_actions))
        assert done[3]
        feet = env.forces.privileged_obs().reshape(env.num_envs, 2, 12)[3]
        assert torch.all(feet[:, 0] == 0.0)  # water depth
        assert torch.all(feet[:, 3:5] == 0.0)  # on-soil flag, sinkage
        assert torch.all(feet[:, 6:12] == 0.0)  # soil parameters
        assert torch.equal(obs["critic"][3, -24:], feet.flatten())  # what the critic sees
        # the refresh is physics-neutral: what the fields integrate is untouched in every world, and the worlds
        # not refreshed keep their observations and contact forces
        env.step(torch.zeros(env.num_envs, env.num_actions))
        state = [t.clone() for t in env.sim.substep_state]
        observed = [t.clone() for t in env.sim.observed]
        assert len(observed) == 3  # contact forces, actuator forces, force observation
        (buffer,) = env.forces.per_world_state()  # the fields' ruts, slip, loads, ... in one allocation
        assert [t.data_ptr() for t in env.sim.substep_state] == [buffer.ptr]
        assert all(buffer.ptr <= a.ptr < buffer.ptr + 4 * buffer.size
                   for a in (env.forces.foot_sinkage, env.forces.foot_slip, env.forces.foot_load, env.forces.xi))
        env.sim.forward(torch.tensor([False, False, False, True, False]))
        assert all(torch.equal(a, b) for a, b in zip(state, env.sim.substep_state))
        assert all(torch.equal(a[[0, 1, 2, 4]], b[[0, 1, 2, 4]]) for a, b in zip(observed, env.sim.observed))
    finally:
        env.terrain_columns[3] = soil


def test_the_ground_friction_is_one_setting():
    """cfg.terrain.static_friction is the ground's friction for MuJoCo's ground geom and for the force fields'
    scaling of contact friction by cell friction (their reference); forces.friction_reference is not a second
    setting of it."""
    cfg = SmallCurriculum()
    cfg.terrain.static_friction = 0.8
    env = GenteBiped(cfg, device="cpu")
    assert env.forces.cfg.friction_reference == 0.8
    assert env.mjm.geom("terrain").friction[0] == pytest.approx(0.8)
    assert cfg.forces.friction_reference is None  # the env's config is left as it was
    cfg.forces.friction_reference = 0.9
    with pytest.raises(ValueError, match=r"friction_reference=0.9: .*static_friction \(0.8\); set that instead"):
        GenteBiped(cfg, device="cpu")


@pytest.mark.parametrize("friction", [-0.5, float("nan"), float("inf")])
def test_a_plane_ground_friction_that_is_not_a_coefficient_is_refused(friction):
    """A plane builds no terrain grid, whose own check refuses such a friction: the env refuses it (MuJoCo would
    compile the ground geom with it silently)."""
    from legged_gente.envs.gente_biped.gente_biped_config import GenteBipedFlatCfg

    cfg = GenteBipedFlatCfg()
    cfg.env.num_envs = 2
    cfg.terrain.static_friction = friction
    with pytest.raises(ValueError, match=r"static_friction=.*finite coefficient >= 0"):
        GenteBiped(cfg, device="cpu")


def test_without_a_curriculum_robots_spawn_on_every_row():
    """terrain.mode 'random' runs no curriculum (levels never move), so, as in legged_gym with the curriculum off,
    robots are spread over all rows, not kept on rows 0..max_init_terrain_level (0..1 here, of 3)."""
    cfg = SmallCurriculum()
    cfg.terrain.mode = "random"
    cfg.env.num_envs = 30
    torch.manual_seed(0)
    env = GenteBiped(cfg, device="cpu")
    assert not env.terrain_curriculum
    assert sorted(set(env.terrain_levels.tolist())) == [0, 1, 2]


def _plain_substeps(sim, decimation):
    """The reference: MuJoCo-Warp's own step, whole, every substep."""
    for _ in range(decimation):
        mjw.step(sim.m, sim.d)
        for hook in sim.after_substep:
            hook()
    for hook in sim.after_step:
        hook()
    sim._contact_forces()


def _plain_recompute(sim, mask):
    """The reference forward: MuJoCo-Warp's own in every world, then the hooks; what they integrate put back."""
    with sim.substep_state_kept():
        mjw.forward(sim.m, sim.d)
        for hook in sim.after_substep:
            hook()
        for hook in sim.after_step:
            hook()
        sim._contact_forces()


def test_the_forwards_stage_gives_the_steps_own_numbers():
    """The forward after a step's resets computes the next substep's positions, contacts and passive forces (the
    soil's ruts and the water's forces included) ahead, and the step reuses them. Against the same run with
    MuJoCo-Warp's own ``mjw.step`` and ``mjw.forward``: bitwise the same state, force-field state and
    observations, over steps with resets on every terrain."""

    def run() -> list[torch.Tensor]:
        torch.manual_seed(3)
        env = GenteBiped(SmallCurriculum(), device="cpu")
        env.reset()
        actions = torch.Generator().manual_seed(4)
        record = []
        for step in range(12):
            if step in (3, 7):  # a reset (so a forward) onto another tile: the feet's force observation changes
                robot, column = {3: (3, 0), 7: (2, 3)}[step]  # soil -> rigid, water -> soil
                env.episode_length_buf[robot] = env.max_episode_length - 1
                env.terrain_columns[robot] = column
            obs, _, _, _ = env.step(torch.rand(5, env.num_actions, generator=actions) * 2 - 1)
            record += [env.sim.qpos.clone(), env.sim.qvel.clone(), obs["critic"]]
            record += [t.clone() for t in env.sim.substep_state]
        assert env.forces.privileged_obs().reshape(5, 2, 12)[:, :, 3].any()  # feet on soil
        return record

    staged = run()
    with patch.object(Simulation, "_substeps", _plain_substeps), patch.object(Simulation, "recompute", _plain_recompute):
        plain = run()
    assert all(torch.equal(a, b) for a, b in zip(staged, plain, strict=True))


def test_play_shows_the_nominal_robot_as_the_evaluation_scores_it():
    """gente-play kept training's friction draw (0.5-1.25 per robot), so the robots shown slipped or gripped
    unlike the evaluation's, which turns friction and mass randomisation off (legged_gym's play does too)."""
    from legged_gente.envs.task_registry import task_registry

    for task in ("gente_biped", "gente_quadruped"):
        env_cfg, _ = task_registry.get_play_cfgs(task, 4)
        rand = env_cfg.domain_rand
        assert not (rand.randomize_friction or rand.randomize_base_mass or rand.push_robots), task


def test_play_draws_every_terrain_type_of_the_task_not_its_first_five_columns():
    """gente-play and gente-view --play (task_registry.get_play_cfgs) build a 5 x 5 grid: as a curriculum its five
    columns would be the first five of the biped's types only (with a warning); drawn by the task's proportions
    its tiles show types from all over the list, and nothing warns."""
    import warnings

    from legged_gente.envs.task_registry import task_registry
    from legged_gente.terrain.terrain import Terrain

    env_cfg, _ = task_registry.get_play_cfgs("gente_biped", 16)
    assert env_cfg.env.num_envs == 16 and not env_cfg.noise.add_noise and not env_cfg.domain_rand.push_robots
    assert (env_cfg.terrain.num_rows, env_cfg.terrain.num_cols, env_cfg.terrain.mode) == (5, 5, "random")
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        terrain = Terrain(env_cfg.terrain, 16)
    types = list(env_cfg.terrain.terrain_types)
    shown = {types.index(name) for name in terrain.tile_names.flatten()}
    assert len(shown) > 5 and max(shown) >= 5, sorted(shown)
