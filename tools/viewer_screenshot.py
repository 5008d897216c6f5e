"""Screenshot of gente-view in headless Chromium (Debian's chromium + chromium-driver, driven by Selenium: the
``browser`` extra, ``pip install -e ".[browser]"``).

    python tools/viewer_screenshot.py docs/img/viewer_beach.png -- /tmp/beach/spec.json
    python tools/viewer_screenshot.py docs/img/viewer_rollout.png --wait 240 -- rollout.npz --step 60

Starts ``gente-view ARGS --headless`` on a free port, loads the page, and takes screenshots until the 3-D view
shows the terrain (enough non-background pixels left of the control panel) or ``--wait`` seconds pass.
Software WebGL (SwiftShader) is slow: the first frame can take a minute on a busy CPU.
"""

from __future__ import annotations

import argparse
import importlib.util
import io
import socket
import subprocess
import sys
import time
import urllib.request
from pathlib import Path

import numpy as np

CHROMIUM, CHROMEDRIVER = "/usr/bin/chromium", "/usr/bin/chromedriver"
WINDOW = (900, 600)
PANEL_WIDTH = 340
"""px of viser's control panel on the right, left out of the terrain-pixel count."""


def free_port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


def browser_missing() -> str | None:
    """What the screenshot needs and this machine lacks, in one line with the install (None: nothing)."""
    if importlib.util.find_spec("selenium") is None:
        return 'Selenium is not installed: pip install -e ".[browser]"'
    for path in (CHROMIUM, CHROMEDRIVER):
        if not Path(path).is_file():
            return f"{path} not found: apt-get install chromium chromium-driver (Debian's)"
    return None


def wait_for_page(url: str, timeout: float, server: subprocess.Popen | None = None) -> None:
    deadline = time.monotonic() + timeout
    while True:
        if server is not None and server.poll() is not None:
            raise RuntimeError(f"gente-view exited with code {server.returncode} before serving {url}")
        try:
            with urllib.request.urlopen(url, timeout=5):
                return
        except OSError:
            if time.monotonic() > deadline:
                raise TimeoutError(f"{url} did not answer within {timeout:.0f} s") from None
            time.sleep(1.0)


def scene_fraction(png: bytes) -> float:
    """Share of the 3-D view's pixels (panel excluded) that are not the white/grey background."""
    from PIL import Image

    rgb = np.asarray(Image.open(io.BytesIO(png)).convert("RGB"), np.int32)
    view = rgb[:, : max(rgb.shape[1] - PANEL_WIDTH, 1)]
    saturation = view.max(-1) - view.min(-1)
    return float(((saturation > 25) | (view.sum(-1) < 690)).mean())


def screenshot(url: str, path: Path, wait: float = 180.0, min_fraction: float = 0.05) -> float:
    """Save a screenshot of ``url`` once the scene covers ``min_fraction`` of the view; returns the fraction."""
    from selenium import webdriver
    from selenium.common.exceptions import WebDriverException
    from selenium.webdriver.chrome.service import Service

    options = webdriver.ChromeOptions()
    options.binary_location = CHROMIUM
    for flag in ("--headless=new", "--no-sandbox", "--disable-dev-shm-usage", f"--window-size={WINDOW[0]},{WINDOW[1]}",
                 "--use-angle=swiftshader", "--enable-unsafe-swiftshader", "--ignore-gpu-blocklist"):
        options.add_argument(flag)
    driver = webdriver.Chrome(service=Service(CHROMEDRIVER), options=options)
    deadline = time.monotonic() + wait
    fraction, notice_removed = 0.0, False
    path.parent.mkdir(parents=True, exist_ok=True)
    try:
        driver.set_page_load_timeout(60)
        driver.get(url)
        while time.monotonic() < deadline:
            time.sleep(5.0)
            try:
                png = driver.get_screenshot_as_png()
            except WebDriverException as error:  # the renderer is still busy with the first frame
                print(f"  no frame yet ({type(error).__name__})", flush=True)
                continue
            if not notice_removed and "Software WebGL" in driver.page_source:
                notice_removed = True  # viser's notice about software rendering is not part of the scene
                driver.execute_script(
                    "for (const n of document.querySelectorAll('[class*=Notification-root], [class*=notification]'))"
                    " if (n.textContent.includes('Software WebGL')) n.remove();")
                continue
            fraction = scene_fraction(png)
            print(f"  frame: scene on {fraction:.1%} of the view", flush=True)
            path.with_suffix(".last.png").write_bytes(png)
            if fraction >= min_fraction:
                path.write_bytes(png)
                return fraction
    finally:
        driver.quit()
    raise TimeoutError(f"the scene covered {fraction:.1%} of the view after {wait:.0f} s (need {min_fraction:.0%})")


def main(argv=None) -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0], usage="%(prog)s [-h] [--wait WAIT] out -- "
                                     "GENTE_VIEW_ARGS...")
    parser.add_argument("out", type=Path)
    parser.add_argument("--wait", type=float, default=240.0, help="s to wait for the scene")
    argv = sys.argv[1:] if argv is None else list(argv)
    split = argv.index("--") if "--" in argv else len(argv)
    args, view_args = parser.parse_args(argv[:split]), argv[split + 1:]  # --help: the usage, before the check below
    if "--" not in argv:
        parser.error("give gente-view's arguments after --")
    missing = browser_missing()
    if missing:
        parser.error(missing)
    port = free_port()
    server = subprocess.Popen([sys.executable, "-m", "legged_gente.scripts.view", *view_args, "--headless",
                               "--no_shadows", "--port", str(port), "--seconds", str(args.wait + 300)])
    try:
        wait_for_page(f"http://127.0.0.1:{port}", 300.0, server)
        fraction = screenshot(f"http://127.0.0.1:{port}", args.out, args.wait)
        print(f"wrote {args.out} (scene on {fraction:.0%} of the view)")
    finally:
        server.terminate()
        server.wait(timeout=30)


if __name__ == "__main__":
    main()
