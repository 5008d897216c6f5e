"""Share of ``mjw.step`` time spent in the terrain force kernels.

``forces_share(m, d, forces, steps)`` times ``steps`` substeps with the callbacks installed (plus
``after_substep``, and ``observe`` once per policy step of ``decimation`` substeps) and without, with
``wp.synchronize`` around each timing, and returns both times and the share.
``python -m legged_gente.external_forces.benchmark`` runs it on a small built-in wading/soil scene; ``gente-benchmark``
times the env's force kernels its own way (captured, in the env's state).
"""

from __future__ import annotations

import argparse
import time

import mujoco
import mujoco_warp as mjw
import numpy as np
import warp as wp


def _time_steps(m, d, steps: int, forces=None, decimation: int = 1) -> float:
    wp.synchronize()
    t0 = time.perf_counter()
    for k in range(steps):
        mjw.step(m, d)
        if forces is not None:
            forces.after_substep()
            if (k + 1) % decimation == 0:
                forces.observe()
    wp.synchronize()
    return time.perf_counter() - t0


def forces_share(m, d, forces, steps: int = 100, warmup: int = 5, decimation: int = 4) -> dict:
    """Seconds per substep with and without the force callbacks, and the forces' share of the step.

    ``forces`` is an installed or not-yet-installed ``TerrainForces`` on (m, d); the model's callbacks are
    restored to the installed state on return. On the GPU this times eager launches (no graph), which
    over-states the share of many small kernels slightly compared with the env's captured graph.
    """
    if steps < 1:
        raise ValueError(f"steps must be >= 1, got {steps}.")
    saved = (m.callback.passive, m.callback.contactfilter)
    m.callback.passive = m.callback.contactfilter = None
    _time_steps(m, d, warmup)
    base = _time_steps(m, d, steps)
    forces.install()
    _time_steps(m, d, warmup, forces, decimation)
    with_forces = _time_steps(m, d, steps, forces, decimation)
    if saved != (None, None):
        m.callback.passive, m.callback.contactfilter = saved
    return {
        "step_s": base / steps,
        "step_with_forces_s": with_forces / steps,
        "forces_share": max(with_forces - base, 0.0) / with_forces,
        "nworld": d.nworld,
        "steps": steps,
        "device": str(d.xfrc_applied.device),
    }


def demo_scene(nworld: int, device=None):
    """Two capsule legs with box feet on slide joints, half in water, half on dry sand."""
    from legged_gente.external_forces.field import ForcesConfig, TerrainForces
    from legged_gente.terrain.materials import MaterialMap

    legs = "".join(
        f'<body name="hip{i}" pos="{x} 0 0.32"><joint type="slide" axis="1 0 0" damping="5"/>'
        f'<joint type="slide" axis="0 0 1" damping="50"/>'
        f'<geom name="shin{i}" type="capsule" size="0.04 0.15" density="3000"/>'
        f'<geom name="foot{i}" type="box" size="0.06 0.05 0.02" pos="0 0 -0.21" mass="10"/></body>'
        for i, x in enumerate((-0.5, 0.5)))
    mjm = mujoco.MjModel.from_xml_string(
        f'<mujoco><option timestep="0.005"/><worldbody><geom type="plane" size="3 3 .1"/>{legs}'
        f'</worldbody></mujoco>')
    shape = (41, 41)
    mat = MaterialMap.rigid(shape)
    mat.water_surface[:20] = 0.25
    mat.flow_kind[:20] = 1
    mat.flow_speed[:20] = 0.5
    mat.soil[20:] = 0
    mat.soil_presets = ["dry_sand"]

    class Cfg(ForcesConfig):
        leg_geom_names = ["shin0", "shin1"]
        foot_geom_names = ["foot0", "foot1"]

    with wp.ScopedDevice(device):
        m = mjw.put_model(mjm)
        d = mjw.make_data(mjm, nworld=nworld, nconmax=16 * nworld, njmax=64 * nworld)
        forces = TerrainForces(mjm, m, d, np.zeros(shape, np.float32), (-2.0, -2.0), 0.1, mat, Cfg(), seed=0)
    return m, d, forces


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__)
    parser.add_argument("--nworld", type=int, default=64)
    parser.add_argument("--steps", type=int, default=50)
    parser.add_argument("--device", default=None, help="warp device, e.g. cpu or cuda:0 (default: warp's)")
    args = parser.parse_args(argv)
    m, d, forces = demo_scene(args.nworld, args.device)
    with wp.ScopedDevice(args.device):
        r = forces_share(m, d, forces, args.steps)
    print(f"{r['device']}: {r['nworld']} worlds, step {1e3 * r['step_s']:.3f} ms, with forces "
          f"{1e3 * r['step_with_forces_s']:.3f} ms, forces' share {100 * r['forces_share']:.1f} %")
    return r


if __name__ == "__main__":
    main()
