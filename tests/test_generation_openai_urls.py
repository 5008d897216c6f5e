"""The server's address and key as a user gives them: a query kept after the path (Azure's ?api-version=), a
password in the address refused and never printed, an empty key refused; a server that hangs up is named as one,
and a model that calls no tool is not said to have made invalid calls."""

from __future__ import annotations

import json
import socket
import struct
import threading
from http.server import BaseHTTPRequestHandler, ThreadingHTTPServer

import pytest

from legged_gente.generation.backends import GenerationError
from legged_gente.generation.backends.openai_backend import OpenAIBackend, base_url_problem
from test_generation_openai import REGISTRY, FakeServer, _completion, _tool_call, ok


def test_a_query_in_the_base_url_stays_after_the_path():
    paths = []

    class Handler(BaseHTTPRequestHandler):
        def log_message(self, *args):
            pass

        def do_POST(self):
            paths.append(self.path)
            self.rfile.read(int(self.headers["Content-Length"]))
            data = json.dumps(_completion([_tool_call("test_bumps", {"height": 0.2, "region": "full"})])).encode()
            self.send_response(200)
            self.send_header("Content-Type", "application/json")
            self.send_header("Content-Length", str(len(data)))
            self.end_headers()
            self.wfile.write(data)

    httpd = ThreadingHTTPServer(("127.0.0.1", 0), Handler)
    threading.Thread(target=httpd.serve_forever, daemon=True).start()
    try:
        url = f"http://127.0.0.1:{httpd.server_address[1]}/v1/?api-version=2024-06-01"
        OpenAIBackend(url, "m", registry=REGISTRY, timeout=5.0).generate(text="bumps")
    finally:
        httpd.shutdown()
    assert paths == ["/v1/chat/completions?api-version=2024-06-01"]


def test_a_password_in_the_address_is_refused_and_not_printed():
    url = "http://user:secret@127.0.0.1:1/v1"
    assert "--api-key-env" in base_url_problem(url)
    with pytest.raises(ValueError) as error:
        OpenAIBackend(url, "m", registry=REGISTRY)
    assert "secret" not in str(error.value) and "user:***@127.0.0.1" in str(error.value)


def test_an_empty_key_is_refused(monkeypatch):
    monkeypatch.setenv("GENTE_TEST_KEY", "")
    with pytest.raises(ValueError, match="GENTE_TEST_KEY is set but empty"):
        OpenAIBackend("http://127.0.0.1:1/v1", "m", registry=REGISTRY, api_key_env="GENTE_TEST_KEY")


@pytest.mark.parametrize("reset", [False, True])
def test_a_server_that_hangs_up_is_named_as_one(reset):
    """A server that closes the socket, politely (FIN) or with a reset (RST, as when it closes with the request
    unread), hung up: both are named so."""
    listener = socket.socket()
    listener.bind(("127.0.0.1", 0))
    listener.listen()

    def hang_up():
        conn, _ = listener.accept()
        if reset:  # linger 0: close sends RST
            conn.setsockopt(socket.SOL_SOCKET, socket.SO_LINGER, struct.pack("ii", 1, 0))
        else:
            conn.recv(65536)
        conn.close()

    threading.Thread(target=hang_up, daemon=True).start()
    url = f"http://127.0.0.1:{listener.getsockname()[1]}/v1"
    with pytest.raises(GenerationError, match="closed the connection without an answer"):
        OpenAIBackend(url, "m", registry=REGISTRY, timeout=5.0).generate(text="bumps")
    listener.close()


def test_a_model_that_calls_no_tool_is_not_said_to_have_made_invalid_calls():
    with FakeServer([ok(_completion(content="no")), ok(_completion(content="still no"))]) as srv:
        with pytest.raises(GenerationError) as error:
            OpenAIBackend(srv.url, "m", registry=REGISTRY, timeout=5.0, max_retries=1).generate(text="x")
    assert str(error.value).startswith("the model gave no valid terrain after 1 correction round(s): round 2: the "
                                       "model answered without calling a tool")


@pytest.mark.parametrize("setting", [{"timeout": 5.0}, {"max_retries": 7}, {"api_key_env": "MY_KEY"}])
def test_the_planner_refuses_the_server_s_settings_from_python_too(setting):
    """gente-generate refuses --timeout, --max-retries and --api-key-env with the planner, as they would be ignored;
    generate_spec took them and ignored them."""
    from legged_gente.generation.pipeline import generate_spec

    with pytest.raises(ValueError, match="are for the openai backend; the planner sends no request"):
        generate_spec("a hill", backend="planner", **setting)


@pytest.mark.parametrize("argv, said", [
    (["--text", "a \udcff yard"], "--text is not valid UTF-8"),  # how Python passes a byte that is not UTF-8
    (["--text", "a yard", "--backend", "openai", "--base-url", "http://127.0.0.1:1/v1", "--model", "m",
      "--api-key-env", ""], "--api-key-env is empty"),
])
def test_gente_generate_refuses_text_it_cannot_store_and_an_empty_key_variable_name(argv, said, tmp_path, capsys):
    from legged_gente.scripts import generate as generate_script

    with pytest.raises(SystemExit) as exit_info:
        generate_script.main([*argv, "--out", str(tmp_path / "o")])
    assert exit_info.value.code == 2 and said in capsys.readouterr().err


@pytest.mark.parametrize("text, name", [("été plage", "ete_plage"), ("ﬁeld of snow", "field_snow"),
                                        ("ǅungle river", "dzungle_river")])
def test_a_default_name_keeps_letters_that_are_not_ascii_as_their_ascii_forms(text, name):
    """'été plage' was named t_plage: the accented letters were dropped, not taken to their ASCII forms."""
    from legged_gente.generation.spec import spec_name

    assert spec_name(text) == name


def test_a_tool_call_off_the_format_is_named_by_its_field():
    """A server that sends a call's arguments as an object (OpenAI sends a JSON string): the error named '3
    validation errors for ChatCompletionMessage', not the field."""
    answer = _completion([_tool_call("test_bumps", {"height": 0.2, "region": "full"})])
    answer["choices"][0]["message"]["tool_calls"][0]["function"]["arguments"] = {"height": 0.2, "region": "full"}
    with FakeServer([ok(answer)]) as srv:
        with pytest.raises(GenerationError) as error:
            OpenAIBackend(srv.url, "m", registry=REGISTRY, timeout=5.0).generate(text="x")
    assert "off OpenAI's format (choices[0].message.tool_calls[0].function.arguments: Input should be a valid " \
        "string" in str(error.value)
