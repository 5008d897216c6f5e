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


def added_mass(rho, cm, radius, submerged_length):
    """Added (hydrodynamic) mass of a cylinder accelerating across a fluid (kg): cm * rho * pi r^2 L.

    Morison equation inertia term; cm = 1 for a circular cylinder in potential flow (Hoerner; Newman,
    *Marine Hydrodynamics*, 1977, sec. 4.13). The reaction force is -m_a * (relative acceleration).
    """
    return np.asarray(cm) * rho * np.pi * np.asarray(radius) ** 2 * submerged_length


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


def soil_friction(c, mu, area, normal_force, slip, K, cap):
    """Friction coefficient that makes a contact's Coulomb limit the soil's mobilised traction: the traction
    over F_N, at most ``cap`` (the cohesion term c A / F_N grows without bound as F_N -> 0).

    Soil cells give their contacts this coefficient instead of the rigid ground's, so the soil limits the
    traction (Mohr-Coulomb) instead of adding to it; the contact solver keeps it dissipative.
    """
    fn = np.maximum(np.asarray(normal_force, dtype=float), 1e-6)
    return np.minimum(soil_traction(c, mu, area, fn, slip, K) / fn, cap)
