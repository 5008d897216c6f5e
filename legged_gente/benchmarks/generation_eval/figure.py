"""Draw docs/img/gen_photos.png: eight evaluation photos next to the terrains the offline planner builds.

    python legged_gente/benchmarks/generation_eval/figure.py

Each terrain preview is turned so that it matches the photo: the tile's front (+x) at the top, its left (+y)
on the left; the robot starts at the bottom edge, where the camera stands.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
from PIL import Image, ImageDraw

from legged_gente.generation.backends.image import plan_image
from legged_gente.generation.spec import TerrainSpec
from legged_gente.terrain.terrain import preview_rgb

HERE = Path(__file__).resolve().parent
OUT = HERE.parents[2] / "docs" / "img" / "gen_photos.png"
PICKS = ("00_beach_waves.png", "02_river_crossing.jpg", "06_city_street.png", "08_stone_stairs.jpg",
         "11_grassy_hill.jpg", "17_rocky_field.jpg", "27_fountain_square.png", "04_snowy_forest.png")
W, H = 160, 120


def main() -> None:
    tiles = []
    for name in PICKS:
        photo = Image.open(HERE / "photos" / name).convert("RGB").resize((W, H))
        result = plan_image(HERE / "photos" / name)
        heights, material = TerrainSpec(result.calls).build()
        rgb = np.rot90(preview_rgb(heights, material, 0.1), 1)  # front (+x) up, left (+y) left
        terrain = Image.fromarray((rgb * 255).round().astype(np.uint8)).resize((H, H), Image.LANCZOS)
        tile = Image.new("RGB", (W + H + 6, H + 14), (255, 255, 255))
        tile.paste(photo, (0, 0))
        tile.paste(terrain, (W + 6, 0))
        ImageDraw.Draw(tile).text((2, H + 1), f"{name[3:].rsplit('.', 1)[0]}: {len(result.calls)} calls", fill=(0, 0, 0))
        tiles.append(tile)
    tw, th = tiles[0].size
    sheet = Image.new("RGB", (2 * tw + 10, 4 * th), (255, 255, 255))
    for k, tile in enumerate(tiles):
        sheet.paste(tile, ((k % 2) * (tw + 10), (k // 2) * th))
    sheet.quantize(128, dither=Image.Dither.NONE).save(OUT, optimize=True)  # small in the repository
    print(f"wrote {OUT} ({OUT.stat().st_size // 1024} KB)")


if __name__ == "__main__":
    main()
