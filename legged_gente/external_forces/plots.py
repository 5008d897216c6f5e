"""The water figure of docs/forces.md, drawn from the numpy references along a kinematic trajectory.

``python -m legged_gente.external_forces.plots docs/img`` writes ``forces_gait.png`` (strip-theory forces on one
swinging shin over two gait cycles in still water, a current and a tide); the trajectory is scripted, not
simulated. The soil figure is simulated: ``tools/plot_forces_soil.py``.
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

RHO, G, CD, CA = 1000.0, 9.81, 1.1, 1.0  # CA: the added-mass coefficient (Morison cm = 1 + CA)


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
                fi = WM.inertia_force(RHO, CA, vol, du, axis) - CA * RHO * vol * (acc - np.dot(acc, axis) * axis)
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


def main(argv=None):
    out = Path((argv or sys.argv[1:] or ["docs/img"])[0])
    out.mkdir(parents=True, exist_ok=True)
    gait_figure(out / "forces_gait.png")


if __name__ == "__main__":
    main()
