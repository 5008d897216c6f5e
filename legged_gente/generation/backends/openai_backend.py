"""The ``openai`` backend: any OpenAI-compatible chat-completions server calls the terrain tools.

One-phase: a (vision-)language model receives the text and/or the image (as a base64 data URL) and the
registry-derived ``tools``, and answers with tool calls. Two-phase (GenTe's scheme): a vision-language
model first describes the image as terrain, then a language model calls the tools from that description.

Every tool call is validated; rejected calls go back to the model as tool results carrying the validation
message, and the model gets at most ``max_retries`` correction rounds after its first answer. The run ends
at the first round whose calls are all valid; if calls are still invalid after the last round, a
:class:`GenerationError` names them. The client's own hidden retries are switched off, so the number of
requests is bounded and visible.
"""

from __future__ import annotations

import base64
import io
import os
from pathlib import Path
from typing import Any, Mapping

import openai
from PIL import Image

from legged_gente.generation.backends import GenerationError, GenerationResult
from legged_gente.generation.tools import named_regions, tool_schemas
from legged_gente.generation.validation import ToolCall, ValidationError, validate_call
from legged_gente.terrain.registry import ATOMIC_TERRAINS, AtomicTerrain

DEFAULT_API_KEY_ENV = "GENTE_API_KEY"

DESCRIBE_PROMPT = (
    "Describe the ground in this image as terrain a legged robot would walk on, seen from above: which "
    "surfaces (water and its depth and flow, sand, mud, snow, ice, grass, rock, pavement), their slopes, "
    "obstacles (trees, rocks, pillars, gaps), stairs, and where each lies (near = back, far = front, "
    "left, right). Be concrete about sizes in metres."
)


def image_data_url(image: str | Path | bytes) -> str:
    """A ``data:image/...;base64,`` URL of an image file or its bytes (the format is read from the data)."""
    data = Path(image).read_bytes() if isinstance(image, (str, Path)) else bytes(image)
    try:
        fmt = Image.open(io.BytesIO(data)).format or "PNG"
    except Exception as exc:  # Pillow raises several types for unreadable data
        raise ValueError(f"the image could not be read ({exc}); pass a PNG or JPEG file.") from None
    return f"data:image/{fmt.lower()};base64,{base64.b64encode(data).decode('ascii')}"


def system_prompt(size_x: float, size_y: float) -> str:
    regions = list(named_regions(size_x, size_y))
    return (
        f"You build a {size_x:g} m x {size_y:g} m terrain tile for a legged robot by calling terrain tools. "
        f"+x is the front of the tile and +y its left; a region is one of {regions} or a rectangle "
        f"{{x0, y0, x1, y1}} in metres. Calls apply in order: first geometric terrains (heights; mode 'set' "
        f"replaces the region's heights, 'add' adds to them), then physical terrains (water, soil, friction) "
        f"over the ground they lie on. Issue all calls at once, using only the tools' declared arguments "
        f"and ranges. If a call is rejected, re-issue only the rejected calls, corrected."
    )


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
    ):
        if max_retries < 0:
            raise ValueError(f"max_retries must be >= 0, got {max_retries}.")
        if timeout <= 0:
            raise ValueError(f"timeout must be > 0 seconds, got {timeout}.")
        self.base_url, self.model = base_url, model
        self.vision_model = vision_model or model
        self.max_retries, self.two_phase, self.timeout = max_retries, two_phase, timeout
        self.tool_choice, self.temperature = tool_choice, temperature
        self.size_x, self.size_y = size_x, size_y
        self.registry = ATOMIC_TERRAINS if registry is None else registry
        self.client = openai.OpenAI(
            base_url=base_url, api_key=os.environ.get(api_key_env, "none"), timeout=timeout, max_retries=0
        )

    def _create(self, **kwargs: Any):
        """One chat-completions request; server failures become GenerationError with the cause and a fix."""
        try:
            return self.client.chat.completions.create(temperature=self.temperature, **kwargs)
        except openai.APITimeoutError:
            raise GenerationError(
                f"the request to {self.base_url} timed out after {self.timeout:g} s; raise --timeout or check "
                f"that the server is serving model {kwargs.get('model')!r}."
            ) from None
        except openai.APIStatusError as exc:
            raise GenerationError(
                f"the server at {self.base_url} answered HTTP {exc.status_code}: {exc.message}"
            ) from None
        except openai.APIConnectionError as exc:
            raise GenerationError(
                f"could not reach {self.base_url} ({exc}); check --base-url and that the server runs."
            ) from None

    def describe(self, image: str | Path | bytes, text: str | None = None) -> str:
        """Phase one of two: the vision model's description of the image as terrain."""
        content: list[dict[str, Any]] = [{"type": "text", "text": DESCRIBE_PROMPT + (f" Context: {text}" if text else "")}]
        content.append({"type": "image_url", "image_url": {"url": image_data_url(image)}})
        resp = self._create(model=self.vision_model, messages=[{"role": "user", "content": content}])
        description = (resp.choices[0].message.content or "").strip() if resp.choices else ""
        if not description:
            raise GenerationError(f"the vision model {self.vision_model!r} returned no description of the image.")
        return description

    def generate(self, text: str | None = None, image: str | Path | bytes | None = None) -> GenerationResult:
        if not text and image is None:
            raise ValueError("give a text description, an image, or both.")
        notes: list[str] = []
        content: list[dict[str, Any]] = []
        if image is not None and self.two_phase:
            description = self.describe(image, text)
            notes.append(f"image description ({self.vision_model}): {description}")
            content.append({"type": "text", "text": f"Build this terrain: {description}"})
        else:
            if text:
                content.append({"type": "text", "text": f"Build this terrain: {text}"})
            if image is not None:
                content.append({"type": "text", "text": "Build the terrain shown in this image."})
                content.append({"type": "image_url", "image_url": {"url": image_data_url(image)}})
        messages: list[dict[str, Any]] = [
            {"role": "system", "content": system_prompt(self.size_x, self.size_y)},
            {"role": "user", "content": content},
        ]
        tools = tool_schemas(self.size_x, self.size_y, self.registry)
        calls: list[ToolCall] = []
        warnings: list[str] = []
        rejected: list[str] = []
        for round_ in range(self.max_retries + 1):
            resp = self._create(model=self.model, messages=messages, tools=tools, tool_choice=self.tool_choice)
            if not resp.choices:
                raise GenerationError(f"the server at {self.base_url} returned no choices.")
            msg = resp.choices[0].message
            tool_calls = msg.tool_calls or []
            messages.append(msg.model_dump(exclude_none=True))
            if not tool_calls:
                rejected = [f"round {round_ + 1}: the model answered without calling a tool ({(msg.content or '')[:200]!r})"]
                messages.append({"role": "user", "content": "Answer by calling the terrain tools, not in text."})
                continue
            rejected = []
            for tc in tool_calls:
                try:
                    call = validate_call(tc.function.name, tc.function.arguments, self.size_x, self.size_y, self.registry)
                except ValidationError as exc:
                    rejected.append(str(exc))
                    result = f"REJECTED: {exc} Re-issue this call corrected."
                else:
                    calls.append(call)
                    result = f"OK: {call.tool} applied on {call.region_json()}."
                messages.append({"role": "tool", "tool_call_id": tc.id, "content": result})
            if not rejected:
                return GenerationResult(calls, warnings, notes, self.model)
            warnings += [f"round {round_ + 1}: rejected: {r}" for r in rejected]
        raise GenerationError(
            f"the model's tool calls were still invalid after {self.max_retries} correction round(s): "
            + " | ".join(rejected)
        )
