"""docs/new_robot.md followed literally on the CPU, plus the clear errors an external MJCF can run into.

The tutorial's files are the doc's code blocks that start with ``file: <path>``; they are written to a
temporary folder, the robot is built and stepped in this process, then the doc's train and play commands
run as subprocesses (with CPU-sized flags added).
"""

import os
import re
import subprocess
import sys
import warnings
from pathlib import Path

import mujoco
import pytest
import torch

from legged_gente.envs.base.legged_robot import LeggedRobot
from legged_gente.envs.task_registry import task_registry
from legged_gente.utils.checkpoints import find_checkpoint

ROOT = Path(__file__).resolve().parents[1]
DOC = ROOT / "docs" / "new_robot.md"
NUM_ENVS = 4


def doc_files() -> dict[str, str]:
    blocks = re.findall(r"```\w+\n(.*?)```", DOC.read_text(), re.S)
    files = {}
    for body in blocks:
        m = re.match(r"(?:#|<!--) file: (\S+)", body)
        if m:
            files[m.group(1)] = body
    return files


def doc_commands() -> list[str]:
    return [c.strip() for c in re.findall(r"```bash\n(.*?)```", DOC.read_text(), re.S)]


@pytest.fixture(scope="module")
def tutorial(tmp_path_factory):
    """The tutorial's folder, written from the doc, with its tasks registered in this process."""
    root = tmp_path_factory.mktemp("tutorial")
    for path, text in doc_files().items():
        (root / path).parent.mkdir(parents=True, exist_ok=True)
        (root / path).write_text(text)
    sys.path.insert(0, str(root / "my_robot"))
    try:
        import my_robot_config  # noqa: F401
        import my_robot_tasks  # noqa: F401
    finally:
        sys.path.remove(str(root / "my_robot"))
    yield root
    for name in ("my_robot", "my_robot_rough"):
        task_registry.tasks.pop(name, None)
    for module in ("my_robot_tasks", "my_robot_config"):
        sys.modules.pop(module, None)


def test_doc_has_every_step():
    assert set(doc_files()) == {"my_robot/my_robot.xml", "my_robot/my_robot_config.py", "my_robot/my_robot_tasks.py",
                                "my_robot/train.py", "my_robot/play.py"}
    commands = doc_commands()
    assert any(c.startswith("python my_robot/train.py --task=my_robot") for c in commands)
    assert any(c.startswith("python my_robot/play.py --task=my_robot") for c in commands)


def test_env_builds_with_actuators_added_and_steps(tutorial):
    assert "<actuator" not in (tutorial / "my_robot/my_robot.xml").read_text()
    cfg, _ = task_registry.get_cfgs("my_robot")
    cfg.env.num_envs = NUM_ENVS
    cfg.domain_rand.push_robots = False
    env, _ = task_registry.make_env("my_robot", env_cfg=cfg)
    assert env.num_actions == 8 and env.mjm.nu == 8
    assert env.layout.joint_names[:2] == ["FL_hip", "FL_knee"]
    assert env.mjm.actuator_gainprm[env.mjm.actuator("RR_knee").id, 0] == pytest.approx(15.0)
    assert env.torque_limits.tolist() == [8.0] * 8  # from the joints' actuatorfrcrange
    assert env.get_observations()["policy"].shape == (NUM_ENVS, 12 + 3 * 8)
    for _ in range(20):
        obs, rew, _, _ = env.step(torch.zeros(NUM_ENVS, env.num_actions))
    assert torch.isfinite(obs["policy"]).all() and torch.isfinite(rew).all()
    # it stands on its feet with zero actions, near the tutorial's base_height_target
    assert env.base_pos[:, 2] == pytest.approx(torch.full((NUM_ENVS,), cfg.rewards.base_height_target), abs=0.03)


def test_rough_variant_resolves_force_geoms(tutorial):
    cfg, _ = task_registry.get_cfgs("my_robot_rough")
    cfg.env.num_envs = NUM_ENVS
    cfg.terrain.num_rows, cfg.terrain.num_cols = 1, 5
    cfg.terrain.terrain_length = cfg.terrain.terrain_width = 3.0
    cfg.terrain.border_size = 1.0
    env, _ = task_registry.make_env("my_robot_rough", env_cfg=cfg)
    assert env.forces is not None and env.forces.nseg == 8 and env.forces.nfoot == 4
    obs, _, _, _ = env.step(torch.zeros(NUM_ENVS, env.num_actions))
    assert torch.isfinite(obs["critic"]).all()


def run_doc_command(tutorial, prefix: str, *extra: str) -> subprocess.CompletedProcess:
    command = next(c for c in doc_commands() if c.startswith(prefix)).split()
    env = dict(os.environ, GENTE_LOG_ROOT=str(tutorial / "logs"),
               PYTHONPATH=os.pathsep.join(filter(None, [str(ROOT), os.environ.get("PYTHONPATH")])))
    result = subprocess.run([sys.executable, *command[1:], *extra], cwd=tutorial, env=env, capture_output=True,
                            text=True, timeout=600)
    assert result.returncode == 0, result.stdout[-3000:] + result.stderr[-3000:]
    return result


def test_train_then_play(tutorial):
    run_doc_command(tutorial, "python my_robot/train.py", "--device=cpu", "--num_envs=4", "--max_iterations=1")
    checkpoint = find_checkpoint(tutorial / "logs" / "my_robot")
    assert checkpoint.is_file() and checkpoint.name == "model_0.pt"
    run_doc_command(tutorial, "python my_robot/play.py", "--device=cpu", "--steps=5")
    exported = checkpoint.parent / "exported"  # the played run's own folder
    assert (exported / "policy.onnx").is_file()


# ----------------------------------------------------------------------------------------------------------
# an external MJCF's mistakes: each is a clear error naming the fix
# ----------------------------------------------------------------------------------------------------------
def variant(tutorial, tmp_path, old: str, new: str, count: int = 1) -> str:
    text = (tutorial / "my_robot/my_robot.xml").read_text()
    assert text.count(old) >= count, old
    path = tmp_path / "robot.xml"
    path.write_text(text.replace(old, new, count))
    return str(path)


def tutorial_cfg(file: str | None = None):
    cfg, _ = task_registry.get_cfgs("my_robot")
    cfg.env.num_envs = 2
    if file is not None:
        cfg.asset.file = file
    return cfg


def test_missing_file(tutorial):
    with pytest.raises(FileNotFoundError, match="no_such_robot.xml.*cfg.asset.file"):
        LeggedRobot(tutorial_cfg("no_such_robot.xml"))


def test_robot_without_free_joint(tutorial, tmp_path):
    with pytest.raises(ValueError, match="exactly one free joint.*found 0.*<freejoint/>"):
        LeggedRobot(tutorial_cfg(variant(tutorial, tmp_path, '<freejoint name="root"/>', "")))


def test_scene_file_with_a_floor(tutorial, tmp_path):
    floor = '<worldbody>\n    <geom name="floor" type="plane" size="5 5 0.1"/>'
    with pytest.raises(ValueError, match=r"geoms on the worldbody \['floor'\].*not at a scene file"):
        LeggedRobot(tutorial_cfg(variant(tutorial, tmp_path, "<worldbody>", floor)))


def test_unknown_body_and_joint_names(tutorial):
    cfg = tutorial_cfg()
    cfg.asset.penalize_contacts_on = ["*_calf"]
    with pytest.raises(ValueError, match=r"body '\*_calf' matches nothing.*FL_shin"):
        LeggedRobot(cfg)
    cfg = tutorial_cfg()
    cfg.asset.base_body = "trunk"
    with pytest.raises(ValueError, match="base_body='trunk' is not a body.*'base'"):
        LeggedRobot(cfg)
    cfg = tutorial_cfg()
    cfg.control.stiffness = {"hip": 15.0, "kne": 15.0, "ankle": 5.0}
    with pytest.raises(ValueError, match=r"cfg.control.stiffness: \['ankle'\] match no joint.*FL_knee"):
        LeggedRobot(cfg)
    cfg = tutorial_cfg()
    cfg.init_state.default_joint_angles = {"hip": 0.6}
    with pytest.raises(ValueError, match="no default angle given for joint 'FL_knee'"):
        LeggedRobot(cfg)


def test_menagerie_style_motors_and_visual_meshes(tutorial, tmp_path):
    """Torque motors become PD actuators limited by the motor's ctrlrange; a visual mesh on a body that has
    its own collision geom stays visual, and the env builds and steps with it."""
    (tmp_path / "assets").mkdir()
    (tmp_path / "assets" / "shell.obj").write_text(
        "v -0.1 -0.05 -0.02\nv 0.1 -0.05 -0.02\nv 0.1 0.05 -0.02\nv -0.1 0.05 -0.02\nv 0 0 0.05\n"
        "f 1 3 2\nf 1 4 3\nf 1 2 5\nf 2 3 5\nf 3 4 5\nf 4 1 5\n")
    text = (tutorial / "my_robot/my_robot.xml").read_text()
    text = text.replace('<compiler angle="radian" autolimits="true"/>',
                        '<compiler angle="radian" autolimits="true" meshdir="assets"/>\n'
                        '  <asset><mesh name="shell" file="shell.obj"/></asset>')
    text = text.replace('actuatorfrcrange="-8 8"', "")
    text = text.replace('<geom name="FL_thigh_geom" class="thigh"/>',
                        '<geom name="FL_thigh_geom" class="thigh" contype="1" conaffinity="1"/>\n'
                        '        <geom name="FL_thigh_shell" type="mesh" mesh="shell" mass="0"/>')
    motors = "".join(f'<motor joint="{leg}_{j}" gear="2" ctrlrange="-3 3"/>' for leg in ("FL", "FR", "RL", "RR")
                     for j in ("hip", "knee"))
    text = text.replace("</mujoco>", f"<actuator>{motors}</actuator>\n</mujoco>")
    (tmp_path / "robot.xml").write_text(text)
    env = LeggedRobot(tutorial_cfg(str(tmp_path / "robot.xml")))
    assert env.mjm.nu == 8
    assert env.torque_limits.tolist() == [6.0] * 8  # ctrlrange 3 x gear 2
    assert env.mjm.actuator_gear[:, 0].tolist() == [1.0] * 8
    assert env.mjm.geom_contype[env.mjm.geom("FL_thigh_shell").id] == 0  # visual mesh stays visual
    assert env.mjm.geom_contype[env.mjm.geom("FL_thigh_geom").id] != 0
    assert env.mjm.geom_contype[env.mjm.geom("FR_thigh_geom").id] != 0  # penalised body switched on
    obs, _, _, _ = env.step(torch.zeros(2, env.num_actions))
    assert torch.isfinite(obs["policy"]).all()


def test_box_feet_on_a_heightfield_warn(tutorial, tmp_path):
    from legged_gente.sim.assembly import build_model
    from legged_gente.terrain.terrain import Terrain

    boxes = variant(tutorial, tmp_path, '<geom type="sphere" size="0.02" mass="0.02"', '<geom type="box" size="0.02 0.02 0.02" mass="0.02"')
    cfg, _ = task_registry.get_cfgs("my_robot_rough")
    cfg.asset.file = boxes
    cfg.terrain.num_rows, cfg.terrain.num_cols = 1, 5
    cfg.terrain.terrain_length = cfg.terrain.terrain_width = 3.0
    cfg.terrain.border_size = 1.0
    terrain = Terrain(cfg.terrain, 2)
    with pytest.warns(UserWarning, match=r"foot geoms \['FL_foot_geom'.*spheres"):
        build_model(cfg, terrain)
    cfg.asset.file = str(tutorial / "my_robot/my_robot.xml")  # the tutorial's sphere feet: no warning
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        build_model(cfg, terrain)


def motor_variant(tutorial, tmp_path, attributes: str) -> str:
    """The tutorial robot without its joints' actuatorfrcrange, driven by one <motor> per joint instead."""
    text = (tutorial / "my_robot/my_robot.xml").read_text().replace('actuatorfrcrange="-8 8"', "")
    motors = "".join(f'<motor joint="{leg}_{j}" {attributes}/>' for leg in ("FL", "FR", "RL", "RR")
                     for j in ("hip", "knee"))
    path = tmp_path / "robot.xml"
    path.write_text(text.replace("</mujoco>", f"<actuator>{motors}</actuator>\n</mujoco>"))
    return str(path)


@pytest.mark.parametrize("attributes, limit", [
    ('gear="2" forcerange="-3 3"', 6.0),  # MuJoCo clamps the actuator's force to 3, then the gear doubles it
    ('gear="2" forcerange="-3 3" ctrlrange="-1 1"', 2.0),  # the control's range binds first: 1 x 2
    ('gear="2" forcerange="-3 3" ctrlrange="-5 5"', 6.0),  # the force range binds first: 3 x 2
    ('gear="-2" forcerange="-3 3"', 6.0),  # a reversed joint: the torque still reaches +-6
])
def test_a_motors_torque_limit_is_its_force_range_times_its_gear(tutorial, tmp_path, attributes, limit):
    """MuJoCo's actuator force is gain x ctrl clamped to forcerange; the joint gets gear x that force. The PD
    actuator that replaces the motor has gear 1, so its force limit is the joint torque the motor could give."""
    env = LeggedRobot(tutorial_cfg(motor_variant(tutorial, tmp_path, attributes)))
    assert env.mjm.actuator_gear[:, 0].tolist() == [1.0] * 8
    assert env.torque_limits.tolist() == [limit] * 8
    assert env.mjm.actuator_forcerange.tolist() == [[-limit, limit]] * 8


def test_a_default_angle_outside_the_joints_range_is_refused(tutorial):
    """The tutorial's knees bend one way (range [-2.4, -0.3] rad): a default of +1.2 (a sign error) would be
    clamped at reset while the PD target stays at 1.2, pressing the knee into its limit for ever."""
    cfg = tutorial_cfg()
    cfg.init_state.default_joint_angles = {"hip": 0.6, "knee": 1.2}
    with pytest.raises(ValueError, match=r"FL_knee=1.2 outside its range \[-2.4, -0.3\].*sign"):
        LeggedRobot(cfg)


def test_a_joint_driven_by_two_actuators_is_refused(tutorial, tmp_path):
    """A second actuator on a joint would be a thirteenth action on twelve joints, the file's own gains added to the
    config's: refused, naming the joint and its actuators."""
    motors = '<actuator><motor name="hip_a" joint="FL_hip" gear="10"/><motor name="hip_b" joint="FL_hip"/></actuator>'
    with pytest.raises(ValueError, match=r"joint 'FL_hip' is driven by 2 actuators \['hip_a', 'hip_b'\].*one each"):
        LeggedRobot(tutorial_cfg(variant(tutorial, tmp_path, "</mujoco>", f"{motors}\n</mujoco>")))


def test_an_actuator_on_a_tendon_or_site_is_refused(tutorial, tmp_path):
    """The env's actions are joint angle targets, one PD actuator per joint: an actuator of another transmission
    would be an action without a joint."""
    extra = ('<tendon><fixed name="knees"><joint joint="FL_knee" coef="1"/><joint joint="FR_knee" coef="1"/></fixed>'
             '</tendon><actuator><motor name="pull" tendon="knees"/></actuator>')
    with pytest.raises(ValueError, match=r"actuator 'pull' drives a tendon.*joints only.*remove it"):
        LeggedRobot(tutorial_cfg(variant(tutorial, tmp_path, "</mujoco>", f"{extra}\n</mujoco>")))


def test_a_foot_without_a_colliding_geom_is_refused(tutorial, tmp_path):
    """A foot whose geoms collide with nothing would pass through the ground (the robot standing on its shins) and
    never register a contact: refused, naming the foot bodies."""
    path = variant(tutorial, tmp_path, '<body name="FL_foot" pos="0 0 -0.12"><geom name="FL_foot_geom" class="foot"/>',
                   '<body name="FL_foot" pos="0 0 -0.12"><geom name="FL_foot_geom" class="foot" contype="0" '
                   'conaffinity="0"/>')
    with pytest.raises(ValueError, match=r"cfg.asset.foot_bodies: \['FL_foot'\] have no geom that collides.*contype"):
        LeggedRobot(tutorial_cfg(path))


def rough_cfg():
    cfg, _ = task_registry.get_cfgs("my_robot_rough")
    cfg.env.num_envs = 2
    cfg.terrain.num_rows, cfg.terrain.num_cols = 1, 5
    cfg.terrain.terrain_length = cfg.terrain.terrain_width = 3.0
    cfg.terrain.border_size = 1.0
    return cfg


def test_foot_geoms_that_leave_out_a_foot_are_refused(tutorial):
    """Three of four feet listed: the fourth would get no soil and collide through MuJoCo while the others use the
    analytic sole contacts. A listed geom off the feet is refused too: its contacts would count for no foot."""
    cfg = rough_cfg()
    cfg.forces.foot_geom_names = ["FL_foot_geom", "FR_foot_geom", "RL_foot_geom"]
    with pytest.raises(ValueError, match=r"forces.foot_geom_names lists no geom of the feet \['RR_foot'\] of "
                                         r"cfg.asset.foot_bodies.*list each foot's sole geoms"):
        LeggedRobot(cfg)
    cfg = rough_cfg()
    cfg.forces.foot_geom_names = [*cfg.forces.foot_geom_names, "FL_shin_collision"]
    with pytest.raises(ValueError, match=r"forces.foot_geom_names: \['FL_shin_collision'\] are on \['FL_shin'\], "
                                         r"no foot of cfg.asset.foot_bodies"):
        LeggedRobot(cfg)


def test_water_and_soil_with_no_geoms_to_feel_them_warn(tutorial):
    """A terrain with water and mud but no leg or foot geoms named: the water and the mud would do nothing, unsaid."""
    cfg = rough_cfg()
    cfg.forces.leg_geom_names, cfg.forces.foot_geom_names = [], []
    with pytest.warns(UserWarning) as caught:
        LeggedRobot(cfg)
    said = " ".join(str(w.message) for w in caught)
    assert "the terrain has water, but forces.leg_geom_names and forces.foot_geom_names name no geom" in said, said
    assert "the terrain has soil, but forces.foot_geom_names names no geom" in said, said


def test_a_body_pattern_matching_nothing_names_its_field(tutorial):
    """Three lists take body patterns: the error says which one it came from (and lists the robot's bodies, the
    world body none of them)."""
    cfg = tutorial_cfg()
    cfg.asset.terminate_after_contacts_on = ["*_calf"]
    with pytest.raises(ValueError, match=r"cfg.asset.terminate_after_contacts_on: body '\*_calf' matches nothing in "
                                         r"the robot; its bodies are: \['base', 'FL_thigh'"):
        LeggedRobot(cfg)


def test_feet_that_end_the_episode_on_contact_are_refused(tutorial):
    cfg = tutorial_cfg()
    cfg.asset.terminate_after_contacts_on = ["base", "*_foot"]
    with pytest.raises(ValueError, match=r"terminate_after_contacts_on includes the feet \['FL_foot', 'FR_foot', "
                                         r"'RL_foot', 'RR_foot'\].*every touchdown would end the episode"):
        LeggedRobot(cfg)


@pytest.mark.parametrize("old, new, reason", [
    ('<geom name="base_geom" type="box"', '<geom name="base_geom" type="mesh" mesh="no_such_mesh"',
     "mesh 'no_such_mesh' not found"),
    ("</worldbody>", "", "XML parse error"),
])
def test_a_file_mujoco_cannot_load_is_named(tutorial, tmp_path, old, new, reason):
    """MuJoCo's own error names no file (and starts with its own "Error:"): the message names the robot file."""
    path = variant(tutorial, tmp_path, old, new)
    with pytest.raises(ValueError, match=rf"robot file '{re.escape(path)}' \(cfg.asset.file\): MuJoCo cannot load it: "
                                         rf"{reason}"):
        LeggedRobot(tutorial_cfg(path))


def test_a_misspelt_force_geom_lists_the_robots_geoms_only(tutorial):
    """The terrain's heightfield pieces are geoms too, dozens of them: the list of names to pick from is the robot's."""
    cfg = rough_cfg()
    cfg.forces.leg_geom_names = ["FL_thigh_gem"]
    with pytest.raises(ValueError, match=r"forces.leg_geom_names: no geom named 'FL_thigh_gem' in the robot \(exact "
                                         r"names\); its named geoms: \['base_geom', 'FL_thigh_geom'") as error:
        LeggedRobot(cfg)
    assert "terrain" not in str(error.value)


def small_runner(cfg, task):
    env, _ = task_registry.make_env(task, env_cfg=cfg)
    _, train_cfg = task_registry.get_cfgs(task)
    train_cfg.actor.hidden_dims = train_cfg.critic.hidden_dims = [8]
    return task_registry.make_alg_runner(env, task, train_cfg=train_cfg, log_root=None)[0]


def test_a_checkpoint_of_a_task_with_other_observations_says_so(tutorial, tmp_path):
    """my_robot and my_robot_rough both have 8 actions; the rough task's policy also sees the height scan. The
    refusal names the difference (the actor's input width), not only the two tasks' equal action counts."""
    from legged_gente.utils.checkpoints import CheckpointError

    path = tmp_path / "model_0.pt"
    small_runner(tutorial_cfg(), "my_robot").save(str(path))
    with pytest.raises(CheckpointError, match=r"is for my_robot \(8 actions\); this task is my_robot_rough \(8 "
                                              r"actions\), whose actor takes \d+ inputs, the checkpoint's \d+ \(another "
                                              r"observation set\)\. Pick a checkpoint of this task"):
        small_runner(rough_cfg(), "my_robot_rough").load(str(path))


def test_a_urdf_gets_advice_it_can_follow(tutorial, tmp_path):
    """A URDF cannot hold <freejoint/>: its floating base is a "floating" joint from a link named "world" (MuJoCo's
    URDF reader makes it a free joint); with one, the file builds."""
    urdf = tmp_path / "robot.urdf"
    urdf.write_text('<robot name="r"><link name="base"><inertial><mass value="1"/><inertia ixx="0.01" iyy="0.01" '
                    'izz="0.01" ixy="0" ixz="0" iyz="0"/></inertial></link></robot>')
    with pytest.raises(ValueError, match=r'found 0; in a URDF the floating base is a joint of type "floating" from '
                                         r'a link named "world" to the root link: add both'):
        LeggedRobot(tutorial_cfg(str(urdf)))
    from legged_gente.sim.assembly import _check_robot

    urdf.write_text(urdf.read_text().replace('<robot name="r">', '<robot name="r"><link name="world"/><joint '
                                             'name="float" type="floating"><parent link="world"/><child link="base"/>'
                                             '</joint>'))
    robot = mujoco.MjSpec.from_file(str(urdf)).compile()
    cfg = tutorial_cfg(str(urdf))
    cfg.control.stiffness = cfg.control.damping = cfg.init_state.default_joint_angles = {}
    _check_robot(robot, cfg)  # one free joint, first in qpos, no geom on the world body


def test_joints_without_a_torque_limit_warn(tutorial, tmp_path):
    """No actuatorfrcrange and no actuator force range: the PD torque is unbounded, which no motor gives."""
    path = variant(tutorial, tmp_path, ' actuatorfrcrange="-8 8"', "")
    with pytest.warns(UserWarning, match=r"joints \['FL_hip', 'FL_knee', .*\] have no torque limit: their PD torque is "
                                         r"unbounded; give them actuatorfrcrange"):
        LeggedRobot(tutorial_cfg(path))
    with warnings.catch_warnings():
        warnings.simplefilter("error")  # the tutorial's robot as written: limited, no warning
        LeggedRobot(tutorial_cfg())
