"""Figures of docs/forces.md, drawn from the numpy references along kinematic trajectories.

``python -m legged_gente.external_forces.plots docs/img`` writes ``forces_gait.png`` (forces on one shin
over a gait cycle in still water, a current and a tide) and ``forces_soil.png`` (sinkage and resistance
of one foot over a stance on dry sand and on mud). The trajectories are scripted, not simulated.
"""

from __future__ import annotations

import sys
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

from legged_gente.external_forces import models  # noqa: E402
from legged_gente.terrain.soil import SOIL_PRESETS  # noqa: E402

RHO, G, CD, CM = 1000.0, 9.81, 1.1, 1.0


def gait_figure(path: Path):
    """Shin of radius 4 cm and 40 cm length in 30 cm deep water, walking at 0.5 m/s with a 1 s stride."""
    t = np.linspace(0.0, 2.0, 801)
    phase = 2 * np.pi * t  # 1 Hz gait
    v = 0.5 + 0.6 * np.sin(phase)  # shin centroid speed along x: stance slower, swing faster
    acc = 0.6 * 2 * np.pi * np.cos(phase)
    lift = 0.08 * np.clip(np.sin(phase), 0.0, None)  # swing lifts the foot by up to 8 cm
    r, depth = 0.04, 0.30
    lsub = np.clip(depth - lift, 0.0, 0.40)
    flows = {"still": ("still", 0.0, 0.0), "current 0.4 m/s": ("current", 0.4, 0.0),
             "tide 0.4 m/s, 0.5 Hz": ("tide", 0.4, np.pi)}
    fig, axes = plt.subplots(3, 1, figsize=(7, 6.5), sharex=True)
    for name, (kind, amp, omega) in flows.items():
        u = models.flow_force(kind, t, amp, omega)
        du = np.gradient(u, t)
        vrel = v - u
        drag = -np.sign(vrel) * models.cylinder_drag(RHO, CD, r, lsub, np.abs(vrel))
        inertia = -models.added_mass(RHO, CM, r, lsub) * (acc - du)
        axes[0].plot(t, drag, label=name)
        axes[1].plot(t, inertia, label=name)
    axes[2].plot(t, models.buoyancy(RHO, G, r, lsub), "k", label="buoyancy (all flows)")
    paper = -np.sign(v) * models.cylinder_drag(RHO, CD, r, lsub, np.abs(v), area="paper")
    axes[0].plot(t, paper, "k:", label="still, paper's area 2*pi*r*h")
    axes[0].set_ylabel("drag x (N)")
    axes[1].set_ylabel("added-mass reaction x (N)")
    axes[2].set_ylabel("buoyancy z (N)")
    axes[2].set_xlabel("time (s)")
    for ax in axes:
        ax.legend(fontsize=7, loc="upper right")
        ax.grid(alpha=0.3)
    fig.suptitle("Shin r=4 cm, 30 cm water, walking 0.5 m/s (scripted kinematics, numpy references)", fontsize=9)
    fig.tight_layout()
    fig.savefig(path, dpi=80)
    plt.close(fig)


def soil_figure(path: Path):
    """One foot (sole 0.2 m x 0.1 m) of a 40 kg biped over a 0.5 s stance: half-sine load peaking at
    1.2 m g, slipping backwards at 3 cm/s and ploughing forward at 0.1 m/s."""
    t = np.linspace(0.0, 0.5, 401)
    load = 1.2 * 40 * G * np.sin(np.pi * t / 0.5)
    width, area = 0.1, 0.02
    fig, axes = plt.subplots(3, 1, figsize=(7, 6.5), sharex=True)
    for name in ("dry_sand", "mud"):
        s = SOIL_PRESETS[name]
        z = np.maximum.accumulate(models.bekker_sinkage(load / area, s.kc[0], s.kphi[0], s.n[0], width))
        bull = models.bulldozing_force(width * s.bulldoze_a[0], s.bulldoze_n[0], z)
        shear = models.presliding_friction(s.mu[0], load, 0.03 * t, s.K[0])
        axes[0].plot(t, 100 * z, label=name)
        axes[1].plot(t, bull, label=name)
        axes[2].plot(t, shear, label=name)
    axes[0].set_ylabel("sinkage (cm)")
    axes[1].set_ylabel("bulldozing (N)")
    axes[2].set_ylabel("pre-sliding (N)")
    axes[2].set_xlabel("time in stance (s)")
    for ax in axes:
        ax.legend(fontsize=8)
        ax.grid(alpha=0.3)
    fig.suptitle("Foot 0.2x0.1 m, 40 kg biped, stance 0.5 s (plastic rut: deepest sinkage kept)", fontsize=9)
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
