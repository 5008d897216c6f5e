"""StepGraph's copy-back at the end of a capture keeps what the eager step computes when the step rebinds one
attribute to another's tensor (the copy itself runs on the CPU too; capture and replay need CUDA)."""

from types import SimpleNamespace

import torch

from legged_gente.utils.cuda_graph import StepGraph, rebound_attributes


def copied_back(owner, step) -> dict:
    """The owner's attributes as a replay leaves them: ``step`` run as the capture runs it, then the copy-back."""
    before = dict(vars(owner))
    step(owner)
    graph = StepGraph.__new__(StepGraph)
    graph.owner = owner
    rebound = rebound_attributes(owner, before)
    graph._bind(rebound, graph._copy_back(rebound, before))
    return {name: value.clone() for name, value in vars(owner).items()}


def test_an_attribute_rebound_to_another_ones_tensor_keeps_that_tensors_old_value():
    """``self.last = self.now; self.now = self.now + 1`` (legged_gym's history pattern, written by rebinding):
    ``last`` holds the step's old ``now`` and ``now`` the new one, whichever attribute was defined first."""
    def step(owner):
        owner.last = owner.now
        owner.now = owner.now + 1.0

    now_first = copied_back(SimpleNamespace(now=torch.zeros(3), last=torch.full((3,), -1.0)), step)
    last_first = copied_back(SimpleNamespace(last=torch.full((3,), -1.0), now=torch.zeros(3)), step)
    for state in (now_first, last_first):
        assert torch.equal(state["last"], torch.zeros(3)) and torch.equal(state["now"], torch.ones(3))


def test_a_swap_of_two_buffers_is_kept():
    """``self.a, self.b = self.b, self.a`` (double buffering): after the copy-back ``a`` holds b's values and ``b``
    a's, in the tensors the graph reads."""
    a, b = torch.zeros(2), torch.ones(2)
    owner = SimpleNamespace(a=a, b=b)

    def step(owner):
        owner.a, owner.b = owner.b, owner.a

    state = copied_back(owner, step)
    assert torch.equal(state["a"], torch.ones(2)) and torch.equal(state["b"], torch.zeros(2))
    assert owner.a is a and owner.b is b  # the tensors the graph reads and writes
