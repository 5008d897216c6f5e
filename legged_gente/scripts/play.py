"""Roll out a trained policy, export it (TorchScript + ONNX), plot command tracking, optionally record a video.

    python legged_gente/scripts/play.py --task=gente_biped [--load_run RUN --checkpoint N] [--video]
"""

from __future__ import annotations

import os
from pathlib import Path

import numpy as np
import torch

from legged_gente.envs.task_registry import LOG_ROOT, apply_args, task_registry
from legged_gente.utils.args import build_parser, parse_args


def export_policy(runner, export_dir: Path) -> tuple[Path, Path]:
    """TorchScript and ONNX copies of the actor (inputs: the concatenated 'policy' observation group)."""
    export_dir.mkdir(parents=True, exist_ok=True)
    runner.export_policy_to_jit(str(export_dir), "policy.pt")
    runner.export_policy_to_onnx(str(export_dir), "policy.onnx")
    return export_dir / "policy.pt", export_dir / "policy.onnx"


def plot_tracking(log: dict[str, np.ndarray], dt: float, path: Path) -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    t = np.arange(len(log["cmd"])) * dt
    fig, axes = plt.subplots(3, 1, figsize=(8, 7), sharex=True)
    for ax, i, label in zip(axes, range(3), ("vx (m/s)", "vy (m/s)", "yaw rate (rad/s)")):
        ax.plot(t, log["cmd"][:, i], label="command", color="k", linestyle="--")
        ax.plot(t, log["vel"][:, i], label="actual", color="tab:blue")
        ax.set_ylabel(label)
        ax.grid(alpha=0.3)
    axes[0].legend(loc="upper right")
    axes[-1].set_xlabel("time (s)")
    fig.suptitle("commanded vs actual base velocity (robot 0)")
    fig.tight_layout()
    fig.savefig(path, dpi=100)
    plt.close(fig)


class VideoRecorder:
    """Offscreen frames of world 0 through mujoco.Renderer (MUJOCO_GL=egl on GPU machines, osmesa on CPU)."""

    def __init__(self, env, width: int = 640, height: int = 480):
        import mujoco

        os.environ.setdefault("MUJOCO_GL", "egl" if torch.cuda.is_available() else "osmesa")
        self.mujoco, self.env = mujoco, env
        self.data = mujoco.MjData(env.mjm)
        try:
            self.renderer = mujoco.Renderer(env.mjm, height=height, width=width)
        except Exception as error:  # no GL context: say how to get one
            raise RuntimeError(f"offscreen rendering failed ({error}); on a CPU machine install OSMesa "
                               "(apt-get install libosmesa6) and set MUJOCO_GL=osmesa, on a GPU set MUJOCO_GL=egl") from error
        self.camera = mujoco.MjvCamera()
        self.camera.distance, self.camera.elevation, self.camera.azimuth = 3.0, -20.0, 135.0
        self.frames: list[np.ndarray] = []

    def capture(self) -> None:
        self.data.qpos[:] = self.env.sim.qpos[0].cpu().numpy()
        self.mujoco.mj_forward(self.env.mjm, self.data)
        self.camera.lookat[:] = self.data.qpos[:3]
        self.renderer.update_scene(self.data, self.camera)
        self.frames.append(self.renderer.render().copy())

    def save(self, path: Path, fps: float) -> None:
        import imageio

        imageio.mimsave(path, self.frames, fps=fps)


def play(args) -> dict:
    env_cfg, train_cfg = task_registry.get_cfgs(args.task)
    env_cfg.env.num_envs = min(env_cfg.env.num_envs, 16)
    env_cfg.noise.add_noise = False
    env_cfg.domain_rand.push_robots = False
    env_cfg.terrain.num_rows = min(env_cfg.terrain.num_rows, 5)
    env_cfg.terrain.num_cols = min(env_cfg.terrain.num_cols, 5)
    env_cfg.terrain.curriculum = False
    env_cfg.sim.torch_compile = False  # for 16 robots the compile (~20 s) costs more than it saves
    apply_args(args, env_cfg, train_cfg)
    train_cfg.runner.resume = True
    env, _ = task_registry.make_env(args.task, args, env_cfg=env_cfg)
    runner, train_cfg, _ = task_registry.make_alg_runner(env, args.task, args, train_cfg=train_cfg,
                                                         log_root=args.log_root)
    policy = runner.get_inference_policy(device=env.device)
    export_dir = Path(args.log_root) / train_cfg.runner.experiment_name / "exported"
    jit_path, onnx_path = export_policy(runner, export_dir)
    print(f"Exported policy to {jit_path} and {onnx_path}")

    recorder = VideoRecorder(env) if args.video else None
    viewer = _open_viewer(env) if not args.headless and os.environ.get("DISPLAY") else None
    obs = env.get_observations()
    log = {"cmd": [], "vel": []}
    with torch.inference_mode():
        for _ in range(args.steps):
            obs, _, _, _ = env.step(policy(obs))
            log["cmd"].append(env.commands[0, :3].cpu().numpy())
            log["vel"].append(torch.cat([env.base_lin_vel[0, :2], env.base_ang_vel[0, 2:3]]).cpu().numpy())
            if recorder is not None:
                recorder.capture()
            if viewer is not None:
                viewer.sync_from(env)
    log = {k: np.asarray(v) for k, v in log.items()}
    plot_path = export_dir / "velocity_tracking.png"
    plot_tracking(log, env.dt, plot_path)
    print(f"Wrote {plot_path}")
    if recorder is not None:
        video_path = export_dir / "rollout.mp4"
        recorder.save(video_path, fps=1.0 / env.dt)
        print(f"Wrote {video_path}")
    return {"jit": jit_path, "onnx": onnx_path, "plot": plot_path, "log": log, "policy": policy, "env": env}


def _open_viewer(env):
    import mujoco
    import mujoco.viewer

    class _Viewer:
        def __init__(self):
            self.data = mujoco.MjData(env.mjm)
            self.handle = mujoco.viewer.launch_passive(env.mjm, self.data)

        def sync_from(self, env_):
            self.data.qpos[:] = env_.sim.qpos[0].cpu().numpy()
            mujoco.mj_forward(env_.mjm, self.data)
            self.handle.sync()

    return _Viewer()


def main(argv=None) -> None:
    parser = build_parser("Roll out, export and record a trained policy.")
    parser.add_argument("--video", action="store_true", help="write an mp4 of robot 0")
    parser.add_argument("--steps", type=int, default=500, help="policy steps to roll out")
    parser.add_argument("--log_root", default=str(LOG_ROOT), help="where runs are (default: logs/)")
    play(parse_args(parser, argv))


if __name__ == "__main__":
    main()
