"""Text and images -> terrain tool calls -> validated TerrainSpec -> emitted terrain config (see docs/generation.md).

``generate_spec`` is imported on first use (PEP 562): a reader of the spec format below this layer
(``legged_gente.evaluation``) then loads no pipeline and no backends (models, images, planners) with it."""

from __future__ import annotations

import importlib

from legged_gente.generation.emit import emit
from legged_gente.generation.spec import TerrainSpec
from legged_gente.generation.tools import tool_schemas
from legged_gente.generation.validation import ToolCall, ValidationError, validate_call

__all__ = ["TerrainSpec", "ToolCall", "ValidationError", "emit", "generate_spec", "tool_schemas", "validate_call"]


def __getattr__(name: str):
    if name == "generate_spec":
        return importlib.import_module(f"{__name__}.pipeline").generate_spec
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
