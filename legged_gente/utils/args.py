"""Command-line flags of train.py / play.py (legged_gym's set) and how they override config fields."""

from __future__ import annotations

import argparse
import ast


def build_parser(description: str) -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(description=description)
    parser.add_argument("--task", default="gente_biped", help="registered task name")
    parser.add_argument("--num_envs", type=int, help="number of parallel robots (worlds)")
    parser.add_argument("--max_iterations", type=int, help="PPO iterations to run")
    parser.add_argument("--headless", action="store_true", help="never open a viewer window")
    parser.add_argument("--resume", action="store_true", help="continue from a checkpoint")
    parser.add_argument("--load_run", help="run folder name under logs/<experiment>/ (default: the latest)")
    parser.add_argument("--checkpoint", type=int, help="checkpoint iteration (default: the latest)")
    parser.add_argument("--experiment_name", help="logs/<experiment_name>/")
    parser.add_argument("--run_name", help="suffix of the run folder")
    parser.add_argument("--seed", type=int, help="random seed")
    parser.add_argument("--device", default=None, help="cpu | cuda | cuda:N (default: cuda if available)")
    parser.add_argument("--terrain", help="'plane', a generated terrain spec JSON, or an emitted terrain_cfg.py")
    parser.add_argument("--set", action="append", default=[], metavar="SECTION.FIELD=VALUE", dest="overrides",
                        help="override any config field (repeatable), e.g. --set terrain.solved_top_level=stay "
                             "--set algorithm.learning_rate=3e-4 (train config: actor, critic, algorithm, runner)")
    return parser


def default_device() -> str:
    import torch

    return "cuda:0" if torch.cuda.is_available() else "cpu"


def parse_args(parser: argparse.ArgumentParser, argv=None) -> argparse.Namespace:
    args = parser.parse_args(argv)
    from legged_gente.utils.distributed import rank_device, torchrun_launch

    launch = torchrun_launch()
    if launch is not None:  # under torchrun each rank trains on cuda:{LOCAL_RANK} (or the CPU)
        try:
            args.device = rank_device(args.device, launch)
        except ValueError as error:
            parser.error(str(error))
    if args.device is None:
        args.device = default_device()
    elif args.device == "cuda":
        args.device = "cuda:0"
    if args.device != "cpu" and not args.device.startswith("cuda"):
        parser.error(f"--device {args.device!r}: use cpu, cuda or cuda:N")
    if args.num_envs is not None and args.num_envs < 1:
        parser.error("--num_envs must be >= 1")
    if args.max_iterations is not None and args.max_iterations < 0:
        parser.error("--max_iterations must be >= 0")
    for text in args.overrides:
        try:
            _parse_override(text)
        except ValueError as error:
            parser.error(str(error))
    return args


def _parse_override(text: str) -> tuple[list[str], str]:
    key, sep, value = text.partition("=")
    path = key.strip().split(".")
    if not sep or len(path) < 2 or not all(path):
        raise ValueError(f"--set {text!r}: write SECTION.FIELD=VALUE, e.g. --set terrain.solved_top_level=stay")
    return path, value.strip()


def _override_value(text: str, current, name: str):
    """The override's value as a Python literal (never evaluated as code), of the same type as ``current``."""
    try:
        value = ast.literal_eval(text)
    except (ValueError, SyntaxError):
        value = text  # a bare word: a string
    if isinstance(current, str) and not isinstance(value, str):
        value = text
    expected = type(current)
    if current is None or isinstance(value, expected) and not (isinstance(value, bool) and expected is int):
        return value
    if expected is float and isinstance(value, int) and not isinstance(value, bool):
        return float(value)
    if expected in (list, tuple) and isinstance(value, (list, tuple)):
        return expected(value)
    raise ValueError(f"--set {name}={text}: the field's value is {current!r} of type {expected.__name__}; give a "
                     f"value of that type")


def apply_overrides(overrides: list[str], env_cfg, train_cfg) -> None:
    """Apply ``--set SECTION.FIELD=VALUE`` to whichever config has SECTION (the train config first); a section
    that neither has is skipped when one config is None (it may be the other's) and an error otherwise, as is
    an unknown field."""
    for text in overrides:
        path, value = _parse_override(text)
        owners = [cfg for cfg in (train_cfg, env_cfg) if cfg is not None and hasattr(cfg, path[0])]
        if not owners and None in (env_cfg, train_cfg):
            continue  # may be a section of the config not given here
        cfg = owners[0] if owners else env_cfg
        owner = cfg
        for i, part in enumerate(path[:-1]):
            owner = getattr(owner, part, None)
            if owner is None or isinstance(owner, (int, float, str, list, dict)):
                raise ValueError(f"--set {text!r}: {'.'.join(path[:i + 1])} is not a config section of "
                                 f"{type(cfg).__name__}")
        if not hasattr(owner, path[-1]) or path[-1].startswith("_"):
            fields = sorted(n for n in dir(owner) if not n.startswith("_"))
            raise ValueError(f"--set {text!r}: {'.'.join(path[:-1])} has no field {path[-1]!r}; its fields: "
                             f"{', '.join(fields)}")
        setattr(owner, path[-1], _override_value(value, getattr(owner, path[-1]), ".".join(path)))
