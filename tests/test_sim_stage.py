"""The substep in two halves, its first half computed ahead by the forward after a step's resets: the same
numbers as MuJoCo-Warp's own ``mjw.step``, and a state written in between is noticed."""

import types

import mujoco
import mujoco_warp as mjw
import numpy as np
import pytest
import torch
import warp as wp

from legged_gente.sim.backend import Simulation

# a box on a plane with a position-controlled leg: contacts, friction, a constraint solve, an actuator
HOPPER = """
<mujoco>
  <option timestep="0.005" integrator="{integrator}"/>
  <worldbody>
    <geom name="floor" type="plane" size="5 5 0.1"/>
    <body name="base" pos="0 0 0.32">
      <freejoint/>
      <geom type="box" size="0.1 0.08 0.05" mass="2"/>
      <body name="leg" pos="0.05 0 -0.05">
        <joint name="hip" type="hinge" axis="0 1 0" range="-1 1" damping="0.1"/>
        <geom type="capsule" fromto="0 0 0 0 0 -0.22" size="0.02" mass="0.3"/>
      </body>
      <geom type="sphere" pos="-0.08 0 -0.06" size="0.02"/>
    </body>
  </worldbody>
  <actuator><position joint="hip" kp="30" kv="1"/></actuator>
</mujoco>
"""
WORLDS, DECIMATION = 3, 4
SIM_CFG = types.SimpleNamespace(cuda_graph="off", nconmax=16, njmax=64)


def _pair(integrator: str):
    """The project's Simulation and a plain MuJoCo-Warp model and data of the same MJCF, in the same state."""
    mjm = mujoco.MjModel.from_xml_string(HOPPER.format(integrator=integrator))
    sim = Simulation(mjm, WORLDS, "cpu", SIM_CFG, batch_model=False)
    with wp.ScopedDevice("cpu"):
        m = mjw.put_model(mjm)
        d = mjw.make_data(mjm, nworld=WORLDS, nconmax=SIM_CFG.nconmax, njmax=SIM_CFG.njmax)
    qvel = torch.tensor(np.random.default_rng(0).normal(0, 0.5, (WORLDS, mjm.nv)), dtype=torch.float32)
    sim.qvel.copy_(qvel)
    wp.to_torch(d.qvel).copy_(qvel)
    return sim, m, d


def _reference_step(m, d, ctrl: torch.Tensor) -> None:
    wp.to_torch(d.ctrl).copy_(ctrl)
    with wp.ScopedDevice("cpu"):
        for _ in range(DECIMATION):
            mjw.step(m, d)


def _assert_same_state(sim, d):
    assert torch.equal(sim.qpos, wp.to_torch(d.qpos)) and torch.equal(sim.qvel, wp.to_torch(d.qvel))


@pytest.mark.parametrize("integrator", ["implicitfast", "Euler"])
def test_steps_after_a_forward_equal_mjw_step(integrator):
    """Policy steps, each after a forward (which computes the next substep's first half ahead) or after none
    (the step computes it): qpos and qvel bitwise those of ``mjw.step``, while the box lands and the leg swings."""
    sim, m, d = _pair(integrator)
    everyone = torch.ones(WORLDS, dtype=torch.bool)
    rng = np.random.default_rng(1)
    steps_in_contact = 0
    for step in range(30):
        if step % 3:
            sim.forward(everyone)
        ctrl = torch.tensor(rng.uniform(-1, 1, (WORLDS, 1)), dtype=torch.float32)
        sim.ctrl.copy_(ctrl)
        sim.step(DECIMATION)
        _reference_step(m, d, ctrl)
        _assert_same_state(sim, d)
        steps_in_contact += int(sim.body_contact_force[:, 1:, 2].gt(0).any())
    assert steps_in_contact >= 15  # the floor held the hopping robots up in most steps


def test_writes_between_the_forward_and_the_step_are_seen():
    """A push written into qvel, a friction changed, a reset: each after the forward computed the next substep's
    first half; the step computes it again from what was written, as ``mjw.step`` does."""
    sim, m, d = _pair("implicitfast")
    everyone = torch.ones(WORLDS, dtype=torch.bool)
    ctrl = torch.full((WORLDS, 1), 0.3)
    sim.ctrl.copy_(ctrl)
    for _ in range(20):  # landed, standing on the box's corner and the leg
        sim.step(DECIMATION)
        _reference_step(m, d, ctrl)

    sim.forward(everyone)
    sim.qvel[:, 0:2] += 0.7  # a push (in place, through a view)
    wp.to_torch(d.qvel)[:, 0:2] += 0.7
    sim.step(DECIMATION)
    _reference_step(m, d, ctrl)
    _assert_same_state(sim, d)

    sim.forward(everyone)
    sim.geom_friction[:] *= 0.2  # slippery floor
    wp.to_torch(m.geom_friction)[:] *= 0.2
    sim.step(DECIMATION)
    _reference_step(m, d, ctrl)
    _assert_same_state(sim, d)

    sim.forward(everyone)
    first = torch.tensor([True, False, False])
    sim.reset_worlds(first)  # through Warp (mjw.reset_data): it drops the stage itself
    with wp.ScopedDevice("cpu"):
        mjw.reset_data(m, d, reset=wp.from_torch(first, dtype=wp.bool))
    sim.ctrl.copy_(ctrl)  # reset_data zeroed the reset world's
    sim.step(DECIMATION)
    _reference_step(m, d, ctrl)
    _assert_same_state(sim, d)


def test_the_forward_solves_the_constraints_of_the_worlds_it_is_given_only():
    """The forward's constraint solve serves the worlds in its mask (a step's resets) only: the others keep their
    last substep's contact forces, so their rows are left unsolved. The reset world's constraint forces are those
    of ``mjw.forward``, the row counts are the staged first half's, and the next step is bitwise ``mjw.step``'s."""
    sim, m, d = _pair("implicitfast")
    ctrl = torch.full((WORLDS, 1), 0.3)
    sim.ctrl.copy_(ctrl)
    for _ in range(20):  # landed: every world has contact rows
        sim.step(DECIMATION)
        _reference_step(m, d, ctrl)
    nefc = wp.to_torch(d.nefc).clone()
    assert (nefc > 0).all()
    last_substep = wp.to_torch(sim.d.efc.force).clone()

    first = torch.tensor([True, False, False])
    sim.forward(first)
    with wp.ScopedDevice("cpu"):
        mjw.forward(m, d)
    solved, reference = wp.to_torch(sim.d.efc.force), wp.to_torch(d.efc.force)
    assert torch.equal(sim.nefc, wp.to_torch(d.nefc))
    assert torch.equal(solved[0, :nefc[0]], reference[0, :nefc[0]])
    for world in (1, 2):
        rows = slice(0, int(nefc[world]))
        assert not torch.equal(reference[world, rows], last_substep[world, rows])  # a full forward would solve them
        assert torch.equal(solved[world, rows], last_substep[world, rows])

    sim.step(DECIMATION)
    _reference_step(m, d, ctrl)
    _assert_same_state(sim, d)


def test_what_the_two_stage_substep_does_not_run_is_refused_with_the_fix():
    mjm = mujoco.MjModel.from_xml_string(HOPPER.format(integrator="RK4"))
    with pytest.raises(ValueError, match="integrator mjINT_RK4 .* set sim.integrator to 'euler' or 'implicitfast'"):
        Simulation(mjm, 1, "cpu", SIM_CFG, batch_model=False)
    mjm = mujoco.MjModel.from_xml_string(HOPPER.format(integrator="Euler").replace(
        "<option ", '<option><flag energy="enable"/></option>\n  <option '))
    with pytest.raises(ValueError, match="energy or sleep flag.*remove <flag energy"):
        Simulation(mjm, 1, "cpu", SIM_CFG, batch_model=False)


def test_after_step_hooks_run_once_per_step_after_the_last_substeps_hooks_and_in_the_forward():
    """A step of DECIMATION substeps runs the after_substep hooks DECIMATION times, then the after_step hooks once,
    at the state of its end (the time after its last substep); the forward runs each once."""
    sim, _, _ = _pair("Euler")
    calls = []
    sim.after_substep.append(lambda: calls.append(("substep", float(sim.time[0]))))
    sim.after_step.append(lambda: calls.append(("step", float(sim.time[0]))))
    sim.step(DECIMATION)
    dt = 0.005
    assert [c[0] for c in calls] == ["substep"] * DECIMATION + ["step"]
    assert calls[-1][1] == pytest.approx(DECIMATION * dt) and calls[-2][1] == calls[-1][1]
    calls.clear()
    sim.forward(torch.ones(WORLDS, dtype=torch.bool))
    assert [c[0] for c in calls] == ["substep", "step"]
