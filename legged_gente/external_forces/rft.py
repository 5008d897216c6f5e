"""Resistive force theory under the soles (Li, Zhang & Goldman, Science 2013): Warp twins of the numpy
references in ``models.py`` (``rft_alpha``, ``rft_plane``, ``rft_element_force``, ``rft_face_force``,
``rft_support``) and the kernel that applies them per sole element and leading face.

A foot on an "rft" soil (``soil.rft_preset``) sinks into its rut until RFT's vertical stress under its current
motion carries its load (p = alpha_z(beta, gamma) |z|: zeta |z| pushed straight down or at rest, 0.375 zeta |z|
dragged level sideways), through the same rut and contact as Bekker's soils: ``rft_force_kernel`` writes each
sole's mean ``rft_support_fn`` over its elements for the next substep's rut (``kernels.rut_sinkage_fn``).
It adds, for each element of the sole plate (``NX x NY`` elements of the sole's footprint at its contact
plane), the horizontal RFT stress -alpha_x(beta, gamma) |z| A against its motion, at the element's own point
(so a turning or tilted sole gets the moment of its elements' forces); and the horizontal RFT stress on the
sole's leading face, the soil wall it pushes from the surface down to its contact plane (``rft_face_force_fn``):
together they stand in place of Bekker's bulldozing. The vertical stress is carried by the contact alone (the
rut), never applied as a force too.
"""

from __future__ import annotations

import warp as wp

from legged_gente.external_forces.contact import surface_height_fn
from legged_gente.external_forces.kernels import (
    MODEL, ZETA, apply_force, bulldozing_width_fn, point_velocity, sole_point)
from legged_gente.external_forces.models import RFT_GENERIC

NX, NY = 4, 2
"""Sole elements along the sole's length and width."""

_K = {name.replace("-", "M"): wp.constant(value) for name, value in RFT_GENERIC.items()}
A00, A10, B11, B01, BM11 = _K["A00"], _K["A10"], _K["B11"], _K["B01"], _K["BM11"]
C11, C01, CM11, D10 = _K["C11"], _K["C01"], _K["CM11"], _K["D10"]
HALF_PI = wp.constant(1.5707963267948966)


@wp.func
def rft_alpha_fn(beta: float, gamma: float, zeta: float) -> wp.vec2:
    """(alpha_x, alpha_z) of Li et al.'s generic fit times zeta (see ``models.rft_alpha``)."""
    az = (A00 + A10 * wp.cos(2.0 * beta) + B11 * wp.sin(2.0 * beta + gamma) + B01 * wp.sin(gamma)
          + BM11 * wp.sin(-2.0 * beta + gamma))
    ax = (C11 * wp.cos(2.0 * beta + gamma) + C01 * wp.cos(gamma) + CM11 * wp.cos(-2.0 * beta + gamma)
          + D10 * wp.sin(2.0 * beta))
    return wp.vec2(zeta * ax, zeta * az)


@wp.func
def rft_plane_fn(normal: wp.vec3, velocity: wp.vec3):
    """(beta, gamma, e) of a plate element: RFT's angles in the vertical plane of its motion and that plane's
    horizontal unit vector (see ``models.rft_plane``)."""
    vh = wp.vec3(velocity[0], velocity[1], 0.0)
    nh = wp.vec3(normal[0], normal[1], 0.0)
    e = wp.vec3(1.0, 0.0, 0.0)
    if wp.length(vh) > 1.0e-9:
        e = wp.normalize(vh)
    elif wp.length(nh) > 1.0e-9:
        e = wp.normalize(nh)
    beta = wp.atan2(normal[2], wp.dot(normal, e)) + HALF_PI
    gamma = wp.atan2(-velocity[2], wp.dot(velocity, e))
    return beta, gamma, e


@wp.func
def rft_element_force_fn(normal: wp.vec3, velocity: wp.vec3, depth: float, area: float, zeta: float,
                         speed_reg: float) -> wp.vec3:
    """Horizontal RFT force on a sole element (see ``models.rft_element_force`` and ``models.rft_plane``)."""
    speed = wp.length(velocity)
    if depth <= 0.0 or speed <= 0.0:
        return wp.vec3(0.0)
    beta, gamma, e = rft_plane_fn(normal, velocity)
    alpha = rft_alpha_fn(beta, gamma, zeta)
    return -(alpha[0] * depth * area * wp.min(speed / speed_reg, 1.0)) * e


@wp.func
def rft_face_force_fn(velocity: wp.vec3, depth: float, face_width: float, zeta: float, speed_reg: float) -> wp.vec3:
    """Horizontal RFT force on a sunk sole's leading face (see ``models.rft_face_force``)."""
    vh = wp.vec3(velocity[0], velocity[1], 0.0)
    speed_h = wp.length(vh)
    if depth <= 0.0 or speed_h <= 0.0:
        return wp.vec3(0.0)
    alpha = rft_alpha_fn(HALF_PI, wp.atan2(-velocity[2], speed_h), zeta)
    fade = wp.min(wp.length(velocity) / speed_reg, 1.0)
    return -(alpha[0] * 0.5 * depth * depth * face_width * fade / speed_h) * vh


@wp.func
def rft_support_fn(normal: wp.vec3, velocity: wp.vec3, speed_reg: float) -> float:
    """alpha_z / zeta of a sole moving at ``velocity`` less its upward part, faded to 1 below speed_reg (see
    ``models.rft_support``)."""
    v = wp.vec3(velocity[0], velocity[1], wp.min(velocity[2], 0.0))
    beta, gamma, e = rft_plane_fn(normal, v)
    alpha = rft_alpha_fn(beta, gamma, 1.0)
    return 1.0 + wp.min(wp.length(v) / speed_reg, 1.0) * (alpha[1] - 1.0)


@wp.kernel
def rft_force_kernel(
    foot_body: wp.array[int],
    foot_offset: wp.array[wp.vec3],
    foot_drop: wp.array[float],
    body_rootid: wp.array[int],
    xpos: wp.array2d[wp.vec3],
    xmat: wp.array2d[wp.mat33],
    xipos: wp.array2d[wp.vec3],
    cvel: wp.array2d[wp.spatial_vector],
    subtree_com: wp.array2d[wp.vec3],
    heights: wp.array2d[float],
    hf_origin: wp.vec2,
    hf_res: float,
    sole_length: float,
    sole_width: float,
    sole_disc: int,
    sole_area: float,
    speed_reg: float,
    soil_params: wp.array3d[float],
    foot_soil: wp.array2d[int],
    # out
    foot_support: wp.array2d[float],
    foot_force: wp.array2d[wp.vec3],
    xfrc: wp.array2d[wp.spatial_vector],
):
    """RFT forces of each foot on an RFT soil, element by element (in the medium, loaded or not): an element at
    (x, y) of the sole plate (body frame: sole_length along the foot body's x axis, sole_width along its y axis,
    the sole's contact plane ``foot_drop`` below its centre, normal the body's z axis) at
    depth |z| below the terrain surface (the unlowered one: the rut is the medium it was pushed into) gets
    ``rft_element_force_fn``, applied at its point; the leading face, as wide as the footprint across the
    horizontal motion of the sole's centre (``kernels.bulldozing_width_fn``), from the surface down to that
    centre's depth, gets ``rft_face_force_fn`` at its centre of pressure, a third of the depth above the
    contact plane (the face's offset along the motion is parallel to the force: it adds no moment).

    Every foot's ``foot_support`` is written for the rut of the next substep, whose contacts are built before
    the velocities are (the load the rut carries is the last substep's too): the mean of its elements'
    ``rft_support_fn``, so that the sole's one rut depth z carries F_N where sum_i alpha_z,i z dA = F_N (a sole
    spun in place gets its elements' sideways value, not the value of its resting centre)."""
    w, f = wp.tid()
    b = foot_body[f]
    xm = xmat[w, b]
    normal = wp.vec3(xm[0, 2], xm[1, 2], xm[2, 2])
    s = foot_soil[w, f]
    rft = int(0)
    if s >= 0:
        if soil_params[w, s, MODEL] > 0.5:
            rft = 1
    area = sole_area / float(NX * NY)  # a disc's elements span its bounding square and share its area
    total = wp.vec3(0.0)
    support = float(0.0)
    for i in range(NX):
        for j in range(NY):
            local = foot_offset[f] + wp.vec3((float(i) + 0.5) / float(NX) * sole_length - 0.5 * sole_length,
                                             (float(j) + 0.5) / float(NY) * sole_width - 0.5 * sole_width,
                                             -foot_drop[f])
            p = xpos[w, b] + xm @ local
            v = point_velocity(cvel, subtree_com, body_rootid, w, b, p)
            support = support + rft_support_fn(normal, v, speed_reg)
            if rft != 0:
                depth = surface_height_fn(heights, hf_origin, hf_res, p[0], p[1])[3] - p[2]
                force = rft_element_force_fn(normal, v, depth, area, soil_params[w, s, ZETA], speed_reg)
                apply_force(xfrc, xipos, w, b, force, p)
                total = total + force
    foot_support[w, f] = support / float(NX * NY)
    if rft != 0:
        p = sole_point(xpos, xmat, w, b, foot_offset[f] - wp.vec3(0.0, 0.0, foot_drop[f]))
        v = point_velocity(cvel, subtree_com, body_rootid, w, b, p)
        depth = surface_height_fn(heights, hf_origin, hf_res, p[0], p[1])[3] - p[2]
        face = bulldozing_width_fn(xm, wp.vec3(v[0], v[1], 0.0), sole_length, sole_width, sole_disc)
        force = rft_face_force_fn(v, depth, face, soil_params[w, s, ZETA], speed_reg)
        apply_force(xfrc, xipos, w, b, force, p + wp.vec3(0.0, 0.0, wp.max(depth, 0.0) / 3.0))
        foot_force[w, f] = foot_force[w, f] + total + force
