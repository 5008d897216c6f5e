"""tools/make_videos.py (the README's gait videos): a quick look (--seconds) at one clip renders it, lists it in
clips.json and leaves out the GIF when the clip ends before the GIF's part of it. Offscreen OpenGL: MUJOCO_GL=egl."""

import json
import os
import subprocess
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]


def test_a_short_river_clip_has_no_gif_and_is_listed(tmp_path):
    env = dict(os.environ, MUJOCO_GL=os.environ.get("MUJOCO_GL", "egl"))
    done = subprocess.run([sys.executable, str(ROOT / "tools" / "make_videos.py"), str(tmp_path), "--clips", "river",
                           "--seconds", "0.2", "--size", "64", "48"], env=env, capture_output=True, text=True,
                          timeout=300)
    assert done.returncode == 0, done.stderr[-2000:]
    assert "no GIF: the river clip (0.2 s) ends before the GIF's start" in done.stdout
    clips = json.loads((tmp_path / "clips.json").read_text())
    assert [c["clip"] for c in clips] == ["river"] and clips[0]["frames"] == 5  # 10 policy steps, every 2nd
    assert (tmp_path / "river.mp4").stat().st_size > 0 and not (tmp_path / "river.gif").exists()


def test_a_clip_of_no_length_is_a_usage_error(tmp_path):
    done = subprocess.run([sys.executable, str(ROOT / "tools" / "make_videos.py"), str(tmp_path), "--seconds", "0"],
                          capture_output=True, text=True, timeout=60)
    assert done.returncode == 2 and "--seconds must be > 0" in done.stderr


def test_an_odd_video_size_is_a_usage_error(tmp_path):
    """H.264 in yuv420p stores colour per 2 x 2 pixels: an odd width fails in the encoder, after every frame."""
    done = subprocess.run([sys.executable, str(ROOT / "tools" / "make_videos.py"), str(tmp_path), "--size", "65", "48"],
                          capture_output=True, text=True, timeout=60)
    assert done.returncode == 2 and "--size 65 48: width and height must be even and >= 2" in done.stderr
    assert "Traceback" not in done.stderr


def test_clips_film_the_nominal_robot(load_file):
    """The clips kept training's friction draw (0.5-1.25 per robot): each film showed a robot on another friction
    than the one gente-play and the evaluation show."""
    from legged_gente.envs.task_registry import task_registry
    from legged_gente.utils.args import apply_overrides

    tool = load_file("tools/make_videos.py")
    env_cfg, train_cfg = task_registry.get_cfgs("gente_biped")
    apply_overrides(tool.clip_settings(tool.CLIPS[0]), env_cfg, train_cfg)
    rand = env_cfg.domain_rand
    assert not (rand.randomize_friction or rand.randomize_base_mass or rand.push_robots or env_cfg.noise.add_noise)
