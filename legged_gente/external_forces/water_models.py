"""Numpy references of the strip-theory water forces (the single source of each formula; ``water.py`` holds the
Warp twins and is tested against these).

A leg segment (capsule or cylinder of radius r, axis a, cylinder half-length H) is cut into ``len(GAUSS_X)`` slices
along the part of its axis that can be wet; slice k has its Gauss-Legendre point p_k, its length l_k (the Gauss
weight times the half-interval) and its exactly submerged volume V_k (the surface read at p_k). Per slice:

* cross-flow (Morison) drag ``-0.5 rho cd (2 r V_k / (pi r^2)) |v_n| v_n``, v_n the relative velocity normal to the
  axis at p_k (independence principle: Hoerner, *Fluid-Dynamic Drag* 1965, ch. 3; strip theory: Morison et al.
  1950), so a tilted leg sees only its cross-flow, a leg moving along its axis none, a swinging leg the right
  damping torque (the force acts at p_k);
* buoyancy ``rho g V_k`` up (Archimedes) with V_k the volume of the tilted cylinder slice below the surface (circular
  segment areas integrated in closed form), continuous as the leg crosses the surface;
* Froude-Krylov plus added mass in accelerating flow ``rho V_k du/dt + ca rho V_k P du/dt`` (P = 1 - a a^T: added
  mass only across the axis), i.e. Morison's inertia force with cm = 1 + ca on a fixed leg (Morison et al. 1950;
  Newman, *Marine Hydrodynamics* 1977, sec. 4.13);
* added mass ``m_k = ca rho V_k`` across the axis. It enters the joint-space mass matrix (M += J_k^T m_k P J_k),
  i.e. implicitly, plus the explicit velocity-product part ``-m_k P (Jdot qvel)_k``; see ``water.py``.

The capsule's hemispherical caps carry buoyancy only: each gets half the submerged volume of the sphere of radius r
at the cylinder's end (exact for a horizontal capsule and for a cap wholly wet or dry; a tilted cap cut by the surface
is off by at most rho g pi r^3 / 3, on a vertical capsule; the volume is continuous).
Feet (``foot_*``): a sphere gets buoyancy from its exact spherical-cap volume and sphere drag on its wet cap's
frontal area (``sphere_wet_frontal_area``); a box gets buoyancy
from its exact submerged volume at any tilt (``box_submerged_volume``) and flat-plate drag on each face pair. Their
forces act on the vertical through the geom's centre (a sphere's centre; a box's wet fraction of half its vertical
extent above its lowest point, the middle of the wetted part for a level box), and the drag takes that point's
velocity, so its power is never positive however the foot spins. Both get an added mass tensor (``foot_added_mass``:
a sphere's half its displaced mass, a box's faces as thin plates), scaled by the wet fraction, entering M implicitly
as the legs' does, and the Froude-Krylov plus added-mass force of an accelerating flow.
"""

from __future__ import annotations

import numpy as np

GAUSS_X = (-np.sqrt(0.6), 0.0, np.sqrt(0.6))
GAUSS_W = (5.0 / 9.0, 8.0 / 9.0, 5.0 / 9.0)
TINY = 1.0e-6


def circle_wet_area(r, d):
    """Area of a circle of radius r below a chord at signed distance d above its centre (m^2).

    Circular segment of height h = r + d: A = r^2 acos((r - h)/r) - (r - h) sqrt(2 r h - h^2), 0 for d <= -r,
    pi r^2 for d >= r.
    """
    d = np.clip(d, -r, r)
    return r * r * np.arccos(np.clip(-d / r, -1.0, 1.0)) + d * np.sqrt(np.maximum(r * r - d * d, 0.0))


def _wet_primitive(r, sin_t, u):
    """sin(theta) times the antiderivative of circle_wet_area over d = u / sin(theta), u = surface - axis height.

    G(d) = r^2 (d acos(-d/r) + sqrt(r^2 - d^2)) - (r^2 - d^2)^(3/2) / 3 with G(-r) = 0, G(r) = pi r^3; beyond the
    circle the slice is dry (0) or fully wet (pi r^2 u).
    """
    if u >= r * sin_t:
        return np.pi * r * r * u
    if u <= -r * sin_t:
        return 0.0
    d = u / sin_t
    q = max(r * r - d * d, 0.0)
    return sin_t * (r * r * (d * np.arccos(np.clip(-d / r, -1.0, 1.0)) + np.sqrt(q)) - q**1.5 / 3.0)


def cylinder_slice_volume(r, sin_t, z_a, z_b, z_w, length):
    """Submerged volume of a cylinder slice of radius r and axial length ``length`` whose axis runs from height
    z_a to z_b, below a flat surface at z_w (m^3); sin_t = sin of the axis' angle from the vertical.

    V = length * (P(z_w - z_a) - P(z_w - z_b)) / (z_b - z_a) with P the primitive above (exact); for a nearly level
    slice (|z_b - z_a| < r / 20) the circular segment area at the middle times the length.
    """
    dz = z_b - z_a
    if abs(dz) < 0.05 * r:
        zm = 0.5 * (z_a + z_b)
        if sin_t < TINY:
            return length * np.pi * r * r * float(zm < z_w)
        return length * float(circle_wet_area(r, (z_w - zm) / sin_t))
    return length * (_wet_primitive(r, sin_t, z_w - z_a) - _wet_primitive(r, sin_t, z_w - z_b)) / dz


def sphere_cap_volume(r, depth):
    """Volume of a sphere of radius r below a surface ``depth`` above its lowest point (m^3):
    pi h^2 (3 r - h) / 3 with h = clip(depth, 0, 2 r)."""
    h = np.clip(depth, 0.0, 2.0 * r)
    return np.pi * h * h * (3.0 * r - h) / 3.0


def wet_interval(c_z, a_z, sin_t, r, half, z_ref):
    """Axial interval [s0, s1] of the cylinder part (s in [-half, half] from the centre) whose cross-sections reach
    below the surface z_ref (their lowest point c_z + s a_z - r sin_t < z_ref); s1 <= s0 when none does."""
    if abs(a_z) < TINY:
        return (-half, half) if c_z - r * sin_t < z_ref else (half, -half)
    s_star = (z_ref - c_z + r * sin_t) / a_z
    if a_z > 0.0:
        return -half, min(half, s_star)
    return max(-half, s_star), half


def segment_slices(c, axis, r, half, surface_at):
    """Slices of a leg segment: list of (Gauss point p_k, length l_k, submerged volume V_k).

    ``surface_at(p)`` returns the water surface height at world point p. The wet interval is found with the
    highest of the surfaces at the segment's two ends and at the Gauss points of its whole cylinder part (a leg
    across a water border, or over a stream narrower than itself); each slice's volume uses the surface at its own
    Gauss point (strip theory: a slice is as wet as the water at its point), so the volume is exact wherever the
    surface is level over each slice.
    """
    c, axis = np.asarray(c, float), np.asarray(axis, float)
    a_z = axis[2]
    sin_t = np.sqrt(max(1.0 - a_z * a_z, 0.0))
    z_ref = max(surface_at(c + s * axis) for s in (-half, half, *(half * x for x in GAUSS_X)))
    s0, s1 = wet_interval(c[2], a_z, sin_t, r, half, z_ref)
    if s1 <= s0:
        return []
    mid, hw = 0.5 * (s0 + s1), 0.5 * (s1 - s0)
    out, e = [], s0
    for x, w in zip(GAUSS_X, GAUSS_W):
        length = hw * w
        p = c + (mid + hw * x) * axis
        z_a, z_b = c[2] + e * a_z, c[2] + (e + length) * a_z
        out.append((p, length, cylinder_slice_volume(r, sin_t, z_a, z_b, surface_at(p), length)))
        e += length
    return out


def crossflow_drag(rho, cd, r, volume, v_rel, axis, paper_area=False):
    """Morison drag on a slice (N, vector): -0.5 rho cd D l |v_n| v_n, v_n = v_rel - (v_rel . a) a.

    D l = 2 r V / (pi r^2) is the projected area of the slice's wetted length V / (pi r^2) (Hoerner); the GenTe
    paper's area is pi times larger (``paper_area``: 2 pi r l). No axial (skin-friction) term.
    """
    v_rel, axis = np.asarray(v_rel, float), np.asarray(axis, float)
    vn = v_rel - np.dot(v_rel, axis) * axis
    area = 2.0 * r * volume / (np.pi * r * r)
    if paper_area:
        area *= np.pi
    return -0.5 * cd * rho * area * np.linalg.norm(vn) * vn


def inertia_force(rho, ca, volume, du, axis):
    """Froude-Krylov plus added-mass force of a flow accelerating at du (N, vector): rho V du + ca rho V P du."""
    du, axis = np.asarray(du, float), np.asarray(axis, float)
    return rho * volume * du + ca * rho * volume * (du - np.dot(du, axis) * axis)


def uniform_sum_cdf(widths, u):
    """P(U_0 + U_1 + U_2 < u) for independent U_i uniform on [0, w_i] (the CDF of a sum of uniforms):
    sum over subsets S of (-1)^|S| max(u - sum_S w, 0)^n / (n! prod w), n the number of widths. A width below 1e-6
    of their sum counts as a point at its middle (u shifted by w / 2: an error below 2e-6), which keeps the division
    by prod w well conditioned."""
    w = np.asarray(widths, float)
    keep = w >= 1.0e-6 * w.sum()
    u = float(u) - 0.5 * float(w[~keep].sum())
    w, n = w[keep], int(keep.sum())
    acc = 0.0
    for mask in range(1 << n):
        picked = [i for i in range(n) if mask >> i & 1]
        acc += (-1.0) ** len(picked) * max(u - float(w[picked].sum()), 0.0) ** n
    return float(np.clip(acc / (np.prod(w) * np.prod(np.arange(1, n + 1))), 0.0, 1.0))


def box_submerged_volume(half, rot, c_z, z_w):
    """Submerged volume of a box (half sizes ``half``, rotation ``rot``) centred at height c_z below a flat surface
    at z_w (m^3), exact at any tilt (Archimedes).

    A point of the box at local coordinates x_i in [-h_i, h_i] lies at height c_z + sum_i rot[2, i] x_i: for a point
    drawn uniformly in the box its height above the lowest point is a sum of three uniforms of widths
    w_i = 2 |rot[2, i]| h_i, so the wet fraction is that sum's CDF at the lowest point's depth
    z_w - (c_z - e_z), e_z = sum_i w_i / 2 (``uniform_sum_cdf``): linear in the depth for a level box, a corner's
    cubic for a box tilted about two axes.
    """
    half = np.asarray(half, float)
    widths = 2.0 * np.abs(np.asarray(rot, float)[2]) * half
    depth = z_w - (c_z - 0.5 * float(widths.sum()))
    return 8.0 * float(np.prod(half)) * uniform_sum_cdf(widths, depth)


def plate_drag(rho, cd, half, rot, depth, v_rel):
    """Flat-plate drag of a box sole (N, vector) whose lowest point is ``depth`` below the surface: each face pair i,
    of area A_i = 4 h_j h_k and normal n_i, resists the velocity along n_i with the wetted part w_i of its lower face:
    -0.5 rho cd A_i w_i |v.n_i| (v.n_i) n_i (Hoerner: cd ~1.17 for a plate normal to the flow). w_i = depth over the
    face's vertical extent 2 (e_z - |n_i,z| h_i), clipped to [0, 1]: exact for a level box, whose bottom face is
    all wet as soon as it touches the water."""
    rot, half = np.asarray(rot, float), np.asarray(half, float)
    e_z = float(np.sum(np.abs(rot[2]) * half))
    f = np.zeros(3)
    if depth <= 0.0:
        return f
    for i in range(3):
        n = rot[:, i]
        ext = 2.0 * (e_z - abs(n[2]) * half[i])
        wet = 1.0 if ext < TINY else min(depth / ext, 1.0)
        vi = float(np.dot(v_rel, n))
        area = 4.0 * half[(i + 1) % 3] * half[(i + 2) % 3]
        f -= 0.5 * cd * rho * area * wet * abs(vi) * vi * n
    return f


# DNV-RP-C205 (2010), Table A-2: added mass coefficient C_A of a thin rectangular plate, sides a <= b, moving normal
# to itself: m_a = C_A rho (pi / 4) a^2 b. Tabulated against b / a; as b / a grows the plate becomes a 2-D strip,
# whose added mass per length is rho pi (a / 2)^2 (C_A -> 1).
PLATE_B_OVER_A = (1.0, 1.25, 1.5, 1.59, 2.0, 2.5, 3.0, 4.0, 5.0, 6.25, 8.0, 10.0)
PLATE_CA = (0.579, 0.642, 0.690, 0.704, 0.757, 0.801, 0.830, 0.871, 0.897, 0.917, 0.934, 0.947)


def plate_added_mass(rho, side_1, side_2):
    """Added mass of a thin rectangular plate moving normal to itself (kg): C_A rho (pi/4) a^2 b, C_A from DNV's table
    interpolated linearly in a / b (0: the strip's 1, 1: the square's 0.579)."""
    a, b = sorted((float(side_1), float(side_2)))
    a_over_b = [0.0] + [1.0 / x for x in reversed(PLATE_B_OVER_A)]
    ca = np.interp(a / b, a_over_b, [1.0] + list(reversed(PLATE_CA)))
    return ca * rho * np.pi / 4.0 * a * a * b


def foot_added_mass(geom_type, size, rho):
    """Added masses of a wholly submerged foot geom along its own axes x, y, z (kg, array of 3).

    A sphere: half its displaced mass in every direction, (2/3) rho pi r^3 (potential flow; Newman, *Marine Hydrodynamics*
    1977, ch. 4). A box (half sizes h): moving along axis i, its face pair
    normal to i as a thin plate of sides 2 h_j x 2 h_k (``plate_added_mass``): right for a sole (thin against its
    width), short for a thick box (a cube gets about two thirds of its potential-flow added mass). Rotational added
    inertia is left out.
    """
    if geom_type == "sphere":
        return np.full(3, 2.0 / 3.0 * rho * np.pi * float(size[0]) ** 3)
    h = np.asarray(size, float)[:3]
    return np.array([plate_added_mass(rho, 2 * h[(i + 1) % 3], 2 * h[(i + 2) % 3]) for i in range(3)])


def foot_inertia_force(rho, volume, added_mass, du, vp_accel):
    """Froude-Krylov and added-mass force of a foot in a flow accelerating at du (N, vector), with the explicit
    velocity-product part of its added-mass reaction: rho V du + A (du - a_vp); ``added_mass`` the 3 x 3 tensor A
    (world frame, wet fraction included), a_vp the foot point's acceleration at zero joint acceleration."""
    du = np.asarray(du, float)
    return rho * volume * du + np.asarray(added_mass, float) @ (du - np.asarray(vp_accel, float))


def sphere_wet_frontal_area(r, depth, v):
    """Area facing a flow along v of the wet part of a sphere of radius r whose lowest point is ``depth`` below a level
    surface (m^2): the wet cap projected on the plane normal to v (exact).

    With h = depth - r the surface's height above the centre, r_w = sqrt(r^2 - h^2) the waterline circle's radius and
    s, c the sine and |cosine| of v's angle from the vertical, a line along v meets the cap iff its chord's lowest
    point is under the surface. Those lines cover the silhouette disk below the chord h / s from its centre (the
    points of the silhouette circle that are wet), ``circle_wet_area(r, h / s)``, and beyond that chord the projected
    waterline disk (an ellipse of semi-axes c r_w, r_w centred h s from the disk's centre, on the chord's side) cut
    by the same line, ``c circle_wet_area(r_w, -h c / s)``. Horizontal flow: the circular segment
    ``circle_wet_area(r, h)``; vertical: the waterline disk pi r_w^2 (pi r^2 once wet past the centre).
    """
    v = np.asarray(v, float)
    speed = float(np.linalg.norm(v))
    if depth <= 0.0:
        return 0.0
    if depth >= 2.0 * r:
        return np.pi * r * r
    h = depth - r
    r_w = np.sqrt(max(r * r - h * h, 0.0))
    s = float(np.hypot(v[0], v[1])) / speed if speed > 0.0 else 1.0
    c = abs(float(v[2])) / speed if speed > 0.0 else 0.0
    if s < TINY:
        return np.pi * r * r if h >= 0.0 else np.pi * r_w * r_w
    area = float(circle_wet_area(r, h / s))
    if r_w > 0.0:
        area += c * float(circle_wet_area(r_w, -h * c / s))
    return area


def sphere_drag(rho, cd, r, depth, v_rel):
    """Drag of a sphere whose lowest point is ``depth`` under the surface (N, vector): the standard drag equation
    -0.5 rho cd A |v| v with A the wet part's frontal area (``sphere_wet_frontal_area``) facing v (Hoerner,
    *Fluid-Dynamic Drag* 1965, ch. 3: cd ~0.47, subcritical; no free-surface correction)."""
    v_rel = np.asarray(v_rel, float)
    return -0.5 * cd * rho * sphere_wet_frontal_area(r, depth, v_rel) * np.linalg.norm(v_rel) * v_rel


def segment_loads(c, axis, r, half, caps, surface_at, velocity_at, vp_accel_at, flow_at, flow_accel_at, rho=1000.0,
                  cd=1.1, ca=1.0, g=9.81, vertical_drag=True, paper_area=False, paper_added_mass=False):
    """All water loads on one leg segment, as the kernel computes them (the reference of ``segment_water_kernel``).

    Callables of a world point p: ``surface_at`` (m), ``velocity_at`` (the body's velocity there), ``vp_accel_at``
    (its acceleration at zero joint acceleration, Jdot qvel), ``flow_at``, ``flow_accel_at`` (vectors).
    Returns (forces, added masses): lists of (point, force vector) and of (point, mass across the axis).
    """
    axis = np.asarray(axis, float)
    forces, masses = [], []
    if caps:
        for e in (-1.0, 1.0):
            q = np.asarray(c, float) + e * half * axis
            vol = 0.5 * sphere_cap_volume(r, surface_at(q) - (q[2] - r))
            if vol > 0:
                forces.append((q, np.array([0.0, 0.0, rho * g * vol])))
    for p, _, vol in segment_slices(c, axis, r, half, surface_at):
        if vol <= 0:
            continue
        vrel = velocity_at(p) - flow_at(p)
        if not vertical_drag:
            vrel[2] = 0.0
        f = crossflow_drag(rho, cd, r, vol, vrel, axis, paper_area) + np.array([0.0, 0.0, rho * g * vol])
        if paper_added_mass:
            f[2] -= ca * rho * vol * g
        else:
            avp = vp_accel_at(p)
            f += inertia_force(rho, ca, vol, flow_accel_at(p), axis) - ca * rho * vol * (avp - np.dot(avp, axis) * axis)
            masses.append((p, ca * rho * vol))
        forces.append((p, f))
    return forces, masses
