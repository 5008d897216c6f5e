"""Task registry: a name -> (env class, env cfg, train cfg); builds envs and rsl-rl runners from args."""

from __future__ import annotations

import argparse
import contextlib
import io
import json
import os
import warnings
from datetime import datetime
from pathlib import Path

import torch

from legged_gente.envs.base.base_config import near_misses
from legged_gente.envs.base.legged_robot_config import LeggedRobotCfg, LeggedRobotCfgPPO, rsl_rl_train_cfg
from legged_gente.envs.terrain_arg import apply_terrain_arg
from legged_gente.terrain.terrain import check_grid_settings
from legged_gente.utils.args import apply_overrides, override_of

CPU_MANY_ENVS = 64  # more robots than this on the CPU: say that it will be slow, and how to make it fast


def default_log_root() -> Path:
    """Where runs go: ``$GENTE_LOG_ROOT``, else ``logs/`` in the current working directory (legged_gym's habit:
    a project's runs land in the project's folder, never in the installed package)."""
    return Path(os.environ.get("GENTE_LOG_ROOT") or "logs").absolute()


def log_root_of(args) -> Path:
    """Where a command's runs are: its ``--log_root`` if given, else ``default_log_root()``."""
    given = getattr(args, "log_root", None)
    return Path(given) if given else default_log_root()


# PPO's settings outside which rsl-rl trains on without complaint but learns nothing sensible: (field, test, bound)
PPO_RANGES = (
    ("learning_rate", lambda v: v > 0, "> 0"),
    ("clip_param", lambda v: v > 0, "> 0"),
    ("gamma", lambda v: 0 < v <= 1, "in (0, 1]"),
    ("lam", lambda v: 0 <= v <= 1, "in [0, 1]"),
    ("max_grad_norm", lambda v: v > 0, "> 0"),
    ("value_loss_coef", lambda v: v >= 0, ">= 0"),
    ("entropy_coef", lambda v: v >= 0, ">= 0"),
    ("desired_kl", lambda v: v > 0, "> 0"),
)
PPO_SCHEDULES = ("adaptive", "fixed")


def is_one_folder_name(value) -> bool:
    """A name that makes one folder inside another: a non-empty string, not '.' or '..', without a path separator."""
    return isinstance(value, str) and value not in ("", ".", "..") and "/" not in value and os.sep not in value


def check_run_folder_names(runner_cfg) -> None:
    """``runner.experiment_name`` and ``runner.run_name`` (if any) each name one folder of
    ``<log root>/<experiment_name>/<date>_<run_name>/``: a '/', '.' or '..' would put a run outside the log root
    or where ``--resume`` never looks, and an empty experiment name would make the log root itself the experiment."""
    for field, value in (("experiment_name", runner_cfg.experiment_name), ("run_name", runner_cfg.run_name)):
        if field == "run_name" and not value:
            continue
        if not is_one_folder_name(value):
            raise ValueError(f"runner.{field}={value!r}: runs are written to <log root>/<experiment_name>/"
                             f"<date>_<run_name>/, one folder each; give a name without '/' that is not empty, '.' or "
                             f"'..' (--{field} or --set runner.{field}=...)")


def validate_cfgs(env_cfg: LeggedRobotCfg | None, train_cfg: LeggedRobotCfgPPO | None) -> None:
    """The settings that divide or count (a zero would crash deep in the env or rsl-rl) and PPO's ranges, checked
    up front."""
    checks = []
    if env_cfg is not None:
        check_grid_settings(env_cfg.terrain)
        checks += [("sim.dt", env_cfg.sim.dt, float, 0.0), ("env.episode_length_s", env_cfg.env.episode_length_s, float, 0.0),
                   ("control.decimation", env_cfg.control.decimation, int, 1), ("env.num_envs", env_cfg.env.num_envs, int, 1),
                   ("terrain.hfield_piece_size", env_cfg.terrain.hfield_piece_size, float, 0.0)]
    if train_cfg is not None:
        r, a = train_cfg.runner, train_cfg.algorithm
        checks += [("runner.save_interval", r.save_interval, int, 1), ("runner.num_steps_per_env", r.num_steps_per_env, int, 1),
                   ("algorithm.num_mini_batches", a.num_mini_batches, int, 1),
                   ("algorithm.num_learning_epochs", a.num_learning_epochs, int, 1),
                   ("runner.max_iterations", r.max_iterations, int, 1)]  # rsl-rl saves a final checkpoint even after none
    for name, value, kind, low in checks:
        number = isinstance(value, (int, float)) and not isinstance(value, bool)
        if not number or (kind is int and value != int(value)):
            raise ValueError(f"{name}={value!r}: must be {'an integer' if kind is int else 'a number'} "
                             f"(--set {name}=...)")
        if (value <= low) if kind is float else (value < low):
            bound = f"> {low}" if kind is float else f">= {low}"
            raise ValueError(f"{name}={value!r}: must be {bound} (--set {name}=...)")
    if train_cfg is not None:
        for message in near_misses(train_cfg, "train_cfg"):
            warnings.warn(message, stacklevel=2)
        a = train_cfg.algorithm
        for field, test, bound in PPO_RANGES:
            value = getattr(a, field)
            if value is None and field == "desired_kl":
                continue  # rsl-rl's "no KL target": the learning rate stays fixed
            if isinstance(value, bool) or not isinstance(value, (int, float)) or not test(value):
                raise ValueError(f"algorithm.{field}={value!r}: must be a number {bound} (--set algorithm.{field}=...)")
        if a.schedule not in PPO_SCHEDULES:
            raise ValueError(f"algorithm.schedule={a.schedule!r}: use 'adaptive' (the learning rate follows "
                             f"desired_kl) or 'fixed' (--set algorithm.schedule=...)")
    if env_cfg is not None and train_cfg is not None:
        batch = env_cfg.env.num_envs * train_cfg.runner.num_steps_per_env
        if batch < train_cfg.algorithm.num_mini_batches:
            raise ValueError(f"env.num_envs * runner.num_steps_per_env = {env_cfg.env.num_envs} * "
                             f"{train_cfg.runner.num_steps_per_env} = {batch} samples cannot fill "
                             f"algorithm.num_mini_batches={train_cfg.algorithm.num_mini_batches} (an empty mini-batch "
                             f"makes the loss NaN); raise --num_envs or runner.num_steps_per_env, or lower "
                             f"algorithm.num_mini_batches")
        unused = batch % train_cfg.algorithm.num_mini_batches
        if unused:  # the update permutes the first num_mini_batches * (batch // num_mini_batches), as rsl-rl does
            warnings.warn(f"{unused} of the {batch} samples of each rollout (env.num_envs * runner.num_steps_per_env) "
                          f"are never used: algorithm.num_mini_batches={train_cfg.algorithm.num_mini_batches} does not "
                          f"divide them; choose num_envs or num_steps_per_env so that it does", stacklevel=2)


# The flags that set a config field, which a --set of that field would contradict (the flag is applied last)
FLAG_FIELDS = {"num_envs": "env.num_envs", "max_iterations": "runner.max_iterations",
               "experiment_name": "runner.experiment_name", "run_name": "runner.run_name",
               "load_run": "runner.load_run", "checkpoint": "runner.checkpoint"}


def apply_args(args: argparse.Namespace, env_cfg, train_cfg) -> None:
    """Override config instances with the flags that were given (None means 'keep the config's value'); a flag
    and a --set of the field it sets are refused (one of them would be ignored)."""
    overrides = getattr(args, "overrides", None) or []
    for flag, field in FLAG_FIELDS.items():
        value = getattr(args, flag, None)
        given = override_of(overrides, field)
        if value is not None and given:
            raise ValueError(f"--{flag} {value} and --set {given} both set {field}; give one")
    apply_overrides(overrides, env_cfg, train_cfg)
    if env_cfg is not None:
        if getattr(args, "num_envs", None) is not None:
            env_cfg.env.num_envs = args.num_envs
        if getattr(args, "terrain", None):
            apply_terrain_with_overrides(args.terrain, env_cfg, overrides)
    if train_cfg is not None:
        if getattr(args, "seed", None) is not None:
            train_cfg.seed = args.seed
        for flag in ("max_iterations", "experiment_name", "run_name", "load_run", "checkpoint"):
            value = getattr(args, flag, None)
            if value is not None:
                setattr(train_cfg.runner, flag, value)
        if getattr(args, "resume", False):
            train_cfg.runner.resume = True


# widened by --terrain <spec.json> to whole cells (by less than a cell): not a contradiction of a --set
TERRAIN_ROUNDED = ("terrain.border_size",)
SPEC_BOUND = ("terrain.terrain_length", "terrain.terrain_width", "terrain.resolution")
"""A generated tile's size and cells: its spec's, which a terrain_cfg.py of gente-generate repeats."""


def apply_terrain_with_overrides(terrain: str, env_cfg, overrides: list[str], given_as: str = "--terrain") -> None:
    """``--terrain`` after the --set: a terrain_cfg.py replaces the terrain section, and the --set terrain.* apply
    to the new one; 'plane' and a spec set fields of it, and a --set of one of those to another value is refused
    (it would be ignored). ``given_as``: how the refusals name the terrain's file (gente-view's source)."""
    given = [text for text in overrides if text.partition("=")[0].strip().startswith("terrain.")]

    def value_of(text):
        owner = env_cfg
        for part in text.partition("=")[0].strip().split("."):
            owner = getattr(owner, part)
        return owner

    section, wanted = env_cfg.terrain, {text: value_of(text) for text in given}
    apply_terrain_arg(terrain, env_cfg)
    if env_cfg.terrain is not section:
        # a module of generated terrain: its specs set the tile's size and cells, which a --set would contradict
        bound = {f: getattr(env_cfg.terrain, f.split(".")[1]) for f in SPEC_BOUND} \
            if env_cfg.terrain.mode == "generated" else {}
        apply_overrides(given, env_cfg, None)
        for text in given:
            field = text.partition("=")[0].strip()
            if field in bound and value_of(text) != bound[field]:
                raise ValueError(f"{given_as} {terrain} is generated terrain whose spec sets {field} to "
                                 f"{bound[field]!r}; leave out --set {text}")
        return
    for text, value in wanted.items():
        field = text.partition("=")[0].strip()
        if field not in TERRAIN_ROUNDED and value_of(text) != value:
            raise ValueError(f"{given_as} {terrain} sets {field} to {value_of(text)!r}; leave out --set {text}")


NETWORK_SECTIONS = ("actor", "critic")
"""The train config's sections of network settings, which a run's config.json records."""


def sets_a_network(override: str) -> bool:
    """Whether a ``--set SECTION.FIELD=VALUE`` sets a network setting (``NETWORK_SECTIONS``)."""
    return override.split(".")[0].strip() in NETWORK_SECTIONS


def nominal(env_cfg: LeggedRobotCfg) -> None:
    """The robot as built, for watching and scoring a policy: no observation noise, pushes, or friction and mass
    draws (legged_gym's play turns off the noise, pushes and friction draw)."""
    env_cfg.noise.add_noise = False
    rand = env_cfg.domain_rand
    rand.push_robots = rand.randomize_friction = rand.randomize_base_mass = False


class TaskRegistry:
    def __init__(self) -> None:
        self.tasks: dict[str, tuple[type, type, type]] = {}
        self.pretrained_from: dict[str, str] = {}

    def register(self, name: str, env_class: type, env_cfg: type[LeggedRobotCfg], train_cfg: type[LeggedRobotCfgPPO],
                 pretrained_from: str | None = None):
        """Name a task (env class, env config class, train config class). The classes are checked here, where a
        user's task module calls this, not at the first command; a name is taken once (the same three again are
        fine: a module imported twice). ``pretrained_from``: a task with a shipped policy that ``--pretrained``
        starts this one from (a task subclassed from it, with the same observations and actions)."""
        from legged_gente.envs.base.legged_robot import LeggedRobot

        for what, value, base in (("env_class", env_class, LeggedRobot), ("env_cfg", env_cfg, LeggedRobotCfg),
                                  ("train_cfg", train_cfg, LeggedRobotCfgPPO)):
            if not (isinstance(value, type) and issubclass(value, base)):
                got = value.__name__ if isinstance(value, type) else f"an instance of {type(value).__name__}"
                kind = f"{base.__name__} or a class derived from it" if base is LeggedRobot else \
                    f"a class derived from {base.__name__}"
                raise TypeError(f"register({name!r}, ...): {what} must be {kind}, got {got}")
        task = (env_class, env_cfg, train_cfg)
        if self.tasks.get(name, task) != task:
            taken = ", ".join(cls.__name__ for cls in self.tasks[name])
            raise ValueError(f"task {name!r} is already registered ({taken}); register {env_cfg.__name__} under "
                             f"another name")
        if pretrained_from is not None:
            from legged_gente.utils.checkpoints import shipped_tasks

            if pretrained_from not in shipped_tasks():
                raise ValueError(f"register({name!r}, ..., pretrained_from={pretrained_from!r}): no policy is shipped "
                                 f"for {pretrained_from!r}; shipped: {', '.join(shipped_tasks()) or 'none'}")
            self.pretrained_from[name] = pretrained_from
        self.tasks[name] = task

    def get_cfgs(self, name: str) -> tuple[LeggedRobotCfg, LeggedRobotCfgPPO]:
        if name not in self.tasks:
            raise KeyError(f"unknown task {name!r}; registered tasks: {sorted(self.tasks)}; a task kept outside the "
                           f"package is registered by its own module: run the command from a script that imports it "
                           f"(docs/new_robot.md)")
        _, env_cfg, train_cfg = self.tasks[name]
        return env_cfg(), train_cfg()

    def shipped_policy(self, name: str) -> tuple[str, Path]:
        """The task whose shipped policy ``--pretrained`` starts ``name`` from, and its ``model.pt``: the policy shipped
        for ``name``, else the one of the task it was registered with ``pretrained_from`` (a task of new rewards on
        the biped starts from the biped's policy; its sizes are checked when it loads)."""
        from legged_gente.utils.checkpoints import pretrained_policy, shipped_tasks

        source = name if name in shipped_tasks() else self.pretrained_from.get(name, name)
        return source, pretrained_policy(source)[0]

    def get_play_cfgs(self, name: str, num_envs: int) -> tuple[LeggedRobotCfg, LeggedRobotCfgPPO]:
        """The task's configs for watching a policy (gente-play, gente-view --play), as legged_gym's play: at most
        ``num_envs`` robots, the nominal robot (``nominal``), a grid of at most 5 x 5 tiles whose terrain types are
        drawn by the task's proportions (a curriculum's columns would show only its first five types)."""
        env_cfg, train_cfg = self.get_cfgs(name)
        env_cfg.env.num_envs = min(env_cfg.env.num_envs, num_envs)
        nominal(env_cfg)
        env_cfg.terrain.num_rows = min(env_cfg.terrain.num_rows, 5)
        env_cfg.terrain.num_cols = min(env_cfg.terrain.num_cols, 5)
        if env_cfg.terrain.mode == "curriculum":
            env_cfg.terrain.mode = "random"
        env_cfg.terrain.curriculum = False
        env_cfg.sim.torch_compile = False  # for a few robots the compile (~20 s) costs more than it saves
        return env_cfg, train_cfg

    def make_env(self, name: str, args=None, env_cfg: LeggedRobotCfg | None = None, device: str | None = None):
        """The task's env with ``args`` (argparse namespace from utils.args) applied to its config; ``device``
        (``cpu``, ``cuda``, ``cuda:N``): the one given, else ``args.device``, else the CPU."""
        default_env_cfg, train_cfg = self.get_cfgs(name)
        env_class = self.tasks[name][0]
        env_cfg = env_cfg or default_env_cfg
        if args is not None:
            apply_args(args, env_cfg, train_cfg)
        validate_cfgs(env_cfg, train_cfg)
        device = device or getattr(args, "device", None) or "cpu"
        if device == "cpu" and env_cfg.env.num_envs > CPU_MANY_ENVS:
            given = getattr(args, "num_envs", None) is not None
            whose = "that many are" if given else "the task's default is"
            print(f"[legged_gente] {env_cfg.env.num_envs} robots on the CPU (no GPU in use): {whose} sized for a GPU "
                  f"and will be slow here; pass e.g. --num_envs 4 for a quick CPU run", flush=True)
        # seed before the env draws anything (spawn yaw, commands, domain randomisation); one seed per rank
        torch.manual_seed(int(train_cfg.seed) + int(os.environ.get("RANK", "0")))
        env = env_class(env_cfg, device=device, train_cfg_steps_per_env=train_cfg.runner.num_steps_per_env)
        return env, env_cfg

    def make_alg_runner(self, env, name: str, args=None, train_cfg: LeggedRobotCfgPPO | None = None,
                        log_root: Path | str | None = "default", policy_only: bool = False):
        """An rsl-rl OnPolicyRunner for ``env``; loads a checkpoint when resuming (latest run by default; an
        unreadable latest checkpoint falls back to the newest readable one). ``log_root``: where runs are
        ("default": ``default_log_root()``; None: no run folder). ``policy_only``: load the checkpoint's policy
        alone, for playing it (an actor-only ``model.pt`` plays too; training needs the critic and optimiser)."""
        from legged_gente.utils.checkpoints import find_checkpoint
        from legged_gente.utils.distributed import GenteOnPolicyRunner

        source, pretrained = self.shipped_policy(name) if getattr(args, "pretrained", False) else (None, None)
        if train_cfg is None:
            _, train_cfg = self.get_cfgs(name)
            if pretrained is not None:
                network_sizes_from(pretrained, train_cfg)  # before the flags: a --set that does not fit is an error
            if args is not None:
                apply_args(args, None, train_cfg)
        runner_cfg = train_cfg.runner
        check_run_folder_names(runner_cfg)
        if log_root == "default":
            log_root = default_log_root()
        experiment_root = Path(log_root).absolute() / runner_cfg.experiment_name if log_root is not None else None
        if runner_cfg.resume:  # the networks its checkpoint was trained with (a --pretrained run's: 32 x 32)
            resumed = find_checkpoint(experiment_root, runner_cfg.load_run, runner_cfg.checkpoint)
            given = next(filter(sets_a_network, getattr(args, "overrides", None) or []), None)
            if network_sizes_from(resumed, train_cfg) and given is not None:
                raise ValueError(f"--set {given}: a resumed run keeps the networks recorded in "
                                 f"{resumed.parent / 'config.json'}; leave it out")
        validate_cfgs(None, train_cfg)
        log_dir = None
        if experiment_root is not None:
            stamp = datetime.now().strftime("%Y-%m-%d_%H-%M-%S")
            log_dir = str(experiment_root / (stamp + (f"_{runner_cfg.run_name}" if runner_cfg.run_name else "")))
            base, n = log_dir, 1
            while Path(log_dir).exists():  # another run started in the same second: never share its folder
                log_dir, n = f"{base}_{n}", n + 1
        runner = GenteOnPolicyRunner(env, rsl_rl_train_cfg(train_cfg), log_dir=log_dir, device=env.device)
        runner.task_name = name
        # the config (and the run's config.json) says what runs: bf16 applies on CUDA only (GenteOnPolicyRunner)
        train_cfg.algorithm.use_mixed_precision = runner.alg.use_mixed_precision
        if runner.gpu_global_rank != 0:
            log_dir = None  # under torchrun only rank 0 writes the run folder (rsl-rl logs from rank 0 only)
        if runner_cfg.resume:
            runner.loaded_checkpoint = load_newest_readable(runner, experiment_root, runner_cfg.load_run,
                                                            runner_cfg.checkpoint,
                                                            {"actor": True} if policy_only else None)
            if env.terrain_curriculum:  # play's and flat tasks' envs have none: nothing to say
                print(runner.curriculum_message)
            # a checkpoint stores the last *finished* iteration; continue with the next one
            runner.current_learning_iteration += 1
        elif pretrained is not None:
            # fine-tuning: the shipped actor (weights, observation normaliser, action noise); a shipped policy has
            # no critic, optimiser state or curriculum, so those start afresh, at iteration 0
            runner.load(str(pretrained), load_cfg={"actor": True}, map_location=env.device)
            runner.loaded_checkpoint = pretrained
            warmup = runner_cfg.critic_warmup_iterations
            if warmup:
                if not hasattr(runner.alg, "freeze_actor"):
                    raise ValueError(f"runner.critic_warmup_iterations={warmup} needs algorithm.class_name "
                                     f"legged_gente.utils.ppo:GentePPO, not {train_cfg.algorithm.class_name}; "
                                     f"set it to 0")
                runner.alg.freeze_actor(warmup)
            shipped_for = source if source == name else f"{source} ({name}'s pretrained_from)"
            message = (f"Starting from the policy shipped for {shipped_for} ({pretrained}): its actor; the critic, "
                       f"optimiser and curriculum start afresh")
            if warmup:
                message += f"; the first {warmup} iterations train the critic alone"
                if 0 < runner_cfg.max_iterations <= warmup:
                    message += (f". Note: --max_iterations {runner_cfg.max_iterations} ends inside that warm-up, so "
                                f"this run leaves the actor as shipped (continue with --resume, or lower "
                                f"runner.critic_warmup_iterations)")
            print(message)
        return runner, train_cfg, log_dir

    def make_pretrained_runner(self, env, name: str, train_cfg: LeggedRobotCfgPPO | None = None):
        """A runner (no run folder) with the policy shipped for task ``name`` loaded (actor only), its network
        sizes taken from the shipped config. The checkpoint's path."""
        _, path = self.shipped_policy(name)
        return self.make_policy_runner(env, name, path, train_cfg), path

    def make_policy_runner(self, env, name: str, checkpoint: Path, train_cfg: LeggedRobotCfgPPO | None = None):
        """A runner (no run folder) with the actor of ``checkpoint`` loaded, for playing or evaluating it: a run's
        ``model_<N>.pt`` or a shipped, actor-only ``model.pt``. The network sizes come from the ``config.json``
        beside it when there is one (a run folder or a shipped policy's folder), else the actor's are read off its
        weights."""
        from legged_gente.utils.checkpoints import actor_settings_from_weights, load_checkpoint

        train_cfg = train_cfg or self.get_cfgs(name)[1]
        train_cfg.runner.resume = False
        if not network_sizes_from(checkpoint, train_cfg):
            # a lone model.pt: its weights say the actor's layer widths and whether it normalises its observations
            settings = actor_settings_from_weights(
                load_checkpoint(checkpoint, map_location="cpu").get("actor_state_dict", {}))
            if settings is not None:
                for key, value in settings.items():
                    setattr(train_cfg.actor, key, value)
                print(f"{checkpoint}: no config.json beside it: the actor's settings are read off its weights: "
                      + ", ".join(f"{key} {value}" for key, value in settings.items()))
        with contextlib.redirect_stdout(io.StringIO()):  # rsl-rl prints its models and observation sets: for training
            runner, _, _ = self.make_alg_runner(env, name, train_cfg=train_cfg, log_root=None)
        runner.load(str(checkpoint), load_cfg={"actor": True}, map_location=env.device)
        runner.loaded_checkpoint = Path(checkpoint)
        return runner


def network_sizes_from(checkpoint: Path, train_cfg: LeggedRobotCfgPPO) -> bool:
    """The actor and critic settings (network sizes) recorded in the ``config.json`` beside ``checkpoint`` (a run
    folder or a shipped policy's folder), if there is one. Whether it recorded any."""
    from legged_gente.envs.base.base_config import update_from_dict

    config_path = Path(checkpoint).parent / "config.json"
    if not config_path.is_file():
        return False
    train = json.loads(config_path.read_text()).get("train", {})
    recorded = [section for section in NETWORK_SECTIONS if section in train]
    for section in recorded:
        update_from_dict(getattr(train_cfg, section), train[section], section)
    return bool(recorded)


def load_newest_readable(runner, experiment_root, load_run=-1, checkpoint=-1, load_cfg: dict | None = None) -> Path:
    """Load the newest checkpoint that reads (see ``load_newest_readable_of``). ``load_cfg``: the parts to load, as
    rsl-rl's (None: all). The path loaded."""
    from legged_gente.utils.checkpoints import checkpoint_candidates, load_newest_readable_of

    candidates = checkpoint_candidates(experiment_root, load_run, checkpoint)
    return load_newest_readable_of(candidates, lambda path: runner.load(str(path), load_cfg), experiment_root)[0]


task_registry = TaskRegistry()


def _register_builtin_tasks() -> None:
    from legged_gente.envs.base.legged_robot import LeggedRobot
    from legged_gente.envs.gente_biped.gente_biped import GenteBiped
    from legged_gente.envs.gente_biped.gente_biped_config import (
        GenteBipedCfg, GenteBipedCfgPPO, GenteBipedFlatCfg, GenteBipedFlatCfgPPO)
    from legged_gente.envs.gente_quadruped.gente_quadruped_config import (
        GenteQuadrupedCfg, GenteQuadrupedCfgPPO, GenteQuadrupedFlatCfg, GenteQuadrupedFlatCfgPPO)

    task_registry.register("gente_biped", GenteBiped, GenteBipedCfg, GenteBipedCfgPPO)
    task_registry.register("gente_biped_flat", GenteBiped, GenteBipedFlatCfg, GenteBipedFlatCfgPPO)
    task_registry.register("gente_quadruped", LeggedRobot, GenteQuadrupedCfg, GenteQuadrupedCfgPPO)
    task_registry.register("gente_quadruped_flat", LeggedRobot, GenteQuadrupedFlatCfg, GenteQuadrupedFlatCfgPPO)


_register_builtin_tasks()
