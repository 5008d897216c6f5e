"""Analytic foot-terrain contacts: sphere and capsule soles against the triangulated heightfield.

MuJoCo collides a geom with a heightfield prism by prism through its general convex solver; once a geom is
a few centimetres inside a cell it returns sideways and downward normals, which launch the foot, so a soil
rut deeper than ~1 cm could not be shown. Here the sole geoms do not collide with the terrain in MuJoCo;
``sole_contact_kernel`` (run in mujoco_warp's contact filter, after its collision and before the constraints
are built) appends one contact per sole sphere (two per capsule: its end spheres, as MuJoCo's capsule-plane
collision) against the same surface MuJoCo draws and collides: the heightfield's triangles, split along the
diagonal from vertex (i, j) to (i + 1, j + 1) as MuJoCo does. The contact is the nearest point of the
triangles around the sphere centre, so flat ground gives exactly vertical normals at any depth, and stair
risers, pillar sides and gap walls (steep triangles of the same surface) give the normals of those walls.
A sphere pushed into a wall (its centre inside the terrain) is pushed out of the wall's nearest face too, never
towards a top far above it, and the solver sees at most ``sole_contact_max_depth`` of penetration: measured
vertically, a quadruped foot inside a 1.5 m pillar was launched at ~10 m/s.

A foot's soil rut lowers the surface under it: the sphere is tested ``rut`` higher than it is (the surface
vertically lowered by the rut), so the foot sits in its full Bekker rut with the contact's usual stiffness.

A leg segment no wider than its foot (``ForcesConfig.rut_leg_geom_names``: the quadruped's calves, as wide as their
foot balls) follows the foot down the hole the foot pressed, and presses a rut of its own where it bears on soil
itself (a calf swinging low into the undisturbed soil ahead of its foot's rut): its capsule, a chain of spheres along
its axis (``leg_points``), touches the terrain through the same contacts, over soil against the surface lowered by
the deeper of the two ruts. Its own rut follows Bekker under its own load as a foot's does (``kernels.LegSoil``); on
soil its friction is ``tan phi`` (``kernels.ground_friction``).

``numpy`` references of every function sit beside their Warp twins (``*_fn``) and are tested against them.
"""

from __future__ import annotations

import mujoco
import numpy as np
import warp as wp
from mujoco_warp._src.collision_core import contact_material_params, write_contact
from mujoco_warp._src.math import make_frame
from mujoco_warp._src.types import vec5

from legged_gente.external_forces.kernels import (
    IN_RUT, ON_FLOOR, FootSoil, LegSoil, SoilMap, cell_of, ground_friction, rut_sinkage_fn,
)

SOLE_TYPES = (int(mujoco.mjtGeom.mjGEOM_SPHERE), int(mujoco.mjtGeom.mjGEOM_CAPSULE))


# --------------------------------------------------------------------------------------------------------
# numpy references


def triangle_vertices(heights, origin, res, i, j, upper):
    """World vertices of one triangle of cell (i, j): ``upper`` the one with fy >= fx (vertices (i, j+1), (i, j),
    (i+1, j+1)), else the one with fx >= fy ((i, j), (i+1, j+1), (i+1, j)); MuJoCo's split of the cell."""
    idx = ((i, j + 1), (i, j), (i + 1, j + 1)) if upper else ((i, j), (i + 1, j + 1), (i + 1, j))
    return [np.array([origin[0] + a * res, origin[1] + b * res, heights[a, b]], float) for a, b in idx]


def surface_height(heights, origin, res, x, y):
    """Height (m) and upward unit normal of the triangulated heightfield at world (x, y). Past the grid's edge the
    edge triangle's plane goes on (MuJoCo's heightfield ends there): ground that is not there, which the env's
    terrain keeps out of reach with its border (``terrain.border_size``) around the tiles."""
    nx, ny = heights.shape
    u = np.clip((x - origin[0]) / res, 0.0, nx - 1.0)
    v = np.clip((y - origin[1]) / res, 0.0, ny - 1.0)
    i, j = min(int(np.floor(u)), nx - 2), min(int(np.floor(v)), ny - 2)
    fx, fy = u - i, v - j
    a, b, c = triangle_vertices(heights, origin, res, i, j, fy > fx)
    n = np.cross(b - a, c - a)
    n = n / np.linalg.norm(n) * np.sign(n[2])
    h = a[2] - (n[0] * (x - a[0]) + n[1] * (y - a[1])) / n[2]
    return h, n


def closest_point_triangle(p, a, b, c):
    """Point of triangle abc nearest to p (Ericson, *Real-Time Collision Detection*, 2005, sec. 5.1.5)."""
    ab, ac, ap = b - a, c - a, p - a
    d1, d2 = ab @ ap, ac @ ap
    if d1 <= 0 and d2 <= 0:
        return a
    bp = p - b
    d3, d4 = ab @ bp, ac @ bp
    if d3 >= 0 and d4 <= d3:
        return b
    vc = d1 * d4 - d3 * d2
    if vc <= 0 and d1 >= 0 and d3 <= 0:
        return a + d1 / (d1 - d3) * ab
    cp = p - c
    d5, d6 = ab @ cp, ac @ cp
    if d6 >= 0 and d5 <= d6:
        return c
    vb = d5 * d2 - d1 * d6
    if vb <= 0 and d2 >= 0 and d6 <= 0:
        return a + d2 / (d2 - d6) * ac
    va = d3 * d6 - d5 * d4
    if va <= 0 and d4 - d3 >= 0 and d5 - d6 >= 0:
        return b + (d4 - d3) / ((d4 - d3) + (d5 - d6)) * (c - b)
    # inside the face: p projected onto its plane (the same point as a + v ab + w ac, but exact where the vertices
    # lie far from p: a plane's one wide cell, 1e4 m away, lost ~1 mm in float32 and tilted the normal by 8 deg)
    n = np.cross(ab, ac)
    return p - n * ((n @ ap) / (n @ n))


def face_tolerance(res):
    """How far (m) the nearest point of a triangle may lie from the centre's projection on its plane and still count
    as inside the face: float32 rounding of points a cell apart (1e-6 m on a 0.1 m grid; 5 mm on a plane's one
    2e4 m cell, whose two coplanar triangles meet along the diagonal through the world's origin)."""
    return 1.0e-6 + 2.5e-7 * res


def face_normal(a, b, c):
    """Upward unit normal of triangle abc."""
    n = np.cross(b - a, c - a)
    return n / np.linalg.norm(n) * np.sign(n[2])


def sphere_contact(heights, origin, res, centre, radius, rut=0.0, reach=None, deep=np.inf):
    """Contact of a sphere with the triangulated heightfield, its surface lowered by ``rut`` under the sphere.

    Returns (dist, normal, pos): signed distance (m, negative: penetration), unit normal from the terrain to
    the sphere, contact point (midway between the surfaces, as MuJoCo's). The distance is the sphere centre's
    distance to the nearest point of the surface, minus the radius:

    * centre above the surface: the nearest point of the triangles within ``reach`` (default: the radius) of the
      cells around the centre, the normal pointing from it to the centre; dist = inf when none lies within reach;
    * centre inside the terrain (below the surface at its x, y): the nearest point of the triangles within
      ``min(vertical depth, deep)``, the normal pointing from the centre to it (a face's own normal where that
      point lies inside the face, so flat ground gives exactly vertical normals at any depth). The point straight
      above is at the vertical depth, so within that window the nearest point is exact; a centre farther than
      ``deep`` from every surface is reported ``deep`` inside it. Beside a tall step or a pillar the nearest
      point is on its side, never on its top far above the sphere: the depth is continuous as the centre moves.
    """
    centre = np.asarray(centre, float)
    q = centre + np.array([0.0, 0.0, rut])
    h, n_face = surface_height(heights, origin, res, q[0], q[1])
    inside = q[2] < h
    window = min(h - q[2], deep) if inside else (radius if reach is None else reach)
    nx, ny = heights.shape
    lo = np.floor((q[:2] - np.asarray(origin) - window) / res).astype(int)
    hi = np.floor((q[:2] - np.asarray(origin) + window) / res).astype(int)
    best, normal = np.inf, n_face
    tol = face_tolerance(res)
    for i in range(max(lo[0], 0), min(hi[0], nx - 2) + 1):
        for j in range(max(lo[1], 0), min(hi[1], ny - 2) + 1):
            for upper in (True, False):
                a, b, c = triangle_vertices(heights, origin, res, i, j, upper)
                p = closest_point_triangle(q, a, b, c)
                d = np.linalg.norm(q - p)
                n = face_normal(a, b, c)
                plane = abs(n @ (q - a))
                if d <= plane + tol:  # the nearest point lies inside the face: its own normal
                    d, candidate = plane, n
                elif inside:
                    candidate = (p - q) / d
                else:
                    candidate = (q - p) / d if d > 1e-9 else n_face
                if d < best:
                    best, normal = d, candidate
    if best > window:
        if not inside:
            return np.inf, normal, centre
        best = window  # farther than ``deep`` from every surface
    dist = (-best if inside else best) - radius
    return dist, normal, centre - normal * (radius + 0.5 * dist)


# --------------------------------------------------------------------------------------------------------
# Warp twins


@wp.func
def vertex_fn(heights: wp.array2d[float], origin: wp.vec2, res: float, i: int, j: int) -> wp.vec3:
    return wp.vec3(origin[0] + float(i) * res, origin[1] + float(j) * res, heights[i, j])


@wp.func
def closest_point_triangle_fn(p: wp.vec3, a: wp.vec3, b: wp.vec3, c: wp.vec3) -> wp.vec3:
    """Ericson's closest point of triangle abc to p (see the numpy reference)."""
    ab = b - a
    ac = c - a
    ap = p - a
    d1 = wp.dot(ab, ap)
    d2 = wp.dot(ac, ap)
    if d1 <= 0.0 and d2 <= 0.0:
        return a
    bp = p - b
    d3 = wp.dot(ab, bp)
    d4 = wp.dot(ac, bp)
    if d3 >= 0.0 and d4 <= d3:
        return b
    vc = d1 * d4 - d3 * d2
    if vc <= 0.0 and d1 >= 0.0 and d3 <= 0.0:
        return a + (d1 / (d1 - d3)) * ab
    cp = p - c
    d5 = wp.dot(ab, cp)
    d6 = wp.dot(ac, cp)
    if d6 >= 0.0 and d5 <= d6:
        return c
    vb = d5 * d2 - d1 * d6
    if vb <= 0.0 and d2 >= 0.0 and d6 <= 0.0:
        return a + (d2 / (d2 - d6)) * ac
    va = d3 * d6 - d5 * d4
    if va <= 0.0 and d4 - d3 >= 0.0 and d5 - d6 >= 0.0:
        return b + ((d4 - d3) / ((d4 - d3) + (d5 - d6))) * (c - b)
    # inside the face: p projected onto its plane (exact where the vertices lie far from p; see the reference)
    n = wp.cross(ab, ac)
    return p - (wp.dot(n, ap) / wp.dot(n, n)) * n


@wp.func
def triangle_fn(heights: wp.array2d[float], origin: wp.vec2, res: float, i: int, j: int, upper: int) -> wp.mat33:
    """Rows: the three vertices of triangle ``upper`` of cell (i, j) (see ``triangle_vertices``)."""
    if upper != 0:
        return wp.matrix_from_rows(vertex_fn(heights, origin, res, i, j + 1), vertex_fn(heights, origin, res, i, j),
                        vertex_fn(heights, origin, res, i + 1, j + 1))
    return wp.matrix_from_rows(vertex_fn(heights, origin, res, i, j), vertex_fn(heights, origin, res, i + 1, j + 1),
                    vertex_fn(heights, origin, res, i + 1, j))


@wp.func
def surface_height_fn(heights: wp.array2d[float], origin: wp.vec2, res: float, x: float, y: float) -> wp.vec4:
    """(normal x, y, z, height) of the triangulated heightfield at (x, y); past the grid's edge the edge triangle's
    plane goes on (see the numpy reference ``surface_height``)."""
    nx = heights.shape[0]
    ny = heights.shape[1]
    u = wp.clamp((x - origin[0]) / res, 0.0, float(nx - 1))
    v = wp.clamp((y - origin[1]) / res, 0.0, float(ny - 1))
    i = wp.min(int(wp.floor(u)), nx - 2)
    j = wp.min(int(wp.floor(v)), ny - 2)
    upper = int(0)
    if v - float(j) > u - float(i):
        upper = 1
    t = triangle_fn(heights, origin, res, i, j, upper)
    n = wp.cross(t[1] - t[0], t[2] - t[0])
    n = wp.normalize(n)
    if n[2] < 0.0:
        n = -n
    h = t[0, 2] - (n[0] * (x - t[0, 0]) + n[1] * (y - t[0, 1])) / n[2]
    return wp.vec4(n[0], n[1], n[2], h)


@wp.func
def sphere_contact_fn(heights: wp.array2d[float], origin: wp.vec2, res: float, centre: wp.vec3, radius: float,
                      rut: float, reach: float, deep: float) -> wp.vec4:
    """(normal x, y, z, dist) of a sphere against the triangulated heightfield lowered by ``rut`` (see the
    numpy reference ``sphere_contact``); dist = 1e10 when nothing lies within reach."""
    q = centre + wp.vec3(0.0, 0.0, rut)
    s = surface_height_fn(heights, origin, res, q[0], q[1])
    n_face = wp.vec3(s[0], s[1], s[2])
    inside = q[2] < s[3]
    window = reach
    if inside:
        window = wp.min(s[3] - q[2], deep)
    nx = heights.shape[0]
    ny = heights.shape[1]
    i0 = wp.max(int(wp.floor((q[0] - origin[0] - window) / res)), 0)
    i1 = wp.min(int(wp.floor((q[0] - origin[0] + window) / res)), nx - 2)
    j0 = wp.max(int(wp.floor((q[1] - origin[1] - window) / res)), 0)
    j1 = wp.min(int(wp.floor((q[1] - origin[1] + window) / res)), ny - 2)
    best = float(1.0e10)
    normal = n_face
    tol = 1.0e-6 + 2.5e-7 * res  # face_tolerance
    for i in range(i0, i1 + 1):
        for j in range(j0, j1 + 1):
            for upper in range(2):
                t = triangle_fn(heights, origin, res, i, j, upper)
                p = closest_point_triangle_fn(q, t[0], t[1], t[2])
                d = wp.length(q - p)
                if d < best + tol:  # else it cannot be the nearest (its plane lies >= d - tol away): skip its normal
                    candidate = n_face
                    n = wp.normalize(wp.cross(t[1] - t[0], t[2] - t[0]))
                    if n[2] < 0.0:
                        n = -n
                    plane = wp.abs(wp.dot(n, q - t[0]))
                    if d <= plane + tol:  # the nearest point lies inside the face: its own normal
                        d = plane
                        candidate = n
                    elif inside:
                        candidate = (p - q) / d
                    elif d > 1.0e-9:
                        candidate = (q - p) / d
                    if d < best:
                        best = d
                        normal = candidate
    if best > window:
        if not inside:
            return wp.vec4(normal[0], normal[1], normal[2], 1.0e10)
        best = window
    if inside:
        best = -best
    return wp.vec4(normal[0], normal[1], normal[2], best - radius)


def _sole_contact_kernel(with_legs: bool):
    """The sole-contact kernel, compiled with the rut legs' branch (``with_legs``) or without it, so a robot
    without rut legs runs the soles' code alone."""

    @wp.kernel(module="unique")
    def kernel(
        # sole points (host constants): geom, capsule end (-1, 0 sphere, +1), foot
        pt_geom: wp.array[int],
        pt_end: wp.array[float],
        pt_foot: wp.array[int],
        pt_leg_step: wp.array[float],
        pt_leg: wp.array[int],
        terrain_geom: int,
        # model
        geom_condim: wp.array[int],
        geom_priority: wp.array[int],
        geom_solmix: wp.array2d[float],
        geom_solref: wp.array2d[wp.vec2],
        geom_solimp: wp.array2d[vec5],
        geom_friction: wp.array2d[wp.vec3],
        geom_adhesion: wp.array2d[float],
        geom_margin: wp.array2d[float],
        geom_gap: wp.array2d[float],
        geom_size: wp.array2d[wp.vec3],
        pair_dim: wp.array[int],
        pair_solref: wp.array2d[wp.vec2],
        pair_solreffriction: wp.array2d[wp.vec2],
        pair_solimp: wp.array2d[vec5],
        pair_adhesion: wp.array2d[float],
        pair_friction: wp.array2d[vec5],
        # state
        geom_xpos: wp.array2d[wp.vec3],
        geom_xmat: wp.array2d[wp.mat33],
        heights: wp.array2d[float],
        hf_origin: wp.vec2,
        hf_res: float,
        soilmap: SoilMap,
        feet: FootSoil,
        legs: LegSoil,
        max_depth: float,
        naconmax: int,
        # out
        foot_touch: wp.array2d[int],
        foot_cand: wp.array2d[float],
        foot_near: wp.array2d[int],
        contact_dist: wp.array[float],
        contact_pos: wp.array[wp.vec3],
        contact_frame: wp.array[wp.mat33],
        contact_includemargin: wp.array[float],
        contact_friction: wp.array[vec5],
        contact_solref: wp.array[wp.vec2],
        contact_solreffriction: wp.array[wp.vec2],
        contact_solimp: wp.array[vec5],
        contact_dim: wp.array[int],
        contact_geom: wp.array[wp.vec2i],
        contact_efc_address: wp.array2d[int],
        contact_worldid: wp.array[int],
        contact_type: wp.array[int],
        contact_geomcollisionid: wp.array[int],
        contact_adhesion: wp.array[float],
        nacon: wp.array[int],
    ):
        """One contact per sole point and world against the heightfield lowered by its foot's rut; the contact's
        material as MuJoCo mixes it for the (terrain, sole) pair, its friction the cell's (``ground_friction``). A leg
        point (``pt_leg`` >= 0, its leg; ``pt_leg_step``: its spacing along the capsule, in ``pt_end``'s units) sees,
        over a soil cell only, the deeper of its leg's own rut and its foot's. Of a leg's chain the two end spheres
        touch, as MuJoCo's capsule against a plane, and an inner sphere only where it lies deeper than its neighbours
        (a step's edge between the ends), so a calf lying on flat ground makes two contacts, not one per sphere.

        A rut deepens towards Bekker's z(F_N / area), F_N twice low-passed (an RFT soil's:
        ``kernels.rut_sinkage_fn``), but at most sink_step below the sphere's current depth (the rules of
        ``kernels.contact_filter_kernel``): a foot's under its load over the sole, a leg's under its own load
        over its capsule's horizontal projection, 2r wide (Bekker's b) and 2r + its axis's horizontal length
        long (exact for a leg lying in the soil; a leg striking with its end alone presses a smaller patch,
        so it sinks at least this much). The solver sees at most
        ``max_depth`` of penetration (``ForcesConfig.sole_contact_max_depth`` says why).
        """
        w, k = wp.tid()
        g = pt_geom[k]
        f = pt_foot[k]
        size = geom_size[w % geom_size.shape[0], g]
        radius = size[0]
        xm = geom_xmat[w, g]
        axis = size[1] * wp.vec3(xm[0, 2], xm[1, 2], xm[2, 2])
        centre = geom_xpos[w, g] + pt_end[k] * axis
        s_foot = feet.soil[w, f]
        leg = int(-1)
        s_leg = int(-1)  # the soil under a leg point
        rut = float(0.0)
        if wp.static(with_legs):
            leg = pt_leg[k]
        if leg < 0:
            if s_foot >= 0:
                rut = feet.sinkage[w, f]
        elif feet.use_soil != 0:
            under = cell_of(centre, soilmap.origin, soilmap.resolution, soilmap.soil.shape[0], soilmap.soil.shape[1])
            s_leg = soilmap.soil[under[0], under[1]]
            if s_leg >= 0:  # ruts are in the soil, not in the rock beside it
                rut = legs.sinkage[w, leg]
                if s_foot >= 0:
                    rut = wp.max(rut, feet.sinkage[w, f])
        geoms = wp.vec2i(terrain_geom, g)
        mid = w % geom_margin.shape[0]
        gid = w % geom_gap.shape[0]
        margin = geom_margin[mid, terrain_geom] + geom_margin[mid, g]
        gap = geom_gap[gid, terrain_geom] + geom_gap[gid, g]
        # reach: contacts within margin + gap, and the unlowered surface (the foot still in its rut)
        reach = radius + wp.max(margin + gap, 0.0) + rut
        if leg < 0:  # where the sole is (kernels.foot_state_kernel: what ends a stance, what a lift-off)
            ground = surface_height_fn(heights, hf_origin, hf_res, centre[0], centre[1])
            # the sphere's gap to the unlowered ground along the face's normal (exact over a planar face)
            above = (centre[2] - ground[3]) * ground[2] - radius
            if above + rut * ground[2] < feet.liftoff_clearance:
                wp.atomic_or(foot_near, w, f, ON_FLOOR)
            if above < margin and rut > 0.0:
                wp.atomic_or(foot_near, w, f, IN_RUT)
        if wp.static(not with_legs):
            res = sphere_contact_fn(heights, hf_origin, hf_res, centre, radius, rut, reach, max_depth)
            if res[3] >= margin + gap:
                return
        else:
            # the sphere, then for an inner sphere of a leg its two neighbours: it touches only at a local deepest
            # point (one call site of sphere_contact_fn: inlined once)
            step = pt_leg_step[k]
            tests = int(1)
            if leg >= 0 and wp.abs(pt_end[k]) < 1.0 - 1.0e-6:
                tests = 3
            res = wp.vec4(0.0)
            touches = int(1)
            for j in range(tests):
                shift = float(0.0)
                if j == 1:
                    shift = -step
                elif j == 2:
                    shift = step
                r = sphere_contact_fn(heights, hf_origin, hf_res, centre + shift * axis, radius, rut, reach, max_depth)
                if j == 0:
                    res = r
                    if r[3] - rut < margin and rut > 0.0 and leg >= 0:
                        legs.inrut[w, leg] = 1
                    if r[3] >= margin + gap:
                        touches = 0
                elif (j == 1 and not res[3] < r[3]) or (j == 2 and not res[3] <= r[3]):
                    touches = 0
                if touches == 0:
                    break
            if touches == 0:
                return
        dist = res[3]
        normal = wp.vec3(res[0], res[1], res[2])
        if s_foot >= 0 and leg < 0:
            z = rut_sinkage_fn(feet.sink_load[w, f] / feet.sole_area, feet.soil_params, w, s_foot, feet.bekker_width,
                               feet.support[w, f])
            # dist - rut: the sphere's depth below the unlowered surface (exact on flat ground)
            wp.atomic_max(foot_cand, w, f, wp.min(z, rut - dist + feet.sink_step))
            foot_touch[w, f] = 1
        if wp.static(with_legs):
            if s_leg >= 0:
                across = wp.sqrt(axis[0] * axis[0] + axis[1] * axis[1])  # half the axis's horizontal length
                area = 2.0 * radius * (2.0 * across + 2.0 * radius)
                z = rut_sinkage_fn(legs.sink_load[w, leg] / area, feet.soil_params, w, s_leg, 2.0 * radius, 1.0)
                wp.atomic_max(legs.cand, w, leg, wp.min(z, rut - dist + feet.sink_step))
                legs.touch[w, leg] = 1
        pos = centre - (radius + 0.5 * dist) * normal
        condim, friction, solref, solreffriction, solimp, adhesion = contact_material_params(
            geom_condim, geom_priority, geom_solmix, geom_solref, geom_solimp, geom_friction, geom_adhesion,
            pair_dim, pair_solref, pair_solreffriction, pair_solimp, pair_adhesion, pair_friction, geoms, -1, w)
        cell = cell_of(pos, soilmap.origin, soilmap.resolution, soilmap.soil.shape[0], soilmap.soil.shape[1])
        traction_of = f  # a foot's soil traction; a leg's tan(phi)
        if leg >= 0:
            traction_of = -1
        friction = ground_friction(friction, cell, traction_of, w, soilmap, feet)
        if friction[0] < feet.min_friction:
            condim = 1  # frictionless (ForcesConfig.min_friction says why)
        write_contact(naconmax, 0, wp.max(dist, -max_depth), pos, make_frame(normal), margin, gap, condim, friction,
                      solref, solreffriction, solimp, adhesion, geoms, wp.vec2i(-1, -1), w, contact_dist, contact_pos,
                      contact_frame, contact_includemargin, contact_friction, contact_solref, contact_solreffriction,
                      contact_solimp, contact_dim, contact_geom, contact_efc_address, contact_worldid, contact_type,
                      contact_geomcollisionid, contact_adhesion, nacon)

    return kernel


sole_contact_kernel = _sole_contact_kernel(with_legs=False)
sole_and_leg_contact_kernel = _sole_contact_kernel(with_legs=True)


# --------------------------------------------------------------------------------------------------------
# Model set-up


def sole_points(mjm: mujoco.MjModel, foot_groups) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The sole points of the feet whose geoms are spheres or capsules: (geom, end, foot) per point; a sphere is
    one point (end 0), a capsule its two end spheres (end -1, +1: centre -+ half-length along its axis)."""
    geoms, ends, feet = [], [], []
    for f, group in enumerate(foot_groups):
        for g in group:
            if int(mjm.geom_type[g]) == SOLE_TYPES[0]:
                geoms.append(g), ends.append(0.0), feet.append(f)
            elif int(mjm.geom_type[g]) == SOLE_TYPES[1]:
                geoms += [g, g]
                ends += [-1.0, 1.0]
                feet += [f, f]
    return np.asarray(geoms, np.int32), np.asarray(ends, np.float32), np.asarray(feet, np.int32)


def leg_points(mjm: mujoco.MjModel, leg_geoms, leg_feet) -> tuple[np.ndarray, ...]:
    """The contact points of the leg capsules that follow their feet into the ruts: (geom, end, foot, step, leg) per
    point, spheres of the capsule's radius along its axis (ends -1 ... +1), ``step`` apart in the ends' units and at
    most one radius apart in metres, so the chain's surface stays within r (1 - cos 30 deg) = 0.13 r of the capsule's
    between two points and matches it at each; ``leg`` the capsule's index in ``leg_geoms``."""
    geoms, ends, feet, steps, legs = [], [], [], [], []
    for leg, (g, f) in enumerate(zip(leg_geoms, leg_feet)):
        radius, half = float(mjm.geom_size[g, 0]), float(mjm.geom_size[g, 1])
        count = max(int(np.ceil(2.0 * half / radius - 1e-6)) + 1, 2)
        geoms += [g] * count
        ends += list(np.linspace(-1.0, 1.0, count))
        feet += [f] * count
        steps += [2.0 / (count - 1)] * count
        legs += [leg] * count
    return (np.asarray(geoms, np.int32), np.asarray(ends, np.float32), np.asarray(feet, np.int32),
            np.asarray(steps, np.float32), np.asarray(legs, np.int32))


def exclude_sole_collisions(spec: mujoco.MjSpec, names) -> None:
    """Stop MuJoCo colliding the named sphere / capsule geoms at all (contype = conaffinity = 0): their terrain
    contacts come from ``sole_contact_kernel``. Only the robot's soles: they touch nothing but the terrain."""
    for name in names:
        geom = spec.geom(name)
        if geom is None:
            raise ValueError(f"forces.foot_geom_names: no geom named {name!r} in the model.")
        if int(geom.type) in SOLE_TYPES:
            geom.contype, geom.conaffinity = 0, 0
