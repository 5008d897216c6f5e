"""Multi-GPU and multi-node PPO under ``torchrun``: one process (rank) per GPU, each with its own envs.

    torchrun --standalone --nproc_per_node=2 legged_gente/scripts/train.py --task=gente_biped_flat
    torchrun --nnodes=2 --node_rank=K --nproc_per_node=8 --rdzv_backend=c10d --rdzv_endpoint=HOST0:29500 \
        --rdzv_id=JOB legged_gente/scripts/train.py --task=gente_biped_flat      # on each of two hosts

torchrun starts ``nproc_per_node`` copies of train.py on each host and gives each RANK (global, 0 ..
WORLD_SIZE - 1 over all hosts), LOCAL_RANK (on this host, 0 .. LOCAL_WORLD_SIZE - 1), WORLD_SIZE and
GROUP_RANK (the host's rank), plus MASTER_ADDR/MASTER_PORT for the process group. Each rank builds ``num_envs``
envs on ``cuda:{LOCAL_RANK}`` (``--device cpu``: on the CPU with the gloo backend, for tests), seeds torch with
``seed + RANK`` so the ranks explore differently, collects its own rollouts, and rsl-rl's PPO averages the
gradients over the ranks (all-reduce) after rank 0's parameters were broadcast at the start. Only global
rank 0 logs and saves checkpoints.

rsl-rl 5.5's own ``OnPolicyRunner._configure_multi_gpu`` only goes distributed when WORLD_SIZE > 1, always
uses NCCL and needs ``cuda:{LOCAL_RANK}``; ``GenteOnPolicyRunner`` also takes a one-process torchrun launch
as distributed (so the code path runs in CI), picks gloo on the CPU, and says clearly what is wrong.
"""

from __future__ import annotations

import atexit
import os
import warnings
from dataclasses import dataclass

import torch
import torch.distributed as dist
from rsl_rl.runners import OnPolicyRunner

from legged_gente.utils.episode_logger import DeferredLogger
from legged_gente.utils.ppo import compile_update_if_configured, mixed_precision_on_cuda_only

TORCHRUN_VARS = ("RANK", "LOCAL_RANK", "WORLD_SIZE")

# NVLink multicast (NVLS / NVLink SHARP) is off unless the user turns it on: NCCL enables it by itself on
# NVSwitch systems, PPO's all-reduce of 1.5-2.4 MB gains nothing from it, and with it off training does not depend
# on the host's NVSwitch multicast support (which shared hosts may restrict). Setting these variables to other
# values turns it on, with a warning (docs/multi_gpu.md). Set before NCCL is initialised.
MULTICAST_OFF = {"NCCL_NVLS_ENABLE": "0", "TORCH_SYMM_MEM_DISABLE_MULTICAST": "1"}


@dataclass(frozen=True)
class Launch:
    """This process's place in a torchrun launch."""

    rank: int  # global rank over all hosts, 0 .. world_size - 1: seeds, logging
    local_rank: int  # rank on this host: the CUDA device index
    world_size: int  # ranks over all hosts
    node: int = 0  # the host's rank (torchrun's GROUP_RANK)

    def rsl_rl_multi_gpu(self) -> dict:
        """The train config's ``multi_gpu`` keys that rsl-rl's PPO reads (all-reduce of the gradients and KL,
        broadcast of the learning rate)."""
        return {"global_rank": self.rank, "local_rank": self.local_rank, "world_size": self.world_size}


def torchrun_launch(environ=None) -> Launch | None:
    """The torchrun ranks from the environment, or None when the process was not started by torchrun."""
    environ = os.environ if environ is None else environ
    present = [name for name in TORCHRUN_VARS if name in environ]
    if not present:
        return None
    missing = [name for name in TORCHRUN_VARS if name not in environ]
    if missing:
        raise ValueError(f"torchrun environment incomplete: {present} set but {missing} missing; launch with "
                         f"`torchrun --nproc_per_node=N ...`, or unset {present} for a single-process run")
    values = {name: environ[name] for name in TORCHRUN_VARS}
    values.update({name: environ[name] for name in ("LOCAL_WORLD_SIZE", "GROUP_RANK") if name in environ})
    try:
        numbers = {name: int(value) for name, value in values.items()}
    except ValueError:
        raise ValueError(f"torchrun variables must be integers, got {values}") from None
    rank, local_rank, world_size = (numbers[name] for name in TORCHRUN_VARS)
    local_world_size = numbers.get("LOCAL_WORLD_SIZE", world_size)
    if (world_size < 1 or not 0 <= rank < world_size or not 0 <= local_rank < local_world_size <= world_size
            or numbers.get("GROUP_RANK", 0) < 0):
        raise ValueError(f"inconsistent torchrun ranks {values}: need 0 <= RANK < WORLD_SIZE, "
                         f"0 <= LOCAL_RANK < LOCAL_WORLD_SIZE <= WORLD_SIZE and GROUP_RANK >= 0")
    return Launch(rank, local_rank, world_size, numbers.get("GROUP_RANK", 0))


def rank_device(device: str | None, launch: Launch) -> str:
    """The device of this rank: ``None`` or ``cuda`` become ``cuda:{LOCAL_RANK}`` (``cpu`` without CUDA);
    an explicit device must be ``cpu`` or ``cuda:{LOCAL_RANK}`` (see ``check_rank_device``)."""
    if device is None:
        device = "cuda" if torch.cuda.is_available() else "cpu"
    if device == "cuda":
        device = f"cuda:{launch.local_rank}"
    check_rank_device(device, launch.local_rank)
    return device


def check_rank_device(device: str, local_rank: int) -> None:
    """Each rank must own exactly one device: ``cuda:{LOCAL_RANK}``, or the CPU."""
    if device != "cpu" and device != f"cuda:{local_rank}":
        raise ValueError(f"device {device!r} does not belong to torchrun LOCAL_RANK {local_rank}: under torchrun "
                         f"each rank trains on cuda:{local_rank}; pass --device cuda (or leave --device out), "
                         f"or --device cpu for a CPU (gloo) run")


def backend_for(device: str) -> str:
    """torch.distributed backend for the device the ranks train on: NCCL between GPUs, gloo on the CPU."""
    if device.startswith("cuda"):
        return "nccl"
    if device == "cpu":
        return "gloo"
    raise ValueError(f"no distributed backend for device {device!r}: use cuda:N (NCCL) or cpu (gloo)")


def init_process_group(launch: Launch, device: str) -> str:
    """Join the torchrun process group once (env:// rendezvous from torchrun's MASTER_ADDR/PORT); the backend."""
    backend = backend_for(device)
    if dist.is_initialized():
        if dist.get_backend() != backend or dist.get_world_size() != launch.world_size:
            raise RuntimeError(f"a {dist.get_backend()} process group of {dist.get_world_size()} ranks already "
                               f"exists, but this run needs {backend} with {launch.world_size}")
        return backend
    if backend == "nccl":
        for name, value in MULTICAST_OFF.items():
            os.environ.setdefault(name, value)
            if os.environ[name] != value:
                warnings.warn(f"{name}={os.environ[name]} turns NVLink multicast on (off by default: "
                              f"docs/multi_gpu.md); unset it or set {name}={value} to keep it off", stacklevel=2)
        torch.cuda.set_device(device)
        dist.init_process_group("nccl", rank=launch.rank, world_size=launch.world_size,
                                device_id=torch.device(device))
    else:
        dist.init_process_group("gloo", rank=launch.rank, world_size=launch.world_size)
    atexit.register(dist.destroy_process_group)
    return backend


MATMUL_PRECISIONS = ("highest", "high", "medium")  # torch.set_float32_matmul_precision's settings


class GenteOnPolicyRunner(OnPolicyRunner):
    """rsl-rl's OnPolicyRunner, made distributed by any torchrun launch, with per-rank torch seeds, the
    configured float32 matmul precision, the update's bf16 autocast (``algorithm.use_mixed_precision``) and
    compiled MLPs (``runner.compile_update``) on CUDA only, and a logger that does not sync with the GPU at every
    env step."""

    def __init__(self, env, train_cfg: dict, log_dir: str | None = None, device: str = "cpu"):
        precision = train_cfg.get("matmul_precision", "highest")
        if precision not in MATMUL_PRECISIONS:
            raise ValueError(f"runner.matmul_precision={precision!r}; use one of {MATMUL_PRECISIONS} "
                             f"(torch.set_float32_matmul_precision)")
        if str(device).startswith("cuda"):
            torch.set_float32_matmul_precision(precision)
        mixed_precision_on_cuda_only(train_cfg, device)
        super().__init__(env, train_cfg, log_dir, device)
        compile_update_if_configured(self.alg, train_cfg)
        self.logger = DeferredLogger(log_dir=log_dir, cfg=self.cfg, env_cfg=self.env.cfg, num_envs=self.env.num_envs,
                                     is_distributed=self.is_distributed, gpu_world_size=self.gpu_world_size,
                                     gpu_global_rank=self.gpu_global_rank, device=self.device)

    def _configure_multi_gpu(self) -> None:
        launch = torchrun_launch()
        if launch is None:  # plain `python train.py`: rsl-rl's single-process settings
            self.gpu_world_size, self.gpu_local_rank, self.gpu_global_rank = 1, 0, 0
            self.is_distributed = False
            self.cfg["multi_gpu"] = None
        else:
            check_rank_device(str(self.device), launch.local_rank)
            self.gpu_world_size, self.gpu_local_rank, self.gpu_global_rank = (
                launch.world_size, launch.local_rank, launch.rank)
            self.is_distributed = True
            self.cfg["multi_gpu"] = launch.rsl_rl_multi_gpu()
            backend = init_process_group(launch, str(self.device))
        # rsl-rl seeds nothing itself: one seed per rank, or every rank would draw the same actions
        self.cfg["seed"] = int(self.cfg["seed"]) + self.gpu_global_rank
        torch.manual_seed(self.cfg["seed"])  # CPU and every CUDA device
        if launch is not None:
            print(f"[distributed] rank {launch.rank}/{launch.world_size} (node {launch.node}, local "
                  f"{launch.local_rank}) on {self.device}, backend {backend}, seed {self.cfg['seed']}"
                  f"{'' if launch.rank == 0 else ', logs on rank 0'}", flush=True)

    task_name: str | None = None  # the registered task, recorded in checkpoints (set by the task registry)

    def save(self, path: str, infos: dict | None = None) -> None:
        """rsl-rl's checkpoint plus the env's curriculum state, what the checkpoint is for (task, action count)
        and the env steps trained so far; written to a temporary file and renamed, so an interrupted save never leaves a truncated one."""
        saved = self.alg.save()
        saved["iter"] = self.current_learning_iteration
        saved["infos"] = {**(infos or {}), "curriculum": self.env.curriculum_state(), "task": self.task_name,
                          "num_actions": self.env.num_actions, "total_steps": self.logger.tot_timesteps}
        partial = f"{path}.partial"
        torch.save(saved, partial)
        os.replace(partial, path)
        self.logger.save_model(path, self.current_learning_iteration)

    def load(self, path: str, load_cfg: dict | None = None, strict: bool = True, map_location: str | None = None):
        """rsl-rl's load, but safe (``torch.load(weights_only=True)``) and with a one-line error for a checkpoint
        of another task whose networks do not fit (one whose networks fit, e.g. the task a user's task subclasses,
        is loaded and named); also restores the env's curriculum when the checkpoint has one of this task that fits
        (``self.curriculum_message`` says what happened). The tensors go to ``map_location``, by default the
        runner's device: a run trained on a GPU continues on the CPU, or on cuda:1 from cuda:0."""
        from legged_gente.utils.checkpoints import (CheckpointError, check_checkpoint_fits, check_state_fits,
                                                    load_checkpoint)

        loaded = load_checkpoint(path, map_location or self.device)
        check_checkpoint_fits(loaded, path, self.task_name, self.env.num_actions, self.alg.get_policy().state_dict(),
                              strict, getattr(self.env, "left_out_observations", None))
        wanted = {"critic": True, "optimizer": True, "iteration": True} if load_cfg is None else load_cfg  # rsl-rl's
        if "critic_state_dict" not in loaded and wanted.get("critic"):
            raise CheckpointError(
                f"checkpoint {path} holds only the policy (a shipped model.pt): play or evaluate it (gente-play "
                f"--pretrained or --load_run, gente-evaluate --checkpoint) or fine-tune it (gente-train --pretrained); "
                f"resuming training needs a run's model_<N>.pt.")
        missing = [key for part, key in (("optimizer", "optimizer_state_dict"), ("iteration", "iter"))
                   if wanted.get(part) and key not in loaded]
        if missing:
            raise CheckpointError(f"checkpoint {path} has no {' or '.join(missing)}: resuming training needs a run's "
                                  f"model_<N>.pt as gente-train writes it; play or evaluate this one (gente-play "
                                  f"--load_run, gente-evaluate --checkpoint).")
        if wanted.get("critic"):
            check_state_fits(loaded["critic_state_dict"], self.alg.save()["critic_state_dict"], path, "critic", strict)
        infos = loaded.get("infos")
        if self.alg.load(loaded, load_cfg, strict):
            self.current_learning_iteration = loaded["iter"]
            # rsl-rl's logger counts from 0 in every run: a resumed run's "Total steps" go on from the checkpoint's
            self.logger.tot_timesteps = int((infos or {}).get("total_steps", 0))
        saved_task = (infos or {}).get("task")
        if saved_task and self.task_name and saved_task != self.task_name:
            # its networks fit (check_checkpoint_fits refuses those that do not), but its levels are another grid's
            self.curriculum_message = (f"the checkpoint is of task {saved_task}, this task is {self.task_name}: its "
                                       f"weights are loaded (the networks fit), the terrain curriculum restarts")
        elif infos and "curriculum" in infos:
            self.curriculum_message = self.env.load_curriculum_state(infos["curriculum"])
        else:
            self.curriculum_message = "the checkpoint has no curriculum state"
        return infos
