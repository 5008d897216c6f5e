"""Roll out a trained policy, export it (one self-contained ONNX file with deployment metadata), plot command
tracking, optionally record a video.

    python legged_gente/scripts/play.py --task=gente_biped [--load_run RUN --checkpoint N | --pretrained] [--video]
"""

from __future__ import annotations

import os
from pathlib import Path

import numpy as np
import torch

from legged_gente.utils.args import (
    build_parser, check_log_root, flag, import_mujoco, override_of, parse_args, run_command)

import_mujoco("gente-play")  # before the imports below load it (a MUJOCO_GL it cannot use: one line)

from legged_gente.envs.task_registry import apply_args, check_run_folder_names, log_root_of, task_registry
from legged_gente.utils.export import deployment_metadata, export_onnx


def export_policy(runner, env, export_dir: Path, checkpoint, task: str) -> Path:
    """The actor as ``export_dir/policy.onnx``: one file, input the actor's observation groups (the 'policy' group
    by default; ``runner.obs_groups``), with the deployment metadata (observation names and scales, action scale,
    default joint positions, PD gains, dt)."""
    actor = runner.alg.get_policy()
    return export_onnx(actor, export_dir / "policy.onnx", deployment_metadata(env, checkpoint, task, actor.obs_groups))


def plot_tracking(log: dict[str, np.ndarray], dt: float, path: Path) -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    t = (np.arange(len(log["cmd"])) + 1) * dt  # entry k: robot 0 after policy step k + 1
    fig, axes = plt.subplots(3, 1, figsize=(8, 7), sharex=True)
    for ax, i, label in zip(axes, range(3), ("vx (m/s)", "vy (m/s)", "yaw rate (rad/s)")):
        ax.plot(t, log["cmd"][:, i], label="command", color="k", linestyle="--")
        ax.plot(t, log["vel"][:, i], label="actual", color="tab:blue")
        ax.set_ylabel(label)
        ax.grid(alpha=0.3)
        for key, colour, style in (("reset", "tab:gray", ":"), ("fall", "tab:red", "-")):
            for n, when in enumerate(t[np.asarray(log.get(key, []), bool)]):  # a fall is also a reset
                ax.axvline(when, color=colour, linestyle=style, linewidth=1.2, label=f"robot 0 {key}" if n == 0 else None)
    axes[0].legend(loc="upper right")
    axes[-1].set_xlabel("time (s)")
    fig.suptitle("commanded vs actual base velocity (robot 0)")
    fig.tight_layout()
    fig.savefig(path, dpi=100)
    plt.close(fig)


class VideoRecorder:
    """Offscreen frames of robot 0 on its terrain in the material colours, with a following camera
    (:class:`legged_gente.viewer.video.VideoRenderer`; MUJOCO_GL=egl, or osmesa)."""

    def __init__(self, env, width: int = 640, height: int = 480):
        from legged_gente.sim.assembly import resolve_path
        from legged_gente.viewer.video import VideoRenderer

        self.env = env
        self.renderer = VideoRenderer(resolve_path(env.cfg.asset.file), env.terrain, width=width, height=height)

    def capture(self) -> None:
        self.renderer.capture(self.env.sim.qpos[0].cpu().numpy())

    def save(self, path: Path, fps: float) -> None:
        import imageio

        imageio.mimsave(path, self.renderer.frames, fps=fps)
        self.renderer.close()


def play(args) -> dict:
    if args.video:
        from legged_gente.viewer.video import check_offscreen_rendering

        check_offscreen_rendering()
    if getattr(args, "pretrained", False):
        task_registry.shipped_policy(args.task)  # a task without a shipped policy: say so before building anything
        check_log_root(args.log_root, log_root_of(args))  # its exports go there
    env_cfg, train_cfg = task_registry.get_play_cfgs(args.task, 16)
    apply_args(args, env_cfg, train_cfg)
    check_run_folder_names(train_cfg.runner)  # before building: --pretrained's exports go there too
    env, _ = task_registry.make_env(args.task, args, env_cfg=env_cfg)
    log_root = log_root_of(args)
    if getattr(args, "pretrained", False):
        runner, checkpoint = task_registry.make_pretrained_runner(env, args.task, train_cfg)
        # a shipped policy has no run folder of its own: its exports go beside the user's runs of the task
        export_dir = log_root / train_cfg.runner.experiment_name / "pretrained" / "exported"
        print(f"Loaded the policy shipped for {args.task}: {checkpoint}")
    else:
        train_cfg.runner.resume = True
        runner, train_cfg, _ = task_registry.make_alg_runner(env, args.task, args, train_cfg=train_cfg,
                                                             log_root=log_root, policy_only=True)
        checkpoint = runner.loaded_checkpoint
        export_dir = checkpoint.parent / "exported"  # per run: another run's play never overwrites it
    policy = runner.get_inference_policy(device=env.device)
    onnx_path = export_policy(runner, env, export_dir, checkpoint, args.task)
    print(f"Exported policy to {onnx_path}")

    recorder = VideoRecorder(env) if args.video else None
    viewer = _open_viewer(env) if not args.headless and os.environ.get("DISPLAY") else None
    obs = env.get_observations()
    log = {"cmd": [], "vel": [], "reset": [], "fall": []}
    with torch.inference_mode():
        for _ in range(args.steps):
            obs, _, _, _ = env.step(policy(obs))
            log["cmd"].append(env.commands[0, :3].cpu().numpy().copy())  # on the CPU .cpu() is the live tensor
            log["vel"].append(torch.cat([env.base_lin_vel[0, :2], env.base_ang_vel[0, 2:3]]).cpu().numpy())
            log["reset"].append(bool(env.reset_buf[0]))  # the episode of robot 0 ended at this step
            log["fall"].append(bool(env.reset_buf[0] & ~env.time_out_buf[0]))
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
    return {"onnx": onnx_path, "plot": plot_path, "log": log, "policy": policy, "env": env, "checkpoint": checkpoint}


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


def build_play_parser():
    parser = build_parser("Roll out, export and record a trained policy.", prog="gente-play", training=False)
    parser.add_argument("--video", action="store_true", help="write an mp4 of robot 0")
    parser.add_argument("--steps", type=int, default=500, help="policy steps to roll out")
    parser.add_argument(*flag("--log_root"), default=None,
                        help="where runs are (default: $GENTE_LOG_ROOT, else ./logs)")
    parser.add_argument("--pretrained", action="store_true",
                        help="play the policy shipped with the package for --task (resources/policies/<task>/)")
    return parser


def main(argv=None) -> None:
    parser = build_play_parser()
    args = parse_args(parser, argv)
    if args.pretrained and (args.load_run or args.checkpoint is not None):
        parser.error("--pretrained plays the shipped policy; leave out --load_run/--checkpoint")
    resume_set = override_of(args.overrides, "runner.resume")
    if resume_set is not None:  # play sets runner.resume itself, after the --set
        parser.error(f"gente-play always loads a checkpoint (a run's, or the shipped one with --pretrained); leave out "
                     f"--set {resume_set}")
    run_command("gente-play", play, args)


if __name__ == "__main__":
    main()
