"""The openai backend against misbehaving servers on 127.0.0.1: every request ends, in time, with a clear error."""

from __future__ import annotations

import json
import re
import socket
import socketserver
import threading
import time

import pytest
from test_generation_openai import FakeServer, _completion, _tool_call, ok

from legged_gente.generation.backends import GenerationError
from legged_gente.generation.backends import openai_backend
from legged_gente.generation.backends.openai_backend import OpenAIBackend


def _read_request(sock, limit=1 << 20):
    """Reads one whole HTTP request (headers and its Content-Length body), so that closing the socket sends FIN.

    A socket closed with unread bytes sends RST instead (RFC 1122, 4.2.2.13), and a client still reading the reply
    then fails with "connection reset" before it has parsed what it was sent.
    """
    data = b""
    while b"\r\n\r\n" not in data and len(data) < limit:
        chunk = sock.recv(65536)
        if not chunk:
            return
        data += chunk
    head, _, body = data.partition(b"\r\n\r\n")
    length = re.search(rb"(?im)^content-length:\s*(\d+)", head)
    missing = int(length.group(1)) - len(body) if length else 0
    while 0 < missing:
        chunk = sock.recv(min(missing, 65536))
        if not chunk:
            return
        missing -= len(chunk)


class RawServer:
    """Answers every connection with ``respond(write, stop)``: raw bytes, at the pace the test wants."""

    def __init__(self, respond):
        self.stop = threading.Event()
        outer = self

        class Handler(socketserver.BaseRequestHandler):
            def handle(self):
                _read_request(self.request)
                try:
                    respond(self.request.sendall, outer.stop)
                except OSError:  # the client gave up and closed the connection
                    pass

        socketserver.ThreadingTCPServer.allow_reuse_address = True
        self.server = socketserver.ThreadingTCPServer(("127.0.0.1", 0), Handler)
        self.server.daemon_threads = True
        self.thread = threading.Thread(target=self.server.serve_forever, daemon=True)

    @property
    def url(self):
        return f"http://127.0.0.1:{self.server.server_address[1]}/v1"

    def __enter__(self):
        self.thread.start()
        return self

    def __exit__(self, *exc):
        self.stop.set()
        self.server.shutdown()
        self.server.server_close()


def _headers(length, content_type="application/json"):
    return (f"HTTP/1.1 200 OK\r\nContent-Type: {content_type}\r\nContent-Length: {length}\r\n\r\n").encode()


def _drip(data, stop, write, period=0.5):
    for i in range(len(data)):
        if stop.wait(period):
            return
        write(data[i:i + 1])


def test_html_body_names_the_server():
    page = b"<html><body>Welcome to nginx!</body></html>"
    with RawServer(lambda write, stop: write(_headers(len(page), "text/html") + page)) as srv:
        with pytest.raises(GenerationError, match=rf"server at {srv.url} answered HTTP 200 with a body that is not JSON.*<html>"):
            OpenAIBackend(srv.url, "m", timeout=5.0).generate(text="x")


def test_json_that_is_not_a_completion():
    body = json.dumps({"status": "ok", "choices": "none"}).encode()
    with RawServer(lambda write, stop: write(_headers(len(body)) + body)) as srv:
        with pytest.raises(GenerationError, match="answered JSON that is not a chat completion"):
            OpenAIBackend(srv.url, "m", timeout=5.0).generate(text="x")


@pytest.mark.parametrize("where", ["body", "headers"])
def test_a_dripping_server_cannot_outlast_the_deadline(where):
    body = json.dumps(_completion(content="late")).encode()

    def respond(write, stop):
        if where == "body":
            write(_headers(len(body)))
            _drip(body, stop, write)
        else:
            _drip(_headers(len(body)), stop, write)

    with RawServer(respond) as srv:
        t0 = time.monotonic()
        with pytest.raises(GenerationError, match="timed out after 2 s"):
            OpenAIBackend(srv.url, "m", timeout=2.0).generate(text="x")
        elapsed = time.monotonic() - t0
    assert elapsed < 3.0, f"a 2 s request took {elapsed:.1f} s"  # one byte per 0.5 s: per-read timeouts never fire


def test_response_size_is_capped(monkeypatch):
    monkeypatch.setattr(openai_backend, "MAX_RESPONSE_BYTES", 10_000)
    body = b"{" + b" " * 50_000 + b"}"
    with RawServer(lambda write, stop: write(_headers(len(body)) + body)) as srv:
        with pytest.raises(GenerationError, match="sent more than 10000 bytes"):
            OpenAIBackend(srv.url, "m", timeout=5.0).generate(text="x")


def test_error_status_with_a_huge_text_is_shortened():
    with FakeServer([(503, {"error": {"message": "overloaded " * 10_000}}, 0.0)]) as srv:
        with pytest.raises(GenerationError, match="HTTP 503: overloaded") as info:
            OpenAIBackend(srv.url, "m", timeout=5.0).generate(text="x")
    assert len(str(info.value)) < 500


def test_too_many_tool_calls_in_one_answer_are_not_read():
    calls = [_tool_call("flat", {"height": 0.0, "region": "full"}, i) for i in range(65)]
    with FakeServer([ok(_completion(calls))]) as srv:
        with pytest.raises(GenerationError, match="65 tool calls in one answer; at most 64"):
            OpenAIBackend(srv.url, "m", timeout=5.0, max_retries=0).generate(text="x")


def test_too_many_tool_calls_are_answered_call_by_call():
    """The follow-up request keeps the chat's turns as the protocol has them: the assistant's answer, then one tool
    result per tool_call_id (each saying why it was not read), never two user messages in a row (strict chat
    templates refuse those); the model's next answer, of 64 calls or fewer, is read."""
    calls = [_tool_call("flat", {"height": 0.0, "region": "full"}, i) for i in range(65)]
    retry = [_tool_call("flat", {"height": 0.0, "region": "full"}, 100)]
    with FakeServer([ok(_completion(calls)), ok(_completion(retry))]) as srv:
        result = OpenAIBackend(srv.url, "m", timeout=5.0, max_retries=1).generate(text="x")
    assert [c.tool for c in result.calls] == ["flat"]
    follow_up = srv.requests[1]["messages"]
    roles = [m["role"] for m in follow_up]
    assert roles == ["system", "user", "assistant"] + ["tool"] * 65
    assert [m["tool_call_id"] for m in follow_up[3:]] == [f"call_{i}" for i in range(65)]
    assert all(m["content"].startswith("REJECTED: ") and "at most 64" in m["content"] for m in follow_up[3:])


def test_unreachable_server():
    with socket.socket() as s:  # a port nobody listens on
        s.bind(("127.0.0.1", 0))
        port = s.getsockname()[1]
    with pytest.raises(GenerationError, match="could not reach"):
        OpenAIBackend(f"http://127.0.0.1:{port}/v1", "m", timeout=2.0).generate(text="x")


@pytest.mark.parametrize("reply, detail", [
    (b"GARBAGE \x1b[31m\r\n\r\n", r"BadStatusLine('GARBAGE \x1b[31m\r\n')"),  # the server's bytes, escaped
    (b"{}", "BadStatusLine('{}')"),  # HTTP/0.9: a bare body, no status line
    (b"HTTP/1.1 200 OK\r\n" + b"X-a: b\r\n" * 200 + b"\r\n{}", "HTTPException('got more than 100 headers')"),
    (b"HTTP/1.1 200 OK\r\nX-a: " + b"b" * 70_000 + b"\r\n\r\n{}",
     "LineTooLong('got more than 65536 bytes when reading header line')"),
    (b"HTTP/1.1 200 OK\r\nTransfer-Encoding: chunked\r\n\r\nZZZ\r\nabc\r\n", "IncompleteRead(0 bytes read)"),
], ids=["status_line", "http09", "many_headers", "long_header", "bad_chunk"])
def test_malformed_http_names_the_server(reply, detail):
    with RawServer(lambda write, stop: write(reply)) as srv:
        with pytest.raises(GenerationError) as info:
            OpenAIBackend(srv.url, "m", timeout=5.0).generate(text="x")
    assert str(info.value) == (f"the server at {srv.url} answered malformed HTTP ({detail}); point --base-url at "
                               f"its OpenAI-compatible API, e.g. http://localhost:8000/v1.")


@pytest.mark.parametrize("status", [301, 302, 303, 307, 308])
def test_a_redirect_is_not_followed(monkeypatch, status):
    """Following it would send the API key (and the prompt) to whatever host the Location names."""
    monkeypatch.setenv("GENTE_API_KEY", "sk-SECRET")
    seen = []
    with RawServer(lambda write, stop: seen.append("request")) as elsewhere:
        target = elsewhere.url.replace("127.0.0.1", "localhost") + "/chat/completions"
        reply = f"HTTP/1.1 {status} Moved\r\nLocation: {target}\r\nContent-Length: 0\r\n\r\n".encode()
        with RawServer(lambda write, stop: write(reply)) as srv:
            with pytest.raises(GenerationError) as info:
                OpenAIBackend(srv.url, "m", timeout=5.0).generate(text="x")
    assert str(info.value) == (f"the server at {srv.url} answered HTTP {status}, a redirect to {target}; redirects "
                               f"are not followed (they would carry the API key to another address): point --base-url "
                               f"at the final address.")
    assert seen == []


def test_the_raw_server_reads_the_whole_request_so_its_reply_arrives_whole():
    """A request whose body comes in a second segment and a reply larger than the socket buffers: all of it arrives.

    Closed with the body unread, the server's socket would reset the connection and drop the reply's unsent tail.
    """
    reply = b"HTTP/1.1 200 OK\r\nX-a: " + b"b" * 8_000_000 + b"\r\n\r\n{}"

    def respond(write, stop):
        time.sleep(0.3)  # the body arrives meanwhile
        write(reply)

    with RawServer(respond) as srv:
        with socket.create_connection(("127.0.0.1", srv.server.server_address[1]), timeout=5.0) as sock:
            sock.sendall(b"POST /v1/chat/completions HTTP/1.1\r\nHost: x\r\nContent-Length: 2\r\n\r\n")
            time.sleep(0.1)  # the server has read the headers
            sock.sendall(b"{}")
            received = b""
            while chunk := sock.recv(1 << 20):
                received += chunk
    assert received == reply
