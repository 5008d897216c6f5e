"""What a run or an evaluation was made with, for its config.json or report.json: the code, the libraries, the
device, the command line."""

from __future__ import annotations

import hashlib
import platform
import shlex
import subprocess
import sys
from importlib.metadata import PackageNotFoundError, version
from pathlib import Path

LIBRARIES = ("torch", "mujoco", "mujoco-warp", "warp-lang", "rsl-rl-lib", "numpy")
"""The installed distributions whose versions change what a run computes."""


def command_line() -> str:
    """The command as typed: the script's name and its arguments."""
    return shlex.join([Path(sys.argv[0]).name, *sys.argv[1:]])


def source_digest(package: Path) -> str:
    """sha256 of the package's Python files (their paths and bytes, in path order): names the code whether or not
    it runs from a git checkout, and whatever changes the checkout holds."""
    digest = hashlib.sha256()
    for path in sorted(package.rglob("*.py")):
        digest.update(path.relative_to(package).as_posix().encode() + b"\0" + path.read_bytes() + b"\0")
    return digest.hexdigest()


def code_version() -> dict:
    """The code: the git commit (and whether the checkout's tracked files had changes: the terrains, runs and
    outputs a user writes inside it are untracked and not counted) when legged_gente runs from a git checkout, the
    installed package's version, and the digest of its source files (``source_digest``), which tells apart two
    installs of one version or two states of one dirty checkout."""
    try:
        package = version("legged_gente")
    except PackageNotFoundError:
        package = None
    source = Path(__file__).resolve().parents[2]
    record = {"git_commit": None, "package_version": package, "source_sha256": source_digest(source / "legged_gente")}
    try:
        def git(*cmd):
            return subprocess.run(["git", "-C", str(source), *cmd], capture_output=True, text=True, timeout=10,
                                  check=True).stdout.strip()

        if Path(git("rev-parse", "--show-toplevel")).resolve() != source:
            raise ValueError("legged_gente is not the checkout's top level")  # e.g. installed inside another repo
        dirty = bool(git("status", "--porcelain", "--untracked-files=no"))
        return record | {"git_commit": git("rev-parse", "HEAD"), "git_dirty": dirty}
    except (OSError, ValueError, subprocess.SubprocessError):
        return record


def platform_record(device: str) -> dict:
    """The device the run computed on (a GPU's name too) and the versions of Python and ``LIBRARIES``."""
    import torch

    record = {"device": str(device), "python": platform.python_version()}
    if str(device).startswith("cuda"):
        record["gpu"] = torch.cuda.get_device_name(torch.device(device))
    versions = {}
    for name in LIBRARIES:
        try:
            versions[name] = version(name)
        except PackageNotFoundError:
            versions[name] = None
    return record | {"libraries": versions}


def file_sha256(path: str | Path) -> str:
    """sha256 of a file's bytes (a policy a report scored, which a later export may overwrite at the same path)."""
    digest = hashlib.sha256()
    with open(path, "rb") as f:
        for block in iter(lambda: f.read(1 << 20), b""):
            digest.update(block)
    return digest.hexdigest()
