"""Assemble one MuJoCo model from a robot MJCF, a terrain and the task config, through MjSpec.

Everything robot-specific is resolved by name here (bodies, joints, geoms), with errors that list the
names the MJCF actually has.
"""

from __future__ import annotations

import dataclasses
import fnmatch
import importlib.resources
import warnings
from pathlib import Path

import mujoco
import numpy as np

PACKAGE_ROOT = Path(str(importlib.resources.files("legged_gente")))  # shipped data: resources/robots/...
TERRAIN_GEOM = "terrain"  # the plane; a heightfield's pieces are terrain, terrain_1, terrain_2, ...
ROBOT_CONTYPE, TERRAIN_CONTYPE, TERRAIN_CONAFFINITY = 2, 1, 2
COLLISION_GROUP = 3  # geoms of a watched body that collide in its stead (MuJoCo models' usual collision group)


def resolve_path(path: str) -> Path:
    """An MJCF path as given (absolute, or relative to the working directory), else one shipped with the package
    (``resources/robots/<name>/<name>.xml``); a clear error when neither exists."""
    candidate = Path(path).expanduser()
    if not candidate.is_absolute() and not candidate.exists():
        candidate = PACKAGE_ROOT / candidate
    if not candidate.is_file():
        raise FileNotFoundError(f"robot file {path!r} not found (also looked in {PACKAGE_ROOT}); set cfg.asset.file "
                                f"to an MJCF path.")
    return candidate


def match_names(patterns: list[str], names: list[str], field: str, what: str) -> list[str]:
    """Names matching any fnmatch pattern, in model order; a pattern matching nothing raises with the valid names
    and the config ``field`` that gave it."""
    matched: list[str] = []
    for pattern in patterns:
        hits = [n for n in names if fnmatch.fnmatchcase(n, pattern)]
        if not hits:
            raise ValueError(f"{field}: {what} {pattern!r} matches nothing in the robot; its "
                             f"{'bodies' if what == 'body' else what + 's'} are: {names}")
        matched += [h for h in hits if h not in matched]
    return [n for n in names if n in matched]


def check_patterns(table: dict, names: list[str], what: str) -> None:
    """Every key of a joint-name table must match some joint: a key that matches none is a typo."""
    unused = [p for p in table if not any(fnmatch.fnmatchcase(n, p) or p in n for n in names)]
    if unused:
        raise ValueError(f"{what}: {unused} match no joint of the robot; its joints are: {names}")


def value_for(name: str, table: dict, what: str) -> float:
    """The value of the first pattern in ``table`` matching ``name``; a clear error when none does."""
    for pattern, value in table.items():
        if fnmatch.fnmatchcase(name, pattern) or pattern in name:
            return float(value)
    raise ValueError(f"no {what} given for joint {name!r}; add a matching pattern to the config ({list(table)}).")


@dataclasses.dataclass
class RobotLayout:
    """Indices the env needs, all resolved from names."""

    base_body: int
    joint_names: list[str]  # actuated joints, in actuator order
    qpos_adr: np.ndarray  # per actuated joint
    dof_adr: np.ndarray
    foot_bodies: np.ndarray
    penalized_bodies: np.ndarray
    terminate_bodies: np.ndarray
    hip_joint_ids: np.ndarray  # positions in joint_names
    default_joint_pos: np.ndarray
    joint_limits: np.ndarray  # (n, 2)
    torque_limits: np.ndarray  # (n,)
    terrain_geoms: np.ndarray  # the plane, or the heightfield's pieces


def _body_names(spec_model: mujoco.MjModel) -> list[str]:
    """The robot's bodies (the world body is none of them)."""
    return [spec_model.body(i).name for i in range(1, spec_model.nbody)]


def build_model(cfg, terrain=None) -> tuple[mujoco.MjModel, RobotLayout]:
    """Compile robot + terrain into one MjModel and resolve the robot's names into indices."""
    path = resolve_path(cfg.asset.file)
    try:
        spec = mujoco.MjSpec.from_file(str(path))
        robot = spec.copy().compile()  # the robot as its file has it, before any edit
    except ValueError as error:  # MuJoCo's parse or compile error, which names no file
        reason = " ".join(str(error).removeprefix("Error: ").split())
        raise ValueError(f"robot file {str(path)!r} (cfg.asset.file): MuJoCo cannot load it: {reason}") from None
    _check_robot(robot, cfg)
    _configure_options(spec, cfg.sim)
    _add_terrain(spec, cfg.terrain, terrain)
    bodies = _body_names(robot)
    collide = [*match_names(cfg.asset.penalize_contacts_on, bodies, "cfg.asset.penalize_contacts_on", "body"),
               *match_names(cfg.asset.terminate_after_contacts_on, bodies, "cfg.asset.terminate_after_contacts_on",
                            "body")]
    # Robot geoms collide with the terrain only (contype 2 vs the terrain's conaffinity 2), never with each
    # other: the geoms the MJCF makes collide (feet) plus, on the bodies whose contacts the task watches but
    # that have no colliding geom, their collision geoms (group 3, MuJoCo's usual collision group) if they
    # have any, else all their geoms (a body with collision geoms keeps its visual meshes non-colliding).
    # Their sliding friction is the ground's, cfg.terrain.static_friction, as friction randomisation sets it: MuJoCo
    # takes a pair's friction from the larger (or higher-priority) geom, so the MJCF's foot friction would override
    # the configured ground friction that the friction observation and the force fields' map scaling assume.
    robot_geoms = [g for g in spec.geoms if g.parent.name != spec.worldbody.name]
    has_collider = {g.parent.name for g in robot_geoms if g.contype or g.conaffinity}
    has_collision_group = {g.parent.name for g in robot_geoms if g.group == COLLISION_GROUP}
    for geom in robot_geoms:
        body = geom.parent.name
        switched_on = (body in collide and body not in has_collider
                       and (geom.group == COLLISION_GROUP or body not in has_collision_group))
        collides = geom.contype or geom.conaffinity or switched_on
        geom.contype, geom.conaffinity = (ROBOT_CONTYPE, 0) if collides else (0, 0)
        geom.friction = [cfg.terrain.static_friction, *geom.friction[1:]]
    colliding = {g.parent.name for g in robot_geoms if g.contype}
    feet = match_names(cfg.asset.foot_bodies, bodies, "cfg.asset.foot_bodies", "body")
    passing = [foot for foot in feet if foot not in colliding]
    if passing:
        raise ValueError(f"cfg.asset.foot_bodies: {passing} have no geom that "
                         f"collides (contype and conaffinity 0 on each), so they would pass through the ground and "
                         f"never touch it; give each foot body a collision geom with contype=\"1\" "
                         f"conaffinity=\"1\"")
    if cfg.forces.enabled and cfg.forces.foot_geom_names:
        _check_foot_geoms(spec, cfg.forces.foot_geom_names, feet)
    if owns_sole_contacts(cfg, terrain):
        # the terrain force fields collide sphere / capsule soles, and the legs that follow them into their ruts,
        # with the heightfield analytically (external_forces/contact.py); MuJoCo must not collide them too
        for name in [*cfg.forces.foot_geom_names, *cfg.forces.rut_leg_geom_names]:
            geom = spec.geom(name)
            if geom is not None and geom.type in (mujoco.mjtGeom.mjGEOM_SPHERE, mujoco.mjtGeom.mjGEOM_CAPSULE):
                geom.contype, geom.conaffinity = 0, 0
    _configure_actuators(spec, robot, cfg.control)
    mjm = spec.compile()
    layout = _layout(mjm, cfg)
    if mjm.geom_type[layout.terrain_geoms[0]] == mujoco.mjtGeom.mjGEOM_HFIELD:
        _warn_flat_feet_on_heightfield(mjm, layout.foot_bodies)
    return mjm, layout


def terrain_geom_ids(mjm: mujoco.MjModel) -> np.ndarray:
    """The terrain's geoms: the plane, or the heightfield's pieces (``terrain``, ``terrain_1``, ...)."""
    first = mjm.geom(TERRAIN_GEOM).id
    count = 1
    while first + count < mjm.ngeom and mjm.geom(first + count).name == f"{TERRAIN_GEOM}_{count}":
        count += 1
    return np.arange(first, first + count, dtype=np.int64)


def owns_sole_contacts(cfg, terrain) -> bool:
    """Whether the terrain force fields own the soles' terrain contacts (a heightfield terrain, forces on,
    ``forces.sole_contact``): then the env must install them even on a terrain without water or soil."""
    forces = getattr(cfg, "forces", None)
    return (terrain is not None and forces is not None and bool(getattr(forces, "enabled", True))
            and bool(forces.sole_contact) and bool(forces.foot_geom_names))


def _warn_flat_feet_on_heightfield(mjm: mujoco.MjModel, foot_bodies: np.ndarray) -> None:
    """Heightfield collisions (prism by prism, general convex solver) give boxes and meshes that sink ~1 cm
    contacts with downward normals, which launch the foot; spheres stay correct (docs/robots.md)."""
    flat = {int(mujoco.mjtGeom.mjGEOM_BOX), int(mujoco.mjtGeom.mjGEOM_MESH)}
    bad = [mjm.geom(g).name or f"geom {g}" for g in range(mjm.ngeom)
           if mjm.geom_bodyid[g] in foot_bodies and mjm.geom_contype[g] and int(mjm.geom_type[g]) in flat]
    if bad:
        warnings.warn(f"foot geoms {bad} collide with the heightfield terrain as boxes/meshes, whose heightfield "
                      f"contacts go wrong once they sink ~1 cm (feet get launched); collide through spheres at the "
                      f"sole's corners instead (see docs/robots.md, 'Why sphere soles').", stacklevel=3)


def _check_foot_geoms(spec: mujoco.MjSpec, names: list[str], feet: list[str]) -> None:
    """The force fields' foot geoms are the feet's soles: each foot of ``asset.foot_bodies`` has some, and none is
    elsewhere. A foot left out would get no soil and touch the terrain through MuJoCo's contacts while the others
    use the sole contacts; a geom elsewhere would press ruts for no foot. (A name that is no geom is
    TerrainForces' error.)"""
    body_of = {name: spec.geom(name).parent.name for name in names if spec.geom(name) is not None}
    stray = [name for name, body in body_of.items() if body not in feet]
    if stray:
        raise ValueError(f"forces.foot_geom_names: {stray} are on {sorted({body_of[n] for n in stray})}, no foot of "
                         f"cfg.asset.foot_bodies ({feet}); list the feet's sole geoms only")
    bare = [foot for foot in feet if foot not in body_of.values()]
    if bare and body_of:
        raise ValueError(f"forces.foot_geom_names lists no geom of the feet {bare} of cfg.asset.foot_bodies: they "
                         f"would get no soil and touch the terrain through MuJoCo's contacts while the others use the "
                         f"sole contacts; list each foot's sole geoms")


def _check_robot(robot: mujoco.MjModel, cfg) -> None:
    """Errors a robot file from elsewhere (e.g. MuJoCo Menagerie) commonly has, each with its fix."""
    free = [j for j in range(robot.njnt) if robot.jnt_type[j] == mujoco.mjtJoint.mjJNT_FREE]
    if len(free) != 1:
        raise ValueError(f"the robot in {cfg.asset.file!r} needs exactly one free joint (floating base), found "
                         f"{len(free)}; " + (
                             "in a URDF the floating base is a joint of type \"floating\" from a link named "
                             "\"world\" to the root link: add both." if str(cfg.asset.file).lower().endswith(
                                 ".urdf") else "add <freejoint/> to its root body."))
    if robot.jnt_qposadr[free[0]] != 0:
        raise ValueError(f"the free joint of {cfg.asset.file!r} must come first in qpos; put the robot's root body "
                         f"first in the worldbody.")
    ground = [robot.geom(g).name or f"geom {g}" for g in range(robot.ngeom) if robot.geom_bodyid[g] == 0]
    if ground:
        raise ValueError(f"{cfg.asset.file!r} has geoms on the worldbody {ground} (a floor?); the env adds the "
                         f"terrain: point cfg.asset.file at the robot's own MJCF, not at a scene file.")
    if cfg.asset.base_body and mujoco.mj_name2id(robot, mujoco.mjtObj.mjOBJ_BODY, cfg.asset.base_body) < 0:
        raise ValueError(f"cfg.asset.base_body={cfg.asset.base_body!r} is not a body of the robot; its bodies are: "
                         f"{_body_names(robot)}")
    for a in range(robot.nu):  # the env's actions are joint targets: one PD actuator per joint, nothing else
        kind = mujoco.mjtTrn(robot.actuator_trntype[a])
        if kind != mujoco.mjtTrn.mjTRN_JOINT:
            raise ValueError(f"actuator {robot.actuator(a).name or a!r} drives a {kind.name[6:].lower()}; legged_gente "
                             f"drives joints only (a PD position actuator per joint, made from the config's gains): "
                             f"remove it from {cfg.asset.file!r}")
    drivers: dict[int, list[str]] = {}
    for a in range(robot.nu):
        drivers.setdefault(int(robot.actuator_trnid[a, 0]), []).append(robot.actuator(a).name or f"actuator {a}")
    for j, names in drivers.items():
        if len(names) > 1:
            raise ValueError(f"joint {robot.joint(j).name!r} is driven by {len(names)} actuators {names} in "
                             f"{cfg.asset.file!r}; legged_gente gives each joint one PD actuator (one action each): "
                             f"keep one each")
    joints = [robot.joint(j).name for j in range(robot.njnt) if robot.jnt_type[j] != mujoco.mjtJoint.mjJNT_FREE]
    check_patterns(cfg.control.stiffness, joints, "cfg.control.stiffness")
    check_patterns(cfg.control.damping, joints, "cfg.control.damping")
    check_patterns(cfg.init_state.default_joint_angles, joints, "cfg.init_state.default_joint_angles")


def _configure_options(spec: mujoco.MjSpec, sim) -> None:
    integrators = {"euler": mujoco.mjtIntegrator.mjINT_EULER, "implicitfast": mujoco.mjtIntegrator.mjINT_IMPLICITFAST}
    solvers = {"newton": mujoco.mjtSolver.mjSOL_NEWTON, "cg": mujoco.mjtSolver.mjSOL_CG}
    cones = {"pyramidal": mujoco.mjtCone.mjCONE_PYRAMIDAL, "elliptic": mujoco.mjtCone.mjCONE_ELLIPTIC}
    for key, table in (("integrator", integrators), ("solver", solvers), ("cone", cones)):
        if getattr(sim, key) not in table:
            raise ValueError(f"cfg.sim.{key}={getattr(sim, key)!r} is not supported; use one of {list(table)}.")
    spec.option.timestep = sim.dt
    spec.option.gravity = sim.gravity
    spec.option.integrator = integrators[sim.integrator]
    spec.option.solver = solvers[sim.solver]
    spec.option.cone = cones[sim.cone]
    spec.option.iterations = sim.iterations
    spec.option.ls_iterations = sim.ls_iterations


def _add_ground_look(spec: mujoco.MjSpec) -> str:
    """A 1 m checker material for the terrain and a shadow-casting sun, so a rendered gait is visible on any
    terrain (rendering only: no effect on the physics). Returns the material's name."""
    spec.add_texture(name="terrain_checker", type=mujoco.mjtTexture.mjTEXTURE_2D,
                     builtin=mujoco.mjtBuiltin.mjBUILTIN_CHECKER, rgb1=[0.62, 0.64, 0.66], rgb2=[0.42, 0.45, 0.48],
                     mark=mujoco.mjtMark.mjMARK_EDGE, markrgb=[0.3, 0.3, 0.3], width=256, height=256)
    material = spec.add_material(name="terrain_checker", texrepeat=[0.5, 0.5], texuniform=True, reflectance=0.05)
    material.textures[mujoco.mjtTextureRole.mjTEXROLE_RGB] = "terrain_checker"  # builtin checker: 2 x 2 squares
    spec.worldbody.add_light(name="sun", type=mujoco.mjtLightType.mjLIGHT_DIRECTIONAL, pos=[0, 0, 20],
                             dir=[0.3, 0.4, -1.0], castshadow=True, diffuse=[0.7, 0.7, 0.7])
    return "terrain_checker"


def _add_terrain(spec: mujoco.MjSpec, cfg_terrain, terrain) -> None:
    friction = [cfg_terrain.static_friction, 0.005, 0.0001]
    material = _add_ground_look(spec)
    if terrain is None:
        spec.worldbody.add_geom(name=TERRAIN_GEOM, type=mujoco.mjtGeom.mjGEOM_PLANE, size=[0, 0, 0.05],
                                friction=friction, contype=TERRAIN_CONTYPE, conaffinity=TERRAIN_CONAFFINITY,
                                material=material)
        return
    heights = np.asarray(terrain.height_field, dtype=np.float64)
    res = terrain.resolution
    ox, oy = terrain.origin_xy
    # MuJoCo-Warp's heightfield collision loses float32 precision with the distance from the heightfield's
    # centre: a capsule 6 cm into flat ground 30 m from it gets a contact 1.3 m deep, and the robot is launched
    # (tests/test_env_terrain.py). The terrain is therefore laid down as pieces of at most hfield_piece_size,
    # each a geom centred on its own patch; neighbours share their edge samples, so the surface is unchanged.
    cells = max(1, round(cfg_terrain.hfield_piece_size / res))  # whole cells (int() would make 0.3 / 0.1 two)
    pieces = [(i, j) for i in _piece_starts(heights.shape[0], cells) for j in _piece_starts(heights.shape[1], cells)]
    for index, (i, j) in enumerate(pieces):
        patch = heights[i:i + cells + 1, j:j + cells + 1]
        nx, ny = patch.shape
        h_min = float(patch.min())
        # MuJoCo rescales any non-flat data to [0, 1] itself, so the elevation must be the patch's exact relief (a
        # floor on it would raise sub-millimetre relief); a flat patch (data all 0) needs just some elevation > 0
        span = float(patch.max()) - h_min or 1e-3
        half_x, half_y = (nx - 1) * res / 2, (ny - 1) * res / 2
        name = TERRAIN_GEOM if index == 0 else f"{TERRAIN_GEOM}_{index}"
        # MuJoCo hfield rows run along y and columns along x; elevation data are normalised to [0, 1].
        hfield = spec.add_hfield(name=f"{name}_hfield", nrow=ny, ncol=nx, size=[half_x, half_y, span, 1.0])
        hfield.userdata = ((patch.T - h_min) / span).ravel().tolist()
        spec.worldbody.add_geom(name=name, type=mujoco.mjtGeom.mjGEOM_HFIELD, hfieldname=f"{name}_hfield",
                                pos=[ox + i * res + half_x, oy + j * res + half_y, h_min], friction=friction,
                                contype=TERRAIN_CONTYPE, conaffinity=TERRAIN_CONAFFINITY, material=material)


def _piece_starts(samples: int, cells: int) -> range:
    """First sample of each piece along one axis: pieces of ``cells`` cells (the last one shorter) cover the
    ``samples - 1`` cells of the axis."""
    return range(0, max(samples - 1, 1), cells)


def _configure_actuators(spec: mujoco.MjSpec, robot: mujoco.MjModel, control) -> None:
    """PD position actuators on every actuated joint, gains from the config by joint-name pattern.

    Joints that have no actuator in the MJCF get one. Torque limits: the joint's actuatorfrcrange, else the joint
    torque the MJCF's actuator could give: MuJoCo clamps an actuator's force (gain x ctrl for a torque motor, as in
    MuJoCo Menagerie models) to its forcerange, then applies its gear (MuJoCo XML reference, actuator/general), so
    gear x forcerange and, for a motor with a ctrlrange, gear x gain x ctrlrange, whichever is narrower. The PD
    actuator has gear 1.
    """
    existing = {a.target: (i, a) for i, a in enumerate(spec.actuators)}
    for joint in spec.joints:
        if joint.type == mujoco.mjtJoint.mjJNT_FREE:
            continue
        kp = value_for(joint.name, control.stiffness, "stiffness (cfg.control.stiffness)")
        kd = value_for(joint.name, control.damping, "damping (cfg.control.damping)")
        index, actuator = existing.get(joint.name) or (None, spec.add_actuator(
            name=joint.name, target=joint.name, trntype=mujoco.mjtTrn.mjTRN_JOINT))
        if index is not None:
            gear = float(robot.actuator_gear[index, 0])
            ranges = []  # joint torques the actuator can give, each [low, high]
            if robot.actuator_forcelimited[index]:
                ranges.append(np.sort(robot.actuator_forcerange[index] * gear))
            if robot.actuator_biastype[index] == mujoco.mjtBias.mjBIAS_NONE and robot.actuator_ctrllimited[index]:
                ranges.append(np.sort(robot.actuator_ctrlrange[index] * robot.actuator_gainprm[index, 0] * gear))
            if ranges:
                actuator.forcelimited = 1
                actuator.forcerange = [max(r[0] for r in ranges), min(r[1] for r in ranges)]
        actuator.gear = [1.0] + [0.0] * 5  # ctrl is the joint angle target itself
        actuator.gaintype = mujoco.mjtGain.mjGAIN_FIXED
        actuator.biastype = mujoco.mjtBias.mjBIAS_AFFINE
        actuator.gainprm = [kp] + [0.0] * 9
        actuator.biasprm = [0.0, -kp, -kd] + [0.0] * 7
        actuator.ctrllimited = 0
        frc = robot.jnt_actfrcrange[robot.joint(joint.name).id]
        if robot.jnt_actfrclimited[robot.joint(joint.name).id]:
            actuator.forcelimited = 1
            actuator.forcerange = list(frc)


def _layout(mjm: mujoco.MjModel, cfg) -> RobotLayout:
    bodies = _body_names(mjm)
    free = [j for j in range(mjm.njnt) if mjm.jnt_type[j] == mujoco.mjtJoint.mjJNT_FREE]
    base = mjm.body(cfg.asset.base_body).id if cfg.asset.base_body else int(mjm.jnt_bodyid[free[0]])
    joint_ids = [int(mjm.actuator_trnid[a, 0]) for a in range(mjm.nu)]
    joint_names = [mjm.joint(j).name for j in joint_ids]
    asset = cfg.asset

    def body_ids(field: str) -> np.ndarray:
        names = match_names(getattr(asset, field), bodies, f"cfg.asset.{field}", "body")
        return np.array([mjm.body(n).id for n in names], dtype=np.int64)

    defaults = np.array([value_for(n, cfg.init_state.default_joint_angles, "default angle") if
                         cfg.init_state.default_joint_angles else 0.0 for n in joint_names])
    # an unlimited joint (range [0, 0] in MjModel) has no limits
    limits = np.array([mjm.jnt_range[j] if mjm.jnt_limited[j] else (-np.inf, np.inf) for j in joint_ids])
    outside = [f"{n}={q:g} outside its range [{lo:g}, {hi:g}]"
               for n, q, (lo, hi) in zip(joint_names, defaults, limits) if not lo <= q <= hi]
    if outside:  # a reset would clamp the joint while its PD target stays outside, pressing it into its limit
        raise ValueError(f"cfg.init_state.default_joint_angles puts {', '.join(outside)}; give an angle inside the "
                         f"joint's range (check the joint's sign)")
    feet, terminate = body_ids("foot_bodies"), body_ids("terminate_after_contacts_on")
    ending = [mjm.body(int(b)).name for b in feet if b in terminate]
    if ending:
        raise ValueError(f"cfg.asset.terminate_after_contacts_on includes the feet {ending} (cfg.asset.foot_bodies): "
                         f"every touchdown would end the episode as a fall; leave the feet out")
    unlimited = [n for a, n in enumerate(joint_names) if not mjm.actuator_forcelimited[a]]
    if unlimited:  # a PD actuator with no force range pushes as hard as its error asks: no real motor does
        warnings.warn(f"joints {unlimited} have no torque limit: their PD torque is unbounded; give them "
                      f"actuatorfrcrange in {cfg.asset.file!r} (or their actuators a forcerange)", stacklevel=2)
    hips = match_names(asset.hip_joints, joint_names, "cfg.asset.hip_joints", "joint")
    return RobotLayout(
        base_body=base,
        joint_names=joint_names,
        qpos_adr=np.array([mjm.jnt_qposadr[j] for j in joint_ids], dtype=np.int64),
        dof_adr=np.array([mjm.jnt_dofadr[j] for j in joint_ids], dtype=np.int64),
        foot_bodies=feet,
        penalized_bodies=body_ids("penalize_contacts_on"),
        terminate_bodies=terminate,
        hip_joint_ids=np.array([joint_names.index(h) for h in hips], dtype=np.int64),
        default_joint_pos=defaults,
        joint_limits=limits,
        torque_limits=np.array([mjm.actuator_forcerange[a, 1] if mjm.actuator_forcelimited[a] else np.inf
                                for a in range(mjm.nu)]),
        terrain_geoms=terrain_geom_ids(mjm),
    )
