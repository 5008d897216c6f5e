"""Render the photo half of the planner's evaluation set: perspective scenes drawn with numpy and PIL.

    python legged_gente/benchmarks/generation_eval/render.py   # rewrite photos/*.png|jpg and photos/manifest.json

Each scene of :data:`SCENES` is written by hand: what is in it (sky, ground surfaces by distance, water,
objects standing on the ground) and its labels (what a walking robot meets on the 20 m in front of the
camera; things far beyond it, such as a distant tree line or mountains, are not labelled). The renderer is a
pinhole camera over a ground plane: every ground pixel is coloured from the world point it sees (so textures
shrink towards the horizon), water reflects the sky, objects are drawn far to near. Each scene draws its own
random palette, light, camera height, focal length, horizon, noise and file format from its seed, so the
rules of the image reader cannot lean on one fixed look. Everything is deterministic.
"""

from __future__ import annotations

import colorsys
import json
from pathlib import Path

import numpy as np
from PIL import Image, ImageDraw, ImageFilter

ROOT = Path(__file__).resolve().parent / "photos"
W, H = 160, 120


def hsv(h, s, v):
    return np.array(colorsys.hsv_to_rgb((h % 360) / 360.0, float(np.clip(s, 0, 1)), float(np.clip(v, 0, 1))))


class Scene:
    """One picture being drawn: camera, sky, ground buffer, painter's list of objects."""

    def __init__(self, seed: int):
        self.rng = np.random.default_rng(seed)
        r = self.rng
        self.hz = H * r.uniform(0.30, 0.52)  # horizon row
        self.f = W / (2 * np.tan(np.radians(r.uniform(50, 75)) / 2))
        self.cam = r.uniform(1.3, 2.0)
        self.light = r.uniform(0.75, 1.15)
        rows, cols = np.mgrid[0:H, 0:W].astype(np.float64)
        self.rows, self.cols = rows, cols
        below = rows + 0.5 - self.hz
        self.Z = np.where(below > 0.3, self.f * self.cam / np.maximum(below, 0.3), 1e4)
        self.X = (cols - W / 2) * self.Z / self.f
        self.img = np.zeros((H, W, 3))
        self.grid = r.random((4, 96, 96))
        self.grid[:, 95, :] = self.grid[:, 0, :]  # periodic: no seam where the coordinates wrap
        self.grid[:, :, 95] = self.grid[:, :, 0]

    # ----------------------------------------------------------------------------------------- helpers
    def noise(self, x, z, scale, k=0):
        """Smooth value noise in [0, 1] at world points (bilinear on a random grid)."""
        g = self.grid[k % 4]
        u, v = (x / scale) % 95, (z / scale) % 95
        i, j = np.floor(u).astype(int), np.floor(v).astype(int)
        fu, fv = u - i, v - j
        fu, fv = fu * fu * (3 - 2 * fu), fv * fv * (3 - 2 * fv)
        return (g[i, j] * (1 - fu) * (1 - fv) + g[i + 1, j] * fu * (1 - fv) + g[i, j + 1] * (1 - fu) * fv
                + g[i + 1, j + 1] * fu * fv)

    def fbm(self, x, z, scale, k=0):
        return 0.55 * self.noise(x, z, scale, k) + 0.3 * self.noise(x, z, scale / 2.3, k + 1) + 0.15 * self.noise(x, z, scale / 5.1, k + 2)

    def row(self, z, y=0.0):
        """Image row of a world point at distance z and height y."""
        return self.hz + self.f * (self.cam - y) / z

    def col(self, x, z):
        return W / 2 + x * self.f / z

    # ----------------------------------------------------------------------------------------- sky
    def sky(self, kind: str, clouds: float = 0.3):
        r = self.rng
        t = np.clip(self.rows / max(self.hz, 1), 0, 1)[..., None]  # 0 top, 1 horizon
        if kind == "blue":
            top, low = hsv(r.uniform(205, 225), r.uniform(0.55, 0.8), r.uniform(0.65, 0.85)), hsv(r.uniform(195, 210), r.uniform(0.15, 0.35), r.uniform(0.9, 1.0))
        elif kind == "overcast":
            g = r.uniform(0.6, 0.85)
            top, low = np.full(3, g - 0.08) + r.uniform(-0.02, 0.02, 3), np.full(3, g + 0.08)
        elif kind == "white":
            top, low = np.full(3, r.uniform(0.85, 0.92)), np.full(3, r.uniform(0.95, 1.0))
        elif kind == "sunset":
            top, low = hsv(r.uniform(230, 270), r.uniform(0.4, 0.6), r.uniform(0.35, 0.55)), hsv(r.uniform(15, 40), r.uniform(0.55, 0.8), r.uniform(0.9, 1.0))
        elif kind == "dusk":
            top, low = hsv(r.uniform(220, 235), 0.7, r.uniform(0.2, 0.3)), hsv(r.uniform(200, 215), 0.45, r.uniform(0.5, 0.65))
        else:
            raise ValueError(kind)
        sky = top * (1 - t ** 1.5) + low * t ** 1.5
        if clouds > 0:
            n = self.fbm(self.cols * 0.04, self.rows * 0.1 + 40, 1.0, 3)
            c = np.clip((n - (1 - clouds * 0.8)) * 3, 0, 1)[..., None] * 0.8
            cloud = low * 0.3 + 0.7 * (np.ones(3) if kind != "sunset" else hsv(20, 0.3, 1.0))
            sky = sky * (1 - c) + cloud * c
        self.sky_rgb = sky
        self.img[:] = sky
        self.low_sky = low

    def background(self, kind: str):
        """Far scenery standing on the horizon (not part of the 20 m tile): mountains, tree line, skyline."""
        r = self.rng
        c = np.arange(W)
        if kind == "mountains":
            ridge = self.hz - H * (0.08 + 0.12 * self.noise(c * 0.05, np.zeros(W) + r.uniform(0, 50), 1.0, 2))
            col = self.low_sky * 0.5 + hsv(r.uniform(200, 230), 0.25, 0.55) * 0.5
            mask = self.rows >= ridge[None, :]
            self.img[mask & (self.rows < self.hz + 1)] = col
            if r.random() < 0.6:  # snow caps
                cap = mask & (self.rows < ridge[None, :] + H * 0.03)
                self.img[cap] = 0.92
        elif kind == "treeline":
            ridge = self.hz - H * (0.02 + 0.03 * self.noise(c * 0.4, np.zeros(W) + r.uniform(0, 50), 1.0, 1))
            mask = (self.rows >= ridge[None, :]) & (self.rows < self.hz + 1)
            self.img[mask] = hsv(r.uniform(90, 140), 0.45, r.uniform(0.18, 0.3))
        elif kind == "skyline":
            x = 0
            while x < W:
                w = int(r.integers(8, 22))
                top = int(self.hz - H * r.uniform(0.04, 0.14))
                self.img[top:int(self.hz) + 1, x:x + w] = self.low_sky * 0.6 + 0.25 * r.uniform(0.5, 1.0)
                x += w

    # ----------------------------------------------------------------------------------------- ground
    def surface(self, name: str, X, Z):
        """Colour of a ground surface at world points (X, Z); arrays of shape X.shape + (3,)."""
        r = self.rng
        fade = np.clip(6.0 / Z, 0.25, 1.0)[..., None]  # fine texture averages out with distance
        def tex(base, amp, scale, k=0):
            n = self.fbm(X, Z, scale, k)[..., None] - 0.5
            return base + amp * fade * n * 2
        if name == "grass":
            base = hsv(r.uniform(75, 115), r.uniform(0.45, 0.7), r.uniform(0.4, 0.6))
            return tex(base, 0.12, 0.4) * (0.85 + 0.3 * self.noise(X, Z, 4.0, 1)[..., None])
        if name == "dry_grass":
            return tex(hsv(r.uniform(50, 70), r.uniform(0.4, 0.55), r.uniform(0.55, 0.7)), 0.1, 0.4)
        if name == "sand":
            base = hsv(r.uniform(33, 48), r.uniform(0.25, 0.45), r.uniform(0.72, 0.9))
            ripple = 0.03 * np.sin(Z * 9 + 3 * self.noise(X, Z, 2.0))[..., None]
            return tex(base, 0.05, 0.8) + ripple * fade
        if name == "snow":
            base = hsv(r.uniform(195, 225), r.uniform(0.03, 0.1), r.uniform(0.86, 0.97))
            shade = (self.noise(X, Z, 5.0, 2) - 0.5)[..., None] * 0.12
            return base + shade + 0.02 * fade * (self.noise(X, Z, 0.1, 3)[..., None] - 0.5)
        if name == "mud":
            base = hsv(r.uniform(18, 35), r.uniform(0.4, 0.6), r.uniform(0.22, 0.38))
            out = tex(base, 0.06, 0.5)
            wet = (self.noise(X, Z, 1.5, 2) > 0.72)[..., None]
            return np.where(wet, base * 0.6 + 0.4 * self.mirror() * 0.6, out)
        if name == "dirt":
            return tex(hsv(r.uniform(25, 40), r.uniform(0.3, 0.45), r.uniform(0.45, 0.62)), 0.08, 0.3)
        if name == "ice":
            base = hsv(r.uniform(185, 205), r.uniform(0.1, 0.28), r.uniform(0.72, 0.88))
            crack = (np.abs(self.noise(X, Z, 1.2, 1) - 0.5) < 0.015)[..., None]
            sheen = 0.25 * self.mirror()
            return np.where(crack, base * 0.75, base * 0.8 + sheen * 0.25 + 0.04 * (self.noise(X, Z, 3.0) - 0.5)[..., None])
        if name == "asphalt":
            base = np.full(3, r.uniform(0.25, 0.42)) + r.uniform(-0.02, 0.02, 3)
            out = tex(base, 0.05, 0.05)
            lane = ((np.abs(X) < 0.08) & ((Z % 3.0) < 1.5))[..., None]
            return np.where(lane, 0.9, out)
        if name == "tiles":
            base = hsv(r.uniform(20, 50), r.uniform(0.0, 0.15), r.uniform(0.5, 0.7))
            joint = (((X % 0.6) < 0.04) | ((Z % 0.6) < 0.04))[..., None] & (fade > 0.5)
            return np.where(joint, base * 0.7, tex(base, 0.04, 0.3))
        if name == "gravel":
            base = hsv(r.uniform(20, 40), r.uniform(0.05, 0.2), r.uniform(0.45, 0.6))
            speck = self.noise(X, Z, 0.04, 1)[..., None] - 0.5
            return base + 0.5 * speck * fade
        if name in ("water", "river", "sea"):
            return self.water(X, Z, name)
        raise ValueError(name)

    def mirror(self):
        """The sky reflected in a flat surface, per pixel (row 2 * horizon - r)."""
        mr = np.clip((2 * self.hz - self.rows).astype(int), 0, int(self.hz))
        return self.sky_rgb[mr, self.cols.astype(int)]

    def water(self, X, Z, kind):
        r = self.rng
        tint = hsv(r.uniform(180, 215), r.uniform(0.3, 0.6), r.uniform(0.3, 0.5))
        out = 0.55 * self.mirror() + 0.45 * tint
        ripple = self.noise(X * 0.3, Z * 6, 1.0, 1)[..., None] - 0.5
        out = out + 0.08 * ripple
        if kind == "river":  # streaks and foam along the current (across the view)
            foam = (self.noise(X * 0.4, Z * 3, 1.0, 2) > 0.7)[..., None]
            out = np.where(foam, 0.85 + 0.1 * ripple, out + 0.1 * ripple)
        elif kind == "sea":  # wave crests across the view with foam
            crest = (np.sin(Z * 2 * np.pi / self.wave + 2 * self.noise(X, Z, 3.0)) > 0.75)[..., None]
            out = np.where(crest, out * 0.5 + 0.5 * 0.95, out)
        return out

    def ground(self, zones):
        """Zones: list of (surface, z0, z1, x0, x1), later ones on top; the first fills the whole ground."""
        self.wave = self.rng.uniform(1.5, 3.0)
        g = self.rows + 0.5 > self.hz
        for name, z0, z1, x0, x1 in zones:
            m = g & (self.Z >= z0) & (self.Z < z1) & (self.X >= x0) & (self.X < x1)
            if m.any():
                col = self.surface(name, self.X, self.Z)
                self.img[m] = col[m]
        # haze towards the horizon
        haze = (1 - np.exp(-self.Z / 80.0))[..., None] * g[..., None]
        self.img = self.img * (1 - haze * 0.7) + self.low_sky * haze * 0.7

    def hill(self, surface, height, tilt=0.0):
        """Ground rising above the horizon: a ridge (height = fraction of the image) or a tilted hillside."""
        r = self.rng
        c = np.arange(W) / W
        if tilt:
            ridge = self.hz - H * (height * 0.3 + tilt * (c if r.random() < 0.5 else 1 - c))
        else:
            ridge = self.hz - H * height * np.sin(np.pi * np.clip(c * r.uniform(0.7, 1.2) + r.uniform(-0.2, 0.2), 0, 1)) ** 0.8
        mask = (self.rows >= ridge[None, :]) & (self.rows < self.hz + 3)
        Zh = 12 + 30 * np.clip((self.rows - ridge[None, :]) / H, 0, 1)
        col = self.surface(surface, (self.cols - W / 2) * Zh / self.f, Zh)
        lit = (0.85 + 0.3 * c)[None, :, None] if r.random() < 0.5 else (1.15 - 0.3 * c)[None, :, None]
        self.img[mask] = (col * lit)[mask]

    # ----------------------------------------------------------------------------------------- objects
    def draw(self, fn):
        im = Image.fromarray((np.clip(self.img, 0, 1) * 255).astype(np.uint8))
        fn(ImageDraw.Draw(im))
        self.img = np.asarray(im, np.float64) / 255.0

    def px(self, x, z, y=0.0):
        return self.col(x, z), self.row(z, y)

    def c255(self, rgb):
        return tuple(int(v) for v in np.clip(np.asarray(rgb) * 255 * self.light, 0, 255))

    def tree(self, x, z, conifer=None):
        r = self.rng
        conifer = r.random() < 0.5 if conifer is None else conifer
        h = r.uniform(4, 9)
        bx, by = self.px(x, z)
        s = self.f / z
        green = hsv(r.uniform(85, 140), r.uniform(0.4, 0.7), r.uniform(0.2, 0.45))
        def fn(d):
            d.rectangle([bx - 0.15 * s, by - 0.45 * h * s, bx + 0.15 * s, by], fill=self.c255(hsv(25, 0.5, 0.3)))
            if conifer:
                for k in range(3):
                    y0 = by - h * s * (0.3 + 0.23 * k)
                    w = (1.6 - 0.4 * k) * s
                    d.polygon([(bx - w, y0), (bx + w, y0), (bx, y0 - 0.4 * h * s)], fill=self.c255(green * (0.9 + 0.1 * k)))
            else:
                for k in range(5):
                    cx, cy = bx + r.uniform(-1, 1) * s, by - h * s * r.uniform(0.55, 0.85)
                    rr = r.uniform(1.0, 1.8) * s
                    d.ellipse([cx - rr, cy - rr, cx + rr, cy + rr], fill=self.c255(green * r.uniform(0.8, 1.2)))
        self.draw(fn)

    def box(self, x, z, w, h, rgb, windows=False):
        """A box standing on the ground, facing the camera (buildings, blocks, cars, benches)."""
        (x0, y0), (x1, y1) = self.px(x - w / 2, z, h), self.px(x + w / 2, z, 0)
        s = self.f / z
        def fn(d):
            d.rectangle([x0, y0, x1, y1], fill=self.c255(rgb))
            d.rectangle([x0, y1 - 0.1 * (y1 - y0), x1, y1], fill=self.c255(np.asarray(rgb) * 0.6))
            if windows:
                for wy in np.arange(y0 + 1.0 * s, y1 - 1.5 * s, 3.0 * s):
                    for wx in np.arange(x0 + 0.8 * s, x1 - 1.2 * s, 2.5 * s):
                        d.rectangle([wx, wy, wx + 1.0 * s, wy + 1.2 * s], fill=self.c255(hsv(210, 0.3, 0.3)))
        self.draw(fn)

    def post(self, x, z, h, rgb=(0.15, 0.15, 0.17), width=0.12):
        (x0, y0), (x1, y1) = self.px(x - width, z, h), self.px(x + width, z, 0)
        self.draw(lambda d: d.rectangle([x0, y0, max(x1, x0 + 1), y1], fill=self.c255(rgb)))

    def rock(self, x, z, size):
        r = self.rng
        cx, cy = self.px(x, z)
        s = self.f / z * size
        g = r.uniform(0.3, 0.55)
        col = np.array([g, g * r.uniform(0.92, 1.0), g * r.uniform(0.85, 0.98)])
        def fn(d):
            d.ellipse([cx - s, cy - 0.2 * s, cx + s, cy + 0.25 * s], fill=self.c255(col * 0.35))  # shadow
            d.ellipse([cx - 0.9 * s, cy - 0.9 * s, cx + 0.9 * s, cy + 0.1 * s], fill=self.c255(col))
            d.ellipse([cx - 0.6 * s, cy - 0.85 * s, cx + 0.2 * s, cy - 0.4 * s], fill=self.c255(col * 1.3))
        self.draw(fn)

    def wall(self, z, x0, x1, h, rgb, fence=False):
        (a, top), (b, bot) = self.px(x0, z, h), self.px(x1, z, 0)
        s = self.f / z
        def fn(d):
            if fence:
                for xx in np.arange(x0, x1, 1.5):
                    px0, _ = self.px(xx, z)
                    d.rectangle([px0, top, px0 + 0.12 * s, bot], fill=self.c255(rgb))
                for k in (0.3, 0.75):
                    yy = bot - k * (bot - top)
                    d.rectangle([a, yy, b, yy + max(0.08 * s, 1)], fill=self.c255(rgb))
            else:
                d.rectangle([a, top, b, bot], fill=self.c255(rgb))
                for yy in np.arange(top, bot, max(0.3 * s, 2)):
                    d.line([a, yy, b, yy], fill=self.c255(np.asarray(rgb) * 0.75))
        self.draw(fn)

    def side_wall(self, x, z0, z1, h, rgb, windows=False):
        """A wall along the view (a building front along a street), from distance z0 to z1 at lateral x."""
        pts = [self.px(x, z0, 0), self.px(x, z1, 0), self.px(x, z1, h), self.px(x, z0, h)]
        def fn(d):
            d.polygon(pts, fill=self.c255(rgb))
            if windows:
                for zz in np.arange(z0 + 1.5, z1 - 1, 3.0):
                    for yy in np.arange(2.0, h - 1.5, 3.0):
                        q = [self.px(x, zz, yy), self.px(x, zz + 1.2, yy), self.px(x, zz + 1.2, yy + 1.4), self.px(x, zz, yy + 1.4)]
                        d.polygon(q, fill=self.c255(hsv(215, 0.25, 0.25)))
        self.draw(fn)

    def stairs(self, z0, n, x0, x1, rise, run, rgb, cover=None):
        """A flight rising away from the camera: step k's riser at distance z0 + k * run."""
        tread = np.asarray(rgb) if cover is None else np.asarray(cover)
        def fn(d):
            for k in reversed(range(n)):
                z, y = z0 + k * run, k * rise
                riser = [self.px(x0, z, y), self.px(x1, z, y), self.px(x1, z, y + rise), self.px(x0, z, y + rise)]
                top = [self.px(x0, z, y + rise), self.px(x1, z, y + rise), self.px(x1, z + run, y + rise), self.px(x0, z + run, y + rise)]
                d.polygon(top, fill=self.c255(tread * 1.1))
                d.polygon(riser, fill=self.c255(np.asarray(rgb) * 0.6))
        self.draw(fn)

    def fountain(self, x, z, rgb):
        cx, cy = self.px(x, z)
        s = self.f / z
        water = np.clip(0.5 * self.low_sky + 0.5 * hsv(200, 0.5, 0.6), 0, 1)
        def fn(d):
            d.ellipse([cx - 3 * s, cy - 1.2 * s, cx + 3 * s, cy + 0.6 * s], fill=self.c255(rgb))
            d.ellipse([cx - 2.6 * s, cy - 1.05 * s, cx + 2.6 * s, cy + 0.2 * s], fill=self.c255(water))
            d.rectangle([cx - 0.25 * s, cy - 2.8 * s, cx + 0.25 * s, cy - 0.4 * s], fill=self.c255(rgb))
            d.ellipse([cx - 0.7 * s, cy - 3.8 * s, cx + 0.7 * s, cy - 2.6 * s], fill=self.c255((0.9, 0.95, 1.0)))
        self.draw(fn)

    def pond(self, x, z, rx, rz):
        """An elliptic pond on the ground at (x, z) with half axes rx, rz metres."""
        m = (((self.X - x) / rx) ** 2 + ((self.Z - z) / rz) ** 2 < 1) & (self.rows + 0.5 > self.hz)
        self.img[m] = self.water(self.X, self.Z, "water")[m]

    def lighthouse(self, x, z):
        bx, by = self.px(x, z)
        s = self.f / z
        h = 18 * s
        def fn(d):
            for k in range(6):
                y1, y0 = by - k * h / 6, by - (k + 1) * h / 6
                w = 1.6 * s * (1 - 0.05 * k)
                d.rectangle([bx - w, y0, bx + w, y1], fill=self.c255((0.9, 0.9, 0.9) if k % 2 == 0 else (0.75, 0.1, 0.1)))
            d.rectangle([bx - 1.0 * s, by - h - 2 * s, bx + 1.0 * s, by - h], fill=self.c255((0.2, 0.2, 0.2)))
        self.draw(fn)

    def finish(self, grey=False, sigma=None, fmt="png"):
        r = self.rng
        img = np.clip(self.img, 0, 1)
        img = img + r.normal(0, r.uniform(0.005, 0.02) if sigma is None else sigma, img.shape)
        if grey:
            img = img.mean(-1, keepdims=True).repeat(3, -1)
        im = Image.fromarray((np.clip(img, 0, 1) * 255).astype(np.uint8))
        return im.filter(ImageFilter.GaussianBlur(r.uniform(0.0, 0.6)))


# ------------------------------------------------------------------------------------------- the scenes
def _trees(s, n, zr=(6, 18), xr=(-9, 9), conifer=None):
    pts = sorted(((s.rng.uniform(*xr), s.rng.uniform(*zr)) for _ in range(n)), key=lambda p: -p[1])
    for x, z in pts:
        s.tree(x, z, conifer)


def _rocks(s, n, zr=(3, 16), xr=(-6, 6), size=(0.2, 0.5)):
    pts = sorted(((s.rng.uniform(*xr), s.rng.uniform(*zr)) for _ in range(n)), key=lambda p: -p[1])
    for x, z in pts:
        s.rock(x, z, s.rng.uniform(*size))


INF = 1e9
SCENES: list[tuple[str, list[str], object]] = []


def scene(name, labels):
    def wrap(fn):
        SCENES.append((name, labels, fn))
        return fn
    return wrap


@scene("beach_waves", ["sand", "water", "flowing"])
def _(s):
    s.sky("blue"); s.ground([("sand", 0, INF, -INF, INF), ("sea", s.rng.uniform(7, 11), INF, -INF, INF)])

@scene("calm_lake", ["water"])
def _(s):
    s.sky("blue", 0.4); s.background("treeline"); s.ground([("grass", 0, INF, -INF, INF), ("water", s.rng.uniform(5, 8), INF, -INF, INF)])

@scene("river_crossing", ["water", "flowing"])
def _(s):
    z = s.rng.uniform(5, 8)
    s.sky("blue"); s.background("treeline"); s.ground([("grass", 0, INF, -INF, INF), ("river", z, z + s.rng.uniform(3, 5), -INF, INF)])

@scene("snowfield_overcast", ["snow"])
def _(s):
    s.sky("overcast", 0.0); s.background("mountains"); s.ground([("snow", 0, INF, -INF, INF)])

@scene("snowy_forest", ["snow", "tall"])
def _(s):
    s.sky(s.rng.choice(["blue", "overcast"])); s.ground([("snow", 0, INF, -INF, INF)]); _trees(s, 7, conifer=True)

@scene("forest_path", ["tall"])
def _(s):
    s.sky("blue"); s.ground([("grass", 0, INF, -INF, INF), ("dirt", 0, INF, -1.0, 1.0)]); _trees(s, 9, xr=(-10, 10))

@scene("city_street", ["tall"])
def _(s):
    s.sky("blue"); s.ground([("asphalt", 0, INF, -INF, INF)])
    for side in (-1, 1):
        s.side_wall(side * s.rng.uniform(5, 7), 4, 60, s.rng.uniform(8, 16), hsv(s.rng.uniform(0, 60), s.rng.uniform(0, 0.4), s.rng.uniform(0.4, 0.8)), True)

@scene("plaza_benches", ["tall"])
def _(s):
    s.sky(s.rng.choice(["blue", "overcast"])); s.ground([("tiles", 0, INF, -INF, INF)])
    for x, z in ((-3, 9), (3, 7), (0, 12)):
        s.box(x, z, 1.8, 0.5, hsv(30, 0.5, 0.35))
    s.post(-5, 8, 4); s.post(5, 10, 4)

@scene("stone_stairs", ["stairs"])
def _(s):
    s.sky("blue"); s.ground([("tiles", 0, INF, -INF, INF)])
    s.stairs(s.rng.uniform(3, 5), 10, -3, 3, 0.16, 0.32, hsv(35, 0.1, 0.7))

@scene("park_stairs", ["stairs", "tall"])
def _(s):
    s.sky("blue"); s.ground([("grass", 0, INF, -INF, INF)]); _trees(s, 4, zr=(10, 18), xr=(-10, -4)); _trees(s, 3, zr=(10, 18), xr=(4, 10))
    s.stairs(4, 8, -2, 2, 0.15, 0.35, hsv(0, 0.0, s.rng.uniform(0.5, 0.8)))

@scene("desert_dunes", ["sand", "slope"])
def _(s):
    s.sky("blue", 0.0); s.ground([("sand", 0, INF, -INF, INF)]); s.hill("sand", s.rng.uniform(0.15, 0.25))

@scene("grassy_hill", ["slope"])
def _(s):
    s.sky("blue"); s.ground([("grass", 0, INF, -INF, INF)]); s.hill("grass", s.rng.uniform(0.18, 0.3))

@scene("snowy_slope", ["snow", "slope"])
def _(s):
    s.sky("blue"); s.ground([("snow", 0, INF, -INF, INF)]); s.hill("snow", 0.1, tilt=s.rng.uniform(0.25, 0.4))

@scene("mud_field", ["mud"])
def _(s):
    s.sky("overcast"); s.background("treeline"); s.ground([("mud", 0, INF, -INF, INF)])

@scene("muddy_track_fence", ["mud", "tall"])
def _(s):
    s.sky("blue"); s.ground([("grass", 0, INF, -INF, INF), ("mud", 0, INF, -2.0, 2.0)])
    s.wall(s.rng.uniform(8, 12), -12, 12, 1.3, hsv(28, 0.5, 0.45), fence=True)

@scene("frozen_lake", ["ice"])
def _(s):
    s.sky("blue"); s.background(s.rng.choice(["mountains", "treeline"])); s.ground([("ice", 0, INF, -INF, INF)])

@scene("icy_road", ["ice"])
def _(s):
    s.sky("overcast"); s.ground([("asphalt", 0, INF, -INF, INF), ("ice", 0, INF, -4, 4)])

@scene("rocky_field", ["low"])
def _(s):
    s.sky("blue"); s.ground([("grass", 0, INF, -INF, INF)]); _rocks(s, 14)

@scene("rubble", ["low", "rough"])
def _(s):
    s.sky(s.rng.choice(["overcast", "blue"])); s.ground([("gravel", 0, INF, -INF, INF)]); _rocks(s, 20, size=(0.15, 0.35))

@scene("gravel_path", ["rough"])
def _(s):
    s.sky("blue"); s.ground([("dry_grass", 0, INF, -INF, INF), ("gravel", 0, INF, -2.5, 2.5)])

@scene("swamp", ["mud", "water"])
def _(s):
    s.sky("overcast"); s.background("treeline"); s.ground([("mud", 0, INF, -INF, INF)]); s.pond(-3, 9, 4, 3); s.pond(4, 14, 3, 3)

@scene("rapids", ["water", "flowing", "low"])
def _(s):
    s.sky("blue"); s.background("treeline"); s.ground([("grass", 0, INF, -INF, INF), ("river", 3, 16, -INF, INF)]); _rocks(s, 6, zr=(4, 14))

@scene("sunset_beach", ["sand", "water", "flowing"])
def _(s):
    s.sky("sunset"); s.ground([("sand", 0, INF, -INF, INF), ("sea", s.rng.uniform(6, 10), INF, -INF, INF)])

@scene("sunset_meadow", [])
def _(s):
    s.sky("sunset"); s.ground([("grass", 0, INF, -INF, INF)])

@scene("overcast_parking", ["tall"])
def _(s):
    s.sky("overcast", 0.0); s.ground([("asphalt", 0, INF, -INF, INF)]); s.box(-3, 9, 4.2, 1.5, hsv(s.rng.uniform(0, 360), 0.5, 0.5)); s.box(4, 12, 4.2, 1.5, hsv(0, 0, 0.8))

@scene("grey_plaza_buildings", ["tall"])
def _(s):
    s.sky("overcast", 0.1); s.ground([("tiles", 0, INF, -INF, INF)])
    s.box(-6, 16, 8, 12, hsv(0, 0, 0.55), True); s.box(5, 18, 9, 15, hsv(0, 0, 0.65), True)

@scene("lighthouse_coast", ["tall", "low", "water", "flowing", "rough"])
def _(s):
    s.sky("blue"); s.ground([("gravel", 0, INF, -INF, INF), ("sea", 7, INF, -INF, INF)]); s.lighthouse(6, 14); _rocks(s, 8, zr=(2, 6))

@scene("fountain_square", ["water", "tall"])
def _(s):
    s.sky("blue"); s.ground([("tiles", 0, INF, -INF, INF)]); s.fountain(0, 9, hsv(40, 0.15, 0.75))

@scene("park_pond", ["water", "tall"])
def _(s):
    s.sky("blue"); s.ground([("grass", 0, INF, -INF, INF)]); s.pond(0, 10, 6, 4); _trees(s, 4, zr=(14, 19))

@scene("brick_alley", ["tall"])
def _(s):
    s.sky("overcast"); s.ground([("tiles", 0, INF, -INF, INF)])
    for side in (-1, 1):
        s.side_wall(side * 2.5, 2, 40, 6, hsv(s.rng.uniform(5, 20), 0.6, 0.5))

@scene("construction_blocks", ["tall"])
def _(s):
    s.sky("blue"); s.ground([("dirt", 0, INF, -INF, INF)])
    for x, z in ((-4, 8), (2, 10), (5, 6)):
        s.box(x, z, 2.0, 1.0, hsv(0, 0, 0.7))

@scene("snowy_stairs", ["snow", "stairs"])
def _(s):
    s.sky("overcast"); s.ground([("snow", 0, INF, -INF, INF)])
    s.stairs(4, 9, -2.5, 2.5, 0.16, 0.33, hsv(0, 0, 0.45), cover=hsv(210, 0.05, 0.95))

@scene("canal_city", ["water", "tall"])
def _(s):
    s.sky("blue"); s.ground([("tiles", 0, INF, -INF, INF), ("water", 0, INF, -4, 4)])
    for side in (-1, 1):
        s.side_wall(side * 9, 6, 60, 12, hsv(s.rng.uniform(20, 50), 0.3, 0.7), True)

@scene("calm_sea_rocks", ["water", "low", "rough"])
def _(s):
    s.sky("blue", 0.2); s.ground([("gravel", 0, INF, -INF, INF), ("water", 6, INF, -INF, INF)]); _rocks(s, 8, zr=(2, 6))

@scene("mountain_trail", ["slope", "low", "rough"])
def _(s):
    s.sky("blue"); s.ground([("gravel", 0, INF, -INF, INF)]); s.hill("gravel", 0.1, tilt=0.3); _rocks(s, 6, zr=(3, 10))

@scene("glacier", ["ice", "snow"])
def _(s):
    s.sky("blue"); s.background("mountains"); s.ground([("snow", 0, INF, -INF, INF), ("ice", 0, 10, -INF, INF)])

@scene("forest_stream", ["water", "flowing", "tall"])
def _(s):
    s.sky("blue"); s.ground([("grass", 0, INF, -INF, INF), ("river", 5, 7.5, -INF, INF)]); _trees(s, 6, zr=(9, 18))

@scene("sand_rocks", ["sand", "low"])
def _(s):
    s.sky("blue"); s.ground([("sand", 0, INF, -INF, INF)]); _rocks(s, 12)

@scene("greyscale_beach", ["sand", "water", "flowing"])
def _(s):
    s.sky("blue"); s.ground([("sand", 0, INF, -INF, INF), ("sea", 8, INF, -INF, INF)]); s.grey = True

@scene("greyscale_street", ["tall"])
def _(s):
    s.sky("overcast"); s.ground([("asphalt", 0, INF, -INF, INF)]); s.grey = True
    for side in (-1, 1):
        s.side_wall(side * 6, 4, 60, 12, hsv(0, 0, 0.6), True)

@scene("dusk_lake", ["water"])
def _(s):
    s.sky("dusk"); s.background("treeline"); s.ground([("grass", 0, INF, -INF, INF), ("water", 5, INF, -INF, INF)])

@scene("white_snow_trees", ["snow", "tall"])
def _(s):
    s.sky("white", 0.0); s.ground([("snow", 0, INF, -INF, INF)]); _trees(s, 4, zr=(8, 16), conifer=True)

@scene("meadow", [])
def _(s):
    s.sky("blue"); s.background(s.rng.choice(["treeline", "mountains"])); s.ground([("grass", 0, INF, -INF, INF)])

@scene("beach_palms", ["sand", "water", "tall"])
def _(s):
    s.sky("blue"); s.ground([("sand", 0, INF, -INF, INF), ("water", 9, INF, -INF, INF)]); _trees(s, 3, zr=(5, 8), xr=(-8, -3))

@scene("grey_concrete_stairs", ["stairs"])
def _(s):
    s.sky("overcast"); s.ground([("asphalt", 0, INF, -INF, INF)]); s.stairs(3.5, 12, -4, 4, 0.15, 0.3, hsv(0, 0, 0.6))

@scene("forest_hill", ["slope", "tall"])
def _(s):
    s.sky("blue"); s.ground([("grass", 0, INF, -INF, INF)]); s.hill("grass", 0.22); _trees(s, 5, zr=(8, 16))

@scene("sunset_river", ["water", "flowing"])
def _(s):
    z = s.rng.uniform(4, 7)
    s.sky("sunset"); s.background("treeline"); s.ground([("dry_grass", 0, INF, -INF, INF), ("river", z, z + 4, -INF, INF)])

@scene("overcast_asphalt", [])
def _(s):
    s.sky("overcast", 0.2); s.ground([("asphalt", 0, INF, -INF, INF)])


def main() -> None:
    ROOT.mkdir(parents=True, exist_ok=True)
    for old in list(ROOT.glob("*.png")) + list(ROOT.glob("*.jpg")):
        old.unlink()
    items = []
    for i, (name, labels, fn) in enumerate(SCENES):
        s = Scene(1000 + i)
        s.grey = False
        fn(s)
        im = s.finish(grey=s.grey)
        fmt = "jpg" if i % 3 == 2 else "png"
        path = ROOT / f"{i:02d}_{name}.{fmt}"
        im.save(path, quality=88) if fmt == "jpg" else im.save(path, optimize=True)
        items.append({"file": path.name, "labels": labels})
    (ROOT / "manifest.json").write_text(json.dumps({
        "about": "Rendered perspective scenes (render.py) with hand labels; see texts.json for the label meanings. "
                 "Odd items tune the rules, even items are held out.",
        "items": items}, indent=1) + "\n")
    print(f"wrote {len(items)} pictures to {ROOT}")


if __name__ == "__main__":
    main()
