"""Command-line flags of the gente-* commands (legged_gym's set), how they override config fields, and how a
command reports a user's mistake (one line, exit 2) and keeps third-party console noise out of sight."""

from __future__ import annotations

import argparse
import ast
import logging
import math
import os
import re
import sys
import tempfile
import traceback
import types
import typing
import warnings
from fnmatch import fnmatchcase
from pathlib import Path


DEFAULT_TASK = "gente_biped"
"""The task a command runs without --task."""


def flag(name: str) -> tuple[str, ...]:
    """A long option in both spellings, ``--num_envs`` and ``--num-envs``: every gente-* command accepts either
    (argparse names the value after the first)."""
    other = "--" + (name[2:].replace("_", "-") if "_" in name else name[2:].replace("-", "_"))
    return (name,) if other == name else (name, other)


class Parser(argparse.ArgumentParser):
    """argparse with a usage error on one line, ``gente-x: error: ...`` and exit status 2 (the usage is in
    --help), and no abbreviated flags (``--set`` would be ambiguous with ``--settle_s``)."""

    def __init__(self, **kwargs):
        super().__init__(allow_abbrev=False, **kwargs)

    def error(self, message: str):
        self.exit(2, f"{self.prog}: error: {one_line(message)}\n")


def seed(text: str) -> int:
    """An argparse type: a seed numpy and torch both take, in [0, 2**32) (beyond it torch's error names no flag)."""
    try:
        value = int(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"{text!r} is not an integer") from None
    if not 0 <= value < 2**32:
        raise argparse.ArgumentTypeError(f"must be in [0, 2**32), got {text}")
    return value


def build_parser(description: str, prog: str | None = None, training: bool = True,
                 headless: str = "never open a viewer window", device: str | None = None) -> Parser:
    """The flags shared by gente-train, gente-play and gente-view; ``training=False`` leaves out those only
    training uses (--max_iterations, --resume, --run_name); ``headless``: what --headless means to the command;
    ``device``: the command's own default device (else cuda when there is one)."""
    parser = Parser(prog=prog, description=description)
    parser.add_argument("--task", default=DEFAULT_TASK, help="registered task name")
    parser.add_argument(*flag("--num_envs"), type=int, help="number of parallel robots (worlds)")
    if training:
        parser.add_argument(*flag("--max_iterations"), type=int, help="PPO iterations to run")
        parser.add_argument("--resume", action="store_true", help="continue from a checkpoint")
        parser.add_argument(*flag("--run_name"), help="suffix of the run folder")
    parser.add_argument("--headless", action="store_true", help=headless)
    parser.add_argument(*flag("--load_run"), help="run folder name under logs/<experiment>/, or the path of a run "
                                                  "folder anywhere (default: the latest under logs/<experiment>/)")
    parser.add_argument("--checkpoint", type=checkpoint_iteration,
                        help="checkpoint iteration N, of model_N.pt in the run (default: the latest)")
    parser.add_argument(*flag("--experiment_name"), help="logs/<experiment_name>/")
    parser.add_argument("--seed", type=seed, help="random seed, in [0, 2**32)")
    parser.add_argument("--device", default=device,
                        help=f"cpu | cuda | cuda:N (default: {device or 'cuda if available'})")
    parser.add_argument("--terrain", help="'plane', a generated terrain spec JSON, or an emitted terrain_cfg.py")
    parser.add_argument("--set", action="append", default=[], metavar="SECTION.FIELD=VALUE", dest="overrides",
                        help="override any config field (repeatable), e.g. --set terrain.solved_top_level=stay "
                             "--set algorithm.learning_rate=3e-4 (train config: actor, critic, algorithm, runner)")
    add_verbose(parser)
    return parser


def checkpoint_iteration(text: str) -> int:
    """``--checkpoint`` of train, play and view: an iteration number. A checkpoint's file is named by its folder and
    its number, which the refusal of a path says."""
    try:
        return int(text)
    except ValueError:
        path = Path(text)
        match = re.fullmatch(r"model_(\d+)\.pt", path.name)
        how = (f"--load_run {path.parent} --checkpoint {match.group(1)}" if match else
               "--load_run RUN_FOLDER --checkpoint N")
        raise argparse.ArgumentTypeError(f"{text!r} is not an iteration number: --checkpoint N loads model_N.pt of "
                                         f"the run; for this file give {how}") from None


def add_verbose(parser: argparse.ArgumentParser) -> None:
    parser.add_argument("--verbose", action="store_true",
                        help="show third-party console output (Warp's module loads, library warnings) and full "
                             "tracebacks of errors")


def default_device() -> str:
    import torch

    return "cuda:0" if torch.cuda.is_available() else "cpu"


def resolve_device(device: str | None) -> str:
    """``None`` -> cuda:0 when a GPU is visible, else cpu; ``cuda`` -> cuda:0; a CUDA device that is not there is
    an error that says so (rather than Warp's 'Invalid device identifier' later)."""
    import torch

    if device is None:
        return default_device()
    given = device
    if device == "cuda":
        device = "cuda:0"
    if device != "cpu" and not (device.startswith("cuda:") and device[5:].isdigit()):
        raise ValueError(f"--device {device!r}: use cpu, cuda or cuda:N")
    if device.startswith("cuda"):
        count = torch.cuda.device_count() if torch.cuda.is_available() else 0
        if count == 0:
            raise ValueError(f"--device {given}: no GPU visible, use --device cpu")
        if int(device[5:]) >= count:
            raise ValueError(f"--device {device}: only {count} GPU(s) visible (cuda:0..cuda:{count - 1})")
    return device


def parse_args(parser: argparse.ArgumentParser, argv=None) -> argparse.Namespace:
    args = parser.parse_args(argv)
    quiet_third_party(verbose=args.verbose)
    from legged_gente.utils.distributed import rank_device, torchrun_launch

    try:
        launch = torchrun_launch()
        if launch is not None:  # under torchrun each rank trains on cuda:{LOCAL_RANK} (or the CPU)
            args.device = rank_device(args.device, launch)
        args.device = resolve_device(args.device)
    except ValueError as error:
        parser.error(str(error))
    if args.num_envs is not None and args.num_envs < 1:
        parser.error("--num_envs must be >= 1")
    if getattr(args, "max_iterations", None) is not None and args.max_iterations < 1:
        parser.error(f"--max_iterations {args.max_iterations}: train at least 1 iteration")
    if getattr(args, "steps", None) is not None and args.steps < 1:  # gente-play's and gente-view's rollouts
        parser.error(f"--steps {args.steps}: roll out at least 1 policy step")
    for text in args.overrides:
        try:
            _parse_override(text)
        except ValueError as error:
            parser.error(str(error))
    return args


GL_FIX = ("set MUJOCO_GL=egl (Mesa's libegl1 on a CPU machine, the GPU driver's EGL otherwise) or MUJOCO_GL=osmesa "
          "(apt-get install libosmesa6)")


def import_mujoco(prog: str) -> None:
    """Import MuJoCo before a command's modules do: a ``MUJOCO_GL`` it cannot use (an unknown value, osmesa without
    libOSMesa) breaks its import, as does a missing package; here either is one line naming the fix (exit 2)
    instead of a traceback."""
    try:
        import mujoco  # noqa: F401
    except ImportError as error:
        if error.name == "mujoco":  # the package itself, not a library its OpenGL backend loads
            print(f"{prog}: error: MuJoCo is not installed ({one_line(error)}); install the project's dependencies "
                  f"with pip install -e . in the checkout (or pip install mujoco==4.0.*)", file=sys.stderr)
            sys.exit(2)
        _opengl_error(prog, error)
    except (RuntimeError, AttributeError, OSError) as error:
        _opengl_error(prog, error)


def _opengl_error(prog: str, error: BaseException) -> None:
    print(f"{prog}: error: MUJOCO_GL={os.environ.get('MUJOCO_GL')}: MuJoCo's OpenGL backend does not load "
          f"({type(error).__name__}: {one_line(error)}); {GL_FIX}, or leave MUJOCO_GL unset for a run that renders "
          f"nothing (no --video on a machine without a display)", file=sys.stderr)
    sys.exit(2)


# What a user can get wrong (a flag, a config value, a file or folder): reported in one line with exit status 2.
USER_ERRORS = (ValueError, OSError, KeyError)


def one_line(message) -> str:
    """An error's text on one line (a validation error lists one problem per line)."""
    return " ".join(str(message).splitlines())


def error_text(error: BaseException) -> str:
    """What went wrong, for the user: a KeyError's message without its quotes, an OSError's path and reason
    (``notimage.png/sub: Not a directory``) without its errno."""
    if isinstance(error, KeyError) and error.args:
        return str(error.args[0])
    if isinstance(error, OSError) and error.strerror and error.filename is not None:
        return f"{error.filename}: {error.strerror}"
    return str(error)


def check_output(path, name: str, folder: bool = True) -> None:
    """Refuse, before any work, an output folder (or with ``folder=False`` a file) that cannot be made or written:
    one under a file, or under a folder without write permission or where nothing can be created (a read-only or
    virtual file system, which the permission bits do not show: a probe folder is made there and removed at once).
    ``name``: the flag or variable that gave it. An empty string is refused: as a path it is the current folder."""
    if isinstance(path, str) and not path.strip():
        raise ValueError(f"{name} is empty; give a {'folder' if folder else 'file name'}")
    path = Path(path)
    if not folder and path.is_dir():
        raise ValueError(f"{name} {path} is a folder; give a file name")
    target = path if folder else path.parent
    existing = next(p for p in (target, *target.parents) if p.exists())
    if not existing.is_dir():
        raise ValueError(f"{name} {path}: {existing} is a file; give a folder to write to")
    if not os.access(existing, os.W_OK | os.X_OK):
        raise ValueError(f"{name} {path}: {existing} is not writable; give a folder you can write to")
    try:
        tempfile.TemporaryDirectory(dir=existing).cleanup()
    except OSError as exc:
        raise ValueError(f"{name} {path}: nothing can be created in {existing} ({exc.strerror}); give a folder you "
                         f"can write to") from None


def check_log_root(given: str | None, default: Path) -> None:
    """``check_output`` of where runs and exports go: ``--log_root`` if given, else ``default`` ($GENTE_LOG_ROOT,
    else ./logs)."""
    if given:
        check_output(given, "--log_root")
    else:
        check_output(default, "GENTE_LOG_ROOT" if os.environ.get("GENTE_LOG_ROOT") else "the log folder")


def run_command(prog: str, main, args: argparse.Namespace):
    """``main(args)``, with a user's mistake reported as ``prog: error: ...`` (exit 2) instead of a traceback;
    ``--verbose`` shows the traceback before that line (the exit status stays 2: a script telling a usage error
    from a crash by it works with and without the flag)."""
    try:
        return main(args)
    except USER_ERRORS as error:
        if getattr(args, "verbose", False):
            traceback.print_exc()
        print(f"{prog}: error: {one_line(error_text(error))}", file=sys.stderr)
        sys.exit(2)


# Third-party console output a user cannot act on, hidden unless --verbose: (category, message regex, module)
THIRD_PARTY_NOISE = (
    (FutureWarning, "", r"(torch|torchvision|onnx|onnxscript|tensordict|rsl_rl)(\.|$)"),
    (DeprecationWarning, "", r"(torch|torchvision|onnx|onnxscript|tensordict|rsl_rl|mujoco_warp|warp)(\.|$)"),
    (UserWarning, r".*(Failed to load image Python extension|torchvision)", ""),
    (UserWarning, r".*torch\.jit\.\w+.*deprecated", ""),
    (FutureWarning, r".*treespec", ""),  # torch.utils._pytree, raised from copyreg during torch.export
    (UserWarning, "", r"glfw(\.|$)"),  # MuJoCo's GLFW backend without a display: its OpenGL error says it all
)
# Python loggers of third-party libraries whose warnings are not the user's (torch.onnx: "torchvision is not
# installed. Skipping torchvision::nms" at every ONNX export)
THIRD_PARTY_LOGGERS = ("torch.onnx",)


_python_formatwarning = warnings.formatwarning


def _one_line_warning(message, category, filename, lineno, line=None) -> str:
    """The project's own warnings as one line, ``warning: <message>``, without Python's file, line and source
    line (which say where the check is, not what to do); anything else as Python writes it."""
    if f"{os.sep}legged_gente{os.sep}" in str(filename):
        return f"warning: {' '.join(str(message).split())}\n"
    return _python_formatwarning(message, category, filename, lineno, line)


def quiet_third_party(verbose: bool = False) -> None:
    """Keep Warp's per-module 'Module ... loaded' lines and its banner (``warp.config.log_level``) and known
    third-party deprecation/future warnings off the console; ``verbose`` keeps everything."""
    if verbose:
        return
    import warp as wp

    wp.config.log_level = wp.LOG_WARNING
    warnings.formatwarning = _one_line_warning
    for name in THIRD_PARTY_LOGGERS:
        logging.getLogger(name).setLevel(logging.ERROR)
    for category, message, module in THIRD_PARTY_NOISE:
        warnings.filterwarnings("ignore", message=message, category=category, module=module)


def override_of(overrides: list[str], *fields: str) -> str | None:
    """The first ``--set`` text (SECTION.FIELD=VALUE) among ``overrides`` that sets one of ``fields``, or None."""
    return next((text for text in overrides if text.partition("=")[0].strip() in fields), None)


def _parse_override(text: str) -> tuple[list[str], str]:
    key, sep, value = text.partition("=")
    path = key.strip().split(".")
    if not sep or len(path) < 2 or not all(path):
        raise ValueError(f"--set {text!r}: write SECTION.FIELD=VALUE, e.g. --set terrain.solved_top_level=stay")
    return path, value.strip()


# The fields (dotted, one pattern per part) where None is a documented setting that --set may give.
NONE_SETTINGS = (
    "algorithm.desired_kl",  # no KL target: the learning rate stays fixed (rsl-rl's PPO; validate_cfgs)
    "observations.*.*",  # the term dropped (terms.obs_terms)
    "observations.*.*.clip",  # the term not clamped (terms.ObsTerm)
    "observations.*.*.when",  # the term always in its group (terms.ObsTerm)
    "forces.foot_water_geom_names",  # the foot_geom_names (ForcesConfig)
    "forces.sole_length", "forces.sole_width",  # the sole's size from the foot geoms (ForcesConfig)
)


def _none_is_a_setting(name: str) -> bool:
    parts = name.split(".")
    return any(len(pattern) == len(parts) and all(map(fnmatchcase, parts, pattern))
               for pattern in (p.split(".") for p in NONE_SETTINGS))


def _override_value(text: str, current, name: str, owner):
    """The override's value as a Python literal (never evaluated as code), of the same type as ``current`` (of the
    type ``owner``'s class declares for the field where ``current`` is None); None where the field is already None
    or None is one of its settings (``NONE_SETTINGS``)."""
    try:
        value = ast.literal_eval(text)
    except (ValueError, SyntaxError):
        value = text  # a bare word: a string
    if value is None and _none_is_a_setting(name):
        return None
    if isinstance(current, str) and not isinstance(value, str) and value is not None:
        value = text
    if _not_finite(value) or (isinstance(value, str) and isinstance(current, (int, float)) and not isinstance(
            current, bool) and value.strip().lower().lstrip("+-") in ("nan", "inf", "infinity")):
        # 1e999 reads as inf; a 400-digit integer overflows a float; nan and inf are words to Python's literals
        raise ValueError(f"--set {name}={text}: {text} is not a finite number; give a finite value")
    expected = type(current)
    if _is_section(current):
        fields = sorted(n for n in dir(current) if not n.startswith("_"))
        raise ValueError(f"--set {name}={text}: {name} is a config section, not a field; set one of its fields, e.g. "
                         f"--set {name}.{fields[0] if fields else 'FIELD'}=...; its fields: {', '.join(fields)}")
    if value is None and current is not None:
        word = " (quote the word: 'None')" if expected is str else ""
        raise ValueError(f"--set {name}={text}: the field's value is {current!r} of type {expected.__name__}; None is "
                         f"not one of its settings (only of {', '.join(NONE_SETTINGS)}); give a value of that "
                         f"type{word}")
    if current is None:
        return _declared_value(value, current, owner, name, text)
    if _union_forms(_declared_type(owner, name)) > 1:  # a field of several forms (a scale: a number or a tuple)
        return _declared_value(value, current, owner, name, text)
    if isinstance(value, expected) and not (isinstance(value, bool) and expected is int):
        return value
    if expected is float and isinstance(value, int) and not isinstance(value, bool):
        return float(value)
    if expected in (list, tuple) and isinstance(value, (list, tuple)):
        return expected(value)
    if expected in (list, tuple):
        raise ValueError(f"--set {name}={text}: the field is a list; give a list literal of numbers or quoted "
                         f"strings, e.g. {name}={list(current)[:2]!r}")
    raise ValueError(f"--set {name}={text}: the field's value is {current!r} of type {expected.__name__}; give "
                     f"{'True or False' if expected is bool else 'a value of that type'}")


def _not_finite(value) -> bool:
    """Whether a literal is or holds (in a list, tuple or dict's values) a number that is no finite float."""
    if isinstance(value, (list, tuple)):
        return any(map(_not_finite, value))
    if isinstance(value, dict):
        return any(map(_not_finite, value.values()))
    if isinstance(value, bool) or not isinstance(value, (int, float)):
        return False
    try:
        return not math.isfinite(value)
    except OverflowError:
        return True


def _declared_value(value, current, owner, name: str, text: str):
    """``value`` checked against the type the field's config class declares: for a field that is None now (its
    value tells nothing of what it takes; ``sole_length: float | None = None``) or that takes several forms (a
    number or a tuple)."""
    if value is None:
        return None
    field = name.rsplit(".", 1)[-1]
    hint = _declared_type(owner, name)
    if hint is None:
        if name.startswith("observations.") and name.count(".") == 2:
            raise ValueError(f"--set {name}={text}: an observation term can only be dropped (=None) by --set; "
                             f"add it as an ObsTerm in the config class")
        raise ValueError(f"--set {name}={text}: the field is None and declares no type; declare it in its config "
                         f"class, e.g. {field}: float | None = None")
    checked = _as_type(value, hint)
    if checked is _MISMATCH:
        shown = str(hint).replace("typing.", "")
        raise ValueError(f"--set {name}={text}: the field is {current!r} now; give a value of its type, {shown}")
    return checked


def _declared_type(owner, name: str):
    """The type ``owner``'s config class declares for the field ``name`` ends in, or None."""
    try:
        return typing.get_type_hints(type(owner)).get(name.rsplit(".", 1)[-1])
    except (NameError, TypeError):  # an annotation that does not resolve: as if undeclared
        return None


def _union_forms(hint) -> int:
    """How many types other than None a declared union admits (0 for no union)."""
    if typing.get_origin(hint) not in (typing.Union, types.UnionType):
        return 0
    return sum(option is not type(None) for option in typing.get_args(hint))


_MISMATCH = object()


def _as_type(value, hint):
    """``value`` as ``hint`` (float, int, str, bool, list[X], tuple[X, ...], tuple[X, Y], a union of those; an
    int where a float is declared becomes a float), or ``_MISMATCH``."""
    origin, args = typing.get_origin(hint), typing.get_args(hint)
    if origin in (typing.Union, types.UnionType):
        for option in args:
            checked = _as_type(value, option)
            if checked is not _MISMATCH:
                return checked
        return _MISMATCH
    if hint is type(None):
        return None if value is None else _MISMATCH
    if hint is float:
        return float(value) if isinstance(value, (int, float)) and not isinstance(value, bool) else _MISMATCH
    if hint in (list, tuple):
        return hint(value) if isinstance(value, (list, tuple)) else _MISMATCH
    if hint in (int, str, bool, dict):
        return value if isinstance(value, hint) and not (hint is int and isinstance(value, bool)) else _MISMATCH
    if origin in (list, tuple) and isinstance(value, (list, tuple)):
        if origin is tuple and args and args[-1] is not Ellipsis:
            kinds = args if len(args) == len(value) else None
        else:
            kinds = [args[0] if args else typing.Any] * len(value)
        if kinds is None:
            return _MISMATCH
        entries = [entry if kind is typing.Any else _as_type(entry, kind) for entry, kind in zip(value, kinds)]
        return _MISMATCH if any(e is _MISMATCH for e in entries) else origin(entries)
    if origin is dict and isinstance(value, dict):
        return value
    return _MISMATCH


def _is_section(value) -> bool:
    """A config section (an instance of a nested config class, or an observation term's record), not a value."""
    return value is not None and not isinstance(value, (int, float, str, list, tuple, dict))


def _entry_kind(entries) -> type | None:
    """The one type (bool, int, float or str) of a list's entries or a dict's values; None when empty or mixed."""
    kinds = {type(entry) for entry in entries}
    return next(iter(kinds)) if len(kinds) == 1 and kinds <= {bool, int, float, str} else None


def _typed_entries(value, current, name: str, text: str):
    """A list's entries or a dict's values of the type of ``current``'s (an int becomes a float where the field's
    entries are floats, as for a number field): a word among numbers fails in torch, far from the flag."""
    if not isinstance(value, (list, tuple, dict)) or not isinstance(current, (list, tuple, dict)):
        return value
    kind = _entry_kind(current.values() if isinstance(current, dict) else current)
    if kind is None:
        return value

    def typed(entry):
        if kind is float and type(entry) is int:
            return float(entry)
        if type(entry) is not kind:
            what = "values" if isinstance(current, dict) else "entries"
            noun = f"numbers ({kind.__name__})" if kind in (int, float) else kind.__name__
            raise ValueError(f"--set {name}={text}: the field's {what} are {noun}, e.g. {name}={current!r}")
        return entry

    if isinstance(value, dict):
        return {key: typed(entry) for key, entry in value.items()}
    return type(value)(typed(entry) for entry in value)


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
            parent, owner = owner, getattr(owner, part, None)
            prefix = ".".join(path[:i + 1])
            if owner is None and not hasattr(parent, part):
                tops = [c for c in (env_cfg, train_cfg) if c is not None] if i == 0 else [parent]
                sections = sorted({n for c in tops for n in dir(c)
                                   if not n.startswith("_") and _is_section(getattr(c, n))})
                where = type(cfg).__name__ if i == 0 else ".".join(path[:i])
                raise ValueError(f"--set {text!r}: {prefix} is not a config section of {where}; "
                                 + (f"its sections: {', '.join(sections)}" if sections else
                                    f"{where} has fields only: --set {where}.FIELD=..."))
            if not _is_section(owner):
                raise ValueError(f"--set {text!r}: {prefix} is a field ({type(owner).__name__}), not a config "
                                 f"section; set it whole: --set {prefix}={owner!r}")
        if not hasattr(owner, path[-1]) or path[-1].startswith("_"):
            fields = sorted(n for n in dir(owner) if not n.startswith("_"))
            raise ValueError(f"--set {text!r}: {'.'.join(path[:-1])} has no field {path[-1]!r}; its fields: "
                             f"{', '.join(fields)}")
        current, name = getattr(owner, path[-1]), ".".join(path)
        typed = _override_value(value, current, name, owner)
        if path[-1] == "hidden_dims":
            _check_layer_widths(name, typed)
        setattr(owner, path[-1], _typed_entries(typed, current, name, value))


def _check_layer_widths(name: str, dims) -> None:
    """A network's hidden_dims: torch fails on an empty list or a negative width, and a width 0 is a dead layer."""
    if not dims or not all(isinstance(d, int) and not isinstance(d, bool) and d >= 1 for d in dims):
        raise ValueError(f"--set {name}={dims!r}: must be a non-empty list of layer widths >= 1, e.g. "
                         f"--set {name}=[256,128]")
