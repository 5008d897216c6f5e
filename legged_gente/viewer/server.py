"""The web viewer: pushes :mod:`.scene` data and rollouts to a viser server, with GUI controls.

A :class:`Viewer` shows one of several terrain items (a spec, a task's grid, the items of a benchmark) and,
optionally, a rollout: the robots drawn from their MJCF geoms at each step, the force arrows, a time slider,
play/pause, and the commanded vs actual velocity of robot 0 with resets and falls marked.
"""

from __future__ import annotations

import dataclasses
import socket
import threading
from typing import Callable

import numpy as np

from legged_gente.viewer.rollout import FORCE_COLOURS, FORCE_KINDS, Kinematics, robot_geoms
from legged_gente.viewer.scene import COLOUR_MODES, Arrows, Label, Lines, Mesh, Points, Scene, terrain_scene

WHOLE = "whole terrain"
FORCE_SCALE = 0.01
"""m of arrow per N of force (100 N: 1 m)."""


@dataclasses.dataclass
class TerrainItem:
    """One terrain the viewer can show: a label, a builder (called once, on first view) and an xy offset (m)."""

    label: str
    build: Callable[[], object]
    offset: tuple[float, float] = (0.0, 0.0)


def gltf_vertex_colours(srgb: np.ndarray) -> np.ndarray:
    """sRGB colours (uint8) as the linear values a glTF COLOR_0 attribute holds (glTF 2.0, 3.7.2.1: vertex
    colours are linear; the browser encodes them back to sRGB on screen, so sRGB sent as is looks pale).
    sRGB decoding of IEC 61966-2-1: c / 12.92 up to 0.04045, else ((c + 0.055) / 1.055) ** 2.4."""
    c = np.asarray(srgb, np.float64) / 255.0
    linear = np.where(c <= 0.04045, c / 12.92, ((c + 0.055) / 1.055) ** 2.4)
    return np.round(255.0 * linear).astype(np.uint8)


def push_scene(server, scene: Scene) -> dict[str, object]:
    """Add every node of ``scene`` to the viser ``server``; returns the handles by name."""
    import trimesh

    handles = {}
    for name, node in scene.nodes.items():
        if isinstance(node, Mesh) and node.vertex_colors is not None:
            mesh = trimesh.Trimesh(node.vertices, node.faces, vertex_colors=gltf_vertex_colours(node.vertex_colors),
                                   process=False)
            handles[name] = server.scene.add_mesh_trimesh(name, mesh, cast_shadow=False)
        elif isinstance(node, Mesh):
            handles[name] = server.scene.add_mesh_simple(name, node.vertices, node.faces, color=node.color,
                                                         opacity=node.opacity, side="double", cast_shadow=False,
                                                         receive_shadow=False)
        elif isinstance(node, Arrows):
            handles[name] = server.scene.add_arrows(name, node.points, node.color, shaft_radius=0.008,
                                                    head_radius=0.025, head_length=0.06)
        elif isinstance(node, Lines):
            handles[name] = server.scene.add_line_segments(name, node.points, node.color, thickness=2.0,
                                                            thickness_units="screen")
        elif isinstance(node, Label):
            handles[name] = server.scene.add_label(name, node.text, position=node.position, anchor="bottom-center")
        elif isinstance(node, Points):
            handles[name] = server.scene.add_point_cloud(name, node.positions, node.color, point_size=node.size,
                                                         point_shape="circle")
    return handles


def legend_html(legend: list[tuple[str, tuple[int, int, int]]]) -> str:
    rows = "".join(
        f'<div style="display:flex;align-items:center;gap:6px;font-size:12px">'
        f'<span style="display:inline-block;width:14px;height:14px;background:rgb{tuple(c)};'
        f'border:1px solid #555"></span>{label}</div>'
        for label, c in legend
    )
    return f'<div style="padding:4px 0">{rows}</div>'


def check_address(host: str, port: int) -> None:
    """A one-line error for an address the server cannot listen on: viser's server thread would fail there and
    leave its constructor waiting forever. (A port in use is fine: viser moves to the next free one.)"""
    if not 0 <= port <= 65535:
        raise ValueError(f"port {port} must be in 0..65535.")
    try:
        family = socket.getaddrinfo(host, None)[0][0]
        with socket.socket(family) as probe:
            probe.bind((host, 0))
    except OSError as error:  # socket.gaierror too
        raise ValueError(f"cannot serve on host {host!r} ({error.strerror or error}); use 127.0.0.1 (this machine) "
                         f"or 0.0.0.0 (every interface).") from None


def point_cameras(server, look_at, position) -> None:
    """Put the initial camera and every connected browser's at ``position`` (m), looking at ``look_at``. A browser
    camera's position setter carries its look-at point along (viser keeps the view direction), so the position
    is set first and the look-at point after it."""
    look_at, position = tuple(float(v) for v in look_at), tuple(float(v) for v in position)
    server.initial_camera.look_at, server.initial_camera.position = look_at, position
    for client in server.get_clients().values():
        client.camera.position = position
        client.camera.look_at = look_at


class Viewer:
    """A viser server showing ``items`` (terrains) and, after :meth:`attach_rollout`, a rollout."""

    def __init__(self, items: list[TerrainItem], host: str = "127.0.0.1", port: int = 8080, shadows: bool = True):
        import viser

        if not items:
            raise ValueError("nothing to show: give a spec.json, a terrain_cfg.py, a task or a benchmark folder.")
        self.items = {item.label: item for item in items}
        if len(self.items) != len(items):
            raise ValueError("terrain items need distinct labels.")
        self._built: dict[str, object] = {}
        check_address(host, port)
        self.terrain(items[0].label)  # its errors (a bad spec or terrain module) before the server starts
        self.server = viser.ViserServer(host=host, port=port, label="legged_gente", verbose=False)
        self.server.scene.set_up_direction("+z")
        self.server.scene.configure_default_lights(enabled=True, cast_shadow=shadows)
        self.lock = threading.Lock()
        self.scene: Scene | None = None
        self.handles: dict[str, object] = {}
        gui = self.server.gui
        with gui.add_folder("Terrain"):
            self.item_gui = gui.add_dropdown("terrain", list(self.items), initial_value=items[0].label,
                                             visible=len(items) > 1)
            self.tile_gui = gui.add_dropdown("tile", [WHOLE], initial_value=WHOLE)
            self.colour_gui = gui.add_dropdown("colours", COLOUR_MODES, initial_value=COLOUR_MODES[0],
                                               hint="materials: soil, ice, ground; heights: elevation colormap")
            self.water_gui = gui.add_checkbox("water surface", True)
            self.flow_gui = gui.add_checkbox("flow arrows", True)
            self.tiles_gui = gui.add_checkbox("tile outlines, labels, spawns", True)
            self.info_gui = gui.add_markdown("")
            self.legend_gui = gui.add_html("")
        self._selecting = False
        self.item_gui.on_update(lambda _: self._select_item())
        self.tile_gui.on_update(lambda _: None if self._selecting else self.show())
        self.colour_gui.on_update(lambda _: self.show(move_camera=False))
        for box in (self.water_gui, self.flow_gui, self.tiles_gui):
            box.on_update(lambda _: self._apply_visibility())
        self.player: RolloutPlayer | None = None
        self._select_item()

    # ------------------------------------------------------------------------------------------- terrain
    @property
    def url(self) -> str:
        return f"http://{self.server.get_host()}:{self.server.get_port()}"

    def terrain(self, label: str | None = None):
        label = label or self.item_gui.value
        if label not in self._built:
            self._built[label] = self.items[label].build()
        return self._built[label]

    def _select_item(self) -> None:
        t = self.terrain()
        tiles = [WHOLE]
        if getattr(t, "mode", "bare") not in ("plane", "bare"):
            tiles += [f"({r}, {c}) {t.tile_names[r, c]}" for r in range(t.num_rows) for c in range(t.num_cols)]
        self._selecting = True
        try:
            self.tile_gui.options = tiles
            self.tile_gui.value = WHOLE
        finally:
            self._selecting = False
        self.show()

    def build_scene(self) -> Scene:
        """The scene the GUI's current choices ask for (plain data, see :mod:`.scene`)."""
        tile = None
        if self.tile_gui.value != WHOLE:
            r, c = self.tile_gui.value[1:].split(")")[0].split(",")
            tile = (int(r), int(c))
        item = self.items[self.item_gui.value]
        return terrain_scene(self.terrain(), self.colour_gui.value, tile, item.offset)

    def show(self, move_camera: bool = True) -> None:
        """Draw the chosen terrain; ``move_camera``: also point the cameras at its overview (a new terrain or
        tile; new colours of the same ground keep the view)."""
        with self.lock:
            scene = self.build_scene()
            for handle in self.handles.values():
                handle.remove()
            self.scene, self.handles = scene, push_scene(self.server, scene)
            lo, hi = scene.bounds
            t = self.terrain()
            self.info_gui.content = (f"**{self.item_gui.value}**: {hi[0] - lo[0]:.1f} m x {hi[1] - lo[1]:.1f} m, "
                                     f"cells of {t.resolution:g} m, heights {lo[2]:+.2f} to {hi[2]:+.2f} m")
            self.legend_gui.content = legend_html(scene.legend)
            if move_camera:
                centre, extent = (lo + hi) / 2, float(max(hi[0] - lo[0], hi[1] - lo[1]))
                point_cameras(self.server, centre, (centre[0] - 0.15 * extent, centre[1] - 0.75 * extent,
                                                    hi[2] + 0.45 * extent))
        self._apply_visibility()

    def _apply_visibility(self) -> None:
        for name, handle in self.handles.items():
            if name.endswith("/water"):
                handle.visible = self.water_gui.value
            elif name.endswith("/flow"):
                handle.visible = self.flow_gui.value
            elif "/tiles/" in name:
                handle.visible = self.tiles_gui.value

    # ------------------------------------------------------------------------------------------- rollout
    def attach_rollout(self, source, mjm, play: bool = True) -> "RolloutPlayer":
        """Show ``source`` (a :class:`~.rollout.Rollout`, or a :class:`~.rollout.Recorder` that is filling)."""
        self.player = RolloutPlayer(self.server, source, mjm, play)
        return self.player

    def stop(self) -> None:
        if self.player is not None:
            self.player.stop()
        self.server.stop()


def _frames(source) -> dict:
    """The arrays of ``source`` up to now: a Rollout's, or a live Recorder's complete steps (its ``add`` appends
    one key after another while the player reads them)."""
    if hasattr(source, "frames"):
        n = min(len(v) for v in source.frames.values())
        return {k: v[:n] for k, v in source.frames.items()} | {"labels": source.labels}
    return {"qpos": source.qpos, "cmd": source.cmd, "vel": source.vel, "done": source.done, "fell": source.fell,
            "forces": source.forces, "force_points": source.force_points, "labels": source.force_labels}


class RolloutPlayer:
    """Robots from their MJCF geoms, force arrows, a step slider, play/pause and the velocity plot."""

    def __init__(self, server, source, mjm, play: bool = True):

        self.server, self.source = server, source
        self.dt = float(getattr(source, "dt", None) or source.env.dt)
        self.kin = Kinematics(mjm)
        self.base = int(mjm.jnt_bodyid[0])  # the floating base: the body the camera follows
        self.shapes = robot_geoms(mjm)
        frames = _frames(source)
        self.num_robots = frames["qpos"][0].shape[0] if len(frames["qpos"]) else len(source.robots)
        self.bodies: dict[tuple[int, int], object] = {}
        self.force_handles: dict[str, object] = {}
        for r in range(self.num_robots):
            for body in sorted({s.body for s in self.shapes}):
                self.bodies[r, body] = server.scene.add_frame(f"/robots/{r}/body_{body}", show_axes=False)
            for k, s in enumerate(self.shapes):
                server.scene.add_mesh_simple(f"/robots/{r}/body_{s.body}/geom_{k}", s.vertices, s.faces, color=s.color,
                                             cast_shadow=True)
        gui = server.gui
        with gui.add_folder("Rollout"):
            self.step_gui = gui.add_slider("step", 0, max(len(frames["qpos"]) - 1, 1), 1, 0)
            self.play_gui = gui.add_checkbox("play", play)
            self.follow_gui = gui.add_checkbox("camera follows robot 0", False)
            self.forces_gui = gui.add_checkbox("force arrows", True)
            self.time_gui = gui.add_markdown("")
            gui.add_html(legend_html([(f"{k} force (1 m = {1 / FORCE_SCALE:g} N)", FORCE_COLOURS[k])
                                      for k in FORCE_KINDS]))
            self.plot_gui = None
        for control in (self.step_gui, self.follow_gui, self.forces_gui):  # also while paused
            control.on_update(lambda _: self.draw(int(self.step_gui.value)))
        self._draw_lock = threading.Lock()  # the GUI's callbacks and the play loop both draw
        self._stop = threading.Event()
        self.thread = threading.Thread(target=self._loop, daemon=True)
        self.thread.start()

    def _loop(self) -> None:
        shown_len = -1
        while not self._stop.is_set():
            n = len(_frames(self.source)["qpos"])
            if n != shown_len and n > 0:
                self.step_gui.max = max(n - 1, 1)
                self._plot()
                paused = int(self.step_gui.value)
                if not self.play_gui.value and shown_len <= paused < n:  # opened at a step not recorded until now
                    self.draw(paused)
                    self.focus(paused)
                shown_len = n
            if self.play_gui.value and n > 0:
                self.step_gui.value = (int(self.step_gui.value) + 1) % n if not hasattr(self.source, "frames") \
                    else n - 1
            self._stop.wait(self.dt)

    def focus(self, t: int, distance: float = 2.5) -> None:
        """Point the camera (initial and connected clients') at robot 0's base at step ``t``."""
        f = _frames(self.source)
        if not len(f["qpos"]):
            return  # a live recording without steps yet: the play loop focuses once the step is recorded
        base = np.asarray(f["qpos"][min(t, len(f["qpos"]) - 1)][0][:3], np.float64)
        point_cameras(self.server, base, base + distance * np.array([-0.6, -0.75, 0.45]))

    def stop(self) -> None:
        self._stop.set()
        self.thread.join(timeout=2.0)

    def draw(self, t: int) -> None:
        with self._draw_lock:
            self._draw(t)

    def _draw(self, t: int) -> None:
        f = _frames(self.source)
        if not len(f["qpos"]):
            return
        t = min(max(t, 0), len(f["qpos"]) - 1)
        with self.server.atomic():
            for r in range(self.num_robots):
                d = self.kin(np.asarray(f["qpos"][t][r], np.float64))
                for (rr, body), handle in self.bodies.items():
                    if rr == r:
                        handle.position = d.xpos[body]
                        handle.wxyz = d.xquat[body]
                if r == 0 and self.follow_gui.value:  # keep each browser's view, moved along with the base
                    base = d.xpos[self.base]
                    for client in self.server.get_clients().values():
                        client.camera.position = client.camera.position + (base - client.camera.look_at)
                        client.camera.look_at = base  # (the position setter carried it there already)
            labels = f["labels"]
            for kind in FORCE_KINDS:
                cols = [k for k, label in enumerate(labels) if label.split(":")[0] == kind]
                name = f"/forces/{kind}"
                if not cols or not self.forces_gui.value:
                    self.force_handles[kind] = self.server.scene.add_arrows(
                        name, np.zeros((0, 2, 3), np.float32), FORCE_COLOURS[kind], visible=False)
                    continue
                force = np.asarray(f["forces"][t])[:, cols].reshape(-1, 3)
                point = np.asarray(f["force_points"][t])[:, cols].reshape(-1, 3)
                keep = np.linalg.norm(force, axis=1) > 1.0  # N: below it, no arrow
                arrows = np.stack([point[keep], point[keep] + FORCE_SCALE * force[keep]], 1).astype(np.float32)
                self.force_handles[kind] = self.server.scene.add_arrows(
                    name, arrows, FORCE_COLOURS[kind], shaft_radius=0.012, head_radius=0.03, head_length=0.05)
        falls = int(np.asarray(f["fell"])[: t + 1, 0].sum())
        resets = int(np.asarray(f["done"])[: t + 1, 0].sum())
        # row t is the state after policy step t + 1 (recorded after each env.step): reached at (t + 1) dt
        self.time_gui.content = (f"t = {(t + 1) * self.dt:.2f} s of {len(f['qpos']) * self.dt:.2f} s; robot 0: "
                                 f"{resets} resets, {falls} falls so far")

    def _plot(self) -> None:
        """Commanded vs actual vx and vy of robot 0; resets and falls as spikes on their own axis."""
        import viser.uplot as uplot

        f = _frames(self.source)
        cmd, vel = np.asarray(f["cmd"])[:, 0], np.asarray(f["vel"])[:, 0]
        t = (np.arange(len(cmd)) + 1) * self.dt  # row k: after policy step k + 1
        data = (t, cmd[:, 0], vel[:, 0], cmd[:, 1], vel[:, 1],
                np.asarray(f["done"])[:, 0].astype(float), np.asarray(f["fell"])[:, 0].astype(float))
        series = (uplot.Series(label="t (s)"),
                  uplot.Series(label="vx cmd", stroke="black", dash=[6, 4], width=1.5),
                  uplot.Series(label="vx", stroke="#1f77b4", width=1.5),
                  uplot.Series(label="vy cmd", stroke="gray", dash=[6, 4], width=1.0),
                  uplot.Series(label="vy", stroke="#2ca02c", width=1.0),
                  uplot.Series(label="reset", stroke="#9467bd", scale="event", width=1.0),
                  uplot.Series(label="fall", stroke="#d62728", scale="event", width=2.0))
        scales = {"event": uplot.Scale(range=(0.0, 1.0))}
        axes = (uplot.Axis(), uplot.Axis(label="m/s"), uplot.Axis(scale="event", side=1, show=False))
        if self.plot_gui is None:
            with self.server.gui.add_folder("Velocity (robot 0)"):
                self.plot_gui = self.server.gui.add_uplot(data, series, scales=scales, axes=axes, aspect=1.6)
        else:
            self.plot_gui.data = data
