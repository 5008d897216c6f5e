"""The viewer in a real browser: headless Chromium loads the page, the terrain appears, a screenshot is saved.

Deselected from the plain ``pytest`` run (software WebGL needs up to a minute for the first frame on a busy
CPU); ``.ci/run`` runs it as its own step:
``GENTE_BROWSER_SHOT=docs/img/viewer_browser_test.png python -m pytest -m browser tests/test_viewer_browser.py``.
The setup installs Debian's ``chromium`` and ``chromium-driver`` with apt-get when they are missing (as root) and
needs Selenium (``pip install -e .[browser]``).
"""

from __future__ import annotations

import importlib.util
import os
import shutil
import subprocess
from pathlib import Path

import numpy as np
import pytest

pytestmark = pytest.mark.browser


@pytest.fixture(scope="module")
def browser(load_file):
    tool = load_file("tools/viewer_screenshot.py")
    if not (Path(tool.CHROMIUM).exists() and Path(tool.CHROMEDRIVER).exists()):
        if os.geteuid() != 0 or shutil.which("apt-get") is None:
            pytest.fail("chromium and chromium-driver are missing: apt-get install -y chromium chromium-driver")
        subprocess.run(["apt-get", "install", "-y", "chromium", "chromium-driver"], check=True, timeout=600,
                       stdout=subprocess.DEVNULL)
    if importlib.util.find_spec("selenium") is None:
        pytest.fail("Selenium is missing: pip install -e '.[browser]'")
    return tool


def test_browser_shows_the_terrain(browser, tmp_path):
    from PIL import Image

    from legged_gente.terrain.terrain import Terrain
    from legged_gente.viewer.server import TerrainItem, Viewer

    class Cfg:
        mesh_type, mode, resolution, border_size = "heightfield", "curriculum", 0.1, 1.0
        terrain_length = terrain_width = 6.0
        num_rows, num_cols = 1, 2
        terrain_types = ["hills+soil:preset=dry_sand", "river+water"]
        terrain_proportions = [0.5, 0.5]
        selected_terrain, selected_params, generated_specs = "flat", {}, []
        max_difficulty, max_init_terrain_level, curriculum, static_friction, seed = 1.0, 0, True, 1.0, 0

    terrain = Terrain(Cfg, num_robots=1)
    viewer = Viewer([TerrainItem("sand and river", lambda: terrain)], port=browser.free_port(), shadows=False)
    try:
        out = tmp_path / "viewer.png"
        fraction = browser.screenshot(viewer.url, out, wait=300.0)
    finally:
        viewer.stop()
    assert fraction >= 0.05
    rgb = np.asarray(Image.open(out).convert("RGB"), np.int32)[:, : -browser.PANEL_WIDTH]
    # sand pixels: warm, red and green above blue; the grey border and the white background are neutral
    sandy = (rgb[..., 0] - rgb[..., 2] > 8) & (rgb[..., 1] - rgb[..., 2] > 5)
    assert sandy.mean() > 0.01, f"no sand-coloured terrain on screen ({sandy.mean():.2%} of the pixels)"
    # and in the dry-sand colour (237, 212, 143), not washed out: vertex colours sent as sRGB instead of linear
    # showed about (239, 235, 224), red only 15 above blue
    warmth = np.median(rgb[sandy][:, 0] - rgb[sandy][:, 2])
    assert warmth > 40, f"the sand is pale: red - blue = {warmth} (dry sand: 237 - 143 = 94)"
    if os.environ.get("GENTE_BROWSER_SHOT"):  # where to keep the screenshot (docs/img/viewer_browser_test.png)
        shutil.copy(out, os.environ["GENTE_BROWSER_SHOT"])
