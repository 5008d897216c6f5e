"""A benchmark folder: ``manifest.json`` listing items (text prompt or image) and their ``spec.json`` files.

``gente100`` ships with the package (``legged_gente/benchmarks/gente100``): ``load_benchmark("gente100")`` or
``"benchmarks/gente100"`` find it from any working directory; any other folder is read as given.

Manifest format (written by ``legged_gente/benchmarks/gente100/build.py``)::

    {"name": "gente100", "tile_size": [20.0, 20.0], "resolution": 0.1,
     "items": [{"id": "text_00_beach", "kind": "text", "prompt": "...", "spec": "specs/text_00_beach.json"},
               {"id": "image_00_pond", "kind": "image", "image": "images/image_00_pond.png",
                "names": ["water", "grass"], "spec": "specs/image_00_pond.json"}]}

``names`` of an image item are the planner LEGEND classes its picture was made to show (what the image
"names"); the checker requires each of them in the spec.
"""

from __future__ import annotations

import collections
import dataclasses
import importlib.resources
import json
from pathlib import Path

from legged_gente.generation.spec import TerrainSpec

TILE_EDGE_MARGIN = 0.5
"""m; a robot's measured episode ends when its base comes this close to its tile's edge. Beyond the edge lies the
next terrain or the layout's border at any height (4.6 m below the rim on one of GenTe's terrains), which the terrain's
author never drew: a fall or a blow-up there is the layout's. In the default pose the shipped robots' bodies reach
0.33 m (biped) and 0.36 m (quadruped) from their base (bounding spheres): half a metre keeps them on the tile."""

KINDS = ("text", "image")
SHIPPED = Path(str(importlib.resources.files("legged_gente"))) / "benchmarks"  # package data


@dataclasses.dataclass(frozen=True)
class Item:
    id: str
    kind: str
    spec_path: Path
    prompt: str | None = None
    image: Path | None = None
    names: tuple[str, ...] = ()

    def spec(self) -> TerrainSpec:
        return TerrainSpec.load(self.spec_path)


def _one_spec(path: Path, ids: list[str] | None) -> list[Item]:
    """The one item of a spec file: its id the spec's name, its kind "image" when an image made it, else "text"."""
    spec = TerrainSpec.load(path)
    item = Item(spec.name, "image" if "image_sha256" in spec.source else "text", path, spec.source.get("text"))
    if ids is not None and list(ids) != [item.id]:
        raise ValueError(f"--items {ids}: the spec {path} is one terrain, {item.id!r}; leave out --items")
    return [item]


def shipped_benchmarks() -> list[str]:
    """The names of the benchmarks shipped with the package."""
    return sorted(p.parent.name for p in SHIPPED.glob("*/manifest.json"))


def benchmark_root(root: str | Path) -> Path:
    """A benchmark folder as given, else a shipped one by name (``gente100``) or by ``benchmarks/<name>``. A relative
    folder without a manifest.json (or a generated terrain's spec.json) does not hide a shipped benchmark of its name:
    ``gente-evaluate --out gente100`` makes one."""
    given = Path(root).expanduser()
    if given.is_absolute() or any((given / name).is_file() for name in ("manifest.json", "spec.json")):
        return given
    for shipped in (SHIPPED / given, SHIPPED.parent / given):
        if (shipped / "manifest.json").is_file():
            return shipped
    return given


def load_benchmark(root: str | Path, ids: list[str] | None = None) -> list[Item]:
    """The items of the benchmark at ``root``: all, in manifest order, or those in ``ids``, in that order. A
    generated terrain's spec.json is a benchmark of one item, named by the spec's name."""
    if Path(root).suffix == ".json" and Path(root).is_file():
        return _one_spec(Path(root), ids)
    root = benchmark_root(root)
    manifest = root / "manifest.json"
    if not manifest.is_file():
        if (root / "spec.json").is_file():  # gente-generate's output: one terrain, not a benchmark
            raise FileNotFoundError(f"{root} holds one generated terrain, not a benchmark (no manifest.json); pass "
                                    f"its {root / 'spec.json'}")
        raise FileNotFoundError(f"{manifest} not found; pass a benchmark folder with a manifest.json, or a shipped "
                                f"benchmark: {shipped_benchmarks()}.")
    try:
        data = json.loads(manifest.read_text())
    except (json.JSONDecodeError, UnicodeDecodeError) as exc:
        raise ValueError(f"{manifest} is not valid JSON ({exc}); fix it, or rebuild the benchmark.") from None
    items = []
    try:
        for entry in data["items"]:
            _check_entry(manifest, entry)
            items.append(Item(entry["id"], entry["kind"], root / entry["spec"], entry.get("prompt"),
                              root / entry["image"] if entry.get("image") else None, tuple(entry.get("names", ()))))
    except (KeyError, TypeError) as exc:
        raise ValueError(f"{manifest} is not a benchmark manifest ({type(exc).__name__}: {exc}): it needs "
                         f'{{"items": [{{"id", "kind", "spec", ...}}, ...]}} (docs/evaluation.md).') from None
    repeated = _repeated([i.id for i in items])
    if repeated:
        raise ValueError(f"{manifest} lists item ids {repeated} more than once; give every item its own id (report "
                         f"rows are named by it).")
    if ids is not None:
        repeated = _repeated(ids)
        if repeated:
            raise ValueError(f"items {repeated} are given more than once; list each once (report rows are named by "
                             f"their id).")
        known = {i.id: i for i in items}
        missing = [i for i in ids if i not in known]
        if missing:
            raise KeyError(f"items {missing} are not in {manifest}; known ids start {sorted(known)[:5]}...")
        items = [known[i] for i in ids]
    if not items:
        raise ValueError(f"{manifest} lists no items.")
    return items


def _check_entry(manifest: Path, entry: dict) -> None:
    """One manifest item's fields, or a one-line error: an id names report rows and ``--items`` (a string), and
    ``names`` is a list (a lone string would be read as one class per letter)."""
    if not isinstance(entry["id"], str) or not entry["id"]:
        raise ValueError(f"{manifest}: item id {entry['id']!r} is not a name; give every item a non-empty string id "
                         f"(report rows and --items name it).")
    if entry["kind"] not in KINDS:
        raise ValueError(f"{manifest}: item {entry['id']!r} has kind {entry['kind']!r}; use one of {KINDS}.")
    for key in ("prompt", "image"):
        if entry.get(key) is not None and not isinstance(entry[key], str):
            raise ValueError(f"{manifest}: item {entry['id']!r} has {key} {entry[key]!r}; give a string.")
    names = entry.get("names", [])
    if not isinstance(names, list) or not all(isinstance(name, str) for name in names):
        raise ValueError(f"{manifest}: item {entry['id']!r} has names {names!r}; give a list of LEGEND class names, "
                         f'e.g. ["water", "grass"].')


def _repeated(ids: list[str]) -> list[str]:
    """The ids that occur more than once, each once, in order."""
    return [i for i, count in collections.Counter(ids).items() if count > 1]


def tile_geometry(specs: list[TerrainSpec]) -> tuple[float, float, float]:
    """(size_x, size_y, resolution) shared by all ``specs``; tiles of one terrain must be equal."""
    geometry = {(s.size_x, s.size_y, s.resolution) for s in specs}
    if len(geometry) != 1:
        raise ValueError(f"the specs have different tile sizes/resolutions {sorted(geometry)}; tiles of one terrain "
                         f"must be equal: regenerate them with one --size and --resolution.")
    return geometry.pop()
