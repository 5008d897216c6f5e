"""Thin MuJoCo-Warp backend: device model/data, zero-copy torch views, a captured substep loop.

A substep is MuJoCo-Warp's step in its two halves: the position and velocity stage (bodies, contacts,
constraint rows, passive forces; what the controls do not enter), then actuation, the constraint solver and the
integration. The forward that follows a policy step's resets computes the next substep's first half, so that
substep reuses it instead of computing it again.

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

# the integrators the two-stage substep is written for (``mjw.step`` runs ``implicit`` for implicitfast)
SPLIT_INTEGRATORS = (mjw.IntegratorType.EULER, mjw.IntegratorType.IMPLICITFAST)
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


@wp.kernel
def _keep_rows_of(worlds: wp.array[bool], nefc: wp.array[int], kept: wp.array[int]):
    """Keep each world's constraint-row count; leave rows only in ``worlds``: the solver skips the others."""
    world = wp.tid()
    kept[world] = nefc[world]
    if not worlds[world]:
        nefc[world] = 0


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
            self._nefc_kept = wp.zeros_like(self.d.nefc)
        opt = self.m.opt
        if opt.integrator not in SPLIT_INTEGRATORS:
            raise ValueError(f"Simulation: integrator {mujoco.mjtIntegrator(opt.integrator).name} is not run by the "
                             f"two-stage substep; set sim.integrator to 'euler' or 'implicitfast'")
        if opt.enableflags & (mjw.EnableBit.ENERGY | mjw.EnableBit.SLEEP):
            raise ValueError("Simulation: the model enables MuJoCo's energy or sleep flag, which the two-stage substep "
                             "does not run; remove <flag energy=.../> and <flag sleep=.../> from the robot's MJCF option")
        self.after_substep: list[Callable[[], None]] = []
        # once after a step's last substep's hooks (and in the forward): work that only the step's end reads, such as
        # observations, so the substeps before it skip it
        self.after_step: list[Callable[[], None]] = []
        self.after_reset: list[Callable[[torch.Tensor], None]] = []  # called with the reset mask (torch bool)
        self._graph = None
        self._make_views()
        # what :meth:`forward` refreshes for the worlds it is given (each (num_worlds, ...)): the others keep their
        # last substep's (the actuator forces it applied, not the forward's recomputation from the new state);
        # and what the callbacks and after_substep hooks integrate from one substep to the next, which it leaves as
        # it was
        self.observed: list[torch.Tensor] = [self.body_contact_force, self.actuator_force]
        self.substep_state: list[torch.Tensor] = []
        # the next substep's first half, computed ahead (see the module docstring): per substep-state array, its
        # value as the stage leaves it and as it was before; the version counters of the inputs the stage was
        # computed from (None: no stage). Warp copies only: ``recompute`` may be captured by Warp or by torch
        self._stage_buffers: list[tuple[wp.array, wp.array, wp.array]] = []
        self._stage_versions: tuple[int, ...] | None = None

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
    def add_substep_state(self, arrays: list[wp.array]) -> None:
        """Register per-world arrays the callbacks and after_substep hooks integrate from one substep to the
        next (soil ruts, slip, ...): ``forward`` leaves them as they were."""
        for a in arrays:
            self.substep_state.append(wp.to_torch(a))
            self._stage_buffers.append((a, wp.empty_like(a), wp.empty_like(a)))

    def _input_versions(self) -> tuple[int, ...]:
        """torch's version counters of the state and model views: any in-place torch write to them (or to a
        view of them) changes its counter. Warp's writes do not: code that runs Warp on ``d`` calls
        ``drop_stage``."""
        return tuple(t._version for t in (self.qpos, self.qvel, self.geom_friction, self.body_mass,
                                          self.body_inertia))

    def drop_stage(self) -> None:
        """Forget the next substep's first half computed ahead: the next step computes it afresh. For code that
        changes ``d`` or the model through Warp between steps (torch writes to the views are noticed)."""
        self._stage_versions = None

    def ensure_stage(self) -> None:
        """Compute the next substep's first half now unless the one computed ahead still holds (nothing wrote
        qpos, qvel, friction, masses or inertias since). Runs before a step, outside any graph."""
        if self._stage_versions != self._input_versions():
            with wp.ScopedDevice(self.wp_device):
                self._stage()
                self._put_back()

    def _stage(self) -> None:
        """The next substep's first half, ahead of it: its results stay in ``d``, and the substep state it
        integrated is kept aside for the substep, as is the state before it (``_put_back`` restores that)."""
        for state, _, before in self._stage_buffers:
            wp.copy(before, state)
        self._position_and_velocity()
        for state, staged, _ in self._stage_buffers:
            wp.copy(staged, state)
        self._stage_versions = self._input_versions()

    def _put_back(self) -> None:
        """The substep state as it was before the stage (the substep takes the stage's with ``_use_stage``)."""
        for state, _, before in self._stage_buffers:
            wp.copy(state, before)

    def _use_stage(self) -> None:
        """The substep state as the stage left it (``d`` holds the stage's results already)."""
        for state, staged, _ in self._stage_buffers:
            wp.copy(state, staged)

    def _position_and_velocity(self) -> None:
        """The first half of MuJoCo-Warp's forward, in ``mjw.forward``'s order: positions (bodies, contacts with
        the contact-filter callback, constraint rows), position sensors, velocities (passive forces with the
        passive callback, which adds the feet's added mass to the inertia, so it is factorised later), velocity
        sensors."""
        m, d = self.m, self.d
        mjw.fwd_position(m, d, factorize=False)
        d.sensordata.zero_()
        mjw.sensor_pos(m, d)
        mjw.fwd_velocity(m, d)
        mjw.sensor_vel(m, d)

    def _acceleration(self) -> None:
        """The second half of MuJoCo-Warp's forward, in ``mjw.forward``'s order: the control callback, actuator
        forces, the factorised inertia and smooth acceleration, the constraint solver, acceleration sensors."""
        m, d = self.m, self.d
        if m.callback.control and not (m.opt.disableflags & mjw.DisableBit.ACTUATION):
            m.callback.control(m, d)
        mjw.fwd_actuation(m, d)
        mjw.fwd_acceleration(m, d, factorize=True)
        mjw.solve(m, d)
        if m.opt.run_rne_postconstraint or (m.sensor_rne_postconstraint
                                            and not m.opt.disableflags & mjw.DisableBit.SENSOR):
            mjw.rne_postconstraint(m, d)
        mjw.sensor_acc(m, d, skip_rne_postconstraint=True)

    def _substeps(self, decimation: int) -> None:
        """``decimation`` substeps, each ``mjw.step`` in two halves then the after_substep hooks, then the
        after_step hooks once; the first substep's first half is the stage computed ahead (``ensure_stage`` ran
        before)."""
        m, d = self.m, self.d
        self._use_stage()
        for substep in range(decimation):
            if substep > 0:
                self._position_and_velocity()
            self._acceleration()
            if m.opt.integrator == mjw.IntegratorType.EULER:
                mjw.euler(m, d)
            else:
                mjw.implicit(m, d)
            for hook in self.after_substep:
                hook()
        for hook in self.after_step:
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
        self.ensure_stage()
        self._stage_versions = None  # the substeps use the stage up
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
        self.drop_stage()
        for hook in self.after_reset:
            hook(mask)

    @torch.compiler.disable
    def forward(self, mask: torch.Tensor) -> None:
        """Recompute what derives from qpos/qvel/ctrl without advancing time, as a substep sees it: bodies,
        contacts (the force fields' contact filter included: ground friction, soil, analytic sole contacts),
        passive forces, constraint forces; then the ``after_substep`` and ``after_step`` hooks (the force fields'
        state and observation) and the per-body contact forces. The worlds in ``mask`` take the new values of every
        ``observed`` tensor; the others keep their last substep's. Only the masked worlds' constraints are solved,
        so what derives from the solve in ``d`` (qacc, constraint forces, acceleration sensors) is the forward's in
        those worlds only: a subclass that observes such a value registers its tensor in ``observed``.

        Physics-neutral: the solver's warm start and everything in ``substep_state`` (what the callbacks and
        hooks integrate once per substep, e.g. soil ruts, slip) stay as they were, in every world. Its first
        half is the next substep's, computed ahead (see the module docstring): the next step reuses it. On the
        CPU it is skipped when no world is masked (a host read, free there; on a GPU it always runs, as the
        step must not wait for the device)."""
        if not self.wp_device.is_cuda and not bool(mask.any()):
            return
        last = [t.clone() for t in self.observed]
        self.recompute(mask)
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

    def recompute(self, mask: torch.Tensor) -> None:
        """The Warp work of :meth:`forward`: the next substep's first half in every world, computed ahead and kept
        for it (with the force fields' callbacks); the second half of MuJoCo's forward, the ``after_substep`` and
        ``after_step`` hooks and the per-body contact forces, with the constraints solved in the worlds in ``mask``
        only (the others' constraint forces are not observed: they keep their last substep's). ``substep_state`` is
        left as it was."""
        with wp.ScopedDevice(self.wp_device):
            self._stage()  # leaves the substep state as the stage integrated it, as the second half expects
            # no rows, no solver work: the solver's iterations and line searches run per constraint row. The row
            # counts go back before anything reads them (the next substep solves the staged rows)
            wp.launch(_keep_rows_of, dim=self.num_worlds, inputs=[wp.from_torch(mask.contiguous(), dtype=wp.bool),
                                                                   self.d.nefc, self._nefc_kept])
            self._acceleration()
            wp.copy(self.d.nefc, self._nefc_kept)
            for hook in self.after_substep:
                hook()
            for hook in self.after_step:
                hook()
            self._contact_forces()
            self._put_back()

    @torch.compiler.disable
    def set_const(self) -> None:
        """Derived model constants (subtree masses, inverse weights) after body masses or inertias changed."""
        with wp.ScopedDevice(self.wp_device):
            mjw.set_const(self.m, self.d)
        self.drop_stage()
