"""Draw docs/img/forces_soil.png from simulation: one biped foot (41.5 kg on a 0.22 m x 0.096 m sole of four
2 cm sole spheres, the analytic sole contacts on a heightfield) standing on dry sand, snow and mud, then pushed
along its length (x: its 9.6 cm width bulldozes) with a slowly rising force.

Left: the foot's depth in the sim (what the viewer shows) over the stance, against Bekker's static sinkage
computed here by hand, z = (p / (kc/b + kphi))^(1/n). Right: how far the foot slides against the push (over each
soil's Mohr-Coulomb limit T = c A + W tan(phi)), with T + R_b marked, R_b = b (bulldoze_c z + bulldoze_g z^2) the
bulldozing of a foot sunk z: up to T the soil's shear holds it, bar the slip that mobilises the shear
(Janosi-Hanamoto: about 3 cm by 0.9 T on dry sand); beyond, the bulldozing (part of the contacts' friction limit)
holds it, and once the push passes T + R_b it slides away.

Preset means (no per-episode scatter), CPU, about 15 s:
    PYTHONPATH=$PWD python tools/plot_forces_soil.py [--out docs/img/forces_soil.png]
"""

from __future__ import annotations

import argparse

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import mujoco  # noqa: E402
import mujoco_warp as mjw  # noqa: E402
import numpy as np  # noqa: E402
import warp as wp  # noqa: E402

from legged_gente.external_forces.field import ForcesConfig, TerrainForces  # noqa: E402
from legged_gente.terrain.materials import MaterialMap  # noqa: E402
from legged_gente.terrain.soil import PARAM_NAMES, SOIL_PRESETS, register_custom_soil  # noqa: E402

G, MASS, LENGTH, WIDTH, DT = 9.81, 41.5, 0.22, 0.096, 0.005
SOLE_XY = [(0.14, 0.028), (0.14, -0.028), (-0.04, 0.028), (-0.04, -0.028)]  # spheres r 2 cm: 0.22 x 0.096 m
SHAPE, RES, ORIGIN = (41, 41), 0.1, (-2.0, -2.0)
SOILS = {"dry_sand": "tab:orange", "snow": "tab:blue", "mud": "tab:brown"}
STANCE, RAMP, TOP = 400, 400, 2.5  # substeps: 2 s standing, then a push rising to 2.5 T for 2 s


class Cfg(ForcesConfig):
    noise_std = 0.0
    wading = False
    foot_geom_names = [f"sole{k}" for k in range(4)]


def foot_model() -> mujoco.MjModel:
    soles = "".join(f'<geom name="sole{k}" type="sphere" size="0.02" pos="{x} {y} 0" contype="0" conaffinity="0"/>'
                    for k, (x, y) in enumerate(SOLE_XY))
    return mujoco.MjModel.from_xml_string(f"""<mujoco><option timestep="{DT}"/>
      <asset><hfield name="hf" nrow="{SHAPE[1]}" ncol="{SHAPE[0]}" size="2 2 1 0.1"/></asset>
      <worldbody><geom name="terrain" type="hfield" hfield="hf"/>
        <body name="foot" pos="0 0 0.02"><joint type="slide" axis="1 0 0"/><joint type="slide" axis="0 0 1"/>
          <geom type="box" size="0.1 0.04 0.01" pos="0.05 0 0.03" mass="{MASS}" contype="0" conaffinity="0"/>
          {soles}</body></worldbody></mujoco>""")


def mean_soil(name: str) -> str:
    """A copy of preset ``name`` with its means only (the figure shows the preset, not one episode's draw)."""
    preset = SOIL_PRESETS[name]
    register_custom_soil(f"plot_{name}", **{p: getattr(preset, p)[0] for p in PARAM_NAMES}, model=preset.model)
    return f"plot_{name}"


def simulate(name: str, t_max: float):
    """(depth over the stance (m), push (N) and slide (m) over the ramp) of the foot on soil ``name``."""
    mjm = foot_model()
    mat = MaterialMap.rigid(SHAPE)
    mat.soil[:] = 0
    mat.soil_presets = [mean_soil(name)]
    m = mjw.put_model(mjm)
    d = mjw.make_data(mjm, nworld=1, nconmax=16, njmax=64)
    forces = TerrainForces(mjm, m, d, np.zeros(SHAPE, np.float32), ORIGIN, RES, mat, Cfg(), seed=0)
    forces.install()
    depth, push, slide = [], [], []
    for k in range(STANCE + RAMP):
        f = TOP * t_max * max(k - STANCE, 0) / RAMP
        d.qfrc_applied.assign(np.array([[f, 0.0]], np.float32))
        mjw.step(m, d)
        forces.after_substep()
        q = d.qpos.numpy()[0]
        if k < STANCE:
            depth.append(-q[1])
        else:
            push.append(f)
            slide.append(q[0])
    SOIL_PRESETS.pop(f"plot_{name}")
    return np.array(depth), np.array(push), np.array(slide) - slide[0]


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--out", default="docs/img/forces_soil.png")
    args = ap.parse_args(argv)
    wp.config.quiet = True
    wp.set_device("cpu")
    fig, (ax0, ax1) = plt.subplots(1, 2, figsize=(8.0, 3.0))
    t = np.arange(STANCE) * DT
    for name, colour in SOILS.items():
        s = SOIL_PRESETS[name]
        p = MASS * G / (LENGTH * WIDTH)  # 19.3 kPa
        z_bekker = (p / (s.kc[0] / WIDTH + s.kphi[0])) ** (1.0 / s.n[0])
        t_max = s.c[0] * LENGTH * WIDTH + MASS * G * s.mu[0]  # Mohr-Coulomb: c A + W tan(phi)
        bulldozing = WIDTH * (s.bulldoze_c[0] * z_bekker + s.bulldoze_g[0] * z_bekker**2)
        depth, push, slide = simulate(name, t_max)
        ax0.plot(t, 100 * depth, color=colour, label=f"{name}: shown")
        ax0.axhline(100 * z_bekker, color=colour, ls=":", lw=1)
        ax1.plot(push / t_max, 100 * slide, color=colour, label=name)
        ax1.axvline((t_max + bulldozing) / t_max, color=colour, ls=":", lw=1)
        at = [100 * slide[np.searchsorted(push, x * t_max)] for x in (0.9, 1.1)]
        print(f"{name}: shown {100 * depth[-1]:.1f} cm, Bekker {100 * z_bekker:.1f} cm; "
              f"Mohr-Coulomb T = {t_max:.0f} N, "
              f"bulldozing at z {bulldozing:.0f} N; slid {at[0]:.1f} cm at 0.9 T, {at[1]:.1f} cm at 1.1 T")
    ax0.set(xlabel="time in stance (s)", ylabel="foot depth (cm)", title="sinkage: sim (solid), Bekker (dotted)")
    ax0.invert_yaxis()
    ax0.legend(fontsize=7)
    ax1.axvline(1.0, color="k", ls="--", lw=1)
    ax1.set(xlabel="push along x / Mohr-Coulomb limit T", ylabel="slide (cm)", ylim=(-1, 30),
            title="traction: T (dashed), T + bulldozing (dotted)")
    ax1.legend(fontsize=7)
    for ax in (ax0, ax1):
        ax.title.set_fontsize(8)
        ax.tick_params(labelsize=7)
        ax.xaxis.label.set_fontsize(8)
        ax.yaxis.label.set_fontsize(8)
    fig.tight_layout()
    fig.savefig(args.out, dpi=90)
    print(f"wrote {args.out}")


if __name__ == "__main__":
    main()
