"""Answers of real OpenAI-compatible servers differ from OpenAI's in fields the backend never reads."""

from __future__ import annotations

import pytest

from legged_gente.generation.backends import GenerationError
from legged_gente.generation.backends.openai_backend import OpenAIBackend
from test_generation_openai import REGISTRY, FakeServer, _completion, _png_bytes, _tool_call, ok


def _backend(server):
    return OpenAIBackend(server.url, "test-model", registry=REGISTRY, timeout=5.0)


@pytest.mark.parametrize("finish_reason", ["eos_token", "eos", None])  # TGI before 2.2, Together's Llama, a bare server
def test_a_finish_reason_outside_openais_list_is_no_error(finish_reason):
    answer = _completion([_tool_call("test_bumps", {"height": 0.2, "region": "full"})])
    answer["choices"][0]["finish_reason"] = finish_reason
    for field in ("object", "created"):  # the envelope is not read either
        del answer[field]
    with FakeServer([ok(answer)]) as srv:
        result = _backend(srv).generate(text="bumps")
    assert [(c.tool, c.params["height"]) for c in result.calls] == [("test_bumps", 0.2)]


def test_two_phase_description_with_a_nonstandard_finish_reason():
    description = _completion(content="A shallow pond.")
    description["choices"][0]["finish_reason"] = "eos_token"
    reply = _completion([_tool_call("test_wet", {"depth": 0.1, "region": "full"})])
    with FakeServer([ok(description), ok(reply)]) as srv:
        result = OpenAIBackend(srv.url, "test-model", registry=REGISTRY, timeout=5.0, two_phase=True).generate(
            image=_png_bytes())
    assert [c.tool for c in result.calls] == ["test_wet"]


@pytest.mark.parametrize("message, expected", [
    ({"role": "assistant", "content": None, "tool_calls": "many"},
     r"off OpenAI's format \(choices\[0\]\.message\.tool_calls: Input should be a valid list"),
    ("text", r"off OpenAI's format \(choices\[0\]\.message: Input should be a valid dictionary"),
])
def test_a_message_that_is_not_one_is_still_refused(message, expected):
    answer = _completion(content="x")
    answer["choices"][0]["message"] = message
    with FakeServer([ok(answer)]) as srv:
        with pytest.raises(GenerationError, match=expected):
            _backend(srv).generate(text="x")


def test_no_choices_is_named():
    answer = _completion(content="x")
    answer["choices"] = []
    with FakeServer([ok(answer)]) as srv:
        with pytest.raises(GenerationError, match="returned no choices"):
            _backend(srv).generate(text="x")
