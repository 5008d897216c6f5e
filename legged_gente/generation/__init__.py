"""Text and images -> terrain tool calls -> validated TerrainSpec -> emitted terrain config (see docs/generation.md)."""

from legged_gente.generation.emit import emit
from legged_gente.generation.pipeline import generate_spec
from legged_gente.generation.spec import TerrainSpec
from legged_gente.generation.tools import tool_schemas
from legged_gente.generation.validation import ToolCall, ValidationError, validate_call

__all__ = ["TerrainSpec", "ToolCall", "ValidationError", "emit", "generate_spec", "tool_schemas", "validate_call"]
