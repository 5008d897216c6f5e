"""The openai backend's protocol edges and the flags and arguments around it (local server on 127.0.0.1)."""

from __future__ import annotations

import pytest
from test_cli_generate_conflicts import OPENAI
from test_generation_openai import REGISTRY, FakeServer, _completion, _png_bytes, _tool_call, ok

from legged_gente.generation.backends import GenerationError
from legged_gente.generation.backends.openai_backend import OpenAIBackend
from legged_gente.generation.pipeline import generate_spec
from legged_gente.scripts import generate as generate_script


def _backend(server, **kw):
    return OpenAIBackend(server.url, "test-model", registry=REGISTRY, timeout=5.0, **kw)


def _cut(answer):
    """``answer`` as a server sends it when it stops generating at its token limit."""
    answer["choices"][0]["finish_reason"] = "length"
    return answer


def test_an_answer_cut_at_the_token_limit_is_named_as_cut():
    """A server that stops at its token limit mid tool call (here a text-parsed call left in the content) did not
    get an answer 'without calling a tool': the user is told the limit and the model to send less."""
    cut = _cut(_completion(content='<tool_call>\n{"name": "test_bumps", "arguments": {"height": 0.2, "reg'))
    with FakeServer([ok(cut), ok(cut)]) as srv:
        with pytest.raises(GenerationError) as info:
            _backend(srv, max_retries=1).generate(text="bumps")
    assert "finish_reason 'length'" in str(info.value)
    assert "raise the server's limit on generated tokens" in str(info.value)
    assert "without calling a tool" not in str(info.value)
    told = srv.requests[1]["messages"][-1]
    assert told["role"] == "user" and "cut off" in told["content"]


def test_a_tool_call_cut_at_the_token_limit_is_named_as_cut():
    """The last call of a cut answer has half its arguments: its rejection says why they are not JSON."""
    answer = _completion([_tool_call("test_bumps", {"height": 0.2, "region": "full"}, 0)])
    answer["choices"][0]["message"]["tool_calls"][0]["function"]["arguments"] = '{"height": 0.2, "regi'
    with FakeServer([ok(_cut(answer))]) as srv:
        with pytest.raises(GenerationError) as info:
            _backend(srv, max_retries=0).generate(text="bumps")
    assert "not valid JSON" in str(info.value) and "finish_reason 'length'" in str(info.value)


def test_an_answer_with_a_tool_call_and_no_finish_reason_is_read():
    """The finish reason is read, never required (test_generation_openai_servers: servers differ in it)."""
    answer = _completion([_tool_call("test_bumps", {"height": 0.2, "region": "full"})])
    del answer["choices"][0]["finish_reason"]
    with FakeServer([ok(answer)]) as srv:
        assert [c.params["height"] for c in _backend(srv).generate(text="bumps").calls] == [0.2]


def test_a_refusal_is_shown_not_an_empty_answer():
    """OpenAI puts a model's refusal in ``refusal`` with no content: the user reads why, not ''."""
    refusal = _completion(content=None)
    refusal["choices"][0]["message"]["refusal"] = "I can't help with that."
    with FakeServer([ok(refusal)]) as srv:
        with pytest.raises(GenerationError, match="I can't help with that."):
            _backend(srv, max_retries=0).generate(text="bumps")


def test_two_phase_without_an_image_is_refused_before_any_request():
    """two_phase describes the image first; with text alone it would be ignored."""
    with FakeServer([]) as srv:
        with pytest.raises(ValueError) as info:
            _backend(srv, two_phase=True).generate(text="a lake")
        assert srv.requests == []
        with pytest.raises(ValueError) as pipe:
            generate_spec("a lake", backend="openai", base_url=srv.url, model="m", two_phase=True)
        assert srv.requests == []
    expected = "two_phase describes the image first; give an image or leave two_phase out."
    assert str(info.value) == expected and str(pipe.value) == expected


def test_a_vision_model_without_two_phase_is_refused():
    with pytest.raises(ValueError) as info:
        OpenAIBackend("http://127.0.0.1:9/v1", "m", vision_model="v")
    assert str(info.value) == "vision_model describes the image in two_phase; pass two_phase=True or leave it out."


def test_two_phase_with_an_image_still_runs():
    description = _completion(content="A shallow pond.")
    reply = _completion([_tool_call("test_wet", {"depth": 0.1, "region": "full"})])
    with FakeServer([ok(description), ok(reply)]) as srv:
        result = _backend(srv, two_phase=True, vision_model="vlm").generate(image=_png_bytes())
    assert [c.tool for c in result.calls] == ["test_wet"] and srv.requests[0]["model"] == "vlm"


@pytest.mark.parametrize("kwargs", [
    {"base_url": "http://127.0.0.1:9/v1"}, {"model": "m"}, {"two_phase": True}, {"vision_model": "v"},
])
def test_the_planner_refuses_the_servers_arguments(kwargs):
    """The planner sends no request: an argument for the server would be silently ignored."""
    with pytest.raises(ValueError) as info:
        generate_spec("a lake", backend="planner", **kwargs)
    assert str(info.value) == ("base_url, model, two_phase, vision_model, timeout, max_retries and api_key_env are "
                               "for the openai backend; the planner sends no request.")


def test_an_api_key_variable_named_but_unset_is_refused(capsys, monkeypatch, tmp_path):
    """--api-key-env names where the key is; an unset variable there would send 'none' as the key."""
    monkeypatch.delenv("GENTE_AUDIT_NO_SUCH_KEY", raising=False)

    def never(*args, **kwargs):
        raise AssertionError("a model was asked")

    monkeypatch.setattr(generate_script, "generate_spec", never)
    with pytest.raises(SystemExit) as exit_info:
        generate_script.main(["--text", "a lake", *OPENAI, "--api-key-env", "GENTE_AUDIT_NO_SUCH_KEY",
                              "--out", str(tmp_path / "o")])
    err = capsys.readouterr().err
    assert exit_info.value.code == 2 and "Traceback" not in err
    assert err.strip().splitlines()[-1] == ("gente-generate: error: --api-key-env GENTE_AUDIT_NO_SUCH_KEY: the "
                                            "variable is not set; export it with the key, or leave out --api-key-env "
                                            "for a server without one.")


@pytest.mark.parametrize("status, fix", [
    (401, "set the key in the environment variable GENTE_API_KEY (or name another with --api-key-env)"),
    (403, "set the key in the environment variable GENTE_API_KEY (or name another with --api-key-env)"),
    (404, "check --base-url (the API's root, e.g. http://localhost:8000/v1) and --model"),
])
def test_an_http_error_that_the_user_can_fix_names_the_fix(status, fix):
    with FakeServer([(status, {"error": {"message": "nope"}}, 0.0)]) as srv:
        with pytest.raises(GenerationError) as info:
            _backend(srv).generate(text="x")
    assert str(info.value) == f"the server at {srv.url} answered HTTP {status}: nope; {fix}."


def test_whole_calls_of_a_cut_answer_are_kept_with_a_warning():
    """Calls after the last whole one may be missing from a cut answer: the terrain is built, the user warned."""
    answer = _completion([_tool_call("test_bumps", {"height": 0.2, "region": "full"})])
    with FakeServer([ok(_cut(answer))]) as srv:
        result = _backend(srv).generate(text="bumps")
    assert [c.params["height"] for c in result.calls] == [0.2]
    assert any("finish_reason 'length'" in w for w in result.warnings)


def test_the_vision_model_that_described_the_image_is_recorded_in_the_spec():
    """Two models made the terrain: the spec's provenance names both (its model field the tool-calling one)."""
    description = _completion(content="A field of low rocks.")
    reply = _completion([_tool_call("rocks", {"region": "full"})])
    with FakeServer([ok(description), ok(reply)]) as srv:
        spec, _ = generate_spec(image=_png_bytes(), backend="openai", base_url=srv.url, model="m", two_phase=True,
                                vision_model="vlm")
    assert spec.model == "m" and spec.to_dict()["source"]["vision_model"] == "vlm"
