"""Documentation assets from the registry: a preview PNG per atomic terrain, the curriculum grid, a mosaic's tiles,
the docs table.

``python -m legged_gente.terrain.gallery [--img docs/img] [--doc docs/terrain.md]`` rewrites the images and the
table of atomic terrains between the ``<!-- atomics:start -->`` / ``<!-- atomics:end -->`` markers of the doc.
"""

from __future__ import annotations

import argparse
from pathlib import Path

import numpy as np

from .benchmark import BENCHMARK_TYPES, curriculum_config
from .composition import Operation, Part, Region, TileSpec
from .registry import ATOMIC_TERRAINS, Param
from .terrain import Terrain, preview_rgb

GALLERY_DIFFICULTY = 0.7
PHYSICAL_BASE = {"water": "river", "soil": "hills", "low_friction": "flat", "ice": "basin"}
"""The geometric terrain each physical one is shown on."""
START, END = "<!-- atomics:start -->", "<!-- atomics:end -->"


def atomic_preview(name: str, size: float = 8.0, resolution: float = 0.1, pixels: int = 240) -> np.ndarray:
    """(pixels, pixels, 3) uint8 preview of atomic ``name`` at GALLERY_DIFFICULTY on a ``size`` m tile."""
    from PIL import Image

    names = [PHYSICAL_BASE[name], name] if name in PHYSICAL_BASE else [name]
    ops = [Operation(n, ATOMIC_TERRAINS[n].params_for_difficulty(GALLERY_DIFFICULTY)) for n in names]
    heights, material = TileSpec(size, size, resolution, 0, [Part(Region(0, 0, size, size), ops)]).build()
    rgb = (preview_rgb(heights, material, resolution) * 255).round().astype(np.uint8)
    return np.asarray(Image.fromarray(rgb).resize((pixels, pixels), Image.BICUBIC))


def curriculum_terrain() -> Terrain:
    return Terrain(curriculum_config(BENCHMARK_TYPES, 10, len(BENCHMARK_TYPES), border_size=2.0), num_robots=1)


GALLERY_MOSAIC = "pyramid_stairs|pyramid_stairs:direction=down|discrete_obstacles|rocks|natural_ground|pyramid_slope"
"""The mosaic shown in docs/terrain.md: four tiles of it at each of four difficulties."""


def mosaic_terrain() -> Terrain:
    return Terrain(curriculum_config([GALLERY_MOSAIC], 4, 4, border_size=2.0), num_robots=1)


def _format(value) -> str:
    if isinstance(value, float):
        return f"{value:.4g}"
    return str(value)


def _param_cell(name: str, p: Param) -> str:
    if p.choices is not None:
        rng = " \\| ".join(p.choices)
    else:
        rng = f"[{_format(p.low)}, {_format(p.high)}] {p.unit}"
    return f"`{name}`={_format(p.default)} ({rng}): {p.doc.replace('|', '&#124;')}"


def atomic_table_markdown() -> str:
    """Markdown table of every atomic: kind, description, parameters, curriculum mapping (difficulty 0 -> 1)."""
    lines = ["| terrain | kind | description | parameters: default (range): meaning | difficulty 0 → 1 | preview |",
             "|---|---|---|---|---|---|"]
    for name, a in ATOMIC_TERRAINS.items():
        params = "<br>".join(_param_cell(k, p) for k, p in a.params.items())
        if a.difficulty is None:
            curriculum = "defaults"
        else:
            lo, hi = a.difficulty(0.0), a.difficulty(1.0)
            curriculum = "<br>".join(f"`{k}` {_format(lo[k])} → {_format(hi[k])}" for k in lo)
        lines.append(
            f"| `{name}` | {a.kind} | {a.description} | {params} | {curriculum} | "
            f"![{name}](img/terrain_{name}.png) |"
        )
    return "\n".join(lines)


def write_gallery(img_dir: Path, doc: Path | None) -> list[Path]:
    from PIL import Image

    img_dir.mkdir(parents=True, exist_ok=True)
    written = []
    for name in ATOMIC_TERRAINS:
        path = img_dir / f"terrain_{name}.png"
        Image.fromarray(atomic_preview(name)).save(path, optimize=True)
        written.append(path)
    for terrain, name in ((curriculum_terrain(), "terrain_curriculum.png"), (mosaic_terrain(), "terrain_mosaic.png")):
        grid = terrain.save_preview(img_dir / name, max_size=1000)
        Image.open(grid).quantize(colors=128).save(grid, optimize=True)  # docs asset: keep it small
        written.append(grid)
    if doc is not None:
        text = doc.read_text()
        if START not in text or END not in text:
            raise ValueError(f"{doc} lacks the markers {START} ... {END} where the atomic table goes; add them.")
        head, rest = text.split(START, 1)
        doc.write_text(head + START + "\n" + atomic_table_markdown() + "\n" + END + rest.split(END, 1)[1])
    return written


if __name__ == "__main__":
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--img", type=Path, default=Path("docs/img"))
    parser.add_argument("--doc", type=Path, default=Path("docs/terrain.md"))
    args = parser.parse_args()
    for path in write_gallery(args.img, args.doc):
        print(f"{path}  {path.stat().st_size / 1024:.0f} KB")
