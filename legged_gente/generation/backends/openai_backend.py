"""The ``openai`` backend: any OpenAI-compatible chat-completions server calls the terrain tools.

One-phase: a (vision-)language model receives the text and/or the image (as a base64 data URL) and the
registry-derived ``tools``, and answers with tool calls. Two-phase (GenTe's scheme): a vision-language
model first describes the image as terrain, then a language model calls the tools from that description.

Every tool call is validated; rejected calls go back to the model as tool results carrying the validation
message, and the model gets at most ``max_retries`` correction rounds after its first answer. The run ends
at the first round whose calls are all valid; if calls are still invalid after the last round, a
:class:`GenerationError` names them. There are no hidden retries, so the number of requests is bounded.

A correction round answers the rejected calls only: its calls take the rejected calls' places, in order (calls
apply in order, so a correction must not move behind the calls that followed it). A call identical to one
accepted in an earlier round is a repeat, applied once and reported; if the other calls do not number exactly
the rejected ones, none of them can be placed and the round is rejected. The result never depends on the model
re-sending (or not) its accepted calls.

Every request is bounded whatever the server does: ``timeout`` is the deadline of the whole request
(connection, headers and body, not of each read: a server dripping one byte at a time cannot hold it
longer), an answer is at most :data:`MAX_RESPONSE_BYTES`, and an answer that is not a chat completion (an
HTML page, a proxy's error, truncated JSON) is a :class:`GenerationError` naming the server. The request
runs in a worker thread so that the deadline holds even while the server drips its headers; the message of
the first choice, the one part read, is read into the ``openai`` package's ``ChatCompletionMessage`` type,
which checks its structure (the rest differs between servers: finish reasons, missing fields). A redirect
(3xx) is not followed: it would carry the API key and the prompt to the address the server names; it is a
:class:`GenerationError` naming that address.
"""

from __future__ import annotations

import base64
import dataclasses
import http.client
import io
import json
import os
import re
import threading
import time
import urllib.error
import urllib.parse
import urllib.request
from pathlib import Path
from typing import Any, Mapping

from openai.types.chat import ChatCompletionMessage

from legged_gente.generation.backends import MAX_RETRIES, MAX_TIMEOUT, GenerationError, GenerationResult
from legged_gente.generation.backends.image import EXIF_ORIENTATION, open_image, upright
from legged_gente.generation.tools import named_regions, tool_schemas
from legged_gente.generation.validation import (
    ToolCall,
    ValidationError,
    check_height_stack,
    printable,
    validate_call,
)
from legged_gente.terrain.composition import MAX_CALLS
from legged_gente.terrain.registry import ATOMIC_TERRAINS, AtomicTerrain

DEFAULT_API_KEY_ENV = "GENTE_API_KEY"
MAX_RESPONSE_BYTES = 8 * 2**20
"""Largest answer read from the server (a chat completion with tool calls is a few kB)."""
HUNG_UP = (ConnectionResetError, ConnectionAbortedError, BrokenPipeError)
"""A server that closed the connection: politely (http.client.RemoteDisconnected is a ConnectionResetError), or
with a reset (it crashed, or closed with the request unread)."""
MAX_DESCRIPTION_CHARS = 4000
"""Longest image description passed on to the language model in a two-phase run (the rest is cut)."""
TOOLSETS = ("ours", "gente")
"""``ours``: the registry's tools; ``gente``: GenTe's original tool list, translated (see gente_compat)."""
MAX_TOOL_CALLS_PER_ANSWER = 64
"""Most tool calls one answer may carry (a spec holds at most ``composition.MAX_CALLS``)."""
CUT = ("the server stopped the answer at its token limit (finish_reason 'length'); raise the server's limit on "
       "generated tokens (or its context length)")
"""What an answer whose choice ends with finish_reason "length" lacks (its last tool call, or those after it), and the fix."""

DESCRIBE_PROMPT = (
    "Describe the ground in this image as terrain a legged robot would walk on, seen from above: which "
    "surfaces (water and its depth and flow, sand, mud, snow, ice, grass, rock, pavement), their slopes, "
    "obstacles (trees, rocks, pillars, gaps), stairs, and where each lies (near = back, far = front, "
    "left, right). Be concrete about sizes in metres."
)


WEB_FORMATS = {"PNG": "png", "JPEG": "jpeg", "MPO": "jpeg", "WEBP": "webp", "GIF": "gif"}
"""Pillow's format -> the image type servers read (a phone's MPO is a JPEG with a second picture appended)."""
PNG_MODES = ("1", "L", "LA", "I", "I;16", "P", "RGB", "RGBA")
"""Pixel modes a PNG holds as they are."""


def image_data_url(image: str | Path | bytes) -> str:
    """A ``data:image/...;base64,`` URL of an image file or its bytes (the format is read from the data).

    PNG, JPEG, WEBP and GIF go as they are; other formats (BMP, TIFF, ...) are re-encoded as PNG, and a picture
    stored turned (EXIF orientation) is sent upright, as servers decode the pixels without turning them.
    """
    data = Path(image).read_bytes() if isinstance(image, (str, Path)) else bytes(image)
    img = open_image(data, image)
    subtype = WEB_FORMATS.get(img.format or "")
    if subtype is None or img.getexif().get(EXIF_ORIENTATION, 1) != 1:
        img = upright(img)
        buf = io.BytesIO()
        if subtype == "jpeg":
            img.convert("RGB").save(buf, format="JPEG", quality=95)
        else:
            subtype = "png"
            img = img if img.mode in PNG_MODES else img.convert("RGBA" if "A" in img.getbands() else "RGB")
            img.save(buf, format="PNG")
        data = buf.getvalue()
    return f"data:image/{subtype};base64,{base64.b64encode(data).decode('ascii')}"


def system_prompt(size_x: float, size_y: float) -> str:
    regions = list(named_regions(size_x, size_y))
    return (
        f"You build a {size_x:g} m x {size_y:g} m terrain tile for a legged robot by calling terrain tools. "
        f"+x is the front of the tile and +y its left; a region is one of {regions} or a rectangle "
        f"{{x0, y0, x1, y1}} in metres. Calls apply in order: first geometric terrains (heights; mode 'set' "
        f"replaces the region's heights, 'add' adds to them), then physical terrains (water, soil, friction, "
        f"ice) over the ground they lie on (ice fills a depression to its level surface). Issue all calls at "
        f"once, using only the tools' declared arguments and ranges. If calls are rejected, answer with one "
        f"corrected call per rejected call, in their order; accepted calls stay applied: do not send them again."
    )


@dataclasses.dataclass
class _Slot:
    """The place of one call of the model's first answer with tool calls: its calls once accepted (None while
    rejected), the tool name the model called, the round that accepted it and the id of the call that last filled it."""

    calls: list[ToolCall] | None = None
    name: str = ""
    round: int = 0
    call_id: str = ""


class _NoRedirect(urllib.request.HTTPRedirectHandler):
    """Hands a 3xx answer back as an HTTPError instead of following it (with the Authorization header)."""

    def redirect_request(self, req, fp, code, msg, headers, newurl):
        return None


_OPENER = urllib.request.build_opener(_NoRedirect)


def shown_url(base_url: str) -> str:
    """``base_url`` as an error may print it: a password in it replaced by ***."""
    try:
        parts = urllib.parse.urlsplit(base_url)
        if parts.password is not None:
            return urllib.parse.urlunsplit(parts._replace(netloc=parts.netloc.replace(f":{parts.password}@", ":***@")))
    except ValueError:
        pass
    return base_url


def base_url_problem(base_url: str) -> str | None:
    """Why ``base_url`` cannot be a server's API address (urllib would also open file:, data: and ftp: ones), or None."""
    try:
        parts = urllib.parse.urlsplit(base_url)
        usable = parts.scheme in ("http", "https") and bool(parts.hostname)
    except ValueError:  # e.g. an unclosed IPv6 bracket
        usable = False
    if not usable:
        return ("not an http:// or https:// address with a host; give the server's API address, e.g. "
                "http://localhost:8000/v1")
    if parts.username is not None or parts.password is not None:  # it would be printed in every error about it
        return "carries a user name or password; give the address alone and the key with --api-key-env"
    if parts.fragment:
        return "has a #fragment, which no request sends; give the API's address alone"
    return None


class OpenAIBackend:
    """Tool calling against an OpenAI-compatible server (``base_url``, ``model``, key from ``api_key_env``)."""

    def __init__(
        self,
        base_url: str,
        model: str,
        *,
        api_key_env: str = DEFAULT_API_KEY_ENV,
        timeout: float = 60.0,
        max_retries: int = 3,
        two_phase: bool = False,
        vision_model: str | None = None,
        tool_choice: str = "required",
        temperature: float = 0.0,
        size_x: float = 20.0,
        size_y: float = 20.0,
        registry: Mapping[str, AtomicTerrain] | None = None,
        resolution: float = 0.1,
        toolset: str = "ours",
    ):
        if not 0 <= max_retries <= MAX_RETRIES:
            raise ValueError(f"max_retries must be between 0 and {MAX_RETRIES}, got {max_retries}.")
        if not 0 < timeout <= MAX_TIMEOUT:  # also refuses nan
            raise ValueError(f"timeout must be > 0 and at most {MAX_TIMEOUT:g} seconds, got {timeout}.")
        if toolset not in TOOLSETS:
            raise ValueError(f"unknown toolset {toolset!r}; use one of {list(TOOLSETS)}.")
        if toolset == "gente" and registry is not None:
            raise ValueError("the gente toolset translates into the global terrain registry; pass no registry.")
        if vision_model and not two_phase:
            raise ValueError("vision_model describes the image in two_phase; pass two_phase=True or leave it out.")
        problem = base_url_problem(base_url)
        if problem:
            raise ValueError(f"base_url {printable(shown_url(base_url)[:200])}: {problem}.")
        self.toolset, self.resolution = toolset, resolution
        self.base_url, self.model = base_url, model
        parts = urllib.parse.urlsplit(base_url)  # a query (Azure's ?api-version=...) stays after the path
        self.endpoint = urllib.parse.urlunsplit(parts._replace(path=parts.path.rstrip("/") + "/chat/completions"))
        self.vision_model = vision_model or model
        self.max_retries, self.two_phase, self.timeout = max_retries, two_phase, timeout
        self.tool_choice, self.temperature = tool_choice, temperature
        self.size_x, self.size_y = size_x, size_y
        self.registry = ATOMIC_TERRAINS if registry is None else registry
        self.api_key_env, self.api_key = api_key_env, os.environ.get(api_key_env, "none")
        if not self.api_key:
            raise ValueError(f"the environment variable {api_key_env} is set but empty; set it to the key, or unset "
                             f"it for a server without one.")
        if not re.fullmatch(r"[!-~]*", self.api_key):  # printable ASCII without spaces, as an HTTP header carries it
            raise ValueError(f"the API key in the environment variable {api_key_env} holds whitespace, control or "
                             f"non-ASCII characters (a trailing newline?); set {api_key_env} to the key alone.")

    def _post(self, payload: dict[str, Any], deadline: float) -> tuple[int, http.client.HTTPMessage, bytes]:
        """(Worker thread) POST ``payload`` to ``{base_url}/chat/completions``; (status, headers, body up to the cap + 1 byte)."""
        request = urllib.request.Request(
            self.endpoint, data=json.dumps(payload).encode(), method="POST",
            headers={"Content-Type": "application/json", "Authorization": f"Bearer {self.api_key}"},
        )
        try:
            response = _OPENER.open(request, timeout=self.timeout)
        except urllib.error.HTTPError as err:  # 3xx/4xx/5xx: the body explains, read it like any other
            response = err
        with response:
            read = getattr(response, "read1", response.read)
            body = bytearray()
            while len(body) <= MAX_RESPONSE_BYTES:
                if time.monotonic() > deadline:
                    raise TimeoutError("deadline passed while reading the answer")
                chunk = read(65536)
                if not chunk:
                    break
                body += chunk
            return response.status, response.headers, bytes(body)

    def _create(self, **payload: Any) -> tuple[ChatCompletionMessage, Any]:
        """One chat-completions request within the deadline: the message of its first choice and that choice's
        ``finish_reason`` (as the server sent it, or None). Every failure is a GenerationError naming the server."""
        deadline = time.monotonic() + self.timeout
        box: dict[str, Any] = {}

        def run() -> None:
            try:
                box["answer"] = self._post({"temperature": self.temperature, **payload}, deadline)
            except BaseException as exc:  # noqa: BLE001 - handed to the caller's thread
                box["error"] = exc

        worker = threading.Thread(target=run, name="gente-openai-request", daemon=True)
        worker.start()
        worker.join(max(deadline - time.monotonic(), 0.0) + 0.05)
        timed_out = GenerationError(
            f"the request to {self.base_url} timed out after {self.timeout:g} s (the whole request); raise "
            f"--timeout or check that the server is serving model {payload.get('model')!r}."
        )
        if worker.is_alive() or isinstance(box.get("error"), TimeoutError):
            raise timed_out
        error = box.get("error")
        if isinstance(error, urllib.error.URLError) and isinstance(error.reason, HUNG_UP):
            error = error.reason  # a reset while the request was being sent
        if isinstance(error, urllib.error.URLError):
            if isinstance(error.reason, TimeoutError):
                raise timed_out
            raise GenerationError(f"could not reach {self.base_url} ({error.reason}); check --base-url and that the server runs.")
        if isinstance(error, HUNG_UP):  # a server that crashed or closed mid-request (FIN or RST)
            raise GenerationError(f"the server at {self.base_url} closed the connection without an answer; check "
                                  f"that it runs and its log (out of memory? a request too large?).")
        if isinstance(error, http.client.HTTPException):  # a status line, headers or chunks that are not HTTP/1.x
            raise GenerationError(f"the server at {self.base_url} answered malformed HTTP ({error!r:.200}); point "
                                  f"--base-url at its OpenAI-compatible API, e.g. http://localhost:8000/v1.")
        if isinstance(error, (OSError, ValueError)):  # connection reset, bad URL
            raise GenerationError(f"the request to {self.base_url} failed ({type(error).__name__}: "
                                  f"{printable(str(error)[:200])}); check --base-url and that the server runs.")
        if error is not None:
            raise error
        status, headers, body = box["answer"]
        if 300 <= status < 400:
            location = headers.get("Location")
            target = (printable(urllib.parse.urljoin(self.endpoint, location)[:300]) if location
                      else "no address (no Location header)")
            raise GenerationError(f"the server at {self.base_url} answered HTTP {status}, a redirect to {target}; redirects "
                                  f"are not followed (they would carry the API key to another address): point --base-url "
                                  f"at the final address.")
        content_type = headers.get("Content-Type", "")
        if len(body) > MAX_RESPONSE_BYTES:
            raise GenerationError(f"the server at {self.base_url} sent more than {MAX_RESPONSE_BYTES} bytes; a chat "
                                  f"completion is a few kB: check --base-url.")
        text = body.decode("utf-8", errors="replace")
        try:
            data = json.loads(text)
        except (ValueError, RecursionError):
            data = None
        if status != 200:
            detail = data.get("error", {}).get("message") if isinstance(data, dict) and isinstance(data.get("error"), dict) else None
            key_fix = f"set the key in the environment variable {self.api_key_env} (or name another with --api-key-env)."
            fix = {401: key_fix, 403: key_fix, 404: "check --base-url (the API's root, e.g. http://localhost:8000/v1) "
                   "and --model."}.get(status)
            said = printable(str(detail or text)[:300])
            raise GenerationError(f"the server at {self.base_url} answered HTTP {status}: "
                                  + (f"{said.rstrip('.')}; {fix}" if fix else said))
        if data is None:
            raise GenerationError(
                f"the server at {self.base_url} answered HTTP 200 with a body that is not JSON (Content-Type "
                f"{content_type[:60]!r}, starting {text[:80]!r}); point --base-url at its OpenAI-compatible API, "
                f"e.g. http://localhost:8000/v1."
            )
        # Only the first choice's message is read, so only it is checked: servers differ from OpenAI in the rest
        # (finish_reason "eos_token" or "eos", no "object" or "created"), which ChatCompletion would refuse.
        choices = data.get("choices") if isinstance(data, dict) else None
        if choices == []:
            raise GenerationError(f"the server at {self.base_url} returned no choices.")
        try:
            if not isinstance(choices, list) or not isinstance(choices[0], dict):
                raise ValueError("'choices' is not a list of objects")
            return ChatCompletionMessage.model_validate(choices[0].get("message")), choices[0].get("finish_reason")
        except ValueError as exc:  # pydantic's ValidationError is a ValueError
            errors = exc.errors() if hasattr(exc, "errors") else []
            if errors:  # pydantic's: the first field at fault, which its one-line summary does not name
                fields = [p for p in errors[0]["loc"] if not (isinstance(p, str) and p[:1].isupper())]  # no types
                where = ("choices[0].message" + "".join(f"[{p}]" if isinstance(p, int) else f".{p}" for p in fields)
                         + f": {errors[0]['msg'][:80]}" + (f", and {len(errors) - 1} more" if len(errors) > 1 else ""))
                raise GenerationError(f"the server at {self.base_url} answered a chat completion off OpenAI's "
                                      f"format ({printable(where)}); check the server's OpenAI compatibility.") from None
            raise GenerationError(
                f"the server at {self.base_url} answered JSON that is not a chat completion ({str(exc).splitlines()[0][:120]}; "
                f"starting {text[:80]!r}); check --base-url and --model."
            ) from None

    def _translate(self, name: Any, arguments: Any) -> tuple[list[ToolCall], list[str]]:
        """Validate (``ours``) or translate (``gente``, a value outside our range rejected) one call; (calls, notes).

        Raises ValidationError with what the model must change.
        """
        if self.toolset == "gente":
            from legged_gente.generation.gente_compat import BLOCKING, translate_call

            translation = translate_call(name, arguments, "multi", self.size_x, self.size_y, live=True,
                                         resolution=self.resolution)
            if translation.blocked:  # why first, then the notes (a part defaulted, an argument ignored)
                reasons_first = sorted(translation.issues, key=lambda i: i.kind not in BLOCKING)
                raise ValidationError([i.message for i in reasons_first])
            return translation.calls, [f"{translation.gente_tool}: {i.message}" for i in translation.issues]
        return [validate_call(name, arguments, self.size_x, self.size_y, self.registry, self.resolution)], []

    def _check_terrain(self, calls: list[ToolCall]) -> None:
        """Raise ValidationError if ``calls``, in order, are too many or can stack heights beyond the bound."""
        if len(calls) > MAX_CALLS:
            raise ValidationError([f"a terrain holds at most {MAX_CALLS} calls; stop calling tools or merge regions."])
        check_height_stack(calls, self.size_x, self.size_y, self.registry)

    def _take_calls(
        self, round_: int, tool_calls: list[Any], slots: list[_Slot], warnings: list[str],
    ) -> tuple[list[dict[str, Any]], list[str]]:
        """Validate one answer's tool calls and place them in ``slots`` (the first answer makes one slot per call;
        see the module docstring for a correction round); (the messages that answer the model, the problems left)."""
        results: dict[int, str] = {}  # the tool result of tool_calls[i]
        # the calls to place: (i, tool name, its calls or why it is rejected, notes)
        fresh: list[tuple[int, str, list[ToolCall] | ValidationError, list[str]]] = []
        for i, tc in enumerate(tool_calls):
            function = getattr(tc, "function", None)
            try:
                if function is None:
                    raise ValidationError([f"tool call {tc.id!r} is not a function call; call the terrain functions."])
                new, notes = self._translate(function.name, function.arguments)
            except ValidationError as exc:
                fresh.append((i, "", exc, []))
                continue
            repeat = next((s for s in slots if s.calls is not None and (s.name, s.calls) == (function.name, new)), None)
            if repeat is None:
                fresh.append((i, function.name, new, notes))
                continue
            warnings.append(f"round {round_}: {function.name} ({tc.id}) repeats the call accepted in round "
                            f"{repeat.round} ({repeat.call_id}); applied once")
            results[i] = (f"ALREADY APPLIED: identical to {repeat.call_id}, accepted in round {repeat.round}; it is "
                          f"applied once. Send only corrections of the rejected calls.")
        if not slots:
            slots.extend(_Slot() for _ in fresh)
        open_slots = [s for s in slots if s.calls is None]
        rejected: list[str] = []
        follow_up: list[dict[str, Any]] = []
        if len(fresh) != len(open_slots):  # the new calls cannot be placed: none is applied
            problem = (f"this answer has {len(fresh)} new call(s) for {len(open_slots)} rejected call(s) "
                       f"({', '.join(s.call_id for s in open_slots)}); answer with exactly one corrected call per "
                       f"rejected call, in their order, and do not repeat accepted calls.")
            rejected = [problem]
            results |= {i: f"REJECTED: {problem}" for i, *_ in fresh}
            if not fresh:  # an answer of repeats only: no call of it to carry the reason
                follow_up = [{"role": "user", "content": problem}]
            open_slots, fresh = [], []
        for slot, (i, name, outcome, notes) in zip(open_slots, fresh):
            slot.call_id = tool_calls[i].id
            try:
                if isinstance(outcome, ValidationError):
                    raise outcome
                self._check_terrain([c for s in slots for c in (outcome if s is slot else s.calls or [])])
            except ValidationError as exc:
                rejected.append(str(exc))
                results[i] = f"REJECTED: {exc} Re-issue this call corrected."
                continue
            slot.name, slot.calls, slot.round = name, outcome, round_
            warnings += notes
            results[i] = f"OK: {', '.join(f'{c.tool} on {c.region_json()}' for c in outcome) or 'nothing to apply'}." + (
                f" Notes: {' '.join(notes)}" if notes else "")
        answers = [{"role": "tool", "tool_call_id": tc.id, "content": results[i]} for i, tc in enumerate(tool_calls)]
        return answers + follow_up, rejected

    def describe(self, image: str | Path | bytes, text: str | None = None) -> str:
        """Phase one of two: the vision model's description of the image as terrain."""
        content: list[dict[str, Any]] = [{"type": "text", "text": DESCRIBE_PROMPT + (f" Context: {text}" if text else "")}]
        content.append({"type": "image_url", "image_url": {"url": image_data_url(image)}})
        message, _ = self._create(model=self.vision_model, messages=[{"role": "user", "content": content}])
        description = (message.content or "").strip()
        if not description:
            raise GenerationError(f"the vision model {self.vision_model!r} returned no description of the image.")
        return description

    def generate(self, text: str | None = None, image: str | Path | bytes | None = None) -> GenerationResult:
        if not text and image is None:
            raise ValueError("give a text description, an image, or both.")
        if self.two_phase and image is None:
            raise ValueError("two_phase describes the image first; give an image or leave two_phase out.")
        notes: list[str] = []
        early_warnings: list[str] = []
        content: list[dict[str, Any]] = []
        if image is not None and self.two_phase:
            description = self.describe(image, text)
            if len(description) > MAX_DESCRIPTION_CHARS:
                early_warnings.append(f"the image description has {len(description)} characters; only the first "
                                      f"{MAX_DESCRIPTION_CHARS} are passed on.")
                description = description[:MAX_DESCRIPTION_CHARS]
            notes.append(f"image description ({self.vision_model}): {description}")
            content.append({"type": "text", "text": f"Build this terrain: {description}"})
            if text:  # the user's own words (sizes, depths) reach the model that sets the parameters too
                content.append({"type": "text", "text": f"The user adds: {text}"})
        else:
            if text:  # GenTe's prompts go as they are, so prompts written for GenTe work unchanged
                content.append({"type": "text", "text": text if self.toolset == "gente" else f"Build this terrain: {text}"})
            if image is not None:
                content.append({"type": "text", "text": "Build the terrain shown in this image."})
                content.append({"type": "image_url", "image_url": {"url": image_data_url(image)}})
        if self.toolset == "gente":
            from legged_gente.generation.gente_compat import gente_tool_schemas

            messages: list[dict[str, Any]] = [{"role": "user", "content": content}]
            tools = gente_tool_schemas("multi")
        else:
            messages = [{"role": "system", "content": system_prompt(self.size_x, self.size_y)},
                        {"role": "user", "content": content}]
            tools = tool_schemas(self.size_x, self.size_y, self.registry)
        slots: list[_Slot] = []  # one per call of the first answer with tool calls, in its order
        warnings: list[str] = early_warnings
        rejected: list[str] = []
        for round_ in range(1, self.max_retries + 2):
            msg, finish_reason = self._create(model=self.model, messages=messages, tools=tools, tool_choice=self.tool_choice)
            tool_calls = msg.tool_calls or []
            if len(tool_calls) > MAX_TOOL_CALLS_PER_ANSWER:  # each call answered: the chat keeps the protocol's turns
                rejected = [f"round {round_}: the model sent {len(tool_calls)} tool calls in one answer; at most "
                            f"{MAX_TOOL_CALLS_PER_ANSWER} are read"]
                messages.append(msg.model_dump(exclude_none=True))
                messages += [{"role": "tool", "tool_call_id": tc.id, "content": f"REJECTED: this answer has "
                              f"{len(tool_calls)} tool calls and at most {MAX_TOOL_CALLS_PER_ANSWER} are read; none "
                              f"is applied. Send the terrain again in at most {MAX_TOOL_CALLS_PER_ANSWER} calls."}
                             for tc in tool_calls]
                continue
            messages.append(msg.model_dump(exclude_none=True))
            said = (msg.content or msg.refusal or "")[:200]
            if not tool_calls and finish_reason == "length":
                rejected = [f"round {round_}: no whole tool call ({said!r}): {CUT}"]
                messages.append({"role": "user", "content": "Your answer was cut off at the token limit before a "
                                                            "whole tool call; answer with fewer, shorter tool calls."})
                continue
            if not tool_calls:
                rejected = [f"round {round_}: the model answered without calling a tool ({said!r})"]
                messages.append({"role": "user", "content": "Answer by calling the terrain tools, not in text."})
                continue
            answers, rejected = self._take_calls(round_, tool_calls, slots, warnings)
            messages += answers
            if finish_reason == "length" and rejected:  # its last call stops mid-way: named first, as errors list 5
                rejected.insert(0, CUT)
            elif finish_reason == "length":  # calls after the last whole one may be missing
                warnings.append(f"round {round_}: {CUT}")
            if not rejected:
                return GenerationResult([c for s in slots for c in s.calls], warnings, notes, self.model)
            warnings += [f"round {round_}: rejected: {r}" for r in rejected]
        raise GenerationError(
            f"the model gave no valid terrain after {self.max_retries} correction round(s): "
            + " | ".join(rejected[:5]) + (f" | ... and {len(rejected) - 5} more" if len(rejected) > 5 else "")
        )
