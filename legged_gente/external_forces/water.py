"""Warp kernels of the strip-theory water forces (twins of ``water_models.py``), launched from the passive callback.

``segment_water_kernel`` (worlds x leg segments) writes drag, buoyancy and the flow's inertia force to
``xfrc_applied`` at each slice's Gauss point; ``foot_water_kernel`` (worlds x foot geoms) does the same for each
foot. ``segment_points_kernel`` and ``foot_points_kernel`` write each water point's added mass (a scale and the
point's offset from the tree's centre of mass) from the same wet geometry (``segment_slices_fn``, ``foot_wet_fn``),
and ``added_mass_kernel`` (worlds x points x dofs), launched after each of them for its own points, builds each
point's tensor from its geom's axes and adds it to the joint-space mass matrix ``d.M``: the added mass does not wait
for the forces. mujoco_warp's ``step`` computes M in ``fwd_position`` (``smooth.crb``, which rebuilds it from
scratch each substep), calls the passive callback in
``fwd_velocity`` and only then factorises M (``fwd_acceleration``) and builds the constraint solver's Hessian and
the implicit integrators' matrices from it, so an addition made here is seen by the whole step: the added mass is
implicit, acts in the same substep and cannot destabilise a light body (an explicit reaction -m_a * a, from last
substep's acceleration, diverges once m_a exceeds the body's mass, and its finite-difference acceleration also sees
contact impulses). The velocity-product part of the point's acceleration (Jdot qvel: centripetal and Coriolis terms)
is applied explicitly.
``mjw.step1``/``step2`` factorise M before the callback and are not supported; ``Simulation`` splits the step after
the passive callback instead, factorising in its second half as ``mjw.step`` does.

M is stored by rows of ancestor dofs (``M_rowadr``, ``M_rownnz``, diagonal last). MuJoCo stores only the diagonal
of "simple" bodies (bodies of the world with a diagonal inertia, e.g. a lone free body or slide joints): there the
coupling terms between their dofs cannot be stored and are left out (``TerrainForces`` warns).
"""

from __future__ import annotations

import warp as wp

from legged_gente.external_forces.kernels import (
    PI,
    WaterMap,
    apply_force,
    cylinder_drag_fn,
    flow_force_fn,
    flow_rate_fn,
    point_velocity,
    water_cell,
    water_flow,
)

GX = wp.constant(wp.vec3(-0.7745966692414834, 0.0, 0.7745966692414834))
GW = wp.constant(wp.vec3(5.0 / 9.0, 8.0 / 9.0, 5.0 / 9.0))
NGAUSS = 3
TINY = wp.constant(1.0e-6)
GEOM_SPHERE = wp.constant(2)


# --------------------------------------------------------------------------------------------------------
# Formulas (twins of water_models.py)


@wp.func
def circle_wet_area_fn(r: float, d: float) -> float:
    """Circular segment below a chord d above the centre: r^2 acos(-d/r) + d sqrt(r^2 - d^2), d clipped to +-r."""
    dc = wp.clamp(d, -r, r)
    return r * r * wp.acos(wp.clamp(-dc / r, -1.0, 1.0)) + dc * wp.sqrt(wp.max(r * r - dc * dc, 0.0))


@wp.func
def wet_primitive_fn(r: float, sin_t: float, u: float) -> float:
    if u >= r * sin_t:
        return PI * r * r * u
    if u <= -r * sin_t:
        return 0.0
    d = u / sin_t
    q = wp.max(r * r - d * d, 0.0)
    return sin_t * (r * r * (d * wp.acos(wp.clamp(-d / r, -1.0, 1.0)) + wp.sqrt(q)) - q * wp.sqrt(q) / 3.0)


@wp.func
def cylinder_slice_volume_fn(r: float, sin_t: float, z_a: float, z_b: float, z_w: float, length: float) -> float:
    """Exact submerged volume of a tilted cylinder slice (see water_models.cylinder_slice_volume)."""
    dz = z_b - z_a
    if wp.abs(dz) < 0.05 * r:
        zm = 0.5 * (z_a + z_b)
        if sin_t < TINY:
            if zm < z_w:
                return length * PI * r * r
            return 0.0
        return length * circle_wet_area_fn(r, (z_w - zm) / sin_t)
    return length * (wet_primitive_fn(r, sin_t, z_w - z_a) - wet_primitive_fn(r, sin_t, z_w - z_b)) / dz


@wp.func
def sphere_cap_volume_fn(r: float, depth: float) -> float:
    """pi h^2 (3r - h) / 3, h = clip(depth, 0, 2r)."""
    h = wp.clamp(depth, 0.0, 2.0 * r)
    return PI * h * h * (3.0 * r - h) / 3.0


@wp.func
def wet_interval_fn(c_z: float, a_z: float, sin_t: float, r: float, half: float, z_ref: float) -> wp.vec2:
    if wp.abs(a_z) < TINY:
        if c_z - r * sin_t < z_ref:
            return wp.vec2(-half, half)
        return wp.vec2(half, -half)
    s_star = (z_ref - c_z + r * sin_t) / a_z
    if a_z > 0.0:
        return wp.vec2(-half, wp.min(half, s_star))
    return wp.vec2(wp.max(-half, s_star), half)


@wp.func
def crossflow_drag_fn(rho: float, cd: float, r: float, volume: float, v_rel: wp.vec3, axis: wp.vec3,
                      paper_area: int) -> wp.vec3:
    """-0.5 rho cd (2 r V / (pi r^2)) |v_n| v_n (projected area; the paper's when paper_area != 0)."""
    vn = v_rel - wp.dot(v_rel, axis) * axis
    speed = wp.length(vn)
    if speed < 1.0e-9:
        return wp.vec3(0.0)
    return -(cylinder_drag_fn(rho, cd, r, volume / (PI * r * r), speed, paper_area) / speed) * vn


@wp.func
def inertia_force_fn(rho: float, ca: float, volume: float, du: wp.vec3, axis: wp.vec3) -> wp.vec3:
    """Froude-Krylov + added mass in accelerating flow: rho V du + ca rho V (du - (du.a) a)."""
    return rho * volume * du + ca * rho * volume * (du - wp.dot(du, axis) * axis)


@wp.func
def uniform_sum_cdf_fn(w: wp.vec3, u: float) -> float:
    """CDF at u of a sum of uniforms on [0, w_i] (water_models.uniform_sum_cdf), in float64: the alternating sum of
    cubes cancels to a small fraction of its terms."""
    tol = 1.0e-6 * (w[0] + w[1] + w[2])
    uu = wp.float64(u)
    prod = wp.float64(1.0)
    fact = wp.float64(1.0)
    n = int(0)
    for i in range(3):
        if w[i] >= tol:
            n = n + 1
            prod = prod * wp.float64(w[i])
            fact = fact * wp.float64(n)
        else:
            uu = uu - wp.float64(0.5 * w[i])
    acc = wp.float64(0.0)
    for mask in range(8):
        s = uu
        sign = wp.float64(1.0)
        used = int(1)
        for i in range(3):
            if ((mask >> i) & 1) == 1:
                if w[i] < tol:
                    used = 0
                s = s - wp.float64(w[i])
                sign = -sign
        if used == 1 and s > wp.float64(0.0):
            term = wp.float64(1.0)
            for k in range(n):
                term = term * s
            acc = acc + sign * term
    return wp.clamp(float(acc / (fact * prod)), 0.0, 1.0)


@wp.func
def box_submerged_fraction_fn(half: wp.vec3, rot: wp.mat33, c_z: float, z_w: float) -> float:
    """Exact wet fraction of a box at any tilt (water_models.box_submerged_volume over the box's volume)."""
    w = 2.0 * wp.vec3(wp.abs(rot[2, 0]) * half[0], wp.abs(rot[2, 1]) * half[1], wp.abs(rot[2, 2]) * half[2])
    return uniform_sum_cdf_fn(w, z_w - (c_z - 0.5 * (w[0] + w[1] + w[2])))


@wp.func
def plate_drag_fn(rho: float, cd: float, half: wp.vec3, rot: wp.mat33, depth: float, v_rel: wp.vec3) -> wp.vec3:
    """Flat-plate drag on each face pair, weighted by the wetted part of its lower face (water_models.plate_drag)."""
    f = wp.vec3(0.0)
    if depth <= 0.0:
        return f
    e_z = wp.abs(rot[2, 0]) * half[0] + wp.abs(rot[2, 1]) * half[1] + wp.abs(rot[2, 2]) * half[2]
    for i in range(3):
        n = wp.vec3(rot[0, i], rot[1, i], rot[2, i])
        ext = 2.0 * (e_z - wp.abs(n[2]) * half[i])
        wet = float(1.0)
        if ext >= TINY:
            wet = wp.min(depth / ext, 1.0)
        vi = wp.dot(v_rel, n)
        area = 4.0 * half[(i + 1) % 3] * half[(i + 2) % 3]
        f = f - (0.5 * cd * rho * area * wet * wp.abs(vi) * vi) * n
    return f


@wp.func
def sphere_wet_frontal_area_fn(r: float, depth: float, v: wp.vec3) -> float:
    """The wet cap projected on the plane normal to v (water_models.sphere_wet_frontal_area)."""
    if depth <= 0.0:
        return 0.0
    if depth >= 2.0 * r:
        return PI * r * r
    h = depth - r
    r_w = wp.sqrt(wp.max(r * r - h * h, 0.0))
    speed = wp.length(v)
    s = float(1.0)
    c = float(0.0)
    if speed > 0.0:
        s = wp.sqrt(v[0] * v[0] + v[1] * v[1]) / speed
        c = wp.abs(v[2]) / speed
    if s < TINY:
        if h >= 0.0:
            return PI * r * r
        return PI * r_w * r_w
    area = circle_wet_area_fn(r, h / s)
    if r_w > 0.0:
        area = area + c * circle_wet_area_fn(r_w, -h * c / s)
    return area


@wp.func
def sphere_drag_fn(rho: float, cd: float, r: float, depth: float, v_rel: wp.vec3) -> wp.vec3:
    """-0.5 rho cd A |v| v, A the wet cap's frontal area facing v (water_models.sphere_drag)."""
    return -(0.5 * cd * rho * sphere_wet_frontal_area_fn(r, depth, v_rel) * wp.length(v_rel)) * v_rel


# --------------------------------------------------------------------------------------------------------
# Kinematics helpers


@wp.func
def flow_accel(water: WaterMap, cell: wp.vec2i, t: float, xi: float) -> wp.vec3:
    i = cell[0]
    j = cell[1]
    du = xi * flow_rate_fn(water.flow_kind[i, j], t, water.flow_speed[i, j], water.flow_omega[i, j],
                           water.flow_phase[i, j])
    return wp.vec3(du * wp.cos(water.flow_dir[i, j]), du * wp.sin(water.flow_dir[i, j]), 0.0)


@wp.func
def dof_jac(cdof: wp.array2d[wp.spatial_vector], w: int, i: int, r: wp.vec3) -> wp.vec3:
    """Column i of the translational Jacobian of a point at r from the tree's subtree_com."""
    c = cdof[w, i]
    return wp.cross(wp.vec3(c[0], c[1], c[2]), r) + wp.vec3(c[3], c[4], c[5])


@wp.func
def velocity_product_accel(cdof_dot: wp.array2d[wp.spatial_vector], qvel: wp.array2d[float],
                           point_dofs: wp.array2d[int], pt: int, w: int) -> wp.spatial_vector:
    """The spatial acceleration at qacc = 0 (Jdot qvel: centripetal and Coriolis terms) of the body carrying water
    point ``pt``, summed over the dofs moving it (its row of ``point_dofs``: independent loads, no walk up the
    tree)."""
    sacc = wp.spatial_vector()
    for n in range(point_dofs.shape[1]):
        i = point_dofs[pt, n]
        if i >= 0:
            sacc = sacc + cdof_dot[w, i] * qvel[w, i]
    return sacc


@wp.func
def point_vp_accel(sacc: wp.spatial_vector, omega: wp.vec3, rp: wp.vec3, v: wp.vec3) -> wp.vec3:
    """A point's acceleration at qacc = 0, at rp from the tree's subtree_com moving at v: a + alpha x rp + omega x v."""
    return wp.spatial_bottom(sacc) + wp.cross(wp.spatial_top(sacc), rp) + wp.cross(omega, v)


# --------------------------------------------------------------------------------------------------------
# Kernels


@wp.func
def segment_slices_fn(water: WaterMap, c: wp.vec3, axis: wp.vec3, a_z: float, sin_t: float, r: float, half: float):
    """A leg segment's three wet slices: each one's Gauss point (the rows) and submerged volume (m^3, all 0 when
    dry). The wet interval lies under the highest of the surfaces at the two ends and at the whole cylinder part's
    Gauss points (a leg across a water border, or over a stream narrower than itself); each slice then takes the
    water at its own Gauss point."""
    cell_a = water_cell(water, c - half * axis)
    cell_b = water_cell(water, c + half * axis)
    z_ref = wp.max(water.surface[cell_a[0], cell_a[1]], water.surface[cell_b[0], cell_b[1]])
    for k in range(NGAUSS):
        cell_k = water_cell(water, c + half * GX[k] * axis)
        z_ref = wp.max(z_ref, water.surface[cell_k[0], cell_k[1]])
    iv = wet_interval_fn(c[2], a_z, sin_t, r, half, z_ref)
    pts = wp.mat33()
    vols = wp.vec3()
    if iv[1] <= iv[0]:
        return pts, vols
    mid = 0.5 * (iv[0] + iv[1])
    hw = 0.5 * (iv[1] - iv[0])
    e0 = iv[0]
    for k in range(NGAUSS):
        length = hw * GW[k]
        p = c + (mid + hw * GX[k]) * axis
        cell = water_cell(water, p)
        vols[k] = cylinder_slice_volume_fn(r, sin_t, c[2] + e0 * a_z, c[2] + (e0 + length) * a_z,
                                           water.surface[cell[0], cell[1]], length)
        e0 = e0 + length
        pts[k] = p
    return pts, vols


@wp.func
def box_half_height_fn(half: wp.vec3, rot: wp.mat33) -> float:
    """Half a box's vertical extent at its tilt."""
    return wp.abs(rot[2, 0]) * half[0] + wp.abs(rot[2, 1]) * half[1] + wp.abs(rot[2, 2]) * half[2]


@wp.func
def foot_wet_fn(geom_type: int, size: wp.vec3, rot: wp.mat33, c: wp.vec3, z_w: float):
    """A foot geom's point its water forces act at and its wet fraction: a sphere's centre; a box's middle of its
    submerged height (exact for a level box)."""
    if geom_type == GEOM_SPHERE:
        r = size[0]
        return c, sphere_cap_volume_fn(r, z_w - (c[2] - r)) / (4.0 / 3.0 * PI * r * r * r)
    frac = box_submerged_fraction_fn(size, rot, c[2], z_w)
    return c - wp.vec3(0.0, 0.0, box_half_height_fn(size, rot) * (1.0 - frac)), frac


@wp.kernel
def segment_water_kernel(
    # segments (host constants)
    seg_geom: wp.array[int],
    seg_body: wp.array[int],
    seg_radius: wp.array[float],
    seg_halflen: wp.array[float],
    seg_caps: wp.array[int],
    # model
    body_rootid: wp.array[int],
    point_dofs: wp.array2d[int],
    # sim state
    geom_xpos: wp.array2d[wp.vec3],
    geom_xmat: wp.array2d[wp.mat33],
    xipos: wp.array2d[wp.vec3],
    cvel: wp.array2d[wp.spatial_vector],
    cdof_dot: wp.array2d[wp.spatial_vector],
    qvel: wp.array2d[float],
    subtree_com: wp.array2d[wp.vec3],
    time: wp.array[float],
    water: WaterMap,
    # parameters
    rho: float,
    cd: float,
    ca: float,
    g: float,
    vertical_drag: int,
    paper_area: int,
    paper_added_mass: int,
    paper_flow_force: int,
    eps: wp.array[float],
    xi: wp.array[float],
    # out
    xfrc: wp.array2d[wp.spatial_vector],
    seg_force: wp.array2d[wp.vec3],
):
    """Strip-theory water forces on one leg segment (3 Gauss slices along its wet part, see water_models.py)."""
    w, s = wp.tid()
    gid = seg_geom[s]
    b = seg_body[s]
    r = seg_radius[s]
    half = seg_halflen[s]
    c = geom_xpos[w, gid]
    xm = geom_xmat[w, gid]
    axis = wp.vec3(xm[0, 2], xm[1, 2], xm[2, 2])
    a_z = axis[2]
    sin_t = wp.sqrt(wp.max(1.0 - a_z * a_z, 0.0))
    t = time[w]
    com = subtree_com[w, body_rootid[b]]
    total = wp.vec3(0.0)

    # hemispherical caps: buoyancy of half a sphere at each end
    if seg_caps[s] != 0:
        for e in range(2):
            q = c + (2.0 * float(e) - 1.0) * half * axis
            cell = water_cell(water, q)
            vol = 0.5 * sphere_cap_volume_fn(r, water.surface[cell[0], cell[1]] - (q[2] - r))
            if vol > 0.0:
                fb = wp.vec3(0.0, 0.0, eps[w] * rho * g * vol)
                apply_force(xfrc, xipos, w, b, fb, q)
                total = total + fb

    pts, vols = segment_slices_fn(water, c, axis, a_z, sin_t, r, half)
    wet = vols[0] + vols[1] + vols[2]
    if wet <= 0.0:
        seg_force[w, s] = total
        return

    # spatial acceleration of the body at qacc = 0 (velocity-product terms), for the explicit part of the added mass
    sacc = velocity_product_accel(cdof_dot, qvel, point_dofs, NGAUSS * s, w)
    vb = cvel[w, b]
    omega = wp.vec3(vb[0], vb[1], vb[2])

    for k in range(NGAUSS):
        p = pts[k]
        cell = water_cell(water, p)
        vol = vols[k]
        if vol <= 0.0:
            continue
        v = point_velocity(cvel, subtree_com, body_rootid, w, b, p)
        vrel = v - water_flow(water, cell, t, xi[w])
        if vertical_drag == 0:
            vrel = wp.vec3(vrel[0], vrel[1], 0.0)
        f = eps[w] * crossflow_drag_fn(rho, cd, r, vol, vrel, axis, paper_area)
        f = f + wp.vec3(0.0, 0.0, eps[w] * rho * g * vol)
        ma = ca * rho * vol
        if paper_added_mass != 0:
            # GenTe's effective weight m_eff = m + m_a: the added mass only adds weight.
            f = f - wp.vec3(0.0, 0.0, eps[w] * ma * g)
        else:
            f = f + inertia_force_fn(rho, ca, vol, flow_accel(water, cell, t, xi[w]), axis)
            # explicit velocity-product part of -m_a P a_p: a_p(qacc = 0) = a_lin + alpha x rp + omega x v_p
            avp = point_vp_accel(sacc, omega, p - com, v)
            f = f - ma * (avp - wp.dot(avp, axis) * axis)
        if paper_flow_force != 0:
            # GenTe's flow term as a force on the wet segment, shared by its slices by submerged volume
            i0 = cell[0]
            j0 = cell[1]
            fl = xi[w] * flow_force_fn(water.flow_kind[i0, j0], t, water.flow_speed[i0, j0],
                                       water.flow_omega[i0, j0], water.flow_phase[i0, j0])
            share = vol / wet
            f = f + share * fl * wp.vec3(wp.cos(water.flow_dir[i0, j0]), wp.sin(water.flow_dir[i0, j0]), 0.0)
        apply_force(xfrc, xipos, w, b, f, p)
        total = total + f
    seg_force[w, s] = total


@wp.kernel
def foot_water_kernel(
    foot_geom: wp.array[int],
    foot_buoyancy: wp.array[float],
    foot_added_mass: wp.array[wp.vec3],
    geom_type: wp.array[int],
    geom_size: wp.array2d[wp.vec3],
    geom_bodyid: wp.array[int],
    body_rootid: wp.array[int],
    point_dofs: wp.array2d[int],
    geom_xpos: wp.array2d[wp.vec3],
    geom_xmat: wp.array2d[wp.mat33],
    xipos: wp.array2d[wp.vec3],
    cvel: wp.array2d[wp.spatial_vector],
    cdof_dot: wp.array2d[wp.spatial_vector],
    qvel: wp.array2d[float],
    subtree_com: wp.array2d[wp.vec3],
    time: wp.array[float],
    water: WaterMap,
    rho: float,
    g: float,
    cd_plate: float,
    cd_sphere: float,
    paper_added_mass: int,
    eps: wp.array[float],
    xi: wp.array[float],
    xfrc: wp.array2d[wp.spatial_vector],
    foot_water_force: wp.array2d[wp.vec3],
    first_point: int,
):
    """Buoyancy, drag and added mass of a foot geom: a sphere (spherical cap, sphere drag) or a box (plate drag).
    Buoyancy is left out (``foot_buoyancy`` 0) for a sphere inside a leg segment, whose own buoyancy counts that
    volume. The added mass tensor (``foot_added_mass``: wholly submerged, along the geom's axes) times the wet
    fraction goes into M through ``added_mass_kernel`` (point ``first_point + k``, its scale the wet fraction:
    ``foot_points_kernel``), as the legs' does (not with ``paper_added_mass``, whose GenTe model has no feet); here
    only its explicit parts, the flow's acceleration and the velocity-product terms."""
    w, k = wp.tid()
    gid = foot_geom[k]
    b = geom_bodyid[gid]
    c = geom_xpos[w, gid]
    rot = geom_xmat[w, gid]
    size = geom_size[w % geom_size.shape[0], gid]
    cell = water_cell(water, c)
    z_w = water.surface[cell[0], cell[1]]
    p, frac = foot_wet_fn(geom_type[gid], size, rot, c, z_w)
    if frac <= 0.0:
        foot_water_force[w, k] = wp.vec3(0.0)
        return
    t = time[w]
    u = water_flow(water, cell, t, xi[w])
    # the drag takes the velocity v of the point p it acts at (the wetted part's middle): its power is never positive
    v = point_velocity(cvel, subtree_com, body_rootid, w, b, p)
    f = wp.vec3(0.0)
    vol = float(0.0)
    if geom_type[gid] == GEOM_SPHERE:
        r = size[0]
        vol = frac * (4.0 / 3.0 * PI * r * r * r)
        f = eps[w] * sphere_drag_fn(rho, cd_sphere, r, z_w - (c[2] - r), v - u)
    else:
        vol = 8.0 * size[0] * size[1] * size[2] * frac
        f = eps[w] * plate_drag_fn(rho, cd_plate, size, rot, z_w - (c[2] - box_half_height_fn(size, rot)), v - u)
    f = f + wp.vec3(0.0, 0.0, foot_buoyancy[k] * eps[w] * rho * g * vol)
    if paper_added_mass == 0:
        added = frac * (rot * wp.diag(foot_added_mass[k]) * wp.transpose(rot))
        # Froude-Krylov and added mass in accelerating flow, and the explicit velocity-product part of -A a_p
        com = subtree_com[w, body_rootid[b]]
        sacc = velocity_product_accel(cdof_dot, qvel, point_dofs, first_point + k, w)
        vb = cvel[w, b]
        avp = point_vp_accel(sacc, wp.vec3(vb[0], vb[1], vb[2]), p - com, v)
        du = flow_accel(water, cell, t, xi[w])
        f = f + rho * vol * du + added * (du - avp)
    apply_force(xfrc, xipos, w, b, f, p)
    foot_water_force[w, k] = f


@wp.kernel
def segment_points_kernel(
    seg_geom: wp.array[int],
    seg_body: wp.array[int],
    seg_radius: wp.array[float],
    seg_halflen: wp.array[float],
    body_rootid: wp.array[int],
    geom_xpos: wp.array2d[wp.vec3],
    geom_xmat: wp.array2d[wp.mat33],
    subtree_com: wp.array2d[wp.vec3],
    water: WaterMap,
    rho: float,
    ca: float,
    point_mass: wp.array2d[float],
    point_offset: wp.array2d[wp.vec3],
):
    """Each leg slice's added mass across its axis, Ca rho V (kg, 0 where dry), and its Gauss point's offset from
    the tree's centre of mass, for ``added_mass_kernel``. Apart from ``segment_water_kernel``, which needs neither,
    so the added mass need not wait for the forces (``TerrainForces.passive``)."""
    w, s = wp.tid()
    gid = seg_geom[s]
    c = geom_xpos[w, gid]
    xm = geom_xmat[w, gid]
    axis = wp.vec3(xm[0, 2], xm[1, 2], xm[2, 2])
    sin_t = wp.sqrt(wp.max(1.0 - axis[2] * axis[2], 0.0))
    pts, vols = segment_slices_fn(water, c, axis, axis[2], sin_t, seg_radius[s], seg_halflen[s])
    com = subtree_com[w, body_rootid[seg_body[s]]]
    for k in range(NGAUSS):
        point_mass[NGAUSS * s + k, w] = ca * rho * wp.max(vols[k], 0.0)
        point_offset[NGAUSS * s + k, w] = pts[k] - com


@wp.kernel
def foot_points_kernel(
    foot_geom: wp.array[int],
    geom_type: wp.array[int],
    geom_size: wp.array2d[wp.vec3],
    geom_bodyid: wp.array[int],
    body_rootid: wp.array[int],
    geom_xpos: wp.array2d[wp.vec3],
    geom_xmat: wp.array2d[wp.mat33],
    subtree_com: wp.array2d[wp.vec3],
    water: WaterMap,
    first_point: int,
    point_mass: wp.array2d[float],
    point_offset: wp.array2d[wp.vec3],
):
    """Each foot's added-mass scale, its wet fraction, and its point's offset from the tree's centre of mass (point
    ``first_point + k``), for ``added_mass_kernel``: apart from ``foot_water_kernel``, as ``segment_points_kernel``."""
    w, k = wp.tid()
    gid = foot_geom[k]
    c = geom_xpos[w, gid]
    cell = water_cell(water, c)
    p, frac = foot_wet_fn(geom_type[gid], geom_size[w % geom_size.shape[0], gid], geom_xmat[w, gid], c,
                          water.surface[cell[0], cell[1]])
    point_mass[first_point + k, w] = wp.max(frac, 0.0)
    point_offset[first_point + k, w] = p - subtree_com[w, body_rootid[geom_bodyid[gid]]]


@wp.kernel
def added_mass_kernel(
    point_dofs: wp.array2d[int],
    point_geom: wp.array[int],
    point_axes: wp.array[wp.vec3],
    dof_parentid: wp.array[int],
    M_rownnz: wp.array[int],
    M_rowadr: wp.array[int],
    geom_xmat: wp.array2d[wp.mat33],
    cdof: wp.array2d[wp.spatial_vector],
    point_mass: wp.array2d[float],
    point_offset: wp.array2d[wp.vec3],
    first_point: int,
    M: wp.array2d[float],
):
    """Implicit added mass: M[i, j] += J_i(p) . A J_j(p) for each water point p (a leg slice's Gauss point, a foot),
    i one of the dofs moving its body (``point_dofs[pt, n]``, -1 past the chain) and j each ancestor of i (or i
    itself). A = s R diag(point_axes) R^T, R its geom's axes, s = ``point_mass`` (a slice's m_k with axes (1, 1, 0):
    across the axis only; a foot's wet fraction with its added masses along its axes). One thread per (world,
    point, dof) keeps the chains' loops short; the points kernels write only a scale and an offset per point. A
    launch covers the points from ``first_point`` on, as many as its second dimension: the legs' and the feet's
    are launched apart, each after its own points kernel (``TerrainForces.passive``)."""
    w, k, n = wp.tid()
    pt = first_point + k
    i = point_dofs[pt, n]
    if i < 0:
        return
    scale = point_mass[pt, w]
    if scale <= 0.0:
        return
    rot = geom_xmat[w, point_geom[pt]]
    added = scale * (rot * wp.diag(point_axes[pt]) * wp.transpose(rot))
    rp = point_offset[pt, w]
    aji = added * dof_jac(cdof, w, i, rp)
    rowadr = M_rowadr[i]
    adr = rowadr + M_rownnz[i] - 1
    j = i
    while j >= 0 and adr >= rowadr:
        wp.atomic_add(M, w, adr, wp.dot(aji, dof_jac(cdof, w, j, rp)))
        adr = adr - 1
        j = dof_parentid[j]
