"""Rebuild a benchmark of our own: text prompts + images -> planner specs, previews, manifest.

    python legged_gente/benchmarks/gente100/build.py            # rewrite images/, specs/, previews_*.png, manifest.json
    python legged_gente/benchmarks/gente100/build.py --check    # and run the checker on every item (non-zero exit on failure)
    python legged_gente/benchmarks/gente100/build.py --set gente_val   # the validation set (see SETS)

``gente100`` (50 prompts, 50 images) is for measuring; ``gente_val`` (30 prompts of its own, 20 images drawn from
other seeds) is for choosing between training candidates, so that the scores reported on gente100 and
gente_original are not those of a choice made on them.

Everything is deterministic: the images are drawn from fixed seeds (half colour-coded sketch maps with the
planner's LEGEND colours, half procedurally rendered scene pictures), and the offline planner backend maps
prompts and images to specs without randomness (each spec's own seed is its set's first seed plus its item
number, ``SETS``).
Heightfields are not stored: every consumer rebuilds them from the specs.
"""

from __future__ import annotations

import argparse
import dataclasses
import json
import math
import sys
from pathlib import Path

import numpy as np
from PIL import Image, ImageDraw

from legged_gente.generation.backends.image import LEGEND
from legged_gente.generation.pipeline import generate_spec
from legged_gente.generation.spec import spec_name
from legged_gente.terrain.terrain import preview_rgb

ROOT = Path(__file__).resolve().parent
BENCHMARKS = ROOT.parent
TILE = 20.0  # m, side of every tile (the planner's default)
RESOLUTION = 0.1  # m
IMAGE_SIZE = 128  # px
NAME_FRACTION = 0.03
"""A sketch class covering at least this fraction of the picture is one the item names."""


# ------------------------------------------------------------------------------------------- sketch maps
def _rgb(name: str) -> tuple[int, int, int]:
    return LEGEND[name].rgb


def _sketch(seed: int) -> tuple[str, Image.Image]:
    """A colour-coded sketch map (top = +x front of the tile): one of several layouts, varied by ``seed``.

    The centre (where robots spawn) is always open ground: grass, pavement, sand, snow or mud.
    """
    rng = np.random.default_rng(1000 + seed)
    s = IMAGE_SIZE
    layouts = ["river", "pond", "stairs", "snow_ice", "mud_rocks", "blocks", "beach", "forest_edge", "marsh",
               "plaza", "dunes_oasis", "ruins"]
    layout = layouts[seed % len(layouts)]
    ground = {"river": "grass", "pond": "grass", "stairs": "pavement", "snow_ice": "snow", "mud_rocks": "mud",
              "blocks": "pavement", "beach": "sand", "forest_edge": "grass", "marsh": "mud", "plaza": "pavement",
              "dunes_oasis": "sand", "ruins": "pavement"}[layout]
    img = Image.new("RGB", (s, s), _rgb(ground))
    d = ImageDraw.Draw(img)
    r = lambda lo, hi: int(rng.integers(lo, hi))  # noqa: E731
    if layout == "river":  # a band across the tile ahead of the robot, with sandy banks
        y = r(10, 30)
        d.rectangle([0, y - 4, s, y + r(18, 26)], fill=_rgb("sand"))
        d.rectangle([0, y, s, y + r(12, 18)], fill=_rgb("water"))
    elif layout == "pond":
        cx, cy = r(20, 40), r(15, 35)
        d.ellipse([cx - 18, cy - 12, cx + 18, cy + 12], fill=_rgb("water"))
        d.rectangle([s - r(25, 35), 0, s, s], fill=_rgb("forest"))
    elif layout == "stairs":
        d.rectangle([r(30, 45), 0, r(80, 100), r(35, 45)], fill=_rgb("stairs"))
        d.rectangle([0, s - r(12, 20), s, s], fill=_rgb("grass"))
    elif layout == "snow_ice":
        for _ in range(3):
            x, y = r(0, s - 40), r(0, 40)
            d.ellipse([x, y, x + r(25, 40), y + r(15, 25)], fill=_rgb("ice"))
        d.rectangle([0, s - 20, s, s], fill=_rgb("ice"))
    elif layout == "mud_rocks":
        for _ in range(4):
            x, y = r(0, s - 30), r(0, 45)
            d.ellipse([x, y, x + r(18, 30), y + r(12, 22)], fill=_rgb("rock"))
        d.rectangle([0, s - 18, r(40, 70), s], fill=_rgb("grass"))
    elif layout == "blocks":  # an obstacle field: raised blocks away from the centre
        for _ in range(r(6, 10)):
            x, y = r(0, s - 10), r(0, s - 10)
            if abs(x - s / 2) < 24 and abs(y - s / 2) < 24:
                continue
            d.rectangle([x, y, x + r(5, 10), y + r(5, 10)], fill=_rgb("obstacle"))
    elif layout == "beach":  # the sea at the front, a grassy strip behind the sand
        d.rectangle([0, 0, s, r(25, 40)], fill=_rgb("water"))
        d.rectangle([0, s - r(15, 25), s, s], fill=_rgb("grass"))
    elif layout == "forest_edge":
        d.rectangle([0, 0, s, r(25, 40)], fill=_rgb("forest"))
        d.rectangle([0, s - 20, r(30, 50), s], fill=_rgb("rock"))
    elif layout == "marsh":
        for _ in range(3):
            x, y = r(0, s - 35), r(0, 40)
            d.ellipse([x, y, x + r(20, 35), y + r(12, 20)], fill=_rgb("water"))
        d.rectangle([s - 25, 0, s, s], fill=_rgb("grass"))
    elif layout == "plaza":
        d.rectangle([0, 0, s, r(18, 28)], fill=_rgb("stairs"))
        for x in range(8, s, r(24, 34)):
            d.rectangle([x, s - 30, x + 4, s - 26], fill=_rgb("obstacle"))
    elif layout == "dunes_oasis":
        d.ellipse([r(60, 80), r(5, 15), r(100, 120), r(35, 45)], fill=_rgb("water"))
        d.rectangle([0, 0, r(20, 35), s], fill=_rgb("rock"))
    elif layout == "ruins":
        d.rectangle([0, 0, s, r(30, 40)], fill=_rgb("rock"))
        for _ in range(3):
            x, y = r(0, s - 12), r(0, 30)
            d.rectangle([x, y, x + 8, y + 8], fill=_rgb("obstacle"))
        d.rectangle([0, s - 16, s, s], fill=_rgb("mud"))
    return f"sketch_{layout}", img


# ------------------------------------------------------------------------------ procedural scene pictures
SCENE_COLOURS = {  # RGB of the surfaces in rendered pictures, chosen inside the image planner's HSV classes
    "grass": (95, 165, 70), "sand": (232, 206, 140), "water": (40, 95, 175), "snow": (244, 246, 250),
    "ice": (172, 226, 236), "mud": (110, 74, 40), "pavement": (150, 150, 152), "rock": (85, 85, 88),
}
SKY = np.array([140, 190, 235], np.float32)
HORIZON = np.array([40, 48, 60], np.float32)


def _scene(seed: int) -> tuple[str, Image.Image, list[str]]:
    """An eye-level scene picture: sky, a dark horizon band, then ground zones (far at the top, near at the bottom).

    Zones are bands with wavy borders; forests get dark trunks on green, rocks get speckle, stairs get
    regular horizontal nosings. Returns (name, image, the surface classes it shows).
    """
    rng = np.random.default_rng(2000 + seed)
    scenes = [
        ("beach", ["water", "sand"]), ("lakeshore", ["water", "grass"]), ("forest", ["forest", "grass"]),
        ("snowfield", ["snow"]), ("frozen_lake", ["ice", "snow"]), ("mudflat", ["mud", "grass"]),
        ("desert", ["sand"]), ("city_stairs", ["stairs", "pavement"]), ("quarry", ["rock", "sand"]),
        ("river_meadow", ["grass", "water", "grass"]), ("swamp", ["water", "mud"]), ("rocky_field", ["rock", "grass"]),
        ("snowy_forest", ["forest", "snow", "snow"]),
    ]
    name, zones = scenes[seed % len(scenes)]
    s = IMAGE_SIZE
    horizon = int(rng.integers(28, 40))
    img = np.zeros((s, s, 3), np.float32)
    rows = np.arange(s)[:, None]
    img[:horizon] = SKY * (0.92 + 0.08 * rows[:horizon, :, None] / horizon)
    img[horizon:horizon + 3] = HORIZON
    # Zone borders: wavy lines splitting the ground rows evenly.
    top = horizon + 3
    cols = np.arange(s)[None, :]
    bounds = [np.full((1, s), top, np.float32)]
    for k in range(1, len(zones)):
        base = top + (s - top) * k / len(zones)
        bounds.append(base + 3 * np.sin(cols / s * 2 * math.pi * rng.uniform(0.5, 1.5) + rng.uniform(0, 6)))
    bounds.append(np.full((1, s), s, np.float32))
    noise = rng.normal(0.0, 1.0, (s, s, 1)).astype(np.float32)
    for k, zone in enumerate(zones):
        mask = (rows >= bounds[k]) & (rows < bounds[k + 1])
        if zone == "forest":
            colour = np.array((50, 120, 45), np.float32) + 10 * noise
            trunks = (np.sin(cols * 1.3 + rng.uniform(0, 6)) > 0.75) & (rows % 9 < 7)
            colour = np.where(trunks[..., None], np.array((45, 30, 20), np.float32), colour)
        elif zone == "stairs":
            colour = np.array(SCENE_COLOURS["pavement"], np.float32) + 3 * noise
            colour = np.where((rows % 8 < 2)[..., None], np.array((70, 70, 72), np.float32), colour)
        elif zone == "rock":
            colour = np.array(SCENE_COLOURS["rock"], np.float32) + 25 * noise
        else:
            colour = np.array(SCENE_COLOURS[zone], np.float32) + 4 * noise
        img = np.where(mask[..., None], colour, img)
    image = Image.fromarray(np.clip(img, 0, 255).astype(np.uint8))
    return f"scene_{name}", image, sorted(set(zones))


# ------------------------------------------------------------------------------------------------- build
@dataclasses.dataclass(frozen=True)
class BenchmarkSet:
    """Where a set's items come from: its prompts file (in its folder), the pictures' seeds (sketch maps, then
    scene pictures) and the first spec seed of its text and image items."""

    sketches: range
    scenes: range
    text_seed: int
    image_seed: int


SETS = {
    "gente100": BenchmarkSet(sketches=range(25), scenes=range(25), text_seed=0, image_seed=100),
    # other pictures (seeds after gente100's) and other spec seeds: no item shares a terrain with gente100
    "gente_val": BenchmarkSet(sketches=range(25, 35), scenes=range(25, 35), text_seed=1000, image_seed=1100),
}


def read_prompts(path: Path = ROOT / "prompts.txt") -> list[str]:
    lines = [ln.strip() for ln in path.read_text().splitlines()]
    return [ln for ln in lines if ln and not ln.startswith("#")]


def sketch_names(image: Image.Image) -> list[str]:
    """LEGEND classes a sketch is drawn with (exact colours), those covering at least NAME_FRACTION of it.

    Black obstacle blocks count at any size: the planner places them exactly.
    """
    px = np.asarray(image).reshape(-1, 3)
    out = []
    for name, legend in LEGEND.items():
        share = float((px == np.array(legend.rgb)).all(1).mean())
        if share >= NAME_FRACTION or (name == "obstacle" and share > 0):
            out.append(name)
    return sorted(out)


def _thumbnail(spec, size: int) -> Image.Image:
    heights, material = spec.build()
    rgb = preview_rgb(heights, material, spec.resolution)
    return Image.fromarray((rgb * 255).round().astype(np.uint8)).resize((size, size), Image.LANCZOS)


def _contact_sheet(tiles: list[Image.Image], cols: int, path: Path) -> None:
    w, h = tiles[0].size
    rows = math.ceil(len(tiles) / cols)
    sheet = Image.new("RGB", (cols * w, rows * h), (255, 255, 255))
    draw = ImageDraw.Draw(sheet)
    for k, tile in enumerate(tiles):
        x, y = (k % cols) * w, (k // cols) * h
        sheet.paste(tile, (x, y))
        draw.text((x + 2, y + 1), f"{k:02d}", fill=(0, 0, 0))
    sheet.save(path, optimize=True)


def build(name: str = "gente100") -> list[dict]:
    root, plan = BENCHMARKS / name, SETS[name]
    (root / "specs").mkdir(exist_ok=True)
    (root / "images").mkdir(exist_ok=True)
    items, text_tiles, image_tiles = [], [], []
    for k, prompt in enumerate(read_prompts(root / "prompts.txt")):
        item_id = f"text_{k:02d}_{spec_name(prompt)}"
        spec, _ = generate_spec(prompt, seed=plan.text_seed + k, size_x=TILE, size_y=TILE, resolution=RESOLUTION,
                                name=item_id)
        spec.save(root / "specs" / f"{item_id}.json")
        items.append({"id": item_id, "kind": "text", "prompt": prompt, "spec": f"specs/{item_id}.json"})
        text_tiles.append(_thumbnail(spec, 96))
    pictures = [_sketch(k) + (None,) for k in plan.sketches] + [_scene(k) for k in plan.scenes]
    for k, (stem, image, names) in enumerate(pictures):
        item_id = f"image_{k:02d}_{stem}"
        image_path = root / "images" / f"{item_id}.png"
        image.save(image_path, optimize=True)
        names = sketch_names(image) if names is None else names
        spec, _ = generate_spec(image=image_path, seed=plan.image_seed + k, size_x=TILE, size_y=TILE,
                                resolution=RESOLUTION, name=item_id)
        spec.save(root / "specs" / f"{item_id}.json")
        items.append({"id": item_id, "kind": "image", "image": f"images/{item_id}.png", "names": names,
                      "spec": f"specs/{item_id}.json"})
        pair = Image.new("RGB", (128, 64))
        pair.paste(image.resize((64, 64), Image.LANCZOS), (0, 0))
        pair.paste(_thumbnail(spec, 64).rotate(90), (64, 0))  # turned so +x is up, as in the picture
        image_tiles.append(pair)
    _contact_sheet(text_tiles, 10, root / "previews_text.png")
    _contact_sheet(image_tiles, 10, root / "previews_image.png")
    manifest = {"name": name, "tile_size": [TILE, TILE], "resolution": RESOLUTION, "items": items}
    (root / "manifest.json").write_text(json.dumps(manifest, indent=1) + "\n")
    return items


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--set", choices=sorted(SETS), default="gente100", help="which benchmark to build")
    parser.add_argument("--check", action="store_true", help="run the checker on every item after building")
    args = parser.parse_args(argv)
    root = BENCHMARKS / args.set
    items = build(args.set)
    print(f"built {len(items)} items in {root}")
    if not args.check:
        return 0
    from legged_gente.evaluation.benchmark import load_benchmark
    from legged_gente.generation.checker import check_item

    failed = 0
    for item in load_benchmark(root):
        result = check_item(item)
        if not result.ok:
            failed += 1
            print(f"FAIL {item.id}: " + " ".join(result.problems))
    print(f"{len(items) - failed}/{len(items)} items pass the checker")
    return 1 if failed else 0


if __name__ == "__main__":
    sys.exit(main())
