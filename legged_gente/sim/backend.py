"""Thin MuJoCo-Warp backend: device model/data, zero-copy torch views, a captured substep loop.

All worlds share one compiled model (robot + terrain); per-world model fields that domain randomisation
touches are batched with ``put_model(batch_sizes=...)``. With ``cuda_graph = "physics"`` on a CUDA device the
``decimation`` substeps (and any force kernels installed as mujoco_warp callbacks) are captured once into a
CUDA graph and replayed each policy step; otherwise they are plain launches on Warp's current stream (the
env records them into its own graph of the whole step with ``cuda_graph = "env_step"``).
"""

from __future__ import annotations

import contextlib
from typing import Callable, Iterator

import mujoco
import mujoco_warp as mjw
import torch
import warp as wp
from mujoco_warp._src.support import contact_force_fn

# per-world model fields: what domain randomisation writes (friction, base mass and inertia) and what
# ``mjw.set_const`` derives from the masses (subtree masses, the inverse weights the solver regularises with)
BATCHED_FIELDS = ("geom_friction", "body_mass", "body_inertia", "body_subtreemass", "body_invweight0",
                  "dof_invweight0", "actuator_acc0")


@wp.kernel
def _body_contact_forces(
    opt_cone: int,
    geom_bodyid: wp.array[int],
    contact_frame: wp.array[wp.mat33],
    contact_friction: wp.array[wp.types.vector(length=5, dtype=float)],
    contact_dim: wp.array[int],
    contact_efc_address: wp.array2d[int],
    contact_worldid: wp.array[int],
    contact_adhesion: wp.array[float],
    contact_geom: wp.array[wp.vec2i],
    efc_force: wp.array2d[float],
    njmax: int,
    nacon: wp.array[int],
    body_force: wp.array2d[wp.vec3],
):
    """World-frame contact force on each body: +f on geom[1]'s body, -f on geom[0]'s (normal points 0 -> 1)."""
    cid = wp.tid()
    if cid >= nacon[0]:
        return
    world = contact_worldid[cid]
    f6 = contact_force_fn(opt_cone, contact_frame, contact_friction, contact_dim, contact_efc_address,
                          contact_adhesion, efc_force, njmax, nacon, world, cid, True)
    f = wp.spatial_top(f6)
    geoms = contact_geom[cid]
    wp.atomic_add(body_force, world, geom_bodyid[geoms[1]], f)
    wp.atomic_sub(body_force, world, geom_bodyid[geoms[0]], f)


class Simulation:
    """``nworld`` copies of one MjModel on a Warp device, stepped ``decimation`` substeps at a time."""

    def __init__(self, mjm: mujoco.MjModel, num_worlds: int, device: str, sim_cfg, batch_model: bool = True):
        self.mjm = mjm
        self.num_worlds = num_worlds
        self.device = device
        self.wp_device = wp.get_device("cpu" if device == "cpu" else device)
        self.use_graph = sim_cfg.cuda_graph == "physics" and self.wp_device.is_cuda
        with wp.ScopedDevice(self.wp_device):
            batch = {name: num_worlds for name in BATCHED_FIELDS} if batch_model else {}
            self.m = mjw.put_model(mjm, batch_sizes=batch)
            # hitting the iteration cap in a few worlds is acceptable in RL; don't print it every substep
            self.m.opt.warn_overflow &= ~(mjw.OverflowType.ITERATIONS | mjw.OverflowType.LS_ITERATIONS)
            self.d = mjw.make_data(mjm, nworld=num_worlds, nconmax=sim_cfg.nconmax, njmax=sim_cfg.njmax)
            self.body_contact_force_wp = wp.zeros((num_worlds, mjm.nbody), dtype=wp.vec3)
        self.after_substep: list[Callable[[], None]] = []
        self.after_reset: list[Callable[[torch.Tensor], None]] = []  # called with the reset mask (torch bool)
        self._graph = None
        self._make_views()
        # what :meth:`forward` refreshes for the worlds it is given (each (num_worlds, ...)), and what the
        # callbacks and after_substep hooks integrate from one substep to the next, which it leaves as it was
        self.observed: list[torch.Tensor] = [self.body_contact_force]
        self.substep_state: list[torch.Tensor] = []

    def _make_views(self) -> None:
        t = wp.to_torch
        d, m = self.d, self.m
        self.qpos, self.qvel, self.ctrl = t(d.qpos), t(d.qvel), t(d.ctrl)
        self.xpos, self.xquat, self.cvel, self.geom_xpos = t(d.xpos), t(d.xquat), t(d.cvel), t(d.geom_xpos)
        self.subtree_com, self.actuator_force = t(d.subtree_com), t(d.actuator_force)
        self.nefc, self.time = t(d.nefc), t(d.time)
        self.body_contact_force = t(self.body_contact_force_wp)
        self.geom_friction = t(m.geom_friction)
        self.body_mass, self.body_inertia = t(m.body_mass), t(m.body_inertia)

    # ---- stepping -------------------------------------------------------------------------------------
    def _substeps(self, decimation: int) -> None:
        for _ in range(decimation):
            mjw.step(self.m, self.d)
            for hook in self.after_substep:
                hook()
        self._contact_forces()

    def _contact_forces(self) -> None:
        """Per-body contact forces (``body_contact_force``) from the contacts and constraint forces now in ``d``."""
        out = self.body_contact_force_wp
        out.zero_()
        wp.launch(_body_contact_forces, dim=self.d.naconmax, inputs=[
            self.m.opt.cone, self.m.geom_bodyid, self.d.contact.frame, self.d.contact.friction,
            self.d.contact.dim, self.d.contact.efc_address, self.d.contact.worldid, self.d.contact.adhesion,
            self.d.contact.geom, self.d.efc.force, self.d.njmax, self.d.nacon], outputs=[out])

    def step(self, decimation: int) -> None:
        """Advance all worlds by ``decimation`` substeps; contact forces per body are refreshed at the end."""
        with wp.ScopedDevice(self.wp_device):
            if not self.use_graph:
                self._substeps(decimation)  # on Warp's current stream (the env's step graph sets it to torch's)
                return
            torch_stream = wp.stream_from_torch(torch.cuda.current_stream(self.device))
            if self._graph is None:
                self._sim_stream = wp.Stream(self.wp_device)
                self._sim_stream.wait_stream(torch_stream)
                with wp.ScopedStream(self._sim_stream):
                    self._substeps(decimation)  # this step, run eagerly: loads every kernel module before capture
                    with wp.ScopedCapture() as capture:  # records the substeps without running them
                        self._substeps(decimation)
                self._graph = capture.graph
                self._graph_decimation = decimation
                wp.synchronize_device(self.wp_device)
                torch_stream.wait_stream(self._sim_stream)
                return  # launching the graph now would advance this first step by 2 x decimation substeps
            if decimation != self._graph_decimation:
                raise ValueError(f"the captured graph runs {self._graph_decimation} substeps, not {decimation}")
            self._sim_stream.wait_stream(torch_stream)
            wp.capture_launch(self._graph, stream=self._sim_stream)
            torch_stream.wait_stream(self._sim_stream)

    # Warp launches: torch.compile leaves these methods to run as they are (graph breaks around them)
    @torch.compiler.disable
    def reset_worlds(self, mask: torch.Tensor) -> None:
        """Restore the masked worlds' Data to the model defaults: qpos0, zero velocities, time, controls, solver
        warm start, applied forces, contacts (``mjw.reset_data``); then the ``after_reset`` hooks. Skipped on
        the CPU when no world is masked (see ``forward``)."""
        if not self.wp_device.is_cuda and not bool(mask.any()):
            return
        with wp.ScopedDevice(self.wp_device):
            mjw.reset_data(self.m, self.d, reset=wp.from_torch(mask.contiguous(), dtype=wp.bool))
        for hook in self.after_reset:
            hook(mask)

    @torch.compiler.disable
    def forward(self, mask: torch.Tensor) -> None:
        """Recompute what derives from qpos/qvel/ctrl without advancing time, as a substep sees it: bodies,
        contacts (the force fields' contact filter included: ground friction, soil, analytic sole contacts),
        passive forces, constraint forces; then the ``after_substep`` hooks (the force fields' observation) and
        the per-body contact forces. The worlds in ``mask`` take the new values of every ``observed`` tensor; the
        others keep their last substep's.

        Physics-neutral: ``mjw.forward`` leaves the solver's warm start alone, and everything in
        ``substep_state`` (what the callbacks and hooks integrate once per substep, e.g. soil ruts, slip) is put
        back as it was, in every world. It costs about a third of a policy step's physics (4 substeps); on the
        CPU it is skipped when no world is masked (a host read, free there; on a GPU it always runs, as the step
        must not wait for the device)."""
        if not self.wp_device.is_cuda and not bool(mask.any()):
            return
        last = [t.clone() for t in self.observed]
        with self.substep_state_kept():
            self.recompute()
        for t, old in zip(self.observed, last):
            t.copy_(torch.where(mask.view(-1, *[1] * (t.dim() - 1)), t, old))

    @contextlib.contextmanager
    def substep_state_kept(self) -> Iterator[None]:
        """Everything in ``substep_state`` put back, in every world, when the block ends (however it ends)."""
        kept = [t.clone() for t in self.substep_state]
        try:
            yield
        finally:
            for t, old in zip(self.substep_state, kept):
                t.copy_(old)

    def recompute(self) -> None:
        """The Warp work of :meth:`forward`, in every world: MuJoCo's forward (with the force fields' callbacks),
        the ``after_substep`` hooks and the per-body contact forces. Unlike ``forward`` it keeps every new value
        and leaves ``substep_state`` advanced."""
        with wp.ScopedDevice(self.wp_device):
            mjw.forward(self.m, self.d)
            for hook in self.after_substep:
                hook()
            self._contact_forces()

    @torch.compiler.disable
    def set_const(self) -> None:
        """Derived model constants (subtree masses, inverse weights) after body masses or inertias changed."""
        with wp.ScopedDevice(self.wp_device):
            mjw.set_const(self.m, self.d)
