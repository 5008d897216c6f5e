"""Checkpoints: finding them under logs/<experiment>/<date>_<run>/model_<iter>.pt, loading them safely, and
checking that one fits the task it is loaded into.

A checkpoint is loaded with ``torch.load(weights_only=True)``: only tensors, numbers, strings and containers
of them are unpickled, never arbitrary Python objects (rsl-rl's own ``OnPolicyRunner.load`` uses
``weights_only=False``, with which opening a checkpoint can run code from it).
"""

from __future__ import annotations

import importlib.resources
import json
import pickle
import re
import sys
import zipfile
from pathlib import Path

import torch


class CheckpointError(ValueError):
    """A checkpoint that cannot be used: unreadable, refused by the safe loader, or made for another task."""


class UnreadableCheckpoint(CheckpointError):
    """A truncated or corrupt checkpoint file (resuming skips it for an older one)."""


def _iteration(path: Path) -> int:
    match = re.fullmatch(r"model_(\d+)\.pt", path.name)
    return int(match.group(1)) if match else -1


def _runs(experiment_root: Path | None) -> list[Path]:
    if experiment_root is None or not Path(experiment_root).is_dir():
        raise FileNotFoundError(f"no runs under {experiment_root}; train first, or pass --experiment_name, "
                                f"--log_root (or set $GENTE_LOG_ROOT) or --load_run RUN_FOLDER to point at the runs.")
    runs = sorted(p for p in Path(experiment_root).iterdir() if p.is_dir() and any(p.glob("model_*.pt")))
    if not runs:
        raise FileNotFoundError(f"no checkpoints (model_*.pt) in any run under {experiment_root}; train first.")
    return runs


def _models(run: Path) -> list[Path]:
    return sorted(run.glob("model_*.pt"), key=_iteration)


def _run(experiment_root: Path | None, load_run) -> Path:
    """The run folder to load from: the latest under ``experiment_root``, the one named ``load_run`` there, or,
    when no run there has that name, ``load_run`` as a path to a run folder anywhere (e.g. copied from another
    machine)."""
    if load_run in (-1, "-1", None):
        latest = _runs(experiment_root)[-1]
        empty = sorted(p.name for p in Path(experiment_root).iterdir() if p.is_dir() and p.name > latest.name)
        if empty:  # runs stopped before their first iteration: nothing of them to resume
            print(f"[legged_gente] the run folder(s) {', '.join(empty)} after {latest.name} hold no checkpoint; "
                  f"resuming from {latest.name} (--load_run names a run)")
        return latest
    root = Path(experiment_root) if experiment_root is not None else None
    named = root / str(load_run) if root is not None else None
    run = named if named is not None and named.is_dir() else Path(str(load_run)).expanduser()
    if not run.is_dir():
        runs = sorted(r.name for r in root.iterdir() if r.is_dir()) if root is not None and root.is_dir() else []
        given = Path(str(load_run)).expanduser()
        if given.is_file():  # a checkpoint's path: its folder and number are the two flags
            number = re.fullmatch(r"model_(\d+)\.pt", given.name)
            raise FileNotFoundError(f"run {load_run!r} is a file; --load_run takes its run folder: --load_run "
                                    f"{given.parent}" + (f" --checkpoint {number.group(1)}" if number else ""))
        raise FileNotFoundError(f"run {load_run!r} is neither a run under {experiment_root} (runs: {runs}) nor a "
                                f"folder; pass a run name or the path of a run folder.")
    if not _models(run):
        raise FileNotFoundError(f"run {run} has no model_*.pt checkpoints.")
    return run


def find_checkpoint(experiment_root: Path | None, load_run=-1, checkpoint=-1) -> Path:
    """The checkpoint file to load: the latest run and iteration unless named."""
    return checkpoint_candidates(experiment_root, load_run, checkpoint)[0]


def checkpoint_candidates(experiment_root: Path | None, load_run=-1, checkpoint=-1) -> list[Path]:
    """Checkpoints to try, in order: a named checkpoint alone; else the run's checkpoints newest first, then
    (when no run was named) those of the earlier runs, newest first."""
    run = _run(experiment_root, load_run)
    models = _models(run)
    if checkpoint not in (-1, "-1", None):
        path = run / f"model_{checkpoint}.pt"
        if not path.is_file():
            raise FileNotFoundError(f"{path} not found; available: {[m.name for m in models]}")
        return [path]
    candidates = models[::-1]
    if load_run in (-1, "-1", None):
        for earlier in _runs(experiment_root)[-2::-1]:
            candidates += _models(earlier)[::-1]
    return candidates


def load_newest_readable_of(candidates: list[Path], load, where) -> tuple[Path, object]:
    """(path, ``load(path)``) for the first of ``candidates`` (newest first) that reads: a truncated or corrupt newer
    one is skipped, and said so; a lone candidate (a checkpoint named explicitly) is loaded or refused, never
    replaced. Any other error (a checkpoint of another task) is raised, not skipped. ``where``: the folder the
    candidates came from, for the error when none reads."""
    skipped = []
    for path in candidates:
        try:
            loaded = load(path)
        except UnreadableCheckpoint as error:
            if len(candidates) == 1:
                raise
            print(f"[legged_gente] {error} Trying the next newest.")
            skipped.append(path.name)
            continue
        print(f"Loaded model from {path}" + (f" (newest readable; skipped {', '.join(skipped)})" if skipped else ""))
        return path, loaded
    raise CheckpointError(f"no readable checkpoint under {where} (tried {', '.join(skipped)}: each truncated or "
                          f"corrupt); pick another run, or train anew (without --resume).")


def _names_nothing(name: str) -> bool:
    """Whether ``name`` (module.attribute, as a pickle's GLOBAL) is no dotted Python name or is missing from a module
    already imported; a name whose module is not imported is not looked up (importing it would run its code)."""
    parts = name.split(".")
    if not all(part.isidentifier() for part in parts):
        return True
    for split in range(len(parts) - 1, 0, -1):
        module = sys.modules.get(".".join(parts[:split]))
        if module is not None:
            target = module
            for attribute in parts[split:]:
                if not hasattr(target, attribute):
                    return True
                target = getattr(target, attribute)
            return False
    return False


def load_checkpoint(path: str | Path, map_location=None) -> dict:
    """The checkpoint's dict, loaded with ``weights_only=True``; an unreadable or unsafe file is a
    CheckpointError that says which and why."""
    path = Path(path)
    if not path.is_file():
        raise FileNotFoundError(f"checkpoint {path}: no such file.")
    try:
        loaded = torch.load(path, map_location=map_location, weights_only=True)
    except pickle.UnpicklingError as error:
        # the safe unpickler names a refused object as a GLOBAL; anything else it stumbles on (e.g. "Can only create
        # new object for nn.Parameter ...") is a broken file, and so is a GLOBAL naming what does not exist in a
        # module already loaded (a flipped bit in a name of torch's, which the zip's checksum does not catch)
        refused = [line.strip() for line in str(error).splitlines() if "GLOBAL " in line]
        if refused and not any(_names_nothing(name) for name in re.findall(r"GLOBAL (\S+)", str(error))):
            raise CheckpointError(f"checkpoint {path} holds Python objects that the safe loader refuses ("
                                  f"{refused[0]}); legged_gente loads checkpoints with torch.load(weights_only=True), "
                                  f"which unpickles tensors and plain values only, so a checkpoint cannot run code."
                                  ) from None
        reason = [line.strip() for line in str(error).splitlines() if line.strip()][-2:-1] or [type(error).__name__]
        raise UnreadableCheckpoint(f"checkpoint {path} is unreadable (corrupt: {reason[0]}).") from None
    except torch.OutOfMemoryError:
        raise  # a RuntimeError too, but the file is fine: the device is full
    except (RuntimeError, EOFError, OSError, zipfile.BadZipFile, ValueError, KeyError, IndexError, TypeError,
            AttributeError) as error:
        # KeyError, IndexError: the legacy unpickler reading bytes that are not a pickle (a text file); TypeError,
        # AttributeError: torch rebuilding a tensor from a corrupt record. Only torch's first sentence: its next
        # ones advise weights_only=False, with which a file can run code.
        first = re.split(r"(?<=\.)\s", str(error).strip(), maxsplit=1)[0].split("\n")[0]
        raise UnreadableCheckpoint(f"checkpoint {path} is unreadable (truncated, corrupt or not written by "
                                   f"torch.save: {type(error).__name__} {first}).") from None
    if isinstance(loaded, dict) and "model_state_dict" in loaded and "actor_state_dict" not in loaded:
        raise CheckpointError(f"checkpoint {path} is in an older rsl-rl's format (legged_gym's: actor and critic in "
                              f"one model_state_dict), which rsl-rl-lib 5.5 cannot load; train the task anew here.")
    if not isinstance(loaded, dict) or "actor_state_dict" not in loaded:
        raise CheckpointError(f"checkpoint {path} is not an rsl-rl training checkpoint (no actor_state_dict); "
                              f"gente-play exports policies, checkpoints are the model_<iteration>.pt of a run.")
    return loaded


def checkpoint_summary(loaded: dict) -> str:
    """'gente_quadruped (12 actions)' for a checkpoint saved by GenteOnPolicyRunner, else what its actor shows."""
    infos = loaded.get("infos") or {}
    actions = infos.get("num_actions", _actor_outputs(loaded["actor_state_dict"]))
    return f"{infos.get('task') or 'an unnamed task'} ({actions} actions)"


def actor_settings_from_weights(state: dict) -> dict | None:
    """The actor's ``hidden_dims`` and ``obs_normalization`` read off its weights (rsl-rl's MLP: ``mlp.<i>.weight``
    layers chained input to output, an ``obs_normalizer.*`` when it normalises), for a checkpoint without its run's
    config.json; None when its layers are not such a chain (another architecture)."""
    layers = sorted(((int(key.split(".")[1]), value) for key, value in state.items()
                     if re.fullmatch(r"mlp\.\d+\.weight", key) and value.ndim == 2), key=lambda layer: layer[0])
    widths = [tuple(value.shape) for _, value in layers]
    if len(widths) < 2 or any(later[1] != earlier[0] for earlier, later in zip(widths, widths[1:])):
        return None
    return {"hidden_dims": [out for out, _ in widths[:-1]],
            "obs_normalization": any(key.startswith("obs_normalizer.") for key in state)}


def _actor_inputs(state: dict) -> int | str:
    """The actor's observation width: the input width of its first layer."""
    weights = [v for k, v in state.items() if k.endswith(".weight") and v.ndim == 2]
    return int(weights[0].shape[1]) if weights else "?"


def _actor_outputs(state: dict) -> int | str:
    """The actor's action count: the width of its distribution's std parameter, else of its last layer."""
    for key, value in state.items():
        if key.startswith("distribution.") and value.ndim == 1:
            return int(value.shape[0])
    weights = [v for k, v in state.items() if k.endswith(".weight") and v.ndim == 2]
    return int(weights[-1].shape[0]) if weights else "?"


def check_checkpoint_fits(loaded: dict, path, task: str | None, num_actions: int, actor_state: dict,
                          strict: bool = True, left_out: dict[str, str] | None = None) -> None:
    """A checkpoint made for another task (another robot or observation set) or another network size is a
    one-line error naming both, instead of torch's 'size mismatch' list. ``left_out``: the policy observation
    terms this env leaves out and what each needs (``LeggedRobot.left_out_observations``), named when the
    checkpoint's actor takes more observations than this env makes."""
    saved = loaded["actor_state_dict"]
    infos = loaded.get("infos") or {}
    saved_task = infos.get("task")
    saved_actions = infos.get("num_actions", _actor_outputs(saved))
    inputs, saved_inputs = _actor_inputs(actor_state), _actor_inputs(saved)
    if left_out and saved_actions == num_actions and isinstance(inputs, int) and isinstance(saved_inputs, int) \
            and saved_inputs > inputs:
        terms = "; ".join(f"{name}, which needs {need}" for name, need in left_out.items())
        raise CheckpointError(f"checkpoint {path}'s actor takes {saved_inputs} observations, this env makes {inputs}: "
                              f"it leaves out {terms}. Run the policy where those terms exist.")
    if saved_actions != num_actions or (saved_task and task and saved_task != task
                                        and _shapes(saved) != _shapes(actor_state)):
        why = (f", whose actor takes {inputs} inputs, the checkpoint's {saved_inputs} (another observation set)"
               if saved_actions == num_actions and inputs != saved_inputs else "")
        raise CheckpointError(f"checkpoint {path} is for {checkpoint_summary(loaded)}; this task is "
                              f"{task or 'unnamed'} ({num_actions} actions){why}. Pick a checkpoint of this task, or "
                              f"the task of this checkpoint (--task).")
    check_state_fits(saved, actor_state, path, "actor", strict)


def check_state_fits(saved: dict, state: dict, path, module: str, strict: bool = True) -> None:
    """The checkpoint's ``module`` (actor or critic) has the tensors of this run's (all of them when ``strict``,
    as torch's load_state_dict), of the same shapes: else a one-line error naming the first difference, instead
    of torch's list of missing, unexpected and resized keys."""
    differences = [f"{key} is {tuple(saved[key].shape)} in the checkpoint, {shape} here"
                   for key, shape in _shapes(state).items() if key in saved and tuple(saved[key].shape) != shape]
    if strict:
        differences += [f"{key} is here, not in the checkpoint" for key in state if key not in saved]
        differences += [f"{key} is in the checkpoint, not here" for key in saved if key not in state]
    if differences:
        raise CheckpointError(
            f"checkpoint {path} does not fit this task's {module}: {differences[0]} (another observation set or "
            f"network; use the run's own settings, e.g. --set {module}.hidden_dims=[...] or "
            f"{module}.obs_normalization=..., as recorded in its config.json).")


def _shapes(state: dict) -> dict[str, tuple[int, ...]]:
    return {key: tuple(value.shape) for key, value in state.items()}


def policies_root() -> Path:
    """Where the package's pretrained policies are: ``resources/policies/<task>/`` (model.pt, config.json)."""
    return Path(str(importlib.resources.files("legged_gente"))) / "resources" / "policies"  # package data


def shipped_tasks() -> list[str]:
    """The tasks with a policy shipped in the package."""
    root = policies_root()
    return sorted(p.name for p in root.iterdir() if (p / "model.pt").is_file()) if root.is_dir() else []


def pretrained_policy(task: str) -> tuple[Path, dict]:
    """The shipped policy of ``task``: its checkpoint and its run's config (network sizes, code commit, note)."""
    folder = policies_root() / task
    if not (folder / "model.pt").is_file():
        raise FileNotFoundError(f"--pretrained: no policy is shipped for task {task!r} (shipped: "
                                f"{', '.join(shipped_tasks()) or 'none'}); train one with gente-train --task {task}, "
                                f"then load it from its run (gente-play --load_run, gente-evaluate --checkpoint), or "
                                f"start a task of your own from a shipped one: task_registry.register(..., "
                                f"pretrained_from='{(shipped_tasks() or ['TASK'])[0]}').")
    return folder / "model.pt", json.loads((folder / "config.json").read_text())


def ship_policy(checkpoint: str | Path, task: str, note: str, destination: Path | None = None) -> Path:
    """Copy a run's checkpoint into the package as the pretrained policy of ``task``: the actor only (what
    playing needs; small and CPU-loadable) in ``model.pt``, and the run's config.json (network sizes, the command
    and the code commit it was trained at) with ``note`` (how it was trained) in ``config.json``."""
    checkpoint = Path(checkpoint)
    loaded = load_checkpoint(checkpoint, map_location="cpu")
    infos = loaded.get("infos") or {}
    config_path = checkpoint.parent / "config.json"
    if not config_path.is_file():
        raise FileNotFoundError(f"{config_path} not found: a shipped policy needs its run's config.json (network "
                                f"sizes); ship a model_<N>.pt from the run folder gente-train wrote, beside its config.json")
    config = json.loads(config_path.read_text())
    # the run's config.json names its task also where the checkpoint does not (saved before the runner recorded it)
    trained = infos.get("task") or config.get("task")
    if trained not in (None, task):
        raise CheckpointError(f"checkpoint {checkpoint} is for {trained}, not {task}: ship it as --task "
                              f"{trained}, or pick a checkpoint of a {task} run")
    folder = Path(destination) if destination is not None else policies_root() / task
    folder.mkdir(parents=True, exist_ok=True)
    actor = {key: value.detach().cpu().clone() for key, value in loaded["actor_state_dict"].items()}
    torch.save({"actor_state_dict": actor, "iter": loaded.get("iter"),
                "infos": {"task": task, "num_actions": infos.get("num_actions", _actor_outputs(actor))}},
               folder / "model.pt")
    config.update(note=note, source_checkpoint=f"{checkpoint.parent.name}/{checkpoint.name}")
    (folder / "config.json").write_text(json.dumps(config, indent=1))
    return folder
