"""Figures of docs/forces.md, drawn from the numpy references along kinematic trajectories.

``python -m legged_gente.external_forces.plots docs/img`` writes ``forces_gait.png`` (strip-theory forces on one
swinging shin over two gait cycles in still water, a current and a tide) and ``forces_soil.png`` (sinkage,
bulldozing and traction limit of one biped foot on dry sand, snow and mud). The trajectories are scripted, not
simulated.
"""

from __future__ import annotations

import sys
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

from legged_gente.external_forces import models  # noqa: E402
from legged_gente.external_forces import water_models as WM  # noqa: E402
from legged_gente.terrain.soil import SOIL_PRESETS  # noqa: E402

RHO, G, CD, CM = 1000.0, 9.81, 1.1, 1.0


def gait_figure(path: Path):
    """A shin (r = 4 cm, 40 cm) hanging from a knee 0.45 m up, swinging +-0.4 rad at 1 Hz while the knee walks at
    0.5 m/s, in 30 cm of still water, a 0.4 m/s current and a 0.4 m/s, 0.5 Hz tide: strip theory (water_models)."""
    r, half, knee_z, depth, walk = 0.04, 0.2, 0.45, 0.30, 0.5
    t = np.linspace(0.0, 2.0, 401)
    phi = 0.4 * np.sin(2 * np.pi * t)  # shin angle from the vertical, about y
    om = 0.4 * 2 * np.pi * np.cos(2 * np.pi * t)
    al = -0.4 * (2 * np.pi) ** 2 * np.sin(2 * np.pi * t)
    flows = {"still": ("still", 0.0, 0.0), "current 0.4 m/s": ("current", 0.4, 0.0),
             "tide 0.4 m/s, 0.5 Hz": ("tide", 0.4, np.pi)}
    fig, axes = plt.subplots(4, 1, figsize=(7, 8), sharex=True)
    for name, (kind, amp, omega) in flows.items():
        rows = []
        for ti, ph, w, a in zip(t, phi, om, al):
            axis = np.array([np.sin(ph), 0.0, np.cos(ph)])  # knee to ankle is -axis
            knee = np.array([walk * ti, 0.0, knee_z])
            u = np.array([models.flow_force(kind, ti, amp, omega), 0.0, 0.0])
            du = np.array([-amp * omega * np.sin(omega * ti) if kind == "tide" else 0.0, 0.0, 0.0])
            wv = np.array([0.0, w, 0.0])
            drag = inertia = buoy = paper = np.zeros(3)
            torque = 0.0
            for p, _, vol in WM.segment_slices(knee - half * axis, axis, r, half, lambda q: depth):
                arm = p - knee
                v = np.array([walk, 0.0, 0.0]) + np.cross(wv, arm)
                acc = np.cross([0.0, a, 0.0], arm) + np.cross(wv, np.cross(wv, arm))
                fd = WM.crossflow_drag(RHO, CD, r, vol, v - u, axis)
                fi = WM.inertia_force(RHO, CM, vol, du, axis) - CM * RHO * vol * (acc - np.dot(acc, axis) * axis)
                drag, inertia = drag + fd, inertia + fi
                buoy = buoy + np.array([0.0, 0.0, RHO * G * vol])
                paper = paper + WM.crossflow_drag(RHO, CD, r, vol, v - u, axis, paper_area=True)
                torque += np.cross(arm, fd)[1]
            rows.append((drag[0], inertia[0], buoy[2], paper[0], torque))
        rows = np.asarray(rows)
        axes[0].plot(t, rows[:, 0], label=name)
        axes[1].plot(t, rows[:, 1], label=name)
        axes[3].plot(t, rows[:, 4], label=name)
        if kind == "still":
            axes[0].plot(t, rows[:, 3], "k:", label="still, paper's area 2*pi*r*h")
            axes[2].plot(t, rows[:, 2], "k", label="buoyancy (all flows)")
    axes[0].set_ylabel("drag x (N)")
    axes[1].set_ylabel("inertia x (N)\n(added mass + F-K)")
    axes[2].set_ylabel("buoyancy z (N)")
    axes[3].set_ylabel("drag torque\nabout knee (N m)")
    axes[3].set_xlabel("time (s)")
    for ax in axes:
        ax.legend(fontsize=7, loc="upper right")
        ax.grid(alpha=0.3)
    fig.suptitle("Shin r=4 cm, 40 cm, swinging +-0.4 rad at 1 Hz, walking 0.5 m/s in 30 cm of water "
                 "(strip theory, 3 Gauss slices)", fontsize=9)
    fig.tight_layout()
    fig.savefig(path, dpi=80)
    plt.close(fig)


def soil_figure(path: Path):
    """One biped foot (sole 0.22 m x 0.096 m, 41.5 kg) over a 0.5 s stance: half-sine load peaking at 1.2 m g,
    ploughing forward at 0.1 m/s; and the traction each soil gives that foot under its weight against the
    distance it has slid (Janosi-Hanamoto), with its Mohr-Coulomb limit."""
    mass, length, width = 41.5, 0.22, 0.096
    area = length * width
    t = np.linspace(0.0, 0.5, 401)
    load = 1.2 * mass * G * np.sin(np.pi * t / 0.5)
    j = np.linspace(0.0, 0.15, 301)
    fig, axes = plt.subplots(3, 1, figsize=(7, 7.5))
    for name, color in (("dry_sand", "C1"), ("snow", "C0"), ("mud", "C5")):
        s = SOIL_PRESETS[name]
        z = np.maximum.accumulate(models.bekker_sinkage(load / area, s.kc[0], s.kphi[0], s.n[0], width))
        bull = models.bulldozing_force(s.bulldoze_c[0], s.bulldoze_g[0], width, z)
        traction = models.soil_traction(s.c[0], s.mu[0], area, mass * G, j, s.K[0])
        axes[0].plot(t, 100 * z, color=color, label=f"{name} (the foot is shown this deep)")
        axes[1].plot(t, bull, color=color, label=name)
        axes[2].plot(100 * j, traction, color=color, label=f"{name}: T(j)")
        axes[2].axhline(models.shear_strength(s.c[0], s.mu[0], area, mass * G), color=color, ls=":", lw=1)
    axes[2].axhline(mass * G, color="k", ls="--", lw=1, label="rigid ground, mu = 1")
    axes[0].set_ylabel("sinkage (cm)")
    axes[0].set_yscale("log")
    axes[0].set_ylim(0.05, 50.0)
    axes[1].set_ylabel("bulldozing at 0.1 m/s (N)")
    axes[0].set_xlabel("time in stance (s)")
    axes[1].set_xlabel("time in stance (s)")
    axes[2].set_ylabel("traction limit (N)")
    axes[2].set_xlabel("slid since touchdown j (cm); dotted: Mohr-Coulomb c A + W tan(phi)")
    for ax in axes:
        ax.legend(fontsize=7)
        ax.grid(alpha=0.3)
    fig.suptitle("Biped foot 0.22 x 0.096 m, 41.5 kg: stance (plastic rut) and traction vs slip", fontsize=9)
    fig.tight_layout()
    fig.savefig(path, dpi=80)
    plt.close(fig)


def main(argv=None):
    out = Path((argv or sys.argv[1:] or ["docs/img"])[0])
    out.mkdir(parents=True, exist_ok=True)
    gait_figure(out / "forces_gait.png")
    soil_figure(out / "forces_soil.png")


if __name__ == "__main__":
    main()
