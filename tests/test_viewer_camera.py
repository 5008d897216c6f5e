"""gente-view's camera as a connected browser sees it: a websocket client that speaks viser's protocol reports its
camera, and the viewer moves it (focus on robot 0, follow robot 0, the overview of a terrain)."""

from __future__ import annotations

import socket
import threading
import time

import msgspec
import numpy as np
import pytest
import viser
from websockets.exceptions import ConnectionClosed
from websockets.sync.client import connect

from legged_gente.terrain.materials import MaterialMap
from legged_gente.viewer.rollout import Rollout, robot_model
from legged_gente.viewer.scene import BareTerrain
from legged_gente.viewer.server import TerrainItem, Viewer

LOOK_AT = np.array([0.0, 0.0, 0.5])
POSITION = np.array([-3.0, -4.0, 2.5])  # the browser's camera as it connects


def free_port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


class Browser:
    """A viser client without a browser: it reports one camera pose and reads (and drops) what the server sends."""

    def __init__(self, viewer: Viewer):
        self.viewer = viewer
        self.ws = connect(f"ws://127.0.0.1:{viewer.server.get_port()}",
                          subprotocols=[f"viser-v{viser.__version__}"], max_size=None)
        self.reader = threading.Thread(target=self._drain, daemon=True)
        self.reader.start()
        self.ws.send(msgspec.msgpack.encode({
            "type": "ViewerCameraMessage", "wxyz": [1.0, 0.0, 0.0, 0.0], "position": POSITION.tolist(), "fov": 1.0,
            "near": 0.01, "far": 1000.0, "image_height": 480, "image_width": 640, "look_at": LOOK_AT.tolist(),
            "up_direction": [0.0, 0.0, 1.0]}))
        for _ in range(500):
            if viewer.server.get_clients():
                break
            time.sleep(0.02)
        (self.client,) = viewer.server.get_clients().values()

    def _drain(self) -> None:
        try:
            while True:
                self.ws.recv()
        except ConnectionClosed:
            pass

    @property
    def camera(self) -> tuple[np.ndarray, np.ndarray]:
        return np.array(self.client.camera.look_at), np.array(self.client.camera.position)

    def close(self) -> None:
        self.ws.close()
        self.reader.join(timeout=5)


@pytest.fixture
def walking():
    """A viewer of a plane, a browser connected to it, and a rollout of robot 0 walking 1 m along x per step."""
    plane = BareTerrain(np.zeros((2, 2), np.float32), MaterialMap.rigid((2, 2)), 20.0, (-10.0, -10.0))
    viewer = Viewer([TerrainItem("plane", lambda: plane)], port=free_port(), shadows=False)
    browser = None
    mjm = robot_model("gente_biped_flat")
    steps = 4
    qpos = np.tile(mjm.qpos0, (steps, 1, 1))
    qpos[:, 0, 0] = np.arange(steps)
    rollout = Rollout("gente_biped_flat", 0.02, qpos, np.zeros((steps, 1, 3)), np.zeros((steps, 1, 3)),
                      np.zeros((steps, 1), bool), np.zeros((steps, 1), bool), [], np.zeros((steps, 1, 0, 3)),
                      np.zeros((steps, 1, 0, 3)), plane.height_field, plane.origin_xy, plane.resolution, plane.material)
    try:
        browser = Browser(viewer)
        player = viewer.attach_rollout(rollout, mjm, play=False)
        for _ in range(500):  # opened paused: the player's loop draws step 0 and focuses on it once
            if np.allclose(browser.camera[0], (0.0, 0.0, mjm.qpos0[2])):
                break
            time.sleep(0.02)
        yield viewer, browser, player, mjm
    finally:
        if browser is not None:
            browser.close()
        viewer.stop()


def test_the_camera_follows_robot_0_without_jumping(walking):
    """Following keeps the browser's view (where the camera is from the point it looks at) and moves that point
    with the base. viser's position setter carries the look-at point along: setting both shifted it twice, and
    the camera jumped between two points every step."""
    viewer, browser, player, mjm = walking
    base = int(mjm.jnt_bodyid[0])
    player.focus(0, distance=2.5)
    view = 2.5 * np.array([-0.6, -0.75, 0.45])  # where the camera is, from the point it looks at
    player.follow_gui.value = True
    for t in (1, 2, 3, 2):
        player.draw(t)
        look_at, position = browser.camera
        np.testing.assert_allclose(look_at, (t, 0.0, mjm.qpos0[2]), atol=1e-9)  # robot 0's base at step t
        np.testing.assert_allclose(look_at, player.bodies[0, base].position, atol=1e-9)
        np.testing.assert_allclose(position - look_at, view, atol=1e-9)


def test_focus_points_the_browser_at_robot_0(walking):
    viewer, browser, player, mjm = walking
    player.focus(2, distance=2.5)
    look_at, position = browser.camera
    base = np.array([2.0, 0.0, mjm.qpos0[2]])  # robot 0's base at step 2
    np.testing.assert_allclose(look_at, base, atol=1e-9)
    np.testing.assert_allclose(position, base + 2.5 * np.array([-0.6, -0.75, 0.45]), atol=1e-9)
    np.testing.assert_allclose(viewer.server.initial_camera.look_at, base, atol=1e-9)


def test_the_overview_moves_the_browser_and_new_colours_do_not(walking):
    viewer, browser, player, mjm = walking
    viewer.show()  # the terrain's overview: look at its centre, from the initial camera's position
    look_at, position = browser.camera
    np.testing.assert_allclose(look_at, viewer.server.initial_camera.look_at, atol=1e-6)
    np.testing.assert_allclose(position, viewer.server.initial_camera.position, atol=1e-6)
    player.focus(3)
    before = browser.camera
    viewer.colour_gui.value = "heights"  # the same ground in other colours: the view stays
    np.testing.assert_allclose(browser.camera, before, atol=1e-9)


def test_following_starts_when_ticked_while_paused(walking):
    """Ticking "camera follows robot 0" on a paused rollout moved nothing until the slider was moved."""
    viewer, browser, player, mjm = walking
    player.step_gui.value = 2
    viewer.show()  # the browser back on the terrain's overview
    player.follow_gui.value = True
    np.testing.assert_allclose(browser.camera[0], (2.0, 0.0, mjm.qpos0[2]), atol=1e-9)
