"""Warp kernels of the terrain force fields (soil, friction, noise; the water kernels are in ``water.py``).

The ``*_fn`` functions are the device twins of the numpy references in ``models.py`` (same names without
the suffix) and are tested against them. The kernels are launched by ``field.TerrainForces`` from
mujoco_warp's ``contactfilter`` and ``passive`` callbacks and after each ``mjw.step``; they never read
anything back to the host, so the whole substep can be captured in a CUDA graph.

Conventions (mujoco_warp 4.0, read from its source): ``xfrc_applied[w, b]`` is a spatial_vector
(force, torque) in world frame, the force acting at the body's centre of mass ``xipos``;
``cvel[w, b]`` is (angular, linear) velocity with the linear part taken at ``subtree_com`` of the body's
root, so the velocity of a world point p on body b is lin + ang x (p - subtree_com[root(b)]).
"""

from __future__ import annotations

import warp as wp
from mujoco_warp._src.support import contact_force_fn
from mujoco_warp._src.types import vec5

# Soil parameter columns (same order as soil.PARAM_NAMES, then the model).
KC, KPHI, N, COH, MU, K, BULL_C, BULL_G, ZETA, MODEL = 0, 1, 2, 3, 4, 5, 6, 7, 8, 9
NSOILPARAM = 10
"""The columns of ``soil.preset_table``: its PARAM_NAMES, then the model (1: RFT)."""
OBS_NAMES = ("water_depth", "flow_x", "flow_y", "on_soil", "sinkage", "normal_force_100N", "kc_1e4", "kphi_1e6", "n",
             "cohesion_1e4Pa", "tan_phi", "K_cm")
"""Privileged observation values per foot, in ``foot_obs_kernel``'s order and scale (``_1e4``: divided by 1e4),
see :meth:`field.TerrainForces.privileged_obs`."""
OBS_PER_FOOT = len(OBS_NAMES)

PI = wp.constant(3.14159265358979)
# where an analytic sole contact's foot is (``foot_near``, bits; 0: clear of the ground):
ON_FLOOR = wp.constant(1)  # within liftoff_clearance of the floor it stands on (its rut's, or the ground)
IN_RUT = wp.constant(2)  # below the unlowered ground: still in its rut


# --------------------------------------------------------------------------------------------------------
# Formulas (device twins of models.py)


@wp.func
def cylinder_drag_fn(rho: float, cd: float, radius: float, length: float, speed: float, paper_area: int) -> float:
    """Morison / Hoerner drag magnitude; projected area 2rL, or the paper's 2*pi*r*L when paper_area != 0."""
    area = 2.0 * radius * length
    if paper_area != 0:
        area = 2.0 * PI * radius * length
    return 0.5 * cd * rho * area * speed * speed


@wp.func
def flow_force_fn(kind: int, t: float, amplitude: float, omega: float, phase: float) -> float:
    """GenTe flow term: still (0) -> 0, current (1) -> A, tide (2) -> A cos(omega t + phase)."""
    if kind == 1:
        return amplitude
    if kind == 2:
        return amplitude * wp.cos(omega * t + phase)
    return 0.0


@wp.func
def flow_rate_fn(kind: int, t: float, amplitude: float, omega: float, phase: float) -> float:
    """Time derivative of flow_force_fn (for the added-mass relative acceleration)."""
    if kind == 2:
        return -amplitude * omega * wp.sin(omega * t + phase)
    return 0.0


@wp.func
def bekker_sinkage_fn(pressure: float, kc: float, kphi: float, n: float, width: float) -> float:
    """Bekker (1969): z = (p / (kc/b + kphi))^(1/n); 0 for p <= 0."""
    if pressure <= 0.0:
        return 0.0
    return wp.pow(pressure / (kc / width + kphi), 1.0 / n)


@wp.func
def rft_sinkage_fn(pressure: float, zeta: float, support: float) -> float:
    """RFT sinkage z = p / (support zeta), the support at least 1e-6; 0 for p <= 0 (``models.rft_sinkage``)."""
    if pressure <= 0.0:
        return 0.0
    return pressure / (zeta * wp.max(support, 1.0e-6))


@wp.func
def rut_sinkage_fn(pressure: float, soil_params: wp.array3d[float], w: int, s: int, width: float,
                   support: float) -> float:
    """The depth of the rut that carries ``pressure`` in soil s of world w: Bekker's sinkage, or on an RFT soil
    the depth whose vertical RFT stress (``support`` zeta, the sole's current motion) carries it."""
    if soil_params[w, s, MODEL] > 0.5:
        return rft_sinkage_fn(pressure, soil_params[w, s, ZETA], support)
    return bekker_sinkage_fn(pressure, soil_params[w, s, KC], soil_params[w, s, KPHI], soil_params[w, s, N], width)


@wp.func
def bulldozing_force_fn(bulldoze_c: float, bulldoze_g: float, width: float, sinkage: float) -> float:
    """Bekker's bulldozing resistance b (0.67 c K_pc z + 0.5 gamma K_pgamma z^2)."""
    z = wp.max(sinkage, 0.0)
    return width * (bulldoze_c * z + bulldoze_g * z * z)


@wp.func
def bulldozing_width_fn(xm: wp.mat33, vh: wp.vec3, length: float, width: float, disc: int) -> float:
    """Bekker's b of bulldozing: the width of the soil face the sole pushes, its footprint projected across the
    horizontal motion vh (Bekker 1969; Wong, Theory of Ground Vehicles, ch. 2). A disc: its diameter. A rectangle (length
    along the foot body's x axis, width along its y axis): length |x.n| + width |y.n|, n horizontal and normal to
    vh. At rest (no force then) the smaller side."""
    if disc != 0:
        return length
    speed = wp.length(vh)
    if speed < 1.0e-9:
        return wp.min(length, width)
    n = wp.vec3(-vh[1], vh[0], 0.0) / speed
    x_axis = wp.vec3(xm[0, 0], xm[1, 0], xm[2, 0])
    y_axis = wp.vec3(xm[0, 1], xm[1, 1], xm[2, 1])
    return length * wp.abs(wp.dot(x_axis, n)) + width * wp.abs(wp.dot(y_axis, n))


@wp.func
def shear_strength_fn(c: float, mu: float, area: float, normal_force: float) -> float:
    """Mohr-Coulomb: c A + F_N tan(phi)."""
    return c * area + wp.max(normal_force, 0.0) * mu


@wp.func
def soil_traction_fn(c: float, mu: float, area: float, normal_force: float, slip: float, k: float) -> float:
    """Janosi-Hanamoto: (c A + F_N tan phi)(1 - exp(-j/K))."""
    return shear_strength_fn(c, mu, area, normal_force) * (1.0 - wp.exp(-wp.max(slip, 0.0) / k))


@wp.func
def soil_friction_fn(c: float, mu: float, area: float, normal_force: float, slip: float, k: float,
                     surface_mu: float, bulldozing: float, cap: float) -> float:
    """The contact friction coefficient of a sole on soil: min(surface_mu, mobilised traction / F_N) plus the
    bulldozing resistance / F_N, at most cap.

    The shear is the weaker of the sole's interface (the cell's friction: ice under snow) and the soil; Bekker's
    bulldozing is the soil's passive pressure on the sunk sole's leading face, not shear, so it adds to either.
    Both are rate-independent: in the friction limit MuJoCo's solver applies them implicitly (an explicit force
    against the velocity is a stiff damper near rest and makes a foot held still chatter)."""
    fn = wp.max(normal_force, 1.0e-6)
    shear = wp.min(surface_mu, soil_traction_fn(c, mu, area, fn, slip, k) / fn)
    return wp.min(shear + bulldozing / fn, cap)


# --------------------------------------------------------------------------------------------------------
# Helpers


@wp.func
def cell_of(p: wp.vec3, origin: wp.vec2, resolution: float, nx: int, ny: int) -> wp.vec2i:
    """Nearest heightfield cell of world point p (clamped to the grid: the terrain's border covers it)."""
    i = int(wp.round((p[0] - origin[0]) / resolution))
    j = int(wp.round((p[1] - origin[1]) / resolution))
    return wp.vec2i(wp.clamp(i, 0, nx - 1), wp.clamp(j, 0, ny - 1))


@wp.func
def point_velocity(
    cvel: wp.array2d[wp.spatial_vector],
    subtree_com: wp.array2d[wp.vec3],
    body_rootid: wp.array[int],
    w: int,
    b: int,
    p: wp.vec3,
) -> wp.vec3:
    v = cvel[w, b]
    ang = wp.vec3(v[0], v[1], v[2])
    lin = wp.vec3(v[3], v[4], v[5])
    return lin + wp.cross(ang, p - subtree_com[w, body_rootid[b]])


@wp.func
def sole_point(xpos: wp.array2d[wp.vec3], xmat: wp.array2d[wp.mat33], w: int, b: int, offset: wp.vec3) -> wp.vec3:
    """World position of a foot's sole centre, ``offset`` in its body's frame."""
    return xpos[w, b] + xmat[w, b] @ offset


@wp.func
def apply_force(
    xfrc: wp.array2d[wp.spatial_vector], xipos: wp.array2d[wp.vec3], w: int, b: int, f: wp.vec3, p: wp.vec3
):
    """Add force f acting at world point p to body b: force plus its torque about the body's CoM."""
    t = wp.cross(p - xipos[w, b], f)
    wp.atomic_add(xfrc, w, b, wp.spatial_vector(f, t))


@wp.func
def flow_velocity(
    kind: int, t: float, speed: float, direction: float, omega: float, phase: float, xi: float
) -> wp.vec3:
    u = xi * flow_force_fn(kind, t, speed, omega, phase)
    return wp.vec3(u * wp.cos(direction), u * wp.sin(direction), 0.0)


@wp.struct
class WaterMap:
    """The water layer of the MaterialMap on the device, with the grid's placement (one kernel argument)."""

    origin: wp.vec2
    resolution: float
    surface: wp.array2d[float]
    flow_kind: wp.array2d[int]
    flow_speed: wp.array2d[float]
    flow_dir: wp.array2d[float]
    flow_omega: wp.array2d[float]
    flow_phase: wp.array2d[float]


@wp.func
def water_cell(water: WaterMap, p: wp.vec3) -> wp.vec2i:
    return cell_of(p, water.origin, water.resolution, water.surface.shape[0], water.surface.shape[1])


@wp.func
def water_flow(water: WaterMap, cell: wp.vec2i, t: float, xi: float) -> wp.vec3:
    """Flow velocity in the cell at time t, times the per-step flow noise xi."""
    i = cell[0]
    j = cell[1]
    return flow_velocity(water.flow_kind[i, j], t, water.flow_speed[i, j], water.flow_dir[i, j],
                         water.flow_omega[i, j], water.flow_phase[i, j], xi)


# --------------------------------------------------------------------------------------------------------
# Noise and per-episode draws


@wp.kernel
def reset_kernel(
    mask: wp.array[bool],
    seed: int,
    counter: wp.array[int],
    noise_std: float,
    soil_table: wp.array3d[float],  # (npreset, NSOILPARAM, 2) mean, std
    eps: wp.array[float],
    soil_params: wp.array3d[float],  # (nworld, npreset, NSOILPARAM)
    foot_slip: wp.array2d[float],
    foot_air: wp.array2d[float],
    foot_sinkage: wp.array2d[float],
    foot_load: wp.array2d[float],
    foot_sink_load: wp.array2d[float],
    foot_traction_load: wp.array2d[float],
    foot_stance: wp.array2d[float],
    foot_support: wp.array2d[float],
):
    """Per-env episode draws: eps ~ N(1, noise_std) and soil parameters ~ N(mean, std) of each preset; the
    feet's soil state (slip, rut, load, RFT support: the value of a sole at rest) starts afresh.

    Draws are truncated below at 10 % of the mean so eps (a drag that never pushes along the motion, a buoyancy
    that never pulls down) and kphi, n, K stay positive (documented in docs).
    """
    w = wp.tid()
    if not mask[w]:
        return
    state = wp.rand_init(seed, w + eps.shape[0] * counter[0])
    eps[w] = wp.max(1.0 + noise_std * wp.randn(state), 0.1)
    for s in range(soil_table.shape[0]):
        for q in range(NSOILPARAM):
            mean = soil_table[s, q, 0]
            value = mean + soil_table[s, q, 1] * wp.randn(state)
            floor = 0.1 * mean
            if mean > 0.0 and value < floor:
                value = floor
            soil_params[w, s, q] = value
    for f in range(foot_slip.shape[1]):
        foot_slip[w, f] = 0.0
        foot_air[w, f] = 1.0e6
        foot_sinkage[w, f] = 0.0
        foot_load[w, f] = 0.0
        foot_sink_load[w, f] = 0.0
        foot_traction_load[w, f] = 0.0
        foot_stance[w, f] = 0.0
        foot_support[w, f] = 1.0


@wp.kernel
def flow_noise_kernel(seed: int, counter: wp.array[int], noise_std: float, xi: wp.array[float]):
    """xi ~ N(1, noise_std) per env, redrawn each policy step (the paper's xi(t)), at least 0.1 (the flow keeps its
    direction)."""
    w = wp.tid()
    state = wp.rand_init(seed + 7919, w + xi.shape[0] * counter[0])
    xi[w] = wp.max(1.0 + noise_std * wp.randn(state), 0.1)


@wp.kernel
def increment_kernel(counter: wp.array[int]):
    counter[0] = counter[0] + 1


# --------------------------------------------------------------------------------------------------------
# Soil and ground friction (contact filter)


@wp.kernel
def foot_cell_kernel(
    foot_body: wp.array[int],
    foot_offset: wp.array[wp.vec3],
    xpos: wp.array2d[wp.vec3],
    xmat: wp.array2d[wp.mat33],
    origin: wp.vec2,
    resolution: float,
    soil: wp.array2d[int],
    use_soil: int,
    foot_soil: wp.array2d[int],
    foot_touch: wp.array2d[int],
    foot_cand: wp.array2d[float],
    foot_near: wp.array2d[int],
    foot_fn: wp.array2d[float],
):
    """Each foot's soil: the cell under its sole centre (one writer per foot: deterministic at soil borders). The
    substep's findings start cleared: contact and rut flags, the rut's candidate depth, and the normal force that
    ``normal_force_kernel`` sums after the step (the last substep's stays readable until the next begins)."""
    w, f = wp.tid()
    foot_touch[w, f] = 0
    foot_cand[w, f] = 0.0
    foot_near[w, f] = 0
    foot_fn[w, f] = 0.0
    s = int(-1)
    if use_soil != 0:
        p = sole_point(xpos, xmat, w, foot_body[f], foot_offset[f])
        cell = cell_of(p, origin, resolution, soil.shape[0], soil.shape[1])
        s = soil[cell[0], cell[1]]
    foot_soil[w, f] = s


@wp.struct
class SoilMap:
    """The soil and friction layers of the MaterialMap on the device, with the grid's placement."""

    origin: wp.vec2
    resolution: float
    soil: wp.array2d[int]
    friction: wp.array2d[float]


@wp.struct
class FootSoil:
    """What a foot's ground contact reads besides the maps: the map-friction and soil settings of ForcesConfig
    and each foot's soil state (per world and foot), shared by the contact filter and the sole contacts."""

    friction_reference: float  # the ground geom's friction, the map's 1.0
    use_friction: int
    use_soil: int
    sole_area: float
    bekker_width: float  # Bekker's b: a rectangle's smaller side, a disc's radius
    bulldozing_face: float  # the width of soil a sole pushes: a rectangle's smaller side, a disc's diameter
    friction_cap: float
    min_friction: float
    sink_step: float  # sinkage_rate * dt
    liftoff_clearance: float
    soil_params: wp.array3d[float]
    load: wp.array2d[float]  # F_N low-passed over sinkage_load_tau (foot_state_kernel)
    sink_load: wp.array2d[float]  # load low-passed again over sinkage_load_tau: what the rut deepens under
    traction_load: wp.array2d[float]  # F_N averaged over the stance, over traction_load_tau (foot_state_kernel)
    support: wp.array2d[float]
    slip: wp.array2d[float]
    sinkage: wp.array2d[float]
    soil: wp.array2d[int]  # the soil under the foot: an index into soil_params, -1 off soil


@wp.struct
class LegSoil:
    """Each rut leg's own soil state (per world and leg; ``ForcesConfig.rut_leg_geom_names``): its rut, pressed by
    its own contacts' low-passed load, and what this substep's sole contacts found for it (its deepest rut
    candidate, whether it touched soil, whether it is still below the unlowered surface), which
    ``leg_state_kernel`` takes in and clears after the step."""

    load: wp.array2d[float]  # F_N low-passed over sinkage_load_tau
    sink_load: wp.array2d[float]  # load low-passed again: what the rut deepens under (as a foot's)
    sinkage: wp.array2d[float]
    cand: wp.array2d[float]
    touch: wp.array2d[int]
    inrut: wp.array2d[int]


@wp.func
def ground_friction(fr: vec5, cell: wp.vec2i, f: int, w: int, soilmap: SoilMap, feet: FootSoil) -> vec5:
    """Tangential friction of a ground contact in ``cell``: the rigid friction scaled by the cell's map friction;
    on soil, at most what the soil's shear strength gives (Mohr-Coulomb): under a foot ``f`` (>= 0) its mobilised
    traction / F (Janosi-Hanamoto); under any other body (a knee, a shank, a fallen trunk), whose contact area is
    unknown, tan(phi), the strength without its cohesion share (exact on a cohesionless sand, low on a mud).
    The torsional friction (condim 4, 6) scales with the sliding one: the spin torque a contact patch holds is
    Coulomb friction too, proportional to mu (a uniformly pressed disc of radius a: the integral of mu p r dA is
    (2/3) mu N a).

    F is the larger of the foot's load low-passed over sinkage_load_tau (50 ms: it follows a load rise within a
    few substeps) and its mean over the stance (traction_load_tau, 0.3 s): a sliding contact hops (MuJoCo's soft
    cones push a sliding body up: F_N is 0 in most substeps and several times the weight in the others), and in
    each hop the fast load sags, so that c A / F was largest at the landings' impacts and the friction force
    mu F_N averaged to more than c A + W tan(phi) (1.6 T at 2 m/s on a mud); the stance's mean holds F there."""
    mu0 = fr[0]
    mu = mu0
    if feet.use_friction != 0:
        mu = mu * soilmap.friction[cell[0], cell[1]] / feet.friction_reference
    s = soilmap.soil[cell[0], cell[1]]
    if feet.use_soil != 0 and s >= 0:
        p = feet.soil_params
        if f >= 0:
            bulldozing = bulldozing_force_fn(p[w, s, BULL_C], p[w, s, BULL_G], feet.bulldozing_face,
                                             feet.sinkage[w, f])
            load = wp.max(feet.load[w, f], feet.traction_load[w, f])
            mu = soil_friction_fn(p[w, s, COH], p[w, s, MU], feet.sole_area, load, feet.slip[w, f],
                                  p[w, s, K], mu, bulldozing, feet.friction_cap)
        else:
            mu = wp.min(mu, p[w, s, MU])
    if mu0 > 0.0:
        fr[2] = fr[2] * mu / mu0
    fr[0] = mu
    fr[1] = mu
    return fr


@wp.kernel
def contact_filter_kernel(
    nacon: wp.array[int],
    geom_foot: wp.array[int],  # ngeom: foot index or -1
    geom_bodyid: wp.array[int],
    soilmap: SoilMap,
    feet: FootSoil,
    max_rut: float,
    max_depth: float,
    # contacts (modified)
    contact_pos: wp.array[wp.vec3],
    contact_geom: wp.array[wp.vec2i],
    contact_worldid: wp.array[int],
    contact_dist: wp.array[float],
    contact_friction: wp.array[vec5],
    contact_dim: wp.array[int],
    # out
    foot_touch: wp.array2d[int],
    foot_cand: wp.array2d[float],
):
    """MuJoCo's ground contacts are at most max_depth deep (``ForcesConfig.terrain_contact_max_depth``: a limb
    inside a tall heightfield column is given the column's top, metres above it) and take the cell's friction
    (soil: its traction limit); a MuJoCo-collided foot on soil sits in a rut of depth z (the analytic sole contacts
    of ``contact.py`` show theirs themselves).

    The rut (foot_sinkage, from the previous substep) is subtracted from each contact's penetration (contact dist +=
    z, at most max_rut): the solver holds the foot that much deeper with the contact's usual stiffness, so the
    sinkage shows as a lowered foot. max_rut keeps geoms within the depth where heightfield contacts stay
    correct; the forces and observations use the full z. The rut deepens towards Bekker's z(F_N / sole area), F_N
    twice low-passed (``foot_state_kernel``) (on an RFT soil: the depth whose RFT stress under the sole's motion,
    ``foot_support``, carries F_N / sole area) but never further than the foot's current penetration (counting
    the rut's unshown part) plus sink_step (sinkage_rate * dt), and never rises during a stance: soil sinkage is
    plastic (Wong: unloading recovers little). Without these two rules the loop F_N -> z -> contact chatters or
    ratchets: a rut deeper than the foot releases the contact, the foot falls into it and the impact load digs it
    deeper still. With them a deepening rut still chatters, by up to sink_step a substep: the load's two
    low-passes keep the rut off its peaks. A contact whose friction is below min_friction becomes frictionless
    (condim 1).
    """
    i = wp.tid()
    if i >= nacon[0]:
        return
    g = contact_geom[i]
    ground = int(-1)
    other = int(-1)
    if geom_bodyid[g[0]] == 0:
        ground = g[0]
        other = g[1]
    elif geom_bodyid[g[1]] == 0:
        ground = g[1]
        other = g[0]
    if ground < 0 or other < 0:
        return
    contact_dist[i] = wp.max(contact_dist[i], -max_depth)
    w = contact_worldid[i]
    cell = cell_of(contact_pos[i], soilmap.origin, soilmap.resolution, soilmap.soil.shape[0], soilmap.soil.shape[1])
    f = geom_foot[other]
    fr = ground_friction(contact_friction[i], cell, f, w, soilmap, feet)
    contact_friction[i] = fr
    if fr[0] < feet.min_friction:
        contact_dim[i] = 1
    if f < 0:
        return
    s = feet.soil[w, f]
    if s < 0:
        return
    z = rut_sinkage_fn(feet.sink_load[w, f] / feet.sole_area, feet.soil_params, w, s, feet.bekker_width,
                       feet.support[w, f])
    rut = feet.sinkage[w, f]
    shown = wp.min(rut, max_rut)
    # the foot's depth counting the rut's unshown part: the rut deepens at most sink_step below it
    wp.atomic_max(foot_cand, w, f, wp.min(z, -contact_dist[i] + rut - shown + feet.sink_step))
    contact_dist[i] = contact_dist[i] + shown
    foot_touch[w, f] = 1


# --------------------------------------------------------------------------------------------------------
# Soil forces (passive callback)


@wp.kernel
def soil_force_kernel(
    foot_body: wp.array[int],
    foot_offset: wp.array[wp.vec3],
    foot_drop: wp.array[float],
    body_rootid: wp.array[int],
    xpos: wp.array2d[wp.vec3],
    xmat: wp.array2d[wp.mat33],
    cvel: wp.array2d[wp.spatial_vector],
    subtree_com: wp.array2d[wp.vec3],
    sole_length: float,
    sole_width: float,
    sole_disc: int,
    speed_reg: float,
    soil_params: wp.array3d[float],
    foot_touch: wp.array2d[int],
    foot_cand: wp.array2d[float],
    foot_soil: wp.array2d[int],
    # out
    foot_sinkage: wp.array2d[float],
    foot_vel: wp.array2d[wp.vec3],
    foot_force: wp.array2d[wp.vec3],
):
    """The soil's response to this substep's contacts, per foot. First the rut: a touching foot's deepens to what
    the contact filter found (``foot_cand``: plastic, it never rises during a stance) for this substep's forces and
    observations and the next substep's contacts; off soil there is none (lift-off: ``foot_state_kernel``). Then
    the sole point's horizontal velocity (slip) and, for the viewer, Bekker's bulldozing resistance against it
    (the footprint's width across the motion) while the foot touches the soil, faded below speed_reg. Nothing is
    applied here: the contacts' friction limit applies the resistance (``ground_friction``, with the shear; the
    sole's smaller side as its width, the friction cone being isotropic)."""
    w, f = wp.tid()
    s = foot_soil[w, f]
    if s < 0:
        foot_sinkage[w, f] = 0.0
    elif foot_touch[w, f] != 0:
        foot_sinkage[w, f] = wp.max(foot_sinkage[w, f], foot_cand[w, f])
    b = foot_body[f]
    p = sole_point(xpos, xmat, w, b, foot_offset[f]) - wp.vec3(0.0, 0.0, foot_drop[f])
    v = point_velocity(cvel, subtree_com, body_rootid, w, b, p)
    vh = wp.vec3(v[0], v[1], 0.0)
    foot_vel[w, f] = vh
    force = wp.vec3(0.0)
    if s >= 0 and foot_touch[w, f] != 0:
        face = bulldozing_width_fn(xmat[w, b], vh, sole_length, sole_width, sole_disc)
        fb = bulldozing_force_fn(soil_params[w, s, BULL_C], soil_params[w, s, BULL_G], face, foot_sinkage[w, f])
        force = -(fb / wp.max(wp.length(vh), speed_reg)) * vh  # reported; the contacts' friction applies it
    foot_force[w, f] = force


# --------------------------------------------------------------------------------------------------------
# After each mjw.step: foot normal forces, loads and slip for the next substep; after a step: privileged observations


@wp.kernel
def normal_force_kernel(
    opt_cone: int,
    nacon: wp.array[int],
    geom_limb: wp.array[int],
    contact_frame: wp.array[wp.mat33],
    contact_friction: wp.array[vec5],
    contact_dim: wp.array[int],
    contact_efc_address: wp.array2d[int],
    contact_adhesion: wp.array[float],
    contact_geom: wp.array[wp.vec2i],
    contact_worldid: wp.array[int],
    efc_force: wp.array2d[float],
    njmax: int,
    limb_fn: wp.array2d[float],
):
    """Sum each limb's (a foot's, or a rut leg's: ``geom_limb`` maps a geom to its index, else -1) contact normal
    forces (N) from the solver's constraint forces, into ``limb_fn`` cleared before: the feet's by
    ``foot_cell_kernel`` at the substep's start, the rut legs' by ``leg_state_kernel`` once it has read them."""
    i = wp.tid()
    if i >= nacon[0]:
        return
    g = contact_geom[i]
    f = geom_limb[g[0]]
    if f < 0:
        f = geom_limb[g[1]]
    if f < 0:
        return
    w = contact_worldid[i]
    frc = contact_force_fn(
        opt_cone, contact_frame, contact_friction, contact_dim, contact_efc_address, contact_adhesion,
        efc_force, njmax, nacon, w, i, False,
    )
    wp.atomic_add(limb_fn, w, f, wp.max(frc[0], 0.0))


@wp.func
def low_pass_fn(value: float, target: float, alpha: float) -> float:
    """One step of a first-order low-pass towards ``target`` (alpha = dt / tau)."""
    return value + alpha * (target - value)


@wp.kernel
def foot_state_kernel(
    dt: float,
    contact_threshold: float,
    load_alpha: float,
    traction_alpha: float,
    foot_fn: wp.array2d[float],
    foot_vel: wp.array2d[wp.vec3],
    liftoff_time: float,
    foot_near: wp.array2d[int],
    foot_slip: wp.array2d[float],
    foot_air: wp.array2d[float],
    foot_stance: wp.array2d[float],
    foot_load: wp.array2d[float],
    foot_sink_load: wp.array2d[float],
    foot_traction_load: wp.array2d[float],
    foot_sinkage: wp.array2d[float],
):
    """Accumulate the distance slid since touchdown (Janosi-Hanamoto's j: over the whole stance, its hops too),
    average the loads, detect lift-off.

    foot_load is F_N through a first-order low-pass (load_alpha = dt / sinkage_load_tau), foot_sink_load foot_load
    through a second: the sinkage follows the sustained load, not the solver's impact spikes. A foot whose rut
    deepens chatters (the rut drops ahead of the sole, the sole falls onto it: F_N 0 to 4 W at about 25 Hz); one
    50 ms low-pass passes an eighth of such a ripple, the rut keeps each peak, and a slowly loaded foot settled
    1.4 x Bekker's depth in mud; two in series pass a sixtieth. foot_traction_load is F_N's mean since touchdown
    (foot_stance: the time since the stance's first contact), then a low-pass with traction_alpha =
    dt / traction_load_tau: a floor under the load that the soil's cohesion share of the friction divides by
    (``ground_friction``). Once the foot's F_N has stayed at or below contact_threshold for liftoff_time, its
    stance ends unless its sole is still on the floor it stood on (``foot_near``: within liftoff_clearance of it),
    its rut is forgotten unless the sole is still in it, and its slip unless either: a force alone would take a
    sliding contact's longer hops for lift-offs, and each landing would restart the traction from 0; a foot swinging
    inside a deep rut (snow) has ended its stance but not left its rut; a foot skimming the ground out of its rut
    leaves the rut behind (it would land in it elsewhere, a hole in undisturbed soil) but keeps its slip.
    """
    w, f = wp.tid()
    fn = foot_fn[w, f]
    foot_load[w, f] = low_pass_fn(foot_load[w, f], fn, load_alpha)
    foot_sink_load[w, f] = low_pass_fn(foot_sink_load[w, f], foot_load[w, f], load_alpha)
    if fn > contact_threshold or foot_stance[w, f] > 0.0:
        foot_stance[w, f] = foot_stance[w, f] + dt
        alpha = wp.max(traction_alpha, dt / foot_stance[w, f])
        foot_traction_load[w, f] = low_pass_fn(foot_traction_load[w, f], fn, alpha)
        foot_slip[w, f] = foot_slip[w, f] + dt * wp.length(foot_vel[w, f])
    if fn > contact_threshold:
        foot_air[w, f] = 0.0
    else:
        foot_air[w, f] = foot_air[w, f] + dt
        if foot_air[w, f] >= liftoff_time:
            near = foot_near[w, f]
            if (near & ON_FLOOR) == 0:
                foot_stance[w, f] = 0.0
                foot_traction_load[w, f] = 0.0
            if (near & IN_RUT) == 0:
                foot_sinkage[w, f] = 0.0
            if near == 0:
                foot_slip[w, f] = 0.0


@wp.kernel
def foot_obs_kernel(
    foot_body: wp.array[int],
    foot_offset: wp.array[wp.vec3],
    xpos: wp.array2d[wp.vec3],
    xmat: wp.array2d[wp.mat33],
    heights: wp.array2d[float],
    time: wp.array[float],
    water: WaterMap,
    xi: wp.array[float],
    soil_params: wp.array3d[float],
    foot_fn: wp.array2d[float],
    foot_sinkage: wp.array2d[float],
    foot_soil: wp.array2d[int],
    obs: wp.array2d[float],
):
    """Each foot's privileged observation (``TerrainForces.privileged_obs``) of the last substep: the water at its
    sole, its soil and rut, its normal force."""
    w, f = wp.tid()
    p = sole_point(xpos, xmat, w, foot_body[f], foot_offset[f])
    cell = water_cell(water, p)  # heights and the water layer share the grid
    depth = wp.max(water.surface[cell[0], cell[1]] - heights[cell[0], cell[1]], 0.0)
    u = water_flow(water, cell, time[w], xi[w])
    o = f * OBS_PER_FOOT
    obs[w, o + 0] = depth
    obs[w, o + 1] = u[0]
    obs[w, o + 2] = u[1]
    s = foot_soil[w, f]
    on_soil = float(0.0)
    if s >= 0:
        on_soil = 1.0
    obs[w, o + 3] = on_soil
    obs[w, o + 4] = foot_sinkage[w, f]
    obs[w, o + 5] = foot_fn[w, f] / 100.0
    for q in range(6):
        obs[w, o + 6 + q] = 0.0
    if s >= 0:
        # scaled to O(1): kc/1e4, kphi/1e6, n, cohesion c/1e4, mu = tan(phi), K in cm
        obs[w, o + 6] = soil_params[w, s, KC] / 1.0e4
        obs[w, o + 7] = soil_params[w, s, KPHI] / 1.0e6
        obs[w, o + 8] = soil_params[w, s, N]
        obs[w, o + 9] = soil_params[w, s, COH] / 1.0e4
        obs[w, o + 10] = soil_params[w, s, MU]
        obs[w, o + 11] = soil_params[w, s, K] * 100.0


@wp.kernel
def leg_state_kernel(
    dt: float,
    contact_threshold: float,
    load_alpha: float,
    liftoff_time: float,
    leg_fn: wp.array2d[float],
    legs: LegSoil,
    leg_air: wp.array2d[float],
):
    """A rut leg's soil state after the step, by its foot's rules (``soil_force_kernel``, ``foot_state_kernel``):
    the rut deepens to what this substep's contacts found and never rises while the leg bears on it (plastic
    sinkage); the load is low-passed; once the leg's normal force has stayed at or below contact_threshold for
    liftoff_time and it is out of its rut, the rut is forgotten (the leg meets the undisturbed surface again).
    The substep's findings (contact flags, candidate depth, normal force) are cleared for the next."""
    w, k = wp.tid()
    legs.load[w, k] = low_pass_fn(legs.load[w, k], leg_fn[w, k], load_alpha)
    legs.sink_load[w, k] = low_pass_fn(legs.sink_load[w, k], legs.load[w, k], load_alpha)
    if legs.touch[w, k] != 0:
        legs.sinkage[w, k] = wp.max(legs.sinkage[w, k], legs.cand[w, k])
    if leg_fn[w, k] > contact_threshold:
        leg_air[w, k] = 0.0
    else:
        leg_air[w, k] = leg_air[w, k] + dt
        if leg_air[w, k] >= liftoff_time and legs.inrut[w, k] == 0:
            legs.sinkage[w, k] = 0.0
    legs.cand[w, k] = 0.0
    legs.touch[w, k] = 0
    legs.inrut[w, k] = 0
    leg_fn[w, k] = 0.0


@wp.kernel
def leg_reset_kernel(mask: wp.array[bool], legs: LegSoil, leg_air: wp.array2d[float]):
    """A reset robot's rut legs start out of any rut, unloaded, in the air."""
    w = wp.tid()
    if not mask[w]:
        return
    for k in range(leg_air.shape[1]):
        legs.load[w, k] = 0.0
        legs.sink_load[w, k] = 0.0
        legs.sinkage[w, k] = 0.0
        leg_air[w, k] = 1.0e6
