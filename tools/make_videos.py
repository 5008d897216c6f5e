"""The README's gait videos: the shipped gente_biped policy on six terrains (two rivers), rendered on the CPU.

    MUJOCO_GL=egl python tools/make_videos.py docs/videos            # every clip, then the GIF
    MUJOCO_GL=egl python tools/make_videos.py /tmp/v --clips river   # one clip

Each clip: one robot, the policy shipped in resources/policies/gente_biped (``--pretrained``), no observation
noise, pushes, or friction and mass draws (the nominal robot, as gente-play shows it) and a fixed command — walk
straight ahead (+x) at ``speed`` with heading 0, spawned at the tile's centre with yaw 0 — on one tile of the
terrain named below (seeded), with a 2 m border. Frames come from
:class:`legged_gente.viewer.video.VideoRenderer` (material colours, 1 m checker, water surface and flow arrows, a
sun with shadows, a camera following the base), every ``--every``-th policy step, encoded with ffmpeg (libx264,
CRF ``--crf``); the GIF is part of the river clip, smaller and slower-framed.
``clips.json`` lists per clip: falls, distance walked along x, rise of the base, mean forward velocity.
"""

from __future__ import annotations

import argparse
import dataclasses
import json
import os
import subprocess
import time
from pathlib import Path

import numpy as np


@dataclasses.dataclass
class Clip:
    name: str
    terrain: str  # one cfg.terrain.terrain_types entry
    seconds: float  # length of the clip
    speed: float = 0.7  # m/s, commanded forward velocity
    seed: int = 1


CLIPS = [
    # a channel along y whose near bank starts 1 m ahead of the spawn (offset: -x is the left of the +y axis),
    # 0.3 m deep with 1 m banks, water 0.25 m deep flowing at 0.5 m/s across the robot's path
    Clip("river", "river:width=2.5,depth=0.3,bank_width=1.0,direction=1.571,offset=-2.0"
                  "+water:depth=0.25,flow=current,speed=0.5,direction=1.571", 8.0),
    # a steeper one: 0.45 m deep, 0.5 m banks (42 degrees), water 0.35 m deep
    Clip("river_steep", "river:width=2.5,depth=0.45,bank_width=0.5,direction=1.571,offset=-1.8"
                        "+water:depth=0.35,flow=current,speed=0.5,direction=1.571", 11.0),
    Clip("dry_sand", "soil:preset=dry_sand", 5.0),
    Clip("snow", "soil:preset=snow", 5.0),
    Clip("mud", "soil:preset=mud", 5.0),
    Clip("stairs", "stairs:step_height=0.1,step_width=0.35,direction=up", 5.0, speed=0.6),
    Clip("obstacles", "discrete_obstacles:max_height=0.1,min_size=0.4,max_size=1.0,density=0.6", 5.0),
]
TASK = "gente_biped"
GIF_CLIP = "river"
GIF_SECONDS = (1.5, 5.0)
"""start and length (s) of the GIF's part of its clip: the robot stepping into the current and wading."""


def clip_settings(clip: Clip) -> list[str]:
    """``--set`` overrides of the task config for ``clip``."""
    return [
        f"terrain.terrain_types=['{clip.terrain}']", "terrain.terrain_proportions=[1.0]",
        "terrain.num_rows=1", "terrain.num_cols=1", "terrain.terrain_length=12.0", "terrain.terrain_width=8.0",
        "terrain.border_size=2.0", f"terrain.seed={clip.seed}", "terrain.curriculum=False",
        f"commands.ranges.lin_vel_x=[{clip.speed},{clip.speed}]", "commands.ranges.lin_vel_y=[0.0,0.0]",
        "commands.ranges.heading=[0.0,0.0]", "commands.still_fraction=0.0", "commands.resampling_time=1000.0",
        "domain_rand.random_init_yaw=False", "domain_rand.init_lin_vel_xy_noise=0.0", "domain_rand.push_robots=False",
        "domain_rand.randomize_friction=False", "domain_rand.randomize_base_mass=False",
        "noise.add_noise=False", "sim.torch_compile=False",
    ]


def record_clip(clip: Clip, out: Path, every: int, size: tuple[int, int], crf: int) -> dict:
    import torch

    from legged_gente.envs.task_registry import apply_args, task_registry
    from legged_gente.sim.assembly import resolve_path
    from legged_gente.utils.args import build_parser, parse_args
    from legged_gente.viewer.video import VideoRenderer

    argv = ["--task", TASK, "--device", "cpu", "--num_envs", "1", "--headless", "--seed", str(clip.seed)]
    for setting in clip_settings(clip):
        argv += ["--set", setting]
    args = parse_args(build_parser("clip"), argv)
    env_cfg, train_cfg = task_registry.get_cfgs(TASK)
    apply_args(args, env_cfg, train_cfg)
    env, _ = task_registry.make_env(TASK, args, env_cfg=env_cfg)
    runner, _ = task_registry.make_pretrained_runner(env, TASK, train_cfg)
    policy = runner.get_inference_policy(device=env.device)
    renderer = VideoRenderer(resolve_path(env_cfg.asset.file), env.terrain, width=size[0], height=size[1])
    steps = int(round(clip.seconds / env.dt))
    obs = env.get_observations()
    start = env.sim.qpos[0, :3].cpu().numpy().copy()
    falls, resets, vx = 0, 0, []
    t0 = time.perf_counter()
    with torch.inference_mode():
        for step in range(steps):
            obs, _, _, _ = env.step(policy(obs))
            if bool(env.reset_buf[0]):
                resets += 1
                falls += int(not bool(env.time_out_buf[0]))
            vx.append(float(env.base_lin_vel[0, 0]))
            if step % every == 0:
                renderer.capture(env.sim.qpos[0].cpu().numpy())
    end = env.sim.qpos[0, :3].cpu().numpy()
    renderer.close()
    path = out / f"{clip.name}.mp4"
    encode_mp4(renderer.frames, path, fps=1.0 / (env.dt * every), crf=crf)
    return {"clip": clip.name, "terrain": clip.terrain, "seed": clip.seed, "command_vx": clip.speed,
            "seconds": clip.seconds, "falls": falls, "resets": resets,
            "distance_x_m": round(float(end[0] - start[0]), 2) if not resets else None,
            "base_rise_m": round(float(end[2] - start[2]), 2) if not resets else None,
            "mean_vx": round(float(np.mean(vx)), 3), "cpu_s": round(time.perf_counter() - t0, 1),
            "file": path.name, "bytes": path.stat().st_size, "frames": len(renderer.frames)}


def ffmpeg() -> str:
    import imageio_ffmpeg

    return imageio_ffmpeg.get_ffmpeg_exe()


def encode_mp4(frames: list[np.ndarray], path: Path, fps: float, crf: int) -> None:
    h, w = frames[0].shape[:2]
    cmd = [ffmpeg(), "-y", "-loglevel", "error", "-f", "rawvideo", "-pix_fmt", "rgb24", "-s", f"{w}x{h}",
           "-r", f"{fps:g}", "-i", "-", "-c:v", "libx264", "-preset", "slow", "-crf", str(crf), "-pix_fmt",
           "yuv420p", "-movflags", "+faststart", str(path)]
    subprocess.run(cmd, input=np.stack(frames).tobytes(), check=True)


def encode_gif(mp4: Path, path: Path, width: int, fps: int, colours: int) -> None:
    """A palette GIF of ``GIF_SECONDS`` of ``mp4`` (ffmpeg's palettegen/paletteuse: one palette for the clip)."""
    graph = (f"fps={fps},scale={width}:-1:flags=lanczos,split[a][b];"
             f"[a]palettegen=max_colors={colours}:stats_mode=diff[p];[b][p]paletteuse=dither=bayer:bayer_scale=3")
    subprocess.run([ffmpeg(), "-y", "-loglevel", "error", "-ss", f"{GIF_SECONDS[0]:g}", "-t", f"{GIF_SECONDS[1]:g}",
                    "-i", str(mp4), "-vf", graph, str(path)], check=True)


def main(argv=None) -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("out", type=Path)
    parser.add_argument("--clips", nargs="+", choices=[c.name for c in CLIPS], default=[c.name for c in CLIPS])
    parser.add_argument("--every", type=int, default=2, help="render every n-th policy step (2: 25 fps)")
    parser.add_argument("--size", type=int, nargs=2, default=(640, 480), metavar=("W", "H"))
    parser.add_argument("--crf", type=int, default=28, help="x264 quality (larger: smaller files)")
    parser.add_argument("--gif_width", type=int, default=320)
    parser.add_argument("--gif_fps", type=int, default=10)
    parser.add_argument("--gif_colours", type=int, default=64)
    parser.add_argument("--seconds", type=float, help="every clip this long (a quick look); default: each clip's own")
    args = parser.parse_args(argv)
    if args.seconds is not None and args.seconds <= 0 or args.every < 1:
        parser.error("--seconds must be > 0 and --every >= 1")
    if any(v < 2 or v % 2 for v in args.size):  # H.264 in yuv420p stores colour per 2 x 2 pixels
        parser.error(f"--size {args.size[0]} {args.size[1]}: width and height must be even and >= 2 (e.g. 640 480)")
    os.environ.setdefault("MUJOCO_GL", "egl")
    args.out.mkdir(parents=True, exist_ok=True)
    report = []
    for clip in (c for c in CLIPS if c.name in args.clips):
        if args.seconds is not None:
            clip = dataclasses.replace(clip, seconds=args.seconds)
        report.append(record_clip(clip, args.out, args.every, tuple(args.size), args.crf))
        print(json.dumps(report[-1]), flush=True)
    gif_clip = next((c for c in report if c["clip"] == GIF_CLIP), None)
    if gif_clip is not None and gif_clip["seconds"] < GIF_SECONDS[0] + 0.5:  # ffmpeg fails on a GIF of no frame
        print(f"no GIF: the {GIF_CLIP} clip ({gif_clip['seconds']:g} s) ends before the GIF's start "
              f"({GIF_SECONDS[0]:g} s) and half a second")
    elif gif_clip is not None:
        gif = args.out / f"{GIF_CLIP}.gif"
        encode_gif(args.out / f"{GIF_CLIP}.mp4", gif, args.gif_width, args.gif_fps, args.gif_colours)
        print(f"wrote {gif} ({gif.stat().st_size} bytes)")
    listed = args.out / "clips.json"  # the clips made now replace their entries; the others stay
    kept = [c for c in json.loads(listed.read_text()) if c["clip"] not in args.clips] if listed.exists() else []
    order = [c.name for c in CLIPS]
    listed.write_text(json.dumps(sorted(kept + report, key=lambda c: order.index(c["clip"])), indent=1) + "\n")


if __name__ == "__main__":
    main()
