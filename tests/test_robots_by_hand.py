"""The shipped robot models, their task configs and docs/robots.md / docs/new_robot.md, checked against values
computed by hand: masses and inertias from the geom shapes (textbook formulas), standing heights from the leg
geometry, the env's gains and torque limits, the sole geometry the analytic contacts read, and the numbers the
docs state. Plain MuJoCo on the CPU (no Warp step)."""

import fnmatch
import itertools
import math
import re
from pathlib import Path

import mujoco
import numpy as np
import pytest

from legged_gente.envs.gente_biped.gente_biped_config import GenteBipedCfg
from legged_gente.envs.gente_quadruped.gente_quadruped_config import GenteQuadrupedCfg
from legged_gente.external_forces.contact import sole_points
from legged_gente.external_forces.field import foot_groups, geom_body_box
from legged_gente.sim.assembly import build_model

ROOT = Path(__file__).resolve().parents[1]
ROBOTS = ROOT / "legged_gente" / "resources" / "robots"
ROBOTS_DOC = " ".join((ROOT / "docs" / "robots.md").read_text().split())  # whitespace-normalised
NEW_ROBOT_DOC = " ".join((ROOT / "docs" / "new_robot.md").read_text().split())
G = 9.81
# mud: sandy loam at 32 % moisture, Wong, Theory of Ground Vehicles, Table 2.3: kc = 0.77 kN/m^1.5,
# kphi = 51.91 kN/m^2.5, n = 0.5
MUD_KC, MUD_KPHI, MUD_N = 0.77e3, 51.91e3, 0.5


def model(name: str) -> mujoco.MjModel:
    return mujoco.MjModel.from_xml_path(str(ROBOTS / name / f"{name}.xml"))


def bekker_sinkage(pressure: float, b: float) -> float:
    """Bekker's static sinkage z = (p / (kc/b + kphi))^(1/n) in mud (Wong, ch. 2)."""
    return (pressure / (MUD_KC / b + MUD_KPHI)) ** (1 / MUD_N)


# ------------------------------------------------------------------------------------------------------------
# masses and inertias
# ------------------------------------------------------------------------------------------------------------
def box(m, sx, sy, sz):
    """Solid box of full sides sx, sy, sz: I = m (b^2 + c^2) / 12 about each axis."""
    return np.diag([m * (sy**2 + sz**2) / 12, m * (sx**2 + sz**2) / 12, m * (sx**2 + sy**2) / 12])


def sphere(m, r):
    return np.eye(3) * 0.4 * m * r**2


def cylinder_z(m, r, length):
    """Solid cylinder along z: I_zz = m r^2 / 2, I_xx = I_yy = m (3 r^2 + L^2) / 12."""
    across = m * (3 * r**2 + length**2) / 12
    return np.diag([across, across, 0.5 * m * r**2])


def capsule_z(m, r, length):
    """Capsule along z (cylinder of length L plus two hemispheres), uniform density. Across the axis each hemisphere
    (mass mh) has 2/5 mh r^2 about its flat face's centre, its centre of mass 3r/8 from it, and sits L/2 from the
    capsule's centre: mh (2/5 r^2 - (3r/8)^2 + (L/2 + 3r/8)^2) = mh (2/5 r^2 + L^2/4 + 3 L r / 8)."""
    v_cyl, v_sph = math.pi * r**2 * length, 4 / 3 * math.pi * r**3
    mc, ms = m * v_cyl / (v_cyl + v_sph), m * v_sph / (v_cyl + v_sph)
    across = mc * (3 * r**2 + length**2) / 12 + ms * (0.4 * r**2 + length**2 / 4 + 3 * length * r / 8)
    return np.diag([across, across, 0.5 * mc * r**2 + 0.4 * ms * r**2])


ALONG_X = np.array([[0.0, 0.0, 1.0], [0.0, 1.0, 0.0], [-1.0, 0.0, 0.0]])  # turns z onto x (quat 0.7071 0 0.7071 0)


def combine(parts):
    """(mass, centre, inertia about the centre) of parts (mass, centre, inertia about their own centre), by the
    parallel-axis theorem: I = sum(I_i + m_i (|d|^2 E - d d^T))."""
    mass = sum(m for m, _, _ in parts)
    com = sum(m * np.asarray(c, float) for m, c, _ in parts) / mass
    inertia = np.zeros((3, 3))
    for m, c, i in parts:
        d = np.asarray(c, float) - com
        inertia += i + m * (d @ d * np.eye(3) - np.outer(d, d))
    return mass, com, inertia


# every body of each robot, from its MJCF geoms (mass, centre in the body frame, inertia about that centre)
BIPED_BODIES = {
    "pelvis": [(5.0, (0, 0, 0), box(5.0, 0.14, 0.26, 0.10))],
    "torso": [(11.0, (0, 0, 0.2), box(11.0, 0.18, 0.28, 0.36)), (1.5, (0, 0, 0.47), sphere(1.5, 0.08))],
    "hip_yaw_link": [(1.5, (0, 0, -0.03), cylinder_z(1.5, 0.04, 0.06))],
    "hip_roll_link": [(1.5, (0, 0, 0), ALONG_X @ cylinder_z(1.5, 0.045, 0.10) @ ALONG_X.T)],
    "thigh": [(5.0, (0, 0, -0.2), capsule_z(5.0, 0.05, 0.34))],  # fromto z -0.03 .. -0.37
    "shank": [(3.0, (0, 0, -0.19), capsule_z(3.0, 0.05, 0.32))],  # fromto z -0.03 .. -0.35
    "foot": [(1.0, (0.05, 0, -0.05), box(1.0, 0.22, 0.09, 0.04))],  # the sole spheres are massless
}
QUADRUPED_BODIES = {
    "trunk": [(6.0, (0, 0, 0), box(6.0, 0.38, 0.12, 0.10))],
    "hip": [(0.7, (0, 0, 0), ALONG_X @ cylinder_z(0.7, 0.045, 0.06) @ ALONG_X.T)],
    "thigh": [(1.0, (0, 0, -0.1), capsule_z(1.0, 0.025, 0.2))],
    "calf": [(0.25, (0, 0, -0.1), capsule_z(0.25, 0.02, 0.2))],  # the collision capsule is massless
    "foot": [(0.05, (0, 0, 0), sphere(0.05, 0.02))],
}


def body_inertia_in_body_frame(m: mujoco.MjModel, b: int) -> np.ndarray:
    """MuJoCo's principal inertia turned back into the body frame: R diag(I) R^T, R from body_iquat."""
    rot = np.zeros(9)
    mujoco.mju_quat2Mat(rot, m.body_iquat[b])
    rot = rot.reshape(3, 3)
    return rot @ np.diag(m.body_inertia[b]) @ rot.T


@pytest.mark.parametrize("name, bodies, total", [("gente_biped", BIPED_BODIES, 41.5),
                                                 ("gente_quadruped", QUADRUPED_BODIES, 14.0)])
def test_masses_and_inertias_follow_the_geom_shapes(name, bodies, total):
    # biped: 5 + 12.5 + 2 (1.5 + 1.5 + 5 + 3 + 1) = 41.5 kg; quadruped: 6 + 4 (0.7 + 1 + 0.25 + 0.05) = 14 kg
    m = model(name)
    assert mujoco.mj_getTotalmass(m) == pytest.approx(total, abs=1e-9)
    checked = 0
    for b in range(1, m.nbody):
        body = m.body(b).name
        key = next(k for k in bodies if body == k or body.endswith("_" + k))
        mass, com, inertia = combine(bodies[key])
        assert m.body_mass[b] == pytest.approx(mass, abs=1e-9), body
        np.testing.assert_allclose(m.body_ipos[b], com, atol=1e-9, err_msg=body)
        np.testing.assert_allclose(body_inertia_in_body_frame(m, b), inertia, rtol=1e-6, atol=1e-12, err_msg=body)
        checked += 1
    assert checked == m.nbody - 1


@pytest.mark.parametrize("name", ["gente_biped", "gente_quadruped"])
def test_inertias_are_physical(name):
    """Positive principal moments that satisfy the triangle inequality (I_a + I_b >= I_c): a real mass
    distribution has them."""
    m = model(name)
    for b in range(1, m.nbody):
        i = np.sort(m.body_inertia[b])
        assert i[0] > 0 and i[0] + i[1] >= i[2], m.body(b).name


# ------------------------------------------------------------------------------------------------------------
# standing heights: keyframe, the config's default pose, its spawn height and reset noise
# ------------------------------------------------------------------------------------------------------------
def default_angles(cfg, m: mujoco.MjModel) -> np.ndarray:
    """The config's default joint angles, by the env's rule (fnmatch or substring, first key wins)."""
    names = [m.joint(j).name for j in range(1, m.njnt)]
    return np.array([next(v for k, v in cfg.init_state.default_joint_angles.items()
                          if fnmatch.fnmatchcase(n, k) or k in n) for n in names])


def lowest_collider_z(m: mujoco.MjModel, base_z: float, angles: np.ndarray) -> float:
    """Lowest point of the colliding (sphere) geoms with the base level at base_z and the joints at angles."""
    d = mujoco.MjData(m)
    d.qpos[:7] = [0, 0, base_z, 1, 0, 0, 0]
    d.qpos[7:] = angles
    mujoco.mj_kinematics(m, d)
    feet = [g for g in range(m.ngeom) if m.geom_contype[g] or m.geom_conaffinity[g]]
    assert all(m.geom_type[g] == mujoco.mjtGeom.mjGEOM_SPHERE for g in feet)
    return min(d.geom_xpos[g, 2] - m.geom_size[g, 0] for g in feet)


def test_biped_standing_heights_by_hand():
    m = model("gente_biped")
    # keyframe: hip pitch -0.3, knee 0.6, ankle -0.3: pelvis -> hip pitch 0.07 + 0.05 + 0.04 = 0.16 m, thigh and
    # shank 0.4 m tilted by 0.3 rad, ankle -> sole 0.07 m
    stand = 0.16 + 2 * 0.4 * math.cos(0.3) + 0.07
    assert m.key("stand").qpos[2] == pytest.approx(stand, abs=1e-5)
    assert "0.16 + 2·0.4·cos 0.3 + 0.07 = 0.994 m" in ROBOTS_DOC and round(stand, 3) == 0.994
    # the config's default pose: hip -0.25, knee 0.55, ankle -0.3: the foot's pitch is -0.25 + 0.55 - 0.3 = 0
    # (sole flat), the pelvis 0.16 + 0.4 cos 0.25 + 0.4 cos 0.30 + 0.07 = 0.9997 m up ("stands at 1.0 m")
    cfg = GenteBipedCfg()
    q = default_angles(cfg, m)
    assert q.tolist() == [0.0, 0.0, -0.25, 0.55, -0.3] * 2
    default_stand = 0.16 + 0.4 * math.cos(0.25) + 0.4 * math.cos(0.30) + 0.07
    assert round(default_stand, 2) == 1.0
    assert lowest_collider_z(m, default_stand, q) == pytest.approx(0.0, abs=1e-9)
    assert cfg.init_state.pos[2] == pytest.approx(default_stand + 0.03, abs=1e-3)  # "dropped from 3 cm"
    # every sole sphere touches at once: the sole is flat
    d = mujoco.MjData(m)
    d.qpos[:7], d.qpos[7:] = [0, 0, default_stand, 1, 0, 0, 0], q
    mujoco.mj_kinematics(m, d)
    soles = [m.geom(f"{s}_sole_{c}").id for s in ("left", "right") for c in ("toe_l", "toe_r", "heel_l", "heel_r")]
    np.testing.assert_allclose(d.geom_xpos[soles, 2] - 0.02, 0.0, atol=1e-9)


def test_quadruped_standing_heights_by_hand():
    m = model("gente_quadruped")
    # thigh 0.8, calf -1.6: both 0.2 m segments 0.8 rad from the vertical, foot ball r 0.02 m
    stand = 2 * 0.2 * math.cos(0.8) + 0.02  # 0.29868 m
    assert m.key("stand").qpos[2] == pytest.approx(stand, abs=2e-5)  # the file rounds it to 0.29867
    assert "2·0.2·cos 0.8 + 0.02 = 0.299 m" in ROBOTS_DOC and round(stand, 3) == 0.299
    cfg = GenteQuadrupedCfg()
    q = default_angles(cfg, m)
    assert q.tolist() == [0.0, 0.8, -1.6] * 4
    assert lowest_collider_z(m, stand, q) == pytest.approx(0.0, abs=1e-9)
    assert cfg.init_state.pos[2] == pytest.approx(stand + 0.03, abs=2e-3)  # "drop from 3 cm above it"
    # feet right below the hips: x = +-0.19 m, y = +-(0.05 + 0.08) = +-0.13 m
    d = mujoco.MjData(m)
    d.qpos[:7], d.qpos[7:] = [0, 0, stand, 1, 0, 0, 0], q
    mujoco.mj_kinematics(m, d)
    for leg, (sx, sy) in zip(("FL", "FR", "RL", "RR"), ((1, 1), (1, -1), (-1, 1), (-1, -1))):
        np.testing.assert_allclose(d.site(f"{leg}_foot_site").xpos, [0.19 * sx, 0.13 * sy, 0.0], atol=1e-9)


@pytest.mark.parametrize("cfg_class, name", [(GenteBipedCfg, "gente_biped"), (GenteQuadrupedCfg, "gente_quadruped")])
def test_default_pose_inside_the_limits_and_reset_noise_spawns_above_ground(cfg_class, name):
    """Every reset draws each joint uniformly within default +- joint_pos_noise (clamped to its range) at the
    config's spawn height: no such pose may put a foot into the ground. The legs are independent, so each leg's
    joints go through a grid of offsets with the others at their defaults."""
    cfg, m = cfg_class(), model(name)
    q0, noise = default_angles(cfg, m), cfg.init_state.joint_pos_noise
    lo, hi = m.jnt_range[1:, 0], m.jnt_range[1:, 1]
    assert np.all((lo < q0) & (q0 < hi))
    per_leg = 5 if name == "gente_biped" else 3
    lowest = np.inf
    for leg in range(len(q0) // per_leg):
        for offsets in itertools.product((-1.0, -0.5, 0.0, 0.5, 1.0), repeat=per_leg):
            q = q0.copy()
            q[leg * per_leg:(leg + 1) * per_leg] += noise * np.array(offsets)
            lowest = min(lowest, lowest_collider_z(m, cfg.init_state.pos[2], np.clip(q, lo, hi)))
    assert lowest > 0.0


# ------------------------------------------------------------------------------------------------------------
# the env's actuators: the config's gains, the file's torque limits
# ------------------------------------------------------------------------------------------------------------
# docs/robots.md's joint tables: (torque limit N*m, armature kg*m^2, damping N*m*s/rad) per joint kind, and the
# tasks' gains (kp N*m/rad, kd N*m*s/rad)
BIPED_JOINTS = {"hip_yaw": (120, 0.03, 1.0, 150, 5), "hip_roll": (150, 0.03, 1.0, 150, 5),
                "hip_pitch": (150, 0.03, 1.0, 150, 5), "knee": (250, 0.05, 1.0, 200, 5), "ankle": (50, 0.01, 0.5, 80, 3)}
QUADRUPED_JOINTS = {"hip": (25, 0.01, 0.5, 30, 0.8), "thigh": (25, 0.01, 0.5, 30, 0.8), "calf": (35, 0.02, 0.5, 30, 0.8)}


@pytest.mark.parametrize("cfg_class, table", [(GenteBipedCfg, BIPED_JOINTS), (GenteQuadrupedCfg, QUADRUPED_JOINTS)])
def test_env_actuators_are_the_configs_pd_with_the_files_torque_limits(cfg_class, table):
    cfg = cfg_class()
    mjm, layout = build_model(cfg)  # a plane: no terrain needed
    assert mjm.nu == len(layout.joint_names) == mjm.njnt - 1
    for a, joint in enumerate(layout.joint_names):
        kind = joint.split("_", 1)[1]
        limit, armature, damping, kp, kd = table[kind]
        j = mjm.joint(joint).id
        dof = mjm.jnt_dofadr[j]
        assert mjm.actuator_trnid[a, 0] == j and mjm.actuator_gear[a, 0] == 1.0
        # position servo: tau = kp (ctrl - q) - kd qdot, clamped to the torque limit
        assert mjm.actuator_gainprm[a, 0] == kp and mjm.actuator_biasprm[a, :3].tolist() == [0.0, -kp, -kd], joint
        assert mjm.actuator_forcelimited[a] and mjm.actuator_forcerange[a].tolist() == [-limit, limit], joint
        assert not mjm.actuator_ctrllimited[a]  # the PD target may leave the range (the joint limit holds)
        assert layout.torque_limits[a] == limit
        assert mjm.dof_armature[dof] == pytest.approx(armature) and mjm.dof_damping[dof] == pytest.approx(damping)
        np.testing.assert_allclose(layout.joint_limits[a], mjm.jnt_range[j])


# ------------------------------------------------------------------------------------------------------------
# the sole geometry the analytic contacts and the soil model read
# ------------------------------------------------------------------------------------------------------------
def test_biped_sole_points_and_footprint():
    cfg = GenteBipedCfg()
    mjm = model("gente_biped")
    bodies, groups = foot_groups(mjm, cfg.forces.foot_geom_names)
    assert [mjm.body(b).name for b in bodies] == ["left_foot", "right_foot"]
    geoms, ends, feet = sole_points(mjm, groups)
    assert len(geoms) == 8 and ends.tolist() == [0.0] * 8 and feet.tolist() == [0] * 4 + [1] * 4
    expected = {(0.14, 0.028), (0.14, -0.028), (-0.04, 0.028), (-0.04, -0.028)}  # toe/heel x, left/right y (m)
    for group in groups:
        assert {tuple(np.round(mjm.geom_pos[g, :2], 6)) for g in group} == expected
        assert mjm.geom_size[group, 0].tolist() == [0.02] * 4
        # the spheres' bottoms are the sole plane: 0.05 + 0.02 = 0.07 m below the ankle, the box's bottom and the
        # foot site's height
        boxes = [geom_body_box(mjm, g) for g in group]
        assert [c[2] - h[2] for c, h in boxes] == pytest.approx([-0.07] * 4, abs=1e-12)
        # the footprint the soil model uses: x from -0.04 - 0.02 to 0.14 + 0.02, y from -0.048 to 0.048
        lo = np.min([c - h for c, h in boxes], axis=0)
        hi = np.max([c + h for c, h in boxes], axis=0)
        assert (hi - lo)[:2].tolist() == pytest.approx([0.22, 0.096], abs=1e-12)
    for side in ("left", "right"):
        assert mjm.site(f"{side}_foot_site").pos.tolist() == pytest.approx([0.05, 0.0, -0.07])
        box_geom = mjm.geom(f"{side}_foot_geom").id
        assert mjm.geom_pos[box_geom, 2] - mjm.geom_size[box_geom, 2] == pytest.approx(-0.07)


def test_quadruped_sole_points_are_the_foot_balls():
    cfg = GenteQuadrupedCfg()
    mjm = model("gente_quadruped")
    bodies, groups = foot_groups(mjm, cfg.forces.foot_geom_names)
    assert [mjm.body(b).name for b in bodies] == ["FL_foot", "FR_foot", "RL_foot", "RR_foot"]
    geoms, ends, feet = sole_points(mjm, groups)
    assert feet.tolist() == [0, 1, 2, 3] and ends.tolist() == [0.0] * 4
    for g in geoms:
        centre, half = geom_body_box(mjm, g)
        assert mjm.geom_size[g, 0] == 0.02 and centre.tolist() == [0.0, 0.0, 0.0] and half.tolist() == [0.02] * 3


# ------------------------------------------------------------------------------------------------------------
# the numbers docs/robots.md and docs/new_robot.md state
# ------------------------------------------------------------------------------------------------------------
def test_biped_doc_numbers():
    m = model("gente_biped")
    d = mujoco.MjData(m)
    mujoco.mj_resetDataKeyframe(m, d, m.key("stand").id)
    mujoco.mj_kinematics(m, d)
    # whole-body centre of mass: sum m_i x_i / M over the bodies' centres
    com = m.body_mass[1:] @ d.xipos[1:] / m.body_mass[1:].sum()
    ankle_x = 0.4 * math.sin(0.3) - 0.4 * math.sin(0.3)  # thigh forward by 0.3 rad, shank back by 0.3 rad: 0
    assert d.xanchor[m.joint("left_ankle").id, 0] == pytest.approx(ankle_x, abs=1e-12)
    assert round(com[2], 2) == 0.83 and round(100 * (com[0] - ankle_x), 1) == 2.6
    assert "centre of mass at z = 0.83 m, 2.6 cm ahead of the ankles" in ROBOTS_DOC
    # overall height: pelvis 0.994 + torso 0.05 + head centre 0.47 + head radius 0.08 = 1.594 m
    top = m.key("stand").qpos[2] + 0.05 + 0.47 + 0.08
    assert round(top, 2) == 1.59 and "overall height ≈ 1.59 m" in ROBOTS_DOC
    # the toppling stiffness: the 39.5 kg above the ankles (all but the two 1 kg feet), their centre 0.80 m above the
    # ankle axis (0.07 m above the sole)
    above = [b for b in range(1, m.nbody) if not m.body(b).name.endswith("_foot")]
    mass = m.body_mass[above].sum()
    height = m.body_mass[above] @ d.xipos[above, 2] / mass - 0.07
    assert mass == pytest.approx(39.5) and round(height, 2) == 0.80
    assert round(mass * G * height, -1) == 310 and "39.5 kg · 9.81 · 0.80 m ≈ 310 N·m/rad" in ROBOTS_DOC


def test_quadruped_mud_doc_numbers():
    # a quarter of 14 kg on a disc of radius 0.02 m: p = 3.5 * 9.81 / (pi 0.02^2) = 27.3 kPa; Bekker b = r
    pressure = 14.0 / 4 * G / (math.pi * 0.02**2)
    sink = bekker_sinkage(pressure, 0.02)  # (27.3e3 / (0.77e3 / 0.02 + 51.91e3))^2 = 0.091 m
    assert round(pressure / 1e3) == 27 and round(100 * sink) == 9
    assert "27 kPa on its 2 cm disc, would sink 9 cm" in ROBOTS_DOC
    # the calf's collision capsule (0 .. 0.14 m down the calf, r 0.02 m) above the sole in the stand: the knee is
    # 0.02 + 0.2 cos 0.8 up, the capsule's end 0.14 cos 0.8 below it, its surface 0.02 lower: 0.06 cos 0.8 = 4.2 cm
    clearance = 0.02 + 0.2 * math.cos(0.8) - 0.14 * math.cos(0.8) - 0.02
    assert round(100 * clearance, 1) == 4.2 and "(4.2 cm in the stand)" in ROBOTS_DOC
    assert sink > clearance  # hence the calves follow their feet into their ruts (forces.rut_leg_geom_names)
    # trotting, two feet carry the 14 kg: 54.6 kPa sinks a foot below the knee (0.02 + 0.2 cos 0.8 = 15.9 cm up) in
    # mud, (54.6e3 / (0.77e3 / 0.02 + 51.91e3))^2 = 37 cm, and in snow (Wong, Table 2.3: n = 1.6, kc = 4.37e3,
    # kphi = 196.72e3), (54.6e3 / (4.37e3 / 0.02 + 196.72e3))^(1 / 1.6) = 28 cm: no collision capsule on the calf
    # clears that
    trot = 14.0 / 2 * G / (math.pi * 0.02**2)
    knee = 0.02 + 0.2 * math.cos(0.8)
    mud, snow = bekker_sinkage(trot, 0.02), (trot / (4.37e3 / 0.02 + 196.72e3)) ** (1 / 1.6)
    assert round(100 * mud) == 37 and round(100 * snow) == 28 and min(mud, snow) > knee
    assert "sink below the knee in mud and snow" in ROBOTS_DOC


def test_biped_shank_collides_only_above_the_deepest_rut():
    """The biped's penalised shanks collide through a group-3 capsule over their upper part, from the knee down
    0.10 m of axis (r 0.05 m), not through the whole shank capsule, whose end cap reaches the ankle 0.07 m above
    the sole. The soil acts on the soles only, so a shank that touched the soil's surface while the foot sank
    stood on rigid ground. In the stand (shank 0.3 rad from the vertical) the knee is 0.4 cos 0.3 + 0.07 m above
    the sole and the capsule's lowest point 0.10 cos 0.3 + 0.05 m below the knee: 30.7 cm of clearance. The
    deepest curriculum soil is snow (Wong, Table 2.3: n = 1.6, kc = 4.37 kN/m^2.6, kphi = 196.72 kN/m^3.6), where
    single support at 1.5 times the weight (a step's load peak) sinks a 0.22 x 0.096 m sole by
    (1.5 * 41.5 * 9.81 / 0.02112 / (4.37e3 / 0.096 + 196.72e3))^(1 / 1.6) = 26.5 cm."""
    m = model("gente_biped")
    d = mujoco.MjData(m)
    mujoco.mj_resetDataKeyframe(m, d, m.key("stand").id)
    mujoco.mj_kinematics(m, d)
    shank = m.body("left_shank").id
    collision = [g for g in range(m.ngeom) if m.geom_bodyid[g] == shank and m.geom_group[g] == 3]
    assert len(collision) == 1 and m.geom_type[collision[0]] == mujoco.mjtGeom.mjGEOM_CAPSULE
    g = collision[0]
    radius, half = m.geom_size[g, 0], m.geom_size[g, 1]
    axis = d.geom_xmat[g].reshape(3, 3)[:, 2]
    ends = d.geom_xpos[g] + np.outer((-half, half), axis)
    soles = [m.geom(f"left_sole_{c}").id for c in ("toe_l", "toe_r", "heel_l", "heel_r")]
    sole_bottom = min(d.geom_xpos[s, 2] - m.geom_size[s, 0] for s in soles)
    clearance = ends[:, 2].min() - radius - sole_bottom
    knee = d.xanchor[m.joint("left_knee").id]
    by_hand = 0.4 * math.cos(0.3) + 0.07 - (0.10 * math.cos(0.3) + 0.05)
    assert clearance == pytest.approx(by_hand, abs=1e-6) and round(100 * by_hand, 1) == 30.7
    # the capsule's top cap holds the knee: a kneeling biped touches with it
    assert np.linalg.norm(ends - knee, axis=1).min() <= radius
    # its mass stays the shank capsule's: the collision geom is massless
    assert m.body_mass[shank] == pytest.approx(3.0)
    snow = (1.5 * 41.5 * G / (0.22 * 0.096) / (4.37e3 / 0.096 + 196.72e3)) ** (1 / 1.6)
    assert round(100 * snow, 1) == 26.5 and clearance > snow
    assert "(30.7 cm in the stand)" in ROBOTS_DOC


def test_new_robot_doc_numbers():
    # my_robot: base 3.0 kg + 4 legs x (thigh 0.3 + shin 0.1 + foot 0.02) = 4.68 kg
    mass = 3.0 + 4 * (0.3 + 0.1 + 0.02)
    assert round(mass, 1) == 4.7 and "a quarter of its 4.7 kg sinks about 1 cm" in NEW_ROBOT_DOC
    quarter = bekker_sinkage(mass * G / 4 / (math.pi * 0.02**2), 0.02)
    half = bekker_sinkage(mass * G / 2 / (math.pi * 0.02**2), 0.02)
    assert round(100 * quarter) == 1 and round(100 * half) == 4 and "(a trot) about 4 cm" in NEW_ROBOT_DOC
    # stand: hip 0.6, knee -1.2: the foot right below the hip, each 0.12 m segment 0.6 rad from the vertical.
    # The knee (0.12 sin 0.6 = 0.068 m behind the hip) holds a quarter of the weight on the foot below the hip
    knee_torque = mass * G / 4 * 0.12 * math.sin(0.6)
    assert round(knee_torque, 1) == 0.8 and "the knee holds about 0.8 N·m" in NEW_ROBOT_DOC
    # the shin's collision capsule (upper 0.06 m, r 0.015 m) above the sole: knee at 0.02 + 0.12 cos 0.6, capsule
    # end 0.06 cos 0.6 lower, its surface 0.015 lower still: 0.005 + 0.06 cos 0.6 = 5.5 cm ("about 5 cm")
    clearance = 0.02 + 0.12 * math.cos(0.6) - 0.06 * math.cos(0.6) - 0.015
    assert 0.05 <= clearance < 0.06 and "about 5 cm above the sole in the stand" in NEW_ROBOT_DOC
    assert clearance > half  # the shins stay clear even in a trot's rut
    # its base stands at 2 * 0.12 cos 0.6 + 0.02 = 0.218 m before the PD sag; spawned at 0.24 m, a little above
    stand = 2 * 0.12 * math.cos(0.6) + 0.02
    assert 0.21 < stand < 0.24 and "pos = [0.0, 0.0, 0.24]" in NEW_ROBOT_DOC


def stand_quadruped(kp: float, seconds: float):
    """The quadruped's PD stand (the file's kv 1, kp given) from its keyframe on a plane: (times s, sag m, tilt deg)."""
    spec = mujoco.MjSpec.from_file(str(ROBOTS / "gente_quadruped" / "gente_quadruped.xml"))
    spec.worldbody.add_geom(name="floor", type=mujoco.mjtGeom.mjGEOM_PLANE, size=[5, 5, 0.1])
    m = spec.compile()
    m.actuator_gainprm[:, 0], m.actuator_biasprm[:, 1] = kp, -kp
    d = mujoco.MjData(m)
    mujoco.mj_resetDataKeyframe(m, d, m.key("stand").id)
    z0, out = d.qpos[2], []
    for i in range(round(seconds / m.opt.timestep)):
        mujoco.mj_step(m, d)
        out.append(((i + 1) * m.opt.timestep, z0 - d.qpos[2], math.degrees(math.acos(min(1.0, d.xmat[1, 8])))))
    return np.array(out)


def test_quadruped_pd_stand_as_the_doc_says():
    """docs/robots.md: kp 40 sags about 3 cm and pitches about 5 deg in 2 s, settling at 4 cm and 7 deg; it falls
    over (tilted past 90 deg) after the stated times at lower kp."""
    run = stand_quadruped(40.0, 10.0)
    at2, end = run[np.argmin(abs(run[:, 0] - 2.0))], run[-1]
    assert round(100 * at2[1]) == 3 and round(at2[2] / 5) * 5 == 5
    assert round(100 * end[1]) == 4 and round(end[2]) == 7
    stated = re.search(r"falls over after about ([\d.]+) s at kp 32, ([\d.]+) s at kp 30 .*? and ([\d.]+) s at kp 20",
                       ROBOTS_DOC, re.S)
    for kp, seconds in zip((32, 30, 20), stated.groups()):
        run = stand_quadruped(kp, 8.0)
        fallen = run[run[:, 2] > 90.0, 0]
        assert len(fallen) and fallen[0] == pytest.approx(float(seconds), rel=0.15), kp


def walk_on_soil(task: str, preset: str, num_envs: int, bodies: list[str]):
    """The shipped policy of ``task`` commanded straight ahead at 0.5 m/s on ``soil:preset=<preset>`` for 3 s; from
    0.5 s on, per step: the contact force on ``bodies`` (num_envs, len(bodies), 3) and the deepest sole sinkage. Returns
    those and the env (its episode lengths tell whether a robot fell)."""
    import torch
    import warp as wp

    from legged_gente.envs.task_registry import task_registry

    cfg, train_cfg = task_registry.get_cfgs(task)
    cfg.env.num_envs = num_envs
    cfg.terrain.terrain_types, cfg.terrain.terrain_proportions = [f"soil:preset={preset}"], [1.0]
    cfg.terrain.num_rows, cfg.terrain.num_cols = 1, 2
    cfg.terrain.terrain_length = cfg.terrain.terrain_width = 6.0
    cfg.terrain.border_size = 1.0
    cfg.domain_rand.push_robots = False
    ranges = cfg.commands.ranges
    ranges.lin_vel_x, ranges.lin_vel_y, ranges.ang_vel_yaw = [0.5, 0.5], [0.0, 0.0], [0.0, 0.0]
    env, _ = task_registry.make_env(task, env_cfg=cfg)
    runner, _ = task_registry.make_pretrained_runner(env, task, train_cfg)
    policy = runner.get_inference_policy(device=env.device)
    ids = [env.mjm.body(name).id for name in bodies]
    obs, forces, sinkage = env.get_observations(), [], []
    with torch.inference_mode():
        for step in range(150):  # 3 s of 0.02 s steps
            obs, _, _, _ = env.step(policy(obs))
            if step >= 25:
                forces.append(env.contact_forces[:, ids].clone())
                sinkage.append(wp.to_torch(env.forces.foot_sinkage).amax())
    return torch.stack(forces), torch.stack(sinkage), env


@pytest.mark.parametrize("preset", ["mud", "snow"])
def test_shipped_biped_policy_walks_in_soil_on_its_soles(preset):
    """The shipped policy walking at 0.5 m/s, 4 robots, 0.5-3 s: its soles sink deeper than the whole shank
    capsule's end clears them (7 cm), so with the whole capsule colliding a shank carried part of the weight on the
    soil's surface (docs/robots.md, 8 robots: snow 27 % of robot-steps, 22 % of the weight; mud 7 / 6 %). The
    collision capsule over the shank's upper part (30.7 cm up) is never reached."""
    shank_force, sinkage, env = walk_on_soil("gente_biped", preset, 4, ["left_shank", "right_shank"])
    assert env.episode_length_buf.min().item() > 100  # nobody fell and was reset mid-way
    assert sinkage.max().item() > 0.07  # deeper than the whole shank's end cap clears the sole
    assert shank_force.abs().max().item() == 0.0


def test_shipped_quadruped_policy_walks_in_mud_on_its_feet():
    """In mud the quadruped's feet sink deeper than its calves' collision capsules clear them (4.2 cm in the stand,
    9 cm of Bekker sinkage standing, more trotting). Held rigid by the soil's surface, the calves carried about 30 %
    of the weight walking at 0.5 m/s (a calf touching in 26 % of the robot-steps, docs/robots.md). The calves, as
    wide as the foot balls, follow their feet into their ruts (``forces.rut_leg_geom_names``): 8 robots walking
    for 3 s, the feet carry the weight and nobody falls. A calf strikes the ground in a stumble now and then (in
    0.025-0.1 % of the robot-steps of 32 robots, at 231-297 N), so the test bounds the calves' share, not its
    maximum."""
    legs = ("FL", "FR", "RL", "RR")
    force, sinkage, env = walk_on_soil("gente_quadruped", "mud", 8, [f"{leg}_{b}" for b in ("calf", "foot")
                                                                    for leg in legs])
    fz = force[..., 2].abs()  # (steps, robots, calves then feet)
    assert env.episode_length_buf.min().item() > 100
    assert sinkage.max().item() > 0.042 + 0.03  # the feet sink well past the calves' clearance
    calves = fz[..., :4].sum(2)
    assert (calves > 0.0).float().mean().item() < 0.005  # robot-steps with a calf touching (26 % held rigid)
    assert (calves / (14.0 * G)).mean().item() < 0.005  # the calves' share of the weight (30 % held rigid)
    # the feet carry the weight: on average over the steps, within the trot's vertical accelerations
    assert 0.85 < (fz[..., 4:].sum(2) / (14.0 * G)).mean().item() < 1.15
