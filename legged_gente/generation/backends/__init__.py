"""Generation backends: ``planner`` (offline, deterministic) and ``openai`` (any OpenAI-compatible server).

Each backend turns a text and/or an image into validated :class:`~legged_gente.generation.validation.ToolCall`
objects and returns them in a :class:`GenerationResult`.
"""

from __future__ import annotations

import dataclasses

from legged_gente.generation.validation import ToolCall

MAX_TIMEOUT = 86_400.0
"""Longest deadline of a request to a server, in seconds (a day; the socket layer overflows near 1e10 s)."""
MAX_RETRIES = 10
"""Most correction rounds after a model's first answer: each is a request of up to the timeout, so a run's time
stays bounded (a model that cannot fix its calls in ten rounds does not in a hundred)."""


class GenerationError(RuntimeError):
    """A generation that could not produce a valid terrain (server failure, calls that stayed invalid)."""


@dataclasses.dataclass
class GenerationResult:
    """What a backend produced: the validated calls in order, warnings for the user, and notes.

    ``notes`` carries backend detail worth printing (the scene cues found, or the image description of a
    two-phase run).
    """

    calls: list[ToolCall]
    warnings: list[str] = dataclasses.field(default_factory=list)
    notes: list[str] = dataclasses.field(default_factory=list)
    model: str | None = None
