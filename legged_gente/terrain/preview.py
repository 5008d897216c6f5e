"""A terrain picture a person can read: hillshaded heights tinted by material, with a legend, axes in metres
and a scale bar, drawn as a robot (and the image planner) sees the tile: +x (forward) up, +y (left) to the left.

That is the orientation of an input picture in ``gente-generate --image``: its top row is the tile's front
(+x), its left column the tile's left (+y), so a preview lies the same way as the picture it came from.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from .materials import MaterialMap
from .terrain import (
    CUSTOM_SOIL_COLOUR, GROUND_GREY, LOW_FRICTION_COLOUR, LOW_FRICTION_TINT_BELOW, SOIL_COLOURS, WATER_COLOUR, preview_rgb)


def material_legend(material: MaterialMap) -> list[tuple[str, tuple[float, float, float]]]:
    """(label, RGB in [0, 1]) of each material present: soil presets, low friction, water."""
    legend = []
    for k, name in enumerate(material.soil_presets):
        if (material.soil == k).any():
            legend.append((name.replace("_", " "), SOIL_COLOURS.get(name, CUSTOM_SOIL_COLOUR)))
    if (material.friction < LOW_FRICTION_TINT_BELOW).any():
        legend.append((f"low friction (mu < {LOW_FRICTION_TINT_BELOW})", LOW_FRICTION_COLOUR))
    if material.has_water().any():
        legend.append(("water", WATER_COLOUR))
    return legend


def top_view(heights: np.ndarray, material: MaterialMap, resolution: float) -> np.ndarray:
    """(nx, ny, 3) preview colours as the picture is read: row 0 is the front edge (largest x), column 0 the
    left edge (largest y)."""
    return preview_rgb(heights, material, resolution).transpose(1, 0, 2)[::-1]


def scale_bar_length(extent: float) -> float:
    """A round length (1, 2 or 5 x 10^k m) about a fifth of ``extent`` (m)."""
    target = extent / 5.0
    power = 10.0 ** np.floor(np.log10(target))
    return float(max(m * power for m in (1.0, 2.0, 5.0) if m * power <= target))


def save_preview_figure(heights: np.ndarray, material: MaterialMap, resolution: float, path: str | Path,
                        origin_xy: tuple[float, float] = (0.0, 0.0), title: str | None = None,
                        size_px: int = 900) -> Path:
    """Write the preview PNG (about ``size_px`` wide): +x up, +y left, axes in metres, legend and scale bar."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    from matplotlib.patches import Patch
    from mpl_toolkits.axes_grid1.anchored_artists import AnchoredSizeBar

    nx, ny = heights.shape
    image = top_view(heights, material, resolution)
    x0, y0 = origin_xy[0] - resolution / 2, origin_xy[1] - resolution / 2
    x1, y1 = x0 + nx * resolution, y0 + ny * resolution
    dpi = 100
    fig, ax = plt.subplots(figsize=(size_px / dpi, size_px / dpi * min(max(nx / ny, 0.4), 2.5)), dpi=dpi)
    ax.imshow(image, extent=(y1, y0, x0, x1), interpolation="nearest")  # left edge: largest y; top: largest x
    ax.set_xlabel("y (m), +y to the left")
    ax.set_ylabel("x (m), +x forward")
    lo, hi = float(heights.min()), float(heights.max())
    ax.set_title(title or "", loc="left")
    ax.text(1.0, 1.01, f"heights {lo:+.2f} to {hi:+.2f} m", transform=ax.transAxes, ha="right", va="bottom",
            fontsize=9)
    bar = scale_bar_length(max(x1 - x0, y1 - y0))
    ax.add_artist(AnchoredSizeBar(ax.transData, -bar, f"{bar:g} m", "lower right", pad=0.5, color="black",
                                  frameon=True, size_vertical=resolution * 1.5))
    handles = [Patch(facecolor=c, edgecolor="0.3", label=label) for label, c in material_legend(material)]
    handles.insert(0, Patch(facecolor=str(sum(GROUND_GREY) / 2), edgecolor="0.3", label="bare ground (grey)"))
    ax.legend(handles=handles, loc="upper left", bbox_to_anchor=(1.01, 1.0), fontsize=9, frameon=False)
    # the ground's lightness against height (before the hillshade, which darkens slopes facing away from the light)
    greys = matplotlib.colors.LinearSegmentedColormap.from_list("ground", [str(GROUND_GREY[0]), str(GROUND_GREY[1])])
    scale = matplotlib.cm.ScalarMappable(matplotlib.colors.Normalize(lo, hi if hi > lo else lo + 1e-3), greys)
    fig.colorbar(scale, ax=ax, location="bottom", fraction=0.04, pad=0.08, label="bare ground's height (m)")
    fig.tight_layout()
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(path, dpi=dpi, bbox_inches="tight")
    plt.close(fig)
    return path
