"""The user-facing docs against the code: every flag a doc passes to a gente-* command is one of that command's
flags, every repository path a doc names exists, and the numbers the docs quote from a command's output are what
that command prints now (the fuzzer's counts, the planner's scores)."""

import contextlib
import io
import re
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
DOCS = ["README.md"] + [f"docs/{name}.md" for name in
                        ("generation", "evaluation", "viewer", "terrain", "new_robot", "multi_gpu", "forces", "robots")]
SCRIPTS = ("train", "play", "benchmark", "generate", "evaluate", "view")
# a command written out: the console script, the script file, or the module
COMMAND = re.compile(r"(?:gente-(train|play|benchmark|generate|evaluate|view)\b"
                     r"|legged_gente/scripts/(\w+)\.py|-m legged_gente\.scripts\.(\w+))")


def _doc(name: str) -> str:
    return (ROOT / name).read_text()


def _commands(text: str) -> list[tuple[str, str]]:
    """(script, its arguments) of every gente-* command in the fenced blocks and inline code of a doc: a block's
    lines joined across '\\' continuations; a command ends at a comment, a pipe, ';' or '&&'."""
    chunks = []
    for block in re.findall(r"```[a-z]*\n(.*?)```", text, re.S):
        chunks += block.replace("\\\n", " ").splitlines()
    chunks += re.findall(r"`([^`\n]+)`", re.sub(r"```.*?```", "", text, flags=re.S))
    found = []
    for chunk in chunks:
        for match in COMMAND.finditer(chunk):
            script = next(group for group in match.groups() if group)
            rest = re.split(r"\s#|\||;|&&", chunk[match.end():])[0]
            found.append((script, rest))
    return found


def _flags_of(script: str) -> set[str]:
    """The long flags of a gente-* command, read from its --help in both spellings."""
    import importlib

    module = importlib.import_module(f"legged_gente.scripts.{script}")
    out = io.StringIO()
    with contextlib.redirect_stdout(out), pytest.raises(SystemExit):
        module.main(["--help"])
    return set(re.findall(r"--[a-z][a-z0-9_-]*", out.getvalue()))


def test_every_flag_a_doc_passes_to_a_gente_command_is_one_of_its_flags():
    flags = {script: _flags_of(script) for script in SCRIPTS}
    unknown = []
    for doc in DOCS:
        for script, rest in _commands(_doc(doc)):
            assert script in flags, f"{doc}: a command of an unknown script {script}"
            for flag in re.findall(r"(?<![\w-])--[a-z][a-z0-9_-]*", rest):
                if flag not in flags[script]:
                    unknown.append(f"{doc}: gente-{script} {flag}")
    assert len([1 for doc in DOCS for _ in _commands(_doc(doc))]) > 40  # the docs show many commands
    assert not unknown, unknown


def test_every_repository_path_a_doc_names_exists():
    # a path: a code span or link target with a '/' and a file suffix, relative to the root, the doc, the package
    # or its benchmarks
    suffixes = (".py", ".md", ".json", ".png", ".npz", ".xml", ".sh", ".txt", ".csv", ".gif", ".mp4", ".toml")
    placeholders = ("http", "logs/", "/tmp", "eval/", "terrains/", "my_robot", "$", "~", "DIR/", "data:",
                    "utils/terrain_utils_", "unitree_go2/")  # run outputs, user files, GenTe's and Menagerie's files
    missing = []
    for doc in DOCS:
        text = _doc(doc)
        names = set(re.findall(r"`([^`\s]+)`", text)) | set(re.findall(r"\]\(([^)\s#]+)", text))
        names |= set(re.findall(r'src="([^"]+)"', text))
        for name in names:
            name = name.split("::")[0].rstrip(".,:;")
            if (name.startswith(placeholders) or any(c in name for c in "<*{") or "..." in name
                    or "/" not in name or not name.endswith(suffixes)):
                continue
            bases = (ROOT, (ROOT / doc).parent, ROOT / "legged_gente", ROOT / "legged_gente" / "benchmarks")
            if not any((base / name).exists() for base in bases):
                missing.append(f"{doc}: {name}")
    assert not missing, missing


def test_generation_doc_quotes_the_fuzzers_seed_0_counts(load_file):
    # docs/generation.md: "Seed 0: 1200 calls, R rejected, A accepted and built; 400 specs, R rejected, B built;
    # 300 GenTe calls, N not translated or rejected, B built; 0 crashes" -- what `python
    # tests/test_generation_fuzz.py 0 1200` prints.
    text = " ".join(_doc("docs/generation.md").split())
    quoted = re.search(r"Seed 0: (\d+) calls, (\d+) rejected, (\d+) accepted and built; (\d+) specs, (\d+) rejected, "
                       r"(\d+) built; (\d+) GenTe calls, (\d+) not translated or rejected, (\d+) built; (\d+) "
                       r"crashes", text)
    assert quoted, "docs/generation.md no longer quotes the fuzzer's seed-0 counts in the form this test reads"
    counts = load_file("tests/test_generation_fuzz.py").fuzz(0, 1200)
    measured = [counts[key] for key in ("calls", "rejected", "accepted_and_built", "specs", "specs_rejected",
                                        "specs_built", "gente_calls", "gente_blocked", "gente_built", "crashes")]
    assert [int(n) for n in quoted.groups()] == measured


def test_generation_doc_quotes_the_planners_scores():
    # docs/generation.md's table: "| texts, tune (54) | before | AFTER | COMPLETE % | m -> MEDIAN |", what
    # `python -m legged_gente.generation.score` prints per set as "micro-F1 X; every expected feature found: Y%;
    # ...; median calls Z".
    from legged_gente.generation import score

    out = io.StringIO()
    with contextlib.redirect_stdout(out):
        score.main([])
    printed = {}
    for kind, split, n, body in re.findall(r"### (\w+), (\w+) \((\d+) items\)(.*?)(?=\n### |\Z)", out.getvalue(), re.S):
        line = re.search(r"micro-F1 ([\d.]+); every expected feature found: (\d+)%;.*median calls ([\d.]+)", body)
        printed[(kind, split.replace("_", "-"), n)] = (line.group(1), line.group(2), line.group(3))
    rows = re.findall(r"^\| (texts|photos), (tune|held-out) \((\d+)\) \| [\d.]+ \| ([\d.]+) \| (\d+) % \| [\d.]+ -> "
                      r"([\d.]+) \|$", _doc("docs/generation.md"), re.M)
    assert len(rows) == 4
    for kind, split, n, f1, complete, median in rows:
        assert printed[(kind, split, n)] == (f1, complete, median), (kind, split)


def test_readme_names_every_atomic_terrain_of_the_registry():
    """README's counts and lists of the atomic terrains are the registry's: a terrain added to the registry (basin,
    ice) must not be missing from the front page."""
    from legged_gente.terrain.registry import ATOMIC_TERRAINS

    readme = " ".join(_doc("README.md").split())
    kinds = {kind: [n for n, t in ATOMIC_TERRAINS.items() if t.kind == kind] for kind in ("geometric", "physical")}
    counts = re.search(r"\((\d+) geometric \+ (\d+) physical terrains\)", readme)
    assert counts and tuple(map(int, counts.groups())) == (len(kinds["geometric"]), len(kinds["physical"]))
    geometric = re.search(r"Geometric terrains: ([a-z_, ]+)\.", readme).group(1).split(", ")
    assert geometric == kinds["geometric"]
    physical = re.findall(r"(\w+) \(", re.search(r"Physical terrains: (.*?)\. Tiles", readme).group(1))
    assert [p for p in physical if p in ATOMIC_TERRAINS] == kinds["physical"]
