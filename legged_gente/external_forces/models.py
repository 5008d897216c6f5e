"""Numpy reference formulas of the terrain force fields: the single source of each formula.

All functions take SI scalars or numpy arrays and broadcast element-wise. The Warp kernels in
``kernels.py`` implement the same formulas and are tested against these.

Where the GenTe paper (and its code) is physically wrong, the correct form is the default and the paper's
is kept as an option:

* Drag area. The paper uses A = 2*pi*r*h (half the lateral *surface* of the cylinder, in fact the whole of
  it). Pressure drag acts on the area projected across the flow, A = 2*r*h (Hoerner, *Fluid-Dynamic Drag*,
  1965, ch. 3; the Morison equation, Morison et al. 1950). ``area="paper"`` keeps the paper's.
* Leg speed. The paper's code feeds the knee joint's angular velocity (rad/s) in as the leg's speed. We
  use the linear velocity of each submerged segment's centroid relative to the flow (m/s).
* Density. The paper's drag omits the fluid density; we use rho (water: 1000 kg/m^3).
* Sinkage. The paper's code samples sinkage at random; we compute it from the foot's pressure with Bekker's
  pressure-sinkage relation.
* Slip. The paper's code measures slip from the episode's spawn point; we accumulate the foot's horizontal
  slip since touchdown and reset it at lift-off (the Janosi-Hanamoto shear displacement).
"""

from __future__ import annotations

import numpy as np

FLOW_NAMES = ("still", "current", "tide")


def cylinder_drag(rho, cd, radius, submerged_length, speed, area="projected"):
    """Magnitude of the pressure drag on a cylinder moving across a fluid (N).

    Morison equation drag term / Hoerner: F = 0.5 * cd * rho * A * |v|^2 with A = 2 r L, the area projected
    across the flow (``area="projected"``). ``area="paper"`` uses the GenTe paper's A = 2 pi r L.
    """
    if area == "projected":
        a = 2.0 * np.asarray(radius) * submerged_length
    elif area == "paper":
        a = 2.0 * np.pi * np.asarray(radius) * submerged_length
    else:
        raise ValueError(f"cylinder_drag: area={area!r} must be 'projected' (correct) or 'paper'.")
    return 0.5 * np.asarray(cd) * rho * a * np.asarray(speed) ** 2


def buoyancy(rho, g, radius, submerged_length):
    """Archimedes' buoyancy on the submerged part of a cylinder (N): rho * g * pi r^2 L."""
    return np.asarray(rho) * g * np.pi * np.asarray(radius) ** 2 * submerged_length


def added_mass(rho, ca, radius, submerged_length):
    """Added (hydrodynamic) mass of a cylinder accelerating across a fluid (kg): ca * rho * pi r^2 L.

    ca the added-mass coefficient, 1 for a circular cylinder in potential flow (Newman, *Marine Hydrodynamics*,
    1977, sec. 4.13); Morison's inertia coefficient of a fixed cylinder in accelerating flow is cm = 1 + ca. The
    reaction force is -m_a * (relative acceleration across the axis).
    """
    return np.asarray(ca) * rho * np.pi * np.asarray(radius) ** 2 * submerged_length


def flow_force(kind, t, amplitude, omega=0.0, phase=0.0):
    """Flow term of the GenTe paper: still -> 0, current -> A, tide -> A cos(omega t + phase).

    We use it as the flow velocity (m/s) that the drag sees (relative velocity = body - flow); in the
    paper's mode it is also added as a force (N) along the flow direction, as the paper does.
    """
    if kind not in FLOW_NAMES:
        raise ValueError(f"flow_force: kind={kind!r} must be one of {FLOW_NAMES}.")
    shape = np.broadcast(np.asarray(t), np.asarray(amplitude), np.asarray(omega), np.asarray(phase)).shape
    if kind == "still":
        return np.zeros(shape)
    if kind == "current":
        return np.broadcast_to(np.asarray(amplitude, dtype=float), shape).copy()
    return np.asarray(amplitude) * np.cos(np.asarray(omega) * t + phase)


def bekker_sinkage(pressure, kc, kphi, n, width):
    """Static sinkage of a plate under ``pressure`` (m), Bekker's pressure-sinkage relation inverted.

    p = (kc / b + kphi) z^n (Bekker, *Introduction to Terrain-Vehicle Systems*, 1969; Wong, *Theory of
    Ground Vehicles*, eq. 2.39) -> z = (p / (kc/b + kphi))^(1/n), b the smaller dimension of the plate.
    Zero for p <= 0 (no load, no sinkage).
    """
    p = np.asarray(pressure, dtype=float)
    k = np.asarray(kc) / width + np.asarray(kphi)
    return np.where(p > 0.0, np.maximum(p, 0.0) / k, 0.0) ** (1.0 / np.asarray(n))


def bulldozing_force(bulldoze_c, bulldoze_g, width, sinkage):
    """Bekker's bulldozing resistance of a foot of ``width`` sunk by ``sinkage`` pushing soil ahead (N).

    R_b = b (0.67 c K_pc z + 0.5 gamma K_pgamma z^2) (Bekker 1960/1969; Wong, *Theory of Ground Vehicles*,
    ch. 2), with ``bulldoze_c = 0.67 c K_pc`` and ``bulldoze_g = 0.5 gamma K_pgamma`` (``terrain/soil.py``). The GenTe
    paper's a z^n is this law with one of its two terms (n = 1: cohesive, n = 2: frictional soil).
    """
    z = np.maximum(np.asarray(sinkage, dtype=float), 0.0)
    return np.asarray(width) * (np.asarray(bulldoze_c) * z + np.asarray(bulldoze_g) * z * z)


def shear_strength(c, mu, area, normal_force):
    """Mohr-Coulomb shear strength of the soil under a sole (N): c A + F_N tan(phi), ``mu`` = tan(phi).

    The most traction the soil can give a foot (Wong, *Theory of Ground Vehicles*, eq. 2.57 integrated over a
    uniformly loaded sole; Coulomb 1776 / Mohr 1900).
    """
    return np.asarray(c) * area + np.maximum(np.asarray(normal_force, dtype=float), 0.0) * np.asarray(mu)


def soil_traction(c, mu, area, normal_force, slip, K):
    """Traction the soil has mobilised after a shear displacement ``slip`` since touchdown (N).

    Janosi-Hanamoto (Janosi & Hanamoto 1961; Wong eq. 2.56): (c A + F_N tan phi)(1 - exp(-j/K)), K the shear
    deformation modulus (m). ``slip`` j is the distance the sole has slid over the soil (its path length: the
    soil is sheared whichever way the foot moves), so the traction never stores energy.
    """
    j = np.maximum(np.asarray(slip, dtype=float), 0.0)
    return shear_strength(c, mu, area, normal_force) * (1.0 - np.exp(-j / np.asarray(K)))


def soil_friction(c, mu, area, normal_force, slip, K, cap, bulldozing=0.0, surface_mu=np.inf):
    """Friction coefficient that makes a sole contact's Coulomb limit the soil's resistance: the shear, the
    weaker of the sole's interface (``surface_mu``, the cell's friction: ice under snow) and the soil's mobilised
    traction (Mohr-Coulomb, Janosi-Hanamoto), plus Bekker's bulldozing resistance, the passive pressure on the
    sunk sole's leading face (not shear: it adds to either), over F_N, at most ``cap`` (the cohesion and
    bulldozing terms over F_N grow without bound as F_N -> 0).

    Soil cells give their contacts this coefficient instead of the rigid ground's, so the soil limits the
    traction instead of adding to it; the contact solver keeps it dissipative and, unlike a force against the
    velocity, implicit (both resistances are rate-independent): a foot held still does not chatter.
    """
    fn = np.maximum(np.asarray(normal_force, dtype=float), 1e-6)
    shear = np.minimum(surface_mu, soil_traction(c, mu, area, fn, slip, K) / fn)
    return np.minimum(shear + bulldozing / fn, cap)


# Resistive force theory (Li, Zhang & Goldman, "A terradynamics of legged locomotion on granular media",
# Science 339, 2013, and its supplementary Table S2): the generic Fourier coefficients of the stresses per unit
# depth on a plate element, in units of the medium constant zeta (alpha_z of a horizontal plate pushed straight
# down: A00 + A10 + B11 + B01 + B-11 = 1.000). The same nine values appear in the public implementations that
# cite the paper (e.g. Treers et al., RA-L 2021); the C terms multiply cosines (a Fourier series' cosine part),
# which gives alpha_x = 0 for a horizontal plate pushed straight down, as symmetry requires.
RFT_GENERIC = {"A00": 0.206, "A10": 0.169, "B11": 0.212, "B01": 0.358, "B-11": 0.055,
               "C11": -0.124, "C01": 0.253, "C-11": 0.007, "D10": 0.088}


def rft_alpha(beta, gamma, zeta):
    """Stresses per unit depth (N/m^3) on a plate element in granular media: (alpha_x, alpha_z).

    Li et al. 2013's discrete Fourier fit, sum over m = -1..1, n = 0..1 of
    A_mn cos(2 m beta + n gamma) + B_mn sin(...) (alpha_z) and C_mn cos(...) + D_mn sin(...) (alpha_x), with the
    generic coefficients (``RFT_GENERIC``) times ``zeta`` (N/m^3). ``beta``: the plate's angle of attack (its
    surface against the horizontal), ``gamma``: the angle of its velocity below the horizontal (pi/2: moving
    straight down), both in the vertical plane of the motion. alpha_z pushes up, alpha_x against the horizontal
    direction of motion; the stress on an element at depth |z| is alpha |z|.
    """
    k = RFT_GENERIC
    beta, gamma = np.asarray(beta, float), np.asarray(gamma, float)
    az = (k["A00"] + k["A10"] * np.cos(2 * beta) + k["B11"] * np.sin(2 * beta + gamma) + k["B01"] * np.sin(gamma)
          + k["B-11"] * np.sin(-2 * beta + gamma))
    ax = (k["C11"] * np.cos(2 * beta + gamma) + k["C01"] * np.cos(gamma) + k["C-11"] * np.cos(-2 * beta + gamma)
          + k["D10"] * np.sin(2 * beta))
    return np.asarray(zeta) * ax, np.asarray(zeta) * az


def rft_plane(normal, velocity):
    """(beta, gamma, e) of a plate element with unit ``normal`` moving at ``velocity``: RFT's angles in the
    vertical plane of the motion and that plane's horizontal unit vector ``e`` (along the horizontal velocity;
    for a vertical motion, along the normal's horizontal part, else x).

    beta = atan2(n_z, n_e) + pi/2 (the plate's tangent against the horizontal; the fit is pi-periodic in beta,
    so either face's normal gives the same stresses), gamma = atan2(-v_z, v_e), in [-pi/2, pi/2].
    """
    n, v = np.asarray(normal, float), np.asarray(velocity, float)
    vh = np.array([v[0], v[1], 0.0])
    nh = np.array([n[0], n[1], 0.0])
    if np.linalg.norm(vh) > 1e-9:
        e = vh / np.linalg.norm(vh)
    elif np.linalg.norm(nh) > 1e-9:
        e = nh / np.linalg.norm(nh)
    else:
        e = np.array([1.0, 0.0, 0.0])
    beta = np.arctan2(n[2], n @ e) + np.pi / 2
    gamma = np.arctan2(-v[2], v @ e)
    return beta, gamma, e


def rft_element_force(normal, velocity, depth, area, zeta, speed_reg):
    """Horizontal RFT force (N, 3-vector) on a sole element of ``area`` at ``depth`` below the surface:
    -alpha_x(beta, gamma) |z| A e, faded in linearly below ``speed_reg`` (m/s), as the reported bulldozing is.

    The vertical stress is the sinkage law the contact holds the foot with (``rft_support``, ``rft_sinkage``),
    so it is not applied here as a force too.
    """
    v = np.asarray(velocity, float)
    if depth <= 0.0 or np.linalg.norm(v) <= 0.0:
        return np.zeros(3)
    beta, gamma, e = rft_plane(normal, v)
    ax, _ = rft_alpha(beta, gamma, zeta)
    fade = min(np.linalg.norm(v) / speed_reg, 1.0)
    return -ax * depth * area * fade * e


def rft_face_force(velocity, depth, face_width, zeta, speed_reg):
    """Horizontal RFT force (N, 3-vector) on a sunk sole's leading face: the soil wall of ``face_width`` (the
    footprint projected across the horizontal motion, as Bekker's bulldozing width) from the surface down to
    the sole's ``depth``, pushed along the motion. Each strip of it at depth |s| is a vertical plate (beta =
    pi/2) moving at gamma: the stress alpha_x(pi/2, gamma) |s| integrates over 0..depth to
    -alpha_x depth^2 / 2 * face_width e (Li et al. 2013's elements summed over the face), faded in linearly
    below ``speed_reg`` (m/s) as the plate's elements are. Its centre of pressure is depth / 3 above the sole's
    contact plane. A motion with no horizontal part moves the face along itself: no force. This is the part of
    RFT that stands for Bekker's bulldozing."""
    v = np.asarray(velocity, float)
    vh = np.array([v[0], v[1], 0.0])
    speed_h = np.linalg.norm(vh)
    if depth <= 0.0 or speed_h <= 0.0:
        return np.zeros(3)
    gamma = np.arctan2(-v[2], speed_h)
    ax, _ = rft_alpha(np.pi / 2, gamma, zeta)
    fade = min(np.linalg.norm(v) / speed_reg, 1.0)
    return -ax * 0.5 * depth**2 * face_width * fade * vh / speed_h


def rft_support(normal, velocity, speed_reg):
    """RFT's vertical stress per unit depth under a sole of unit ``normal`` moving at ``velocity``, in units of
    zeta: alpha_z(beta, gamma) / zeta, faded linearly to 1 (a sole pushed straight down, alpha_z(0, pi/2) = zeta)
    as the speed drops below ``speed_reg`` (m/s), as the horizontal stress fades (``rft_element_force``).

    The velocity's upward part is left out (gamma is then at least 0): the sole bears on the medium with its lower
    face only, and RFT's smaller (down to negative) alpha_z of a plate rising through the medium comes from the
    grains above a buried plate, which a sole in its open rut does not have; a rising sole unloads, and its rut
    (plastic) keeps its depth, so a sole rising straight up is supported as at rest, not as one dragged sideways
    (whose rut would deepen under it while it rebounds).
    """
    v = np.asarray(velocity, float)
    v = np.array([v[0], v[1], min(v[2], 0.0)])
    beta, gamma, _ = rft_plane(normal, v)
    _, az = rft_alpha(beta, gamma, 1.0)
    fade = min(np.linalg.norm(v) / speed_reg, 1.0)
    return 1.0 + fade * (az - 1.0)


def rft_sinkage(pressure, zeta, support):
    """Sinkage (m) of a sole under ``pressure`` in an RFT medium whose vertical stress is ``support`` zeta |z|
    (``rft_support``): z = p / (support zeta), the depth whose stress carries the load; 0 for p <= 0. Where RFT
    gives the motion no upward stress (support <= 0, a steep sole dragged leading edge down) no depth carries
    the load: the support is taken as 1e-6 (the rut then deepens at ``sinkage_rate``)."""
    p = np.asarray(pressure, dtype=float)
    return np.where(p > 0.0, np.maximum(p, 0.0) / (np.asarray(zeta) * np.maximum(support, 1e-6)), 0.0)
