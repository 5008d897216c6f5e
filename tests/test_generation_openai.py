"""The openai backend against a local chat-completions server (http.server on 127.0.0.1, in a thread)."""

from __future__ import annotations

import base64
import io
import json
import math
import threading
import time
from http.server import BaseHTTPRequestHandler, ThreadingHTTPServer

import numpy as np
import pytest
from PIL import Image

from legged_gente.generation.backends import GenerationError
from legged_gente.generation.backends.openai_backend import OpenAIBackend
from legged_gente.terrain.registry import AtomicTerrain, Param


def _bumps(shape, resolution, rng, height, count):
    return np.full(shape, height, np.float32)


def _wet(shape, resolution, rng, heights, depth):
    raise AssertionError("not built in these tests")


REGISTRY = {
    "test_bumps": AtomicTerrain(
        "test_bumps", "geometric", "test bumps",
        {"height": Param(0.1, "bump height", "m", 0.0, 0.5), "count": Param(3, "number of bumps", "1", 1, 10, integer=True)},
        _bumps,
    ),
    "test_wet": AtomicTerrain("test_wet", "physical", "test water", {"depth": Param(0.2, "water depth", "m", 0.0, 2.0)}, _wet),
}


def _tool_call(name, args, i=0):
    return {"id": f"call_{i}", "type": "function", "function": {"name": name, "arguments": json.dumps(args)}}


def _completion(tool_calls=None, content=None):
    msg = {"role": "assistant", "content": content}
    if tool_calls:
        msg["tool_calls"] = tool_calls
    return {
        "id": "cmpl-test", "object": "chat.completion", "created": 0, "model": "test-model",
        "choices": [{"index": 0, "message": msg, "finish_reason": "tool_calls" if tool_calls else "stop"}],
    }


class FakeServer:
    """Answers each POST /v1/chat/completions with the next scripted reply; records the requests."""

    def __init__(self, replies):
        self.replies = list(replies)
        self.requests: list[dict] = []
        outer = self

        class Handler(BaseHTTPRequestHandler):
            def log_message(self, *args):
                pass

            def do_POST(self):
                body = json.loads(self.rfile.read(int(self.headers["Content-Length"])))
                outer.requests.append(body)
                status, payload, delay = outer.replies.pop(0)
                time.sleep(delay)
                data = json.dumps(payload).encode()
                try:
                    self.send_response(status)
                    self.send_header("Content-Type", "application/json")
                    self.send_header("Content-Length", str(len(data)))
                    self.end_headers()
                    self.wfile.write(data)
                except (BrokenPipeError, ConnectionResetError):
                    pass

        self.httpd = ThreadingHTTPServer(("127.0.0.1", 0), Handler)
        self.httpd.daemon_threads = True
        self.thread = threading.Thread(target=self.httpd.serve_forever, daemon=True)

    @property
    def url(self):
        return f"http://127.0.0.1:{self.httpd.server_address[1]}/v1"

    def __enter__(self):
        self.thread.start()
        return self

    def __exit__(self, *exc):
        self.httpd.shutdown()
        self.httpd.server_close()


def ok(payload, delay=0.0):
    return (200, payload, delay)


def _backend(server, **kw):
    return OpenAIBackend(server.url, "test-model", registry=REGISTRY, timeout=kw.pop("timeout", 5.0), **kw)


def test_tool_calls_are_validated_and_returned():
    reply = _completion([
        _tool_call("test_bumps", {"height": 0.2, "count": 4, "region": "front_left"}, 0),
        _tool_call("test_wet", {"depth": 0.3, "region": {"x0": 0, "y0": 0, "x1": 10, "y1": 5}}, 1),
    ])
    with FakeServer([ok(reply)]) as srv:
        result = _backend(srv).generate(text="a pond with bumps")
    assert [c.tool for c in result.calls] == ["test_bumps", "test_wet"]
    assert result.calls[0].params == {"height": 0.2, "count": 4}
    assert result.calls[1].region == (0.0, 0.0, 10.0, 5.0) and result.calls[1].mode is None
    req = srv.requests[0]
    assert req["model"] == "test-model" and req["tool_choice"] == "required"
    names = sorted(t["function"]["name"] for t in req["tools"])
    assert names == ["test_bumps", "test_wet"]
    assert "a pond with bumps" in json.dumps(req["messages"])


def test_invalid_call_is_corrected_on_second_turn():
    bad = _completion([_tool_call("test_bumps", {"height": 3.0, "region": "full"}, 0)])
    good = _completion([_tool_call("test_bumps", {"height": 0.3, "region": "full"}, 1)])
    with FakeServer([ok(bad), ok(good)]) as srv:
        result = _backend(srv).generate(text="big bumps")
    assert [c.params["height"] for c in result.calls] == [0.3]
    assert any("height" in w and "3.0" in w for w in result.warnings)
    # the second request carries the rejection as a tool result for the model to read
    tool_msgs = [m for m in srv.requests[1]["messages"] if m["role"] == "tool"]
    assert len(tool_msgs) == 1 and tool_msgs[0]["tool_call_id"] == "call_0"
    assert "REJECTED" in tool_msgs[0]["content"] and "[0.0, 0.5]" in tool_msgs[0]["content"]


def test_retry_limit_fails_clearly():
    bad = _completion([_tool_call("test_nope", {"region": "full"}, 0)])
    with FakeServer([ok(bad)] * 3) as srv:
        with pytest.raises(GenerationError, match=r"no valid terrain after 2 correction.*unknown tool \"test_nope\""):
            _backend(srv, max_retries=2).generate(text="x")
        assert len(srv.requests) == 3  # first answer + 2 correction rounds, no more


def test_text_answer_without_tool_calls_counts_as_a_round():
    with FakeServer([ok(_completion(content="I think flat ground."))] * 2) as srv:
        with pytest.raises(GenerationError, match="without calling a tool"):
            _backend(srv, max_retries=1).generate(text="x")


def _png_bytes():
    buf = io.BytesIO()
    Image.fromarray(np.full((8, 8, 3), (0, 0, 255), np.uint8)).save(buf, format="PNG")
    return buf.getvalue()


def test_image_arrives_as_data_url():
    png = _png_bytes()
    reply = _completion([_tool_call("test_wet", {"region": "full"})])
    with FakeServer([ok(reply)]) as srv:
        _backend(srv).generate(image=png)
    parts = srv.requests[0]["messages"][1]["content"]
    urls = [p["image_url"]["url"] for p in parts if p["type"] == "image_url"]
    assert len(urls) == 1 and urls[0].startswith("data:image/png;base64,")
    assert base64.b64decode(urls[0].split(",", 1)[1]) == png


def test_two_phase_describes_then_calls_tools():
    description = _completion(content="A shallow pond covering the whole area.")
    reply = _completion([_tool_call("test_wet", {"depth": 0.1, "region": "full"})])
    with FakeServer([ok(description), ok(reply)]) as srv:
        result = _backend(srv, two_phase=True, vision_model="test-vlm").generate(image=_png_bytes())
    first, second = srv.requests
    assert first["model"] == "test-vlm" and "tools" not in first
    assert any(p["type"] == "image_url" for p in first["messages"][0]["content"])
    assert second["model"] == "test-model" and "shallow pond" in json.dumps(second["messages"])
    assert "image_url" not in json.dumps(second["messages"])
    assert result.calls[0].params["depth"] == 0.1 and "shallow pond" in result.notes[0]


def test_two_phase_passes_the_users_text_to_the_tool_calling_model_too():
    """The text given with the image (sizes, a depth, what to stress) reaches both models: the vision model as
    context for its description, the tool-calling model as the user's own words beside that description."""
    description = _completion(content="A shallow pond covering the whole area.")
    reply = _completion([_tool_call("test_wet", {"depth": 0.1, "region": "full"})])
    with FakeServer([ok(description), ok(reply)]) as srv:
        _backend(srv, two_phase=True, vision_model="test-vlm").generate(text="the pond is 0.1 m deep",
                                                                        image=_png_bytes())
    first, second = srv.requests
    assert "the pond is 0.1 m deep" in json.dumps(first["messages"])
    user = [m for m in second["messages"] if m["role"] == "user"]
    texts = [p["text"] for p in user[0]["content"]]
    assert any("shallow pond" in t for t in texts) and any("the pond is 0.1 m deep" in t for t in texts)


def test_server_error_is_clear():
    with FakeServer([(500, {"error": {"message": "model exploded"}}, 0.0)]) as srv:
        with pytest.raises(GenerationError, match="HTTP 500.*model exploded"):
            _backend(srv).generate(text="x")


def test_timeout_is_clear():
    with FakeServer([ok(_completion(content="late"), delay=1.5)]) as srv:
        with pytest.raises(GenerationError, match="timed out after 0.3 s"):
            _backend(srv, timeout=0.3).generate(text="x")


@pytest.mark.parametrize("key", ["sk-SECRET-1234567890\n", " sk-SECRET", "sk-SECRET\x1b[0m", "sk-SECRET\u2019"])
def test_a_malformed_api_key_is_refused_before_the_request(monkeypatch, key):
    monkeypatch.setenv("GENTE_API_KEY", key)
    with FakeServer([]) as srv:
        with pytest.raises(ValueError) as info:
            _backend(srv).generate(text="x")
    assert str(info.value) == ("the API key in the environment variable GENTE_API_KEY holds whitespace, control or "
                               "non-ASCII characters (a trailing newline?); set GENTE_API_KEY to the key alone.")
    assert srv.requests == []


def test_the_error_text_of_the_server_is_escaped():
    with FakeServer([(500, {"error": {"message": "internal\nboom \x1b[31mred"}}, 0.0)]) as srv:
        with pytest.raises(GenerationError) as info:
            _backend(srv).generate(text="x")
    assert str(info.value) == rf"the server at {srv.url} answered HTTP 500: internal\nboom \x1b[31mred"


@pytest.mark.parametrize("timeout", [0.0, -1.0, math.nan, math.inf, 1e10])
def test_timeout_must_be_a_finite_positive_number(timeout):
    with pytest.raises(ValueError) as info:
        OpenAIBackend("http://127.0.0.1:9/v1", "m", timeout=timeout)
    assert str(info.value) == f"timeout must be > 0 and at most 86400 seconds, got {timeout}."


@pytest.mark.parametrize("base_url", ["file:///tmp/fs", "data:,{}", "ftp://host/v1", "localhost:8000/v1", "http:///v1"])
def test_the_base_url_must_be_an_http_address(base_url):
    """urllib's opener would read a file: or data: address too, and its answer has no HTTP status."""
    with pytest.raises(ValueError) as info:
        OpenAIBackend(base_url, "m")
    assert str(info.value) == (f"base_url {base_url}: not an http:// or https:// address with a host; give the "
                               f"server's API address, e.g. http://localhost:8000/v1.")


@pytest.mark.parametrize("max_retries", [-1, 11, 10**6])
def test_correction_rounds_are_bounded(max_retries):
    """Each round is a request of up to ``timeout`` seconds: their number is capped so a run's time is bounded."""
    with pytest.raises(ValueError) as info:
        OpenAIBackend("http://127.0.0.1:9/v1", "m", max_retries=max_retries)
    assert str(info.value) == f"max_retries must be between 0 and 10, got {max_retries}."


def _bumps_call(height, region="full", mode="add", i=0):
    return _tool_call("test_bumps", {"height": height, "region": region, "mode": mode}, i)


def _summary(result):
    return [(c.params["height"], c.region, c.mode) for c in result.calls]


def test_a_correction_round_does_not_apply_accepted_calls_twice():
    """A model that re-sends its accepted call with the corrected one gets each applied once."""
    first = _completion([_bumps_call(0.1, i=0), _bumps_call(9.0, i=1)])
    second = _completion([_bumps_call(0.1, i=2), _bumps_call(0.2, i=3)])
    with FakeServer([ok(first), ok(second)]) as srv:
        result = _backend(srv).generate(text="x")
    assert _summary(result) == [(0.1, "full", "add"), (0.2, "full", "add")]
    assert len(srv.requests) == 2
    assert "round 2: test_bumps (call_2) repeats the call accepted in round 1 (call_0); applied once" in result.warnings
    # in one answer, two identical calls are two calls
    with FakeServer([ok(_completion([_bumps_call(0.1, i=0), _bumps_call(0.1, i=1)]))]) as srv:
        assert len(_backend(srv).generate(text="x").calls) == 2


def test_a_corrected_call_takes_the_place_of_the_rejected_one():
    """Calls apply in order: a correction goes where its rejected call was, not after the calls that followed it."""
    first = _completion([_bumps_call(9.0, mode="set", i=0), _bumps_call(0.1, region="front_left", i=1)])
    second = _completion([_bumps_call(0.3, mode="set", i=2)])
    with FakeServer([ok(first), ok(second)]) as srv:
        result = _backend(srv).generate(text="x")
    assert _summary(result) == [(0.3, "full", "set"), (0.1, "front_left", "add")]


def test_a_correction_round_must_answer_each_rejected_call_once():
    """Two new calls for one rejected call cannot be placed: the round is rejected and the model told why."""
    first = _completion([_bumps_call(0.1, i=0), _bumps_call(9.0, i=1)])
    second = _completion([_bumps_call(0.2, i=2), _bumps_call(0.3, i=3)])
    third = _completion([_bumps_call(0.2, i=4)])
    with FakeServer([ok(first), ok(second), ok(third)]) as srv:
        result = _backend(srv).generate(text="x")
    assert _summary(result) == [(0.1, "full", "add"), (0.2, "full", "add")]
    replies = [m["content"] for m in srv.requests[2]["messages"] if m["role"] == "tool" and m["tool_call_id"] in ("call_2", "call_3")]
    expected = ("REJECTED: this answer has 2 new call(s) for 1 rejected call(s) (call_1); answer with exactly one "
                "corrected call per rejected call, in their order, and do not repeat accepted calls.")
    assert replies == [expected, expected]
    with FakeServer([ok(first), ok(second)]) as srv:
        with pytest.raises(GenerationError, match=r"no valid terrain after 1 correction.*2 new call\(s\) for 1 rejected"):
            _backend(srv, max_retries=1).generate(text="x")


def test_an_answer_that_only_repeats_accepted_calls_is_told_what_is_missing():
    first = _completion([_bumps_call(0.1, i=0), _bumps_call(9.0, i=1)])
    repeat = _completion([_bumps_call(0.1, i=2)])
    with FakeServer([ok(first), ok(repeat), ok(_completion([_bumps_call(0.2, i=3)]))]) as srv:
        result = _backend(srv).generate(text="x")
    assert _summary(result) == [(0.1, "full", "add"), (0.2, "full", "add")]
    *_, answer, told = srv.requests[2]["messages"]
    assert answer["tool_call_id"] == "call_2" and answer["content"].startswith("ALREADY APPLIED: identical to call_0")
    assert told == {"role": "user", "content": "this answer has 0 new call(s) for 1 rejected call(s) (call_1); answer "
                                               "with exactly one corrected call per rejected call, in their order, "
                                               "and do not repeat accepted calls."}
