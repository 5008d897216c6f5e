"""The curriculum's first pass after a --resume: a gente_biped checkpoint on its curriculum, its robots restored to
the checkpoint's levels (one in every stride, so that each keeps its column), rsl-rl's random initial episode
lengths, one whole episode (1000 steps); the mean level every 100 steps. The record of how docs/performance.md's
numbers were made (the code of 5b2a81e):

    python first_episode_after_resume.py MODE ROBOTS CHECKPOINT

MODE: own_time (the rule since then), whole_episode (legged_gym's: the start offsets ignored), no_random_start
(every episode whole: the control)."""
import sys

import torch

from legged_gente.envs.task_registry import task_registry

mode, robots, checkpoint = sys.argv[1], int(sys.argv[2]), sys.argv[3]
env_cfg, train_cfg = task_registry.get_cfgs("gente_biped")
env_cfg.env.num_envs = robots
env, _ = task_registry.make_env("gente_biped", None, env_cfg=env_cfg)
runner = task_registry.make_policy_runner(env, "gente_biped", checkpoint, train_cfg)
policy = runner.get_inference_policy(device="cpu")
saved = torch.load(checkpoint, map_location="cpu", weights_only=False)["infos"]["curriculum"]["terrain_levels"]
stride = saved.numel() // robots  # robot j sits in the column of the saved run's robot j * stride
print(env.load_curriculum_state({"terrain_levels": saved[::stride][:robots].clone()}))
torch.manual_seed(1)
if mode != "no_random_start":
    env.episode_length_buf = torch.randint_like(env.episode_length_buf, high=int(env.max_episode_length))
    if mode == "whole_episode":
        env._episode_start_step.zero_()
obs = env.get_observations()
with torch.inference_mode():
    for i in range(env.max_episode_length):
        obs, _, _, _ = env.step(policy(obs))
        if (i + 1) % 100 == 0:
            print(mode, i + 1, f"{env.terrain_levels.float().mean().item():.3f}", flush=True)
